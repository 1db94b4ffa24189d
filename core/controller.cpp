// SPDX-License-Identifier: Apache-2.0
// core/controller.cpp — the UR controller's motion layer (urt/controller.h): robot and safety
// state machine, motion generators (movej, movel, servoj, speedj, speedl, stopj, stopl, direct,
// servol, servoc, direct torque, freedrive, force mode, pause),
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
// - PAUSE multiplies the slider's scaling by a pause factor that slews to 0 at 4 /s (RESUME: back
//   to 1), so movej/movel (and a movej waiting behind a stop) slow down along their path, hold,
//   and continue; streamed motions (servoj/l/c, speedj/l, direct, torque, freedrive, force) stop
//   as with HALT. PROGRAM_STATE STOPPED clears the pause and stops what it held.
// - SET_WRENCH writes d->wrench_ext (each force ≤ 1000 N, torque ≤ 200 N m, finite).
// - SET_GRAVITY changes the controller's model only (feed-forward, freedrive and torque-mode
//   gravity), as set_gravity does on a real controller; the world's gravity is the model's
//   (urt_model_t is const), so a wrong value shows as a tracking error, as on a real arm.
// - TORQUE (directTorque) and FREEDRIVE run the drives in torque mode (urt_command_t.torque_mask:
//   i_ref = τ/(k_t τ_gear), position and speed loops off). The set-point follows the arm. TORQUE
//   applies the command each period (index 1 adds the friction model at the actual speed); with
//   no new TORQUE for 4 periods the drives return to position control, decelerate at 4 rad/s²
//   and hold. Torques above torque_max are a protective stop.
// - FREEDRIVE: τ = g(q) of the controller's gravity; held feature-frame axes (q[i] = 0) get a
//   Cartesian spring-damper toward the pose freedrive began at (tick_freedrive).
// - SERVOL: IK of the pose once per command (from the set-point), then servoj's filter. SERVOC:
//   the tool twist ramps at a toward min(v, √(2 a d)) along the line to the goal; r is treated
//   as 0 (no blending); its id is done on arrival.
// - FORCE_MODE: a first-order admittance per compliant task-frame axis on the F/T reading
//   d->wrench_ext (an ideal sensor), speed-limited; the other axes follow a speedl inside force
//   mode (or hold) and are checked against their deviation limits (tick_force).
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
constexpr double kPauseRate = 4.0;      // pause_scale slew rate [1/s]: 0.25 s from full speed to rest
constexpr int kTorqueTimeout = 4;       // periods without a TORQUE before the arm is stopped
constexpr double kWrenchMaxF = 1000.0;  // SET_WRENCH / FORCE_MODE force bound per axis [N]
constexpr double kWrenchMaxT = 200.0;   // and torque bound [N m]
constexpr double kGravityMax = 100.0;   // SET_GRAVITY bound per axis (the loader's) [m/s²]
constexpr double kForceGain = 0.005;    // force-mode admittance, translation [(m/s)/N]
constexpr double kForceGainRot = 0.05;  // and rotation [(rad/s)/(N m)]
constexpr double kForceAcc = 2.5;       // force-mode tool acceleration bound [m/s²]
constexpr double kForceAccRot = 5.0;    // and angular [rad/s²]
constexpr double kHoldK = 1e4;          // freedrive's spring on held axes, translation [N/m]
constexpr double kHoldD = 300.0;        // and damper [N s/m]
constexpr double kHoldKRot = 1000.0;    // rotation [N m/rad]
constexpr double kHoldDRot = 20.0;      // [N m s/rad]
constexpr uint32_t kAllJoints = (1u << URT_NJ) - 1u;

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

struct TorquePlan {
  double tau[URT_NJ];            // commanded joint torques [N m]
  double friction;               // 1: add the friction model at the actual speed
  double since;                  // time since the last TORQUE [s]
};

struct FreedrivePlan {
  double free[6];                // feature-frame axes x y z rx ry rz: 1 free, 0 held
  double feature[6];             // the feature frame (pose in the base frame)
  double p_hold[3], r_hold[3];   // TCP pose when freedrive began (base frame)
};

struct ServocPlan {
  double target[6];              // pose goal
  double xd[6];                  // current tool twist (v; ω), base frame
};

