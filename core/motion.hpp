// SPDX-License-Identifier: Apache-2.0
// core/motion.hpp — the controller's motions as objects: one small interface (validate, start,
// tick, stop, blend) that every motion type implements in its own file (core/motion_*.cpp),
// and the helpers they share. The state machine (controller.cpp) picks the type of a command
// (motion_for_command) or of the running motion (motion_of), and calls it; each type keeps its
// state in its member of c->motion_state (urt/controller_motion_state.h). Internal. Context: RT
// (no allocation, no exceptions, fixed-size Eigen on the stack).
#ifndef URT_CORE_MOTION_HPP
#define URT_CORE_MOTION_HPP

#include <cmath>
#include <cstdint>
#include <cstring>

#include <Eigen/LU>

#include "controller_internal.hpp"
#include "urt/controller.h"

namespace urt::core {

constexpr double kHaltDecel = 4.0;      // HALT and servo time-out deceleration [rad/s²]
constexpr double kSpeedMargin = 0.98;   // planned speeds up to this fraction of qd_max
constexpr double kAccMargin = 0.9;      // planned accelerations up to this fraction of qdd_max

// What a motion works on during one call.
struct MotionEnv {
  const urt_model_t* m;
  urt_ctrl_t* c;
  urt_data_t* d;
  double scale;    // planned-motion time rate: speed slider × pause (tick only)
  double dscale;   // its rate of change [1/s] (tick only)
};

// What the state machine learnt before starting a command.
struct MotionStart {
  urt_ctrl_motion_t prev;   // the motion that ran until now
  const double* q_goal;     // IK of the command's pose from the set-point (pose commands), or null
};

// Why a motion is asked to stop.
enum class StopCause { kHalt, kPause };

struct Motion {
  urt_ctrl_motion_t id;        // c->motion while it runs
  bool pose_target;            // the command's pose must have an IK solution (else refused)
  bool stream;                 // a command with the same id and kind continues it
  bool torque_controlled;      // it drives the joints in torque mode (keeps c->torque_mask)

  // Argument checks (true: refused, URT_CTRL_FAULT_BAD_ARGUMENT) and target checks
  // (URT_PSTOP_* bits: a protective stop) of a command that would start this motion.
  bool (*bad_argument)(const urt_ctrl_cmd_t& cmd);
  uint32_t (*bad_target)(const urt_model_t* m, const urt_ctrl_cmd_t& cmd);

  // Take over the motion generator; c->active is the command, c->motion_id its id, and the
  // previous motion's id is done.
  void (*start)(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s);

  // One period: from the set-point at the period's start (c->q0, qd0, qdd0) to its end
  // (c->q1, qd1, qdd1). Returns 0, or the URT_CTRL_FAULT_* of a protective stop.
  uint32_t (*tick)(const MotionEnv& e);

  // HALT (every motion ends and decelerates) or PAUSE (streams end and decelerate; planned
  // motions slow down along their path instead).
  void (*stop)(const MotionEnv& e, StopCause why);

