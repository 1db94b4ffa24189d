/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/urscript.h — the URScript program runner: one thread that parses and
 * interprets the URScript arriving on ports 30001–30003 (protocols.md §4.6, §5) and drives the
 * controller only through a host interface of function pointers.
 *
 *   text unit ──urt_runner_submit()──▶ queue ──runner thread──▶ lexer → parser → name check
 *                                                               └──▶ interpreter ──host->submit()──▶ urt_ctrl_cmd_t
 *   host->snapshot() / host->wait_tick() ◀── blocking calls (movej, sleep, sync …) wait on controller time
 *   host->message()  ──▶ primary interface (TEXT, KEY PROGRAM_XXX_STARTED/STOPPED, RUNTIME_EXCEPTION)
 *
 * A unit is a main program (`def name(): … end`) or one or more plain statements (run as one
 * program); either stops the running main program first. A secondary unit (`sec name(): … end`)
 * runs alongside the main program, must not move, sleep or sync, and reports errors as a KEY
 * message titled SECONDARY_PROGRAM_EXCEPTION_XXX.
 */
#ifndef URT_NET_URSCRIPT_H
#define URT_NET_URSCRIPT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/controller.h"
#include "urt/net/rtde.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bounds (the runner refuses larger input with a message, it never grows past them). */
#define URT_SCRIPT_MAX_TEXT (1u << 20)  /* bytes of one unit                         */
#define URT_SCRIPT_MAX_DEPTH 64         /* nesting of blocks, expressions and calls  */
#define URT_SCRIPT_MAX_LIST 1024        /* elements of one list                      */
#define URT_SCRIPT_MAX_STRING 4096      /* bytes of one string value                 */

/* What the runner tells the primary interface (protocols.md §4.5 ROBOT_MESSAGE). */
typedef enum urt_script_msg_kind {
  URT_SCRIPT_MSG_TEXT = 0,               /* robot_message_type 0: text                   */
  URT_SCRIPT_MSG_POPUP = 2,              /* robot_message_type 2: title, text, flags       */
  URT_SCRIPT_MSG_KEY = 7,                /* robot_message_type 7: title + text            */
  URT_SCRIPT_MSG_RUNTIME_EXCEPTION = 10  /* robot_message_type 10: line, column, text      */
} urt_script_msg_kind_t;

/* One message: a value with fixed-size, NUL-terminated buffers (no pointers). */
typedef struct urt_script_msg {
  int32_t kind;          /* urt_script_msg_kind_t                                         */
  int32_t code;          /* KEY: code (0)                                                  */
  int32_t argument;      /* KEY: argument (0)                                              */
  uint8_t warning, error, blocking;  /* POPUP: its flags                                    */
  uint32_t line;         /* RUNTIME_EXCEPTION: 1-based line of the offending token          */
  uint32_t column;       /* RUNTIME_EXCEPTION: 1-based column of the offending token        */
  double time;           /* controller time when it was emitted [s]                        */
  char title[64];        /* KEY: "PROGRAM_XXX_STARTED", "PROGRAM_XXX_STOPPED",
                            "SECONDARY_PROGRAM_EXCEPTION_XXX"; POPUP: its title             */
  char text[1024];       /* TEXT: the message; KEY: program name or error; EXCEPTION: text  */
} urt_script_msg_t;

/* The outside world of the runner. All four functions are called from the runner thread
 * only. submit must not block (return false when the command ring is full: the runner retries
 * on later ticks). wait_tick sleeps until a snapshot newer than after_tick exists or
 * timeout_ms passed, and returns the newest tick. Optional (nullable) kinematics let movej
 * take a pose and movel take joint positions; without them those forms are runtime errors. */
typedef struct urt_script_host {
  void *ctx;
  bool (*submit)(void *ctx, const urt_ctrl_cmd_t *cmd);
  uint64_t (*wait_tick)(void *ctx, uint64_t after_tick, int timeout_ms);
  void (*snapshot)(void *ctx, urt_snapshot_t *out);
  void (*message)(void *ctx, const urt_script_msg_t *msg);
  /* Nullable: joint positions reaching pose nearest qnear; returns 0 or nonzero (no solution). */
  int (*inverse_kinematics)(void *ctx, const double pose[6], const double qnear[URT_NJ],
                            double q[URT_NJ]);
  /* Nullable: TCP pose (with the active TCP offset) of joint positions q; returns 0. */
  int (*forward_kinematics)(void *ctx, const double q[URT_NJ], double pose[6]);
  /* Nullable: the RTDE register bank (protocols.md §2.5–2.6). read_registers copies all of it
   * consistently (one client data package is never seen half-applied), the input registers as
   * the controller latched them for tick (UINT64_MAX: the newest; the write counts are always
   * the newest); write_output_register sets one output register: kind URT_SCRIPT_REG_INT /
   * _DOUBLE / _BIT. */
  void (*read_registers)(void *ctx, uint64_t tick, urt_rtde_registers_t *out);
  void (*write_output_register)(void *ctx, int kind, int index, double value);
  /* Nullable: the loaded robot model, for native programs' kinematics and dynamics getters. */
  const urt_model_t *(*model)(void *ctx);
  /* Nullable: the snapshot of an earlier tick (get_actual_joint_positions_history); 0, or
   * nonzero when the controller no longer keeps it (or has not published it yet). */
  int (*snapshot_at)(void *ctx, uint64_t tick, urt_snapshot_t *out);
  /* Nullable: a (main) program has run its slice of tick (running), or has ended (!running):
   * the emulator keeps the output registers of each slice for that tick's RTDE package. */
  void (*tick_done)(void *ctx, uint64_t tick, bool running);
} urt_script_host_t;

