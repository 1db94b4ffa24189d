/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/loop.h — the hard real-time loop: one physics thread that owns the model's
 * data and the controller, keeps simulation time locked to wall time, drains command rings and
 * publishes one snapshot per controller tick.
 *
 *   producers (one ring each) ──urt_loop_submit()──▶ [physics thread] ──▶ snapshot history
 *   readers: urt_loop_wait() for a new tick, then urt_loop_read(tick) — never blocking the writer.
 *
 * The physics thread never allocates, locks, blocks (other than its own pacing sleep) or prints.
 */
#ifndef URT_LOOP_H
#define URT_LOOP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/controller.h"
#include "urt/faults.h"
#include "urt/model.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum urt_pacing {
  URT_PACING_TICK = 0,   /* wake at each controller period (absolute clock_nanosleep), run its steps */
  URT_PACING_STEP,       /* wake once per physics step (isolated cores, PREEMPT_RT)                 */
  URT_PACING_FREE,       /* as fast as possible                                                     */
  URT_PACING_LOCKSTEP    /* a tick only when granted by urt_loop_grant()                            */
} urt_pacing_t;

#define URT_LOOP_HISTORY 512       /* snapshots kept (about 1 s at 500 Hz) */
#define URT_LOOP_MAX_PRODUCERS 8   /* command rings */
#define URT_LOOP_RING_CAPACITY 256 /* commands per ring */
// a paced loop that falls behind wall time catches up by running late ticks back to back; more
// than this many periods behind, it counts them as missed periods and re-anchors its clock. With
// no missed periods the tick count is therefore never more than this many periods off wall time
#define URT_LOOP_CATCH_UP_LIMIT 50

typedef struct urt_loop_config {
  double period;         /* controller period [s]: 0.002 e-Series, 0.008 CB3 */
  urt_pacing_t pacing;
  int powered;           /* 1: boot RUNNING + NORMAL; 0: POWER_OFF            */
  int rt_priority;       /* SCHED_FIFO priority, 0: do not ask                */
  int lock_memory;       /* 1: best-effort mlockall + stack prefault          */
  double drive_rate;     /* drive samples per second (0: none), at most 1/m->dt */
  urt_fault_scenario_t faults;  /* installed at start (urt/faults.h); n = 0: none */
} urt_loop_config_t;

/* The drive internals at a rate set apart from the controller's (up to 1 kHz and more),
 * for the LCM drive message and PHM research. */
typedef struct urt_drive_sample {
  uint64_t seq;                     /* sample number since start (1, 2, …)   */
  double time;                      /* physics time                [s]       */
  double q[URT_NJ], qd[URT_NJ];     /* joint position, speed [rad, rad/s]    */
  double motor_angle[URT_NJ], motor_speed[URT_NJ];  /* q_M, q̇_M [rad, rad/s] */
  double i[URT_NJ], i_ref[URT_NJ];  /* motor current, its reference [A]      */
  double v[URT_NJ];                 /* motor voltage               [V]       */
  double gear_in_torque[URT_NJ];    /* wave-generator input T_in   [N m]     */
  double gear_out_torque[URT_NJ];   /* circular-spline output T_CS [N m]     */
  double friction_torque[URT_NJ];   /* LuGre T_f                   [N m]     */
  double flex_x[URT_NJ], flex_y[URT_NJ];  /* flexspline deflection [m]       */
  double bristle_z[URT_NJ];         /* LuGre z                     [rad]     */
  double i_meas[URT_NJ];            /* the current sensor's reading [A]      */
  double temperature[URT_NJ];       /* motor winding temperature   [°C]      */
} urt_drive_sample_t;

typedef struct urt_loop urt_loop_t;

/* Build a loop around a loaded model, at rest at q0 (NULL: m->q0). Context: non-RT.
 * Returns 0 or URT_EINVAL (period not a whole number of m->dt) / URT_ENOMEM / URT_ESOLVER;
 * err receives a message. Nullable: q0, err. */
int urt_loop_create(const urt_model_t *m, const urt_loop_config_t *cfg, const double *q0,
                    urt_loop_t **out, char *err, size_t err_sz);

/* Start the physics thread. Warnings (no SCHED_FIFO, no mlockall) go to stderr, never fail.
 * Returns 0 or URT_EIO. */
int urt_loop_start(urt_loop_t *l);

/* Stop and join the physics thread (idempotent). Then free with urt_loop_destroy. */
void urt_loop_stop(urt_loop_t *l);
void urt_loop_destroy(urt_loop_t *l);

