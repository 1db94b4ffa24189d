// SPDX-License-Identifier: Apache-2.0
// core/controller.cpp — the UR controller's state machine (urt/controller.h): robot and safety
// modes, which commands are taken or refused, which motion runs (movej, movel, servoj, speedj,
// speedl, stopj, stopl, direct, servol, servoc, direct torque, freedrive, force mode, pause)
// and when its id is done, the speed slider and pause, the command checks and protective stops,
// and the set-point interpolation the physics steps follow. The rest of the motion layer sits
// beside it, one job a file: the commands that are not motions (outputs, modes, payload, force
// mode, …: controller_commands.cpp), the motions (motion.hpp, motion_*.cpp), kinematics and IK
// (controller_kinematics.cpp), the model feed-forward (controller_feedforward.cpp) and the motor
// thermal model (controller_thermal.cpp); controller_internal.hpp is what they share.
// Everything runs on the physics thread: fixed-size Eigen on the stack, no allocation, no
// exceptions. Context: RT unless stated.
//
// Choices (the contract leaves them to the controller):
// - Blending (r > 0): movej/optimovej/movel with r > 0, movep, movec and optimovel run as a
//   planned path (motion_path.cpp); a planned motion arriving while one with r > 0 runs is
//   queued behind it through the running motion's blend hook (below, in apply_motion).
// - A movej/movel arriving while the set-point moves first brings the arm to rest at the new
//   command's deceleration, then starts (c->pending); the previous motion's id is marked done.
// - When not RUNNING, or in a protective stop, the set-point holds where the arm is (the brakes
//   hold a real arm; here the drives, which stay engaged in the physics, do).
// - Feed-forward: every set-point carries the model's torque (controller_feedforward.cpp).
// - The speed slider scales a planned motion's time (movej, movel) and speedj's: its path (or
//   motion) time advances at speed_scaling per second, and speed_scaling follows the slider at
//   most 2 /s; a speedj's speeds are its commanded ones times the scaling, and its t is motion
//   time (motion_speedj.cpp), as on a controller, whose slider slows every motion. servoj,
//   speedl and stops are not scaled here yet.
// - HALT decelerates like stopj(4 rad/s²); it does not change program_state (the runner does).
// - SET_PAYLOAD mounts the payload on link 6 (urt_data_set_payload): the physics, the CVODE
//   reference and the controller's model (feed-forward, target current, TCP force, freedrive)
//   all read d->live.payload, so the twin carries what the program says it carries. A payload
//   outside urt_payload_invalid()'s bounds (over 5 kg, CoG beyond 1 m, a non-physical inertia)
//   is refused. With a transition time t (set_target_payload) the payload moves linearly to the
//   new one over t, a step each tick (urt_data_live_advance); payload_mass/cog are the target.
// - PAUSE multiplies the slider's scaling by a pause factor that slews to 0 at 4 /s (RESUME: back
//   to 1), so movej/movel (and a movej waiting behind a stop) slow down along their path, hold,
//   and continue; streamed motions (servoj/l/c, speedj/l, direct, torque, freedrive, force) stop
//   as with HALT. PROGRAM_STATE STOPPED clears the pause and stops what it held.
// - DIRECT (LCM, DDS) set-points further from the current set-point than qd_max · period are a
//   protective stop (URT_CTRL_FAULT_JUMP), not a step the interpolation would clamp.
// - SET_WRENCH writes d->wrench_ext (each force ≤ 1000 N, torque ≤ 200 N m, finite).
// - SET_GRAVITY changes the controller's model only (feed-forward, freedrive and torque-mode
//   gravity), as set_gravity does on a real controller; the world's gravity is the model's
//   (urt_model_t is const), so a wrong value shows as a tracking error, as on a real arm.
// - TORQUE (directTorque) and FREEDRIVE run the drives in torque mode (urt_command_t.torque_mask:
//   i_ref = τ/(k_t τ_gear), position and speed loops off). The set-point follows the arm. TORQUE
//   applies the command each period (index 1 adds the friction model at the actual speed); with
//   no new TORQUE for 4 periods the drives return to position control, decelerate at 4 rad/s²
//   and hold. Torques above torque_max are a protective stop.
// - FREEDRIVE: τ = g(q) of the controller's gravity; held feature-frame axes (q[i] = 0) get a
//   Cartesian spring-damper toward the pose freedrive began at (tick_freedrive in
//   motion_freedrive.cpp).
// - SERVOL: IK of the pose once per command (from the set-point), then servoj's filter. SERVOC:
//   the tool twist ramps at a toward min(v, √(2 a d)) along the line to the goal; r is treated
//   as 0 (no blending); its id is done on arrival.
// - FORCE_MODE: a first-order admittance per compliant task-frame axis on the F/T reading
//   d->wrench_ext (an ideal sensor), speed-limited; the other axes follow a speedl inside force
//   mode (or hold) and are checked against their deviation limits (tick_force in
//   motion_force.cpp).
#include <cmath>
#include <cstring>

