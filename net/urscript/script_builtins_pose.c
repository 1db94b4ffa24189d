/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_pose.c — the rest of UR's pose algebra (module urmath):
 * pose_sub, pose_dist, point_dist, interpolate_pose, rotvec2rpy and rpy2rotvec, normalize.
 * pose_trans, pose_add and pose_inv live in script_builtins_math.c. Nothing here reads the
 * controller or waits.
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"

static int need_pose(vm *V, const us_node *n, const sv *a, int k) {
  if (a[k].t != V_POSE) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s must be a pose", k + 1,
                        n->name->len, n->name->s);
  }
  return X_OK;
}

/* three numbers from a list (rotvec2rpy, rpy2rotvec) */
static int vec3(vm *V, const us_node *n, const sv *a, int k, double x[3]) {
  if (a[k].t != V_LIST || a[k].n != 3) {
    return urt__us_fail(V, n, "Type error: argument %d of %.*s must be a list of 3 numbers",
                        k + 1, n->name->len, n->name->s);
  }
  for (int j = 0; j < 3; j++) {
    if (!is_num(&a[k].u.l[j]) || !isfinite(num(&a[k].u.l[j]))) {
      return urt__us_fail(V, n, "Type error: element %d of argument %d of %.*s is not a number",
                          j, k + 1, n->name->len, n->name->s);
    }
    x[j] = num(&a[k].u.l[j]);
  }
  return X_OK;
}

static void transpose(const double R[9], double T[9]) {
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) T[3 * i + j] = R[3 * j + i];
  }
}

/* pose_sub(p_to, p_from): positions subtract; the rotation is the one pose_add composes with
 * p_from's to give p_to's (pose_add(p_from, pose_sub(p_to, p_from)) == p_to) */
static int b_pose_sub(vm *V, const us_node *n, sv *a, sv *out) {
  if (need_pose(V, n, a, 0) != X_OK || need_pose(V, n, a, 1) != X_OK) return X_ERR;
  const double *to = a[0].u.p, *from = a[1].u.p;
  double Rt[9], Rf[9], RfT[9], R[9], o[6];
  urt__us_rotvec_to_mat(to + 3, Rt);
  urt__us_rotvec_to_mat(from + 3, Rf);
  transpose(Rf, RfT);
  urt__us_mat_mul(Rt, RfT, R);
  for (int i = 0; i < 3; i++) o[i] = to[i] - from[i];
  urt__us_mat_to_rotvec(R, o + 3);
  *out = mk_pose(o);
  return X_OK;
}

/* pose_dist(p_from, p_to): the euclidean distance of the six numbers (rotation included), as
 * UR's worked example gives 2.50394 for [0.4,-0.2,0.4,-3.1,2.8,-2.3] → [-0.01,-1.5,-0.002,
 * -1.5,1.5,-2.3] */
static int b_pose_dist(vm *V, const us_node *n, sv *a, sv *out) {
  if (need_pose(V, n, a, 0) != X_OK || need_pose(V, n, a, 1) != X_OK) return X_ERR;
  double s = 0;
  for (int j = 0; j < 6; j++) s += (a[0].u.p[j] - a[1].u.p[j]) * (a[0].u.p[j] - a[1].u.p[j]);
  *out = mk_float(sqrt(s));
  return X_OK;
}

/* point_dist(p_from, p_to): the distance of the positions only */
static int b_point_dist(vm *V, const us_node *n, sv *a, sv *out) {
  if (need_pose(V, n, a, 0) != X_OK || need_pose(V, n, a, 1) != X_OK) return X_ERR;
  double s = 0;
  for (int j = 0; j < 3; j++) s += (a[0].u.p[j] - a[1].u.p[j]) * (a[0].u.p[j] - a[1].u.p[j]);
  *out = mk_float(sqrt(s));
  return X_OK;
}

/* interpolate_pose(p_from, p_to, alpha): the position on the straight line, the orientation
 * along the geodesic R_from · exp(alpha · log(R_fromᵀ R_to)); alpha outside [0, 1] extrapolates */
