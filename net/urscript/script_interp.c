/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_interp.c — the URScript tree-walking interpreter: values and variables,
 * expressions, statements, calls (user functions, and builtins bound by their parameter lists)
 * and the entry point. The builtins live in script_builtins*.c; the controller's clock and
 * command queue are reached through script_controller.c.
 *
 * Values: int, float, bool, string, pose (6 doubles inline) and flat lists (numbers, bools,
 * poses; at most URT_SCRIPT_MAX_LIST). Temporaries live in a scratch stack that is reset after
 * every statement; variables own heap copies. Time is controller time: every blocking builtin
 * waits on host->wait_tick and reads host->snapshot, so a lock-stepped (virtual) clock works.
 * A step budget between two ticks turns a loop that never yields into "Runtime is too much
 * behind" instead of a hang.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "script_vm.h"

#define SCRATCH_BYTES (4u << 20)
#define MAX_EVAL_DEPTH 1024
#define MAX_VAR_BYTES (64u << 20)  /* strings and lists held by variables, all frames */

//---- errors and scratch memory ----

int urt__us_fail(vm *V, const us_node *at, const char *fmt, ...) {
  if (V->err->kind != US_ERR_NONE || urt__us_unwinding(V)) {
    return X_ERR;
  }
  V->err->kind = US_ERR_RUNTIME;
  V->err->line = at ? at->line : 0;
  V->err->column = at ? at->col : 0;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(V->err->text, sizeof V->err->text, fmt, ap);
  va_end(ap);
  return X_ERR;
}

void *urt__us_salloc(vm *V, const us_node *at, size_t n) {
  n = (n + 15u) & ~(size_t)15u;
  if (V->used + n > SCRATCH_BYTES) {
    urt__us_fail(V, at, "Out of memory: temporary values exceed %u bytes", SCRATCH_BYTES);
    return NULL;
  }
  void *p = V->scratch + V->used;
  V->used += n;
  return p;
}

int urt__us_list_out(vm *V, const us_node *at, const double *x, int n, sv *out) {
  sv *l = urt__us_salloc(V, at, (size_t)(n ? n : 1) * sizeof *l);
  if (!l) return X_ERR;
  for (int k = 0; k < n; k++) l[k] = mk_float(x[k]);
  out->t = V_LIST;
  out->n = n;
  out->u.l = l;
  return X_OK;
}

int urt__us_str_out(vm *V, const us_node *at, const char *s, size_t n, sv *out) {
  char *d = urt__us_salloc(V, at, n + 1);
  if (!d) return X_ERR;
  memcpy(d, s, n);
  d[n] = 0;
  out->t = V_STR;
  out->n = (int32_t)n;
  out->u.s = d;
  return X_OK;
}

//---- values ----

static void vfree(sv *v) {
  if (v->t == V_STR || is_flat(v)) {
    free((void *)(v->t == V_STR ? (void *)v->u.s : (void *)v->u.l));
  }
  memset(v, 0, sizeof *v);
}

/* heap copy of a value (lists are flat: one block) */
static bool vdup(const sv *src, sv *dst) {
  *dst = *src;
  if (src->t == V_STR) {
    char *s = malloc((size_t)src->n + 1);
    if (!s) return false;
    memcpy(s, src->u.s, (size_t)src->n);
    s[src->n] = 0;
    dst->u.s = s;
  } else if (is_flat(src)) {
    sv *l = malloc((size_t)(src->n ? src->n : 1) * sizeof *l);
    if (!l) return false;
    memcpy(l, src->u.l, (size_t)src->n * sizeof *l);
    dst->u.l = l;
  }
  return true;
}

/* scratch copy of a heap value (so it survives the heap value being replaced) */
static bool vscratch(vm *V, const us_node *at, const sv *src, sv *dst) {
  *dst = *src;
  if (src->t == V_STR) {
    char *s = urt__us_salloc(V, at, (size_t)src->n + 1);
    if (!s) return false;
    memcpy(s, src->u.s, (size_t)src->n);
    s[src->n] = 0;
    dst->u.s = s;
  } else if (is_flat(src)) {
    sv *l = urt__us_salloc(V, at, (size_t)(src->n ? src->n : 1) * sizeof *l);
    if (!l) return false;
    memcpy(l, src->u.l, (size_t)src->n * sizeof *l);
    dst->u.l = l;
  }
  return true;
}

