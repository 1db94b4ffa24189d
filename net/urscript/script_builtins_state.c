/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_state.c — the URScript getters of the controller's state and of
 * the robot model: step time, target TCP speed, joint torques and accelerations, payload, the
 * flange pose, the dynamics (mass matrix, Coriolis and centrifugal torques, Jacobian and its
 * time derivative, as 6×6 matrices) and the kinematic checks (IK solution, safety limits).
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"
#include "urt/core.h"

static int matrix_out(vm *V, const us_node *at, const double A[36], sv *out) {
  if (urt__us_list_out(V, at, A, 36, out) != X_OK) return X_ERR;
  out->t = V_MATRIX;
  out->cols = 6;
  return X_OK;
}

static const urt_model_t *model(vm *V, const us_node *n) {
  const urt_script_host_t *h = V->h->host;
  const urt_model_t *m = h->model ? h->model(h->ctx) : NULL;
  if (!m) urt__us_fail(V, n, "%.*s: the robot model is not available", n->name->len, n->name->s);
  return m;
}

//---- controller state ----

static int b_get_steptime(vm *V, const us_node *n, sv *a, sv *out) {
  *out = mk_float(urt__us_snap(V)->period);
  return X_OK;
}

static int b_get_target_tcp_speed(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_list_out(V, n, urt__us_snap(V)->tcp_speed_target, 6, out);
}

static int b_get_joint_torques(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_list_out(V, n, urt__us_snap(V)->tau, 6, out);
}

static int b_get_target_joint_accelerations(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_list_out(V, n, urt__us_snap(V)->qdd_target, 6, out);
}

static int b_get_target_payload(vm *V, const us_node *n, sv *a, sv *out) {
  *out = mk_float(urt__us_snap(V)->payload_mass);
  return X_OK;
}

static int b_get_target_payload_cog(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_list_out(V, n, urt__us_snap(V)->payload_cog, 3, out);
}

static int b_get_target_payload_inertia(vm *V, const us_node *n, sv *a, sv *out) {
  return urt__us_list_out(V, n, urt__us_snap(V)->payload_inertia, 6, out);
}

/* the payload the arm carries now: the snapshot's, with the declared inertia tensor replaced by
 * the nearest PSD one, as the physics carries it (a declared tensor need not be a body's) */
static urt_payload_t mounted(const urt_snapshot_t *s) {
  urt_payload_t p = {.mass = s->payload_mass};
  memcpy(p.cog, s->payload_cog, sizeof p.cog);
  urt_payload_physical(s->payload_inertia, p.inertia);
  return p;
}

static int b_get_freedrive_status(vm *V, const us_node *n, sv *a, sv *out) {
  // 0: not in freedrive; 1: freedrive (urtwin does not report the near-limit states 2, 3)
  *out = mk_int(urt__us_snap(V)->motion == URT_MOTION_FREEDRIVE ? 1 : 0);
  return X_OK;
}

//---- the model ----

static int b_get_actual_tool_flange_pose(vm *V, const us_node *n, sv *a, sv *out) {
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  double zero[6] = {0}, p[6];
  urt_ctrl_forward_kinematics_tcp(m, zero, urt__us_snap(V)->q, p);
  *out = mk_pose(p);
  return X_OK;
}

static int b_get_mass_matrix(vm *V, const us_node *n, sv *a, sv *out) {
  if (a[0].t != V_NONE && truthy(&a[0])) {
    return urt__us_fail(V, n, "get_mass_matrix: include_rotors_inertia is not modelled by urtwin");
  }
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  double M[36];
  const urt_payload_t p = mounted(urt__us_snap(V));
  urt_arm_mass_matrix_payload(m, &p, urt__us_snap(V)->q, M);
  return matrix_out(V, n, M, out);
}

static int b_get_jacobian(vm *V, const us_node *n, sv *a, sv *out) {
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  double J[36];
  urt_arm_jacobian(m, urt__us_snap(V)->q, J);
  return matrix_out(V, n, J, out);
}

static int b_get_jacobian_time_derivative(vm *V, const us_node *n, sv *a, sv *out) {
  // dJ/dt = Σ_j ∂J/∂q_j q̇_j: a central difference along q̇
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  const urt_snapshot_t *s = urt__us_snap(V);
  double h = 1e-6, qp[6], qm[6], Jp[36], Jm[36], D[36];
  for (int j = 0; j < 6; j++) {
    qp[j] = s->q[j] + h * s->qd[j];
    qm[j] = s->q[j] - h * s->qd[j];
  }
  urt_arm_jacobian(m, qp, Jp);
  urt_arm_jacobian(m, qm, Jm);
  for (int k = 0; k < 36; k++) D[k] = (Jp[k] - Jm[k]) / (2 * h);
  return matrix_out(V, n, D, out);
}

