/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_interp.c — the URScript tree-walking interpreter and its builtins.
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
  if (V->err->kind != US_ERR_NONE) {
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

//---- values ----

static void vfree(sv *v) {
  if (v->t == V_STR || v->t == V_LIST) {
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
  } else if (src->t == V_LIST) {
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
  } else if (src->t == V_LIST) {
    sv *l = urt__us_salloc(V, at, (size_t)(src->n ? src->n : 1) * sizeof *l);
    if (!l) return false;
    memcpy(l, src->u.l, (size_t)src->n * sizeof *l);
    dst->u.l = l;
  }
  return true;
}

static bool mk_list(vm *V, const us_node *at, const double *x, int n, sv *out) {
  sv *l = urt__us_salloc(V, at, (size_t)n * sizeof *l);
  if (!l) return false;
  for (int k = 0; k < n; k++) {
    l[k] = mk_float(x[k]);
  }
  out->t = V_LIST;
  out->n = n;
  out->u.l = l;
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

static bool mk_str(vm *V, const us_node *at, const char *s, size_t n, sv *out) {
  if (n > URT_SCRIPT_MAX_STRING) {
    n = URT_SCRIPT_MAX_STRING;
  }
  char *d = urt__us_salloc(V, at, n + 1);
  if (!d) return false;
  memcpy(d, s, n);
  d[n] = 0;
  out->t = V_STR;
  out->n = (int32_t)n;
  out->u.s = d;
  return true;
}

static bool to_str(vm *V, const us_node *at, const sv *v, sv *out) {
  char buf[URT_SCRIPT_MAX_STRING + 1];
  int n = urt__us_fmt_value(v, buf, sizeof buf);
  if (n < 0) n = 0;
  if (n > URT_SCRIPT_MAX_STRING) n = URT_SCRIPT_MAX_STRING;
  return mk_str(V, at, buf, (size_t)n, out);
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

/* the variable a read sees: a local, else a program variable */
static var *lookup(vm *V, const us_name *name) {
  var *v = find_in(&V->frames[V->depth], name);
  if (v && v->is_global) {
    v = NULL;
  } else if (v) {
    return v;
  }
  return find_in(&V->frames[0], name);
}

/* the variable an assignment writes: `global` declared → program frame; else local */
static var *lookup_write(vm *V, const us_node *at, const us_name *name) {
  frame *f = &V->frames[V->depth];
  var *v = find_in(f, name);
  if (v && v->is_global) {
    f = &V->frames[0];
    v = find_in(f, name);
  }
  return v ? v : add_var(V, at, f, name);
}

static size_t vbytes(const sv *v) {
  return v->t == V_STR ? (size_t)v->n + 1 : v->t == V_LIST ? (size_t)v->n * sizeof(sv) : 0;
}

static int store(vm *V, const us_node *at, var *dst, const sv *val) {
  size_t before = V->var_bytes - vbytes(&dst->v);
  if (before + vbytes(val) > MAX_VAR_BYTES) {
    return urt__us_fail(V, at, "Out of memory: variables hold more than %u bytes", MAX_VAR_BYTES);
  }
  sv copy;
  if (!vdup(val, &copy)) {
    return urt__us_fail(V, at, "Out of memory");
  }
  vfree(&dst->v);
  dst->v = copy;
  V->var_bytes = before + vbytes(&copy);
  return X_OK;
}

static void frame_clear(vm *V, frame *f) {
  for (int k = 0; k < f->n; k++) {
    V->var_bytes -= vbytes(&f->vars[k].v);
    vfree(&f->vars[k].v);
  }
  f->n = 0;
}


//---- evaluation ----

static int step(vm *V, const us_node *at) {
  if (++V->steps > V->h->step_budget) {
    return urt__us_fail(V, at, "Runtime is too much behind");
  }
  return X_OK;
}

static int eval(vm *V, const us_node *n, sv *out);
static int exec_block(vm *V, const us_node *b);

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
    case V_LIST:
      if (a->n != b->n) return false;
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
        return urt__us_fail(V, n, "Type error: cannot compare %s and %s", type_name(a.t), type_name(b.t));
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
      if (!is_num(&e)) return urt__us_fail(V, n->kids[k], "Type error: pose element is %s", type_name(e.t));
      p[k] = num(&e);
    }
    *out = mk_pose(p);
    return X_OK;
  }
  sv *l = urt__us_salloc(V, n, (size_t)(n->n ? n->n : 1) * sizeof *l);
  if (!l) return X_ERR;
  for (int k = 0; k < n->n; k++) {
    if (eval(V, n->kids[k], &l[k]) != X_OK) return X_ERR;
    if (l[k].t == V_LIST || l[k].t == V_STR || l[k].t == V_NONE) {
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
  if (ix->t != V_INT) return urt__us_fail(V, at, "Type error: index is %s, not int", type_name(ix->t));
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
    uint32_t bits = is_name(n->a->name, "digital_out") ? urt__us_snap(V)->digital_out : urt__us_snap(V)->digital_in;
    *out = mk_bool((bits >> k) & 1u);
    return X_OK;
  }
  sv base;
  if (eval(V, n->a, &base) != X_OK || eval(V, n->b, &ix) != X_OK) return X_ERR;
  int k;
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

static int call_builtin(vm *V, const us_node *n, sv *out);

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
        return urt__us_fail(V, n, "Type error: %.*s has no parameter %.*s", d->name->len, d->name->s,
                    n->argn[k]->len, n->argn[k]->s);
      }
    }
    if (slot >= d->n) {
      return urt__us_fail(V, n, "Type error: %.*s takes %d arguments, got %d", d->name->len, d->name->s,
                  d->n, n->n);
    }
    if (eval(V, n->kids[k], &args[slot]) != X_OK) return X_ERR;
  }
  for (int j = 0; j < d->n; j++) {
    if (args[j].t == V_NONE) {
      if (!d->kids[j]) {
        return urt__us_fail(V, n, "Type error: %.*s: missing argument %.*s", d->name->len, d->name->s,
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
    default: rc = urt__us_fail(V, n, "internal: not an expression"); break;
  }
  V->eval_depth--;
  return rc;
}

//---- statements ----

static int set_io(vm *V, const us_node *at, int index, bool value);

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
    return set_io(V, n, k, truthy(&val));
  }
  if (!v) return urt__us_fail(V, n, "Variable %.*s is not initialized", n->name->len, n->name->s);
  int k;
  if (v->v.t == V_POSE) {
    if (index_of(V, n->a, &ix, 6, &k) != X_OK) return X_ERR;
    if (!is_num(&val)) return urt__us_fail(V, n->b, "Type error: pose element is %s", type_name(val.t));
    v->v.u.p[k] = num(&val);
    return X_OK;
  }
  if (v->v.t == V_LIST) {
    if (index_of(V, n->a, &ix, v->v.n, &k) != X_OK) return X_ERR;
    if (val.t == V_LIST || val.t == V_STR || val.t == V_NONE) {
      return urt__us_fail(V, n->b, "Type error: a list cannot hold a %s", type_name(val.t));
    }
    v->v.u.l[k] = val;
    return X_OK;
  }
  return urt__us_fail(V, n, "Type error: %s cannot be indexed", type_name(v->v.t));
}

