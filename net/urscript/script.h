/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script.h — private: the URScript arena, tokens, syntax tree, values and the
 * interpreter entry points shared by script_parse.c, script_interp.c and runner.c.
 */
#ifndef URT_NET_URSCRIPT_SCRIPT_H
#define URT_NET_URSCRIPT_SCRIPT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/exec_hist.h"
#include "urt/net/urscript.h"

//---- arena ----

/* A chain of blocks; everything a parsed program owns lives here and goes in one free. */
typedef struct us_arena {
  struct us_block *head;
  size_t used_total, cap_total;  /* bytes handed out; refusal above cap_total */
} us_arena;

void *urt__us_alloc(us_arena *a, size_t n);  /* zeroed, 16-aligned; NULL over the cap */
void urt__us_arena_free(us_arena *a);

//---- errors ----

typedef enum us_err_kind {
  US_ERR_NONE = 0,
  US_ERR_SYNTAX,    /* syntax_error_on_line:<line>:<source line>: */
  US_ERR_COMPILE,   /* compile_error_name_not_found:<name>: and friends */
  US_ERR_RUNTIME,   /* type errors, index errors, protective stops, too much behind */
  US_ERR_CANCEL     /* stopped from outside (new program, dashboard stop): no message */
} us_err_kind;

typedef struct us_err {
  int kind;               /* us_err_kind */
  uint32_t line, column;  /* 1-based */
  char text[1024];
} us_err;

//---- tokens (also the operator of N_UNARY / N_BINARY) ----

enum {
  T_EOF = 0, T_ERR, T_INT, T_FLOAT, T_STR, T_NAME, T_POSE,
  T_LP, T_RP, T_LB, T_RB, T_COMMA, T_COLON, T_ASSIGN,
  T_EQ, T_NE, T_LT, T_LE, T_GT, T_GE, T_PLUS, T_MINUS, T_STAR, T_SLASH, T_PERCENT,
  /* keywords */
  T_DEF, T_SEC, T_THREAD, T_END, T_IF, T_ELIF, T_ELSE, T_THEN, T_WHILE, T_DO, T_RETURN,
  T_GLOBAL, T_LOCAL, T_TRUE, T_FALSE, T_AND, T_OR, T_NOT, T_XOR, T_HALT, T_BREAK, T_CONTINUE,
  T_RUN, T_JOIN, T_KILL, T_FOR
};

//---- syntax tree ----

typedef enum us_kind {
  /* expressions */
  N_INT, N_FLOAT, N_STR, N_BOOL, N_NAME, N_LIST, N_POSE, N_CALL, N_INDEX, N_UNARY, N_BINARY,
  /* statements */
  N_BLOCK, N_ASSIGN, N_GLOBAL, N_LOCAL, N_IF, N_WHILE, N_RETURN, N_HALT, N_BREAK, N_CONTINUE,
  N_EXPR, N_DEF,
  /* threads (appended: the kinds above keep their values) */
  N_RUN,       /* expression `run name()`: def = the thread, value = its handle        */
  N_JOIN,      /* `join h`: a = the handle                                               */
  N_KILL,      /* `kill h`: a = the handle                                               */
  N_CRITICAL   /* `enter_critical` (flag 1) / `exit_critical` (flag 0)                   */
} us_kind;

/* N_DEF flag values */
enum { US_DEF_FUNC = 0, US_DEF_SEC = 1, US_DEF_THREAD = 2 };

/* An interned identifier: equal names are the same pointer. */
typedef struct us_name {
  const char *s;
  int len;
  int id;  /* 0..n_names-1 */
} us_name;

typedef struct us_node us_node;
struct us_node {
  uint8_t kind;       /* us_kind */
  uint8_t op;         /* N_UNARY/N_BINARY: token kind of the operator */
  uint8_t flag;       /* N_IF: has else; N_DEF: US_DEF_*; N_CRITICAL: enter */
  uint32_t line, col;
  int n;              /* number of kids */
  us_node **kids;     /* list elements, call args, block statements, if cond/block pairs… */
  const us_name **argn;  /* N_CALL: name of each argument (NULL: positional); N_DEF: params */
  const us_name *name;   /* N_NAME, N_CALL, N_ASSIGN target, N_GLOBAL/N_LOCAL, N_DEF */
  us_node *a, *b;        /* N_INDEX: base, index; N_BINARY: left, right; N_UNARY: operand;
                            N_ASSIGN: index (NULL for plain) and value; N_WHILE: cond, body;
                            N_RETURN: value; N_DEF: body; N_GLOBAL/N_LOCAL: value */
  double f;              /* N_FLOAT */
  int64_t i;             /* N_INT, N_BOOL */
  const char *s;         /* N_STR (unescaped, NUL-terminated) */
  int slen;
  int builtin;           /* N_CALL: builtin index or -1 */
  us_node *def;          /* N_CALL: user function; N_RUN: the thread */
};

