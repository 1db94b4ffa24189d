/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_math.c — the URScript builtins that compute from their arguments
 * alone: math on numbers, strings and list lengths, and the pose algebra (pose_trans, pose_add,
 * pose_inv, pose_sub). Nothing here reads the controller or waits.
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"

//---- numbers ----

/* math: one double in, one double out */
static int math1(vm *V, const us_node *n, sv *a, sv *out, double (*f)(double), double lo, double hi) {
  double x;
  if (urt__us_arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  if (x < lo || x > hi) {
    return urt__us_fail(V, n, "%.*s: argument %g outside [%g, %g]", n->name->len, n->name->s, x,
                        lo, hi);
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
/* log(b, f): the logarithm of f to the base b (UR's log takes the base first) */
static int b_log(vm *V, const us_node *n, sv *a, sv *out) {
  double b, f;
  if (urt__us_arg_num(V, n, a, 0, 0, &b) != X_OK || urt__us_arg_num(V, n, a, 1, 0, &f) != X_OK) return X_ERR;
  if (!(b > 0) || b == 1 || !(f > 0)) return urt__us_fail(V, n, "log: base %g or value %g out of range", b, f);
  *out = mk_float(log(f) / log(b));
  return X_OK;
}
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
  if (urt__us_arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  return int_of(V, n, floor(x), out);
}

static int b_ceil(vm *V, const us_node *n, sv *a, sv *out) {
  double x;
  if (urt__us_arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  return int_of(V, n, ceil(x), out);
}

static int b_atan2(vm *V, const us_node *n, sv *a, sv *out) {
  double y, x;
  if (urt__us_arg_num(V, n, a, 0, 0, &y) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                    &x) != X_OK) return X_ERR;
  *out = mk_float(atan2(y, x));
  return X_OK;
}

static int b_pow(vm *V, const us_node *n, sv *a, sv *out) {
  double x, y;
  if (urt__us_arg_num(V, n, a, 0, 0, &x) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                    &y) != X_OK) return X_ERR;
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
    // UR: "the euclidian norm of the pose", all six numbers (norm(p[-.2,.2,-.2,-1.57,0,3.14])
    // is 3.52768 in the script manual)
    for (int j = 0; j < 6; j++) s += a[0].u.p[j] * a[0].u.p[j];
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

//---- strings and lists ----

static bool mk_str(vm *V, const us_node *at, const char *s, size_t n, sv *out) {
  return urt__us_str_out(V, at, s, n > URT_SCRIPT_MAX_STRING ? URT_SCRIPT_MAX_STRING : n, out) ==
         X_OK;
}

static bool to_str(vm *V, const us_node *at, const sv *v, sv *out) {
  char buf[URT_SCRIPT_MAX_STRING + 1];
  int n = urt__us_fmt_value(v, buf, sizeof buf);
  if (n < 0) n = 0;
  if (n > URT_SCRIPT_MAX_STRING) n = URT_SCRIPT_MAX_STRING;
  return mk_str(V, at, buf, (size_t)n, out);
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

//---- poses ----

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

void urt__us_mat_to_rotvec(const double R[9], double r[3]) {
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

void urt__us_mat_mul(const double A[9], const double B[9], double C[9]) {
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
  urt__us_mat_mul(Rp, Rq, R);
  for (int i = 0; i < 3; i++) o[i] = p[i] + Rp[3 * i] * q[0] + Rp[3 * i + 1] * q[1] + Rp[3 * i + 2] * q[2];
  urt__us_mat_to_rotvec(R, o + 3);
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
  urt__us_mat_mul(Rq, Rp, R);
  for (int i = 0; i < 3; i++) o[i] = p[i] + q[i];
  urt__us_mat_to_rotvec(R, o + 3);
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
  urt__us_mat_to_rotvec(Rt, o + 3);
  *out = mk_pose(o);
  return X_OK;
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_math[] = {
    // math and strings
    {"sin", b_sin, 1, P("f")},
    {"cos", b_cos, 1, P("f")},
    {"tan", b_tan, 1, P("f")},
    {"asin", b_asin, 1, P("f")},
    {"acos", b_acos, 1, P("f")},
    {"atan", b_atan, 1, P("f")},
    {"atan2", b_atan2, 2, P("x", "y")},
    {"sqrt", b_sqrt, 1, P("f")},
    {"log", b_log, 2, P("b", "f")},
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
};
#undef P

const int urt__us_n_builtins_math =
    (int)(sizeof urt__us_builtins_math / sizeof urt__us_builtins_math[0]);
