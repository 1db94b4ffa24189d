/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_modes.c — the URScript builtins that put the arm in a control
 * mode other than a planned motion: force mode (with its damping and gain scaling), freedrive and
 * teach mode, servoc and direct_torque streams, and the model settings set_gravity and
 * set_target_payload. Each is one controller command (core/include/urt/controller.h).
 */
#include <math.h>
#include <string.h>

#include "script_vm.h"

//---- force mode ----

static int b_force_mode(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_FORCE_MODE};
  int64_t type;
  bool frame_is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, c.pose, &frame_is_pose) != X_OK ||
      urt__us_arg_vec6(V, n, a, 1, c.q, NULL) != X_OK ||
      urt__us_arg_vec6(V, n, a, 2, c.tau, NULL) != X_OK || urt__us_arg_int(V, n, a, 3, &type) != X_OK ||
      urt__us_arg_vec6(V, n, a, 4, c.qd, NULL) != X_OK) {
    return X_ERR;
  }
  if (type < 1 || type > 3) return urt__us_fail(V, n, "force_mode: type %lld is not 1, 2 or 3", (long long)type);
  for (int j = 0; j < 6; j++) {
    if (c.q[j] != 0 && c.q[j] != 1) return urt__us_fail(V, n, "force_mode: selection_vector element %d is not 0 or 1", j);
  }
  us_force_state *f = urt__us_force_state(V);
  c.index = (int32_t)type;
  c.value = f->damping;
  c.gain = f->gain_scaling;
  if (urt__us_submit(V, n, &c) != X_OK) return X_ERR;
  f->active = true;
  f->cmd = c;
  return X_OK;
}

static int force_setting(vm *V, const us_node *n, sv *a, double lo, double hi, bool damping) {
  double x;
  if (urt__us_arg_num(V, n, a, 0, 0, &x) != X_OK) return X_ERR;
  if (x < lo || x > hi) {
    return urt__us_fail(V, n, "%.*s: %g outside [%g, %g]", n->name->len, n->name->s, x, lo, hi);
  }
  us_force_state *f = urt__us_force_state(V);
  if (damping) f->damping = x;
  else f->gain_scaling = x;
  if (!f->active) return X_OK;
  // the active force mode takes it at once
  f->cmd.value = f->damping;
  f->cmd.gain = f->gain_scaling;
  return urt__us_submit(V, n, &f->cmd);
}

static int b_force_mode_set_damping(vm *V, const us_node *n, sv *a, sv *out) { return force_setting(V, n, a, 0, 1, true); }
static int b_force_mode_set_gain_scaling(vm *V, const us_node *n, sv *a, sv *out) { return force_setting(V, n, a, 0, 2, false); }

static int b_end_force_mode(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_FORCE_MODE_END};
  urt__us_force_state(V)->active = false;
  return urt__us_submit(V, n, &c);
}

//---- freedrive and teach mode ----

static int freedrive(vm *V, const us_node *n, const double axes[6], const double feature[6], bool on) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_FREEDRIVE, .index = on ? 1 : 0};
  if (axes) memcpy(c.q, axes, sizeof c.q);
  if (feature) memcpy(c.pose, feature, sizeof c.pose);
  return urt__us_motion(V, n, on ? "freedrive_mode" : "end_freedrive_mode", &c, false);
}

static int b_freedrive_mode(vm *V, const us_node *n, sv *a, sv *out) {
  double axes[6] = {1, 1, 1, 1, 1, 1}, feature[6] = {0};
  if (a[0].t != V_NONE && urt__us_arg_vec6(V, n, a, 0, axes, NULL) != X_OK) return X_ERR;
  if (a[1].t != V_NONE && urt__us_arg_vec6(V, n, a, 1, feature, NULL) != X_OK) return X_ERR;
  for (int j = 0; j < 6; j++) {
    if (axes[j] != 0 && axes[j] != 1) return urt__us_fail(V, n, "freedrive_mode: freeAxes element %d is not 0 or 1", j);
  }
  return freedrive(V, n, axes, feature, true);
}

static int b_teach_mode(vm *V, const us_node *n, sv *a, sv *out) {
  static const double all[6] = {1, 1, 1, 1, 1, 1};
  return freedrive(V, n, all, NULL, true);
}

static int b_end_freedrive_mode(vm *V, const us_node *n, sv *a, sv *out) { return freedrive(V, n, NULL, NULL, false); }

//---- streams ----

