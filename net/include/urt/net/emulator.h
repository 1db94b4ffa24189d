/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/emulator.h — the UR controller's TCP interfaces on top of a running hard
 * loop: primary 30001, secondary 30002, real-time 30003 (and their read-only twins 30011–30013),
 * RTDE 30004 and the dashboard 29999, all served by one I/O thread (the single producer of
 * commands from clients), plus the URScript program runner.
 *
 *   hard loop ──snapshots──▶ I/O thread ──▶ 30003 packets every tick, robot state at 10 Hz
 *   clients ──bytes──▶ script framer ──▶ controller commands (ring) / programs (runner)
 *   runner ──robot messages──▶ I/O thread ──▶ 30001 clients
 */
#ifndef URT_NET_EMULATOR_H
#define URT_NET_EMULATOR_H

#include <stddef.h>
#include <stdint.h>

#include "urt/loop.h"
#include "urt/net/urscript.h"
#include "urt/net/version.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_emulator_config {
  const char *bind;          /* IPv4 address, default "127.0.0.1"                   */
  int port_offset;           /* added to every port                                  */
  urt_version_t version;     /* the emulated controller                              */
  const char *programs_dir;  /* where dashboard `load` finds programs; NULL: none       */
  const char *programs_alias; /* that folder's absolute name as clients see it (a path
                                 starting with '/'); NULL: "/programs", a controller's       */
  int local_control;         /* e-Series: 1 = local control (dashboard refuses changes) */
  int remote_control_off;    /* e-Series: remote control disabled (urt_dashboard_state_t) */
  const char *serial_number; /* digits; NULL: "20235501783"                            */
  int rt_priority;           /* > 0: SCHED_FIFO priority of the I/O and script threads
                                (best effort)                                              */
  const char *const *script_allow_hosts;  /* hosts besides loopback URScript's socket_open
                                             may dial (--script-allow-host; at most 16)   */
  int n_script_allow_hosts;
  /* Where a played program's External Control node fetches its program (the URCap's
     installation: host IP and port). NULL / 0: 127.0.0.1 / 50002. Loopback only: create
     refuses any other host. */
  const char *external_control_host;
  int external_control_port;
  /* Clients at once on each port (0: URT_EMULATOR_MAX_CLIENTS). UR documents no limit; a
     connection beyond it is accepted and closed at once, with a log line (rate-limited). */
  int max_clients;
  /* Bytes of output buffers all clients together may hold (0: URT_EMULATOR_OUT_BUDGET). */
  size_t out_budget;
  /* An existing folder where the dashboard's saveLog, generate flight report and generate
     support file write the controller's log (net/server/ctrl_log.h); NULL: they are refused. */
  const char *log_dir;
} urt_emulator_config_t;

/* The defaults: a UR client stack opens 1–4 connections per port (ur_rtde's receive, control
   and IO interfaces on 30004; URCL's primary, RTDE, dashboard), so 32 per port leaves room for
   several of them; 16 MiB of output is 32 clients that never read 30003 (512 KiB each). */
#define URT_EMULATOR_MAX_CLIENTS 32
#define URT_EMULATOR_OUT_BUDGET (16u * 1024u * 1024u)

/* Per-port counters (readable while running, approximately). */
typedef struct urt_emulator_stats {
  uint64_t clients;          /* connected now, all ports                             */
  uint64_t rt_packets;       /* 30003 packets queued, summed over clients            */
  uint64_t rt_dropped;       /* 30003 packets dropped for clients that do not read   */
  uint64_t state_messages;   /* robot-state messages queued on 30001/30002           */
  uint64_t ticks_lost;       /* ticks the I/O thread fell too far behind to stream    */
  uint64_t scripts;          /* script units received                                */
  uint64_t refused_cap;      /* connections closed at once: their port was at its cap  */
  uint64_t refused_fds;      /* connections closed at once: no descriptor left (EMFILE) */
  uint64_t out_bytes;        /* output buffers allocated now, all clients            */
  uint64_t out_refused;      /* buffer growths refused for the output budget          */
  urt_runner_tick_stats_t script_tick;  /* the URScript VM's CPU time per tick (urscript.h) */
} urt_emulator_stats_t;

typedef struct urt_emulator urt_emulator_t;

/* Bind every port (all open or none). Context: non-RT. Returns 0 or URT_EIO (err: which port
 * and why) / URT_ENOMEM. Nullable: err. */
int urt_emulator_create(urt_loop_t *loop, const urt_emulator_config_t *cfg, urt_emulator_t **out,
                        char *err, size_t err_sz);
int urt_emulator_start(urt_emulator_t *e);
void urt_emulator_stop(urt_emulator_t *e);          /* idempotent; closes every client */
void urt_emulator_destroy(urt_emulator_t *e);       /* Nullable: e */
void urt_emulator_get_stats(const urt_emulator_t *e, urt_emulator_stats_t *out);

/* True once a dashboard client sent `shutdown` (the owner then stops everything). */
int urt_emulator_shutdown_requested(const urt_emulator_t *e);

#ifdef __cplusplus
}
#endif
#endif
