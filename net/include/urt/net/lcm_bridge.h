/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/lcm_bridge.h — urtwin on LCM, the way Drake's hardware simulators talk:
 * a status message for every controller tick, drive messages from the loop's drive samples, and
 * a command subscriber that turns each lcmt_urtwin_command into a URT_CTRL_DIRECT set-point.
 *
 *   physics thread ──snapshot history──▶ [publisher thread] ──▶ URTWIN_STATUS, URTWIN_DRIVE
 *   URTWIN_COMMAND ──▶ [subscriber thread] ──urt_loop_submit() (its own ring)──▶ physics thread
 *                                         └─urt_loop_grant(1) in lockstep (one tick per command)
 *
 * Both threads are non-RT and may block; the physics thread never waits for them. The publisher
 * reads tick by tick (urt_loop_wait + urt_loop_read) so no tick is skipped unless it falls more
 * than URT_LOOP_HISTORY ticks behind, and then it counts the lost ticks.
 *
 * Traffic stays on this host by default: the URL's ttl=0 keeps multicast packets off the wire.
 * udpm needs a multicast route; on a host without a default route, add LCM's loopback route
 * with tools/lcm_loopback_route.sh.
 */
#ifndef URT_NET_LCM_BRIDGE_H
#define URT_NET_LCM_BRIDGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/controller.h"
#include "urt/loop.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_LCM_DEFAULT_URL "udpm://239.255.76.67:7667?ttl=0"
#define URT_LCM_DEFAULT_STATUS "URTWIN_STATUS"
#define URT_LCM_DEFAULT_DRIVE "URTWIN_DRIVE"
#define URT_LCM_DEFAULT_COMMAND "URTWIN_COMMAND"
#define URT_LCM_DEFAULT_IO "URTWIN_IO"
#define URT_LCM_DEFAULT_FAULT "URTWIN_FAULT"
#define URT_LCM_DEFAULT_FAULT_TRUTH "URTWIN_FAULT_TRUTH"

typedef struct urt_lcm_config {
  const char *url;             /* LCM provider URL; NULL: URT_LCM_DEFAULT_URL                   */
  const char *status_channel;  /* NULL: URT_LCM_DEFAULT_STATUS; "": publish no status          */
  const char *drive_channel;   /* NULL: URT_LCM_DEFAULT_DRIVE; "": publish no drive messages    */
  const char *command_channel; /* NULL: URT_LCM_DEFAULT_COMMAND; "": no subscriber thread.
                                * LCM treats it as a regular expression (anchored).             */
  const char *io_channel;      /* NULL: URT_LCM_DEFAULT_IO; "": do not listen for input levels
                                * (lcmt_urtwin_io → URT_CTRL_SET_INPUTS, on the subscriber
                                * thread; never grants a tick)                                   */
  const char *fault_channel;   /* NULL: URT_LCM_DEFAULT_FAULT; "": no live fault injection
                                * (lcmt_urtwin_fault → URT_CTRL_FAULT, on the subscriber thread,
                                * checked against the source's model; never grants a tick)     */
  const char *fault_truth_channel; /* NULL: URT_LCM_DEFAULT_FAULT_TRUTH; "": none. One
                                * lcmt_urtwin_fault_truth per tick, after its status           */
  double drive_rate;           /* drive messages per second at most [Hz], by sample time;
                                * 0: every sample the loop makes (its own drive_rate)           */
  int lockstep;                /* 1 (loop in URT_PACING_LOCKSTEP): grant one tick at start, so a
                                * first status goes out, and one per accepted command (Drake's
                                * LcmDrivenLoop); while no new tick comes, repeat the newest
                                * status every 100 ms (same tick: receivers drop repeats) so a
                                * client that subscribes late can start; 0: never grant      */
} urt_lcm_config_t;

/* All defaults (the NULL / 0 values above). Context: any. */
void urt_lcm_config_default(urt_lcm_config_t *cfg);

