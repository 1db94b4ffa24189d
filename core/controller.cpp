// SPDX-License-Identifier: Apache-2.0
// core/controller.cpp — the UR controller's motion layer (urt/controller.h): robot and safety
// state machine, motion generators (movej, movel, servoj, speedj, speedl, stopj, stopl, direct),
// the set-point interpolation the physics steps follow, model feed-forward, inverse kinematics
// and the motor thermal model. Everything runs on the physics thread: fixed-size Eigen on the
// stack, no allocation, no exceptions. Context: RT unless stated.
//
// Choices (the contract leaves them to this file):
// - Blending (r > 0) is not implemented: movej/movel stop at every target, as with r = 0.
// - A movej/movel arriving while the set-point moves first brings the arm to rest at the new
//   command's deceleration, then starts (c->pending); the previous motion's id is marked done.
// - When not RUNNING, or in a protective stop, the set-point holds where the arm is (the brakes
//   hold a real arm; here the drives, which stay engaged in the physics, do).
// - Feed-forward: every set-point carries τ_ff = RNEA(q, q̇, q̈) + friction(q̇) − τ_bias, with
//   τ_bias = g(q_init): urt_data_init starts the speed-loop integrators carrying g(q_init), so
//   the feed-forward adds only the change from there. The speed loop's integral time is ~10 s
//   (P_vel/I_vel), far too slow to take up gravity changes within a move.
// - The speed slider scales a planned motion's time (movej, movel): its path time advances at
//   speed_scaling per second, and speed_scaling follows the slider at most 2 /s. servoj, speedj,
//   speedl and stops are not scaled.
// - HALT decelerates like stopj(4 rad/s²); it does not change program_state (the runner does).
// - The payload is stored (snapshot), not added to the dynamics: the physics (urt_step) has no
//   payload either, so a feed-forward with it would only create a model mismatch.
#include <cmath>
#include <cstring>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "controller_internal.hpp"
#include "step_internal.h"
#include "urt/controller.h"
#include "urt/core.h"
#include "urt/drivers/friction.h"

