/* SPDX-License-Identifier: Apache-2.0
 * core/loop.c — the hard real-time loop (loop.h). One physics thread owns urt_data_t and
 * urt_ctrl_t; everything else talks to it through command rings (in) and a seqlocked snapshot
 * history (out). Inside the cycle: no allocation, no locks, no printing; the only system calls
 * are the pacing sleep, clock reads (vDSO, plus one CLOCK_THREAD_CPUTIME_ID read per period: a
 * short non-blocking call) and a futex wake when a reader sleeps.
 */
#define _GNU_SOURCE
#include "urt/loop.h"

#include <errno.h>
#include <limits.h>
#include <linux/futex.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include "urt/core.h"
#include "urt/exec_hist.h"
#include "urt/seqlock.h"
#include "urt/spsc_ring.h"
#include "urt/thread.h"

#define DRIVE_HISTORY 1024          /* drive samples kept (1 s at 1 kHz)            */
#define STACK_PREFAULT (256 * 1024) /* bytes of stack touched before the loop        */
#define PHYSICS_STACK (1024 * 1024) /* the physics thread's whole stack                */

struct urt_loop {
  const urt_model_t *m;
  urt_loop_config_t cfg;
  int n_sub;                        /* physics steps per controller period */
  int64_t period_ns, dt_ns;

  /* owned by the physics thread once started */
  urt_data_t d;
  urt_ctrl_t c;
  urt_snapshot_t snap;
  urt_drive_sample_t drive;
  int drive_every;                  /* physics steps per drive sample (0: none) */
  uint64_t steps;

  /* clients → physics: one SPSC ring per producer thread */
  urt_spsc_ring_t ring[URT_LOOP_MAX_PRODUCERS];
  urt_ctrl_cmd_t ring_storage[URT_LOOP_MAX_PRODUCERS][URT_LOOP_RING_CAPACITY];
  char producer_name[URT_LOOP_MAX_PRODUCERS][32];
  _Atomic int n_producers;
  pthread_mutex_t producer_lock;    /* non-RT: only add_producer takes it */

  /* physics → readers */
  urt_seqlock_t *history;           /* URT_LOOP_HISTORY slots, indexed by tick  */
  urt_seqlock_t *drive_history;     /* DRIVE_HISTORY slots, indexed by seq      */
  _Atomic uint64_t latest_tick, latest_drive;
  _Atomic uint32_t futex_word;      /* low bits of latest_tick, for futex waits */
  _Atomic int waiters;
  _Atomic int notify_fd;            /* eventfd written after each tick, or -1   */
  atomic_bool notify_busy;          /* the physics thread holds a notify_fd value */

  _Atomic uint64_t program_slice;   /* urt_loop_note_program_slice */

  /* lockstep */
  _Atomic uint64_t granted;         /* ticks allowed so far */
  _Atomic uint32_t grant_word;

  /* statistics */
  _Atomic uint64_t overruns, missed_periods;
  _Atomic uint64_t exec_last_ns;
  urt_exec_hist_t exec_hist;        /* wall time of each period's work             */
  urt_exec_hist_t cpu_hist;         /* the thread's CPU time per period            */
  _Atomic uint64_t refined_steps;   /* copy of d.refined_count for other threads   */

  pthread_t thread;
  _Atomic int stop;
  int started;
};

//---- time helpers ----

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static struct timespec to_timespec(int64_t ns) {
  struct timespec ts = {(time_t)(ns / 1000000000LL), (long)(ns % 1000000000LL)};
  return ts;
}

// Sleep until an absolute CLOCK_MONOTONIC time; EINTR just retries.
static void sleep_until(int64_t t_ns) {
  struct timespec ts = to_timespec(t_ns);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
  }
}

static void futex_wake_all(_Atomic uint32_t *w) {
  syscall(SYS_futex, (uint32_t *)w, FUTEX_WAKE_PRIVATE, INT_MAX, NULL, NULL, 0);
}

