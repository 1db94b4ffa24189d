/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_robot.c — the URScript builtins that move the arm or read its
 * state: motions (movej … stopl, through script_controller.c), textmsg, sleep and sync in
 * controller time, the TCP and payload settings, and the joint and TCP getters (kinematics and the rest of the
 * state: script_builtins_client.c).
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"

//---- motion ----

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
  if (h->forward_kinematics(h->ctx, x, p) != 0) return urt__us_fail(V, n,
                                                                    "Forward kinematics failed");
  return X_OK;
}

static int b_move(vm *V, const us_node *n, sv *a, sv *out, int kind, double da, double dv) {
  urt_ctrl_cmd_t c = {.kind = kind};
  double x[6];
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK || urt__us_arg_num(V, n, a, 1, da,
                                                                           &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, dv, &c.v) != X_OK || urt__us_arg_num(V, n, a, 3, 0,
                                                                       &c.t) != X_OK ||
      urt__us_arg_num(V, n, a, 4, 0, &c.r) != X_OK) {
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

/* optimovej(q, a=0.3, v=0.3, r=0): a and v are fractions in (0, 1] of the joints' limits; the
 * controller (core/motion_movej.cpp) refuses fractions outside it. UR added optimovej and
 * optimovel in 5.21 (none on CB3): on an older emulated release a runtime error, as for
 * direct_torque (URCL's tests skip them there; its script leaves them out) */
static int b_optimovej(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_OPTIMOVEJ};
  double x[6];
  bool is_pose;
  if (urt__us_require_version(V, n, "optimovej", 5, 21, 0) != X_OK ||
      urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK ||
      urt__us_arg_num(V, n, a, 1, 0.3, &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0.3, &c.v) != X_OK ||
      urt__us_arg_num(V, n, a, 3, 0, &c.r) != X_OK || to_joints(V, n, x, is_pose, c.q) != X_OK) {
    return X_ERR;
  }
  return urt__us_motion(V, n, "optimovej", &c, true);
}

static int b_movel(vm *V, const us_node *n, sv *a, sv *out) {
  return b_move(V, n, a, out, URT_CTRL_MOVEL, 1.2, 0.25);
}

/* movep(pose, a=1.2, v=0.25, r=0): the tool at constant speed v, circular blends of radius r
 * (core/motion_path.cpp); a joint list is a pose through forward kinematics */
static int b_movep(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_MOVEP};
  double x[6];
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK ||
      urt__us_arg_num(V, n, a, 1, 1.2, &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0.25, &c.v) != X_OK ||
      urt__us_arg_num(V, n, a, 3, 0, &c.r) != X_OK || to_pose(V, n, x, is_pose, c.pose) != X_OK) {
    return X_ERR;
  }
  return urt__us_motion(V, n, "movep", &c, true);
}

/* movec(pose_via, pose_to, a=1.2, v=0.25, r=0, mode=0): the arc from the current pose through
 * pose_via's position to pose_to; mode 0 interpolates the orientation to pose_to's, mode 1
 * keeps it fixed relative to the arc's tangent. The controller takes pose_via in q[0..2] */
static int b_movec(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_MOVEC};
  double xv[6], xt[6], via[6], mode;
  bool via_pose, to_pose_;
  if (urt__us_arg_vec6(V, n, a, 0, xv, &via_pose) != X_OK ||
      urt__us_arg_vec6(V, n, a, 1, xt, &to_pose_) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 1.2, &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 3, 0.25, &c.v) != X_OK ||
      urt__us_arg_num(V, n, a, 4, 0, &c.r) != X_OK ||
      urt__us_arg_num(V, n, a, 5, 0, &mode) != X_OK || to_pose(V, n, xv, via_pose, via) != X_OK ||
      to_pose(V, n, xt, to_pose_, c.pose) != X_OK) {
    return X_ERR;
  }
  if (mode != 0 && mode != 1) {
    return urt__us_fail(V, n, "movec: mode must be 0 (unconstrained) or 1 (fixed), not %g", mode);
  }
  c.index = (int32_t)mode;
  memcpy(c.q, via, 3 * sizeof *c.q);
  return urt__us_motion(V, n, "movec", &c, true);
}

