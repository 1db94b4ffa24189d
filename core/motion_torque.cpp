// SPDX-License-Identifier: Apache-2.0
// core/motion_torque.cpp — direct torque (directTorque): every drive in torque mode makes the
// commanded joint torque (index 1: plus the friction model at the actual speed); the set-point
// follows the arm. With no new TORQUE for 4 periods the drives return to position control,
// decelerate at 4 rad/s² and hold. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

constexpr int kTorqueTimeout = 4;  // periods without a TORQUE before the arm is stopped

uint32_t bad_target(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  return torque_faults(m, cmd.tau);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_torque_state_t& tp = e.c->motion_state.torque;
  std::memcpy(tp.tau, cmd.tau, sizeof tp.tau);
  tp.friction = cmd.index == 1 ? 1.0 : 0.0;
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
  for (int j = 0; j < URT_NJ; j++) {
    double f = tp.friction != 0.0 ? friction_ff(m, j, e.d->x[j][URT_X_QD]) : 0.0;
    c->tau_ff[j] = clamp_torque(m, j, tp.tau[j] + f);
  }
  mark_done(c, c->motion_id);
  return 0;
}

}  // namespace

const Motion kTorqueMotion = {URT_MOTION_TORQUE, false, true,         true,   no_bad_argument,
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