#include "controller_internal.hpp"
#include "motion.hpp"
#include "step_internal.h"
#include "urt/controller.h"
#include "urt/faults.h"
#include "urt/core.h"

namespace urt::core {

namespace {

constexpr double kSliderRate = 2.0;  // speed_scaling slew rate [1/s]
constexpr double kPauseRate = 4.0;   // pause_scale slew rate [1/s]: 0.25 s from full speed to rest

}  // namespace

// ---- command checks ----

// URT_PSTOP_* bit a joint target deserves (0: fine); inverse kinematics checks its candidates
// with it too
uint32_t target_faults(const urt_model_t* m, const double* q) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(q[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    if (q[j] < m->joint[j].q_min || q[j] > m->joint[j].q_max) {
      return URT_PSTOP_POS_LIMIT;
    }
  }
  return 0;
}

// ---- motion bookkeeping (the generators end their motions too) ----

void mark_done(urt_ctrl_t* c, uint64_t id) noexcept {
  if (id > c->motion_done_id) {
    c->motion_done_id = id;
  }
}

// end the current motion (finished or aborted): its id is done
void finish_motion(urt_ctrl_t* c) noexcept {
  mark_done(c, c->motion_id);
  if (c->has_pending) {
    mark_done(c, c->pending.id);
    c->has_pending = 0;
  }
  c->motion = URT_MOTION_IDLE;
  std::memset(c->tau_ff, 0, sizeof c->tau_ff);
  c->torque_mask = 0;   // back to position control
  c->force_mode = 0;
}


uint32_t speed_faults(const urt_model_t* m, const double* qd) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(qd[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
    if (std::fabs(qd[j]) > m->joint[j].qd_max) {
      return URT_PSTOP_SPEED_LIMIT;
    }
  }
  return 0;
}

uint32_t torque_faults(const urt_model_t* m, const double* tau) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(tau[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
    if (std::fabs(tau[j]) > m->joint[j].torque_max) {
      return URT_PSTOP_TORQUE_LIMIT;
    }
  }
  return 0;
}

// ---- the state machine's moves (the settings' commands use them too) ----

bool running(const urt_ctrl_t* c) noexcept {
  return c->robot_mode == URT_ROBOT_MODE_RUNNING && c->safety_mode == URT_SAFETY_MODE_NORMAL;
}

// hold the set-point at q, at rest (both ends of the current period)
void hold_at(urt_ctrl_t* c, const Vec6& q) noexcept {
  put6(q, c->q0);
  put6(q, c->q1);
  std::memset(c->qd0, 0, sizeof c->qd0);
  std::memset(c->qd1, 0, sizeof c->qd1);
  std::memset(c->qdd0, 0, sizeof c->qdd0);
  std::memset(c->qdd1, 0, sizeof c->qdd1);
}

// the arm powered off: the motion ends and the set-point holds where the arm is
void power_off(urt_ctrl_t* c, const urt_data_t* d) noexcept {
  finish_motion(c);
  c->robot_mode = URT_ROBOT_MODE_POWER_OFF;
  hold_at(c, measured_q(d));
}

void protective_stop(urt_ctrl_t* c, urt_data_t* d, uint32_t fault, uint32_t pstop_bits) noexcept {
  c->fault |= fault;
  c->safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  // a stop met while running (the path left the workspace, the physics stopped, the program's
  // own protective_stop()) pauses the program, as on a UR: it stays paused after the unlock
  // until `play` resumes it or a stop ends it (external_control.md, "Pause"). A target outside
  // the joint limits is a runtime error that ends the program instead (the VM reports it).
  if (c->program_state == URT_PROGRAM_PLAYING && !(fault & URT_CTRL_FAULT_BAD_TARGET)) {
    c->paused = 1;
  }
  finish_motion(c);  // and out of torque and force mode
  if (pstop_bits) {
    d->pstop |= pstop_bits;
    urt__command_hold(d);
  }
  hold_at(c, vec6(d->cmd.q));
  std::memset(c->tau_model0, 0, sizeof c->tau_model0);
  std::memset(c->tau_model1, 0, sizeof c->tau_model1);
}

namespace {

void refuse(urt_ctrl_t* c, const urt_ctrl_cmd_t* cmd, uint32_t fault) noexcept {
  c->fault |= fault;
  mark_done(c, cmd->id);
}

// a motion command: checked, then started by its type (motion.hpp)
void apply_motion(const MotionEnv& e, const Motion& type, const urt_ctrl_cmd_t* cmd) noexcept {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_data_t* d = e.d;
  const int kind = cmd->kind;
  if (!running(c) || d->pstop) {
    refuse(c, cmd, URT_CTRL_FAULT_NOT_RUNNING);
    return;
  }
  // arguments first (refused, no stop), then targets (protective stop)
  if (type.bad_argument(*cmd)) {
    refuse(c, cmd, URT_CTRL_FAULT_BAD_ARGUMENT);
    return;
  }
  if (uint32_t bad_target = type.bad_target(m, *cmd)) {
    mark_done(c, cmd->id);
    protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, bad_target);
    return;
  }
  // an external set-point the joints cannot reach within the period is a protective stop where
  // the arm is, not a step the set-point interpolation would clamp to qd_max in silence
  if (kind == URT_CTRL_DIRECT && direct_jump_joints(m, c, *cmd)) {
    mark_done(c, cmd->id);
    protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET | URT_CTRL_FAULT_JUMP, URT_PSTOP_SPEED_LIMIT);
    return;
  }
  double qg[URT_NJ];
  if (type.pose_target) {
    if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, cmd->pose, c->q1, qg) != URT_OK) {
      // a tool-space line (movel, movep) is planned in Cartesian space, and one whose target
      // the arm cannot reach leaves the workspace: a protective stop, as the line leaving it
      // midway is (motion_movel.cpp). URCL's unfeasible_movel_target test sends a movel to
      // x = -10.2 m and waits for RobotModeData's protective stop (URSim gives it), then
      // unlocks. urtwin stops at once, where the arm is; whether a real controller first runs
      // the line to the workspace's edge is unchecked. Other pose commands are refused.
      if (kind == URT_CTRL_MOVEL || kind == URT_CTRL_MOVEP) {
        mark_done(c, cmd->id);
        protective_stop(c, d, URT_CTRL_FAULT_IK, URT_PSTOP_POS_LIMIT);
        return;
      }
      refuse(c, cmd, URT_CTRL_FAULT_IK);
      return;
    }
  }

  // inside force mode a speedl (or a stop) sets the motion of the non-compliant axes; any
  // other motion ends force mode and runs as usual
  if (c->force_mode && c->motion == URT_MOTION_FORCE) {
    if (kind == URT_CTRL_SPEEDL || kind == URT_CTRL_STOPL || kind == URT_CTRL_STOPJ) {
      force_take_speed(e, *cmd);
      return;
    }
    c->force_mode = 0;
  }

  // the running motion may take the new one over inside its blend radius
  const Motion& now = motion_of(c->motion);
  if (now.blend && now.blend(e, *cmd)) {
    return;
  }

  // accepted: the previous motion is over (aborted or superseded); a stream (same id, same
  // kind) continues
  c->fault = 0;
  const int prev_kind = c->active.kind;
  const bool same_stream =
      type.stream && cmd->id == c->motion_id && kind == prev_kind && c->motion == type.id;
  uint64_t prev_id = c->motion_id;
  if (c->has_pending) {
    mark_done(c, c->pending.id);
    c->has_pending = 0;
  }
  if (!same_stream) {
    mark_done(c, prev_id);
  }
  std::memset(c->tau_ff, 0, sizeof c->tau_ff);
  if (!type.torque_controlled) {
    c->torque_mask = 0;  // position control from where the arm is (q1, q̇1 follow it)
  }
  const urt_ctrl_motion_t prev_motion = c->motion;
  c->active = *cmd;
  c->motion_id = cmd->id;
  c->seg_time = 0.0;
  type.start(e, *cmd, MotionStart{prev_motion, type.pose_target ? qg : nullptr});
}

}  // namespace
}  // namespace urt::core

