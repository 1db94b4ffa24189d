/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/fake_host.h — a fake controller behind urt_script_host_t: a virtual clock
 * that advances one tick (2 ms) per wait_tick call, motions that finish after motion_ticks
 * ticks, and a record of every command and message. Thread-safe (the runner calls it from its
 * thread while the test reads). */
#ifndef URT_TEST_FAKE_HOST_H
#define URT_TEST_FAKE_HOST_H

#include <pthread.h>
#include <string.h>
#include <unistd.h>

#include "urt/net/urscript.h"

#define FAKE_MAX 256
#define FAKE_HISTORY 64  /* snapshots kept for snapshot_at */

typedef struct fake_host {
  pthread_mutex_t mu;
  urt_snapshot_t s;
  int motion_ticks;         /* ticks a motion takes (0: done on submit)        */
  uint64_t motion_end;      /* tick at which the active motion finishes        */
  uint64_t pending_id;      /* id of the active motion                         */
  bool refuse_motion;       /* answer every motion with a protective stop      */
  int pause_stops;          /* the next this many motions meet a protective stop that pauses
                               a playing program, as the controller's (controller.cpp)     */
  uint64_t unlock_at;       /* nonzero: the protective stop is unlocked at this tick      */
  uint64_t resume_at;       /* nonzero: a paused program resumes (`play`) at this tick     */
  uint64_t pause_from;      /* nonzero: a dashboard `pause` of a playing program at this tick */
  uint64_t pstop_at;        /* nonzero: a protective stop at this tick (program paused too)  */
  int full_for;             /* refuse this many submits (ring full)            */
  int tick_sleep_us;        /* real time per tick (0: as fast as asked)        */
  unsigned jump_seed;       /* nonzero: each wait_tick advances 1–4 ticks (a late runner) */
  uint64_t vm_tick;         /* the tick the runner asked to process: last after_tick + 1  */
  uint64_t running_from;    /* nonzero: robot mode RUNNING from this tick on (a boot)     */
  bool ramp;                /* q_target[0] = 0.001·tick and tcp_force[2] = −tick each tick */
  uint64_t path_until;      /* nonzero: s.motion is URT_MOTION_PATH until this tick, then idle */
  uint64_t stall_at;        /* nonzero: from this tick, wait_tick times out (no tick) ...    */
  int stall_waits;          /* ... this many times, each after timeout_ms (a host stall)      */
  urt_ctrl_cmd_t cmd[FAKE_MAX];
  uint64_t cmd_vm_tick[FAKE_MAX];  /* vm_tick when each command arrived                */
  uint64_t cmd_tick[FAKE_MAX];     /* the controller's tick when each command arrived */
  int n_cmd;
  urt_script_msg_t msg[FAKE_MAX];
  int n_msg;
  urt_snapshot_t history[FAKE_HISTORY];  /* by tick % FAKE_HISTORY, written at each tick */
} fake_host;

static inline bool is_motion(int kind) {
  return (kind >= URT_CTRL_MOVEJ && kind <= URT_CTRL_STOPL) || kind == URT_CTRL_OPTIMOVEJ ||
         kind == URT_CTRL_MOVEP || kind == URT_CTRL_MOVEC || kind == URT_CTRL_OPTIMOVEL;
}

static inline bool fake_submit(void *ctx, const urt_ctrl_cmd_t *c) {
  fake_host *f = ctx;
  pthread_mutex_lock(&f->mu);
  if (f->full_for > 0) {
    f->full_for--;
    pthread_mutex_unlock(&f->mu);
    return false;
  }
  if (f->n_cmd < FAKE_MAX) {
    f->cmd_vm_tick[f->n_cmd] = f->vm_tick;
    f->cmd_tick[f->n_cmd] = f->s.tick;
    f->cmd[f->n_cmd++] = *c;
  }
  if (is_motion(c->kind)) {
    if (f->pause_stops > 0) {
      f->pause_stops--;
      f->s.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
      f->s.ctrl_fault = URT_CTRL_FAULT_IK;
      if (f->s.program_state == URT_PROGRAM_PLAYING) f->s.program_state = URT_PROGRAM_PAUSED;
      f->s.motion_done_id = c->id;
    } else if (f->refuse_motion) {
      f->s.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
      f->s.ctrl_fault = URT_CTRL_FAULT_PSTOP;
      f->s.motion_done_id = c->id;
    } else if (f->motion_ticks == 0) {
      f->s.ctrl_fault = 0;  // accepted: the last refusal is over, as the controller's
      f->s.motion_done_id = c->id;
    } else {
      f->s.ctrl_fault = 0;
      f->pending_id = c->id;
      f->motion_end = f->s.tick + (uint64_t)f->motion_ticks;
    }
    f->s.motion_id = c->id;
  } else if (c->kind == URT_CTRL_SET_DIGITAL_OUT) {
    f->s.digital_out = c->value != 0 ? f->s.digital_out | (1u << c->index)
                                     : f->s.digital_out & ~(1u << c->index);
  } else if (c->kind == URT_CTRL_PROGRAM_STATE) {
    f->s.program_state = c->index;
  } else if (c->kind == URT_CTRL_HALT) {
    if (f->pending_id) f->s.motion_done_id = f->pending_id;
    f->pending_id = 0;
  }
  pthread_mutex_unlock(&f->mu);
  return true;
}