static int exec_stmt(vm *V, const us_node *n) {
  if (step(V, n) != X_OK) return X_ERR;
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
      frame *f = &V->frames[V->depth];
      var *v = find_in(f, n->name);
      if (n->kind == N_GLOBAL && V->depth > 0) {
        // mark the name as the program's in this frame, then write there
        if (!v && !(v = add_var(V, n, f, n->name))) { rc = X_ERR; break; }
        V->var_bytes -= vbytes(&v->v);
        vfree(&v->v);
        v->is_global = true;
        f = &V->frames[0];
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
      for (;;) {
        sv c;
        V->used = mark;
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

//---- builtins ----

typedef int (*builtin_fn)(vm *V, const us_node *n, sv *a, sv *out);

typedef struct builtin {
  const char *name;
  builtin_fn fn;
  int nreq;                       /* required leading parameters */
  const char *params[MAX_ARGS];   /* parameter names, for named arguments */
} builtin;

/* number argument k, or def when absent */
static int arg_num(vm *V, const us_node *n, const sv *a, int k, double def, double *out) {
  *out = def;
  if (a[k].t == V_NONE) {
    *out = def;
    return X_OK;
  }
  if (!is_num(&a[k]) && a[k].t != V_BOOL) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not a number", k + 1, n->name->len,
                n->name->s, type_name(a[k].t));
  }
  *out = a[k].t == V_BOOL ? (double)a[k].u.i : num(&a[k]);
  if (!isfinite(*out)) {
    return urt__us_fail(V, n, "Argument %d of %.*s is not finite", k + 1, n->name->len, n->name->s);
  }
  return X_OK;
}

static int arg_int(vm *V, const us_node *n, const sv *a, int k, int64_t *out) {
  *out = 0;
  if (a[k].t != V_INT) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not int", k + 1, n->name->len,
                n->name->s, type_name(a[k].t));
  }
  *out = a[k].u.i;
  return X_OK;
}

/* six numbers from a list or a pose; *is_pose tells which */
static int arg_vec6(vm *V, const us_node *n, const sv *a, int k, double x[6], bool *is_pose) {
  if (a[k].t == V_POSE) {
    memcpy(x, a[k].u.p, 6 * sizeof *x);
    if (is_pose) *is_pose = true;
  } else if (a[k].t == V_LIST && a[k].n == 6) {
    for (int j = 0; j < 6; j++) {
      if (!is_num(&a[k].u.l[j])) {
        return urt__us_fail(V, n, "Type error: element %d of argument %d is %s", j, k + 1,
                    type_name(a[k].u.l[j].t));
      }
      x[j] = num(&a[k].u.l[j]);
    }
    if (is_pose) *is_pose = false;
  } else {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s must be a list of 6 numbers or a pose",
                k + 1, n->name->len, n->name->s);
  }
  for (int j = 0; j < 6; j++) {
    if (!isfinite(x[j])) return urt__us_fail(V, n, "Argument %d of %.*s is not finite", k + 1, n->name->len, n->name->s);
  }
  return X_OK;
}

static int arg_bool(vm *V, const us_node *n, const sv *a, int k, bool *out) {
  *out = false;
  if (a[k].t != V_BOOL && !is_num(&a[k])) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not bool", k + 1, n->name->len,
                n->name->s, type_name(a[k].t));
  }
  *out = truthy(&a[k]);
  return X_OK;
}

static int to_joints(vm *V, const us_node *n, const double x[6], bool is_pose, double q[6]) {
  if (!is_pose) {
    memcpy(q, x, 6 * sizeof *q);
    return X_OK;
  }
  const urt_script_host_t *h = V->h->host;
  if (!h->inverse_kinematics) return urt__us_fail(V, n, "Inverse kinematics is not available");
  if (h->inverse_kinematics(h->ctx, x, urt__us_snap(V)->q, q) != 0) {
    return urt__us_fail(V, n, "Inverse kinematics failed: no solution for the pose");
  }
  return X_OK;
}

static int to_pose(vm *V, const us_node *n, const double x[6], bool is_pose, double p[6]) {
  if (is_pose) {
    memcpy(p, x, 6 * sizeof *p);
    return X_OK;
  }
  const urt_script_host_t *h = V->h->host;
  if (!h->forward_kinematics) return urt__us_fail(V, n, "Forward kinematics is not available");
  if (h->forward_kinematics(h->ctx, x, p) != 0) return urt__us_fail(V, n, "Forward kinematics failed");
  return X_OK;
}

