/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_sched.c — the URScript VM's threads and their controller-clocked
 * scheduler: the program body and every `run` thread is a coroutine (its own preallocated
 * stack, ucontext swapcontext) running the tree-walker of script_interp.c, and the scheduler
 * resumes them in a fixed order once per controller tick.
 *
 * UR's rule (script manual, "Thread scheduling"): each 2 ms frame, every runnable thread runs
 * until it executes something that consumes time (a motion, sync, sleep, a blocking read, join)
 * or ends. Here every such wait goes through urt__us_wait_tick → urt__us_yield, which parks the
 * thread until the next tick. "If a thread uses up its entire time slice … by computational
 * heavy instructions (such as an infinite loop that do not control the robot) it is placed in a
 * non-runnable state, and is not allowed to run until the next frame starts": a thread that ran
 * the step budget since it was resumed is preempted (urt__us_preempt) at its next statement or
 * loop turn, and the others run in this frame. One that goes on computing without ever waiting
 * or reading a socket, TOO_MUCH_BEHIND_SLICES slices in a row, is "Runtime is too much behind"
 * (script_interp.c) and stops the program.
 *
 * Time is counted, not measured: the scheduler processes ticks one after the other (tick+1
 * after tick, never skipping when the host is ahead because the runner woke late), so the same
 * program with the same inputs gives the same per-tick commands whatever the OS does, and a
 * `servoj(…, t=0.002)` loop takes exactly one tick per iteration. Only one coroutine runs at a
 * time, on the runner thread: no locks between URScript threads are needed.
 *
 * `make test` runs this under clang ASan: every switch is annotated with
 * __sanitizer_start_switch_fiber / __sanitizer_finish_switch_fiber.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <ucontext.h>

#include "script_vm.h"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define US_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(US_ASAN)
#define US_ASAN 1
#endif
#ifdef US_ASAN
#include <sanitizer/common_interface_defs.h>
#define START_SWITCH(save, bottom, size) __sanitizer_start_switch_fiber(save, bottom, size)
#define FINISH_SWITCH(save, bottom, size) __sanitizer_finish_switch_fiber(save, bottom, size)
#else
#define START_SWITCH(save, bottom, size) ((void)(save), (void)(bottom), (void)(size))
#define FINISH_SWITCH(save, bottom, size) ((void)(save), (void)(bottom), (void)(size))
#endif

// ThreadSanitizer follows the switches too (each coroutine is a fiber of its own), else it
// would take one coroutine's stack accesses for another's and the runner thread's history
// would be a mix of all of them
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define US_TSAN 1
#endif
#endif
#if defined(__SANITIZE_THREAD__) && !defined(US_TSAN)
#define US_TSAN 1
#endif
#ifdef US_TSAN
#include <sanitizer/tsan_interface.h>
#define TSAN_CURRENT() __tsan_get_current_fiber()
#define TSAN_CREATE() __tsan_create_fiber(0)
#define TSAN_DESTROY(f) __tsan_destroy_fiber(f)
#define TSAN_SWITCH(f) __tsan_switch_to_fiber(f, 0)
#else
#define TSAN_CURRENT() NULL
#define TSAN_CREATE() NULL
#define TSAN_DESTROY(f) ((void)(f))
#define TSAN_SWITCH(f) ((void)(f))
#endif

#define GUARD ((size_t)65536)     /* below each stack: a multiple of any page size */
#define MAX_THREADS 64              /* live threads of one program (the body counts)        */
#define FIBER_STACK (8u << 20)      /* reserved per thread; touched pages only are committed:
                                       the interpreter recurses (URT_SCRIPT_MAX_DEPTH calls,
                                       1024 expression levels), 8 MiB is what the fuzzer ran
                                       millions of inputs in under ASan                       */

