// SPDX-License-Identifier: Apache-2.0
// core/motion_servoc.cpp — servoc: the tool twist ramps (at a) toward the straight line to the
// goal at the speed that can still stop there, min(v, √(2 a d), d/T); the orientation turns in
// proportion so that both arrive together (at most 1 rad/s, 4 rad/s², alone once the position
// is there). Blending (r) is not done: each new goal is approached from the current set-point
// and twist. The id is done on arrival, the set-point then on the goal at rest. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.r);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s) {
  urt_ctrl_t* c = e.c;
  urt_servoc_state_t& sc = c->motion_state.servoc;
  if (s.prev != URT_MOTION_SERVOC) {
    put6(setpoint_twist(e.m, c), sc.xd);
  }
  std::memcpy(sc.target, cmd.pose, sizeof sc.target);
  c->motion = URT_MOTION_SERVOC;
}

// true when the goal is reached
bool advance(const urt_model_t* m, urt_ctrl_t* c) {
  constexpr double kRotV = 1.0, kRotA = 4.0;
  const double T = c->period, a = c->active.a, v = c->active.v;
  urt_servoc_state_t& sc = c->motion_state.servoc;
  Mat3 R;
  Vec3 pos;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q0), R, pos, nullptr);
  const Vec3 p_goal(sc.target[0], sc.target[1], sc.target[2]);
  const Mat3 R_goal = rotation_from_rotvec(Vec3(sc.target[3], sc.target[4], sc.target[5]));
  const Vec3 dp = p_goal - pos;
  const Vec3 rot = R * rotvec_from_rotation(R.transpose() * R_goal);  // base frame
  const double dist = dp.norm(), theta = rot.norm();
  const Vec6 xd_now = vec6(sc.xd);

  // arrived: land on the goal exactly (IK) and rest
  if (dist < 2e-5 && theta < 2e-4 && xd_now.head<3>().norm() <= 2.0 * a * T &&
      xd_now.tail<3>().norm() <= 2.0 * kRotA * T) {
    double q[URT_NJ];
    if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, sc.target, c->q0, q) == URT_OK) {
      std::memcpy(c->q1, q, sizeof c->q1);
    }
    std::memset(c->qd1, 0, sizeof c->qd1);
    std::memset(c->qdd1, 0, sizeof c->qdd1);
    std::memset(sc.xd, 0, sizeof sc.xd);
    return true;
  }

  // desired twist, then ramp the twist toward it
  double vd = std::fmin(v, std::fmin(std::sqrt(2.0 * a * dist), dist / T));
  Vec3 v_des = dist > 1e-12 ? Vec3(dp * (vd / dist)) : Vec3::Zero();
  double wd = std::fmin(kRotV, std::fmin(std::sqrt(2.0 * kRotA * theta), theta / T));
  if (dist > 1e-6) {
    wd = std::fmin(wd, theta * vd / dist);
  }
  Vec3 w_des = theta > 1e-12 ? Vec3(rot * (wd / theta)) : Vec3::Zero();
  ramp3(sc.xd, v_des.data(), a * T);
  ramp3(sc.xd + 3, w_des.data(), kRotA * T);
  twist_to_joints(m, c, vec6(sc.xd));
  return false;
}

uint32_t tick(const MotionEnv& e) {
  if (advance(e.m, e.c)) {
    finish_motion(e.c);
  }
  return 0;
}

}  // namespace

const Motion kServocMotion = {URT_MOTION_SERVOC, true,  true,         false,  bad_argument,
                              pose_faults,       start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
