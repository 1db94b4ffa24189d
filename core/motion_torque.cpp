// SPDX-License-Identifier: Apache-2.0
// core/motion_torque.cpp — direct torque (direct_torque, directTorque): every drive in torque
// mode makes the commanded joint torque plus the controller's gravity g(q) (UR: "The function
// always compensates for gravity, meaning that the provided target torque should not include
// gravity compensation"; script manual 5.25.1) plus the friction model at the actual speed in
// the shares the command asks (index 1: all of it, friction_comp=True; index 2: the viscous and
// the Coulomb part scaled per joint, viscous_scale/coulomb_scale); the set-point follows the
// arm. With no new TORQUE for 4 periods the drives return to position control, decelerate at
// 4 rad/s² and hold. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

constexpr int kTorqueTimeout = 4;  // periods without a TORQUE before the arm is stopped

uint32_t bad_target(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  return torque_faults(m, cmd.tau);
}

// the friction shares: index 0..2, and with 2 every scale in [0, 1] (UR's range)
bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  if (cmd.index < 0 || cmd.index > 2) {
    return true;
  }
  bool bad = false;
  for (int j = 0; cmd.index == 2 && j < URT_NJ; j++) {
    bad = bad || !(cmd.q[j] >= 0.0 && cmd.q[j] <= 1.0) || !(cmd.qd[j] >= 0.0 && cmd.qd[j] <= 1.0);
  }
  return bad;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_torque_state_t& tp = e.c->motion_state.torque;
  std::memcpy(tp.tau, cmd.tau, sizeof tp.tau);
  for (int j = 0; j < URT_NJ; j++) {
    tp.viscous[j] = cmd.index == 2 ? cmd.q[j] : (cmd.index == 1 ? 1.0 : 0.0);
    tp.coulomb[j] = cmd.index == 2 ? cmd.qd[j] : (cmd.index == 1 ? 1.0 : 0.0);
  }
  tp.since = 0.0;
  e.c->motion = URT_MOTION_TORQUE;
}

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_torque_state_t& tp = c->motion_state.torque;
  follow_actual(m, c, e.d, kAllJoints);
  tp.since += c->period;
  if (tp.since > (kTorqueTimeout + 0.5) * c->period) {
    // the stream stopped: back to position control, decelerate to rest and hold
    finish_motion(c);
    start_stop(c, joint_stop_time(c, kHaltDecel));
    return 0;
  }
  c->torque_mask = kAllJoints;
  Vec6 g;
  ctrl_rnea(m, c, e.d->live.payload, actual_q(e.d), Vec6::Zero(), Vec6::Zero(), g);
  for (int j = 0; j < URT_NJ; j++) {
    const double f = friction_ff_scaled(m, j, e.d->x[j][URT_X_QD], tp.viscous[j], tp.coulomb[j]);
    c->tau_ff[j] = clamp_torque(m, j, tp.tau[j] + g[j] + f);
  }
  mark_done(c, c->motion_id);
  return 0;
}

}  // namespace

const Motion kTorqueMotion = {URT_MOTION_TORQUE, false, true,         true,   bad_argument,
                              bad_target,        start, tick, stop_to_rest, nullptr};

// torque-controlled joints: the set-point follows the arm (q, q̇ at the tick, q̈ their change),
// so that the command checks, the snapshot's targets and the return to position control see
// where the arm really is
void follow_actual(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                   uint32_t mask) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!((mask >> j) & 1u)) {
      continue;
    }
    const double amax = kAccMargin * m->joint[j].qdd_max;
    c->q1[j] = d->x[j][URT_X_Q];
    c->qd1[j] = d->x[j][URT_X_QD];
    c->qdd1[j] = std::fmax(-amax, std::fmin(amax, (c->qd1[j] - c->qd0[j]) / c->period));
  }
}

}  // namespace urt::core