int urt__us_fmt_value(const sv *v, char *buf, size_t cap) {
  switch (v->t) {
    case V_INT: return snprintf(buf, cap, "%lld", (long long)v->u.i);
    case V_FLOAT: return snprintf(buf, cap, "%.6g", v->u.f);
    case V_BOOL: return snprintf(buf, cap, "%s", v->u.i ? "True" : "False");
    case V_STR: return snprintf(buf, cap, "%.*s", v->n, v->u.s);
    case V_POSE:
      return snprintf(buf, cap, "p[%.6g,%.6g,%.6g,%.6g,%.6g,%.6g]", v->u.p[0], v->u.p[1],
                      v->u.p[2], v->u.p[3], v->u.p[4], v->u.p[5]);
    case V_MATRIX: {
      // [[a,b],[c,d]]: the rows as lists
      size_t at = (size_t)snprintf(buf, cap, "[");
      int cols = v->cols ? v->cols : 1;
      for (int r = 0; r * cols < v->n && at < cap; r++) {
        sv row = {.t = V_LIST, .n = cols};
        row.u.l = v->u.l + r * cols;
        if (r) at += (size_t)snprintf(buf + at, cap - at, ",");
        if (at < cap) at += (size_t)urt__us_fmt_value(&row, buf + at, cap - at);
      }
      if (at < cap) at += (size_t)snprintf(buf + at, cap - at, "]");
      return (int)at;
    }
    case V_LIST: {
      size_t at = 0;
      at += (size_t)snprintf(buf, cap, "[");
      for (int k = 0; k < v->n && at < cap; k++) {
        if (k) at += (size_t)snprintf(buf + at, cap - at, ",");
        if (at < cap) at += (size_t)urt__us_fmt_value(&v->u.l[k], buf + at, cap - at);
      }
      if (at < cap) at += (size_t)snprintf(buf + at, cap - at, "]");
      return (int)at;
    }
    default: return snprintf(buf, cap, "None");
  }
}

//---- variables ----

static var *find_in(frame *f, const us_name *name) {
  for (int k = 0; k < f->n; k++) {
    if (f->vars[k].name == name) {
      return &f->vars[k];
    }
  }
  return NULL;
}

static var *add_var(vm *V, const us_node *at, frame *f, const us_name *name) {
  if (f->n == f->cap) {
    int cap = f->cap ? f->cap * 2 : 16;
    if (cap > 65536) {
      urt__us_fail(V, at, "Out of memory: too many variables");
      return NULL;
    }
    var *v = realloc(f->vars, (size_t)cap * sizeof *v);
    if (!v) {
      urt__us_fail(V, at, "Out of memory");
      return NULL;
    }
    f->vars = v;
    f->cap = cap;
  }
  var *v = &f->vars[f->n++];
  memset(v, 0, sizeof *v);
  v->name = name;
  return v;
}

/* the frame of the running function (depth 0: the globals) */
static frame *cur_frame(vm *V) { return V->depth == 0 ? V->globals : &V->frames[V->depth]; }

/* the variable a read sees: a local, else a program variable */
static var *lookup(vm *V, const us_name *name) {
  var *v = find_in(cur_frame(V), name);
  if (v && v->is_global) {
    v = NULL;
  } else if (v) {
    return v;
  }
  return find_in(V->globals, name);
}

/* the variable an assignment writes (UR's scoping rules): `global` declared → the program
 * frame; a local (parameter, `local`, or assigned before) → it; a free name → the program's
 * variable if there is one, else a new local */
static var *lookup_write(vm *V, const us_node *at, const us_name *name) {
  frame *f = cur_frame(V);
  var *v = find_in(f, name);
  if ((v && v->is_global) || (!v && V->depth > 0 && find_in(V->globals, name))) {
    f = V->globals;
    v = find_in(f, name);
  }
  return v ? v : add_var(V, at, f, name);
}

static size_t vbytes(const sv *v) {
  return v->t == V_STR ? (size_t)v->n + 1 : is_flat(v) ? (size_t)v->n * sizeof(sv) : 0;
}

static int store(vm *V, const us_node *at, var *dst, const sv *val) {
  size_t before = *V->var_bytes - vbytes(&dst->v);
  if (before + vbytes(val) > MAX_VAR_BYTES) {
    return urt__us_fail(V, at, "Out of memory: variables hold more than %u bytes", MAX_VAR_BYTES);
  }
  sv copy;
  if (!vdup(val, &copy)) {
    return urt__us_fail(V, at, "Out of memory");
  }
  vfree(&dst->v);
  dst->v = copy;
  *V->var_bytes = before + vbytes(&copy);
  return X_OK;
}

static void frame_clear(vm *V, frame *f) {
  for (int k = 0; k < f->n; k++) {
    *V->var_bytes -= vbytes(&f->vars[k].v);
    vfree(&f->vars[k].v);
  }
  f->n = 0;
}