static int b_servoc(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SERVOC};
  bool is_pose;
  if (urt__us_arg_vec6(V, n, a, 0, c.pose, &is_pose) != X_OK || urt__us_arg_num(V, n, a, 1, 1.2, &c.a) != X_OK ||
      urt__us_arg_num(V, n, a, 2, 0.25, &c.v) != X_OK || urt__us_arg_num(V, n, a, 3, 0, &c.r) != X_OK) {
    return X_ERR;
  }
  if (!is_pose) return urt__us_fail(V, n, "servoc: the target must be a pose");
  if (urt__us_motion(V, n, "servoc", &c, false) != X_OK) return X_ERR;
  return urt__us_wait_for(V, n, urt__us_snap(V)->period, true, "servoc");  // one control cycle
}

/* direct_torque(torque, friction_comp, viscous_scale, coulomb_scale): the joint torques besides
 * gravity, which the controller adds (core/motion_torque.cpp). As UR's releases have it: none
 * before 5.23 (CB3 has none); 5.23 to 5.25.0 take friction_comp (default True: the whole
 * friction model); from 5.25.1 viscous_scale and coulomb_scale, each six shares in [0, 1] of the
 * model's viscous and Coulomb parts, default [0.9, 0.9, 0.8, 0.9, 0.9, 0.9] and
 * [0.8, 0.8, 0.7, 0.8, 0.8, 0.8] (script manual 5.25.1), with friction_comp still taken but
 * ignored once a scale is given. */
static int b_direct_torque(vm *V, const us_node *n, sv *a, sv *out) {
  static const double kViscous[URT_NJ] = {0.9, 0.9, 0.8, 0.9, 0.9, 0.9};
  static const double kCoulomb[URT_NJ] = {0.8, 0.8, 0.7, 0.8, 0.8, 0.8};
  const int *ver = V->h->version;
  if (urt__us_require_version(V, n, "direct_torque", 5, 23, 0) != X_OK) {
    return X_ERR;
  }
  const bool scales = urt__us_version_at_least(V, 5, 25, 1);
  if (!scales && (a[2].t != V_NONE || a[3].t != V_NONE)) {
    return urt__us_fail(V, n, "direct_torque: viscous_scale and coulomb_scale need software 5.25.1 (this is %d.%d.%d)",
                        ver[0], ver[1], ver[2]);
  }
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_TORQUE};
  if (urt__us_arg_vec6(V, n, a, 0, c.tau, NULL) != X_OK) return X_ERR;
  if (scales && (a[2].t != V_NONE || a[3].t != V_NONE || a[1].t == V_NONE)) {
    c.index = 2;
    memcpy(c.q, kViscous, sizeof c.q);
    memcpy(c.qd, kCoulomb, sizeof c.qd);
    if (a[2].t != V_NONE && urt__us_arg_vec6(V, n, a, 2, c.q, NULL) != X_OK) return X_ERR;
    if (a[3].t != V_NONE && urt__us_arg_vec6(V, n, a, 3, c.qd, NULL) != X_OK) return X_ERR;
    for (int j = 0; j < URT_NJ; j++) {
      if (!(c.q[j] >= 0.0 && c.q[j] <= 1.0) || !(c.qd[j] >= 0.0 && c.qd[j] <= 1.0)) {
        return urt__us_fail(V, n, "direct_torque: viscous_scale and coulomb_scale must lie in [0, 1] (joint %d)", j);
      }
    }
  } else {
    bool friction = true;
    if (a[1].t != V_NONE && urt__us_arg_bool(V, n, a, 1, &friction) != X_OK) return X_ERR;
    c.index = friction ? 1 : 0;
  }
  if (urt__us_motion(V, n, "direct_torque", &c, false) != X_OK) return X_ERR;
  return urt__us_wait_for(V, n, urt__us_snap(V)->period, true, "direct_torque");
}

//---- model settings ----

static int b_set_gravity(vm *V, const us_node *n, sv *a, sv *out) {
  // UR's argument is the direction away from the earth; the controller takes the acceleration
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_GRAVITY};
  if (a[0].t != V_LIST || a[0].n != 3) return urt__us_fail(V, n, "Type error: set_gravity takes a list of 3 numbers");
  for (int j = 0; j < 3; j++) {
    if (!is_num(&a[0].u.l[j])) return urt__us_fail(V, n, "Type error: set_gravity element %d is %s", j, type_name(a[0].u.l[j].t));
    c.pose[j] = -num(&a[0].u.l[j]);
    if (!isfinite(c.pose[j])) return urt__us_fail(V, n, "set_gravity: element %d is not finite", j);
  }
  return urt__us_submit(V, n, &c);
}