namespace urt::core {

namespace {

constexpr double kSpeedMargin = 0.98;   // planned speeds up to this fraction of qd_max
constexpr double kAccMargin = 0.9;      // planned accelerations up to this fraction of qdd_max
constexpr double kHaltDecel = 4.0;      // HALT and servo time-out deceleration [rad/s²]
constexpr double kSliderRate = 2.0;     // speed_scaling slew rate [1/s]
constexpr double kServoH = 2.5e-4;      // largest servo-filter integration step [s]
constexpr double kFrictionVEps = 2e-3;  // speed over which the friction feed-forward turns on [rad/s]

// ---- plans, stored in c->plan (copied in and out once per tick) ----

// Trapezoidal speed profile over a distance D: accelerate at ap for ta, cruise at vp, brake.
struct Trap {
  double D, T, ta, vp, ap;
};

struct MovejPlan {
  Trap tr;
  double q_start[URT_NJ], dq[URT_NJ];
};

struct MovelPlan {
  Trap tr;
  double p_start[3], dp[3];      // line: p = p_start + dp · s/D
  double r_start[3];             // start orientation (rotation vector)
  double axis[3], theta;         // R(s) = R_start · Rot(axis, θ s/D), axis in the start frame
};

struct StopPlan {
  double a[URT_NJ];              // per-joint deceleration, all joints reach 0 together
};

struct SpeedjPlan {
  double qd_goal[URT_NJ], a[URT_NJ];
};

struct SpeedlPlan {
  double xd_goal[6], xd[6];      // goal and current tool twist (v; ω), base frame
};

struct ServojPlan {
  double target[URT_NJ];
  double since;                  // time since the last servoj [s]
};

union Plan {
  MovejPlan movej;
  MovelPlan movel;
  StopPlan stop;
  SpeedjPlan speedj;
  SpeedlPlan speedl;
  ServojPlan servoj;
  double raw[64];
};
static_assert(sizeof(Plan) == sizeof(((urt_ctrl_t*)nullptr)->plan), "plan fits c->plan");

Plan load_plan(const urt_ctrl_t* c) noexcept {
  Plan p;
  std::memcpy(&p, c->plan, sizeof p);
  return p;
}

void store_plan(urt_ctrl_t* c, const Plan& p) noexcept { std::memcpy(c->plan, &p, sizeof p); }

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

// ---- small helpers ----

Vec6 vec6(const double* x) noexcept { return Eigen::Map<const Vec6>(x); }
void put6(const Vec6& v, double* x) noexcept { Eigen::Map<Vec6>{x} = v; }

Vec6 actual_q(const urt_data_t* d) noexcept {
  Vec6 q;
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = d->x[j][URT_X_Q];
  }
  return q;
}

bool all_finite(const double* x, int n) noexcept {
  for (int i = 0; i < n; i++) {
    if (!std::isfinite(x[i])) {
      return false;
    }
  }
  return true;
}

// URT_PSTOP_* bit a joint target deserves (0: fine)
uint32_t target_faults(const urt_model_t* m, const double* q) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(q[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    if (q[j] < m->joint[j].q_min || q[j] > m->joint[j].q_max) {
      return URT_PSTOP_POS_LIMIT;
    }
  }
  return 0;
}

uint32_t speed_faults(const urt_model_t* m, const double* qd) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(qd[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
    if (std::fabs(qd[j]) > m->joint[j].qd_max) {
      return URT_PSTOP_SPEED_LIMIT;
    }
  }
  return 0;
}

bool is_motion(int kind) noexcept {
  return kind >= URT_CTRL_MOVEJ && kind <= URT_CTRL_DIRECT;
}

bool running(const urt_ctrl_t* c) noexcept {
  return c->robot_mode == URT_ROBOT_MODE_RUNNING && c->safety_mode == URT_SAFETY_MODE_NORMAL;
}

void mark_done(urt_ctrl_t* c, uint64_t id) noexcept {
  if (id > c->motion_done_id) {
    c->motion_done_id = id;
  }
}

// end the current motion (finished or aborted): its id is done
void finish_motion(urt_ctrl_t* c) noexcept {
  mark_done(c, c->motion_id);
  if (c->has_pending) {
    mark_done(c, c->pending.id);
    c->has_pending = 0;
  }
  c->motion = URT_MOTION_IDLE;
  std::memset(c->tau_ff, 0, sizeof c->tau_ff);
}

// hold the set-point at q, at rest (both ends of the current period)
void hold_at(urt_ctrl_t* c, const Vec6& q) noexcept {
  put6(q, c->q0);
  put6(q, c->q1);
  std::memset(c->qd0, 0, sizeof c->qd0);
  std::memset(c->qd1, 0, sizeof c->qd1);
  std::memset(c->qdd0, 0, sizeof c->qdd0);
  std::memset(c->qdd1, 0, sizeof c->qdd1);
}

// the model feed-forward at a set-point
void model_torque(const urt_model_t* m, const urt_ctrl_t* c, const double* q, const double* qd,
                  const double* qdd, double* tau) noexcept {
  Vec6 t;
  rnea(m->arm, vec6(q), vec6(qd), vec6(qdd), t);
  for (int j = 0; j < URT_NJ; j++) {
    double f = 0.0;
    if (m->friction[j].enabled) {
      // steady-state LuGre (σ0 z = g(q̇) sign q̇), faded in over a small speed
      f = urt_friction_g(&m->friction[j], qd[j]) * std::tanh(qd[j] / kFrictionVEps);
    }
    tau[j] = t[j] + f - c->tau_bias[j];
  }
}

void protective_stop(urt_ctrl_t* c, urt_data_t* d, uint32_t fault, uint32_t pstop_bits) noexcept {
  c->fault |= fault;
  c->safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  finish_motion(c);
  if (pstop_bits) {
    d->pstop |= pstop_bits;
    urt__command_hold(d);
  }
  hold_at(c, vec6(d->cmd.q));
  std::memset(c->tau_model0, 0, sizeof c->tau_model0);
  std::memset(c->tau_model1, 0, sizeof c->tau_model1);
}

void refuse(urt_ctrl_t* c, const urt_ctrl_cmd_t* cmd, uint32_t fault) noexcept {
  c->fault |= fault;
  mark_done(c, cmd->id);
}

double tcp_twist_decel_time(const urt_model_t* m, const urt_ctrl_t* c, double a,
                            double a_rot) noexcept {
  Mat3 R;
  Vec3 p;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R, p, &J);
  Vec6 x = J * vec6(c->qd1);
  return std::fmax(x.head<3>().norm() / a, x.tail<3>().norm() / a_rot);
}

// start decelerating every joint to rest, all together, the leading one at a
void start_stop(urt_ctrl_t* c, Plan& p, double t_stop) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    p.stop.a[j] = t_stop > 0.0 ? std::fabs(c->qd1[j]) / t_stop : 0.0;
  }
  c->motion = URT_MOTION_STOP;
  c->seg_time = 0.0;
}

double joint_stop_time(const urt_ctrl_t* c, double a) noexcept {
  double vmax = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    vmax = std::fmax(vmax, std::fabs(c->qd1[j]));
  }
  return vmax / a;
}

bool moving(const urt_ctrl_t* c) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (c->qd1[j] != 0.0) {
      return true;
    }
  }
  return false;
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

// ---- thermal ----

void tick_thermal(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    const urt_thermal_params_t& th = m->thermal[j];
    if (th.c_th <= 0.0 || th.r_th <= 0.0) {
      c->temperature[j] = th.t_amb;
      continue;
    }
    double i = d->x[j][URT_X_I];
    double p_loss = m->motor[j].r * i * i;
    // exact for constant loss over the period (stable at any rate)
    double t_ss = th.t_amb + p_loss * th.r_th;
    double k = std::exp(-c->period / (th.r_th * th.c_th));
    c->temperature[j] = t_ss + (c->temperature[j] - t_ss) * k;
  }
}

}  // namespace

