/* SPDX-License-Identifier: Apache-2.0
 * net/server/emulator_internal.h — what the I/O thread's parts share: the emulator, its
 * clients, and one set of hooks per kind of port (port_script.c: 30001–30003 and their
 * read-only twins; port_rtde.c: 30004; port_dashboard.c: 29999). Everything here runs on the
 * I/O thread unless a comment says otherwise.
 */
#ifndef URT_NET_EMULATOR_INTERNAL_H
#define URT_NET_EMULATOR_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "ctrl_log.h"
#include "urt/net/dashboard.h"
#include "urt/net/emulator.h"
#include "urt/net/primary.h"
#include "urt/net/rtde.h"
#include "urt/net/tcp.h"
#include "urt/net/urp.h"
#include "urt/net/urscript.h"

/* What each port does (protocols.md §0.2). */
typedef enum port_kind {
  PORT_PRIMARY = 0,     /* 30001: version, state at 10 Hz, robot messages; takes URScript */
  PORT_SECONDARY,       /* 30002: version, state at 10 Hz; takes URScript                 */
  PORT_RT,              /* 30003: a packet every controller tick; takes URScript          */
  PORT_PRIMARY_RO,      /* 30011 */
  PORT_SECONDARY_RO,    /* 30012 */
  PORT_RT_RO,           /* 30013 */
  PORT_RTDE,            /* 30004 */
  PORT_DASHBOARD,       /* 29999 */
  URT__N_PORTS
} port_kind_t;

#define MSG_QUEUE 256   /* robot messages waiting for the I/O thread */
#define URT__IN_HISTORY 64  /* latched input-register states kept (one per tick with a write) */

/* The I/O thread's command rings into the physics thread, one per kind of client, so that a
 * flood on one (RTDE inputs at 10 kHz) never costs another its commands (a dashboard `power
 * off`, a primary `unlock protective stop`): each ring is drained in turn and counts its own
 * drops (urt_loop_producer_dropped). */
typedef enum ring_kind {
  URT__RING_SCRIPT = 0,   /* 30001–30003 primary commands */
  URT__RING_RTDE,         /* 30004 inputs                 */
  URT__RING_DASHBOARD,    /* 29999                        */
  URT__N_RINGS
} ring_kind_t;

typedef struct urt__client {
  urt_tcp_conn_t *conn;
  void *proto;               /* the port's per-connection state */
  struct urt__client *next;
} urt__client_t;

struct urt_emulator {
  urt_loop_t *loop;
  const urt_model_t *m;
  urt_emulator_config_t cfg;
  char bind[64], programs_dir[1024], programs_alias[256];
  int ring[URT__N_RINGS];        /* the I/O thread's command rings, one per kind of client */
  uint64_t rtde_applied_tick;    /* tick of the last RTDE inputs handed to the controller */
  urt_runner_t *runner;
  int runner_producer;           /* the runner thread's command ring */

  int listen_fd[URT__N_PORTS];
  int epoll_fd, tick_fd, msg_fd;
  urt__client_t *clients;

  /* connection caps (emulator.c): clients per port, the spare descriptor that drains a
   * listener when the table is full, listeners paused when even that failed, what every
   * client's output may hold together, and the refusals not yet logged */
  int max_clients;
  int port_clients[URT__N_PORTS];
  int reserve_fd;
  int64_t listen_paused_until_ns[URT__N_PORTS];  /* 0: listening */
  urt_tcp_budget_t out_budget;
  uint64_t unlogged_cap[URT__N_PORTS], unlogged_fds;
  int64_t last_refusal_log_ns;
  uint64_t streamed_tick;        /* last tick handed to the ports */

  /* 30001–30003 */
  urt_primary_robot_info_t info;
  uint64_t state_every;          /* ticks between robot-state messages (10 Hz) */
  int32_t last_safety_mode;      /* safety mode of the last streamed tick, < 0: none yet */

  /* 30004: the register bank is shared with the runner thread, hence the lock */
  urt_rtde_registry_t rtde_registry;
  pthread_mutex_t reg_lock;
  urt_rtde_registers_t regs;
  /* the output registers as a running program left them after its slice of each tick (under
   * reg_lock): the data package of tick k carries those of slice k - 1, the slice whose
   * commands tick k executed, however late the I/O thread streams it */
  struct urt__out_regs {
    uint64_t slice;              /* 1 + the tick of the slice (0: none yet) */
    int32_t out_int[URT_RTDE_NREG];
    double out_double[URT_RTDE_NREG];
    uint8_t out_bit[URT_RTDE_NBITREG];
  } out_hist[URT_LOOP_HISTORY];
  uint64_t out_done;             /* 1 + the tick of the newest slice kept there (0: none) */
  bool out_running;              /* a main program runs (its slices are reported) */
  /* the input registers as the controller latched them (under reg_lock): a client's package
   * applied while tick L was the newest takes effect from tick L + 1, as a controller latches
   * its inputs once per cycle; the program's slice of tick k and the data package of tick k
   * both read the entry in force at k, so a late runner thread reads what the tick held, not
   * what arrived since (urt__inputs_at) */
  struct urt__in_regs {
    uint64_t from;               /* first tick this entry holds for (0: unused) */
    int32_t in_int[URT_RTDE_NREG];
    double in_double[URT_RTDE_NREG];
    uint8_t in_bit[URT_RTDE_NBITREG];
  } in_hist[URT__IN_HISTORY];
  uint32_t in_newest;            /* index of the newest entry of in_hist */
  uint64_t in_read_tick;         /* the newest tick whose inputs the program has read */