static int b_interpolate_pose(vm *V, const us_node *n, sv *a, sv *out) {
  double alpha;
  if (need_pose(V, n, a, 0) != X_OK || need_pose(V, n, a, 1) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0, &alpha) != X_OK) {
    return X_ERR;
  }
  const double *p = a[0].u.p, *q = a[1].u.p;
  double Rp[9], RpT[9], Rq[9], D[9], d[3], Ra[9], R[9], o[6];
  urt__us_rotvec_to_mat(p + 3, Rp);
  urt__us_rotvec_to_mat(q + 3, Rq);
  transpose(Rp, RpT);
  urt__us_mat_mul(RpT, Rq, D);
  urt__us_mat_to_rotvec(D, d);
  for (int j = 0; j < 3; j++) d[j] *= alpha;
  urt__us_rotvec_to_mat(d, Ra);
  urt__us_mat_mul(Rp, Ra, R);
  for (int j = 0; j < 3; j++) o[j] = p[j] + alpha * (q[j] - p[j]);
  urt__us_mat_to_rotvec(R, o + 3);
  *out = mk_pose(o);
  return X_OK;
}

/* R_rpy = Rz(yaw) Ry(pitch) Rx(roll) (UR's definition) */
static void rpy_to_mat(const double rpy[3], double R[9]) {
  double cr = cos(rpy[0]), sr = sin(rpy[0]), cp = cos(rpy[1]), sp = sin(rpy[1]),
         cy = cos(rpy[2]), sy = sin(rpy[2]);
  double M[9] = {cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
                 sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
                 -sp,     cp * sr,                cp * cr};
  memcpy(R, M, sizeof M);
}

static int b_rotvec2rpy(vm *V, const us_node *n, sv *a, sv *out) {
  double r[3], R[9], rpy[3];
  if (vec3(V, n, a, 0, r) != X_OK) return X_ERR;
  urt__us_rotvec_to_mat(r, R);
  rpy[1] = atan2(-R[6], sqrt(R[0] * R[0] + R[3] * R[3]));
  if (fabs(cos(rpy[1])) > 1e-12) {
    rpy[0] = atan2(R[7], R[8]);
    rpy[2] = atan2(R[3], R[0]);
  } else {
    // gimbal lock: roll and yaw share one axis; put it all in roll
    rpy[0] = atan2(-R[5], R[4]);
    rpy[2] = 0;
  }
  return urt__us_list_out(V, n, rpy, 3, out);
}

static int b_rpy2rotvec(vm *V, const us_node *n, sv *a, sv *out) {
  double rpy[3], R[9], r[3];
  if (vec3(V, n, a, 0, rpy) != X_OK) return X_ERR;
  rpy_to_mat(rpy, R);
  urt__us_mat_to_rotvec(R, r);
  return urt__us_list_out(V, n, r, 3, out);
}

/* normalize(v): v / norm(v) for a list of numbers; all zeros is an error, as UR documents */
static int b_normalize(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t != V_LIST) return urt__us_fail(V, n, "Type error: normalize of %s", type_name(a[0].t));
  double s = 0, x[URT_SCRIPT_MAX_LIST];
  for (int j = 0; j < a[0].n; j++) {
    if (!is_num(&a[0].u.l[j])) return urt__us_fail(V, n, "Type error: normalize of a list of %s", type_name(a[0].u.l[j].t));
    x[j] = num(&a[0].u.l[j]);
    s += x[j] * x[j];
  }
  if (!(s > 0) || !isfinite(s)) return urt__us_fail(V, n, "normalize: the list has no direction (all zeros)");
  s = sqrt(s);
  for (int j = 0; j < a[0].n; j++) x[j] /= s;
  return urt__us_list_out(V, n, x, a[0].n, out);
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_pose[] = {
    {"pose_sub", b_pose_sub, 2, P("p_to", "p_from")},
    {"pose_dist", b_pose_dist, 2, P("p_from", "p_to")},
    {"point_dist", b_point_dist, 2, P("p_from", "p_to")},
    {"interpolate_pose", b_interpolate_pose, 3, P("p_from", "p_to", "alpha")},
    {"rotvec2rpy", b_rotvec2rpy, 1, P("rotation_vector")},
    {"rpy2rotvec", b_rpy2rotvec, 1, P("rpy_vector")},
    {"normalize", b_normalize, 1, P("v")},
};
#undef P

const int urt__us_n_builtins_pose =
    (int)(sizeof urt__us_builtins_pose / sizeof urt__us_builtins_pose[0]);