static void futex_wait(_Atomic uint32_t *w, uint32_t expected, int64_t timeout_ns) {
  struct timespec ts = to_timespec(timeout_ns > 0 ? timeout_ns : 0);
  syscall(SYS_futex, (uint32_t *)w, FUTEX_WAIT_PRIVATE, expected, &ts, NULL, 0);
}

//---- creation ----

int urt_loop_create(const urt_model_t *m, const urt_loop_config_t *cfg, const double *q0,
                    urt_loop_t **out, char *err, size_t err_sz) {
  if (!m || !cfg || !out) {
    return URT_EINVAL;
  }
  double ratio = cfg->period / m->dt;
  int n_sub = (int)lround(ratio);
  if (cfg->period <= 0 || n_sub < 1 || fabs(ratio - n_sub) > 1e-9 * ratio) {
    if (err) {
      snprintf(err, err_sz, "controller period %g s is not a whole number of physics steps (dt %g s)",
               cfg->period, m->dt);
    }
    return URT_EINVAL;
  }
  if (cfg->drive_rate < 0 || cfg->drive_rate * m->dt > 1.0 + 1e-12) {
    if (err) {
      snprintf(err, err_sz, "drive rate %g Hz must be in [0, %g] (the physics rate)", cfg->drive_rate,
               1.0 / m->dt);
    }
    return URT_EINVAL;
  }
  urt_loop_t *l = calloc(1, sizeof *l);
  if (!l) {
    return URT_ENOMEM;
  }
  l->history = calloc(URT_LOOP_HISTORY, sizeof *l->history);
  l->drive_history = calloc(DRIVE_HISTORY, sizeof *l->drive_history);
  if (!l->history || !l->drive_history) {
    urt_loop_destroy(l);
    return URT_ENOMEM;
  }
  l->m = m;
  l->cfg = *cfg;
  l->notify_fd = -1;
  l->n_sub = n_sub;
  l->dt_ns = llround(m->dt * 1e9);
  l->period_ns = l->dt_ns * n_sub;
  l->drive_every = cfg->drive_rate > 0 ? (int)lround(1.0 / (cfg->drive_rate * m->dt)) : 0;
  pthread_mutex_init(&l->producer_lock, NULL);
  for (int i = 0; i < URT_LOOP_HISTORY; i++) {
    urt_seqlock_init(&l->history[i], sizeof(urt_snapshot_t));
  }
  for (int i = 0; i < DRIVE_HISTORY; i++) {
    urt_seqlock_init(&l->drive_history[i], sizeof(urt_drive_sample_t));
  }
  int rc = urt_data_init(m, &l->d, q0);
  if (rc == 0 && cfg->faults.n > 0) {
    rc = urt_data_set_faults(m, &l->d, &cfg->faults);
  }
  if (rc == 0) {
    rc = urt_ctrl_init(m, &l->c, &l->d, cfg->period, cfg->powered);
  }
  if (rc != 0) {
    if (err) {
      snprintf(err, err_sz, "cannot start at the initial pose: %s", urt_strerror(rc));
    }
    urt_loop_destroy(l);
    return rc;
  }
  *out = l;
  return URT_OK;
}

void urt_loop_destroy(urt_loop_t *l) {
  if (!l) {
    return;
  }
  urt_loop_stop(l);
  free(l->history);
  free(l->drive_history);
  pthread_mutex_destroy(&l->producer_lock);
  free(l);
}

const urt_model_t *urt_loop_model(const urt_loop_t *l) { return l->m; }
double urt_loop_period(const urt_loop_t *l) { return l->cfg.period; }

//---- producers ----

int urt_loop_add_producer(urt_loop_t *l, const char *name) {
  pthread_mutex_lock(&l->producer_lock);
  int i = atomic_load(&l->n_producers);
  if (i >= URT_LOOP_MAX_PRODUCERS) {
    pthread_mutex_unlock(&l->producer_lock);
    return URT_ENOSPC;
  }
  urt_spsc_ring_init(&l->ring[i], l->ring_storage[i], URT_LOOP_RING_CAPACITY, sizeof(urt_ctrl_cmd_t));
  snprintf(l->producer_name[i], sizeof l->producer_name[i], "%s", name ? name : "");
  // publish the ring only once it is initialised: the physics thread reads n_producers
  atomic_store_explicit(&l->n_producers, i + 1, memory_order_release);
  pthread_mutex_unlock(&l->producer_lock);
  return i;
}