enum { URT_SCRIPT_REG_INT = 0, URT_SCRIPT_REG_DOUBLE = 1, URT_SCRIPT_REG_BIT = 2 };

typedef struct urt_runner_config {
  int64_t step_budget;   /* a thread's slice: interpreter steps it may run in one controller
                            tick without waiting before it is preempted until the next; 20
                            slices in a row without a wait or a socket read are "Runtime is
                            too much behind" (0: 10000)                                    */
  int wait_timeout_ms;   /* timeout handed to wait_tick (0: default 20)                    */
  int rt_priority;       /* > 0: SCHED_FIFO priority of the script thread (best effort): a
                            real controller runs the script in its own cycle, so a script
                            thread that wakes late would fall behind controller time     */
  /* Hosts besides loopback (127.0.0.0/8, ::1, "localhost") that socket_open may dial, as
   * written in the script (--script-allow-host); at most 16, copied. Nullable when 0. */
  const char *const *allow_hosts;
  int n_allow_hosts;
  /* The emulated controller's software version (major, minor, bugfix): builtins whose
   * defaults changed between releases follow it (direct_torque). All 0: the newest. */
  int version[3];
} urt_runner_config_t;

typedef struct urt_runner urt_runner_t;

/* Create the runner and start its thread. The host is copied. Nullable: cfg.
 * Context: non-RT (allocates, starts a thread). Returns 0, URT_EINVAL (missing host
 * function, more than 16 allowed hosts or one longer than 255 bytes) or URT_EIO (thread
 * creation failed); *out untouched on failure. */
int urt_runner_create(const urt_script_host_t *host, const urt_runner_config_t *cfg,
                      urt_runner_t **out);

/* Queue one framed unit of URScript (copied). A main program or statement unit makes the
 * running main program stop at its next blocking point (HALT, PROGRAM_XXX_STOPPED) before the
 * new one starts; a `sec` unit runs alongside. Context: any thread; never waits for the
 * runner. Returns 0, URT_EINVAL (empty or larger than URT_SCRIPT_MAX_TEXT) or URT_EAGAIN
 * (more than 64 units queued). */
int urt_runner_submit(urt_runner_t *r, const char *text, size_t len);

/* Stop the running main program and drop queued main units (dashboard "stop").
 * Context: any thread. */
void urt_runner_stop(urt_runner_t *r);

/* URT_PROGRAM_STOPPED or URT_PROGRAM_PLAYING. Context: any thread. */
int urt_runner_state(const urt_runner_t *r);

/* Block until the runner has nothing queued and no main program runs, or timeout_ms passed.
 * Returns true when idle. Context: non-RT, not the runner thread (tests, shutdown). */
bool urt_runner_wait_idle(urt_runner_t *r, int timeout_ms);

/* Stop everything, join the thread, free. Nullable: r. Context: non-RT. */
void urt_runner_destroy(urt_runner_t *r);

/* The main programs' VM work per controller tick so far: the runner thread's CPU time from a
 * wait's return to its next wait (the service thread, every URScript thread's slice, the
 * switches), as quantiles and maximum [s]; 0 before the first tick. Context: any thread. */
typedef struct urt_runner_tick_stats {
  double p50, p99, p999, max;
  uint64_t ticks;
  /* slices the runner took after the controller had passed their tick (descheduled: their
   * commands reach a later tick), and the most ticks it was behind */
  uint64_t late_slices, late_max;
  /* URScript threads preempted until the next tick for running a whole slice (step_budget
   * steps) without waiting: a program computing more than UR's time slice, or spinning */
  uint64_t preempted;
  /* main programs' wall time from their arrival (urt_runner_submit) to PROGRAM_XXX_STARTED
   * [s]: the previous program's end, the compile, the controller's first tick. Clients time
   * it (URCL waits 100 ms after re-sending its program), so a slow start is named here. */
  double start_p50, start_max;
  uint64_t starts;
  double compile_p50, compile_max;  /* of that, the compile [s] */
  /* socket_opens that waited for a server on this machine to accept the connection
   * (script_builtins_socket.c, wait_accepted), and the most ticks one waited */
  uint64_t accept_waits, accept_wait_max;
} urt_runner_tick_stats_t;
void urt_runner_tick_stats(const urt_runner_t *r, urt_runner_tick_stats_t *out);

/* Parse and name-check one unit without running it. On failure msg (nullable) receives the
 * RUNTIME_EXCEPTION the runner would report. Context: any. Returns 0 or URT_EINVAL. */
int urt_script_check(const char *text, size_t len, urt_script_msg_t *msg);

#ifdef __cplusplus
}
#endif
#endif