static int b_move(vm *V, const us_node *n, sv *a, sv *out, int kind, double da, double dv) {
  urt_ctrl_cmd_t c = {.kind = kind};
  double x[6];
  bool is_pose;
  if (arg_vec6(V, n, a, 0, x, &is_pose) != X_OK || arg_num(V, n, a, 1, da, &c.a) != X_OK ||
      arg_num(V, n, a, 2, dv, &c.v) != X_OK || arg_num(V, n, a, 3, 0, &c.t) != X_OK ||
      arg_num(V, n, a, 4, 0, &c.r) != X_OK) {
    return X_ERR;
  }
  if (kind == URT_CTRL_MOVEJ) {
    if (to_joints(V, n, x, is_pose, c.q) != X_OK) return X_ERR;
    return urt__us_motion(V, n, "movej", &c, true);
  }
  if (to_pose(V, n, x, is_pose, c.pose) != X_OK) return X_ERR;
  return urt__us_motion(V, n, "movel", &c, true);
}

static int b_movej(vm *V, const us_node *n, sv *a, sv *out) {
  return b_move(V, n, a, out, URT_CTRL_MOVEJ, 1.4, 1.05);
}

static int b_movel(vm *V, const us_node *n, sv *a, sv *out) {
  return b_move(V, n, a, out, URT_CTRL_MOVEL, 1.2, 0.25);
}

static int b_servoj(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SERVOJ};
  double x[6], ignored;
  bool is_pose;
  if (arg_vec6(V, n, a, 0, x, &is_pose) != X_OK || arg_num(V, n, a, 1, 0, &ignored) != X_OK ||
      arg_num(V, n, a, 2, 0, &ignored) != X_OK || arg_num(V, n, a, 3, 0.002, &c.t) != X_OK ||
      arg_num(V, n, a, 4, 0.1, &c.lookahead_time) != X_OK ||
      arg_num(V, n, a, 5, 300, &c.gain) != X_OK || to_joints(V, n, x, is_pose, c.q) != X_OK) {
    return X_ERR;
  }
  if (urt__us_motion(V, n, "servoj", &c, false) != X_OK) return X_ERR;
  return urt__us_wait_for(V, n, c.t, true, "servoj");
}

/* speedj/speedl: block t if given, else until the speed is reached (ramp time at a) */
static int speed_wait(vm *V, const us_node *n, const char *what, double t, double ramp) {
  if (t > 0) return urt__us_wait_for(V, n, t, true, what);
  return urt__us_wait_for(V, n, ramp, true, what);
}

static int b_speedj(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SPEEDJ};
  double t_min;
  if (arg_vec6(V, n, a, 0, c.q, NULL) != X_OK || arg_num(V, n, a, 1, 0, &c.a) != X_OK ||
      arg_num(V, n, a, 2, 0, &c.t) != X_OK || arg_num(V, n, a, 3, 0, &t_min) != X_OK) {
    return X_ERR;
  }
  if (c.t <= 0) c.t = t_min;
  double ramp = 0;
  const urt_snapshot_t *s = urt__us_snap(V);
  for (int j = 0; j < 6 && c.a > 0; j++) {
    double dt = fabs(c.q[j] - s->qd[j]) / c.a;
    if (dt > ramp) ramp = dt;
  }
  if (urt__us_motion(V, n, "speedj", &c, false) != X_OK) return X_ERR;
  return speed_wait(V, n, "speedj", c.t, ramp);
}

static int b_speedl(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SPEEDL};
  double t_min;
  if (arg_vec6(V, n, a, 0, c.pose, NULL) != X_OK || arg_num(V, n, a, 1, 0, &c.a) != X_OK ||
      arg_num(V, n, a, 2, 0, &c.t) != X_OK || arg_num(V, n, a, 3, c.a, &c.a_rot) != X_OK ||
      arg_num(V, n, a, 4, 0, &t_min) != X_OK) {
    return X_ERR;
  }
  if (c.t <= 0) c.t = t_min;
  double ramp = 0;
  const urt_snapshot_t *s = urt__us_snap(V);
  for (int j = 0; j < 6; j++) {
    double acc = j < 3 ? c.a : c.a_rot;
    double dt = acc > 0 ? fabs(c.pose[j] - s->tcp_speed[j]) / acc : 0;
    if (dt > ramp) ramp = dt;
  }
  if (urt__us_motion(V, n, "speedl", &c, false) != X_OK) return X_ERR;
  return speed_wait(V, n, "speedl", c.t, ramp);
}

static int b_stopj(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_STOPJ};
  if (arg_num(V, n, a, 0, 0, &c.a) != X_OK) return X_ERR;
  return urt__us_motion(V, n, "stopj", &c, true);
}

static int b_stopl(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_STOPL};
  if (arg_num(V, n, a, 0, 0, &c.a) != X_OK || arg_num(V, n, a, 1, c.a, &c.a_rot) != X_OK) {
    return X_ERR;
  }
  return urt__us_motion(V, n, "stopl", &c, true);
}

static int set_io(vm *V, const us_node *at, int index, bool value) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_DIGITAL_OUT, .index = index, .value = value ? 1 : 0};
  return urt__us_submit(V, at, &c);
}

/* set_*_digital_out(n, b): base is the bit of output 0, count the number of outputs */
static int digital_out(vm *V, const us_node *n, sv *a, int base, int count) {
  int64_t k;
  bool b;
  if (arg_int(V, n, a, 0, &k) != X_OK || arg_bool(V, n, a, 1, &b) != X_OK) return X_ERR;
  if (k < 0 || k >= count) return urt__us_fail(V, n, "Index out of bounds: digital output %lld", (long long)k);
  return set_io(V, n, base + (int)k, b);
}

static int b_set_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 0, 18); }
static int b_set_standard_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 0, 8); }
static int b_set_configurable_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 8, 8); }
static int b_set_tool_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 16, 2); }

static int b_set_analog_out(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t k;
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_ANALOG_OUT};
  if (arg_int(V, n, a, 0, &k) != X_OK || arg_num(V, n, a, 1, 0, &c.value) != X_OK) return X_ERR;
  if (k < 0 || k > 1) return urt__us_fail(V, n, "Index out of bounds: analog output %lld", (long long)k);
  if (c.value < 0 || c.value > 1) return urt__us_fail(V, n, "Analog output value %g outside [0, 1]", c.value);
  c.index = (int32_t)k;
  return urt__us_submit(V, n, &c);
}

