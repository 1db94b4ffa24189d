// SPDX-License-Identifier: Apache-2.0
// core/motion_movel.cpp — movel: the TCP on a straight line (and the orientation about one
// axis, in proportion) along a trapezoid in path length from rest to rest, IK every period
// from the last set-point; a pure rotation takes a, v in rad/s², rad/s. Its time is the path
// time c->traj_time (speed slider, pause). Arriving while the set-point moves, it first stops
// (c->pending). A line that leaves the workspace is a protective stop. Context: RT.
//
// The trajectory limiter: a line whose a and v (or t) would turn a joint faster than the
// planner's margins on qd_max and qdd_max is slowed down to them, as a real controller's speed
// scaling slows it ("Unfeasible time constraints should simply result in speed scaling slowing
// down the robot": URCL's unfeasible_times_succeeds, a movel of t = 0.1 s that must succeed).
// The joints' rates per metre of path are sampled along the line at plan time; a line within
// them keeps the plan bit for bit.
#include <Eigen/Geometry>

#include "motion.hpp"

namespace urt::core {

namespace {

constexpr int kLimiterSamples = 24;  // points on the line where the joints' rates are sampled

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.t) || cmd.t < 0.0;
}

// the TCP pose at fraction u of the line (position, then rotation vector)
void line_pose(const urt_movel_state_t& ml, double u, double pose[6]) {
  Vec3 axis(ml.axis[0], ml.axis[1], ml.axis[2]);
  Mat3 R0 = rotation_from_rotvec(Vec3(ml.r_start[0], ml.r_start[1], ml.r_start[2]));
  Mat3 R = R0 * rotation_from_rotvec(axis * (ml.theta * u));
  Vec3 r = rotvec_from_rotation(R);
  for (int i = 0; i < 3; i++) {
    pose[i] = ml.p_start[i] + ml.dp[i] * u;
    pose[3 + i] = r[i];
  }
}

// the TCP twist per unit of path length (D: the translation, or the angle of a pure rotation)
Vec6 unit_twist(const urt_movel_state_t& ml, double D) {
  Vec3 axis(ml.axis[0], ml.axis[1], ml.axis[2]);
  Mat3 R0 = rotation_from_rotvec(Vec3(ml.r_start[0], ml.r_start[1], ml.r_start[2]));
  Vec6 x;
  x << ml.dp[0] / D, ml.dp[1] / D, ml.dp[2] / D, R0 * axis * (ml.theta / D);
  return x;
}

// the largest path speed and acceleration whose joint rates stay within the planner's margins
// at every sampled point of the line (up to the first the arm cannot reach: the tick stops there)
void joint_rate_limits(const MotionEnv& e, const urt_movel_state_t& ml, double D, double& v_lim,
                       double& a_lim) {
  const urt_model_t* m = e.m;
  const urt_ctrl_t* c = e.c;
  const Vec6 unit = unit_twist(ml, D);
  double q[URT_NJ], qnear[URT_NJ];
  std::memcpy(q, c->q1, sizeof q);
  for (int k = 0; k <= kLimiterSamples; k++) {
    if (k > 0) {
      double pose[6];
      line_pose(ml, (double)k / kLimiterSamples, pose);
      std::memcpy(qnear, q, sizeof qnear);
      if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, pose, qnear, q) != URT_OK) {
        return;
      }
    }
    Mat3 R;
    Vec3 p;
    Mat6 J;
    tcp_kinematics(m->arm, c->tcp_offset, vec6(q), R, p, &J);
    const Vec6 rate = dls_solve(J, unit, 0.0);  // joint rates per unit of path
    for (int j = 0; j < URT_NJ; j++) {
      const double g = std::fabs(rate[j]);
      if (g > 0.0 && std::isfinite(g)) {
        v_lim = std::fmin(v_lim, kSpeedMargin * m->joint[j].qd_max / g);
        a_lim = std::fmin(a_lim, kAccMargin * m->joint[j].qdd_max / g);
      }
    }
  }
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
  double v_lim = HUGE_VAL, a_lim = HUGE_VAL;
  if (D > 0.0) {
    joint_rate_limits(e, ml, D, v_lim, a_lim);
  }
  if (ml.tr.vp > v_lim || ml.tr.ap > a_lim) {
    // too fast for the joints: t cannot be kept, and a and v are capped at what they allow
    // (as movej does with a t beyond the limits)
    ml.tr = trap_plan(D, std::fmin(cmd.v, v_lim), std::fmin(cmd.a, a_lim), 0.0);
  }
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
  double pose[6];
  line_pose(ml, u, pose);
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
