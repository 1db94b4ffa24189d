/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_vm.h — private to the interpreter: the values a running program computes
 * with, the interpreter's state, and the calls that cross between the evaluator
 * (script_interp.c), the controller link (script_controller.c) and the builtins. script.h is
 * the interpreter seen from the parser and the runner; this header is the view from inside.
 */
#ifndef URT_NET_URSCRIPT_SCRIPT_VM_H
#define URT_NET_URSCRIPT_SCRIPT_VM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "script.h"

#define MAX_CALL_DEPTH URT_SCRIPT_MAX_DEPTH
#define MAX_ARGS 8
/* slices in a row that a thread may spend computing, without a wait or a socket read, before
 * the program stops with "Runtime is too much behind" (each slice is step_budget steps;
 * script_sched.c). Ours, not UR's: UR documents only that such a thread is preempted. */
#define TOO_MUCH_BEHIND_SLICES 20

//---- values ----

/* V_MATRIX: n = rows·cols floats in u.l, row-major (get_mass_matrix, get_jacobian: 6×6) */
enum { V_NONE = 0, V_BOOL, V_INT, V_FLOAT, V_STR, V_LIST, V_POSE, V_MATRIX };

typedef struct sv {
  uint8_t t;
  uint16_t cols; /* V_MATRIX: columns */
  int32_t n;  /* V_STR: bytes; V_LIST, V_MATRIX: elements */
  union {
    int64_t i;  /* V_INT, V_BOOL */
    double f;
    const char *s;
    struct sv *l;
    double p[6];
  } u;
} sv;

static inline const char *type_name(int t) {
  static const char *const names[] = {"none",   "bool", "int",  "float",
                                       "string", "list", "pose", "matrix"};
  return t >= 0 && t <= V_MATRIX ? names[t] : "?";
}

static inline bool is_num(const sv *v) { return v->t == V_INT || v->t == V_FLOAT; }
static inline double num(const sv *v) { return v->t == V_INT ? (double)v->u.i : v->u.f; }

static inline sv mk_int(int64_t i) { sv v = {.t = V_INT}; v.u.i = i; return v; }
static inline sv mk_float(double f) { sv v = {.t = V_FLOAT}; v.u.f = f; return v; }
static inline sv mk_bool(bool b) { sv v = {.t = V_BOOL}; v.u.i = b; return v; }

static inline sv mk_pose(const double p[6]) {
  sv v = {.t = V_POSE};
  memcpy(v.u.p, p, sizeof v.u.p);
  return v;
}

/* flat element storage: lists and matrices */
static inline bool is_flat(const sv *v) { return v->t == V_LIST || v->t == V_MATRIX; }

static inline bool truthy(const sv *v) {
  switch (v->t) {
    case V_BOOL:
    case V_INT: return v->u.i != 0;
    case V_FLOAT: return v->u.f != 0;
    default: return true;
  }
}

static inline bool is_name(const us_name *nm, const char *s) {
  return nm && (int)strlen(s) == nm->len && memcmp(s, nm->s, (size_t)nm->len) == 0;
}

/* "%.6g" numbers, True/False, p[…] and […] without spaces (as a controller's log shows);
 * returns what snprintf would. */
int urt__us_fmt_value(const sv *v, char *buf, size_t cap);

//---- interpreter state ----

typedef struct var {
  const us_name *name;
  sv v;              /* heap-owned */
  bool is_global;    /* `global x` inside a function: x lives in the program frame */
} var;

typedef struct frame {
  var *vars;
  int n, cap;
} frame;

struct us_sched;   /* the program's threads and their scheduler (script_sched.c) */
struct us_thread;

/* One URScript thread's view of the running program: builtins get the running thread's vm.
 * The program's threads share prog, hooks, err, the globals frame and the variable budget;
 * each has its own locals, scratch, call depth and step count. */
typedef struct vm {
  const us_prog *prog;
  const us_hooks *h;
  us_err *err;           /* shared: the first error of any thread stops the program */
  struct us_sched *S;
  struct us_thread *T;   /* this thread */
  /* scratch stack for temporaries */
  char *scratch;
  size_t used;
  /* frames: 0 = program body (the globals, *globals: the main thread's frames[0]) */
  frame frames[MAX_CALL_DEPTH + 1];
  frame *globals;
  int depth;        /* current frame index (a thread's body runs at 1) */
  int eval_depth;
  sv retval;        /* heap-owned value of the last `return` */
  bool halted;      /* `halt` inside a function: unwinds as X_ERR with no error */
  size_t *var_bytes; /* shared: heap held by variables (bounded by MAX_VAR_BYTES) */
  /* time: the controller tick the scheduler is running (every thread sees the same), and the
   * ticks the program has spent paused so far, frozen (script_sched.c) */
  uint64_t tick;
  uint64_t frozen;
  /* motion time the last scaled wait ran past its t, and the tick it ended at: a wait that
   * starts in that same tick continues the stream (urt__us_wait_scaled) */
  double motion_carry;
  uint64_t motion_carry_tick;
  int64_t steps;    /* steps since this thread last waited or read a socket */
  int64_t slice;    /* steps since this thread was last resumed (its share of this frame) */
  urt_snapshot_t snap;
} vm;

