/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/runner.c — the program runner thread: a queue of framed URScript units, one
 * main program at a time, secondary programs in between, and the program-state bookkeeping a
 * real controller reports (PROGRAM_XXX_STARTED/STOPPED, PROGRAM_STATE, HALT on stop).
 *
 * Cancellation is cooperative: a newer main unit or a stop makes the running program's next
 * wait (every blocking builtin waits through host->wait_tick) return US_ERR_CANCEL. Secondary
 * programs queued meanwhile run at those waits, so they never wait for the main program to end.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "script.h"
#include "script_socket.h"
#include "urt/errors.h"
#include "urt/thread.h"

#define QUEUE_CAP 64
#define HALT_DECELERATION 4.0  /* [rad/s²] joint deceleration of the stop that ends a program */
#define SUBMIT_RETRY_TICKS 100
#define CLOSE_WAIT_MS 250      /* [ms] at most, at a program's end, for the peers to close their ends */
#define FIRST_TICK_TRIES 100   /* waits of wait_timeout_ms for the controller's first tick before a program starts */
#define FINISH_STALL_MS 1000   /* [ms] without a tick before a program's last move is no longer waited for */

typedef struct unit {
  char *text;
  size_t len;
  bool sec;
  uint64_t seq;   /* main units: their place in submission order */
  uint64_t arrived_ns;  /* CLOCK_MONOTONIC at urt_runner_submit */
} unit;

struct urt_runner {
  urt_script_host_t host;
  urt_runner_config_t cfg;
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t cv;       /* work arrived / quit                 */
  pthread_cond_t idle_cv;  /* the thread became idle              */
  unit q[QUEUE_CAP];       /* FIFO, q[0] first                    */
  int qn;
  uint64_t main_seq;       /* seq of the newest main unit submitted */
  uint64_t stop_seq;       /* bumped by urt_runner_stop             */
  bool quit, busy;
  _Atomic int state;       /* URT_PROGRAM_*                         */
  uint64_t motion_id;      /* runner thread only                    */
  us_sockets *sockets;     /* the main program's sockets (runner thread only) */
  urt_exec_hist_t tick_cpu;  /* main programs' VM work per tick (runner thread writes) */
  uint64_t late_slices, late_max;  /* slices taken after their tick had passed (us_hooks) */
  uint64_t preempted;              /* threads preempted for computing a whole slice (us_hooks) */
  urt_exec_hist_t start_wall;      /* main programs: arrival to PROGRAM_XXX_STARTED (wall) */
  urt_exec_hist_t compile_wall;    /* main programs: their compile (wall) */
  /* the running main program (runner thread only) */
  uint64_t cur_seq, cur_stop;
};

//---- helpers (runner thread) ----

static uint64_t mono_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (uint64_t)t.tv_sec * 1000000000u + (uint64_t)t.tv_nsec;
}

static uint64_t since_ns(uint64_t from) {
  uint64_t now = mono_ns();
  return now > from ? now - from : 0;
}

static double now_time(urt_runner_t *r) {
  urt_snapshot_t s;
  r->host.snapshot(r->host.ctx, &s);
  return s.time;
}

static void emit(urt_runner_t *r, urt_script_msg_t *m) {
  m->time = now_time(r);
  r->host.message(r->host.ctx, m);
}

static void emit_key(urt_runner_t *r, const char *title, const char *text) {
  urt_script_msg_t m;
  memset(&m, 0, sizeof m);
  m.kind = URT_SCRIPT_MSG_KEY;
  snprintf(m.title, sizeof m.title, "%s", title);
  snprintf(m.text, sizeof m.text, "%s", text);
  emit(r, &m);
}

/* a command outside a program (state, halt): retried on later ticks, never forever */
static void submit_retry(urt_runner_t *r, const urt_ctrl_cmd_t *cmd) {
  urt_snapshot_t s;
  r->host.snapshot(r->host.ctx, &s);
  uint64_t tick = s.tick;
  for (int k = 0; k < SUBMIT_RETRY_TICKS; k++) {
    if (r->host.submit(r->host.ctx, cmd)) {
      return;
    }
    tick = r->host.wait_tick(r->host.ctx, tick, r->cfg.wait_timeout_ms);
  }
}

static void set_state(urt_runner_t *r, int state) {
  atomic_store(&r->state, state);
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_PROGRAM_STATE, .index = state};
  submit_retry(r, &c);
}

static void report(urt_runner_t *r, const us_err *e, bool secondary) {
  if (e->kind == US_ERR_NONE || e->kind == US_ERR_CANCEL) {
    return;
  }
  urt_script_msg_t m;
  urt__us_err_msg(e, secondary, &m);
  emit(r, &m);
}