/* optimovel(goal, a=0.3, v=0.3, r=0): a and v are fractions in (0, 1] of the tool acceleration
 * and speed the joints allow along the line; the controller refuses fractions outside it */
static int b_optimovel(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_OPTIMOVEL};
  double x[6];
  bool is_pose;
  if (urt__us_require_version(V, n, "optimovel", 5, 21, 0) != X_OK ||
      urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK ||
      urt__us_arg_num(V, n, a, 1, 0.3, &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0.3, &c.v) != X_OK ||
      urt__us_arg_num(V, n, a, 3, 0, &c.r) != X_OK || to_pose(V, n, x, is_pose, c.pose) != X_OK) {
    return X_ERR;
  }
  return urt__us_motion(V, n, "optimovel", &c, true);
}

static int b_servoj(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SERVOJ};
  double x[6], ignored;
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, x, &is_pose) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                           &ignored) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0, &ignored) != X_OK || urt__us_arg_num(V, n, a, 3, 0.002,
                                                                          &c.t) != X_OK ||
      urt__us_arg_num(V, n, a, 4, 0.1, &c.lookahead_time) != X_OK ||
      urt__us_arg_num(V, n, a, 5, 300, &c.gain) != X_OK || to_joints(V, n, x, is_pose,
                                                                     c.q) != X_OK) {
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
  if (urt__us_arg_vec6(V, n, a, 0, c.q, NULL) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                         &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0, &c.t) != X_OK || urt__us_arg_num(V, n, a, 3, 0,
                                                                      &t_min) != X_OK) {
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
  // the slider scales speedj (core/motion_speedj.cpp): t is motion time, and so is the ramp
  if (c.t > 0) return urt__us_wait_scaled(V, n, c.t, "speedj");
  return urt__us_wait_scaled(V, n, ramp, "speedj");
}

static int b_speedl(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SPEEDL};
  double t_min;
  if (urt__us_arg_vec6(V, n, a, 0, c.pose, NULL) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                            &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0, &c.t) != X_OK || urt__us_arg_num(V, n, a, 3, c.a,
                                                                      &c.a_rot) != X_OK ||
      urt__us_arg_num(V, n, a, 4, 0, &t_min) != X_OK) {
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
  if (urt__us_arg_num(V, n, a, 0, 0, &c.a) != X_OK) return X_ERR;
  return urt__us_motion(V, n, "stopj", &c, true);
}

static int b_stopl(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_STOPL};
  if (urt__us_arg_num(V, n, a, 0, 0, &c.a) != X_OK || urt__us_arg_num(V, n, a, 1, c.a,
                                                                      &c.a_rot) != X_OK) {
    return X_ERR;
  }
  return urt__us_motion(V, n, "stopl", &c, true);
}

//---- program ----

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
  if (urt__us_arg_num(V, n, a, 0, 0, &t) != X_OK) return X_ERR;
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

//---- settings ----

static int b_set_tcp(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_TCP};
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, c.pose, &is_pose) != X_OK) return X_ERR;
  return urt__us_submit(V, n, &c);
}

/* set_payload(m[, cog]) and the two setters below are one SET_PAYLOAD each (mounted on link 6
 * at the next tick). set_payload leaves a point mass (UR: an omitted inertia is a zero
 * matrix); set_payload_mass and set_payload_cog keep the rest of the mounted payload. */