// ---- kinematics shared with the snapshot ----

void tcp_kinematics(const urt_arm_params_t& a, const double tcp[6], const Vec6& q, Mat3& R_BT,
                    Vec3& p_BT, Mat6* J) noexcept {
  ArmKinematics k;
  arm_kinematics(a, q, k);
  Vec3 z[URT_NJ], o[URT_NJ];
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
  for (int j = 0; j < URT_NJ; ++j) {
    z[j] = R.col(2);
    o[j] = p;
    p += R * k.p_PC[j];
    R = R * k.R_PC[j];
  }
  const Vec3 p_FT(tcp[0], tcp[1], tcp[2]);
  R_BT = R * rotation_from_rotvec(Vec3(tcp[3], tcp[4], tcp[5]));
  p_BT = p + R * p_FT;
  if (J) {
    for (int j = 0; j < URT_NJ; ++j) {
      J->block<3, 1>(0, j) = z[j].cross(p_BT - o[j]);
      J->block<3, 1>(3, j) = z[j];
    }
  }
}

Vec6 dls_solve(const Mat6& J, const Vec6& b, double lambda) noexcept {
  if (lambda <= 0.0) {
    return Eigen::PartialPivLU<Mat6>(J).solve(b);
  }
  Mat6 A = J * J.transpose();
  A.diagonal().array() += lambda * lambda;
  return J.transpose() * Eigen::PartialPivLU<Mat6>(A).solve(b);
}

namespace {

// Newton on the calibrated model from a seed; true when converged within tol
bool ik_newton(const urt_arm_params_t& a, const double tcp[6], const Mat3& R_goal,
               const Vec3& p_goal, Vec6& q, int max_iter) noexcept {
  constexpr double kTol = 1e-10;
  double prev = HUGE_VAL;
  for (int it = 0; it < max_iter; it++) {
    Mat3 R;
    Vec3 p;
    Mat6 J;
    tcp_kinematics(a, tcp, q, R, p, &J);
    Vec6 e;
    e.head<3>() = p_goal - p;
    e.tail<3>() = R * rotvec_from_rotation(R.transpose() * R_goal);
    double err = e.norm();
    if (!std::isfinite(err)) {
      return false;
    }
    // converged: stop when the error no longer shrinks (machine precision) below tol
    if (err < 1e-14 || (err < kTol && err > 0.5 * prev)) {
      return true;
    }
    prev = err;
    // Levenberg–Marquardt-like damping that vanishes with the error: quadratic convergence
    // near the solution, bounded steps near singular configurations
    Vec6 dq = dls_solve(J, e, std::fmin(0.05, 0.1 * err));
    double n = dq.cwiseAbs().maxCoeff();
    if (n > 0.3) {
      dq *= 0.3 / n;
    }
    q += dq;
  }
  // a last look
  Mat3 R;
  Vec3 p;
  tcp_kinematics(a, tcp, q, R, p, nullptr);
  return (p_goal - p).norm() < kTol && rotvec_from_rotation(R.transpose() * R_goal).norm() < kTol;
}

// bring each joint by whole turns as close to qnear as the limits allow
void wrap_near(const urt_model_t* m, const double* qnear, Vec6& q) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    double k = std::round((qnear[j] - q[j]) / (2.0 * M_PI));
    double c = q[j] + k * 2.0 * M_PI;
    if (c >= m->joint[j].q_min && c <= m->joint[j].q_max) {
      q[j] = c;
    }
  }
}

// Closed-form IK of the nominal UR chain (standard DH: Rot(z, q) Transl(z, d) Transl(x, a)
// Rot(x, α), α = π/2, 0, 0, π/2, −π/2, 0, with the calibrated chain's a2, a3, d1, d4, d5, d6):
// up to 8 seeds for the flange pose that puts the TCP at the goal. Returns how many.
using Mat4 = Eigen::Matrix4d;

Mat4 dh(double theta, double d, double a, double alpha) noexcept {
  const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(alpha),
               sa = std::sin(alpha);
  Mat4 A;
  A << ct, -st * ca, st * sa, a * ct, st, ct * ca, -ct * sa, a * st, 0.0, sa, ca, d, 0.0, 0.0, 0.0,
      1.0;
  return A;
}

Mat4 rigid_inverse(const Mat4& T) noexcept {
  Mat4 I = Mat4::Identity();
  I.block<3, 3>(0, 0) = T.block<3, 3>(0, 0).transpose();
  I.block<3, 1>(0, 3) = -I.block<3, 3>(0, 0) * T.block<3, 1>(0, 3);
  return I;
}