/* protective_stop(): the controller enters a protective stop now (C209A0 on the primary
 * interface, the 5 s unlock rule: core/controller.cpp, net/server/port_script.c); the program
 * stops with it, as a protective stop stops any program */
static int b_protective_stop(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_PROTECTIVE_STOP};
  // no wait here: URCL sends it as a secondary program (`sec … protective_stop() end`), which
  // may not consume time; the stop lands at the next controller tick and stops the program
  return urt__us_submit(V, n, &c);
}

/* set_target_payload(m, cog, inertia=[0]*6, transition_time=0): mass, CoG in the flange frame,
 * inertia about the CoG with flange-parallel axes (UR's conventions), mounted on link 6 at the
 * next controller tick (core/payload.cpp). A payload the physics cannot carry (over 5 kg, a CoG
 * beyond 1 m, a non-physical inertia) is a runtime error with urt_payload_invalid()'s reason.
 * With transition_time > 0 the payload moves linearly to the new one over that time. */
static int b_set_target_payload(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_PAYLOAD};
  double t;
  if (urt__us_arg_num(V, n, a, 0, 0, &c.value) != X_OK || urt__us_arg_num(V, n, a, 3, 0, &t) != X_OK) return X_ERR;
  if (a[1].t != V_LIST || a[1].n != 3) return urt__us_fail(V, n, "Type error: set_target_payload: cog must be 3 numbers");
  for (int j = 0; j < 3; j++) {
    if (!is_num(&a[1].u.l[j])) return urt__us_fail(V, n, "Type error: set_target_payload: cog element %d is %s", j, type_name(a[1].u.l[j].t));
    c.pose[j] = num(&a[1].u.l[j]);
  }
  if (a[2].t != V_NONE) {
    if (a[2].t != V_LIST || a[2].n != 6) return urt__us_fail(V, n, "Type error: set_target_payload: inertia must be 6 numbers");
    for (int j = 0; j < 6; j++) {
      if (!is_num(&a[2].u.l[j])) return urt__us_fail(V, n, "Type error: set_target_payload: inertia element %d is %s", j, type_name(a[2].u.l[j].t));
      c.tau[j] = num(&a[2].u.l[j]);
    }
  }
  if (!(t >= 0)) return urt__us_fail(V, n, "set_target_payload: negative transition_time %g", t);
  if (!(t <= 1000)) return urt__us_fail(V, n, "set_target_payload: transition_time %g s is beyond urtwin's 1000 s", t);
  c.t = t;
  urt_payload_t p = {.mass = c.value};
  memcpy(p.cog, c.pose, sizeof p.cog);
  memcpy(p.inertia, c.tau, sizeof p.inertia);
  const char *why = urt_payload_invalid(&p);
  if (why) return urt__us_fail(V, n, "set_target_payload: %s", why);
  return urt__us_submit(V, n, &c);
}

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_modes[] = {
    {"force_mode", b_force_mode, 5, P("task_frame", "selection_vector", "wrench", "type", "limits")},
    {"force_mode_set_damping", b_force_mode_set_damping, 1, P("damping")},
    {"force_mode_set_gain_scaling", b_force_mode_set_gain_scaling, 1, P("scaling")},
    {"end_force_mode", b_end_force_mode, 0, P(NULL)},
    {"freedrive_mode", b_freedrive_mode, 0, P("freeAxes", "feature")},
    {"end_freedrive_mode", b_end_freedrive_mode, 0, P(NULL)},
    {"teach_mode", b_teach_mode, 0, P(NULL)},
    {"end_teach_mode", b_end_freedrive_mode, 0, P(NULL)},
    {"servoc", b_servoc, 1, P("pose", "a", "v", "r")},
    {"direct_torque", b_direct_torque, 1, P("torque", "friction_comp", "viscous_scale", "coulomb_scale")},
    {"set_gravity", b_set_gravity, 1, P("d")},
    {"protective_stop", b_protective_stop, 0, P(NULL)},
    {"set_target_payload", b_set_target_payload, 2, P("m", "cog", "inertia", "transition_time")},
};
#undef P

const int urt__us_n_builtins_modes =
    (int)(sizeof urt__us_builtins_modes / sizeof urt__us_builtins_modes[0]);