typedef struct us_thread {
  int64_t id;               /* the handle `run` returns (1: the program body)               */
  vm *V;
  const us_node *def;
  bool is_main;
  ucontext_t ctx;
  char *map;                /* the mapping: a guard page, then the stack                    */
  size_t map_size;
  void *fake;               /* ASan's fake-stack handle while suspended                     */
  void *tsan;               /* TSan's fiber (NULL without TSan)                              */
  bool started, done, killed;
  bool parked;              /* yielded; runs again once the tick advances past parked_tick  */
  uint64_t parked_tick;
  int rc;                   /* the body's X_OK / X_ERR                                      */
} us_thread;

typedef struct us_sched {
  const us_prog *prog;
  const us_hooks *h;
  us_err *err;
  size_t var_bytes;         /* every thread's variables count against one budget            */
  uint64_t tick;            /* the controller tick being processed                          */
  uint64_t frozen;          /* ticks the program was paused, its threads not run             */
  bool stop_paused;         /* the current pause came with a protective stop: not frozen     */
  us_thread *th[MAX_THREADS];
  int n;
  us_thread *main;
  int64_t next_id;
  int64_t critical;         /* handle of the thread between enter_ and exit_critical, 0 none */
  us_force_state force;
  us_service service;
  bool stopping;            /* the program ends: every thread unwinds without recording      */
  bool halted;
  ucontext_t ctx;           /* the scheduler (the runner thread's own stack)                 */
  void *fake;
  void *tsan;               /* the runner thread's TSan fiber, set by each resume            */
  const void *stack_bottom;
  size_t stack_size;
} us_sched;

//---- coroutines ----

static void fiber_entry(unsigned hi, unsigned lo) {
  us_thread *t = (us_thread *)(((uintptr_t)hi << 32) | (uintptr_t)lo);
  us_sched *S = t->V->S;
  FINISH_SWITCH(NULL, &S->stack_bottom, &S->stack_size);
  t->rc = urt__us_vm_body(t->V, t->def, t->is_main);
  if (t->V->halted && !t->killed && !S->stopping) {
    S->halted = true;
  }
  t->done = true;
  // the last switch: NULL drops this coroutine's fake stack
  START_SWITCH(NULL, S->stack_bottom, S->stack_size);
  TSAN_SWITCH(S->tsan);
  swapcontext(&t->ctx, &S->ctx);
  abort();  // a finished coroutine is never resumed
}

static void resume(us_sched *S, us_thread *t) {
  if (!t->started) {
    t->started = true;
    getcontext(&t->ctx);
    t->ctx.uc_stack.ss_sp = t->map + GUARD;
    t->ctx.uc_stack.ss_size = t->map_size - GUARD;
    t->ctx.uc_link = NULL;
    uintptr_t p = (uintptr_t)t;
    makecontext(&t->ctx, (void (*)(void))fiber_entry, 2, (unsigned)(p >> 32),
                (unsigned)(p & 0xffffffffu));
    t->tsan = TSAN_CREATE();
  }
  t->parked = false;
  S->tsan = TSAN_CURRENT();
  START_SWITCH(&S->fake, t->map + GUARD, t->map_size - GUARD);
  TSAN_SWITCH(t->tsan);
  swapcontext(&S->ctx, &t->ctx);
  FINISH_SWITCH(S->fake, NULL, NULL);
  if (t->done && S->critical == t->id) {
    S->critical = 0;  // a thread that ends inside a critical section leaves it
  }
}

us_force_state *urt__us_force_state(vm *V) { return &V->S->force; }
us_service *urt__us_service(vm *V) { return &V->S->service; }

bool urt__us_unwinding(const vm *V) {
  return V->S && (V->S->stopping || (V->T && V->T->killed));
}

int urt__us_yield(vm *V) {
  us_sched *S = V->S;
  us_thread *t = V->T;
  if (urt__us_unwinding(V)) {
    return X_ERR;
  }
  t->parked = true;
  t->parked_tick = S->tick;
  START_SWITCH(&t->fake, S->stack_bottom, S->stack_size);
  TSAN_SWITCH(S->tsan);
  swapcontext(&t->ctx, &S->ctx);
  FINISH_SWITCH(t->fake, &S->stack_bottom, &S->stack_size);
  if (urt__us_unwinding(V)) {
    return X_ERR;
  }
  V->tick = S->tick;
  V->frozen = S->frozen;
  V->steps = 0;
  V->slice = 0;
  return X_OK;
}