static void run_sec(urt_runner_t *r, const unit *u) {
  us_prog *p = NULL;
  us_err e;
  if (urt__us_parse(u->text, u->len, &p, &e) != 0) {
    report(r, &e, true);
    return;
  }
  us_hooks h = {.host = &r->host, .motion_id = &r->motion_id, .step_budget = r->cfg.step_budget,
                .wait_timeout_ms = r->cfg.wait_timeout_ms,
                .version = {r->cfg.version[0], r->cfg.version[1], r->cfg.version[2]}};
  // a sec unit's program must not block: mark it secondary whatever its first keyword
  p->secondary = true;
  if (urt__us_run(p, &h, &e) != 0) {
    report(r, &e, true);
  }
  urt__us_prog_free(p);
}

/* called at every wait of the main program: run queued secondary units, tell if cancelled */
static int poll_main(void *ctx) {
  urt_runner_t *r = ctx;
  for (;;) {
    unit u = {0};
    pthread_mutex_lock(&r->mu);
    bool cancel = r->quit || r->main_seq > r->cur_seq || r->stop_seq != r->cur_stop;
    for (int k = 0; k < r->qn; k++) {
      if (r->q[k].sec) {
        u = r->q[k];
        memmove(&r->q[k], &r->q[k + 1], (size_t)(r->qn - k - 1) * sizeof r->q[0]);
        r->qn--;
        break;
      }
    }
    pthread_mutex_unlock(&r->mu);
    if (!u.text) {
      return cancel;
    }
    run_sec(r, &u);
    free(u.text);
  }
}

/* a program that ended normally with a move whose blend radius let it go on (its id done, the
 * arm still on the way, core/motion_path.cpp) ends when that move has stopped at its target, as
 * the last motion of a sequence does on a controller; a stop request or a controller that no
 * longer ticks (none for FINISH_STALL_MS) ends the wait. One wait_tick timeout is not that: a
 * busy host held urtwin's physics thread off for 27 ms in a fresh clone's test run, the wait
 * (20 ms) ended, and the program's HALT stopped its last movel 27 mm short of its target */
static void finish_path(urt_runner_t *r) {
  urt_snapshot_t s;
  r->host.snapshot(r->host.ctx, &s);
  uint64_t stalled_from = 0;  // when the ticks stopped coming (0: they come)
  while (s.motion == URT_MOTION_PATH && !poll_main(r)) {
    uint64_t tick = s.tick;
    if (r->host.wait_tick(r->host.ctx, tick, r->cfg.wait_timeout_ms) == tick) {
      if (!stalled_from) {
        stalled_from = mono_ns();
      } else if (since_ns(stalled_from) >= (uint64_t)FINISH_STALL_MS * 1000000u) {
        break;
      }
    } else {
      stalled_from = 0;
    }
    r->host.snapshot(r->host.ctx, &s);
  }
}

static void run_main(urt_runner_t *r, const unit *u) {
  us_prog *p = NULL;
  us_err e;

  // compile first: a program with a compile error never starts, nothing moves
  uint64_t compile_from = mono_ns();
  if (urt__us_parse(u->text, u->len, &p, &e) != 0) {
    report(r, &e, false);
    return;
  }
  urt_exec_hist_add(&r->compile_wall, since_ns(compile_from));

  // the ports open before the physics thread publishes its first tick, and a program that
  // came in between read the snapshot of none (robot mode 0): its first move was refused as
  // "robot is not running" (1 in 14–27 runs of a program sent as soon as 30002 accepted)
  urt_snapshot_t s;
  r->host.snapshot(r->host.ctx, &s);
  for (int k = 0; s.tick == 0 && k < FIRST_TICK_TRIES && !poll_main(r); k++) {
    r->host.wait_tick(r->host.ctx, 0, r->cfg.wait_timeout_ms);
    r->host.snapshot(r->host.ctx, &s);
  }

  set_state(r, URT_PROGRAM_PLAYING);
  emit_key(r, "PROGRAM_XXX_STARTED", p->name);
  urt_exec_hist_add(&r->start_wall, since_ns(u->arrived_ns));
  us_hooks h = {.host = &r->host, .sockets = r->sockets, .motion_id = &r->motion_id,
                .step_budget = r->cfg.step_budget, .wait_timeout_ms = r->cfg.wait_timeout_ms,
                .poll = poll_main, .poll_ctx = r, .tick_cpu = &r->tick_cpu,
                .late_slices = &r->late_slices, .late_max = &r->late_max,
                .preempted = &r->preempted,
                .version = {r->cfg.version[0], r->cfg.version[1], r->cfg.version[2]}};
  p->secondary = false;
  if (urt__us_run(p, &h, &e) != 0) {
    report(r, &e, false);
  } else {
    finish_path(r);
  }
  // the end of a program stops the arm (speedj without t, blends, a stop from outside), at
  // once: not after the wait for the peers below
  urt_ctrl_cmd_t halt = {.kind = URT_CTRL_HALT, .a = HALT_DECELERATION};
  submit_retry(r, &halt);

  // the peers see the disconnect now, before the next program dials them (URCL's servers
  // take one client each: external_control.md §2.1, §6): each peer has closed its end, or
  // CLOSE_WAIT_MS went by
  urt__us_sockets_close_all_wait(r->sockets, CLOSE_WAIT_MS);
  set_state(r, URT_PROGRAM_STOPPED);
  emit_key(r, "PROGRAM_XXX_STOPPED", p->name);
  urt__us_prog_free(p);
}

