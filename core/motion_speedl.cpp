// SPDX-License-Identifier: Apache-2.0
// core/motion_speedl.cpp — speedl: the tool twist (v; ω, base frame) ramps to its goal at a
// (a_rot, else a, for ω), resolved into joint speeds through the damped inverse Jacobian at the
// set-point. With t > 0 the tool decelerates after t; without, the call returns once the twist
// is reached and it holds until replaced. Inside force mode a speedl moves the non-compliant
// axes instead (motion_force.cpp). Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.a_rot) ||
         !std::isfinite(cmd.t);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_ctrl_t* c = e.c;
  urt_speedl_state_t& sl = c->motion_state.speedl;
  put6(setpoint_twist(e.m, c), sl.xd);
  std::memcpy(sl.xd_goal, cmd.pose, sizeof sl.xd_goal);
  c->motion = URT_MOTION_SPEEDL;
}

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  const double T = c->period;
  urt_speedl_state_t& sl = c->motion_state.speedl;
  double a_rot = c->active.a_rot > 0.0 ? c->active.a_rot : c->active.a;
  ramp3(sl.xd, sl.xd_goal, c->active.a * T);
  ramp3(sl.xd + 3, sl.xd_goal + 3, a_rot * T);
  Mat3 R;
  Vec3 pos;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q0), R, pos, &J);
  Vec6 qd = dls_solve(J, vec6(sl.xd), dls_lambda(J));
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j];
    c->qd1[j] = qd[j];
    c->q1[j] = c->q0[j] + 0.5 * (v0 + qd[j]) * T;
    c->qdd1[j] = (qd[j] - v0) / T;
  }
  bool reached = true;
  for (int i = 0; i < 6; i++) {
    reached = reached && sl.xd[i] == sl.xd_goal[i];
  }
  if (reached && c->active.t <= 0.0) {
    mark_done(c, c->motion_id);
  }
  if (c->active.t > 0.0 && c->seg_time >= c->active.t - 1e-12) {
    mark_done(c, c->motion_id);
    start_stop(c, tcp_twist_decel_time(m, c, c->active.a, a_rot));
  }
  return 0;
}

}  // namespace

const Motion kSpeedlMotion = {URT_MOTION_SPEEDL, false, false,        false,  bad_argument,
                              pose_faults,       start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
