// SPDX-License-Identifier: Apache-2.0
// core/motion_force.cpp — force mode, a first-order admittance in the task frame. With the F/T
// reading w_ext (the wrench the environment applies at the TCP, d->wrench_ext: an ideal sensor)
// and the commanded wrench w_cmd (what the robot shall apply to the environment), each
// compliant axis i moves at
//   v_i = sat_{±limit_i}( k_i (w_cmd,i + w_ext,i) ),   k = 0.005 (m/s)/N, 0.05 (rad/s)/(N m),
// which is at rest exactly when the environment pushes back with −w_cmd. Non-compliant axes
// move with the speedl running inside force mode (else hold). The twist ramps at 2.5 m/s²,
// 5 rad/s². A non-compliant axis deviating from the set-point by more than its limit (> 0) is
// a protective stop. FORCE_MODE (c->force, not a motion command) starts it. Context: RT.
#include <Eigen/Geometry>

#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kForceGain = 0.005;    // admittance, translation [(m/s)/N]
constexpr double kForceGainRot = 0.05;  // and rotation [(rad/s)/(N m)]

// force mode's task frame (UR types): 1 — y from the TCP toward the frame's origin; 2 — the
// frame as given; 3 — x along the TCP velocity projected on the frame's x-y plane
Mat3 force_task_frame(const urt_ctrl_cmd_t& f, const Vec3& p_tcp, const Vec3& v_tcp) noexcept {
  const Mat3 Rf = rotation_from_rotvec(Vec3(f.pose[3], f.pose[4], f.pose[5]));
  const Vec3 pf(f.pose[0], f.pose[1], f.pose[2]);
  Mat3 Rt = Rf;
  if (f.index == 1) {
    Vec3 y = pf - p_tcp;
    Vec3 z = Rf.col(2) - Rf.col(2).dot(y.normalized()) * y.normalized();
    if (y.norm() > 1e-6 && z.norm() > 1e-6) {
      y.normalize();
      z.normalize();
      Rt.col(0) = y.cross(z);
      Rt.col(1) = y;
      Rt.col(2) = z;
    }
  } else if (f.index == 3) {
    const Vec3 z = Rf.col(2);
    Vec3 x = v_tcp - v_tcp.dot(z) * z;
    if (x.norm() > 1e-6) {
      x.normalize();
      Rt.col(0) = x;
      Rt.col(1) = z.cross(x);
      Rt.col(2) = z;
    }
  }
  return Rt;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t&, const MotionStart&) { force_begin(e); }

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  const urt_data_t* d = e.d;
  const double T = c->period;
  const urt_ctrl_cmd_t& f = c->force;
  urt_force_state_t& fp = c->motion_state.force;
  Mat3 R;
  Vec3 pos;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q0), R, pos, &J);
  const Vec6 x_now = J * vec6(c->qd0);
  const Mat3 Rt = force_task_frame(f, pos, x_now.head<3>());

  // the wrench and the speedl goal in the task frame
  const Mat3 Rt_T = Rt.transpose();
  Vec6 w_t, g_t;
  for (int h = 0; h < 2; h++) {
    const Vec3 w(d->wrench_ext[3 * h], d->wrench_ext[3 * h + 1], d->wrench_ext[3 * h + 2]);
    const Vec3 g(fp.xd_goal[3 * h], fp.xd_goal[3 * h + 1], fp.xd_goal[3 * h + 2]);
    const Vec3 wt = Rt_T * w, gt = Rt_T * g;
    for (int i = 0; i < 3; i++) {
      w_t[3 * h + i] = wt[i];
      g_t[3 * h + i] = gt[i];
    }
  }
  Vec6 v_t;
  for (int i = 0; i < 6; i++) {
    if (f.q[i] != 0.0) {
      const double k = i < 3 ? kForceGain : kForceGainRot;
      v_t[i] = std::fmax(-f.qd[i], std::fmin(f.qd[i], k * (f.tau[i] + w_t[i])));
    } else {
      v_t[i] = g_t[i];
    }
  }
  Vec3 v_des = Rt * v_t.head<3>(), w_des = Rt * v_t.tail<3>();
  ramp3(fp.xd, v_des.data(), kForceAcc * T);
  ramp3(fp.xd + 3, w_des.data(), kForceAccRot * T);
  twist_to_joints(m, c, vec6(fp.xd));

  // deviation limits of the non-compliant axes: the arm against its set-point
  Mat3 Ra, Rs;
  Vec3 pa, ps;
  Vec6 qa;
  for (int j = 0; j < URT_NJ; j++) {
    qa[j] = d->x[j][URT_X_Q];
  }
  tcp_kinematics(m->arm, c->tcp_offset, qa, Ra, pa, nullptr);
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), Rs, ps, nullptr);
  const Vec3 dev_p = Rt_T * Vec3(pa - ps);
  const Vec3 dev_r = Rt_T * Vec3(Rs * rotvec_from_rotation(Rs.transpose() * Ra));
  const double dev[6] = {dev_p[0], dev_p[1], dev_p[2], dev_r[0], dev_r[1], dev_r[2]};
  for (int i = 0; i < 6; i++) {
    if (f.q[i] == 0.0 && f.qd[i] > 0.0 && std::fabs(dev[i]) > f.qd[i]) {
      return URT_CTRL_FAULT_BAD_TARGET;
    }
  }
  return 0;
}

}  // namespace

void force_begin(const MotionEnv& e) noexcept {
  urt_ctrl_t* c = e.c;
  // a running speedl goes on inside force mode, any other motion is over
  Vec6 xd = setpoint_twist(e.m, c);
  Vec6 goal = Vec6::Zero();
  if (c->motion == URT_MOTION_SPEEDL) {
    goal = vec6(c->motion_state.speedl.xd_goal);
  }
  finish_motion(c);
  urt_force_state_t& fp = c->motion_state.force;
  put6(xd, fp.xd);
  put6(goal, fp.xd_goal);
  c->force_mode = 1;
  c->motion = URT_MOTION_FORCE;
  c->seg_time = 0.0;
}

void force_take_speed(const MotionEnv& e, const urt_ctrl_cmd_t& cmd) noexcept {
  urt_ctrl_t* c = e.c;
  c->fault = 0;
  mark_done(c, c->motion_id);
  c->motion_id = cmd.id;
  urt_force_state_t& fp = c->motion_state.force;
  for (int i = 0; i < 6; i++) {
    fp.xd_goal[i] = cmd.kind == URT_CTRL_SPEEDL ? cmd.pose[i] : 0.0;
  }
  mark_done(c, cmd.id);  // returns at once: the goal holds until replaced
}

const Motion kForceMotion = {URT_MOTION_FORCE, false, false,        false,  no_bad_argument,
                             no_bad_target,    start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
