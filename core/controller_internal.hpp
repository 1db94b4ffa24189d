// SPDX-License-Identifier: Apache-2.0
// core/controller_internal.hpp — what the controller's files (core/controller*.cpp) share, and
// the kinematics with a runtime TCP offset that the snapshot (core/snapshot.cpp) uses too.
// Internal. Context: RT.
#ifndef URT_CORE_CONTROLLER_INTERNAL_HPP
#define URT_CORE_CONTROLLER_INTERNAL_HPP

#include <cmath>
#include <cstdint>

#include "arm.hpp"
#include "urt/controller.h"
#include "urt/core.h"
#include "step_internal.h"

namespace urt::core {

// ---- constants both the state machine and the motion generators use ----

constexpr double kForceAcc = 2.5;       // force-mode tool acceleration bound [m/s²]
constexpr double kForceAccRot = 5.0;    // and angular [rad/s²]
constexpr uint32_t kAllJoints = (1u << URT_NJ) - 1u;  // a torque_mask with every joint

// ---- command checks (controller.cpp) ----

// URT_PSTOP_* bit a joint target deserves (0: fine): non-finite, or outside the joint limits.
uint32_t target_faults(const urt_model_t* m, const double* q) noexcept;

// ---- motion bookkeeping (controller.cpp) ----

// Mark the motion id done (ids only grow: an older id changes nothing).
void mark_done(urt_ctrl_t* c, uint64_t id) noexcept;

// End the current motion (finished or aborted): its id, and a pending one's, are done; back to
// position control, out of force mode, no external feed-forward.
void finish_motion(urt_ctrl_t* c) noexcept;

// ---- the state machine's moves (controller.cpp) ----

// RUNNING with safety NORMAL: the arm takes motions.
bool running(const urt_ctrl_t* c) noexcept;

// Hold the set-point at q, at rest (both ends of the current period).
void hold_at(urt_ctrl_t* c, const Vec6& q) noexcept;

// The arm powered off: the motion ends and the set-point holds where the arm is.
void power_off(urt_ctrl_t* c, const urt_data_t* d) noexcept;

// A protective stop: fault bits into c->fault, a running program paused (but for a bad target),
// the motion ended, pstop_bits (if any) into the physics' stop, the set-point held where the
// physics' command is.
void protective_stop(urt_ctrl_t* c, urt_data_t* d, uint32_t fault, uint32_t pstop_bits) noexcept;

// ---- the commands that are not motions (controller_commands.cpp) ----

struct MotionEnv;  // motion.hpp

// Apply one command that motion_for_command() does not take: outputs, slider, TCP, payload,
// power, brakes, unlock, safety restart, program state, pause/resume, wrench, inputs, faults,
// F/T zero, tool voltage, gravity, freedrive end, force mode, protective stop, HALT.
void apply_setting(const MotionEnv& e, const urt_ctrl_cmd_t* cmd) noexcept;

// ---- shared by the motions (core/motion_*.cpp, interface in motion.hpp) ----

// Torque-controlled joints (mask): the set-point follows the arm, so that the command checks,
// the snapshot's targets and the return to position control see where the arm really is.
// (motion_torque.cpp)
void follow_actual(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                   uint32_t mask) noexcept;

// ---- kinematics (controller_kinematics.cpp) ----

// The TCP (flange · offset, offset = x y z rx ry rz) at q: pose R_BT, p_BT in the base frame and,
// if J is not null, the geometric Jacobian of the TCP point, rows (v; ω), base frame.
// frames (optional, 7 entries): origin of every DH frame 0..6 in the base frame.
void tcp_kinematics(const urt_arm_params_t& a, const double tcp[6], const Vec6& q, Mat3& R_BT,
                    Vec3& p_BT, Mat6* J) noexcept;

// Solve J x = b by damped least squares, x = Jᵀ (J Jᵀ + λ² 1)⁻¹ b; λ = 0 gives the exact
// inverse (LU) for a well-conditioned J.
Vec6 dls_solve(const Mat6& J, const Vec6& b, double lambda) noexcept;

// ---- the controller's arm model and feed-forward (controller_feedforward.cpp) ----

// Inverse dynamics of the controller's arm model: the model's, with the controller's gravity
// and the payload the run has mounted (d->live.payload: what set_payload told the controller).
void ctrl_rnea(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
               const Vec6& q, const Vec6& qd, const Vec6& qdd, Vec6& tau) noexcept;

// Steady-state LuGre friction of joint j at speed qd (σ0 z = g(q̇) sign q̇), faded in over a
// small speed [N m].
double friction_ff(const urt_model_t* m, int j, double qd) noexcept;

// The same with its viscous part (f_v |q̇|^{2/3}) scaled by viscous and the rest (Coulomb and
// Stribeck) by coulomb: direct_torque's friction compensation [N m]. Scales 1, 1: friction_ff.
double friction_ff_scaled(const urt_model_t* m, int j, double qd, double viscous,
                          double coulomb) noexcept;

// The model feed-forward at a set-point q, qd, qdd: τ = RNEA + friction − c->tau_bias [N m].
void model_torque(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
                  const double* q, const double* qd, const double* qdd, double* tau) noexcept;

// optimovej/optimovel's "maximum acceleration of the robot" (UR: a is a fraction of it): the
// acceleration A along the joint-space direction d (rad/s² per unit of d) for which every
// joint's inertial torque M(q)·d·A plus its gravity stays within kOptTorqueShare of its
// torque_max at q (the rest is left to friction, Coriolis and the position loops). Never below
// kOptMinAccel. The controller's gravity and payload. Context: RT (two RNEAs, no allocation).
constexpr double kOptTorqueShare = 0.6;
constexpr double kOptMinAccel = 0.1;  // [rad/s²]
double feasible_accel(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
                      const double* q, const double* d) noexcept;

// The same for a joint move from q_s by dq (its largest component D): the least of the start,
// the middle and the end, along dq/D, so the leading joint's acceleration [rad/s²].
double feasible_joint_move_accel(const urt_model_t* m, const urt_ctrl_t* c,
                                 const urt_payload_t& load, const double* q_s, const double* dq,
                                 double D) noexcept;

// Joint j's torque within what the drives (and urt_command_set) accept [N m].
double clamp_torque(const urt_model_t* m, int j, double tau) noexcept;

// ---- thermal (controller_thermal.cpp) ----

// Advance every motor's winding temperature c->temperature by one period c->period, under the
// copper loss of the motor current in d (exact for a loss constant over the period).
void tick_thermal(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d) noexcept;

// ---- the motor/joint encoder check (controller_encoders.cpp) ----

// Compare each joint's motor encoder (over the gear ratio) with its joint encoder: the first
// joint whose disagreement has moved beyond URT_ENCODER_TOLERANCE while the arm runs (run),
// or −1. While it does not run, the disagreement is re-taken as the reference. Once per
// period, before the motions; the caller stops the arm. Context: RT.
int tick_encoder_check(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                       bool run) noexcept;

// ---- the over-current check (controller_overcurrent.cpp) ----

// Time each joint's drive asking for its current limit (|d->i_ref| at i_max, the outputs of the
// state the tick starts from) while the arm runs
// (run); the first joint that has done so for URT_OVERCURRENT_TIME without a break, or −1.
// While it does not run the times restart. Once per period, before the motions; the caller
// faults the joint. Context: RT.
int tick_overcurrent_check(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                           bool run) noexcept;

// ---- small helpers ----

// six doubles as a vector and back
inline Vec6 vec6(const double* x) noexcept { return Eigen::Map<const Vec6>(x); }
inline void put6(const Vec6& v, double* x) noexcept { Eigen::Map<Vec6>{x} = v; }

// the joint angles of the physics state
inline Vec6 actual_q(const urt_data_t* d) noexcept {
  Vec6 q;
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = d->x[j][URT_X_Q];
  }
  return q;
}

// the joint encoders' reading, where a hold puts the set-point (urt__measured_q)
inline Vec6 measured_q(const urt_data_t* d) noexcept {
  Vec6 q;
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = urt__measured_q(d, j);
  }
  return q;
}

inline bool all_finite(const double* x, int n) noexcept {
  for (int i = 0; i < n; i++) {
    if (!std::isfinite(x[i])) {
      return false;
    }
  }
  return true;
}

}  // namespace urt::core

#endif