static inline uint64_t fake_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  fake_host *f = ctx;
  if (f->tick_sleep_us > 0) usleep((useconds_t)f->tick_sleep_us);
  pthread_mutex_lock(&f->mu);
  if (f->stall_at && f->s.tick >= f->stall_at && f->stall_waits > 0) {
    f->stall_waits--;
    uint64_t t = f->s.tick;
    pthread_mutex_unlock(&f->mu);
    usleep((useconds_t)timeout_ms * 1000);
    return t;
  }
  f->vm_tick = after + 1;
  uint64_t n = 1;
  if (f->jump_seed) {
    f->jump_seed = f->jump_seed * 1103515245u + 12345u;
    if (!f->jump_seed) f->jump_seed = 1;
    n = f->s.tick <= after ? 1 + (uint64_t)((f->jump_seed >> 16) & 3) : 0;
  }
  for (uint64_t k = 0; k < n; k++) {  // every tick passed over is kept, as the controller does
    f->s.tick++;
    f->s.time = (double)f->s.tick * f->s.period;
    if (f->running_from && f->s.tick >= f->running_from) f->s.robot_mode = URT_ROBOT_MODE_RUNNING;
    if (f->unlock_at && f->s.tick >= f->unlock_at &&
        f->s.safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP) {
      f->s.safety_mode = URT_SAFETY_MODE_NORMAL;  // the program stays paused
    }
    if (f->resume_at && f->s.tick >= f->resume_at && f->s.program_state == URT_PROGRAM_PAUSED) {
      f->s.program_state = URT_PROGRAM_PLAYING;
    }
    if (f->pause_from && f->s.tick == f->pause_from && f->s.program_state == URT_PROGRAM_PLAYING) {
      f->s.program_state = URT_PROGRAM_PAUSED;
    }
    if (f->pstop_at && f->s.tick == f->pstop_at) {
      f->s.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
      if (f->s.program_state == URT_PROGRAM_PLAYING) f->s.program_state = URT_PROGRAM_PAUSED;
    }
    if (f->ramp) {  // readings that differ every tick
      f->s.q_target[0] = 0.001 * (double)f->s.tick;
      f->s.tcp_force[2] = -(double)f->s.tick;
    }
    if (f->path_until) {
      f->s.motion = f->s.tick < f->path_until ? URT_MOTION_PATH : URT_MOTION_IDLE;
    }
    if (f->pending_id && f->s.tick >= f->motion_end) {
      f->s.motion_done_id = f->pending_id;
      f->pending_id = 0;
    }
    f->history[f->s.tick % FAKE_HISTORY] = f->s;
  }
  uint64_t t = f->s.tick;
  pthread_mutex_unlock(&f->mu);
  return t;
}

static inline int fake_snapshot_at(void *ctx, uint64_t tick, urt_snapshot_t *out) {
  fake_host *f = ctx;
  pthread_mutex_lock(&f->mu);
  bool kept = tick <= f->s.tick && f->s.tick - tick < FAKE_HISTORY && f->history[tick % FAKE_HISTORY].tick == tick;
  if (kept) *out = f->history[tick % FAKE_HISTORY];
  pthread_mutex_unlock(&f->mu);
  return kept ? 0 : -1;
}

static inline void fake_snapshot(void *ctx, urt_snapshot_t *out) {
  fake_host *f = ctx;
  pthread_mutex_lock(&f->mu);
  *out = f->s;
  pthread_mutex_unlock(&f->mu);
}

static inline void fake_message(void *ctx, const urt_script_msg_t *m) {
  fake_host *f = ctx;
  pthread_mutex_lock(&f->mu);
  if (f->n_msg < FAKE_MAX) f->msg[f->n_msg++] = *m;
  pthread_mutex_unlock(&f->mu);
}

static inline int fake_ik(void *ctx, const double pose[6], const double qnear[URT_NJ],
                          double q[URT_NJ]) {
  for (int j = 0; j < 6; j++) q[j] = pose[j] + 100 + qnear[j];  // recognisable, qnear honoured
  return 0;
}

static inline void fake_init(fake_host *f, urt_script_host_t *h) {
  memset(f, 0, sizeof *f);
  pthread_mutex_init(&f->mu, NULL);
  f->s.period = 0.002;
  f->s.speed_scaling = 1.0;  /* as a controller at rest: slider 100 %, not paused */
  f->s.motion_rate = 1.0;
  f->s.safety_mode = URT_SAFETY_MODE_NORMAL;
  f->s.robot_mode = URT_ROBOT_MODE_RUNNING;
  f->s.program_state = URT_PROGRAM_STOPPED;
  *h = (urt_script_host_t){.ctx = f, .submit = fake_submit, .wait_tick = fake_wait_tick,
                           .snapshot = fake_snapshot, .message = fake_message,
                           .inverse_kinematics = fake_ik, .snapshot_at = fake_snapshot_at};
}

/* index of the first command of a kind at or after from, or -1 */
static inline int fake_find_cmd(fake_host *f, int kind, int from) {
  for (int k = from; k < f->n_cmd; k++) {
    if (f->cmd[k].kind == kind) return k;
  }
  return -1;
}

#endif