typedef struct us_prog {
  us_arena arena;
  us_node *main;          /* the function to run (N_DEF); a synthetic one for statements */
  bool secondary;         /* a `sec` program */
  char name[64];          /* program name for PROGRAM_XXX_STARTED/STOPPED */
  us_node **defs;         /* every user function (program body first), resolved by name */
  int n_defs;
  int n_names;
} us_prog;

/* Parse and name-check one unit. Returns 0 and *out, or -1 with err filled (nothing
 * allocated). Context: any. */
int urt__us_parse(const char *text, size_t len, us_prog **out, us_err *err);
void urt__us_prog_free(us_prog *p);

/* Builtin index by name, -1 if none. */
int urt__us_builtin_find(const char *name, int len);

/* Whether urtwin runs builtin k (false: a controller function it knows and refuses, which the
 * name check makes a compile error). */
bool urt__us_builtin_supported(int k);

//---- interpreter ----

struct us_sockets;

typedef struct us_hooks {
  const urt_script_host_t *host;
  /* the program's sockets (script_socket.h), owned by the runner, which closes them when the
   * program ends. Nullable: socket builtins are runtime errors (secondary programs). */
  struct us_sockets *sockets;
  uint64_t *motion_id;     /* last motion id used by this runner (incremented per motion) */
  int64_t step_budget;     /* steps between ticks */
  int wait_timeout_ms;
  int version[3];          /* the controller's major, minor, bugfix; all 0: the newest */
  /* called after every wait_tick: nonzero cancels the program (US_ERR_CANCEL). Nullable. */
  int (*poll)(void *ctx);
  void *poll_ctx;
  /* each controller tick's VM work [ns of the runner thread's CPU time]: the service thread,
   * every URScript thread's slice and the switches, from the wait's return to the next wait
   * (what `make bench` reports). Single writer: the runner thread. Nullable. */
  urt_exec_hist_t *tick_cpu;
  /* the slices taken after the controller had already passed their tick, and the most ticks
   * it was ahead (a runner descheduled: its commands reach a later tick than they were issued
   * for). Written by the runner thread with relaxed atomic stores. Nullable, both or neither. */
  uint64_t *late_slices, *late_max;
  /* threads preempted for using up their slice computing (script_sched.c). Written by the
   * runner thread with relaxed atomic stores. Nullable. */
  uint64_t *preempted;
} us_hooks;

/* Run a parsed program to its end. Returns 0, or -1 with err filled. Context: the runner
 * thread (calls the host's blocking wait_tick). */
int urt__us_run(const us_prog *p, const us_hooks *h, us_err *err);

/* Pose algebra shared with the native programs: axis-angle → row-major rotation matrix, and
 * pose_trans(p_from, p_from_to) = p_from ∘ p_from_to. */
void urt__us_rotvec_to_mat(const double r[3], double R[9]);
void urt__us_mat_to_rotvec(const double R[9], double r[3]);
void urt__us_mat_mul(const double A[9], const double B[9], double C[9]);  /* C = A B, row-major */
void urt__us_pose_trans(const double p_from[6], const double p_from_to[6], double out[6]);

/* Whether the safety mode lets the arm move (normal or reduced). */
bool urt__us_safety_ok(const urt_snapshot_t *s);

/* Whether the controller would refuse a motion now (not running) or has refused or aborted
 * one (a fault bit, or a safety stop): false if it may go, else true with the message
 * "<what>: motion refused …" in text[n]. unknown names a fault with no known bit. */
bool urt__us_motion_refused(const urt_snapshot_t *s, const char *what, const char *unknown,
                            char *text, size_t n);

/* Format an error as the RUNTIME_EXCEPTION (or KEY for secondary programs) message. */
void urt__us_err_msg(const us_err *e, bool secondary, urt_script_msg_t *msg);

#endif