using namespace urt::core;

extern "C" {


int urt_ctrl_init(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d, double period,
                  int powered) {
  if (!m || !c || !d || !(period > 0.0)) {
    return URT_EINVAL;
  }
  double n = period / m->dt;
  if (std::fabs(n - std::round(n)) > 1e-6 || std::round(n) < 1.0) {
    return URT_EINVAL;
  }
  std::memset(c, 0, sizeof *c);
  c->period = period;
  c->n_sub = (int)std::round(n);
  c->robot_mode = powered ? URT_ROBOT_MODE_RUNNING : URT_ROBOT_MODE_POWER_OFF;
  c->safety_mode = URT_SAFETY_MODE_NORMAL;
  c->program_state = URT_PROGRAM_STOPPED;
  c->speed_slider = 1.0;
  c->speed_scaling = 1.0;
  c->pause_scale = 1.0;
  std::memcpy(c->gravity, m->arm.gravity, sizeof c->gravity);
  std::memcpy(c->tcp_offset, m->arm.tcp, sizeof c->tcp_offset);
  c->motion = URT_MOTION_IDLE;
  Vec6 q = actual_q(d);
  hold_at(c, q);
  Vec6 g;
  gravity(m->arm, d->live.payload, q, g);
  put6(g, c->tau_bias);
  model_torque(m, c, d->live.payload, c->q1, c->qd1, c->qdd1, c->tau_model1);
  std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);
  for (int j = 0; j < URT_NJ; j++) {
    c->temperature[j] = m->thermal[j].t_amb;
  }
  // the encoders' disagreement now (the gear's deflection at rest) is the first reference
  c->enc_joint = -1;
  c->fault_joint = -1;
  tick_encoder_check(m, c, d, false);
  return URT_OK;
}

