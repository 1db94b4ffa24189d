// SPDX-License-Identifier: Apache-2.0
// core/motion_movel.cpp — movel: the TCP on a straight line (and the orientation about one
// axis, in proportion) along a trapezoid in path length from rest to rest, IK every period
// from the last set-point; a pure rotation takes a, v in rad/s², rad/s. Its time is the path
// time c->traj_time (speed slider, pause). Arriving while the set-point moves, it first stops
// (c->pending). A line that leaves the workspace is a protective stop. Context: RT.
#include <Eigen/Geometry>

#include "motion.hpp"

namespace urt::core {

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.t) || cmd.t < 0.0;
}

void plan(const MotionEnv& e, const urt_ctrl_cmd_t& cmd) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_movel_state_t& ml = c->motion_state.movel;
  Mat3 R0;
  Vec3 p0;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R0, p0, nullptr);
  Vec3 p1(cmd.pose[0], cmd.pose[1], cmd.pose[2]);
  Mat3 R1 = rotation_from_rotvec(Vec3(cmd.pose[3], cmd.pose[4], cmd.pose[5]));
  Vec3 rel = rotvec_from_rotation(R0.transpose() * R1);
  Vec3 dp = p1 - p0;
  Vec3 r0 = rotvec_from_rotation(R0);
  for (int i = 0; i < 3; i++) {
    ml.p_start[i] = p0[i];
    ml.dp[i] = dp[i];
    ml.r_start[i] = r0[i];
  }
  ml.theta = rel.norm();
  Vec3 axis = ml.theta > 0.0 ? Vec3(rel / ml.theta) : Vec3(0.0, 0.0, 1.0);
  for (int i = 0; i < 3; i++) {
    ml.axis[i] = axis[i];
  }
  // path length: the translation, or for a pure rotation the angle (a, v then in rad/s², rad/s)
  double D = dp.norm() > 1e-7 ? dp.norm() : ml.theta;
  ml.tr = trap_plan(D, cmd.v, cmd.a, cmd.t);
  c->motion = URT_MOTION_MOVEL;
  c->traj_time = 0.0;
  c->seg_time = 0.0;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_ctrl_t* c = e.c;
  if (moving(c)) {
    c->pending = cmd;
    c->has_pending = 1;
    start_stop(c, tcp_twist_decel_time(e.m, c, cmd.a, cmd.a));
  } else {
    plan(e, cmd);
  }
}

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  c->traj_time += e.scale * c->period;
  const urt_movel_state_t& ml = c->motion_state.movel;
  double s, sd, sdd;
  bool end = c->traj_time >= ml.tr.T;
  trap_eval(ml.tr, c->traj_time, s, sd, sdd);
  double u = ml.tr.D > 0.0 ? s / ml.tr.D : 1.0,
         ud = ml.tr.D > 0.0 ? sd * e.scale / ml.tr.D : 0.0;
  Vec3 axis(ml.axis[0], ml.axis[1], ml.axis[2]);
  Mat3 R0 = rotation_from_rotvec(Vec3(ml.r_start[0], ml.r_start[1], ml.r_start[2]));
  Mat3 R = R0 * rotation_from_rotvec(axis * (ml.theta * u));
  Vec3 pos(ml.p_start[0] + ml.dp[0] * u, ml.p_start[1] + ml.dp[1] * u,
           ml.p_start[2] + ml.dp[2] * u);
  Vec3 r = rotvec_from_rotation(R);
  double pose[6] = {pos[0], pos[1], pos[2], r[0], r[1], r[2]};
  double q[URT_NJ];
  if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, pose, c->q1, q) != URT_OK) {
    return URT_CTRL_FAULT_IK;  // the line left the workspace
  }
  Vec6 twist;
  twist << ml.dp[0] * ud, ml.dp[1] * ud, ml.dp[2] * ud, R0 * axis * (ml.theta * ud);
  Mat3 Rq;
  Vec3 pq;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(q), Rq, pq, &J);
  Vec6 qd = dls_solve(J, twist, 0.0);
  for (int j = 0; j < URT_NJ; j++) {
    c->q1[j] = q[j];
    c->qd1[j] = end ? 0.0 : qd[j];
    c->qdd1[j] = (c->qd1[j] - c->qd0[j]) / c->period;
  }
  if (end) {
    std::memset(c->qdd1, 0, sizeof c->qdd1);
    finish_motion(c);
  }
  return 0;
}

}  // namespace

const Motion kMovelMotion = {URT_MOTION_MOVEL, true, false,        false,  bad_argument,
                             pose_faults,      start, tick, stop_on_path, nullptr};

}  // namespace urt::core