const urt_model_t *urt_loop_model(const urt_loop_t *l);
double urt_loop_period(const urt_loop_t *l);

/* Claim a command ring for the calling producer thread (one ring per producer thread).
 * Returns a producer index ≥ 0 or URT_ENOSPC. Context: non-RT, before or after start. */
int urt_loop_add_producer(urt_loop_t *l, const char *name);

/* Push one command; drained by the physics thread at the start of the next tick, the rings
 * taken in turn one command at a time (a ring's commands keep their order; no producer's
 * backlog goes before another's next command). Never waits: returns false (and counts it
 * for that ring) when that ring is full. A thread may own several rings (the I/O thread: one
 * per kind of client), a ring never more than one thread. */
bool urt_loop_submit(urt_loop_t *l, int producer, const urt_ctrl_cmd_t *cmd);

/* Tick of the newest published snapshot (0 before the first). Context: any. */
uint64_t urt_loop_latest_tick(const urt_loop_t *l);

/* Copy the snapshot of a given tick. Returns 0, URT_EAGAIN (not published yet) or URT_ERANGE
 * (already overwritten: the reader fell more than URT_LOOP_HISTORY ticks behind).
 * Context: any reader thread. */
int urt_loop_read(const urt_loop_t *l, uint64_t tick, urt_snapshot_t *out);

/* Copy the newest snapshot. Returns its tick. */
uint64_t urt_loop_read_latest(const urt_loop_t *l, urt_snapshot_t *out);

/* Sleep until a snapshot newer than after_tick exists or timeout_ms passes (futex; the
 * physics thread only wakes it, it never waits for it). Returns the newest tick. */
uint64_t urt_loop_wait(const urt_loop_t *l, uint64_t after_tick, int timeout_ms);

/* Drive samples, as for snapshots: newest seq, copy one (0 / URT_EAGAIN / URT_ERANGE). */
uint64_t urt_loop_latest_drive(const urt_loop_t *l);
int urt_loop_read_drive(const urt_loop_t *l, uint64_t seq, urt_drive_sample_t *out);

/* Also signal each new tick by writing 1 to an eventfd (non-blocking: a full counter is
 * simply not incremented), for a reader that waits in epoll. At most one; -1 removes it.
 * Returns once the physics thread no longer uses the previous fd (it may then be closed): a
 * wait of at most one eventfd write. Context: non-RT. */
void urt_loop_set_notify_fd(urt_loop_t *l, int eventfd);

/* The command rings claimed so far, and per ring its producer's name and the commands it
 * could not push because the ring was full (any thread). Returns the ring count; name and
 * dropped of ring i < count (NULL / 0 otherwise). */
int urt_loop_producer_count(const urt_loop_t *l);
const char *urt_loop_producer_name(const urt_loop_t *l, int producer);
uint64_t urt_loop_producer_dropped(const urt_loop_t *l, int producer);

/* The running program's thread has delivered its slice of controller tick `tick` (its commands
 * are submitted); 0: no program runs. Read by the physics thread before each period
 * (urt_ctrl_t.program_slice). Any thread; one writer (the program runner). */
void urt_loop_note_program_slice(urt_loop_t *l, uint64_t tick);

/* Lockstep pacing: allow n more controller ticks. Other pacings ignore it. */
void urt_loop_grant(urt_loop_t *l, uint64_t n);

/* Loop statistics (any thread). */
typedef struct urt_loop_stats {
  uint64_t ticks, overruns, missed_periods, cmd_dropped;
  double exec_max, exec_last;   /* physics time per period, wall clock [s] */
  /* quantiles of every period so far (urt/exec_hist.h: within 1/16 above the true value) of
   * the wall time (includes time the thread was preempted) and of the thread's CPU time [s] */
  double exec_p50, exec_p99, exec_p999;
  double cpu_p50, cpu_p99, cpu_p999, cpu_max;
  uint64_t refined_steps;       /* physics steps redone as sub-steps (urt_step) */
  /* periods whose wall / CPU time reached half the period (urt_exec_hist_count_from): how often
   * the worst case happened, where the maximum says only how bad it was once */
  uint64_t exec_over_half, cpu_over_half, exec_periods;
} urt_loop_stats_t;
void urt_loop_get_stats(const urt_loop_t *l, urt_loop_stats_t *out);

#ifdef __cplusplus
}
#endif
#endif
