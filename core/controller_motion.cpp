// SPDX-License-Identifier: Apache-2.0
// core/controller_motion.cpp — the controller's motion generators: what each motion does to the
// set-point once per controller period. Planned motions (movej, movel) follow a trapezoidal
// speed profile from rest to rest; online motions (stops, speedj, speedl, servoj/servol, servoc,
// force mode, freedrive) integrate from the set-point of the last period. The state machine
// (controller.cpp) starts them and ticks them; each keeps what it needs in c->plan (Plan,
// controller_internal.hpp). Fixed-size Eigen on the stack, no allocation, no exceptions.
// Context: RT.
#include <cmath>
#include <cstring>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "controller_internal.hpp"
#include "urt/controller.h"
#include "urt/core.h"

namespace urt::core {

namespace {

constexpr double kSpeedMargin = 0.98;   // planned speeds up to this fraction of qd_max
constexpr double kAccMargin = 0.9;      // planned accelerations up to this fraction of qdd_max
constexpr double kServoH = 2.5e-4;      // largest servo-filter integration step [s]
constexpr double kForceGain = 0.005;    // force-mode admittance, translation [(m/s)/N]
constexpr double kForceGainRot = 0.05;  // and rotation [(rad/s)/(N m)]
constexpr double kHoldK = 1e4;          // freedrive's spring on held axes, translation [N/m]
constexpr double kHoldD = 300.0;        // and damper [N s/m]
constexpr double kHoldKRot = 1000.0;    // rotation [N m/rad]
constexpr double kHoldDRot = 20.0;      // [N m s/rad]

// ---- trapezoid ----

Trap trap_plan(double D, double v, double a, double t) noexcept {
  Trap tr{D, 0.0, 0.0, 0.0, 0.0};
  if (D <= 0.0) {
    return tr;
  }
  if (t > 0.0) {
    // fit the duration: keep a if it can make it in t, else the triangle that takes exactly t
    double disc = a * a * t * t - 4.0 * a * D;
    if (disc >= 0.0) {
      v = 0.5 * (a * t - std::sqrt(disc));
    } else {
      a = 4.0 * D / (t * t);
      v = 2.0 * D / t;
    }
  }
  if (D * a <= v * v) {  // triangle
    tr.ta = std::sqrt(D / a);
    tr.vp = a * tr.ta;
    tr.T = 2.0 * tr.ta;
  } else {
    tr.ta = v / a;
    tr.vp = v;
    tr.T = D / v + v / a;
  }
  tr.ap = tr.vp / tr.ta;
  return tr;
}

// distance, speed and acceleration along the trapezoid at time t
void trap_eval(const Trap& tr, double t, double& s, double& sd, double& sdd) noexcept {
  if (tr.D <= 0.0 || t >= tr.T) {
    s = tr.D;
    sd = sdd = 0.0;
  } else if (t <= 0.0) {
    s = sd = sdd = 0.0;
  } else if (t < tr.ta) {
    s = 0.5 * tr.ap * t * t;
    sd = tr.ap * t;
    sdd = tr.ap;
  } else if (t <= tr.T - tr.ta) {
    s = 0.5 * tr.ap * tr.ta * tr.ta + tr.vp * (t - tr.ta);
    sd = tr.vp;
    sdd = 0.0;
  } else {
    double r = tr.T - t;
    s = tr.D - 0.5 * tr.ap * r * r;
    sd = tr.ap * r;
    sdd = -tr.ap;
  }
}

// ---- twists ----

// ramp a vector toward a goal by at most step (along the difference)
void ramp3(double* x, const double* goal, double step) noexcept {
  Vec3 d(goal[0] - x[0], goal[1] - x[1], goal[2] - x[2]);
  double n = d.norm();
  double k = n <= step ? 1.0 : step / n;
  for (int i = 0; i < 3; i++) {
    x[i] += k * d[i];
  }
}

// damping of the inverse Jacobian near singularities (manipulability |det J|)
double dls_lambda(const Mat6& J) noexcept {
  constexpr double w0 = 1e-3, lambda0 = 0.05;
  double w = std::fabs(J.determinant());
  return w >= w0 ? 0.0 : lambda0 * std::sqrt(1.0 - (w / w0) * (w / w0));
}

// integrate a tool twist into the set-point through the damped inverse Jacobian at q0
void twist_to_joints(const urt_model_t* m, urt_ctrl_t* c, const Vec6& xd) noexcept {
  const double T = c->period;
  Mat3 R;
  Vec3 pos;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q0), R, pos, &J);
  Vec6 qd = dls_solve(J, xd, dls_lambda(J));
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j];
    c->qd1[j] = qd[j];
    c->q1[j] = c->q0[j] + 0.5 * (v0 + qd[j]) * T;
    c->qdd1[j] = (qd[j] - v0) / T;
  }
}

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

}  // namespace