int urt__us_preempt(vm *V) {
  if (V->prog->secondary) {
    // it runs within one cycle, unpreempted, until step() stops it at the whole budget
    V->slice = 0;
    return X_OK;
  }
  if (V->h->preempted) {
    __atomic_store_n(V->h->preempted, *V->h->preempted + 1, __ATOMIC_RELAXED);
  }
  int64_t steps = V->steps;
  if (urt__us_yield(V) != X_OK) {
    return X_ERR;
  }
  V->steps = steps;
  return X_OK;
}

//---- threads ----

static void thread_free(us_thread *t) {
  if (!t) {
    return;
  }
  if (t->map) {
    munmap(t->map, t->map_size);
  }
  if (t->tsan) {
    TSAN_DESTROY(t->tsan);
  }
  urt__us_vm_free(t->V);
  free(t);
}

static us_thread *thread_new(us_sched *S, const us_node *def, bool is_main, frame *globals) {
  if (S->n == MAX_THREADS) {
    return NULL;
  }
  us_thread *t = calloc(1, sizeof *t);
  if (!t) {
    return NULL;
  }
  t->map_size = FIBER_STACK + GUARD;
  t->map = mmap(NULL, t->map_size, PROT_READ | PROT_WRITE,
                MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE | MAP_STACK, -1, 0);
  if (t->map == MAP_FAILED) {
    t->map = NULL;
    free(t);
    return NULL;
  }
  mprotect(t->map, GUARD, PROT_NONE);  // overflow faults, never corrupts
  t->V = urt__us_vm_new(S->prog, S->h, S->err, globals, &S->var_bytes);
  if (!t->V) {
    thread_free(t);
    return NULL;
  }
  t->V->S = S;
  t->V->T = t;
  t->V->tick = S->tick;
  t->V->frozen = S->frozen;
  t->id = ++S->next_id;
  t->def = def;
  t->is_main = is_main;
  S->th[S->n++] = t;
  return t;
}

static us_thread *thread_find(us_sched *S, int64_t id) {
  for (int k = 0; k < S->n; k++) {
    if (S->th[k]->id == id) {
      return S->th[k];
    }
  }
  return NULL;
}

int urt__us_thread_run(vm *V, const us_node *at, const us_node *def, int64_t *handle) {
  us_sched *S = V->S;
  if (V->prog->secondary) {
    return urt__us_fail(V, at, "Threads are not allowed in a secondary program");
  }
  us_thread *t = thread_new(S, def, false, V->globals);
  if (!t) {
    return urt__us_fail(V, at, "Too many threads: at most %d run at once", MAX_THREADS);
  }
  // the new thread is runnable at once: it runs later in this same tick, after its elders
  *handle = t->id;
  return X_OK;
}

int urt__us_thread_join(vm *V, const us_node *at, int64_t handle) {
  if (handle == V->T->id) {
    return urt__us_fail(V, at, "join: a thread cannot join itself");
  }
  for (;;) {
    us_thread *t = thread_find(V->S, handle);
    if (!t || t->done) {
      return X_OK;  // ended (or never was): join returns at once, as on a controller
    }
    if (urt__us_wait_tick(V, at) != X_OK) {
      return X_ERR;
    }
  }
}

int urt__us_thread_kill(vm *V, const us_node *at, int64_t handle) {
  us_sched *S = V->S;
  us_thread *t = thread_find(S, handle);
  if (!t || t->done) {
    return X_OK;  // killing a thread that ended is no error on a controller
  }
  if (t->is_main) {
    return urt__us_fail(V, at, "kill: the program's own body is not a thread");
  }
  t->killed = true;
  if (S->critical == t->id) {
    S->critical = 0;
  }
  // killing itself unwinds now; another thread is unwound by the scheduler before it runs
  return t == V->T ? X_ERR : X_OK;
}