//---- evaluation ----

static int step(vm *V, const us_node *at) {
  V->slice++;
  if (++V->steps > V->h->step_budget * TOO_MUCH_BEHIND_SLICES) {
    return urt__us_fail(V, at, "Runtime is too much behind");
  }
  return X_OK;
}

/* A statement's start or a loop's next turn: where a thread that has used up its slice
 * (step_budget steps since it was resumed) gives the frame to the others (script_sched.c). */
static int turn(vm *V) {
  if (V->slice >= V->h->step_budget) {
    return urt__us_preempt(V);
  }
  return X_OK;
}

static int eval(vm *V, const us_node *n, sv *out);
static int exec_block(vm *V, const us_node *b);

static int arith(vm *V, const us_node *n, int op, const sv *a, const sv *b, sv *out);

/* Lists of numbers are vectors (URCL's script: `q + qd * steptime`, `norm(end_q - start_q)`,
 * `(-3 * q0 + q1 * 3 - …) / pow(t, 2)`): list ± list of the same length element by element,
 * list * number, number * list and list / number on each element; each element follows the
 * scalar rules (int op int stays int). Any other combination is a type error. */
static int list_arith(vm *V, const us_node *n, int op, const sv *a, const sv *b, sv *out) {
  bool both = a->t == V_LIST && b->t == V_LIST;
  bool ok = both ? (op == T_PLUS || op == T_MINUS)
                 : a->t == V_LIST ? is_num(b) && (op == T_STAR || op == T_SLASH)
                                  : is_num(a) && op == T_STAR;
  if (!ok) {
    return urt__us_fail(V, n, "Type error: operator not defined for %s and %s", type_name(a->t),
                        type_name(b->t));
  }
  if (both && a->n != b->n) {
    return urt__us_fail(V, n, "Type error: lists of different lengths (%d and %d)", a->n, b->n);
  }
  int len = a->t == V_LIST ? a->n : b->n;
  sv *l = urt__us_salloc(V, n, (size_t)(len ? len : 1) * sizeof *l);
  if (!l) return X_ERR;
  for (int k = 0; k < len; k++) {
    const sv *x = a->t == V_LIST ? &a->u.l[k] : a;
    const sv *y = b->t == V_LIST ? &b->u.l[k] : b;
    if (!is_num(x) || !is_num(y)) {
      return urt__us_fail(V, n, "Type error: list element %d is %s, not a number", k,
                          type_name(is_num(x) ? y->t : x->t));
    }
    if (arith(V, n, op, x, y, &l[k]) != X_OK) return X_ERR;
  }
  out->t = V_LIST;
  out->n = len;
  out->u.l = l;
  return X_OK;
}

static int arith(vm *V, const us_node *n, int op, const sv *a, const sv *b, sv *out) {
  // string concatenation is not URScript (str_cat is): numbers only, plus pose/list element-wise
  if (is_num(a) && is_num(b)) {
    if (a->t == V_INT && b->t == V_INT && op != T_SLASH) {
      int64_t x = a->u.i, y = b->u.i;
      switch (op) {
        case T_PLUS: *out = mk_int((int64_t)((uint64_t)x + (uint64_t)y)); return X_OK;
        case T_MINUS: *out = mk_int((int64_t)((uint64_t)x - (uint64_t)y)); return X_OK;
        case T_STAR: *out = mk_int((int64_t)((uint64_t)x * (uint64_t)y)); return X_OK;
        case T_PERCENT:
          if (y == 0) return urt__us_fail(V, n, "Division by zero");
          if (y == -1) { *out = mk_int(0); return X_OK; }
          *out = mk_int(x % y);
          return X_OK;
      }
    }
    double x = num(a), y = num(b);
    switch (op) {
      case T_PLUS: *out = mk_float(x + y); return X_OK;
      case T_MINUS: *out = mk_float(x - y); return X_OK;
      case T_STAR: *out = mk_float(x * y); return X_OK;
      case T_SLASH:
        if (y == 0) return urt__us_fail(V, n, "Division by zero");
        *out = mk_float(x / y);
        return X_OK;
      case T_PERCENT:
        if (y == 0) return urt__us_fail(V, n, "Division by zero");
        *out = mk_float(fmod(x, y));
        return X_OK;
    }
  }
  if (a->t == V_LIST || b->t == V_LIST) {
    return list_arith(V, n, op, a, b, out);
  }
  if (a->t == V_POSE && b->t == V_POSE && (op == T_PLUS || op == T_MINUS)) {
    double p[6];
    for (int k = 0; k < 6; k++) {
      p[k] = op == T_PLUS ? a->u.p[k] + b->u.p[k] : a->u.p[k] - b->u.p[k];
    }
    *out = mk_pose(p);
    return X_OK;
  }
  return urt__us_fail(V, n, "Type error: operator not defined for %s and %s", type_name(a->t),
                      type_name(b->t));
}