static int b_get_coriolis_and_centrifugal_torques(vm *V, const us_node *n, sv *a, sv *out) {
  // C(q, q̇) q̇ = rnea(q, q̇, 0) − g(q)
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  const urt_snapshot_t *s = urt__us_snap(V);
  double zero[6] = {0}, tau[6], g[6];
  const urt_payload_t p = mounted(s);
  urt_arm_rnea_payload(m, &p, s->q, s->qd, zero, tau);
  urt_arm_gravity_payload(m, &p, s->q, g);
  for (int j = 0; j < 6; j++) tau[j] -= g[j];
  return urt__us_list_out(V, n, tau, 6, out);
}

static bool within_limits(const urt_model_t *m, const double q[6]) {
  for (int j = 0; j < URT_NJ; j++) {
    if (!isfinite(q[j]) || q[j] < m->joint[j].q_min || q[j] > m->joint[j].q_max) return false;
  }
  return true;
}

static int b_get_inverse_kin_has_solution(vm *V, const us_node *n, sv *a, sv *out) {
  double x[6], qnear[6], q[6];
  if (urt__us_arg_vec6(V, n, a, 0, x, NULL) != X_OK) return X_ERR;
  memcpy(qnear, urt__us_snap(V)->q, sizeof qnear);
  if (a[1].t != V_NONE && urt__us_arg_vec6(V, n, a, 1, qnear, NULL) != X_OK) return X_ERR;
  if (a[4].t != V_NONE) {
    return urt__us_fail(V, n, "get_inverse_kin_has_solution: the tcp argument is not supported "
                              "by urtwin (the active TCP is used)");
  }
  const urt_script_host_t *h = V->h->host;
  if (!h->inverse_kinematics) return urt__us_fail(V, n, "Inverse kinematics is not available");
  *out = mk_bool(h->inverse_kinematics(h->ctx, x, qnear, q) == 0);
  return X_OK;
}

static int b_is_within_safety_limits(vm *V, const us_node *n, sv *a, sv *out) {
  // a pose: reachable by IK (from the actual joints) within the joint limits; joints: the limits
  double x[6], q[6];
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK) return X_ERR;
  const urt_model_t *m = model(V, n);
  if (!m) return X_ERR;
  if (!is_pose) {
    *out = mk_bool(within_limits(m, x));
    return X_OK;
  }
  const urt_script_host_t *h = V->h->host;
  if (!h->inverse_kinematics) return urt__us_fail(V, n, "Inverse kinematics is not available");
  *out = mk_bool(h->inverse_kinematics(h->ctx, x, urt__us_snap(V)->q, q) == 0 &&
                 within_limits(m, q));
  return X_OK;
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_state[] = {
    {"get_steptime", b_get_steptime, 0, P(NULL)},
    {"get_target_tcp_speed", b_get_target_tcp_speed, 0, P(NULL)},
    {"get_joint_torques", b_get_joint_torques, 0, P(NULL)},
    {"get_target_joint_accelerations", b_get_target_joint_accelerations, 0, P(NULL)},
    {"get_target_payload", b_get_target_payload, 0, P(NULL)},
    {"get_target_payload_cog", b_get_target_payload_cog, 0, P(NULL)},
    {"get_target_payload_inertia", b_get_target_payload_inertia, 0, P(NULL)},
    {"get_freedrive_status", b_get_freedrive_status, 0, P(NULL)},
    {"get_actual_tool_flange_pose", b_get_actual_tool_flange_pose, 0, P(NULL)},
    {"get_mass_matrix", b_get_mass_matrix, 0, P("include_rotors_inertia")},
    {"get_jacobian", b_get_jacobian, 0, P(NULL)},
    {"get_jacobian_time_derivative", b_get_jacobian_time_derivative, 0, P(NULL)},
    {"get_coriolis_and_centrifugal_torques", b_get_coriolis_and_centrifugal_torques, 0, P(NULL)},
    {"get_inverse_kin_has_solution", b_get_inverse_kin_has_solution, 1,
     P("pose", "qnear", "maxPositionError", "maxOrientationError", "tcp")},
    {"is_within_safety_limits", b_is_within_safety_limits, 1, P("pose")},
};
#undef P

const int urt__us_n_builtins_state =
    (int)(sizeof urt__us_builtins_state / sizeof urt__us_builtins_state[0]);