int nominal_ik_seeds(const urt_arm_params_t& arm, const double tcp[6], const Mat3& R_goal,
                     const Vec3& p_goal, Vec6* out) noexcept {
  const double d1 = arm.link[0].d, a2 = arm.link[1].a, a3 = arm.link[2].a, d4 = arm.link[3].d,
               d5 = arm.link[4].d, d6 = arm.link[5].d;
  const double h = M_PI / 2;
  // flange pose: goal · tcp⁻¹
  Mat3 R_FT = rotation_from_rotvec(Vec3(tcp[3], tcp[4], tcp[5]));
  Mat3 R = R_goal * R_FT.transpose();
  Vec3 p = p_goal - R * Vec3(tcp[0], tcp[1], tcp[2]);
  Mat4 T06 = Mat4::Identity();
  T06.block<3, 3>(0, 0) = R;
  T06.block<3, 1>(0, 3) = p;

  // base: the wrist centre (frame 5 origin) lies d4 off the plane of the arm
  const Vec3 p5 = p - d6 * R.col(2);
  const double r5 = std::hypot(p5.x(), p5.y());
  if (r5 < std::fabs(d4)) {
    return 0;
  }
  const double psi = std::atan2(p5.y(), p5.x()), phi = std::acos(d4 / r5);
  int n = 0;
  for (int s1 = -1; s1 <= 1; s1 += 2) {
    const double q1 = psi + s1 * phi + h;
    const double c1 = std::cos(q1), s1n = std::sin(q1);
    // wrist 2 from the flange position across the arm plane
    double c5 = (p.x() * s1n - p.y() * c1 - d4) / d6;
    if (std::fabs(c5) > 1.0 + 1e-9) {
      continue;
    }
    c5 = std::fmax(-1.0, std::fmin(1.0, c5));
    for (int s5 = -1; s5 <= 1; s5 += 2) {
      const double q5 = s5 * std::acos(c5), sin5 = std::sin(q5);
      // wrist 3 from the base axes seen from the flange (arbitrary at sin q5 = 0)
      double q6 = 0.0;
      if (std::fabs(sin5) > 1e-9) {
        q6 = std::atan2((-R(0, 1) * s1n + R(1, 1) * c1) / sin5, (R(0, 0) * s1n - R(1, 0) * c1) / sin5);
      }
      // the planar shoulder–elbow–wrist-1 chain
      const Mat4 T01 = dh(q1, d1, 0.0, h), T45 = dh(q5, d5, 0.0, -h), T56 = dh(q6, d6, 0.0, 0.0);
      const Mat4 T14 = rigid_inverse(T01) * T06 * rigid_inverse(T45 * T56);
      const Vec3 p13 = (T14 * Eigen::Vector4d(0.0, -d4, 0.0, 1.0)).head<3>();
      const double L = p13.norm();
      double c3 = (L * L - a2 * a2 - a3 * a3) / (2.0 * a2 * a3);
      if (std::fabs(c3) > 1.0 + 1e-9) {
        continue;
      }
      c3 = std::fmax(-1.0, std::fmin(1.0, c3));
      for (int s3 = -1; s3 <= 1; s3 += 2) {
        const double q3 = s3 * std::acos(c3);
        const double q2 = -std::atan2(p13.y(), -p13.x()) + std::asin(a3 * std::sin(q3) / L);
        const Mat4 T13 = dh(q2, 0.0, a2, 0.0) * dh(q3, 0.0, a3, 0.0);
        const Mat4 T34 = rigid_inverse(T13) * T14;
        const double q4 = std::atan2(T34(1, 0), T34(0, 0));
        Vec6 sol;
        sol << q1, q2, q3, q4, q5, q6;
        for (int j = 0; j < URT_NJ; j++) {
          sol[j] -= arm.link[j].theta;  // the calibrated joint offsets, to first order
          sol[j] = std::remainder(sol[j], 2.0 * M_PI);
        }
        out[n++] = sol;
      }
    }
  }
  return n;
}

}  // namespace
}  // namespace urt::core

using namespace urt::core;