static bool values_equal(const sv *a, const sv *b) {
  if (is_num(a) && is_num(b)) {
    if (a->t == V_INT && b->t == V_INT) return a->u.i == b->u.i;
    return num(a) == num(b);
  }
  if (a->t != b->t) return false;
  switch (a->t) {
    case V_BOOL: return (a->u.i != 0) == (b->u.i != 0);
    case V_STR: return a->n == b->n && memcmp(a->u.s, b->u.s, (size_t)a->n) == 0;
    case V_POSE: return memcmp(a->u.p, b->u.p, sizeof a->u.p) == 0;
    case V_MATRIX:
    case V_LIST:
      if (a->n != b->n || a->cols != b->cols) return false;
      for (int k = 0; k < a->n; k++) {
        if (!values_equal(&a->u.l[k], &b->u.l[k])) return false;
      }
      return true;
    default: return true;
  }
}

static int eval_binary(vm *V, const us_node *n, sv *out) {
  sv a, b;
  // and/or short-circuit
  if (n->op == T_AND || n->op == T_OR) {
    if (eval(V, n->a, &a) != X_OK) return X_ERR;
    bool x = truthy(&a);
    if ((n->op == T_AND && !x) || (n->op == T_OR && x)) {
      *out = mk_bool(x);
      return X_OK;
    }
    if (eval(V, n->b, &b) != X_OK) return X_ERR;
    *out = mk_bool(truthy(&b));
    return X_OK;
  }
  if (eval(V, n->a, &a) != X_OK || eval(V, n->b, &b) != X_OK) return X_ERR;
  switch (n->op) {
    case T_XOR: *out = mk_bool(truthy(&a) != truthy(&b)); return X_OK;
    case T_EQ: *out = mk_bool(values_equal(&a, &b)); return X_OK;
    case T_NE: *out = mk_bool(!values_equal(&a, &b)); return X_OK;
    case T_LT:
    case T_LE:
    case T_GT:
    case T_GE: {
      if (!is_num(&a) || !is_num(&b)) {
        return urt__us_fail(V, n, "Type error: cannot compare %s and %s", type_name(a.t),
                            type_name(b.t));
      }
      double x = num(&a), y = num(&b);
      bool r = n->op == T_LT ? x < y : n->op == T_LE ? x <= y : n->op == T_GT ? x > y : x >= y;
      *out = mk_bool(r);
      return X_OK;
    }
    default: return arith(V, n, n->op, &a, &b, out);
  }
}

static int eval_list(vm *V, const us_node *n, sv *out) {
  if (n->kind == N_POSE) {
    if (n->n != 6) return urt__us_fail(V, n, "Type error: a pose has 6 numbers, got %d", n->n);
    double p[6];
    for (int k = 0; k < 6; k++) {
      sv e;
      if (eval(V, n->kids[k], &e) != X_OK) return X_ERR;
      if (!is_num(&e)) return urt__us_fail(V, n->kids[k], "Type error: pose element is %s",
                                           type_name(e.t));
      p[k] = num(&e);
    }
    *out = mk_pose(p);
    return X_OK;
  }
  sv *l = urt__us_salloc(V, n, (size_t)(n->n ? n->n : 1) * sizeof *l);
  if (!l) return X_ERR;
  for (int k = 0; k < n->n; k++) {
    if (eval(V, n->kids[k], &l[k]) != X_OK) return X_ERR;
    if (is_flat(&l[k]) || l[k].t == V_STR || l[k].t == V_NONE) {
      return urt__us_fail(V, n->kids[k], "Type error: a list cannot hold a %s", type_name(l[k].t));
    }
  }
  out->t = V_LIST;
  out->n = n->n;
  out->u.l = l;
  return X_OK;
}

static int index_of(vm *V, const us_node *at, const sv *ix, int len, int *out) {
  *out = 0;
  if (ix->t != V_INT) return urt__us_fail(V, at, "Type error: index is %s, not int",
                                          type_name(ix->t));
  if (ix->u.i < 0 || ix->u.i >= len) {
    return urt__us_fail(V, at, "Index out of bounds: %lld (length %d)", (long long)ix->u.i, len);
  }
  *out = (int)ix->u.i;
  return X_OK;
}