static void *thread_main(void *arg) {
  urt_runner_t *r = arg;
  for (;;) {
    pthread_mutex_lock(&r->mu);
    while (r->qn == 0 && !r->quit) {
      r->busy = false;
      pthread_cond_broadcast(&r->idle_cv);
      pthread_cond_wait(&r->cv, &r->mu);
    }
    if (r->quit) {
      r->busy = false;
      pthread_cond_broadcast(&r->idle_cv);
      pthread_mutex_unlock(&r->mu);
      return NULL;
    }
    unit u = r->q[0];
    memmove(&r->q[0], &r->q[1], (size_t)(r->qn - 1) * sizeof r->q[0]);
    r->qn--;
    r->busy = true;
    r->cur_seq = u.seq;
    r->cur_stop = r->stop_seq;
    pthread_mutex_unlock(&r->mu);

    if (u.sec) {
      run_sec(r, &u);
    } else {
      run_main(r, &u);
    }
    free(u.text);
  }
}

//---- public API ----

/* `sec` as the first word (after blanks and comments) makes a secondary unit */
static bool is_sec_unit(const char *s, size_t len) {
  size_t k = 0;
  while (k < len) {
    char c = s[k];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      k++;
    } else if (c == '#' || c == '$') {
      while (k < len && s[k] != '\n') k++;
    } else {
      break;
    }
  }
  if (len - k < 4 || memcmp(s + k, "sec", 3) != 0) {
    return false;
  }
  char c = s[k + 3];
  return !((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_');
}

int urt_runner_create(const urt_script_host_t *host, const urt_runner_config_t *cfg,
                      urt_runner_t **out) {
  if (!host || !out || !host->submit || !host->wait_tick || !host->snapshot || !host->message) {
    return URT_EINVAL;
  }
  urt_runner_t *r = calloc(1, sizeof *r);
  if (!r) {
    return URT_ENOMEM;
  }
  r->host = *host;
  if (cfg) {
    r->cfg = *cfg;
  }
  r->sockets = urt__us_sockets_new(r->cfg.allow_hosts, r->cfg.n_allow_hosts);
  r->cfg.allow_hosts = NULL;  // copied into the table
  if (!r->sockets) {
    free(r);
    return URT_EINVAL;
  }
  if (r->cfg.step_budget <= 0) {
    r->cfg.step_budget = 10000;
  }
  if (r->cfg.wait_timeout_ms <= 0) {
    r->cfg.wait_timeout_ms = 20;
  }
  atomic_init(&r->state, URT_PROGRAM_STOPPED);
  pthread_mutex_init(&r->mu, NULL);
  pthread_cond_init(&r->cv, NULL);
  pthread_cond_init(&r->idle_cv, NULL);

  // the interpreter recurses (bounded by URT_SCRIPT_MAX_DEPTH and the eval depth); 8 MiB is what
  // the fuzzer ran millions of inputs in under ASan (a main thread's default stack)
  int rc = urt_thread_start(&r->thread, thread_main, r, 8u << 20);
  if (rc == 0) {
    urt_thread_set_fifo(r->thread, r->cfg.rt_priority, "script thread");
  }
  if (rc != 0) {
    pthread_cond_destroy(&r->idle_cv);
    pthread_cond_destroy(&r->cv);
    pthread_mutex_destroy(&r->mu);
    urt__us_sockets_free(r->sockets);
    free(r);
    return URT_EIO;
  }
  *out = r;
  return 0;
}

int urt_runner_submit(urt_runner_t *r, const char *text, size_t len) {
  if (!r || !text || len == 0 || len > URT_SCRIPT_MAX_TEXT) {
    return URT_EINVAL;
  }
  char *copy = malloc(len + 1);
  if (!copy) {
    return URT_ENOMEM;
  }
  memcpy(copy, text, len);
  copy[len] = 0;
  unit u = {.text = copy, .len = len, .sec = is_sec_unit(text, len), .arrived_ns = mono_ns()};

  pthread_mutex_lock(&r->mu);
  if (r->qn == QUEUE_CAP) {
    pthread_mutex_unlock(&r->mu);
    free(copy);
    return URT_EAGAIN;
  }
  if (!u.sec) {
    u.seq = ++r->main_seq;
  }
  r->q[r->qn++] = u;
  r->busy = true;
  pthread_cond_signal(&r->cv);
  pthread_mutex_unlock(&r->mu);
  return 0;
}

void urt_runner_stop(urt_runner_t *r) {
  if (!r) {
    return;
  }
  pthread_mutex_lock(&r->mu);
  r->stop_seq++;
  for (int k = 0; k < r->qn;) {
    if (!r->q[k].sec) {
      free(r->q[k].text);
      memmove(&r->q[k], &r->q[k + 1], (size_t)(r->qn - k - 1) * sizeof r->q[0]);
      r->qn--;
    } else {
      k++;
    }
  }
  pthread_mutex_unlock(&r->mu);
}

int urt_runner_state(const urt_runner_t *r) {
  return r ? atomic_load(&((urt_runner_t *)r)->state) : URT_PROGRAM_STOPPED;
}

bool urt_runner_wait_idle(urt_runner_t *r, int timeout_ms) {
  struct timespec until;
  clock_gettime(CLOCK_REALTIME, &until);
  until.tv_sec += timeout_ms / 1000;
  until.tv_nsec += (long)(timeout_ms % 1000) * 1000000L;
  if (until.tv_nsec >= 1000000000L) {
    until.tv_sec++;
    until.tv_nsec -= 1000000000L;
  }
  pthread_mutex_lock(&r->mu);
  int rc = 0;
  while ((r->busy || r->qn > 0) && rc == 0) {
    rc = pthread_cond_timedwait(&r->idle_cv, &r->mu, &until);
  }
  bool idle = !r->busy && r->qn == 0;
  pthread_mutex_unlock(&r->mu);
  return idle;
}

void urt_runner_destroy(urt_runner_t *r) {
  if (!r) {
    return;
  }
  pthread_mutex_lock(&r->mu);
  r->quit = true;
  pthread_cond_broadcast(&r->cv);
  pthread_mutex_unlock(&r->mu);
  pthread_join(r->thread, NULL);
  for (int k = 0; k < r->qn; k++) {
    free(r->q[k].text);
  }
  pthread_cond_destroy(&r->idle_cv);
  pthread_cond_destroy(&r->cv);
  pthread_mutex_destroy(&r->mu);
  urt__us_sockets_free(r->sockets);
  free(r);
}

void urt_runner_tick_stats(const urt_runner_t *r, urt_runner_tick_stats_t *out) {
  out->p50 = urt_exec_hist_quantile(&r->tick_cpu, 0.50);
  out->p99 = urt_exec_hist_quantile(&r->tick_cpu, 0.99);
  out->p999 = urt_exec_hist_quantile(&r->tick_cpu, 0.999);
  out->max = urt_exec_hist_max(&r->tick_cpu);
  out->ticks = urt_exec_hist_count(&r->tick_cpu);
  out->late_slices = __atomic_load_n(&r->late_slices, __ATOMIC_RELAXED);
  out->late_max = __atomic_load_n(&r->late_max, __ATOMIC_RELAXED);
  out->preempted = __atomic_load_n(&r->preempted, __ATOMIC_RELAXED);
  out->start_p50 = urt_exec_hist_quantile(&r->start_wall, 0.50);
  out->start_max = urt_exec_hist_max(&r->start_wall);
  out->starts = urt_exec_hist_count(&r->start_wall);
  out->compile_p50 = urt_exec_hist_quantile(&r->compile_wall, 0.50);
  out->compile_max = urt_exec_hist_max(&r->compile_wall);
  out->accept_waits = __atomic_load_n(&r->sockets->accept_waits, __ATOMIC_RELAXED);
  out->accept_wait_max = __atomic_load_n(&r->sockets->accept_wait_max, __ATOMIC_RELAXED);
}