extern "C" {

void urt_ctrl_forward_kinematics_tcp(const urt_model_t* m, const double tcp[6],
                                     const double q[URT_NJ], double pose[6]) {
  Mat3 R;
  Vec3 p;
  tcp_kinematics(m->arm, tcp, vec6(q), R, p, nullptr);
  Vec3 r = rotvec_from_rotation(R);
  for (int i = 0; i < 3; i++) {
    pose[i] = p[i];
    pose[3 + i] = r[i];
  }
}

// Newton from qnear: when qnear is the previous set-point (movel, every tick) the solution is
// within a few mrad and is taken at once. Otherwise every branch is tried: the closed-form UR
// solution of the nominal DH chain (α = ±π/2 or 0, β = θ = 0, a1 = a4 = a5 = 0) gives up to 8
// seeds, Newton moves each onto the calibrated chain, and the solution closest to qnear (after
// whole turns toward qnear within the limits) wins.
int urt_ctrl_inverse_kinematics_tcp(const urt_model_t* m, const double tcp[6],
                                    const double pose[6], const double qnear[URT_NJ],
                                    double q[URT_NJ]) {
  if (!all_finite(pose, 6) || !all_finite(qnear, URT_NJ) || !all_finite(tcp, 6)) {
    return URT_ERANGE;
  }
  const Mat3 R_goal = rotation_from_rotvec(Vec3(pose[3], pose[4], pose[5]));
  const Vec3 p_goal(pose[0], pose[1], pose[2]);
  const Vec6 qn = vec6(qnear);

  double best = HUGE_VAL;
  Vec6 best_q = Vec6::Zero();
  auto consider = [&](Vec6 cand, int iters) noexcept {
    if (!ik_newton(m->arm, tcp, R_goal, p_goal, cand, iters)) {
      return;
    }
    wrap_near(m, qnear, cand);
    if (target_faults(m, cand.data()) != 0) {
      return;
    }
    double dist = (cand - qn).squaredNorm();
    if (dist < best) {
      best = dist;
      best_q = cand;
    }
  };

  consider(qn, 40);
  if (best < 0.1 * 0.1) {  // closer than any other branch away from singular poses
    put6(best_q, q);
    return URT_OK;
  }
  Vec6 seeds[8];
  int n = nominal_ik_seeds(m->arm, tcp, R_goal, p_goal, seeds);
  for (int k = 0; k < n; k++) {
    consider(seeds[k], 60);
  }
  if (best == HUGE_VAL) {
    return URT_ERANGE;
  }
  put6(best_q, q);
  return URT_OK;
}

int urt_ctrl_inverse_kinematics(const urt_model_t* m, const double pose[6],
                                const double qnear[URT_NJ], double q[URT_NJ]) {
  return urt_ctrl_inverse_kinematics_tcp(m, m->arm.tcp, pose, qnear, q);
}

int urt_ctrl_init(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d, double period,
                  int powered) {
  if (!m || !c || !d || !(period > 0.0)) {
    return URT_EINVAL;
  }
  double n = period / m->dt;
  if (std::fabs(n - std::round(n)) > 1e-6 || std::round(n) < 1.0) {
    return URT_EINVAL;
  }
  std::memset(c, 0, sizeof *c);
  c->period = period;
  c->n_sub = (int)std::round(n);
  c->robot_mode = powered ? URT_ROBOT_MODE_RUNNING : URT_ROBOT_MODE_POWER_OFF;
  c->safety_mode = URT_SAFETY_MODE_NORMAL;
  c->program_state = URT_PROGRAM_STOPPED;
  c->speed_slider = 1.0;
  c->speed_scaling = 1.0;
  std::memcpy(c->tcp_offset, m->arm.tcp, sizeof c->tcp_offset);
  c->motion = URT_MOTION_IDLE;
  Vec6 q = actual_q(d);
  hold_at(c, q);
  Vec6 g;
  gravity(m->arm, q, g);
  put6(g, c->tau_bias);
  model_torque(m, c, c->q1, c->qd1, c->qdd1, c->tau_model1);
  std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);
  for (int j = 0; j < URT_NJ; j++) {
    c->temperature[j] = m->thermal[j].t_amb;
  }
  return URT_OK;
}