/* Counters, readable from any thread while the bridge runs. */
typedef struct urt_lcm_stats {
  uint64_t status_sent;     /* status messages published, one per tick                       */
  uint64_t status_repeated; /* lockstep: the newest status sent again while idle             */
  uint64_t ticks_lost;      /* controller ticks overwritten before the publisher read them   */
  uint64_t drive_sent;      /* drive messages published                                      */
  uint64_t drive_lost;      /* drive samples overwritten before the publisher read them      */
  uint64_t publish_errors;  /* lcm_publish failures                                           */
  uint64_t cmd_received;    /* messages on the command channel                               */
  uint64_t cmd_accepted;    /* decoded, valid and submitted                                  */
  uint64_t cmd_rejected;    /* malformed (URT_EPROTO) or not finite (URT_ERANGE)             */
  uint64_t cmd_dropped;     /* valid but the command ring was full                           */
  uint64_t last_tick;       /* tick of the last status published                             */
  uint64_t io_received, io_accepted, io_rejected, io_dropped;  /* the same, I/O channel   */
  uint64_t fault_received, fault_accepted, fault_rejected, fault_dropped;  /* fault channel */
  uint64_t truth_sent;      /* fault-truth messages published                                */
} urt_lcm_stats_t;

/* Where the bridge reads ticks and drive samples and sends commands: the loop (urt_lcm_bridge_
 * create fills it from urt/loop.h), or a fake in tests. Functions have the semantics of their
 * urt_loop_* namesakes; they are called from the bridge's threads only. Nullable: release. */
typedef struct urt_lcm_source {
  void *ctx;
  uint64_t (*wait)(void *ctx, uint64_t after_tick, int timeout_ms);
  int (*read)(void *ctx, uint64_t tick, urt_snapshot_t *out);
  uint64_t (*latest_drive)(void *ctx);
  int (*read_drive)(void *ctx, uint64_t seq, urt_drive_sample_t *out);
  bool (*submit)(void *ctx, const urt_ctrl_cmd_t *cmd);   /* from the subscriber thread only */
  void (*grant)(void *ctx, uint64_t n);
  void (*release)(void *ctx);                             /* at destroy                      */
  const urt_model_t *model;  /* what fault injections are checked against (the loop's model);
                              * NULL: only their names are checked, the controller the rest */
} urt_lcm_source_t;

typedef struct urt_lcm_bridge urt_lcm_bridge_t;

/* Create a bridge on a loop: claims a command ring (urt_loop_add_producer "lcm") and opens the
 * LCM URL (publisher and subscriber instances). The loop must outlive the bridge.
 * Context: non-RT. Returns 0, URT_EINVAL (drive_rate < 0 or NaN, lockstep not 0/1, a channel
 * name longer than 63 characters), URT_ENOSPC (no free command ring),
 * URT_EIO (lcm_create failed: bad URL, or no multicast route — see the file comment) or
 * URT_ENOMEM; err receives a message. Nullable: cfg (defaults), err. */
int urt_lcm_bridge_create(urt_loop_t *loop, const urt_lcm_config_t *cfg, urt_lcm_bridge_t **out,
                          char *err, size_t err_sz);

/* The same over any source (copied; src->release runs at destroy, or on failure here).
 * Context: non-RT. Returns as urt_lcm_bridge_create. Nullable: cfg, err. */
int urt_lcm_bridge_create_source(const urt_lcm_source_t *src, const urt_lcm_config_t *cfg,
                                 urt_lcm_bridge_t **out, char *err, size_t err_sz);

/* Start the publisher and subscriber threads. Publishing starts at the newest tick and drive
 * sample. Returns 0, URT_EINVAL (already started) or URT_EIO (thread creation failed; the
 * bridge is left stopped). Context: non-RT. */
int urt_lcm_bridge_start(urt_lcm_bridge_t *b);

/* Stop both threads and join them (idempotent). Each thread notices within about 50 ms; a join
 * that takes longer than 2 s is abandoned with a message on stderr and the bridge's memory is
 * then never freed. Context: non-RT. */
void urt_lcm_bridge_stop(urt_lcm_bridge_t *b);

/* Stop if running, release the source, free everything. Nullable: b. Context: non-RT. */
void urt_lcm_bridge_destroy(urt_lcm_bridge_t *b);

/* Copy the counters. Context: any. */
void urt_lcm_bridge_get_stats(const urt_lcm_bridge_t *b, urt_lcm_stats_t *out);

#ifdef __cplusplus
}
#endif
#endif
