/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_client.c — the state getters and settings URCL's and ur_rtde's
 * control scripts call beyond script_builtins_robot.c's: the step time, target speeds and
 * accelerations, joint torques, the flange pose, the payload as set, the joints' history,
 * inverse kinematics with qnear and tcp honoured and a solution check, joint limits, Coriolis
 * torques, set_gravity / set_target_payload / set_tool_voltage, and popup.
 *
 * set_target_payload (script_builtins_modes.c) mounts mass, centre of gravity and inertia on
 * link 6 through the controller's SET_PAYLOAD, over its transition time.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "script_vm.h"
#include "urt/core.h"

static void pose_inv(const double p[6], double o[6]) {
  double R[9], Rt[9];
  urt__us_rotvec_to_mat(p + 3, R);
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) Rt[3 * i + j] = R[3 * j + i];
  }
  for (int i = 0; i < 3; i++) o[i] = -(Rt[3 * i] * p[0] + Rt[3 * i + 1] * p[1] + Rt[3 * i + 2] * p[2]);
  urt__us_mat_to_rotvec(Rt, o + 3);
}

/* a pose for tool `from` re-expressed for tool `to`: pose ∘ from⁻¹ ∘ to (same flange) */
static void retool(const double pose[6], const double from[6], const double to[6], double o[6]) {
  double inv[6], flange[6];
  pose_inv(from, inv);
  urt__us_pose_trans(pose, inv, flange);
  urt__us_pose_trans(flange, to, o);
}

//---- getters ----

/* get_actual_joint_positions_history(steps=0): the actual joint positions `steps` controller
 * ticks before the newest snapshot (the controller keeps URT_LOOP_HISTORY ticks) */
static int b_get_actual_joint_positions_history(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t steps = 0;
  if (a[0].t != V_NONE && urt__us_arg_int(V, n, a, 0, &steps) != X_OK) return X_ERR;
  const urt_script_host_t *h = V->h->host;
  const urt_snapshot_t *now = urt__us_snap(V);
  if (steps < 0 || (uint64_t)steps > now->tick) {
    return urt__us_fail(V, n, "get_actual_joint_positions_history: %lld steps back is outside 0..%llu",
                        (long long)steps, (unsigned long long)now->tick);
  }
  if (steps == 0) return urt__us_list_out(V, n, now->q, 6, out);
  urt_snapshot_t past;
  if (!h->snapshot_at || h->snapshot_at(h->ctx, now->tick - (uint64_t)steps, &past) != 0) {
    return urt__us_fail(V, n, "get_actual_joint_positions_history: %lld steps back is older than the controller keeps",
                        (long long)steps);
  }
  return urt__us_list_out(V, n, past.q, 6, out);
}


/* get_joint_positions(): the controller's current target joint positions (external_control.md
 * §2.4.3: "the robot's current target"), not the encoders. URCL's script takes it as the start
 * of each spline and as the servo set-point when it enters servoj mode; the measured q (one
 * encoder count from the set-point at rest) made that first servoj move a resting arm. */
static int b_get_joint_positions(vm *V, const us_node *n, sv *a, sv *out) { return urt__us_list_out(V, n, urt__us_snap(V)->q_target, 6, out); }
static int b_get_actual_joint_accelerations(vm *V, const us_node *n, sv *a, sv *out) { return urt__us_list_out(V, n, urt__us_snap(V)->qdd, 6, out); }
static int b_get_tcp_force(vm *V, const us_node *n, sv *a, sv *out) { return urt__us_list_out(V, n, urt__us_snap(V)->tcp_force, 6, out); }

/* force(): the size of the force part of the TCP wrench (UR: the norm of Fx, Fy, Fz) */
static int b_force(vm *V, const us_node *n, sv *a, sv *out) {
  const double *f = urt__us_snap(V)->tcp_force;
  *out = mk_float(sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]));
  return X_OK;
}

static int b_get_tool_accelerometer_reading(vm *V, const us_node *n, sv *a, sv *out) { return urt__us_list_out(V, n, urt__us_snap(V)->tool_accel, 3, out); }

static int b_get_joint_temp(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t j;
  if (urt__us_arg_int(V, n, a, 0, &j) != X_OK) return X_ERR;
  if (j < 0 || j >= URT_NJ) return urt__us_fail(V, n, "get_joint_temp: joint %lld outside 0..5", (long long)j);
  *out = mk_float(urt__us_snap(V)->temperature[j]);
  return X_OK;
}

//---- kinematics ----

/* the optional tcp argument k: a pose (absent: the active TCP) */
static int tcp_arg(vm *V, const us_node *n, const sv *a, int k, double tcp[6]) {
  if (a[k].t == V_NONE) {
    memcpy(tcp, urt__us_snap(V)->tcp_offset, 6 * sizeof *tcp);
    return X_OK;
  }
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, k, tcp, &is_pose) != X_OK) return X_ERR;
  if (!is_pose) return urt__us_fail(V, n, "Type error: tcp of %.*s must be a pose", n->name->len, n->name->s);
  return X_OK;
}

/* IK of pose x for tool tcp near qnear (absent: the actual joint positions): 0, or -1 with
 * no solution; X_ERR for bad arguments or no kinematics */