// ---- starting a motion ----

// start servoing to the joint target q (servoj, and servol on its IK); a command without a
// time lasts one period
void start_servoj(urt_ctrl_t* c, Plan& p, const double* q, urt_ctrl_motion_t motion) noexcept {
  std::memcpy(p.servoj.target, q, sizeof p.servoj.target);
  p.servoj.since = 0.0;
  if (!(c->active.t > 0.0)) {
    c->active.t = c->period;
  }
  c->motion = motion;
}

// start decelerating every joint to rest, all together, the leading one at a
void start_stop(urt_ctrl_t* c, Plan& p, double t_stop) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    p.stop.a[j] = t_stop > 0.0 ? std::fabs(c->qd1[j]) / t_stop : 0.0;
  }
  c->motion = URT_MOTION_STOP;
  c->seg_time = 0.0;
}

// ---- planned motions ----

bool start_movej(const urt_model_t* m, urt_ctrl_t* c, Plan& p,
                 const urt_ctrl_cmd_t* cmd) noexcept {
  MovejPlan& mj = p.movej;
  double D = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    mj.q_start[j] = c->q1[j];
    mj.dq[j] = cmd->q[j] - c->q1[j];
    D = std::fmax(D, std::fabs(mj.dq[j]));
  }
  double v = cmd->v, a = cmd->a;
  for (int j = 0; j < URT_NJ && D > 0.0; j++) {
    double f = std::fabs(mj.dq[j]) / D;  // this joint's share of the leading axis' motion
    if (f > 0.0) {
      v = std::fmin(v, kSpeedMargin * m->joint[j].qd_max / f);
      a = std::fmin(a, kAccMargin * m->joint[j].qdd_max / f);
    }
  }
  if (cmd->t > 0.0) {
    // t overrides a and v, but never beyond the joints' limits
    Trap fit = trap_plan(D, v, a, cmd->t);
    if (fit.vp <= v * 1.0000001 && fit.ap <= a * 1.0000001) {
      mj.tr = fit;
    } else {
      mj.tr = trap_plan(D, v, a, 0.0);
    }
  } else {
    mj.tr = trap_plan(D, v, a, 0.0);
  }
  c->motion = URT_MOTION_MOVEJ;
  c->traj_time = 0.0;
  c->seg_time = 0.0;
  return true;
}

bool start_movel(const urt_model_t* m, urt_ctrl_t* c, Plan& p,
                 const urt_ctrl_cmd_t* cmd) noexcept {
  MovelPlan& ml = p.movel;
  Mat3 R0;
  Vec3 p0;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R0, p0, nullptr);
  Vec3 p1(cmd->pose[0], cmd->pose[1], cmd->pose[2]);
  Mat3 R1 = rotation_from_rotvec(Vec3(cmd->pose[3], cmd->pose[4], cmd->pose[5]));
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
  ml.tr = trap_plan(D, cmd->v, cmd->a, cmd->t);
  c->motion = URT_MOTION_MOVEL;
  c->traj_time = 0.0;
  c->seg_time = 0.0;
  return true;
}

void tick_movej(urt_ctrl_t* c, Plan& p, double scale, double dscale) noexcept {
  const MovejPlan& mj = p.movej;
  double s, sd, sdd;
  trap_eval(mj.tr, c->traj_time, s, sd, sdd);
  double D = mj.tr.D;
  for (int j = 0; j < URT_NJ; j++) {
    double f = D > 0.0 ? mj.dq[j] / D : 0.0;
    c->q1[j] = mj.q_start[j] + f * s;
    c->qd1[j] = f * sd * scale;
    c->qdd1[j] = f * (sdd * scale * scale + sd * dscale);
  }
  if (c->traj_time >= mj.tr.T) {
    for (int j = 0; j < URT_NJ; j++) {
      c->q1[j] = mj.q_start[j] + mj.dq[j];
      c->qd1[j] = c->qdd1[j] = 0.0;
    }
    finish_motion(c);
  }
}