static int eval_index(vm *V, const us_node *n, sv *out) {
  sv ix;
  // digital_out[n] / digital_in[n]: the CB2 I/O arrays, unless a variable shadows them
  if (n->a->kind == N_NAME && !lookup(V, n->a->name) &&
      (is_name(n->a->name, "digital_out") || is_name(n->a->name, "digital_in"))) {
    if (eval(V, n->b, &ix) != X_OK) return X_ERR;
    int k;
    if (index_of(V, n->b, &ix, 18, &k) != X_OK) return X_ERR;
    uint32_t bits = is_name(n->a->name, "digital_out") ? urt__us_snap(V)->digital_out
                                                        : urt__us_snap(V)->digital_in;
    *out = mk_bool((bits >> k) & 1u);
    return X_OK;
  }
  sv base;
  if (eval(V, n->a, &base) != X_OK || eval(V, n->b, &ix) != X_OK) return X_ERR;
  int k;
  if (base.t == V_MATRIX) {
    // m[i, j]: an element; m[i]: row i as a list
    int cols = base.cols ? base.cols : 1, rows = base.n / cols;
    if (index_of(V, n->b, &ix, rows, &k) != X_OK) return X_ERR;
    if (n->n == 1) {
      sv jx;
      int j;
      if (eval(V, n->kids[0], &jx) != X_OK || index_of(V, n->kids[0], &jx, cols, &j) != X_OK) {
        return X_ERR;
      }
      *out = base.u.l[k * cols + j];
      return X_OK;
    }
    out->t = V_LIST;
    out->n = cols;
    out->u.l = base.u.l + k * cols;  // scratch or the variable's copy: read-only here
    return X_OK;
  }
  if (n->n == 1) {
    return urt__us_fail(V, n, "Type error: %s has no [row, column] elements", type_name(base.t));
  }
  if (base.t == V_POSE) {
    if (index_of(V, n->b, &ix, 6, &k) != X_OK) return X_ERR;
    *out = mk_float(base.u.p[k]);
    return X_OK;
  }
  if (base.t == V_LIST) {
    if (index_of(V, n->b, &ix, base.n, &k) != X_OK) return X_ERR;
    *out = base.u.l[k];
    return X_OK;
  }
  return urt__us_fail(V, n, "Type error: %s cannot be indexed", type_name(base.t));
}

/* bind the arguments to the builtin's parameters (positional, then named) and call it */
static int call_builtin(vm *V, const us_node *n, sv *out) {
  const us_builtin *b = urt__us_builtin_get(n->builtin);
  if (!b) return urt__us_fail(V, n, "internal: unresolved call");
  if (!b->fn) {
    // known URScript that urtwin does not emulate: a runtime error naming it, where it is
    // reached (the name check lets it compile: script_parse.c says why)
    return urt__us_fail(V, n, "%.*s is not supported by urtwin", n->name->len, n->name->s);
  }
  int np = 0;
  while (np < MAX_ARGS && b->params[np]) np++;
  sv a[MAX_ARGS];
  memset(a, 0, sizeof a);
  for (int k = 0; k < n->n; k++) {
    int slot = k;
    if (n->argn && n->argn[k]) {
      slot = -1;
      for (int j = 0; j < np; j++) {
        if (is_name(n->argn[k], b->params[j])) slot = j;
      }
      if (slot < 0) {
        return urt__us_fail(V, n, "Type error: %s has no parameter %.*s", b->name, n->argn[k]->len, n->argn[k]->s);
      }
    }
    if (slot >= np) {
      return urt__us_fail(V, n, "Type error: %s takes at most %d arguments, got %d", b->name, np,
                          n->n);
    }
    if (eval(V, n->kids[k], &a[slot]) != X_OK) return X_ERR;
  }
  for (int j = 0; j < b->nreq; j++) {
    if (a[j].t == V_NONE) return urt__us_fail(V, n, "Type error: %s: missing argument %s", b->name, b->params[j]);
  }
  out->t = V_NONE;
  return b->fn(V, n, a, out);
}