static int payload_submit(vm *V, const us_node *n, sv *a, const double *inertia, const char *fn) {
  // set_payload(m, CoG=…) spells the second parameter two ways
  if (a[1].t == V_NONE) a[1] = a[2];
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_PAYLOAD};
  if (urt__us_arg_num(V, n, a, 0, 0, &c.value) != X_OK) return X_ERR;
  if (c.value < 0) return urt__us_fail(V, n, "%s: negative mass %g", fn, c.value);
  const urt_snapshot_t *s = urt__us_snap(V);
  memcpy(c.pose, s->payload_cog, sizeof s->payload_cog);
  if (inertia) memcpy(c.tau, inertia, 6 * sizeof *c.tau);
  if (a[1].t != V_NONE) {
    // CoG as [x, y, z], (x, y, z) or a pose (position part)
    if (a[1].t == V_POSE) {
      memcpy(c.pose, a[1].u.p, 3 * sizeof *c.pose);
    } else if (a[1].t == V_LIST && a[1].n == 3 && is_num(&a[1].u.l[0]) && is_num(&a[1].u.l[1]) &&
               is_num(&a[1].u.l[2])) {
      for (int j = 0; j < 3; j++) c.pose[j] = num(&a[1].u.l[j]);
    } else {
      return urt__us_fail(V, n, "Type error: %s center of gravity must be 3 numbers", fn);
    }
  }
  urt_payload_t p = {.mass = c.value};
  memcpy(p.cog, c.pose, sizeof p.cog);
  memcpy(p.inertia, c.tau, sizeof p.inertia);
  const char *why = urt_payload_invalid(&p);
  if (why) return urt__us_fail(V, n, "%s: %s", fn, why);
  return urt__us_submit(V, n, &c);
}

static int b_set_payload(vm *V, const us_node *n, sv *a, sv *out) {
  return payload_submit(V, n, a, NULL, "set_payload");
}

static int b_set_payload_mass(vm *V, const us_node *n, sv *a, sv *out) {
  sv args[MAX_ARGS] = {a[0]};
  return payload_submit(V, n, args, urt__us_snap(V)->payload_inertia, "set_payload_mass");
}

static int b_set_payload_cog(vm *V, const us_node *n, sv *a, sv *out) {
  sv args[MAX_ARGS] = {mk_float(urt__us_snap(V)->payload_mass), a[0]};
  return payload_submit(V, n, args, urt__us_snap(V)->payload_inertia, "set_payload_cog");
}


//---- state ----

static int vec_out(vm *V, const us_node *n, const double *x, sv *out) { return urt__us_list_out(V, n, x, 6, out); }

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

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_robot[] = {
    // motion
    {"movej", b_movej, 1, P("q", "a", "v", "t", "r")},
    {"optimovej", b_optimovej, 1, P("q", "a", "v", "r")},
    {"movel", b_movel, 1, P("pose", "a", "v", "t", "r")},
    {"movep", b_movep, 1, P("pose", "a", "v", "r")},
    {"movec", b_movec, 2, P("pose_via", "pose_to", "a", "v", "r", "mode")},
    {"optimovel", b_optimovel, 1, P("goal", "a", "v", "r")},
    {"servoj", b_servoj, 1, P("q", "a", "v", "t", "lookahead_time", "gain")},
    {"speedj", b_speedj, 2, P("qd", "a", "t", "t_min")},
    {"speedl", b_speedl, 2, P("xd", "a", "t", "aRot", "t_min")},
    {"stopj", b_stopj, 1, P("a")},
    {"stopl", b_stopl, 1, P("a", "aRot")},
    // program
    {"textmsg", b_textmsg, 1, P("s1", "s2")},
    {"sleep", b_sleep, 1, P("t")},
    {"sync", b_sync, 0, P(NULL)},
    // settings
    {"set_tcp", b_set_tcp, 1, P("pose")},
    {"set_payload", b_set_payload, 1, P("m", "cog", "CoG")},
    {"set_payload_mass", b_set_payload_mass, 1, P("m")},
    {"set_payload_cog", b_set_payload_cog, 1, P("CoG")},
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
};
#undef P

const int urt__us_n_builtins_robot =
    (int)(sizeof urt__us_builtins_robot / sizeof urt__us_builtins_robot[0]);