void urt_ctrl_apply(const urt_model_t* m, urt_ctrl_t* c, urt_data_t* d,
                    const urt_ctrl_cmd_t* cmd) {
  const MotionEnv e{m, c, d, 0.0, 0.0};
  if (const Motion* type = motion_for_command(*cmd)) {
    apply_motion(e, *type, cmd);
    return;
  }
  apply_setting(e, cmd);  // everything else: I/O, modes, payload, … (controller_commands.cpp)
}

void urt_ctrl_tick(const urt_model_t* m, urt_ctrl_t* c, urt_data_t* d) {
  c->tick++;
  // the end of the last period is the start of this one
  std::memcpy(c->q0, c->q1, sizeof c->q0);
  std::memcpy(c->qd0, c->qd1, sizeof c->qd0);
  std::memcpy(c->qdd0, c->qdd1, sizeof c->qdd0);
  std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);

  // parameters in transition (a payload's transition_time) take this period's value
  urt_data_live_advance(m, d, c->period);

  tick_thermal(m, c, d);

  // the speed slider, slewed
  double ds = c->speed_slider - c->speed_scaling, dmax = kSliderRate * c->period;
  double dscale = std::fmax(-dmax, std::fmin(dmax, ds)) / c->period;
  c->speed_scaling += dscale * c->period;

  // the pause, slewed the same way, multiplies it: planned motions slow down along their path
  double dp = (c->paused ? 0.0 : 1.0) - c->pause_scale, dpmax = kPauseRate * c->period;
  double dpause = std::fmax(-dpmax, std::fmin(dpmax, dp)) / c->period;
  c->pause_scale += dpause * c->period;
  const double scale = c->speed_scaling * c->pause_scale;
  const double dscale_all = dscale * c->pause_scale + c->speed_scaling * dpause;

  // the physics stopped: follow it
  if (d->pstop && c->safety_mode != URT_SAFETY_MODE_PROTECTIVE_STOP) {
    protective_stop(c, d, URT_CTRL_FAULT_PSTOP, 0);
  }
  // a joint's two encoders disagree: stop the arm before the loop carries it further
  const int enc = tick_encoder_check(m, c, d, running(c) && !d->pstop);
  if (enc >= 0) {
    c->enc_joint = enc;
    protective_stop(c, d, URT_CTRL_FAULT_ENCODER, URT_PSTOP_ENCODER);
  }
  // a drive held at its current limit: the joint faults and the arm powers off, its brakes
  // holding it where it is; a running program ends (its motion is refused), as on a UR
  const int oc = tick_overcurrent_check(m, c, d, running(c) && !d->pstop);
  if (oc >= 0) {
    c->fault |= URT_CTRL_FAULT_JOINT;
    c->fault_joint = oc;
    c->safety_mode = URT_SAFETY_MODE_FAULT;
    power_off(c, d);
  }
  if (!running(c)) {
    c->torque_mask = c->torque_mask_last = 0;
    // hold (protective stop: where the physics froze; otherwise where the set-point was)
    if (c->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP) {
      hold_at(c, vec6(d->cmd.q));
      std::memset(c->tau_model1, 0, sizeof c->tau_model1);
      std::memset(c->tau_model0, 0, sizeof c->tau_model0);
    } else {
      hold_at(c, vec6(c->q0));
      model_torque(m, c, d->live.payload, c->q1, c->qd1, c->qdd1, c->tau_model1);
    }
    return;
  }

  c->seg_time += c->period;
  const MotionEnv e{m, c, d, scale, dscale_all};
  if (uint32_t fault = motion_of(c->motion).tick(e)) {
    // the motion cannot go on (a line out of the workspace, a force-mode deviation)
    protective_stop(c, d, fault, URT_PSTOP_POS_LIMIT);
    c->torque_mask_last = 0;
    return;
  }

  // a set-point the joints cannot follow is a protective stop, as on a real robot (for
  // torque-controlled joints: the arm left the joint limits or runs too fast)
  uint32_t bad = target_faults(m, c->q1);
  if (!bad) {
    bad = speed_faults(m, c->qd1);
  }
  if (bad) {
    protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, bad);
    c->torque_mask_last = 0;
    return;
  }
  model_torque(m, c, d->live.payload, c->q1, c->qd1, c->qdd1, c->tau_model1);

  // torque-controlled joints take c->tau_ff alone; a joint back from torque control starts
  // its period on the model feed-forward (not on the zero it carried)
  for (int j = 0; j < URT_NJ; j++) {
    const bool now = (c->torque_mask >> j) & 1u, before = (c->torque_mask_last >> j) & 1u;
    if (now) {
      c->tau_model0[j] = c->tau_model1[j] = 0.0;
    } else if (before) {
      c->tau_model0[j] = c->tau_model1[j];
    }
  }
  c->torque_mask_last = c->torque_mask;
}