  /* 29999 */
  urt_dashboard_ctx_t dash_ctx;
  urt_dashboard_state_t dash;
  urt_ctrl_log_t log;            /* the controller's log (ctrl_log.h)                 */
  char log_dir[1024];            /* where saveLog & co. write it; "" : nowhere         */
  double pstop_since;            /* controller time the protective stop began, < 0: none */

  /* the loaded program (program_play.c): a compiled .urp, or NULL for a URScript file; and
   * the thread that fetches an External Control node's program before playing it */
  urt_urp_program_t *urp;
  char ec_host[64];
  int ec_port;
  pthread_t fetch_thread;
  bool fetch_started;            /* fetch_thread must be joined                    */
  _Atomic int fetch_busy;        /* the thread is fetching (a play then waits)     */
  _Atomic int fetch_cancel;      /* a stop or load: drop what the thread fetched   */
  bool fetch_replay;             /* a play came while a cancelled fetch wound down */
  pthread_mutex_t fetch_lock;    /* cancel vs. the thread's submit                 */

  /* runner → I/O thread */
  pthread_mutex_t msg_lock;
  urt_script_msg_t msg_queue[MSG_QUEUE];
  unsigned msg_head, msg_len;
  uint64_t msg_dropped;

  pthread_t io_thread;
  _Atomic int stop;
  _Atomic int shutdown_requested;  /* the dashboard asked the emulator to shut down */
  int started;

  _Atomic uint64_t n_clients, rt_packets, rt_dropped, state_messages, ticks_lost, scripts,
      rtde_packages, rtde_dropped, refused_cap, refused_fds, out_bytes, out_refused;
};

/* Hooks of one kind of port. Nullable: every hook. */
typedef struct urt__port_ops {
  /* a client connected: set c->proto, queue a greeting; false: refuse (close) it */
  bool (*open)(urt_emulator_t *e, urt__client_t *c);
  /* bytes arrived; false: close the connection (after flushing what is queued) */
  bool (*input)(urt_emulator_t *e, urt__client_t *c, const uint8_t *data, size_t n);
  /* the peer closed: last chance to act on buffered input */
  void (*eof)(urt_emulator_t *e, urt__client_t *c);
  /* free c->proto */
  void (*close)(urt_emulator_t *e, urt__client_t *c);
} urt__port_ops_t;

extern const urt__port_ops_t urt__port_script_ops, urt__port_rtde_ops, urt__port_dashboard_ops;

/* The input registers latched per tick (input_latch.c), all under reg_lock: latch the bank's
 * inputs as in force from newest_tick + 1 (or after the newest tick the program has read);
 * copy into r the inputs in force at tick (_read: the program's read, which fixes that tick's
 * inputs). */
void urt__inputs_latch(urt_emulator_t *e, uint64_t newest_tick);
void urt__inputs_at(const urt_emulator_t *e, uint64_t tick, urt_rtde_registers_t *r);
void urt__inputs_read(urt_emulator_t *e, uint64_t tick, urt_rtde_registers_t *r);

/* Per tick, in order: RTDE inputs into the controller, then what every port streams. */
void urt__rtde_apply_inputs(urt_emulator_t *e);
void urt__script_stream_tick(urt_emulator_t *e, const urt_snapshot_t *s, bool safety_changed);
void urt__rtde_stream_tick(urt_emulator_t *e, const urt_snapshot_t *s);
void urt__dashboard_tick(urt_emulator_t *e, const urt_snapshot_t *s);

/* Safety-mode change messages, before this tick's state (port_script.c); true when the mode
 * changed this tick (the robot state then goes out in the same tick). */
bool urt__script_safety_tick(urt_emulator_t *e, const urt_snapshot_t *s);

/* The dashboard's saveLog, generate flight report and generate support file
 * (urt_dashboard_ctx_t.write_log; port_dashboard.c). */
int urt__dashboard_write_log(void *user, int what, const char *arg, size_t arg_len, char *out,
                             size_t out_sz);

/* Robot messages to every primary client (30001, 30011); each also goes into the log. */
void urt__script_broadcast(urt_emulator_t *e, const urt_script_msg_t *msg);
void urt__script_broadcast_text(urt_emulator_t *e, const char *text);

/* The runner's host over this emulator (script_host.c): it uses the runner's producer ring,
 * reg_lock and the message queue. */
urt_script_host_t urt__script_host(urt_emulator_t *e);

/* A command from the I/O thread into the controller through one of its rings; a full ring is
 * counted for that ring and reported as text. */
void urt__submit(urt_emulator_t *e, ring_kind_t ring, const urt_ctrl_cmd_t *cmd);
void urt__submit_kind(urt_emulator_t *e, ring_kind_t ring, int kind);

/* Send one message to every client of the ports for which want(kind) is true. */
void urt__send_to(urt_emulator_t *e, bool (*want)(int kind), const uint8_t *buf, size_t len,
                  _Atomic uint64_t *sent, _Atomic uint64_t *dropped);

/* Programs of the dashboard (program_play.c): `load` compiles a .urp (the dashboard's
 * prepare hook), `play` runs the loaded program (a URScript file as it is, a .urp rendered,
 * fetching an External Control node's program on its own thread), a stop or load cancels a
 * fetch in flight, and destroy joins it. */
int urt__program_prepare(void *user, const char *host_path, char *why, size_t why_sz);
void urt__program_play(urt_emulator_t *e);
void urt__program_cancel(urt_emulator_t *e);
void urt__program_tick(urt_emulator_t *e);
int urt__program_state(urt_emulator_t *e, int snapshot_state);  /* PLAYING while fetching */  /* per tick: a play held back by a winding-down fetch */
void urt__program_shutdown(urt_emulator_t *e);

/* Controller time of the newest snapshot [µs]. */
uint64_t urt__timestamp_us(const urt_emulator_t *e);

#endif