/* the program's own time in ticks: the controller's less those it spent paused. Timeouts
 * (sleep, socket reads) count these, so a pause freezes them as it freezes the threads. */
static inline uint64_t urt__us_run_tick(const vm *V) {
  return V->tick - V->frozen;
}

enum { X_OK = 0, X_ERR, X_RETURN, X_BREAK, X_CONTINUE, X_HALT };

/* Record a runtime error at `at` (the first one wins) and return X_ERR. Nullable: at. */
int urt__us_fail(vm *V, const us_node *at, const char *fmt, ...);

/* n bytes of scratch, 16-aligned, freed after the statement; NULL (error set) when full. */
void *urt__us_salloc(vm *V, const us_node *at, size_t n);

/* A list of n floats, or a string copy of s[0..n), in scratch: X_OK, or X_ERR when full. */
int urt__us_list_out(vm *V, const us_node *at, const double *x, int n, sv *out);
int urt__us_str_out(vm *V, const us_node *at, const char *s, size_t n, sv *out);

//---- threads (script_sched.c) ----

/* The interpreter's side, called by the scheduler (script_interp.c): a thread's vm, and running
 * the program body (is_main: frame 0, parameters take their defaults) or a thread's body. */
vm *urt__us_vm_new(const us_prog *p, const us_hooks *h, us_err *err, frame *globals,
                   size_t *var_bytes);
void urt__us_vm_free(vm *V);
frame *urt__us_vm_globals(vm *V);
int urt__us_vm_body(vm *V, const us_node *def, bool is_main);

/* Suspend the running thread until the next controller tick (the one primitive every wait goes
 * through). X_ERR when the thread was killed or the program stopped meanwhile (nothing
 * recorded: the unwinding is silent). */
int urt__us_yield(vm *V);

/* The running thread used up its slice computing (step_budget steps since it was resumed): it
 * is not run again before the next frame, but it did not wait, so its steps since its last wait
 * keep counting. X_ERR when killed or stopped meanwhile. A secondary program runs on within
 * its one cycle (step() stops it at TOO_MUCH_BEHIND_SLICES slices, as any thread). */
int urt__us_preempt(vm *V);

/* run name() → *handle; join h; kill h; enter_critical / exit_critical */
int urt__us_thread_run(vm *V, const us_node *at, const us_node *def, int64_t *handle);
int urt__us_thread_join(vm *V, const us_node *at, int64_t handle);
int urt__us_thread_kill(vm *V, const us_node *at, int64_t handle);
int urt__us_critical(vm *V, const us_node *at, bool enter);

/* Force mode as the program set it (shared by its threads): force_mode_set_damping and
 * _gain_scaling apply to the next force_mode and to the active one. */
typedef struct us_force_state {
  bool active;
  double damping, gain_scaling;
  urt_ctrl_cmd_t cmd;   /* the active force_mode command */
} us_force_state;
us_force_state *urt__us_force_state(vm *V);

/* What the controller records and checks every tick for the program (script_service.c). */
#define US_HIST 2048  /* ticks of TCP-force history (4 s at 500 Hz) */
typedef struct us_service {
  uint64_t n;                      /* ticks recorded */
  double f[US_HIST][6];            /* TCP force per tick (tool_contact) */
  bool wd_on, wd_double, wd_pause; /* rtde_set_watchdog (wd_pause: action "pause", not "stop") */
  int wd_reg;
  double wd_period, wd_last;
  uint32_t wd_count;
  char wd_name[64];
} us_service;
us_service *urt__us_service(vm *V);

/* Once per tick before the threads run: record, then the watchdog (X_ERR with err set when it
 * fired). Context: the runner thread. */
int urt__us_service_tick(us_service *sv, const us_hooks *h, uint64_t tick, us_err *err);

/* Whether this thread is being unwound (killed, or the program stops): errors go unrecorded. */
bool urt__us_unwinding(const vm *V);