bool urt_loop_submit(urt_loop_t *l, int producer, const urt_ctrl_cmd_t *cmd) {
  if (producer < 0 || producer >= atomic_load_explicit(&l->n_producers, memory_order_acquire)) {
    return false;
  }
  return urt_spsc_ring_try_push(&l->ring[producer], cmd);
}

//---- readers ----

uint64_t urt_loop_latest_tick(const urt_loop_t *l) {
  return atomic_load_explicit(&l->latest_tick, memory_order_acquire);
}

// Copy slot seq % n of a history whose payload starts with its own uint64 sequence number.
static int read_slot(const urt_seqlock_t *slots, size_t n, uint64_t seq, void *out) {
  if (seq == 0) {
    return URT_EAGAIN;
  }
  if (urt_seqlock_read(&slots[seq % n], out, 0) < 0) {
    return URT_EAGAIN;
  }
  uint64_t got;
  memcpy(&got, out, sizeof got);
  if (got == seq) {
    return URT_OK;
  }
  return got > seq ? URT_ERANGE : URT_EAGAIN;
}

int urt_loop_read(const urt_loop_t *l, uint64_t tick, urt_snapshot_t *out) {
  _Static_assert(offsetof(urt_snapshot_t, tick) == 0, "the history reads the tick first");
  return read_slot(l->history, URT_LOOP_HISTORY, tick, out);
}

uint64_t urt_loop_read_latest(const urt_loop_t *l, urt_snapshot_t *out) {
  for (;;) {
    uint64_t t = urt_loop_latest_tick(l);
    if (t == 0) {
      memset(out, 0, sizeof *out);
      return 0;
    }
    if (urt_loop_read(l, t, out) == URT_OK) {
      return t;
    }
  }
}

uint64_t urt_loop_wait(const urt_loop_t *l, uint64_t after_tick, int timeout_ms) {
  urt_loop_t *w = (urt_loop_t *)l;  // the futex word and waiter count are reader bookkeeping
  int64_t deadline = now_ns() + (int64_t)timeout_ms * 1000000LL;
  for (;;) {
    atomic_fetch_add(&w->waiters, 1);
    uint32_t seen = atomic_load(&w->futex_word);
    uint64_t t = urt_loop_latest_tick(l);
    int64_t left = deadline - now_ns();
    if (t > after_tick || left <= 0) {
      atomic_fetch_sub(&w->waiters, 1);
      return t;
    }
    futex_wait(&w->futex_word, seen, left);
    atomic_fetch_sub(&w->waiters, 1);
  }
}

uint64_t urt_loop_latest_drive(const urt_loop_t *l) {
  return atomic_load_explicit(&l->latest_drive, memory_order_acquire);
}

int urt_loop_read_drive(const urt_loop_t *l, uint64_t seq, urt_drive_sample_t *out) {
  _Static_assert(offsetof(urt_drive_sample_t, seq) == 0, "the history reads seq first");
  return read_slot(l->drive_history, DRIVE_HISTORY, seq, out);
}

void urt_loop_set_notify_fd(urt_loop_t *l, int eventfd) {
  atomic_store(&l->notify_fd, eventfd);
  // acknowledge: once notify_busy reads false after the store, the physics thread has either
  // finished with the old fd or will load the new one (sequentially consistent order: it raises
  // notify_busy before it loads the fd); its write takes microseconds
  while (atomic_load(&l->notify_busy)) {
    struct timespec ts = {0, 20000};
    nanosleep(&ts, NULL);
  }
}

int urt_loop_producer_count(const urt_loop_t *l) {
  return atomic_load_explicit(&l->n_producers, memory_order_acquire);
}

const char *urt_loop_producer_name(const urt_loop_t *l, int producer) {
  return producer >= 0 && producer < urt_loop_producer_count(l) ? l->producer_name[producer]
                                                                 : NULL;
}