static int get_bit(vm *V, const us_node *n, sv *a, sv *out, bool input, int base, int count) {
  int64_t k;
  if (arg_int(V, n, a, 0, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= count) return urt__us_fail(V, n, "Index out of bounds: %lld", (long long)k);
  uint32_t bits = input ? urt__us_snap(V)->digital_in : urt__us_snap(V)->digital_out;
  *out = mk_bool((bits >> (base + k)) & 1u);
  return X_OK;
}

static int b_get_standard_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 0, 8); }
static int b_get_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 0, 18); }
static int b_get_configurable_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 8, 8); }
static int b_get_tool_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 16, 2); }
static int b_get_standard_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 0, 8); }
static int b_get_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 0, 18); }

static int b_textmsg(vm *V, const us_node *n, sv *a, sv *out) {
  urt_script_msg_t m = {.kind = URT_SCRIPT_MSG_TEXT};
  int at = urt__us_fmt_value(&a[0], m.text, sizeof m.text);
  if (at < 0) at = 0;
  if (a[1].t != V_NONE && (size_t)at < sizeof m.text) urt__us_fmt_value(&a[1], m.text + at, sizeof m.text - (size_t)at);
  m.time = urt__us_snap(V)->time;
  V->h->host->message(V->h->host->ctx, &m);
  return X_OK;
}

static int b_sleep(vm *V, const us_node *n, sv *a, sv *out) {
  double t;
  if (arg_num(V, n, a, 0, 0, &t) != X_OK) return X_ERR;
  if (t < 0) return urt__us_fail(V, n, "sleep: negative time %g", t);
  return urt__us_wait_for(V, n, t, false, "sleep");
}

static int b_sync(vm *V, const us_node *n, sv *a, sv *out) {
  uint64_t t0 = V->tick;
  while (V->tick <= t0) {
    if (urt__us_wait_tick(V, n) != X_OK) return X_ERR;
  }
  return X_OK;
}

static int b_set_tcp(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_TCP};
  bool is_pose;
  if (arg_vec6(V, n, a, 0, c.pose, &is_pose) != X_OK) return X_ERR;
  return urt__us_submit(V, n, &c);
}

static int b_set_payload(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_PAYLOAD};
  if (arg_num(V, n, a, 0, 0, &c.value) != X_OK) return X_ERR;
  if (c.value < 0) return urt__us_fail(V, n, "set_payload: negative mass %g", c.value);
  const urt_snapshot_t *s = urt__us_snap(V);
  memcpy(c.pose, s->payload_cog, sizeof s->payload_cog);
  if (a[1].t != V_NONE) {
    // CoG as [x, y, z], (x, y, z) or a pose (position part)
    if (a[1].t == V_POSE) {
      memcpy(c.pose, a[1].u.p, 3 * sizeof *c.pose);
    } else if (a[1].t == V_LIST && a[1].n == 3 && is_num(&a[1].u.l[0]) && is_num(&a[1].u.l[1]) &&
               is_num(&a[1].u.l[2])) {
      for (int j = 0; j < 3; j++) c.pose[j] = num(&a[1].u.l[j]);
    } else {
      return urt__us_fail(V, n, "Type error: set_payload center of gravity must be 3 numbers");
    }
  }
  return urt__us_submit(V, n, &c);
}

static int b_set_payload_mass(vm *V, const us_node *n, sv *a, sv *out) {
  sv args[MAX_ARGS] = {a[0]};
  return b_set_payload(V, n, args, out);
}

static int b_set_payload_cog(vm *V, const us_node *n, sv *a, sv *out) {
  sv args[MAX_ARGS] = {mk_float(urt__us_snap(V)->payload_mass), a[0]};
  return b_set_payload(V, n, args, out);
}

static int vec_out(vm *V, const us_node *n, const double *x, sv *out) { return mk_list(V, n, x, 6, out) ? X_OK : X_ERR; }

static int b_get_actual_joint_positions(vm *V, const us_node *n, sv *a, sv *out) { return vec_out(V, n, urt__us_snap(V)->q, out); }
static int b_get_target_joint_positions(vm *V, const us_node *n, sv *a, sv *out) { return vec_out(V, n, urt__us_snap(V)->q_target, out); }
static int b_get_actual_joint_speeds(vm *V, const us_node *n, sv *a, sv *out) { return vec_out(V, n, urt__us_snap(V)->qd, out); }
static int b_get_target_joint_speeds(vm *V, const us_node *n, sv *a, sv *out) { return vec_out(V, n, urt__us_snap(V)->qd_target, out); }
static int b_get_actual_tcp_pose(vm *V, const us_node *n, sv *a, sv *out) { *out = mk_pose(urt__us_snap(V)->tcp_pose); return X_OK; }
static int b_get_target_tcp_pose(vm *V, const us_node *n, sv *a, sv *out) { *out = mk_pose(urt__us_snap(V)->tcp_pose_target); return X_OK; }
static int b_get_actual_tcp_speed(vm *V, const us_node *n, sv *a, sv *out) { return vec_out(V, n, urt__us_snap(V)->tcp_speed, out); }
static int b_get_tcp_offset(vm *V, const us_node *n, sv *a, sv *out) { *out = mk_pose(urt__us_snap(V)->tcp_offset); return X_OK; }

static int b_is_steady(vm *V, const us_node *n, sv *a, sv *out) {
  const urt_snapshot_t *s = urt__us_snap(V);
  bool steady = true;
  for (int j = 0; j < URT_NJ; j++) {
    if (fabs(s->qd[j]) > 1e-3) steady = false;
  }
  *out = mk_bool(steady && s->motion == URT_MOTION_IDLE);
  return X_OK;
}