int urt__us_critical(vm *V, const us_node *at, bool enter) {
  us_sched *S = V->S;
  if (enter) {
    S->critical = V->T->id;  // only the holder runs, so no other can hold it now
  } else if (S->critical == V->T->id) {
    S->critical = 0;
  }
  (void)at;
  return X_OK;
}

//---- the scheduler ----

/* free every finished thread but the program body (its frame holds the globals) */
static void reap(us_sched *S) {
  int w = 0;
  for (int k = 0; k < S->n; k++) {
    us_thread *t = S->th[k];
    if (t->done && !t->is_main) {
      thread_free(t);
    } else {
      S->th[w++] = t;
    }
  }
  S->n = w;
}

static bool program_over(const us_sched *S) {
  return S->err->kind != US_ERR_NONE || S->halted || S->main->done;
}

/* A critical section is not interrupted between waits: once its holder can run in this tick,
 * no other thread runs before it has run (its next wait or its exit_critical). While the holder
 * waits (it has had its turn in this tick), the others run: URCL's external-control script
 * waits in socket_read_binary_integer inside its main loop's critical section and its
 * servoThread holds one across servoj, each re-entering at once after exit_critical; if a
 * waiting holder kept the others out, one of the two would starve, which on a controller it
 * does not (the robot follows URCL's servo stream). */
static bool holder_runs_first(us_sched *S) {
  us_thread *h = thread_find(S, S->critical);
  if (!h || h->done) {
    return false;
  }
  return h->killed || !(h->parked && h->parked_tick >= S->tick);
}

/* one controller tick: passes over the threads in creation order until none is runnable */
static void run_tick(us_sched *S) {
  bool ran = true;
  while (ran && !program_over(S)) {
    ran = false;
    for (int k = 0; k < S->n && !program_over(S); k++) {
      us_thread *t = S->th[k];
      if (t->done) {
        continue;
      }
      if (t->killed) {
        if (t->started) {
          resume(S, t);  // it wakes in urt__us_yield with X_ERR and unwinds
        }
        t->done = true;
        continue;
      }
      if (t->parked && t->parked_tick >= S->tick) {
        continue;  // had its turn this tick
      }
      if (S->critical && S->critical != t->id && holder_runs_first(S)) {
        continue;
      }
      resume(S, t);
      ran = true;
    }
  }
  reap(S);
}

/* A program the user paused is frozen, as on a controller (external_control.md, "Pause"):
 * while the controller says PAUSED at this tick (dashboard `pause`), none of its threads runs,
 * and the timeouts of sleep and socket reads, counted in the program's own ticks
 * (urt__us_run_tick), stand still. The ROS driver stops writing while paused; a reverse-socket
 * read that went on timing out would end URCL's program before `play`.
 * A pause that came with a protective stop is not frozen: only the thread whose motion the
 * stop interrupted waits (script_controller.c). URCL's UrDriverTest.read_error_code stops the
 * arm with a secondary program's protective_stop() under the running external-control program,
 * unlocks it, and the next test's TearDown/SetUp need that program to read its STOP and end,
 * which it does against URSim; a frozen program would hold its sockets open and ignore them.
 * Threads killed or a stop while frozen are handled at the next tick that runs, or by the
 * cancellation (next_tick). A secondary program runs in one cycle and is not paused. */
static bool frozen_at(us_sched *S) {
  if (S->prog->secondary) {
    return false;
  }
  urt_snapshot_t s;
  urt__us_snap_at(S->h->host, S->tick, &s);
  if (s.program_state != URT_PROGRAM_PAUSED) {
    S->stop_paused = false;
    return false;
  }
  if (s.safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP) {
    S->stop_paused = true;  // this pause is the stop's, until the program plays again
  }
  return !S->stop_paused;
}