uint64_t urt_loop_producer_dropped(const urt_loop_t *l, int producer) {
  if (producer < 0 || producer >= urt_loop_producer_count(l)) {
    return 0;
  }
  return atomic_load_explicit(&l->ring[producer].dropped, memory_order_relaxed);
}

void urt_loop_note_program_slice(urt_loop_t *l, uint64_t tick) {
  // release: the slice's commands, pushed before, are in the rings when the physics sees it
  atomic_store_explicit(&l->program_slice, tick, memory_order_release);
}

void urt_loop_grant(urt_loop_t *l, uint64_t n) {
  atomic_fetch_add(&l->granted, n);
  atomic_fetch_add(&l->grant_word, 1);
  futex_wake_all(&l->grant_word);
}

void urt_loop_get_stats(const urt_loop_t *l, urt_loop_stats_t *out) {
  uint64_t dropped = 0;
  int n = atomic_load(&l->n_producers);
  for (int i = 0; i < n; i++) {
    dropped += atomic_load_explicit(&l->ring[i].dropped, memory_order_relaxed);  // producer-owned
  }
  out->ticks = urt_loop_latest_tick(l);
  out->overruns = atomic_load(&l->overruns);
  out->missed_periods = atomic_load(&l->missed_periods);
  out->cmd_dropped = dropped;
  out->exec_last = atomic_load(&l->exec_last_ns) * 1e-9;
  out->exec_max = urt_exec_hist_max(&l->exec_hist);  // the histogram keeps the exact maximum
  out->exec_p50 = urt_exec_hist_quantile(&l->exec_hist, 0.50);
  out->exec_p99 = urt_exec_hist_quantile(&l->exec_hist, 0.99);
  out->exec_p999 = urt_exec_hist_quantile(&l->exec_hist, 0.999);
  out->cpu_p50 = urt_exec_hist_quantile(&l->cpu_hist, 0.50);
  out->cpu_p99 = urt_exec_hist_quantile(&l->cpu_hist, 0.99);
  out->cpu_p999 = urt_exec_hist_quantile(&l->cpu_hist, 0.999);
  out->cpu_max = urt_exec_hist_max(&l->cpu_hist);
  out->refined_steps = atomic_load_explicit(&l->refined_steps, memory_order_relaxed);
  out->exec_over_half = urt_exec_hist_count_from(&l->exec_hist, 0.5 * l->cfg.period);
  out->cpu_over_half = urt_exec_hist_count_from(&l->cpu_hist, 0.5 * l->cfg.period);
  out->exec_periods = urt_exec_hist_count(&l->exec_hist);
}

//---- the physics thread ----

// Best-effort real-time set-up: warn, never fail (the emulator must also run on a laptop).
static void rt_setup(const urt_loop_config_t *cfg) {
  if (cfg->lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      fprintf(stderr, "urtwin: warning: mlockall failed (%s); running without locked memory\n",
              strerror(errno));
    }
    volatile unsigned char stack[STACK_PREFAULT];
    for (size_t i = 0; i < sizeof stack; i += 4096) {
      stack[i] = 0;
    }
  }
  urt_thread_set_fifo(pthread_self(), cfg->rt_priority, "physics thread");
}

// Round robin, one command per ring per pass, so that a flooded ring does not go before the
// others' commands; bounded: at most what the rings held when the pass began plus what
// producers push meanwhile, never more than URT_LOOP_RING_CAPACITY passes.
static void drain_commands(urt_loop_t *l) {
  int n = atomic_load_explicit(&l->n_producers, memory_order_acquire);
  urt_ctrl_cmd_t cmd;
  for (int pass = 0; pass < URT_LOOP_RING_CAPACITY; pass++) {
    bool any = false;
    for (int i = 0; i < n; i++) {
      if (urt_spsc_ring_try_pop(&l->ring[i], &cmd)) {
        urt_ctrl_apply(l->m, &l->c, &l->d, &cmd);
        any = true;
      }
    }
    if (!any) {
      break;
    }
  }
}