static int b_get_inverse_kin(vm *V, const us_node *n, sv *a, sv *out) {
  double x[6], q[6];
  bool is_pose;
  if (arg_vec6(V, n, a, 0, x, &is_pose) != X_OK || to_joints(V, n, x, true, q) != X_OK) return X_ERR;
  return vec_out(V, n, q, out);
}

static int b_get_forward_kin(vm *V, const us_node *n, sv *a, sv *out) {
  double q[6], p[6];
  if (a[0].t == V_NONE) {
    memcpy(q, urt__us_snap(V)->q, sizeof q);
  } else if (arg_vec6(V, n, a, 0, q, NULL) != X_OK) {
    return X_ERR;
  }
  if (to_pose(V, n, q, false, p) != X_OK) return X_ERR;
  *out = mk_pose(p);
  return X_OK;
}

/* math: one double in, one double out */
static int math1(vm *V, const us_node *n, sv *a, sv *out, double (*f)(double), double lo, double hi) {
  double x;
  if (arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  if (x < lo || x > hi) {
    return urt__us_fail(V, n, "%.*s: argument %g outside [%g, %g]", n->name->len, n->name->s, x, lo, hi);
  }
  *out = mk_float(f(x));
  return X_OK;
}

static double d2r(double x) { return x * M_PI / 180.0; }
static double r2d(double x) { return x * 180.0 / M_PI; }

static int b_sin(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, sin, -HUGE_VAL, HUGE_VAL); }
static int b_cos(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, cos, -HUGE_VAL, HUGE_VAL); }
static int b_tan(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, tan, -HUGE_VAL, HUGE_VAL); }
static int b_asin(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, asin, -1, 1); }
static int b_acos(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, acos, -1, 1); }
static int b_atan(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, atan, -HUGE_VAL, HUGE_VAL); }
static int b_sqrt(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, sqrt, 0, HUGE_VAL); }
static int b_log(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, log, 0, HUGE_VAL); }
static int b_d2r(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, d2r, -HUGE_VAL, HUGE_VAL); }
static int b_r2d(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, r2d, -HUGE_VAL, HUGE_VAL); }
static int b_fabs(vm *V, const us_node *n, sv *a, sv *out) { return math1(V, n, a, out, fabs, -HUGE_VAL, HUGE_VAL); }

static int int_of(vm *V, const us_node *n, double x, sv *out) {
  if (!(x >= -9.2e18 && x <= 9.2e18)) return urt__us_fail(V, n, "Integer overflow: %g", x);
  *out = mk_int((int64_t)x);
  return X_OK;
}

static int b_floor(vm *V, const us_node *n, sv *a, sv *out) {
  double x;
  if (arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  return int_of(V, n, floor(x), out);
}

static int b_ceil(vm *V, const us_node *n, sv *a, sv *out) {
  double x;
  if (arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  return int_of(V, n, ceil(x), out);
}

static int b_atan2(vm *V, const us_node *n, sv *a, sv *out) {
  double y, x;
  if (arg_num(V, n, a, 0, 0, &y) != X_OK || arg_num(V, n, a, 1, 0, &x) != X_OK) return X_ERR;
  *out = mk_float(atan2(y, x));
  return X_OK;
}

static int b_pow(vm *V, const us_node *n, sv *a, sv *out) {
  double x, y;
  if (arg_num(V, n, a, 0, 0, &x) != X_OK || arg_num(V, n, a, 1, 0, &y) != X_OK) return X_ERR;
  *out = mk_float(pow(x, y));
  return X_OK;
}

static int b_norm(vm *V, const us_node *n, sv *a, sv *out) {
  if (is_num(&a[0])) {
    *out = mk_float(fabs(num(&a[0])));
    return X_OK;
  }
  double s = 0;
  if (a[0].t == V_POSE) {
    for (int j = 0; j < 3; j++) s += a[0].u.p[j] * a[0].u.p[j];  // position part
  } else if (a[0].t == V_LIST) {
    for (int j = 0; j < a[0].n; j++) {
      if (!is_num(&a[0].u.l[j])) return urt__us_fail(V, n, "Type error: norm of a list of %s", type_name(a[0].u.l[j].t));
      s += num(&a[0].u.l[j]) * num(&a[0].u.l[j]);
    }
  } else {
    return urt__us_fail(V, n, "Type error: norm of %s", type_name(a[0].t));
  }
  *out = mk_float(sqrt(s));
  return X_OK;
}

static int b_to_str(vm *V, const us_node *n, sv *a, sv *out) { return to_str(V, n, &a[0], out) ? X_OK : X_ERR; }

static int b_str_cat(vm *V, const us_node *n, sv *a, sv *out) {
  sv x, y;
  if (!to_str(V, n, &a[0], &x) || !to_str(V, n, &a[1], &y)) return X_ERR;
  size_t len = (size_t)x.n + (size_t)y.n;
  if (len > URT_SCRIPT_MAX_STRING) return urt__us_fail(V, n, "str_cat: string longer than %d", URT_SCRIPT_MAX_STRING);
  char *d = urt__us_salloc(V, n, len + 1);
  if (!d) return X_ERR;
  memcpy(d, x.u.s, (size_t)x.n);
  memcpy(d + x.n, y.u.s, (size_t)y.n);
  d[len] = 0;
  out->t = V_STR;
  out->n = (int32_t)len;
  out->u.s = d;
  return X_OK;
}

static int b_str_len(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t != V_STR) return urt__us_fail(V, n, "Type error: str_len of %s", type_name(a[0].t));
  *out = mk_int(a[0].n);
  return X_OK;
}

static int b_get_list_length(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t == V_LIST) *out = mk_int(a[0].n);
  else if (a[0].t == V_POSE) *out = mk_int(6);
  else return urt__us_fail(V, n, "Type error: length of %s", type_name(a[0].t));
  return X_OK;
}