/* the calling thread's CPU time [ns]: a tick's VM cost without the time the OS ran others */
static uint64_t thread_cpu_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* wait for the controller's next tick and take it (tick + 1, even if the host is further:
 * a late runner catches up tick by tick). Nonzero when the program is cancelled. */
static int next_tick(us_sched *S) {
  const urt_script_host_t *host = S->h->host;
  uint64_t want = S->tick + 1;
  for (;;) {
    uint64_t t = host->wait_tick(host->ctx, S->tick, S->h->wait_timeout_ms);
    if (t >= want) {
      if (t > want && S->h->late_slices) {  // the controller already ran past this slice's tick
        __atomic_store_n(S->h->late_slices, *S->h->late_slices + 1, __ATOMIC_RELAXED);
        if (t - want > *S->h->late_max) {
          __atomic_store_n(S->h->late_max, t - want, __ATOMIC_RELAXED);
        }
      }
      break;
    }
    if (S->h->poll && S->h->poll(S->h->poll_ctx)) {
      return 1;
    }
  }
  if (S->h->poll && S->h->poll(S->h->poll_ctx)) {
    return 1;
  }
  S->tick = want;
  return 0;
}

/* end every thread that still runs: resumed with stopping set, each unwinds silently */
static void stop_all(us_sched *S) {
  S->stopping = true;
  for (int k = 0; k < S->n; k++) {
    us_thread *t = S->th[k];
    if (t->started && !t->done) {
      resume(S, t);
    }
    t->done = true;
  }
}

int urt__us_run(const us_prog *p, const us_hooks *h, us_err *err) {
  memset(err, 0, sizeof *err);
  us_sched *S = calloc(1, sizeof *S);
  if (!S) {
    err->kind = US_ERR_RUNTIME;
    snprintf(err->text, sizeof err->text, "Out of memory");
    return -1;
  }
  S->prog = p;
  S->h = h;
  S->err = err;
  S->force.damping = 0.005;       // UR's defaults
  S->force.gain_scaling = 1.0;
  urt_snapshot_t s;
  h->host->snapshot(h->host->ctx, &s);
  S->tick = s.tick;
  S->main = thread_new(S, p->main, true, NULL);
  if (!S->main) {
    free(S);
    err->kind = US_ERR_RUNTIME;
    snprintf(err->text, sizeof err->text, "Out of memory");
    return -1;
  }
  // each tick's slice is reported (the emulator pairs its register writes with the tick)
  void (*tick_done)(void *, uint64_t, bool) = p->secondary ? NULL : h->host->tick_done;
  if (tick_done) {
    tick_done(h->host->ctx, S->tick > 0 ? S->tick - 1 : 0, true);
  }
  for (;;) {
    const uint64_t cpu0 = h->tick_cpu ? thread_cpu_ns() : 0;
    if (!p->secondary && urt__us_service_tick(&S->service, h, S->tick, err) != X_OK) {
      break;  // the watchdog fired: the program stops with its message
    }
    if (frozen_at(S)) {
      S->frozen++;  // paused: no thread runs, and the program's timeouts stand still
    } else {
      run_tick(S);
    }
    if (tick_done) {
      tick_done(h->host->ctx, S->tick, true);
    }
    if (h->tick_cpu) {
      urt_exec_hist_add(h->tick_cpu, thread_cpu_ns() - cpu0);
    }
    if (program_over(S)) {
      break;
    }
    if (next_tick(S) != 0) {
      if (err->kind == US_ERR_NONE) {
        err->kind = US_ERR_CANCEL;
        snprintf(err->text, sizeof err->text, "stopped");
      }
      break;
    }
  }
  if (tick_done) {
    tick_done(h->host->ctx, 0, false);
  }
  stop_all(S);
  us_thread *main = S->main;
  for (int k = 0; k < S->n; k++) {
    if (S->th[k] != main) {
      thread_free(S->th[k]);
    }
  }
  thread_free(main);  // last: its frame 0 is every thread's globals
  free(S);
  return err->kind != US_ERR_NONE ? -1 : 0;
}