// returns false when the line left the workspace (no IK)
bool tick_movel(const urt_model_t* m, urt_ctrl_t* c, Plan& p, double scale) noexcept {
  const MovelPlan& ml = p.movel;
  double s, sd, sdd;
  bool end = c->traj_time >= ml.tr.T;
  trap_eval(ml.tr, c->traj_time, s, sd, sdd);
  double u = ml.tr.D > 0.0 ? s / ml.tr.D : 1.0, ud = ml.tr.D > 0.0 ? sd * scale / ml.tr.D : 0.0;
  Vec3 axis(ml.axis[0], ml.axis[1], ml.axis[2]);
  Mat3 R0 = rotation_from_rotvec(Vec3(ml.r_start[0], ml.r_start[1], ml.r_start[2]));
  Mat3 R = R0 * rotation_from_rotvec(axis * (ml.theta * u));
  Vec3 pos(ml.p_start[0] + ml.dp[0] * u, ml.p_start[1] + ml.dp[1] * u,
           ml.p_start[2] + ml.dp[2] * u);
  Vec3 r = rotvec_from_rotation(R);
  double pose[6] = {pos[0], pos[1], pos[2], r[0], r[1], r[2]};
  double q[URT_NJ];
  if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, pose, c->q1, q) != URT_OK) {
    return false;
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
  return true;
}

// ---- online motions ----

void tick_stop(urt_ctrl_t* c, const Plan& p) noexcept {
  const double T = c->period;
  bool rest = true;
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j], dv = p.stop.a[j] * T;
    double v1 = std::fabs(v0) <= dv ? 0.0 : v0 - std::copysign(dv, v0);
    c->qd1[j] = v1;
    c->q1[j] = c->q0[j] + 0.5 * (v0 + v1) * T;
    c->qdd1[j] = (v1 - v0) / T;
    rest = rest && v1 == 0.0;
  }
  if (rest) {
    std::memset(c->qdd1, 0, sizeof c->qdd1);
  }
}

void tick_speedj(urt_ctrl_t* c, const Plan& p) noexcept {
  const double T = c->period;
  bool reached = true;
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j], g = p.speedj.qd_goal[j], dv = p.speedj.a[j] * T;
    double v1 = std::fabs(g - v0) <= dv ? g : v0 + std::copysign(dv, g - v0);
    c->qd1[j] = v1;
    c->q1[j] = c->q0[j] + 0.5 * (v0 + v1) * T;
    c->qdd1[j] = (v1 - v0) / T;
    reached = reached && v1 == g;
  }
  if (reached && c->active.t <= 0.0) {
    mark_done(c, c->motion_id);  // speedj without t returns once the speed is reached
  }
}

void tick_speedl(const urt_model_t* m, urt_ctrl_t* c, Plan& p) noexcept {
  const double T = c->period;
  SpeedlPlan& sl = p.speedl;
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
}

// q̈_s = gain (q_target − q_s − lookahead q̇_s) on the set-point: a ramp is followed with a lag
// of exactly lookahead; speeds and accelerations clamped to the joint limits
void tick_servoj(const urt_model_t* m, urt_ctrl_t* c, Plan& p) noexcept {
  const double T = c->period, gain = c->active.gain, la = c->active.lookahead_time;
  int n = (int)std::ceil(T / kServoH - 1e-9);
  double h = T / n;
  for (int j = 0; j < URT_NJ; j++) {
    double q = c->q0[j], v = c->qd0[j], a = 0.0;
    double vmax = kSpeedMargin * m->joint[j].qd_max, amax = kAccMargin * m->joint[j].qdd_max;
    for (int k = 0; k < n; k++) {
      a = gain * (p.servoj.target[j] - q - la * v);
      a = std::fmax(-amax, std::fmin(amax, a));
      double v1 = std::fmax(-vmax, std::fmin(vmax, v + a * h));
      q += 0.5 * (v + v1) * h;
      v = v1;
    }
    c->q1[j] = q;
    c->qd1[j] = v;
    c->qdd1[j] = (v - c->qd0[j]) / T;
  }
  p.servoj.since += T;
  if (p.servoj.since >= c->active.t) {
    mark_done(c, c->motion_id);  // the call has controlled the robot for its t
  }
}