/* axis-angle ↔ rotation matrix for the pose functions */
void urt__us_rotvec_to_mat(const double r[3], double R[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (th < 1e-12) {
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(R, I, sizeof I);
    return;
  }
  double x = r[0] / th, y = r[1] / th, z = r[2] / th, c = cos(th), s = sin(th), C = 1 - c;
  double M[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s,
                 y * x * C + z * s, c + y * y * C,     y * z * C - x * s,
                 z * x * C - y * s, z * y * C + x * s, c + z * z * C};
  memcpy(R, M, sizeof M);
}

static void mat_to_rotvec(const double R[9], double r[3]) {
  double c = (R[0] + R[4] + R[8] - 1) / 2;
  c = c > 1 ? 1 : c < -1 ? -1 : c;
  double th = acos(c);
  if (th < 1e-12) {
    r[0] = r[1] = r[2] = 0;
    return;
  }
  if (M_PI - th < 1e-6) {
    // near π: the axis from the diagonal
    double x = sqrt(fmax(0, (R[0] + 1) / 2)), y = sqrt(fmax(0, (R[4] + 1) / 2)),
           z = sqrt(fmax(0, (R[8] + 1) / 2));
    if (x >= y && x >= z) { y = copysign(y, R[1]); z = copysign(z, R[2]); }
    else if (y >= z) { x = copysign(x, R[1]); z = copysign(z, R[5]); }
    else { x = copysign(x, R[2]); y = copysign(y, R[5]); }
    r[0] = x * th; r[1] = y * th; r[2] = z * th;
    return;
  }
  double k = th / (2 * sin(th));
  r[0] = (R[7] - R[5]) * k;
  r[1] = (R[2] - R[6]) * k;
  r[2] = (R[3] - R[1]) * k;
}

static void mat_mul(const double A[9], const double B[9], double C[9]) {
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) {
      C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
    }
  }
}

static int pose_args(vm *V, const us_node *n, sv *a, int k) {
  if (a[k].t != V_POSE) return urt__us_fail(V, n, "Type error: argument %d of %.*s must be a pose", k + 1, n->name->len, n->name->s);
  return X_OK;
}

void urt__us_pose_trans(const double p[6], const double q[6], double o[6]) {
  double Rp[9], Rq[9], R[9];
  urt__us_rotvec_to_mat(p + 3, Rp);
  urt__us_rotvec_to_mat(q + 3, Rq);
  mat_mul(Rp, Rq, R);
  for (int i = 0; i < 3; i++) o[i] = p[i] + Rp[3 * i] * q[0] + Rp[3 * i + 1] * q[1] + Rp[3 * i + 2] * q[2];
  mat_to_rotvec(R, o + 3);
}

/* pose_trans(p_from, p_from_to) = p_from ∘ p_from_to */
static int b_pose_trans(vm *V, const us_node *n, sv *a, sv *out) {
  if (pose_args(V, n, a, 0) != X_OK || pose_args(V, n, a, 1) != X_OK) return X_ERR;
  double o[6];
  urt__us_pose_trans(a[0].u.p, a[1].u.p, o);
  *out = mk_pose(o);
  return X_OK;
}

/* pose_add(p1, p2): positions add, rotations compose in the base frame (R2 R1) */
static int b_pose_add(vm *V, const us_node *n, sv *a, sv *out) {
  if (pose_args(V, n, a, 0) != X_OK || pose_args(V, n, a, 1) != X_OK) return X_ERR;
  const double *p = a[0].u.p, *q = a[1].u.p;
  double Rp[9], Rq[9], R[9], o[6];
  urt__us_rotvec_to_mat(p + 3, Rp);
  urt__us_rotvec_to_mat(q + 3, Rq);
  mat_mul(Rq, Rp, R);
  for (int i = 0; i < 3; i++) o[i] = p[i] + q[i];
  mat_to_rotvec(R, o + 3);
  *out = mk_pose(o);
  return X_OK;
}

static int b_pose_inv(vm *V, const us_node *n, sv *a, sv *out) {
  if (pose_args(V, n, a, 0) != X_OK) return X_ERR;
  const double *p = a[0].u.p;
  double R[9], Rt[9], o[6];
  urt__us_rotvec_to_mat(p + 3, R);
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) Rt[3 * i + j] = R[3 * j + i];
  }
  for (int i = 0; i < 3; i++) o[i] = -(Rt[3 * i] * p[0] + Rt[3 * i + 1] * p[1] + Rt[3 * i + 2] * p[2]);
  mat_to_rotvec(Rt, o + 3);
  *out = mk_pose(o);
  return X_OK;
}

//---- RTDE registers (protocols.md §2.5–2.6) ----

/* the register number argument 0, checked against the bank's size */
static int reg_index(vm *V, const us_node *n, sv *a, int count, int *out) {
  int64_t k;
  if (arg_int(V, n, a, 0, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= count) {
    return urt__us_fail(V, n, "%.*s: register %lld out of range 0..%d", n->name->len, n->name->s,
                (long long)k, count - 1);
  }
  *out = (int)k;
  return X_OK;
}

static int reg_write(vm *V, const us_node *n, sv *a, int kind, int count) {
  const urt_script_host_t *h = V->h->host;
  int k = 0;
  double x;
  if (!h->write_output_register) return urt__us_fail(V, n, "RTDE registers are not available");
  if (reg_index(V, n, a, count, &k) != X_OK) return X_ERR;
  if (kind == URT_SCRIPT_REG_INT) {
    int64_t i;
    if (arg_int(V, n, a, 1, &i) != X_OK) return X_ERR;
    if (i < INT32_MIN || i > INT32_MAX) return urt__us_fail(V, n, "%.*s: %lld does not fit 32 bits", n->name->len, n->name->s, (long long)i);
    x = (double)i;
  } else if (kind == URT_SCRIPT_REG_BIT) {
    bool b;
    if (arg_bool(V, n, a, 1, &b) != X_OK) return X_ERR;
    x = b ? 1 : 0;
  } else if (arg_num(V, n, a, 1, 0, &x) != X_OK) {
    return X_ERR;
  }
  h->write_output_register(h->ctx, kind, k, x);
  return X_OK;
}

static int reg_read(vm *V, const us_node *n, sv *a, sv *out, int kind, bool input) {
  const urt_script_host_t *h = V->h->host;
  int k = 0;
  if (!h->read_registers) return urt__us_fail(V, n, "RTDE registers are not available");
  if (reg_index(V, n, a, kind == URT_SCRIPT_REG_BIT ? URT_RTDE_NBITREG : URT_RTDE_NREG, &k) != X_OK) return X_ERR;
  urt_rtde_registers_t r;
  h->read_registers(h->ctx, &r);
  if (kind == URT_SCRIPT_REG_INT) *out = mk_int(input ? r.in_int[k] : r.out_int[k]);
  else if (kind == URT_SCRIPT_REG_DOUBLE) *out = mk_float(input ? r.in_double[k] : r.out_double[k]);
  else *out = mk_bool((input ? r.in_bit[k] : r.out_bit[k]) != 0);
  return X_OK;
}

static int b_write_output_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_INT, URT_RTDE_NREG); }
static int b_write_output_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_DOUBLE, URT_RTDE_NREG); }
static int b_write_output_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_BIT, URT_RTDE_NBITREG); }
static int b_read_input_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_INT, true); }
static int b_read_input_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_DOUBLE, true); }
static int b_read_input_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_BIT, true); }
static int b_read_output_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_INT, false); }
static int b_read_output_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_DOUBLE, false); }
static int b_read_output_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_BIT, false); }