void urt_ctrl_apply(const urt_model_t* m, urt_ctrl_t* c, urt_data_t* d,
                    const urt_ctrl_cmd_t* cmd) {
  Plan p = load_plan(c);
  const int kind = cmd->kind;

  if (is_motion(kind)) {
    if (!running(c) || d->pstop) {
      refuse(c, cmd, URT_CTRL_FAULT_NOT_RUNNING);
      return;
    }
    // arguments first (refused, no stop), then targets (protective stop)
    bool bad_arg = false;
    uint32_t bad_target = 0;
    switch (kind) {
      case URT_CTRL_MOVEJ:
        bad_arg = !(cmd->a > 0.0) || !(cmd->v > 0.0) || !std::isfinite(cmd->a) ||
                  !std::isfinite(cmd->v) || !std::isfinite(cmd->t) || cmd->t < 0.0;
        bad_target = target_faults(m, cmd->q);
        break;
      case URT_CTRL_MOVEL:
        bad_arg = !(cmd->a > 0.0) || !(cmd->v > 0.0) || !std::isfinite(cmd->a) ||
                  !std::isfinite(cmd->v) || !std::isfinite(cmd->t) || cmd->t < 0.0;
        bad_target = all_finite(cmd->pose, 6) ? 0 : URT_PSTOP_NONFINITE_CMD;
        break;
      case URT_CTRL_SERVOJ:
        bad_arg = !(cmd->lookahead_time >= 0.03 && cmd->lookahead_time <= 0.2) ||
                  !(cmd->gain >= 100.0 && cmd->gain <= 2000.0) || !std::isfinite(cmd->t) ||
                  cmd->t < 0.0;
        bad_target = target_faults(m, cmd->q);
        break;
      case URT_CTRL_SPEEDJ:
        bad_arg = !(cmd->a > 0.0) || !std::isfinite(cmd->a) || !std::isfinite(cmd->t);
        bad_target = speed_faults(m, cmd->q);
        break;
      case URT_CTRL_SPEEDL:
        bad_arg = !(cmd->a > 0.0) || !std::isfinite(cmd->a) || !std::isfinite(cmd->a_rot) ||
                  !std::isfinite(cmd->t);
        bad_target = all_finite(cmd->pose, 6) ? 0 : URT_PSTOP_NONFINITE_CMD;
        break;
      case URT_CTRL_STOPJ:
      case URT_CTRL_STOPL:
        bad_arg = !(cmd->a > 0.0) || !std::isfinite(cmd->a) || !std::isfinite(cmd->a_rot);
        break;
      case URT_CTRL_DIRECT:
        bad_target = target_faults(m, cmd->q);
        if (!bad_target) {
          bad_target = speed_faults(m, cmd->qd);
        }
        for (int j = 0; j < URT_NJ && !bad_target; j++) {
          if (!std::isfinite(cmd->tau[j])) {
            bad_target = URT_PSTOP_NONFINITE_CMD;
          } else if (std::fabs(cmd->tau[j]) > m->joint[j].torque_max) {
            bad_target = URT_PSTOP_TORQUE_LIMIT;
          }
        }
        break;
      default:
        break;
    }
    if (bad_arg) {
      refuse(c, cmd, URT_CTRL_FAULT_BAD_ARGUMENT);
      return;
    }
    if (bad_target) {
      mark_done(c, cmd->id);
      protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, bad_target);
      return;
    }
    if (kind == URT_CTRL_MOVEL) {
      double qg[URT_NJ];
      if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, cmd->pose, c->q1, qg) != URT_OK) {
        refuse(c, cmd, URT_CTRL_FAULT_IK);
        return;
      }
    }

    // accepted: the previous motion is over (aborted or superseded)
    c->fault = 0;
    const bool was_servo = c->motion == URT_MOTION_SERVOJ;
    uint64_t prev_id = c->motion_id;
    if (c->has_pending) {
      mark_done(c, c->pending.id);
      c->has_pending = 0;
    }
    if (kind != URT_CTRL_SERVOJ || !was_servo || cmd->id != prev_id) {
      mark_done(c, prev_id);
    }
    std::memset(c->tau_ff, 0, sizeof c->tau_ff);
    c->active = *cmd;
    c->motion_id = cmd->id;
    c->seg_time = 0.0;

    switch (kind) {
      case URT_CTRL_MOVEJ:
      case URT_CTRL_MOVEL:
        if (moving(c)) {
          c->pending = *cmd;
          c->has_pending = 1;
          double t_stop = kind == URT_CTRL_MOVEJ
                              ? joint_stop_time(c, cmd->a)
                              : tcp_twist_decel_time(m, c, cmd->a, cmd->a);
          start_stop(c, p, t_stop);
        } else if (kind == URT_CTRL_MOVEJ) {
          start_movej(m, c, p, cmd);
        } else {
          start_movel(m, c, p, cmd);
        }
        break;
      case URT_CTRL_SERVOJ:
        std::memcpy(p.servoj.target, cmd->q, sizeof p.servoj.target);
        p.servoj.since = 0.0;
        if (!(c->active.t > 0.0)) {
          c->active.t = c->period;
        }
        c->motion = URT_MOTION_SERVOJ;
        break;
      case URT_CTRL_SPEEDJ: {
        double dmax = 0.0;
        for (int j = 0; j < URT_NJ; j++) {
          p.speedj.qd_goal[j] = cmd->q[j];
          dmax = std::fmax(dmax, std::fabs(cmd->q[j] - c->qd1[j]));
        }
        double tr = dmax / cmd->a;
        for (int j = 0; j < URT_NJ; j++) {
          p.speedj.a[j] = tr > 0.0 ? std::fabs(cmd->q[j] - c->qd1[j]) / tr : 0.0;
        }
        c->motion = URT_MOTION_SPEEDJ;
        break;
      }
      case URT_CTRL_SPEEDL: {
        Mat3 R;
        Vec3 pos;
        Mat6 J;
        tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R, pos, &J);
        put6(J * vec6(c->qd1), p.speedl.xd);
        std::memcpy(p.speedl.xd_goal, cmd->pose, sizeof p.speedl.xd_goal);
        c->motion = URT_MOTION_SPEEDL;
        break;
      }
      case URT_CTRL_STOPJ:
        start_stop(c, p, joint_stop_time(c, cmd->a));
        break;
      case URT_CTRL_STOPL:
        start_stop(c, p,
                   tcp_twist_decel_time(m, c, cmd->a, cmd->a_rot > 0.0 ? cmd->a_rot : cmd->a));
        break;
      case URT_CTRL_DIRECT:
        std::memcpy(c->tau_ff, cmd->tau, sizeof c->tau_ff);
        c->motion = URT_MOTION_DIRECT;
        break;
      default:
        break;
    }
    store_plan(c, p);
    return;
  }

  switch (kind) {
    case URT_CTRL_SET_DIGITAL_OUT:
      if (cmd->index < 0 || cmd->index > 17) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else if (cmd->value != 0.0) {
        c->digital_out |= 1u << cmd->index;
      } else {
        c->digital_out &= ~(1u << cmd->index);
      }
      break;
    case URT_CTRL_SET_ANALOG_OUT:
      if (cmd->index < 0 || cmd->index > 1 || !(cmd->value >= 0.0 && cmd->value <= 1.0)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->analog_out[cmd->index] = cmd->value;
      }
      break;
    case URT_CTRL_SET_SPEED_SLIDER:
      if (!(cmd->value >= 0.0 && cmd->value <= 1.0)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->speed_slider = cmd->value;
      }
      break;
    case URT_CTRL_SET_TCP:
      if (!all_finite(cmd->pose, 6)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(c->tcp_offset, cmd->pose, sizeof c->tcp_offset);
      }
      break;
    case URT_CTRL_SET_PAYLOAD:
      if (!(cmd->value >= 0.0) || !std::isfinite(cmd->value) || !all_finite(cmd->pose, 3)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->payload_mass = cmd->value;
        std::memcpy(c->payload_cog, cmd->pose, sizeof c->payload_cog);
      }
      break;
    case URT_CTRL_POWER_ON:
      if (c->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
        c->robot_mode = URT_ROBOT_MODE_IDLE;
      }
      break;
    case URT_CTRL_POWER_OFF:
      finish_motion(c);
      c->robot_mode = URT_ROBOT_MODE_POWER_OFF;
      hold_at(c, actual_q(d));
      break;
    case URT_CTRL_BRAKE_RELEASE:
      if (c->robot_mode == URT_ROBOT_MODE_IDLE || c->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
        c->robot_mode = URT_ROBOT_MODE_RUNNING;  // the set-point keeps holding where it was
      }
      break;
    case URT_CTRL_UNLOCK_PSTOP:
      if (c->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP || d->pstop) {
        urt_pstop_reset(m, d);
        c->safety_mode = URT_SAFETY_MODE_NORMAL;
        hold_at(c, actual_q(d));
        model_torque(m, c, c->q1, c->qd1, c->qdd1, c->tau_model1);
        std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);
      }
      break;
    case URT_CTRL_PROGRAM_STATE:
      c->program_state = cmd->index;
      break;
    case URT_CTRL_HALT:
      if (c->motion != URT_MOTION_IDLE || moving(c)) {
        finish_motion(c);
        start_stop(c, p, joint_stop_time(c, kHaltDecel));
        store_plan(c, p);
      }
      break;
    default:
      break;
  }
}

