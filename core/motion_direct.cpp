// SPDX-License-Identifier: Apache-2.0
// core/motion_direct.cpp — external joint set-points (the LCM command channel): the set-point is
// the command's q, q̇ (q̈ their change over the period), with its torque feed-forward; each
// command is done in the period it is applied. Context: RT.
#include <cmath>

#include "motion.hpp"

namespace urt::core {

namespace {

uint32_t bad_target(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  uint32_t bad = target_faults(m, cmd.q);
  if (!bad) {
    bad = speed_faults(m, cmd.qd);
  }
  if (!bad) {
    bad = torque_faults(m, cmd.tau);
  }
  for (int j = 0; !bad && cmd.kind == URT_CTRL_SETPOINT && j < URT_NJ; j++) {
    if (!std::isfinite(cmd.pose[j])) {
      bad = URT_PSTOP_NONFINITE_CMD;
    } else if (std::fabs(cmd.pose[j]) > m->joint[j].qdd_max) {
      bad = URT_PSTOP_ACC_LIMIT;
    }
  }
  return bad;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  std::memcpy(e.c->tau_ff, cmd.tau, sizeof e.c->tau_ff);
  e.c->motion = URT_MOTION_DIRECT;
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  std::memcpy(c->q1, c->active.q, sizeof c->q1);
  std::memcpy(c->qd1, c->active.qd, sizeof c->qd1);
  for (int j = 0; j < URT_NJ; j++) {
    c->qdd1[j] = c->active.kind == URT_CTRL_SETPOINT ? c->active.pose[j]
                                                     : (c->qd1[j] - c->qd0[j]) / c->period;
  }
  mark_done(c, c->motion_id);
  return 0;
}

}  // namespace

const Motion kDirectMotion = {URT_MOTION_DIRECT, false, false,        false,  no_bad_argument,
                              bad_target,        start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
