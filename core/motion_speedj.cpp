// SPDX-License-Identifier: Apache-2.0
// core/motion_speedj.cpp — speedj: every joint's speed ramps to its goal, the joints arriving
// together (the leading one at a). With t > 0 the arm decelerates at a after t; without, the
// call returns once the speed is reached and the speed holds until replaced. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.t);
}

uint32_t bad_target(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  return speed_faults(m, cmd.q);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_ctrl_t* c = e.c;
  urt_speedj_state_t& sj = c->motion_state.speedj;
  double dmax = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    sj.qd_goal[j] = cmd.q[j];
    dmax = std::fmax(dmax, std::fabs(cmd.q[j] - c->qd1[j]));
  }
  double tr = dmax / cmd.a;
  for (int j = 0; j < URT_NJ; j++) {
    sj.a[j] = tr > 0.0 ? std::fabs(cmd.q[j] - c->qd1[j]) / tr : 0.0;
  }
  c->motion = URT_MOTION_SPEEDJ;
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  const urt_speedj_state_t& sj = c->motion_state.speedj;
  const double T = c->period;
  bool reached = true;
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j], g = sj.qd_goal[j], dv = sj.a[j] * T;
    double v1 = std::fabs(g - v0) <= dv ? g : v0 + std::copysign(dv, g - v0);
    c->qd1[j] = v1;
    c->q1[j] = c->q0[j] + 0.5 * (v0 + v1) * T;
    c->qdd1[j] = (v1 - v0) / T;
    reached = reached && v1 == g;
  }
  if (reached && c->active.t <= 0.0) {
    mark_done(c, c->motion_id);  // speedj without t returns once the speed is reached
  }
  if (c->active.t > 0.0 && c->seg_time >= c->active.t - 1e-12) {
    mark_done(c, c->motion_id);
    start_stop(c, joint_stop_time(c, c->active.a));
  }
  return 0;
}

}  // namespace

const Motion kSpeedjMotion = {URT_MOTION_SPEEDJ, false, false,        false,  bad_argument,
                              bad_target,        start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