void urt_ctrl_tick(const urt_model_t* m, urt_ctrl_t* c, urt_data_t* d) {
  c->tick++;
  // the end of the last period is the start of this one
  std::memcpy(c->q0, c->q1, sizeof c->q0);
  std::memcpy(c->qd0, c->qd1, sizeof c->qd0);
  std::memcpy(c->qdd0, c->qdd1, sizeof c->qdd0);
  std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);

  tick_thermal(m, c, d);

  // the speed slider, slewed
  double ds = c->speed_slider - c->speed_scaling, dmax = kSliderRate * c->period;
  double dscale = std::fmax(-dmax, std::fmin(dmax, ds)) / c->period;
  c->speed_scaling += dscale * c->period;

  // the physics stopped: follow it
  if (d->pstop && c->safety_mode != URT_SAFETY_MODE_PROTECTIVE_STOP) {
    protective_stop(c, d, URT_CTRL_FAULT_PSTOP, 0);
  }
  if (!running(c)) {
    // hold (protective stop: where the physics froze; otherwise where the set-point was)
    if (c->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP) {
      hold_at(c, vec6(d->cmd.q));
      std::memset(c->tau_model1, 0, sizeof c->tau_model1);
      std::memset(c->tau_model0, 0, sizeof c->tau_model0);
    } else {
      hold_at(c, vec6(c->q0));
      model_torque(m, c, c->q1, c->qd1, c->qdd1, c->tau_model1);
    }
    return;
  }

  Plan p = load_plan(c);
  c->seg_time += c->period;
  switch (c->motion) {
    case URT_MOTION_IDLE:
      std::memset(c->qd1, 0, sizeof c->qd1);
      std::memset(c->qdd1, 0, sizeof c->qdd1);
      break;
    case URT_MOTION_MOVEJ: {
      double s = c->speed_scaling;
      c->traj_time += s * c->period;
      tick_movej(c, p, s, dscale);
      break;
    }
    case URT_MOTION_MOVEL: {
      double s = c->speed_scaling;
      c->traj_time += s * c->period;
      if (!tick_movel(m, c, p, s)) {
        protective_stop(c, d, URT_CTRL_FAULT_IK, URT_PSTOP_POS_LIMIT);
        return;
      }
      break;
    }
    case URT_MOTION_SERVOJ:
      tick_servoj(m, c, p);
      if (p.servoj.since > std::fmax(c->active.t, c->period) + c->period) {
        // no new servoj in time: decelerate to rest
        mark_done(c, c->motion_id);
        start_stop(c, p, joint_stop_time(c, kHaltDecel));
      }
      break;
    case URT_MOTION_SPEEDJ:
      tick_speedj(c, p);
      if (c->active.t > 0.0 && c->seg_time >= c->active.t - 1e-12) {
        mark_done(c, c->motion_id);
        start_stop(c, p, joint_stop_time(c, c->active.a));
      }
      break;
    case URT_MOTION_SPEEDL:
      tick_speedl(m, c, p);
      if (c->active.t > 0.0 && c->seg_time >= c->active.t - 1e-12) {
        mark_done(c, c->motion_id);
        double a_rot = c->active.a_rot > 0.0 ? c->active.a_rot : c->active.a;
        start_stop(c, p, tcp_twist_decel_time(m, c, c->active.a, a_rot));
      }
      break;
    case URT_MOTION_STOP:
      tick_stop(c, p);
      if (!moving(c)) {
        if (c->has_pending) {
          urt_ctrl_cmd_t next = c->pending;
          c->has_pending = 0;
          if (next.kind == URT_CTRL_MOVEJ) {
            start_movej(m, c, p, &next);
          } else {
            start_movel(m, c, p, &next);
          }
        } else {
          finish_motion(c);
        }
      }
      break;
    case URT_MOTION_DIRECT:
      std::memcpy(c->q1, c->active.q, sizeof c->q1);
      std::memcpy(c->qd1, c->active.qd, sizeof c->qd1);
      for (int j = 0; j < URT_NJ; j++) {
        c->qdd1[j] = (c->qd1[j] - c->qd0[j]) / c->period;
      }
      mark_done(c, c->motion_id);
      break;
  }
  store_plan(c, p);

  // a set-point the joints cannot follow is a protective stop, as on a real robot
  uint32_t bad = target_faults(m, c->q1);
  if (!bad) {
    bad = speed_faults(m, c->qd1);
  }
  if (bad) {
    protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, bad);
    return;
  }
  model_torque(m, c, c->q1, c->qd1, c->qdd1, c->tau_model1);
}