static void publish_drive_sample(urt_loop_t *l) {
  const urt_data_t *d = &l->d;
  urt_drive_sample_t *s = &l->drive;
  urt_data_update_outputs(l->m, &l->d);
  s->seq = atomic_load_explicit(&l->latest_drive, memory_order_relaxed) + 1;
  s->time = d->t;
  for (int j = 0; j < URT_NJ; j++) {
    s->q[j] = d->x[j][URT_X_Q];
    s->qd[j] = d->x[j][URT_X_QD];
    s->motor_angle[j] = d->x[j][URT_X_QM];
    s->motor_speed[j] = d->x[j][URT_X_QDM];
    s->i[j] = d->x[j][URT_X_I];
    s->i_ref[j] = d->i_ref[j];
    s->v[j] = d->v_sup[j];
    s->gear_in_torque[j] = d->t_in[j];
    s->gear_out_torque[j] = d->t_cs[j];
    s->friction_torque[j] = d->t_f[j];
    s->flex_x[j] = d->x[j][URT_X_XFS];
    s->flex_y[j] = d->x[j][URT_X_YFS];
    s->bristle_z[j] = d->x[j][URT_X_Z];
    s->i_meas[j] = d->i_fb[j];
    s->temperature[j] = l->c.temperature[j];
  }
  urt_seqlock_write(&l->drive_history[s->seq % DRIVE_HISTORY], s);
  atomic_store_explicit(&l->latest_drive, s->seq, memory_order_release);
}

// One physics step at sub-step k of the current period.
static void physics_step(urt_loop_t *l, int k) {
  urt_command_t cmd;
  urt_ctrl_setpoint(l->m, &l->c, k, &cmd);
  // a refused set-point sets d->pstop; the controller turns it into a protective stop next tick
  urt_command_set(l->m, &l->d, &cmd);
  urt_step(l->m, &l->d);
  l->steps++;
  if (l->drive_every && l->steps % (uint64_t)l->drive_every == 0) {
    publish_drive_sample(l);
  }
}

static void publish_snapshot(urt_loop_t *l, uint64_t tick, int64_t exec_ns) {
  urt_snapshot_t *s = &l->snap;
  urt_snapshot_fill(l->m, &l->c, &l->d, s);
  s->tick = tick;
  s->period = l->cfg.period;
  s->time = (double)tick * l->cfg.period;
  s->exec_time = exec_ns * 1e-9;
  s->overruns = atomic_load_explicit(&l->overruns, memory_order_relaxed);
  s->missed_periods = atomic_load_explicit(&l->missed_periods, memory_order_relaxed);
  uint64_t dropped = 0;
  int n = atomic_load_explicit(&l->n_producers, memory_order_acquire);
  for (int i = 0; i < n; i++) {
    dropped += atomic_load_explicit(&l->ring[i].dropped, memory_order_relaxed);
  }
  s->cmd_dropped = dropped;
  struct timespec wall;
  clock_gettime(CLOCK_REALTIME, &wall);  // vDSO: no system call
  s->published_wall_ns = (int64_t)wall.tv_sec * 1000000000 + wall.tv_nsec;
  urt_seqlock_write(&l->history[tick % URT_LOOP_HISTORY], s);
  atomic_store_explicit(&l->latest_tick, tick, memory_order_release);
  atomic_store(&l->futex_word, (uint32_t)tick);
  if (atomic_load(&l->waiters) > 0) {
    futex_wake_all(&l->futex_word);
  }
  atomic_store(&l->notify_busy, true);
  int fd = atomic_load(&l->notify_fd);
  if (fd >= 0) {
    // the I/O thread waits in epoll: one non-blocking eventfd write instead of a relay thread
    uint64_t one = 1;
    ssize_t rc = write(fd, &one, sizeof one);
    (void)rc;  // EAGAIN: the counter is full, the reader is woken anyway
  }
  atomic_store(&l->notify_busy, false);
}