// servoc: the tool twist ramps (at a) toward the straight line to the goal at the speed that
// can still stop there, min(v, √(2 a d), d/T); the orientation turns in proportion so that both
// arrive together (at most 1 rad/s, 4 rad/s², alone once the position is there). Blending
// (r) is not done: each new goal is approached from the current set-point and twist. Returns
// true when the goal is reached (the set-point then sits on it at rest).
bool tick_servoc(const urt_model_t* m, urt_ctrl_t* c, Plan& p) noexcept {
  constexpr double kRotV = 1.0, kRotA = 4.0;
  const double T = c->period, a = c->active.a, v = c->active.v;
  ServocPlan& sc = p.servoc;
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

// force mode, a first-order admittance in the task frame. With the F/T reading w_ext (the wrench
// the environment applies at the TCP, d->wrench_ext: an ideal sensor) and the commanded wrench
// w_cmd (what the robot shall apply to the environment), each compliant axis i moves at
//   v_i = sat_{±limit_i}( k_i (w_cmd,i + w_ext,i) ),   k = 0.005 (m/s)/N, 0.05 (rad/s)/(N m),
// which is at rest exactly when the environment pushes back with −w_cmd. Non-compliant axes
// move with the speedl running inside force mode (else hold). The twist ramps at 2.5 m/s²,
// 5 rad/s². Returns false when a non-compliant axis deviates from the set-point by more than
// its limit (> 0).
bool tick_force(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d, Plan& p) noexcept {
  const double T = c->period;
  const urt_ctrl_cmd_t& f = c->force;
  ForcePlan& fp = p.force;
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
      return false;
    }
  }
  return true;
}

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

// freedrive: every drive in torque mode carrying the controller's gravity model, so that only
// friction and the drives' inertia resist a push. Held axes of the feature frame (free[i] = 0)
// get a Cartesian spring-damper toward the pose freedrive began at, τ += Jᵀ w with
// w = K e − D v per held axis (10 kN/m, 300 N s/m; 1000 N m/rad, 20 N m s/rad): a push on a
// held axis deflects it by about |F|/K plus what friction holds.
void tick_freedrive(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d, Plan& p) noexcept {
  const FreedrivePlan& fd = p.freedrive;
  const Vec6 q = actual_q(d);
  follow_actual(m, c, d, kAllJoints);
  Vec6 tau;
  ctrl_rnea(m, c, q, Vec6::Zero(), Vec6::Zero(), tau);

  bool held = false;
  for (int i = 0; i < 6; i++) {
    held = held || fd.free[i] == 0.0;
  }
  if (held) {
    Mat3 R;
    Vec3 pos;
    Mat6 J;
    tcp_kinematics(m->arm, c->tcp_offset, q, R, pos, &J);
    Vec6 qd;
    for (int j = 0; j < URT_NJ; j++) {
      qd[j] = d->x[j][URT_X_QD];
    }
    const Vec6 x = J * qd;
    const Mat3 Rf = rotation_from_rotvec(Vec3(fd.feature[3], fd.feature[4], fd.feature[5]));
    const Mat3 Rf_T = Rf.transpose();
    const Mat3 R_hold = rotation_from_rotvec(Vec3(fd.r_hold[0], fd.r_hold[1], fd.r_hold[2]));
    const Vec3 e_p = Rf_T * Vec3(Vec3(fd.p_hold[0], fd.p_hold[1], fd.p_hold[2]) - pos);
    const Vec3 e_r = Rf_T * Vec3(R * rotvec_from_rotation(R.transpose() * R_hold));
    const Vec3 v_f = Rf_T * Vec3(x.head<3>()), w_f = Rf_T * Vec3(x.tail<3>());
    Vec3 f_f, m_f;
    for (int i = 0; i < 3; i++) {
      f_f[i] = fd.free[i] == 0.0 ? kHoldK * e_p[i] - kHoldD * v_f[i] : 0.0;
      m_f[i] = fd.free[3 + i] == 0.0 ? kHoldKRot * e_r[i] - kHoldDRot * w_f[i] : 0.0;
    }
    Vec6 w;
    w.head<3>() = Rf * f_f;
    w.tail<3>() = Rf * m_f;
    tau += J.transpose() * w;
  }
  for (int j = 0; j < URT_NJ; j++) {
    c->tau_ff[j] = clamp_torque(m, j, tau[j]);
  }
  c->torque_mask = kAllJoints;
}

}  // namespace urt::core