//---- the controller (script_controller.c) ----

/* Read the host's snapshot into V->snap and return it. */
urt_snapshot_t *urt__us_snap(vm *V);
/* the snapshot of controller tick `tick`, the newest when the host no longer keeps it (or for
 * tick 0); what urt__us_snap and the per-tick service read */
void urt__us_snap_at(const urt_script_host_t *h, uint64_t tick, urt_snapshot_t *out);

/* One wait for a newer tick; cancellation and secondary programs are checked here. */
int urt__us_wait_tick(vm *V, const us_node *at);

/* Queue a command, retrying for SUBMIT_RETRY_TICKS ticks while the queue is full. */
int urt__us_submit(vm *V, const us_node *at, const urt_ctrl_cmd_t *cmd);

/* Whether the emulated controller's software is at least major.minor.bugfix (a version of all
 * zeros is the newest, so it is). */
bool urt__us_version_at_least(const vm *V, int major, int minor, int bugfix);
/* X_OK when it is; otherwise X_ERR with "<what> is not available on software x.y.z (UR added it
 * in <since>)", the runtime error a builtin of a later release gives. */
int urt__us_require_version(vm *V, const us_node *at, const char *what, int major, int minor,
                            int bugfix);

/* Submit a motion and, if wait, block until the controller reports it done. */
int urt__us_motion(vm *V, const us_node *at, const char *what, urt_ctrl_cmd_t *cmd, bool wait);

/* Block for t seconds of controller time (whole ticks, counted by the scheduler, not read from
 * the clock: a late VM catches up and never lags), checking the motion is not refused if asked. */
int urt__us_wait_for(vm *V, const us_node *at, double t, bool check_motion, const char *what);
/* block for t seconds of motion time: each tick adds period × the speed scaling the controller
 * ran that tick with (its snapshot's motion_rate: slider × pause, not speedj's limiter), so at scaling 1 exactly
 * as urt__us_wait_for; a motion the slider scales (speedj) lasts as long as the controller's */
int urt__us_wait_scaled(vm *V, const us_node *at, double t, const char *what);

//---- builtins (script_builtins*.c) ----

/* A builtin gets its arguments in a[0..MAX_ARGS-1] in parameter order (V_NONE where absent)
 * and leaves its result in *out (V_NONE: no value). Returns X_OK, or X_ERR with the error set. */
typedef int (*us_builtin_fn)(vm *V, const us_node *n, sv *a, sv *out);

typedef struct us_builtin {
  const char *name;
  us_builtin_fn fn;               /* NULL: known URScript that urtwin does not emulate */
  int nreq;                       /* required leading parameters */
  const char *params[MAX_ARGS];   /* parameter names, for named arguments */
} us_builtin;

/* Each family's table, defined next to its builtins; script_builtins.c joins them. */
extern const us_builtin urt__us_builtins_robot[], urt__us_builtins_io[], urt__us_builtins_math[],
    urt__us_builtins_state[], urt__us_builtins_modes[], urt__us_builtins_service[],
    urt__us_builtins_socket[], urt__us_builtins_client[], urt__us_builtins_pose[],
    urt__us_builtins_text[];
extern const int urt__us_n_builtins_robot, urt__us_n_builtins_io, urt__us_n_builtins_math,
    urt__us_n_builtins_state, urt__us_n_builtins_modes, urt__us_n_builtins_service,
    urt__us_n_builtins_socket, urt__us_n_builtins_client, urt__us_n_builtins_pose,
    urt__us_n_builtins_text;

/* The builtin urt__us_builtin_find gave index k, NULL for any other k. */
const us_builtin *urt__us_builtin_get(int k);

/* Argument k of the builtin called at n: a number (bool counts; def when absent), an int, six
 * numbers from a list or a pose (*is_pose tells which; nullable), or a bool. Non-finite numbers
 * and wrong types are runtime errors naming the argument. */
int urt__us_arg_num(vm *V, const us_node *n, const sv *a, int k, double def, double *out);
int urt__us_arg_int(vm *V, const us_node *n, const sv *a, int k, int64_t *out);
int urt__us_arg_vec6(vm *V, const us_node *n, const sv *a, int k, double x[6], bool *is_pose);
int urt__us_arg_bool(vm *V, const us_node *n, const sv *a, int k, bool *out);

/* Queue digital output `index` (bit of the 18: standard, configurable, tool) set to value;
 * also what `digital_out[i] = b` does. */
int urt__us_set_io(vm *V, const us_node *at, int index, bool value);

#endif
