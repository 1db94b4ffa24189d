/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins.c — the URScript builtin registry: every family's table
 * (script_builtins_robot.c, _io.c, _math.c, _socket.c, _client.c,
 * _pose.c, _text.c) behind one index the parser resolves names to,
 * the names urtwin knows but does not emulate, and the argument readers every builtin uses.
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"

//---- argument readers ----

/* number argument k, or def when absent */
int urt__us_arg_num(vm *V, const us_node *n, const sv *a, int k, double def, double *out) {
  *out = def;
  if (a[k].t == V_NONE) {
    *out = def;
    return X_OK;
  }
  if (!is_num(&a[k]) && a[k].t != V_BOOL) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not a number", k + 1,
                        n->name->len,
                        n->name->s, type_name(a[k].t));
  }
  *out = a[k].t == V_BOOL ? (double)a[k].u.i : num(&a[k]);
  if (!isfinite(*out)) {
    return urt__us_fail(V, n, "Argument %d of %.*s is not finite", k + 1, n->name->len, n->name->s);
  }
  return X_OK;
}

int urt__us_arg_int(vm *V, const us_node *n, const sv *a, int k, int64_t *out) {
  *out = 0;
  if (a[k].t != V_INT) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not int", k + 1, n->name->len,
                        n->name->s, type_name(a[k].t));
  }
  *out = a[k].u.i;
  return X_OK;
}

/* six numbers from a list or a pose; *is_pose tells which */
int urt__us_arg_vec6(vm *V, const us_node *n, const sv *a, int k, double x[6], bool *is_pose) {
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
    return urt__us_fail(V, n,
                        "Type error: argument %d of %.*s must be a list of 6 numbers or a pose",
                        k + 1, n->name->len, n->name->s);
  }
  for (int j = 0; j < 6; j++) {
    if (!isfinite(x[j])) return urt__us_fail(V, n, "Argument %d of %.*s is not finite", k + 1, n->name->len, n->name->s);
  }
  return X_OK;
}

int urt__us_arg_bool(vm *V, const us_node *n, const sv *a, int k, bool *out) {
  *out = false;
  if (a[k].t != V_BOOL && !is_num(&a[k])) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s is %s, not bool", k + 1,
                        n->name->len,
                        n->name->s, type_name(a[k].t));
  }
  *out = truthy(&a[k]);
  return X_OK;
}

//---- the registry ----

/* known URScript, not emulated: a compile error naming it (script_parse.c's name check), so a
 * program that calls one never starts. Each is named in tests/python/test_script_inventory.py's
 * PENDING when a client script calls it. */
#define P(...) {__VA_ARGS__}
static const us_builtin kUnsupported[] = {
    {"servol", NULL, 0, P(NULL)},
    {"rpc_factory", NULL, 0, P(NULL)},
    // no external force/torque sensor input in urtwin
    {"ft_rtde_input_enable", NULL, 0, P(NULL)},
    {"enable_external_ft_sensor", NULL, 0, P(NULL)},
    // no controller state behind them yet
    {"get_target_waypoint", NULL, 0, P(NULL)},
};
#undef P

static const int kNUnsupported = (int)(sizeof kUnsupported / sizeof kUnsupported[0]);

/* the families in index order: a builtin's index is its place in this concatenation */
static const struct {
  const us_builtin *list;
  const int *n;
} kFamilies[] = {
    {urt__us_builtins_robot, &urt__us_n_builtins_robot},
    {urt__us_builtins_io, &urt__us_n_builtins_io},
    {urt__us_builtins_math, &urt__us_n_builtins_math},
    {urt__us_builtins_state, &urt__us_n_builtins_state},
    {urt__us_builtins_modes, &urt__us_n_builtins_modes},
    {urt__us_builtins_service, &urt__us_n_builtins_service},
    {urt__us_builtins_socket, &urt__us_n_builtins_socket},
    {urt__us_builtins_client, &urt__us_n_builtins_client},
    {urt__us_builtins_pose, &urt__us_n_builtins_pose},
    {urt__us_builtins_text, &urt__us_n_builtins_text},
    {kUnsupported, &kNUnsupported},
};

#define N_FAMILIES ((int)(sizeof kFamilies / sizeof kFamilies[0]))

int urt__us_builtin_find(const char *name, int len) {
  int base = 0;
  for (int f = 0; f < N_FAMILIES; f++) {
    const us_builtin *list = kFamilies[f].list;
    for (int k = 0; k < *kFamilies[f].n; k++) {
      if ((int)strlen(list[k].name) == len && memcmp(list[k].name, name, (size_t)len) == 0) {
        return base + k;
      }
    }
    base += *kFamilies[f].n;
  }
  return -1;
}

bool urt__us_builtin_supported(int k) {
  const us_builtin *b = urt__us_builtin_get(k);
  return b && b->fn;
}

const us_builtin *urt__us_builtin_get(int k) {
  for (int f = 0; f < N_FAMILIES && k >= 0; f++) {
    if (k < *kFamilies[f].n) {
      return &kFamilies[f].list[k];
    }
    k -= *kFamilies[f].n;
  }
  return NULL;
}