struct ForcePlan {
  double xd[6];                  // current tool twist (v; ω), base frame
  double xd_goal[6];             // twist of the speedl running inside force mode, base frame
};

union Plan {
  MovejPlan movej;
  MovelPlan movel;
  StopPlan stop;
  SpeedjPlan speedj;
  SpeedlPlan speedl;
  ServojPlan servoj;
  TorquePlan torque;
  FreedrivePlan freedrive;
  ServocPlan servoc;
  ForcePlan force;
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

Vec6 actual_q(const urt_data_t* d) noexcept {
  Vec6 q;
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = d->x[j][URT_X_Q];
  }
  return q;
}

}  // namespace

// URT_PSTOP_* bit a joint target deserves (0: fine); inverse kinematics checks its candidates
// with it too
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

namespace {

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

uint32_t torque_faults(const urt_model_t* m, const double* tau) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(tau[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
    if (std::fabs(tau[j]) > m->joint[j].torque_max) {
      return URT_PSTOP_TORQUE_LIMIT;
    }
  }
  return 0;
}

bool is_motion(const urt_ctrl_cmd_t* cmd) noexcept {
  const int kind = cmd->kind;
  return (kind >= URT_CTRL_MOVEJ && kind <= URT_CTRL_DIRECT) || kind == URT_CTRL_SERVOL ||
         kind == URT_CTRL_SERVOC || kind == URT_CTRL_TORQUE ||
         (kind == URT_CTRL_FREEDRIVE && cmd->index == 1);
}

// streamed motions stop on PAUSE (planned ones slow down along their path instead)
bool is_streaming(urt_ctrl_motion_t motion) noexcept {
  switch (motion) {
    case URT_MOTION_SERVOJ:
    case URT_MOTION_SPEEDJ:
    case URT_MOTION_SPEEDL:
    case URT_MOTION_DIRECT:
    case URT_MOTION_SERVOL:
    case URT_MOTION_SERVOC:
    case URT_MOTION_TORQUE:
    case URT_MOTION_FREEDRIVE:
    case URT_MOTION_FORCE:
      return true;
    default:
      return false;
  }
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
  c->torque_mask = 0;   // back to position control
  c->force_mode = 0;
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

void protective_stop(urt_ctrl_t* c, urt_data_t* d, uint32_t fault, uint32_t pstop_bits) noexcept {
  c->fault |= fault;
  c->safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  finish_motion(c);  // and out of torque and force mode
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

// the TCP twist (v; ω) of the set-point q1, qd1, base frame
Vec6 setpoint_twist(const urt_model_t* m, const urt_ctrl_t* c) noexcept {
  Mat3 R;
  Vec3 p;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R, p, &J);
  return J * vec6(c->qd1);
}

double tcp_twist_decel_time(const urt_model_t* m, const urt_ctrl_t* c, double a,
                            double a_rot) noexcept {
  Vec6 x = setpoint_twist(m, c);
  return std::fmax(x.head<3>().norm() / a, x.tail<3>().norm() / a_rot);
}

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

}  // namespace
}  // namespace urt::core

using namespace urt::core;

