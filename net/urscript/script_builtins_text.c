/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_text.c — UR's string and list functions beyond to_str, str_cat,
 * str_len and get_list_length (script_builtins_math.c): length, size, str_at, str_empty,
 * str_find, str_sub, to_num, and the bit lists binary_list_to_integer / integer_to_binary_list.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "script_vm.h"

static int need_str(vm *V, const us_node *n, const sv *a, int k) {
  if (a[k].t != V_STR) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not a string", k + 1,
                        n->name->len, n->name->s, type_name(a[k].t));
  }
  return X_OK;
}

/* length(v) and size(v) of a list or a string (a pose has 6) */
static int b_length(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t == V_LIST || a[0].t == V_STR) *out = mk_int(a[0].n);
  else if (a[0].t == V_POSE) *out = mk_int(6);
  else return urt__us_fail(V, n, "Type error: %.*s of %s", n->name->len, n->name->s, type_name(a[0].t));
  return X_OK;
}

static int b_str_empty(vm *V, const us_node *n, sv *a, sv *out) {
  if (need_str(V, n, a, 0) != X_OK) return X_ERR;
  *out = mk_bool(a[0].n == 0);
  return X_OK;
}

/* str_at(src, index): the one-character string at index */
static int b_str_at(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t k;
  if (need_str(V, n, a, 0) != X_OK || urt__us_arg_int(V, n, a, 1, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= a[0].n) return urt__us_fail(V, n, "str_at: index %lld outside the string (length %d)", (long long)k, a[0].n);
  return urt__us_str_out(V, n, a[0].u.s + k, 1, out);
}

/* str_find(src, target, start_from=0): the first index of target at or after start_from, or -1 */
static int b_str_find(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t from = 0;
  if (need_str(V, n, a, 0) != X_OK || need_str(V, n, a, 1) != X_OK ||
      (a[2].t != V_NONE && urt__us_arg_int(V, n, a, 2, &from) != X_OK)) {
    return X_ERR;
  }
  if (from < 0 || from > a[0].n) return urt__us_fail(V, n, "str_find: start_from %lld outside the string (length %d)", (long long)from, a[0].n);
  *out = mk_int(-1);
  for (int64_t i = from; i + a[1].n <= a[0].n; i++) {
    if (memcmp(a[0].u.s + i, a[1].u.s, (size_t)a[1].n) == 0) {
      *out = mk_int(i);
      break;
    }
  }
  return X_OK;
}

/* str_sub(src, index, len): len characters from index (to the end when len is absent; what
 * runs past the end is cut) */
static int b_str_sub(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t k, len = -1;
  if (need_str(V, n, a, 0) != X_OK || urt__us_arg_int(V, n, a, 1, &k) != X_OK ||
      (a[2].t != V_NONE && urt__us_arg_int(V, n, a, 2, &len) != X_OK)) {
    return X_ERR;
  }
  if (k < 0 || k > a[0].n) return urt__us_fail(V, n, "str_sub: index %lld outside the string (length %d)", (long long)k, a[0].n);
  if (a[2].t != V_NONE && len < 0) return urt__us_fail(V, n, "str_sub: negative length %lld", (long long)len);
  int64_t rest = a[0].n - k;
  if (len < 0 || len > rest) len = rest;
  return urt__us_str_out(V, n, a[0].u.s + k, (size_t)len, out);
}

/* to_num(str): an int when the text is one, else a float; anything else is an error */
static int b_to_num(vm *V, const us_node *n, sv *a, sv *out) {
  if (need_str(V, n, a, 0) != X_OK) return X_ERR;
  const char *s = a[0].u.s;
  char *e;
  errno = 0;
  long long i = strtoll(s, &e, 10);
  while (*e == ' ' || *e == '\t') e++;
  if (e != s && *e == 0 && errno == 0) {
    *out = mk_int(i);
    return X_OK;
  }
  double f = strtod(s, &e);
  while (*e == ' ' || *e == '\t') e++;
  if (e == s || *e != 0 || !isfinite(f)) return urt__us_fail(V, n, "to_num: \"%s\" is not a number", s);
  *out = mk_float(f);
  return X_OK;
}

/* binary_list_to_integer(l): bools, index 0 the least significant bit, the first 32 as a
 * signed int32; [] is 0 */
static int b_binary_list_to_integer(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t != V_LIST) return urt__us_fail(V, n, "Type error: binary_list_to_integer of %s", type_name(a[0].t));
  uint32_t x = 0;
  for (int j = 0; j < a[0].n && j < 32; j++) {
    if (a[0].u.l[j].t != V_BOOL) return urt__us_fail(V, n, "Type error: element %d of binary_list_to_integer's list is %s, not bool", j, type_name(a[0].u.l[j].t));
    if (a[0].u.l[j].u.i) x |= 1u << j;
  }
  *out = mk_int((int32_t)x);
  return X_OK;
}

/* integer_to_binary_list(x): 32 bools of the signed int32 x, least significant first */
static int b_integer_to_binary_list(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t x;
  if (urt__us_arg_int(V, n, a, 0, &x) != X_OK) return X_ERR;
  if (x < INT32_MIN || x > INT32_MAX) return urt__us_fail(V, n, "integer_to_binary_list: %lld does not fit 32 bits", (long long)x);
  sv *l = urt__us_salloc(V, n, 32 * sizeof *l);
  if (!l) return X_ERR;
  uint32_t u = (uint32_t)(int32_t)x;
  for (int j = 0; j < 32; j++) l[j] = mk_bool((u >> j) & 1u);
  out->t = V_LIST;
  out->n = 32;
  out->u.l = l;
  return X_OK;
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_text[] = {
    {"length", b_length, 1, P("v")},
    {"size", b_length, 1, P("v")},
    {"str_empty", b_str_empty, 1, P("str")},
    {"str_at", b_str_at, 2, P("src", "index")},
    {"str_find", b_str_find, 2, P("src", "target", "start_from")},
    {"str_sub", b_str_sub, 2, P("src", "index", "len")},
    {"to_num", b_to_num, 1, P("str")},
    {"binary_list_to_integer", b_binary_list_to_integer, 1, P("l")},
    {"integer_to_binary_list", b_integer_to_binary_list, 1, P("x")},
};
#undef P

const int urt__us_n_builtins_text =
    (int)(sizeof urt__us_builtins_text / sizeof urt__us_builtins_text[0]);