// Cubic Hermite between (q0, q̇0) and (q1, q̇1) over the period. The physics holds q̈ over its
// step (q + q̇ s + q̈ s²/2), so q̈ is the cubic's at a third of the step: the step then ends
// exactly on the cubic.
void urt_ctrl_setpoint(const urt_model_t* m, const urt_ctrl_t* c, int k, urt_command_t* out) {
  const double T = c->period, dt = m->dt;
  const double u = (k * dt) / T, um = (k * dt + dt / 3.0) / T;
  const double u2 = u * u, u3 = u2 * u;
  const double h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  const double d00 = 6 * u2 - 6 * u, d10 = 3 * u2 - 4 * u + 1, d01 = -d00, d11 = 3 * u2 - 2 * u;
  const double a00 = 12 * um - 6, a10 = 6 * um - 4, a01 = -a00, a11 = 6 * um - 2;
  const double w = (k * dt + 0.5 * dt) / T;  // feed-forward: linear, at the step's middle
  for (int j = 0; j < URT_NJ; j++) {
    double dq = c->q1[j] - c->q0[j];
    out->q[j] = c->q0[j] + (h10 * T * c->qd0[j] + h01 * dq + h11 * T * c->qd1[j]);
    out->qd[j] = (d00 * c->q0[j] + d10 * T * c->qd0[j] + d01 * c->q1[j] + d11 * T * c->qd1[j]) / T;
    out->qdd[j] =
        (a00 * c->q0[j] + a10 * T * c->qd0[j] + a01 * c->q1[j] + a11 * T * c->qd1[j]) / (T * T);
    // keep within what urt_command_set accepts (rounding at the limits)
    const double vmax = m->joint[j].qd_max, amax = m->joint[j].qdd_max;
    out->qd[j] = std::fmax(-vmax, std::fmin(vmax, out->qd[j]));
    out->qdd[j] = std::fmax(-amax, std::fmin(amax, out->qdd[j]));
    out->tau_ff[j] = (1.0 - w) * c->tau_model0[j] + w * c->tau_model1[j] + c->tau_ff[j];
  }
}

}  // extern "C"