extern "C" {

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
  c->pause_scale = 1.0;
  std::memcpy(c->gravity, m->arm.gravity, sizeof c->gravity);
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

  if (is_motion(cmd)) {
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
      case URT_CTRL_SERVOL:
        bad_arg = !(cmd->lookahead_time >= 0.03 && cmd->lookahead_time <= 0.2) ||
                  !(cmd->gain >= 100.0 && cmd->gain <= 2000.0) || !std::isfinite(cmd->t) ||
                  cmd->t < 0.0;
        bad_target = all_finite(cmd->pose, 6) ? 0 : URT_PSTOP_NONFINITE_CMD;
        break;
      case URT_CTRL_SERVOC:
        bad_arg = !(cmd->a > 0.0) || !(cmd->v > 0.0) || !std::isfinite(cmd->a) ||
                  !std::isfinite(cmd->v) || !std::isfinite(cmd->r);
        bad_target = all_finite(cmd->pose, 6) ? 0 : URT_PSTOP_NONFINITE_CMD;
        break;
      case URT_CTRL_TORQUE:
        bad_target = torque_faults(m, cmd->tau);
        break;
      case URT_CTRL_FREEDRIVE:
        for (int j = 0; j < URT_NJ; j++) {
          bad_arg = bad_arg || !(cmd->q[j] == 0.0 || cmd->q[j] == 1.0);
        }
        bad_arg = bad_arg || !all_finite(cmd->pose, 6);
        break;
      case URT_CTRL_DIRECT:
        bad_target = target_faults(m, cmd->q);
        if (!bad_target) {
          bad_target = speed_faults(m, cmd->qd);
        }
        if (!bad_target) {
          bad_target = torque_faults(m, cmd->tau);
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
    double qg[URT_NJ];
    if (kind == URT_CTRL_MOVEL || kind == URT_CTRL_SERVOL || kind == URT_CTRL_SERVOC) {
      if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, cmd->pose, c->q1, qg) != URT_OK) {
        refuse(c, cmd, URT_CTRL_FAULT_IK);
        return;
      }
    }

    // inside force mode a speedl (or a stop) sets the motion of the non-compliant axes; any
    // other motion ends force mode and runs as usual
    if (c->force_mode && c->motion == URT_MOTION_FORCE) {
      if (kind == URT_CTRL_SPEEDL || kind == URT_CTRL_STOPL || kind == URT_CTRL_STOPJ) {
        c->fault = 0;
        mark_done(c, c->motion_id);
        c->motion_id = cmd->id;
        for (int i = 0; i < 6; i++) {
          p.force.xd_goal[i] = kind == URT_CTRL_SPEEDL ? cmd->pose[i] : 0.0;
        }
        mark_done(c, cmd->id);  // returns at once: the goal holds until replaced
        store_plan(c, p);
        return;
      }
      c->force_mode = 0;
    }

    // accepted: the previous motion is over (aborted or superseded); a stream (same id, same
    // kind) continues
    c->fault = 0;
    const int prev_kind = c->active.kind;
    const bool same_stream = cmd->id == c->motion_id && kind == prev_kind &&
                             ((kind == URT_CTRL_SERVOJ && c->motion == URT_MOTION_SERVOJ) ||
                              (kind == URT_CTRL_SERVOL && c->motion == URT_MOTION_SERVOL) ||
                              (kind == URT_CTRL_SERVOC && c->motion == URT_MOTION_SERVOC) ||
                              (kind == URT_CTRL_TORQUE && c->motion == URT_MOTION_TORQUE));
    uint64_t prev_id = c->motion_id;
    if (c->has_pending) {
      mark_done(c, c->pending.id);
      c->has_pending = 0;
    }
    if (!same_stream) {
      mark_done(c, prev_id);
    }
    std::memset(c->tau_ff, 0, sizeof c->tau_ff);
    if (kind != URT_CTRL_TORQUE && kind != URT_CTRL_FREEDRIVE) {
      c->torque_mask = 0;  // position control from where the arm is (q1, q̇1 follow it)
    }
    const urt_ctrl_motion_t prev_motion = c->motion;
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
        start_servoj(c, p, cmd->q, URT_MOTION_SERVOJ);
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
      case URT_CTRL_SPEEDL:
        put6(setpoint_twist(m, c), p.speedl.xd);
        std::memcpy(p.speedl.xd_goal, cmd->pose, sizeof p.speedl.xd_goal);
        c->motion = URT_MOTION_SPEEDL;
        break;
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
      case URT_CTRL_SERVOL:
        // servoj on the joint target of the pose (IK from the set-point, once per command)
        start_servoj(c, p, qg, URT_MOTION_SERVOL);
        break;
      case URT_CTRL_SERVOC:
        if (prev_motion != URT_MOTION_SERVOC) {
          put6(setpoint_twist(m, c), p.servoc.xd);
        }
        std::memcpy(p.servoc.target, cmd->pose, sizeof p.servoc.target);
        c->motion = URT_MOTION_SERVOC;
        break;
      case URT_CTRL_TORQUE:
        std::memcpy(p.torque.tau, cmd->tau, sizeof p.torque.tau);
        p.torque.friction = cmd->index == 1 ? 1.0 : 0.0;
        p.torque.since = 0.0;
        c->motion = URT_MOTION_TORQUE;
        break;
      case URT_CTRL_FREEDRIVE:
        if (prev_motion != URT_MOTION_FREEDRIVE) {
          double pose[6];
          urt_ctrl_forward_kinematics_tcp(m, c->tcp_offset, c->q1, pose);
          std::memcpy(p.freedrive.p_hold, pose, sizeof p.freedrive.p_hold);
          std::memcpy(p.freedrive.r_hold, pose + 3, sizeof p.freedrive.r_hold);
        }
        std::memcpy(p.freedrive.free, cmd->q, sizeof p.freedrive.free);
        std::memcpy(p.freedrive.feature, cmd->pose, sizeof p.freedrive.feature);
        mark_done(c, cmd->id);  // teach mode returns at once; it lasts until ended
        c->motion = URT_MOTION_FREEDRIVE;
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
      if (cmd->index == URT_PROGRAM_STOPPED && c->paused) {
        // the program ended while paused: the held motion is over
        c->paused = 0;
        if (c->motion != URT_MOTION_IDLE || c->has_pending) {
          finish_motion(c);
          start_stop(c, p, joint_stop_time(c, kHaltDecel));
          store_plan(c, p);
        }
      }
      break;
    case URT_CTRL_PAUSE:
      if (!c->paused) {
        c->paused = 1;
        if (is_streaming(c->motion)) {
          finish_motion(c);
          start_stop(c, p, joint_stop_time(c, kHaltDecel));
          store_plan(c, p);
        }
      }
      break;
    case URT_CTRL_RESUME:
      c->paused = 0;
      break;
    case URT_CTRL_SET_WRENCH: {
      bool ok = all_finite(cmd->pose, 6);
      for (int i = 0; i < 6 && ok; i++) {
        ok = std::fabs(cmd->pose[i]) <= (i < 3 ? kWrenchMaxF : kWrenchMaxT);
      }
      if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(d->wrench_ext, cmd->pose, sizeof d->wrench_ext);
      }
      break;
    }
    case URT_CTRL_SET_GRAVITY: {
      bool ok = all_finite(cmd->pose, 3);
      for (int i = 0; i < 3 && ok; i++) {
        ok = std::fabs(cmd->pose[i]) <= kGravityMax;
      }
      if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(c->gravity, cmd->pose, sizeof c->gravity);
      }
      break;
    }
    case URT_CTRL_FREEDRIVE:  // index 0 (index 1 is a motion): end, decelerate, hold
      if (c->motion == URT_MOTION_FREEDRIVE) {
        finish_motion(c);
        start_stop(c, p, joint_stop_time(c, kHaltDecel));
        store_plan(c, p);
      }
      break;
    case URT_CTRL_FORCE_MODE: {
      bool ok = all_finite(cmd->pose, 6) && all_finite(cmd->q, 6) && all_finite(cmd->tau, 6) &&
                all_finite(cmd->qd, 6) && cmd->index >= 1 && cmd->index <= 3;
      for (int i = 0; i < 6 && ok; i++) {
        ok = (cmd->q[i] == 0.0 || cmd->q[i] == 1.0) && cmd->qd[i] >= 0.0 &&
             std::fabs(cmd->tau[i]) <= (i < 3 ? kWrenchMaxF : kWrenchMaxT);
      }
      if (!running(c) || d->pstop) {
        c->fault |= URT_CTRL_FAULT_NOT_RUNNING;
      } else if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->force = *cmd;
        if (!c->force_mode || c->motion != URT_MOTION_FORCE) {
          // force mode takes the motion generator over from the current set-point and twist;
          // a running speedl goes on inside it, any other motion is over
          Vec6 xd = setpoint_twist(m, c);
          Vec6 goal = Vec6::Zero();
          if (c->motion == URT_MOTION_SPEEDL) {
            goal = vec6(p.speedl.xd_goal);
          }
          finish_motion(c);
          put6(xd, p.force.xd);
          put6(goal, p.force.xd_goal);
          c->force_mode = 1;
          c->motion = URT_MOTION_FORCE;
          c->seg_time = 0.0;
          store_plan(c, p);
        }
      }
      break;
    }
    case URT_CTRL_FORCE_MODE_END:
      if (c->force_mode || c->motion == URT_MOTION_FORCE) {
        bool was_force = c->motion == URT_MOTION_FORCE;
        c->force_mode = 0;
        if (was_force) {
          finish_motion(c);
          start_stop(c, p, tcp_twist_decel_time(m, c, kForceAcc, kForceAccRot));
          store_plan(c, p);
        }
      }
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

  // the pause, slewed the same way, multiplies it: planned motions slow down along their path
  double dp = (c->paused ? 0.0 : 1.0) - c->pause_scale, dpmax = kPauseRate * c->period;
  double dpause = std::fmax(-dpmax, std::fmin(dpmax, dp)) / c->period;
  c->pause_scale += dpause * c->period;
  const double scale = c->speed_scaling * c->pause_scale;
  const double dscale_all = dscale * c->pause_scale + c->speed_scaling * dpause;

  // the physics stopped: follow it
  if (d->pstop && c->safety_mode != URT_SAFETY_MODE_PROTECTIVE_STOP) {
    protective_stop(c, d, URT_CTRL_FAULT_PSTOP, 0);
  }
  if (!running(c)) {
    c->torque_mask = c->torque_mask_last = 0;
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
    case URT_MOTION_MOVEJ:
      c->traj_time += scale * c->period;
      tick_movej(c, p, scale, dscale_all);
      break;
    case URT_MOTION_MOVEL:
      c->traj_time += scale * c->period;
      if (!tick_movel(m, c, p, scale)) {
        protective_stop(c, d, URT_CTRL_FAULT_IK, URT_PSTOP_POS_LIMIT);
        c->torque_mask_last = 0;
        return;
      }
      break;
    case URT_MOTION_SERVOJ:
    case URT_MOTION_SERVOL:
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
    case URT_MOTION_SERVOC:
      if (tick_servoc(m, c, p)) {
        finish_motion(c);
      }
      break;
    case URT_MOTION_TORQUE: {
      // torque control of every drive: the set-point follows the arm, the drives make the
      // commanded torque (plus the friction model at the actual speed with index 1)
      TorquePlan& tp = p.torque;
      follow_actual(m, c, d, kAllJoints);
      tp.since += c->period;
      if (tp.since > (kTorqueTimeout + 0.5) * c->period) {
        // the stream stopped: back to position control, decelerate to rest and hold
        finish_motion(c);
        start_stop(c, p, joint_stop_time(c, kHaltDecel));
        break;
      }
      c->torque_mask = kAllJoints;
      for (int j = 0; j < URT_NJ; j++) {
        double f = tp.friction != 0.0 ? friction_ff(m, j, d->x[j][URT_X_QD]) : 0.0;
        c->tau_ff[j] = clamp_torque(m, j, tp.tau[j] + f);
      }
      mark_done(c, c->motion_id);
      break;
    }
    case URT_MOTION_FREEDRIVE:
      tick_freedrive(m, c, d, p);
      break;
    case URT_MOTION_FORCE:
      if (!tick_force(m, c, d, p)) {
        protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, URT_PSTOP_POS_LIMIT);
        c->torque_mask_last = 0;
        return;
      }
      break;
  }
  store_plan(c, p);

  // a set-point the joints cannot follow is a protective stop, as on a real robot (for
  // torque-controlled joints: the arm left the joint limits or runs too fast)
  uint32_t bad = target_faults(m, c->q1);
  if (!bad) {
    bad = speed_faults(m, c->qd1);
  }
  if (bad) {
    protective_stop(c, d, URT_CTRL_FAULT_BAD_TARGET, bad);
    c->torque_mask_last = 0;
    return;
  }
  model_torque(m, c, c->q1, c->qd1, c->qdd1, c->tau_model1);

  // torque-controlled joints take c->tau_ff alone; a joint back from torque control starts
  // its period on the model feed-forward (not on the zero it carried)
  for (int j = 0; j < URT_NJ; j++) {
    const bool now = (c->torque_mask >> j) & 1u, before = (c->torque_mask_last >> j) & 1u;
    if (now) {
      c->tau_model0[j] = c->tau_model1[j] = 0.0;
    } else if (before) {
      c->tau_model0[j] = c->tau_model1[j];
    }
  }
  c->torque_mask_last = c->torque_mask;
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
  out->torque_mask = c->torque_mask;
}

}  // extern "C"