static int b_noop(vm *V, const us_node *n, sv *a, sv *out) { return X_OK; }

static int b_unsupported(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_fail(V, n, "%.*s is not supported by urtwin", n->name->len, n->name->s);
}

#define P(...) {__VA_ARGS__}
static const builtin kBuiltins[] = {
    // motion
    {"movej", b_movej, 1, P("q", "a", "v", "t", "r")},
    {"movel", b_movel, 1, P("pose", "a", "v", "t", "r")},
    {"servoj", b_servoj, 1, P("q", "a", "v", "t", "lookahead_time", "gain")},
    {"speedj", b_speedj, 2, P("qd", "a", "t", "t_min")},
    {"speedl", b_speedl, 2, P("xd", "a", "t", "aRot", "t_min")},
    {"stopj", b_stopj, 1, P("a")},
    {"stopl", b_stopl, 1, P("a", "aRot")},
    // I/O
    {"set_digital_out", b_set_digital_out, 2, P("n", "b")},
    {"set_standard_digital_out", b_set_standard_digital_out, 2, P("n", "b")},
    {"set_configurable_digital_out", b_set_configurable_digital_out, 2, P("n", "b")},
    {"set_tool_digital_out", b_set_tool_digital_out, 2, P("n", "b")},
    {"set_analog_out", b_set_analog_out, 2, P("n", "f")},
    {"set_standard_analog_out", b_set_analog_out, 2, P("n", "f")},
    {"get_standard_digital_out", b_get_standard_digital_out, 1, P("n")},
    {"get_digital_out", b_get_digital_out, 1, P("n")},
    {"get_configurable_digital_out", b_get_configurable_digital_out, 1, P("n")},
    {"get_tool_digital_out", b_get_tool_digital_out, 1, P("n")},
    {"get_standard_digital_in", b_get_standard_digital_in, 1, P("n")},
    {"get_digital_in", b_get_digital_in, 1, P("n")},
    // program
    {"textmsg", b_textmsg, 1, P("s1", "s2")},
    {"sleep", b_sleep, 1, P("t")},
    {"sync", b_sync, 0, P(NULL)},
    // settings
    {"set_tcp", b_set_tcp, 1, P("pose")},
    {"set_payload", b_set_payload, 1, P("m", "cog", "CoG")},
    {"set_payload_mass", b_set_payload_mass, 1, P("m")},
    {"set_payload_cog", b_set_payload_cog, 1, P("CoG")},
    {"zero_ftsensor", b_noop, 0, P(NULL)},
    // state
    {"get_actual_joint_positions", b_get_actual_joint_positions, 0, P(NULL)},
    {"get_target_joint_positions", b_get_target_joint_positions, 0, P(NULL)},
    {"get_actual_joint_speeds", b_get_actual_joint_speeds, 0, P(NULL)},
    {"get_target_joint_speeds", b_get_target_joint_speeds, 0, P(NULL)},
    {"get_actual_tcp_pose", b_get_actual_tcp_pose, 0, P(NULL)},
    {"get_target_tcp_pose", b_get_target_tcp_pose, 0, P(NULL)},
    {"get_actual_tcp_speed", b_get_actual_tcp_speed, 0, P(NULL)},
    {"get_tcp_offset", b_get_tcp_offset, 0, P(NULL)},
    {"is_steady", b_is_steady, 0, P(NULL)},
    {"get_inverse_kin", b_get_inverse_kin, 1, P("x", "qnear", "maxPositionError", "maxOrientationError", "tcp")},
    {"get_forward_kin", b_get_forward_kin, 0, P("q", "tcp")},
    // math and strings
    {"sin", b_sin, 1, P("f")},
    {"cos", b_cos, 1, P("f")},
    {"tan", b_tan, 1, P("f")},
    {"asin", b_asin, 1, P("f")},
    {"acos", b_acos, 1, P("f")},
    {"atan", b_atan, 1, P("f")},
    {"atan2", b_atan2, 2, P("x", "y")},
    {"sqrt", b_sqrt, 1, P("f")},
    {"log", b_log, 1, P("f")},
    {"pow", b_pow, 2, P("base", "exponent")},
    {"d2r", b_d2r, 1, P("d")},
    {"r2d", b_r2d, 1, P("r")},
    {"fabs", b_fabs, 1, P("f")},
    {"floor", b_floor, 1, P("f")},
    {"ceil", b_ceil, 1, P("f")},
    {"norm", b_norm, 1, P("a")},
    {"to_str", b_to_str, 1, P("val")},
    {"str_cat", b_str_cat, 2, P("op1", "op2")},
    {"str_len", b_str_len, 1, P("str")},
    {"get_list_length", b_get_list_length, 1, P("v")},
    {"pose_trans", b_pose_trans, 2, P("p_from", "p_from_to")},
    {"pose_add", b_pose_add, 2, P("p_1", "p_2")},
    {"pose_inv", b_pose_inv, 1, P("p_from")},
    // RTDE registers
    {"write_output_integer_register", b_write_output_integer_register, 2, P("address", "value")},
    {"write_output_float_register", b_write_output_float_register, 2, P("address", "value")},
    {"write_output_boolean_register", b_write_output_boolean_register, 2, P("address", "value")},
    {"read_input_integer_register", b_read_input_integer_register, 1, P("address")},
    {"read_input_float_register", b_read_input_float_register, 1, P("address")},
    {"read_input_boolean_register", b_read_input_boolean_register, 1, P("address")},
    {"read_output_integer_register", b_read_output_integer_register, 1, P("address")},
    {"read_output_float_register", b_read_output_float_register, 1, P("address")},
    {"read_output_boolean_register", b_read_output_boolean_register, 1, P("address")},
    // known URScript, not emulated: a runtime error before anything of the call happens
    {"movep", b_unsupported, 0, P(NULL)},
    {"movec", b_unsupported, 0, P(NULL)},
    {"servol", b_unsupported, 0, P(NULL)},
    {"servoc", b_unsupported, 0, P(NULL)},
    {"force_mode", b_unsupported, 0, P(NULL)},
    {"end_force_mode", b_unsupported, 0, P(NULL)},
    {"freedrive_mode", b_unsupported, 0, P(NULL)},
    {"end_freedrive_mode", b_unsupported, 0, P(NULL)},
    {"teach_mode", b_unsupported, 0, P(NULL)},
    {"end_teach_mode", b_unsupported, 0, P(NULL)},
    {"socket_open", b_unsupported, 0, P(NULL)},
    {"socket_close", b_unsupported, 0, P(NULL)},
    {"socket_send_string", b_unsupported, 0, P(NULL)},
    {"socket_send_line", b_unsupported, 0, P(NULL)},
    {"socket_read_ascii_float", b_unsupported, 0, P(NULL)},
    {"socket_read_binary_integer", b_unsupported, 0, P(NULL)},
    {"popup", b_unsupported, 0, P(NULL)},
    {"set_gravity", b_unsupported, 0, P(NULL)},
    {"set_tool_voltage", b_unsupported, 0, P(NULL)},
    {"set_target_payload", b_unsupported, 0, P(NULL)},
    {"rpc_factory", b_unsupported, 0, P(NULL)},
};
#undef P