static int call_user(vm *V, const us_node *n, sv *out) {
  const us_node *d = n->def;
  if (V->depth >= MAX_CALL_DEPTH) {
    return urt__us_fail(V, n, "Stack overflow: calls nested deeper than %d", MAX_CALL_DEPTH);
  }
  // bind arguments (positional, then named, then defaults) in the caller's scratch
  sv *args = urt__us_salloc(V, n, (size_t)(d->n ? d->n : 1) * sizeof *args);
  if (!args) return X_ERR;
  for (int k = 0; k < n->n; k++) {
    int slot = k;
    if (n->argn && n->argn[k]) {
      slot = -1;
      for (int j = 0; j < d->n; j++) {
        if (d->argn[j] == n->argn[k]) slot = j;
      }
      if (slot < 0) {
        return urt__us_fail(V, n, "Type error: %.*s has no parameter %.*s", d->name->len,
                            d->name->s,
                            n->argn[k]->len, n->argn[k]->s);
      }
    }
    if (slot >= d->n) {
      return urt__us_fail(V, n, "Type error: %.*s takes %d arguments, got %d", d->name->len,
                          d->name->s,
                          d->n, n->n);
    }
    if (eval(V, n->kids[k], &args[slot]) != X_OK) return X_ERR;
  }
  for (int j = 0; j < d->n; j++) {
    if (args[j].t == V_NONE) {
      if (!d->kids[j]) {
        return urt__us_fail(V, n, "Type error: %.*s: missing argument %.*s", d->name->len,
                            d->name->s,
                            d->argn[j]->len, d->argn[j]->s);
      }
      if (eval(V, d->kids[j], &args[j]) != X_OK) return X_ERR;
    }
  }

  // run the body in a new frame
  frame *f = &V->frames[V->depth + 1];
  frame_clear(V, f);
  for (int j = 0; j < d->n; j++) {
    var *v = add_var(V, n, f, d->argn[j]);
    if (!v || store(V, n, v, &args[j]) != X_OK) {
      frame_clear(V, f);
      return X_ERR;
    }
  }
  V->depth++;
  int rc = exec_block(V, d->a);
  V->depth--;
  frame_clear(V, f);
  if (rc == X_RETURN) {
    rc = X_OK;
    bool ok = vscratch(V, n, &V->retval, out);
    vfree(&V->retval);
    if (!ok) return X_ERR;
  } else if (rc == X_OK) {
    out->t = V_NONE;
  } else if (rc == X_BREAK || rc == X_CONTINUE) {
    return urt__us_fail(V, n, "break or continue outside a loop");
  } else if (rc == X_HALT) {
    // expressions propagate anything but X_OK as X_ERR: remember it was a halt
    V->halted = true;
    return X_ERR;
  }
  return rc;
}

static int eval(vm *V, const us_node *n, sv *out) {
  if (!n) return urt__us_fail(V, NULL, "internal: empty expression");
  if (step(V, n) != X_OK) return X_ERR;
  if (++V->eval_depth > MAX_EVAL_DEPTH) {
    V->eval_depth--;
    return urt__us_fail(V, n, "Stack overflow");
  }
  int rc = X_OK;
  memset(out, 0, sizeof *out);
  switch (n->kind) {
    case N_INT: *out = mk_int(n->i); break;
    case N_FLOAT: *out = mk_float(n->f); break;
    case N_BOOL: *out = mk_bool(n->i != 0); break;
    case N_STR:
      out->t = V_STR;
      out->n = n->slen;
      out->u.s = n->s;
      break;
    case N_NAME: {
      var *v = lookup(V, n->name);
      if (v) {
        // a scratch copy: a call later in the same expression may replace the variable
        if (v->v.t == V_NONE) {
          rc = urt__us_fail(V, n, "Variable %.*s has no value", n->name->len, n->name->s);
        } else if (!vscratch(V, n, &v->v, out)) {
          rc = X_ERR;
        }
      } else if (is_name(n->name, "pi")) {
        *out = mk_float(M_PI);
      } else {
        rc = urt__us_fail(V, n, "Variable %.*s is not initialized", n->name->len, n->name->s);
      }
      break;
    }
    case N_LIST:
    case N_POSE: rc = eval_list(V, n, out); break;
    case N_INDEX: rc = eval_index(V, n, out); break;
    case N_UNARY: {
      sv a;
      rc = eval(V, n->a, &a);
      if (rc != X_OK) break;
      if (n->op == T_NOT) {
        *out = mk_bool(!truthy(&a));
      } else if (a.t == V_INT) {
        *out = mk_int(n->op == T_MINUS ? (int64_t)(0 - (uint64_t)a.u.i) : a.u.i);
      } else if (a.t == V_FLOAT) {
        *out = mk_float(n->op == T_MINUS ? -a.u.f : a.u.f);
      } else if (a.t == V_LIST) {
        sv minus_one = mk_int(-1);  // element-wise: -i stays int, -x flips the sign exactly
        if (n->op == T_MINUS) {
          rc = list_arith(V, n, T_STAR, &a, &minus_one, out);
        } else {
          *out = a;
        }
      } else if (a.t == V_POSE && n->op == T_MINUS) {
        double p[6];
        for (int k = 0; k < 6; k++) p[k] = -a.u.p[k];
        *out = mk_pose(p);
      } else {
        rc = urt__us_fail(V, n, "Type error: unary operator on %s", type_name(a.t));
      }
      break;
    }
    case N_BINARY: rc = eval_binary(V, n, out); break;
    case N_CALL: rc = n->def ? call_user(V, n, out) : call_builtin(V, n, out); break;
    case N_RUN: {
      int64_t handle = 0;
      rc = urt__us_thread_run(V, n, n->def, &handle);
      if (rc == X_OK) *out = mk_int(handle);
      break;
    }
    default: rc = urt__us_fail(V, n, "internal: not an expression"); break;
  }
  V->eval_depth--;
  return rc;
}