  // A new motion command arrived while this one runs: may it start inside this motion's blend
  // radius (true: the motion took it over)? null: never, the new motion starts from a stop.
  bool (*blend)(const MotionEnv& e, const urt_ctrl_cmd_t& next);
};

// The type a motion command starts (null: not a motion command), and the running one's.
const Motion* motion_for_command(const urt_ctrl_cmd_t& cmd) noexcept;
const Motion& motion_of(urt_ctrl_motion_t id) noexcept;

// The types (one file each).
extern const Motion kIdleMotion;       // motion_idle.cpp
extern const Motion kMovejMotion;      // motion_movej.cpp
extern const Motion kOptimovejMotion;  // motion_movej.cpp (a, v as fractions of the limits)
extern const Motion kMovelMotion;      // motion_movel.cpp
extern const Motion kStopMotion;       // motion_stop.cpp (stopj, stopl)
extern const Motion kServojMotion;     // motion_servoj.cpp
extern const Motion kServolMotion;     // motion_servoj.cpp (servoj on the pose's IK)
extern const Motion kSpeedjMotion;     // motion_speedj.cpp
extern const Motion kSpeedlMotion;     // motion_speedl.cpp
extern const Motion kDirectMotion;     // motion_direct.cpp
extern const Motion kServocMotion;     // motion_servoc.cpp
extern const Motion kTorqueMotion;     // motion_torque.cpp
extern const Motion kFreedriveMotion;  // motion_freedrive.cpp
extern const Motion kForceMotion;      // motion_force.cpp
extern const Motion kPathJointMotion;  // motion_path.cpp: movej/optimovej with r > 0
extern const Motion kPathToolMotion;   // motion_path.cpp: movel with r > 0, movep, optimovel
extern const Motion kPathArcMotion;    // motion_path.cpp: movec

// ---- shared by the types ----

// stops (motion_stop.cpp): decelerate every joint to rest, all together, the leading one
// reaching 0 after t_stop; and the default stop hooks
void start_stop(urt_ctrl_t* c, double t_stop) noexcept;
void stop_to_rest(const MotionEnv& e, StopCause why) noexcept;    // end, decelerate (HALT rate)
void stop_on_path(const MotionEnv& e, StopCause why) noexcept;    // PAUSE: keep (slows on path)

// force mode (motion_force.cpp), set by FORCE_MODE (not a motion command): take the generator
// over from the current set-point and twist (a running speedl goes on inside it); inside it a
// speedl or stop sets the motion of the non-compliant axes
void force_begin(const MotionEnv& e) noexcept;
void force_take_speed(const MotionEnv& e, const urt_ctrl_cmd_t& cmd) noexcept;

// an external set-point's jump (motion_direct.cpp): the joints (bits 0–5) whose commanded q is
// further from the current set-point c->q1 than qd_max moves them in one period
uint32_t direct_jump_joints(const urt_model_t* m, const urt_ctrl_t* c,
                            const urt_ctrl_cmd_t& cmd) noexcept;

// the controller's checks (controller.cpp)
uint32_t speed_faults(const urt_model_t* m, const double* qd) noexcept;
uint32_t torque_faults(const urt_model_t* m, const double* tau) noexcept;

// the TCP twist (v; ω) of the set-point q1, qd1, base frame
inline Vec6 setpoint_twist(const urt_model_t* m, const urt_ctrl_t* c) noexcept {
  Mat3 R;
  Vec3 p;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), R, p, &J);
  return J * vec6(c->qd1);
}

inline double tcp_twist_decel_time(const urt_model_t* m, const urt_ctrl_t* c, double a,
                                   double a_rot) noexcept {
  Vec6 x = setpoint_twist(m, c);
  return std::fmax(x.head<3>().norm() / a, x.tail<3>().norm() / a_rot);
}

inline double joint_stop_time(const urt_ctrl_t* c, double a) noexcept {
  double vmax = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    vmax = std::fmax(vmax, std::fabs(c->qd1[j]));
  }
  return vmax / a;
}

inline bool moving(const urt_ctrl_t* c) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    if (c->qd1[j] != 0.0) {
      return true;
    }
  }
  return false;
}

// ---- trapezoid (movej, movel) ----

inline urt_trap_t trap_plan(double D, double v, double a, double t) noexcept {
  urt_trap_t tr{D, 0.0, 0.0, 0.0, 0.0};
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
inline void trap_eval(const urt_trap_t& tr, double t, double& s, double& sd,
                      double& sdd) noexcept {
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

// ---- twists (speedl, servoc, force mode) ----

// ramp a vector toward a goal by at most step (along the difference)
inline void ramp3(double* x, const double* goal, double step) noexcept {
  Vec3 d(goal[0] - x[0], goal[1] - x[1], goal[2] - x[2]);
  double n = d.norm();
  double k = n <= step ? 1.0 : step / n;
  for (int i = 0; i < 3; i++) {
    x[i] += k * d[i];
  }
}

// damping of the inverse Jacobian near singularities (manipulability |det J|)
inline double dls_lambda(const Mat6& J) noexcept {
  constexpr double w0 = 1e-3, lambda0 = 0.05;
  double w = std::fabs(J.determinant());
  return w >= w0 ? 0.0 : lambda0 * std::sqrt(1.0 - (w / w0) * (w / w0));
}

// integrate a tool twist into the set-point through the damped inverse Jacobian at q0
inline void twist_to_joints(const urt_model_t* m, urt_ctrl_t* c, const Vec6& xd) noexcept {
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

// the common argument checks
inline bool no_bad_argument(const urt_ctrl_cmd_t&) { return false; }
inline uint32_t no_bad_target(const urt_model_t*, const urt_ctrl_cmd_t&) { return 0; }
inline uint32_t pose_faults(const urt_model_t*, const urt_ctrl_cmd_t& cmd) {
  return all_finite(cmd.pose, 6) ? 0 : URT_PSTOP_NONFINITE_CMD;
}
inline uint32_t joint_target_faults(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  return target_faults(m, cmd.q);
}

}  // namespace urt::core

#endif