#define N_BUILTINS ((int)(sizeof kBuiltins / sizeof kBuiltins[0]))

int urt__us_builtin_find(const char *name, int len) {
  for (int k = 0; k < N_BUILTINS; k++) {
    if ((int)strlen(kBuiltins[k].name) == len && memcmp(kBuiltins[k].name, name, (size_t)len) == 0) {
      return k;
    }
  }
  return -1;
}

static int call_builtin(vm *V, const us_node *n, sv *out) {
  if (n->builtin < 0 || n->builtin >= N_BUILTINS) return urt__us_fail(V, n, "internal: unresolved call");
  const builtin *b = &kBuiltins[n->builtin];
  if (b->fn == b_unsupported) return b_unsupported(V, n, NULL, out);
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
      return urt__us_fail(V, n, "Type error: %s takes at most %d arguments, got %d", b->name, np, n->n);
    }
    if (eval(V, n->kids[k], &a[slot]) != X_OK) return X_ERR;
  }
  for (int j = 0; j < b->nreq; j++) {
    if (a[j].t == V_NONE) return urt__us_fail(V, n, "Type error: %s: missing argument %s", b->name, b->params[j]);
  }
  // set_payload(m, CoG=…) spells the second parameter two ways
  if (b->fn == b_set_payload && a[1].t == V_NONE) a[1] = a[2];
  out->t = V_NONE;
  return b->fn(V, n, a, out);
}

//---- entry ----

int urt__us_run(const us_prog *p, const us_hooks *h, us_err *err) {
  memset(err, 0, sizeof *err);
  vm *V = calloc(1, sizeof *V);
  if (!V) {
    err->kind = US_ERR_RUNTIME;
    snprintf(err->text, sizeof err->text, "Out of memory");
    return -1;
  }
  V->scratch = malloc(SCRATCH_BYTES);
  if (!V->scratch) {
    free(V);
    err->kind = US_ERR_RUNTIME;
    snprintf(err->text, sizeof err->text, "Out of memory");
    return -1;
  }
  V->prog = p;
  V->h = h;
  V->err = err;
  V->tick = urt__us_snap(V)->tick;

  // the program body runs in frame 0; its parameters (if any) take their defaults
  const us_node *d = p->main;
  int rc = X_OK;
  for (int j = 0; j < d->n && rc == X_OK; j++) {
    sv v;
    var *slot = add_var(V, d, &V->frames[0], d->argn[j]);
    if (!slot) {
      rc = X_ERR;
    } else if (!d->kids[j]) {
      rc = urt__us_fail(V, d, "Type error: %.*s: missing argument %.*s", d->name->len, d->name->s,
                d->argn[j]->len, d->argn[j]->s);
    } else if ((rc = eval(V, d->kids[j], &v)) == X_OK) {
      rc = store(V, d, slot, &v);
    }
  }
  if (rc == X_OK) {
    rc = exec_block(V, d->a);
  }
  if (rc == X_BREAK || rc == X_CONTINUE) {
    rc = urt__us_fail(V, d, "break or continue outside a loop");
  }
  if (rc == X_ERR && V->halted && err->kind == US_ERR_NONE) {
    rc = X_HALT;
  }

  for (int k = 0; k <= MAX_CALL_DEPTH; k++) {
    frame_clear(V, &V->frames[k]);
    free(V->frames[k].vars);
  }
  vfree(&V->retval);
  free(V->scratch);
  free(V);
  return rc == X_ERR ? -1 : 0;
}