//---- statements ----

static int exec_assign(vm *V, const us_node *n) {
  sv val;
  if (eval(V, n->b, &val) != X_OK) return X_ERR;
  if (!n->a) {
    var *v = lookup_write(V, n, n->name);
    return v ? store(V, n, v, &val) : X_ERR;
  }

  // x[i] = value; digital_out[i] = b is python-urx's CB2 spelling of set_digital_out
  sv ix;
  if (eval(V, n->a, &ix) != X_OK) return X_ERR;
  var *v = lookup(V, n->name);
  if (!v && is_name(n->name, "digital_out")) {
    int k;
    if (index_of(V, n->a, &ix, 18, &k) != X_OK) return X_ERR;
    if (val.t != V_BOOL && !is_num(&val)) return urt__us_fail(V, n->b, "Type error: digital output value is %s", type_name(val.t));
    return urt__us_set_io(V, n, k, truthy(&val));
  }
  if (!v) return urt__us_fail(V, n, "Variable %.*s is not initialized", n->name->len, n->name->s);
  int k;
  if (v->v.t == V_POSE) {
    if (index_of(V, n->a, &ix, 6, &k) != X_OK) return X_ERR;
    if (!is_num(&val)) return urt__us_fail(V, n->b, "Type error: pose element is %s",
                                           type_name(val.t));
    v->v.u.p[k] = num(&val);
    return X_OK;
  }
  if (v->v.t == V_LIST) {
    if (index_of(V, n->a, &ix, v->v.n, &k) != X_OK) return X_ERR;
    if (is_flat(&val) || val.t == V_STR || val.t == V_NONE) {
      return urt__us_fail(V, n->b, "Type error: a list cannot hold a %s", type_name(val.t));
    }
    v->v.u.l[k] = val;
    return X_OK;
  }
  return urt__us_fail(V, n, "Type error: %s cannot be indexed", type_name(v->v.t));
}

static int exec_stmt(vm *V, const us_node *n) {
  if (turn(V) != X_OK || step(V, n) != X_OK) return X_ERR;
  size_t mark = V->used;
  int rc = X_OK;
  switch (n->kind) {
    case N_EXPR: {
      sv v;
      rc = eval(V, n->a, &v);
      break;
    }
    case N_ASSIGN: rc = exec_assign(V, n); break;
    case N_GLOBAL:
    case N_LOCAL: {
      frame *f = cur_frame(V);
      var *v = find_in(f, n->name);
      if (n->kind == N_GLOBAL && V->depth > 0) {
        // mark the name as the program's in this frame, then write there
        if (!v && !(v = add_var(V, n, f, n->name))) { rc = X_ERR; break; }
        *V->var_bytes -= vbytes(&v->v);
        vfree(&v->v);
        v->is_global = true;
        f = V->globals;
        v = find_in(f, n->name);
      } else if (v && v->is_global) {
        v->is_global = false;
      }
      if (!v && !(v = add_var(V, n, f, n->name))) { rc = X_ERR; break; }
      if (n->a) {
        sv val;
        rc = eval(V, n->a, &val);
        if (rc == X_OK) rc = store(V, n, v, &val);
      }
      break;
    }
    case N_IF: {
      int pairs = n->n - (n->flag ? 1 : 0);
      bool done = false;
      for (int k = 0; k + 1 < pairs; k += 2) {
        sv c;
        rc = eval(V, n->kids[k], &c);
        if (rc != X_OK) break;
        if (truthy(&c)) {
          V->used = mark;
          rc = exec_block(V, n->kids[k + 1]);
          done = true;
          break;
        }
      }
      if (rc == X_OK && !done && n->flag) {
        V->used = mark;
        rc = exec_block(V, n->kids[n->n - 1]);
      }
      break;
    }
    case N_WHILE:
      for (bool again = false;; again = true) {
        sv c;
        V->used = mark;
        if (again && (rc = turn(V)) != X_OK) break;
        rc = eval(V, n->a, &c);
        if (rc != X_OK || !truthy(&c)) break;
        V->used = mark;
        rc = exec_block(V, n->b);
        if (rc == X_BREAK) { rc = X_OK; break; }
        if (rc == X_CONTINUE) { rc = X_OK; continue; }
        if (rc != X_OK) break;
      }
      break;
    case N_RETURN:
      vfree(&V->retval);
      if (n->a) {
        sv v;
        rc = eval(V, n->a, &v);
        if (rc == X_OK && !vdup(&v, &V->retval)) rc = urt__us_fail(V, n, "Out of memory");
      }
      if (rc == X_OK) rc = X_RETURN;
      break;
    case N_HALT: rc = X_HALT; break;
    case N_JOIN:
    case N_KILL: {
      sv h;
      rc = eval(V, n->a, &h);
      if (rc != X_OK) break;
      if (h.t != V_INT) {
        rc = urt__us_fail(V, n->a, "Type error: %s needs a thread handle, got %s",
                          n->kind == N_JOIN ? "join" : "kill", type_name(h.t));
        break;
      }
      rc = n->kind == N_JOIN ? urt__us_thread_join(V, n, h.u.i) : urt__us_thread_kill(V, n, h.u.i);
      break;
    }
    case N_CRITICAL: rc = urt__us_critical(V, n, n->flag != 0); break;
    case N_BREAK: rc = X_BREAK; break;
    case N_CONTINUE: rc = X_CONTINUE; break;
    case N_DEF: break;  // functions are resolved at compile time
    default: rc = urt__us_fail(V, n, "internal: not a statement"); break;
  }
  V->used = mark;
  return rc;
}