// Cubic Hermite between (q0, q̇0) and (q1, q̇1) over the period. The physics holds q̈ over its
// step (q + q̇ s + q̈ s²/2), so q̈ is the cubic's at a third of the step: the step then ends
// exactly on the cubic.
void urt_ctrl_setpoint(const urt_model_t* m, const urt_ctrl_t* c, int k, urt_command_t* out) {
  const double T = c->period, dt = m->dt;
  const double u = (k * dt) / T, um = (k * dt + dt / 3.0) / T;
  const double u2 = u * u, u3 = u2 * u;
  const double h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  const double d00 = 6 * u2 - 6 * u, d10 = 3 * u2 - 4 * u + 1, d01 = -d00, d11 = 3 * u2 - 2 * u;
  const double a00 = 12 * um - 6, a10 = 6 * um - 4, a01 = -a00, a11 = 6 * um - 2;
  const double w = (k * dt + 0.5 * dt) / T;  // feed-forward: linear, at the step's middle
  for (int j = 0; j < URT_NJ; j++) {
    double dq = c->q1[j] - c->q0[j];
    out->q[j] = c->q0[j] + (h10 * T * c->qd0[j] + h01 * dq + h11 * T * c->qd1[j]);
    out->qd[j] = (d00 * c->q0[j] + d10 * T * c->qd0[j] + d01 * c->q1[j] + d11 * T * c->qd1[j]) / T;
    out->qdd[j] =
        (a00 * c->q0[j] + a10 * T * c->qd0[j] + a01 * c->q1[j] + a11 * T * c->qd1[j]) / (T * T);
    // keep within what urt_command_set accepts (rounding at the limits)
    const double vmax = m->joint[j].qd_max, amax = m->joint[j].qdd_max;
    out->qd[j] = std::fmax(-vmax, std::fmin(vmax, out->qd[j]));
    out->qdd[j] = std::fmax(-amax, std::fmin(amax, out->qdd[j]));
    out->tau_ff[j] = (1.0 - w) * c->tau_model0[j] + w * c->tau_model1[j] + c->tau_ff[j];
  }
  out->torque_mask = c->torque_mask;
}

}  // extern "C"