static int ik(vm *V, const us_node *n, const sv *a, double q[6], bool *found) {
  double x[6], qnear[6], tcp[6], target[6];
  bool is_pose;
  const urt_script_host_t *h = V->h->host;
  if (urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK) return X_ERR;
  if (!is_pose) return urt__us_fail(V, n, "Type error: argument 1 of %.*s must be a pose", n->name->len, n->name->s);
  if (a[1].t == V_NONE) memcpy(qnear, urt__us_snap(V)->q, sizeof qnear);
  else if (urt__us_arg_vec6(V, n, a, 1, qnear, NULL) != X_OK) return X_ERR;
  double ignored;
  if (urt__us_arg_num(V, n, a, 2, 1e-10, &ignored) != X_OK || urt__us_arg_num(V, n, a, 3, 1e-10, &ignored) != X_OK) return X_ERR;
  if (tcp_arg(V, n, a, 4, tcp) != X_OK) return X_ERR;
  if (!h->inverse_kinematics) return urt__us_fail(V, n, "%.*s: inverse kinematics is not available", n->name->len, n->name->s);
  // the host solves for the active TCP: move the target there
  retool(x, tcp, urt__us_snap(V)->tcp_offset, target);
  *found = h->inverse_kinematics(h->ctx, target, qnear, q) == 0;
  return X_OK;
}

/* get_inverse_kin(x, qnear, maxPositionError, maxOrientationError, tcp): the solution nearest
 * qnear; none is a runtime error, as on the controller */
static int b_get_inverse_kin(vm *V, const us_node *n, sv *a, sv *out) {
  double q[6];
  bool found = false;
  if (ik(V, n, a, q, &found) != X_OK) return X_ERR;
  if (!found) return urt__us_fail(V, n, "get_inverse_kin: no solution for the pose");
  return urt__us_list_out(V, n, q, 6, out);
}

/* get_forward_kin(q, tcp): the pose of tool tcp (absent: the active TCP) at q (absent: actual) */
static int b_get_forward_kin(vm *V, const us_node *n, sv *a, sv *out) {
  double q[6], tcp[6], p[6], o[6];
  const urt_script_host_t *h = V->h->host;
  if (a[0].t == V_NONE) memcpy(q, urt__us_snap(V)->q, sizeof q);
  else if (urt__us_arg_vec6(V, n, a, 0, q, NULL) != X_OK) return X_ERR;
  if (tcp_arg(V, n, a, 1, tcp) != X_OK) return X_ERR;
  if (!h->forward_kinematics) return urt__us_fail(V, n, "get_forward_kin: forward kinematics is not available");
  if (h->forward_kinematics(h->ctx, q, p) != 0) return urt__us_fail(V, n, "get_forward_kin failed");
  retool(p, urt__us_snap(V)->tcp_offset, tcp, o);
  *out = mk_pose(o);
  return X_OK;
}

//---- settings ----

/* set_tool_voltage(voltage): 0, 12 or 24 V at the tool connector (RTDE tool_output_voltage) */
static int b_set_tool_voltage(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_TOOL_VOLTAGE};
  if (urt__us_arg_num(V, n, a, 0, 0, &c.value) != X_OK) return X_ERR;
  if (c.value != 0 && c.value != 12 && c.value != 24) {
    return urt__us_fail(V, n, "set_tool_voltage: %g V is not 0, 12 or 24", c.value);
  }
  return urt__us_submit(V, n, &c);
}

//---- operator ----

/* popup(s, title="Popup", warning=False, error=False, blocking=False): the primary interface's
 * POPUP message; a blocking popup holds the program until an operator dismisses it, and urtwin
 * has no operator: it waits until the program is stopped, as a controller with nobody at the
 * pendant does */
static int b_popup(vm *V, const us_node *n, sv *a, sv *out) {
  urt_script_msg_t m = {.kind = URT_SCRIPT_MSG_POPUP};
  bool warning = false, error = false, blocking = false;
  if ((a[2].t != V_NONE && urt__us_arg_bool(V, n, a, 2, &warning) != X_OK) ||
      (a[3].t != V_NONE && urt__us_arg_bool(V, n, a, 3, &error) != X_OK) ||
      (a[4].t != V_NONE && urt__us_arg_bool(V, n, a, 4, &blocking) != X_OK)) {
    return X_ERR;
  }
  if (a[1].t != V_NONE && a[1].t != V_STR) return urt__us_fail(V, n, "Type error: popup title is %s, not a string", type_name(a[1].t));
  urt__us_fmt_value(&a[0], m.text, sizeof m.text);
  snprintf(m.title, sizeof m.title, "%.*s", a[1].t == V_STR ? a[1].n : 5, a[1].t == V_STR ? a[1].u.s : "Popup");
  m.warning = warning;
  m.error = error;
  m.blocking = blocking;
  m.time = urt__us_snap(V)->time;
  V->h->host->message(V->h->host->ctx, &m);
  while (blocking) {
    if (urt__us_wait_tick(V, n) != X_OK) return X_ERR;
  }
  return X_OK;
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_client[] = {
    {"get_joint_positions", b_get_joint_positions, 0, P(NULL)},
    {"get_actual_joint_positions_history", b_get_actual_joint_positions_history, 0, P("steps")},
    {"get_actual_joint_accelerations", b_get_actual_joint_accelerations, 0, P(NULL)},
    {"get_tcp_force", b_get_tcp_force, 0, P(NULL)},
    {"get_joint_temp", b_get_joint_temp, 1, P("j")},
    {"force", b_force, 0, P(NULL)},
    {"get_tool_accelerometer_reading", b_get_tool_accelerometer_reading, 0, P(NULL)},
    {"get_inverse_kin", b_get_inverse_kin, 1, P("x", "qnear", "maxPositionError", "maxOrientationError", "tcp")},
    {"get_forward_kin", b_get_forward_kin, 0, P("q", "tcp")},
    {"popup", b_popup, 1, P("s", "title", "warning", "error", "blocking")},
    {"set_tool_voltage", b_set_tool_voltage, 1, P("voltage")},
};
#undef P

const int urt__us_n_builtins_client =
    (int)(sizeof urt__us_builtins_client / sizeof urt__us_builtins_client[0]);