static int exec_block(vm *V, const us_node *b) {
  if (!b) return X_OK;
  for (int k = 0; k < b->n; k++) {
    int rc = exec_stmt(V, b->kids[k]);
    if (rc != X_OK) return rc;
  }
  return X_OK;
}

//---- entry (the scheduler runs each thread's body through these) ----

vm *urt__us_vm_new(const us_prog *p, const us_hooks *h, us_err *err, frame *globals,
                   size_t *var_bytes) {
  vm *V = calloc(1, sizeof *V);
  if (!V) {
    return NULL;
  }
  V->scratch = malloc(SCRATCH_BYTES);
  if (!V->scratch) {
    free(V);
    return NULL;
  }
  V->prog = p;
  V->h = h;
  V->err = err;
  V->globals = globals ? globals : &V->frames[0];
  V->var_bytes = var_bytes;
  return V;
}

frame *urt__us_vm_globals(vm *V) { return V->globals; }

void urt__us_vm_free(vm *V) {
  if (!V) {
    return;
  }
  for (int k = 0; k <= MAX_CALL_DEPTH; k++) {
    frame_clear(V, &V->frames[k]);
    free(V->frames[k].vars);
  }
  vfree(&V->retval);
  free(V->scratch);
  free(V);
}

/* X_OK (ended, returned or halted: V->halted tells a halt) or X_ERR with the error recorded */
int urt__us_vm_body(vm *V, const us_node *d, bool is_main) {
  int rc = X_OK;
  if (is_main) {
    // the program body runs in frame 0; its parameters (if any) take their defaults
    V->depth = 0;
    for (int j = 0; j < d->n && rc == X_OK; j++) {
      sv v;
      var *slot = add_var(V, d, V->globals, d->argn[j]);
      if (!slot) {
        rc = X_ERR;
      } else if (!d->kids[j]) {
        rc = urt__us_fail(V, d, "Type error: %.*s: missing argument %.*s", d->name->len,
                          d->name->s, d->argn[j]->len, d->argn[j]->s);
      } else if ((rc = eval(V, d->kids[j], &v)) == X_OK) {
        rc = store(V, d, slot, &v);
      }
    }
  } else {
    // a thread's body: its own locals in frame 1, the program's variables seen through
    V->depth = 1;
    frame_clear(V, &V->frames[1]);
  }
  if (rc == X_OK) {
    rc = exec_block(V, d->a);
  }
  if (rc == X_BREAK || rc == X_CONTINUE) {
    rc = urt__us_fail(V, d, "break or continue outside a loop");
  }
  if (rc == X_HALT || (rc == X_ERR && V->halted && V->err->kind == US_ERR_NONE &&
                       !urt__us_unwinding(V))) {
    V->halted = true;
    return X_OK;
  }
  return rc == X_ERR ? X_ERR : X_OK;
}