// Lockstep: sleep until a tick is granted (or stop). The only wait the physics thread does
// besides its pacing sleep, and it is its pacing.
static bool wait_for_grant(urt_loop_t *l, uint64_t done) {
  while (!atomic_load(&l->stop)) {
    uint32_t seen = atomic_load(&l->grant_word);
    if (atomic_load(&l->granted) > done) {
      return true;
    }
    futex_wait(&l->grant_word, seen, 100000000LL);
  }
  return false;
}

static int64_t thread_cpu_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void *physics_main(void *arg) {
  urt_loop_t *l = arg;
  rt_setup(&l->cfg);
  const urt_pacing_t pacing = l->cfg.pacing;
  int64_t anchor = now_ns();  // wall time of tick 0
  int64_t cpu_prev = thread_cpu_ns();
  uint64_t tick = 0;
  while (!atomic_load_explicit(&l->stop, memory_order_relaxed)) {
    if (pacing == URT_PACING_LOCKSTEP && !wait_for_grant(l, tick)) {
      break;
    }
    int64_t start = now_ns();
    // read before the drain: a slice noted as delivered has its commands drained with it
    l->c.program_slice = atomic_load_explicit(&l->program_slice, memory_order_acquire);
    drain_commands(l);
    urt_ctrl_tick(l->m, &l->c, &l->d);
    int64_t busy = 0;
    for (int k = 0; k < l->n_sub; k++) {
      if (pacing == URT_PACING_STEP) {
        busy += now_ns() - start;
        sleep_until(anchor + (int64_t)tick * l->period_ns + (int64_t)k * l->dt_ns);
        start = now_ns();
      }
      physics_step(l, k);
    }
    tick++;
    int64_t end = now_ns();
    int64_t exec = busy + (end - start);
    publish_snapshot(l, tick, exec);
    atomic_store_explicit(&l->exec_last_ns, (uint64_t)exec, memory_order_relaxed);
    // wall time counts what preempted the thread too; its CPU time (this period's work and the
    // previous period's pacing, which costs next to nothing) is the work alone
    urt_exec_hist_add(&l->exec_hist, (uint64_t)exec);
    int64_t cpu = thread_cpu_ns();
    urt_exec_hist_add(&l->cpu_hist, (uint64_t)(cpu - cpu_prev));
    cpu_prev = cpu;
    atomic_store_explicit(&l->refined_steps, l->d.refined_count, memory_order_relaxed);
    if (pacing == URT_PACING_TICK || pacing == URT_PACING_STEP) {
      // tick k's work belongs to wall interval [anchor + (k-1)·P, anchor + k·P)
      int64_t deadline = anchor + (int64_t)tick * l->period_ns;
      end = now_ns();
      if (end > deadline) {
        atomic_fetch_add_explicit(&l->overruns, 1, memory_order_relaxed);
        int64_t behind = (end - deadline) / l->period_ns;
        if (behind > URT_LOOP_CATCH_UP_LIMIT) {
          // too far behind to catch up: count the periods as missed and re-anchor
          atomic_fetch_add_explicit(&l->missed_periods, (uint64_t)behind, memory_order_relaxed);
          anchor += behind * l->period_ns;
        }
      }
      if (pacing == URT_PACING_TICK) {
        sleep_until(anchor + (int64_t)tick * l->period_ns);
      }
    }
  }
  return NULL;
}

int urt_loop_start(urt_loop_t *l) {
  if (l->started) {
    return URT_OK;
  }
  atomic_store(&l->stop, 0);
  int rc = urt_thread_start(&l->thread, physics_main, l, PHYSICS_STACK);
  if (rc != 0) {
    fprintf(stderr, "urtwin: cannot start the physics thread: %s\n", strerror(rc));
    return URT_EIO;
  }
  l->started = 1;
  return URT_OK;
}

void urt_loop_stop(urt_loop_t *l) {
  if (!l->started) {
    return;
  }
  atomic_store(&l->stop, 1);
  atomic_fetch_add(&l->grant_word, 1);
  futex_wake_all(&l->grant_word);
  pthread_join(l->thread, NULL);
  l->started = 0;
}
