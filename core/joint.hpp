// SPDX-License-Identifier: Apache-2.0
// core/joint.hpp — one joint's drive (controller, PWM, motor, gear, sensors) and friction
// assembled into the 21-state right-hand side of model.md §1.9. Internal to the core.
#ifndef URT_CORE_JOINT_HPP
#define URT_CORE_JOINT_HPP

#include <cmath>

#include "urt/data.h"
#include "urt/drivers/friction.h"
#include "urt/model.h"

namespace urt::core {

// Which saturations the right-hand side assumes. kNatural evaluates them from the state;
// the forced sets make the drive block exactly affine, which is how the integrator tables
// take its Jacobian (model.md §5.2: the Jacobian must match the active saturation set).
enum ActiveSet : int {
  kFree = 0,         // neither i_ref nor V saturated
  kCurrentSat = 1,   // i_ref at ±i_max, ξ_v held
  kVoltageSat = 2,   // V at ±V_net, ξ_c held
  kBothSat = 3,
  // a backlash fault's dead zone: the gear's output spring carries nothing (T_CS = 0), so the
  // drive block is affine again, with k_CS = c_CS = 0 (in contact it is the healthy block with
  // a constant offset, the healthy tables)
  kGearGap = 4,
  kNumActiveSets = 8,
  kNatural = -1
};

// Set-point and held measurement errors the joint sees during one step.
struct JointInput {
  double q_set, qd_set;    // set-point at the evaluation time [rad, rad/s]
  double i_ff;             // current feed-forward [A]
  double eps_i, eps_w, eps_q;  // held measurement errors (sensors.h)
  double i_offset;         // zero offset of the current measurement [A]
  int drives_engaged;
  int torque;              // 1: torque mode (urt_command_t.torque_mask)
  // the joint's parameters and sensor errors as its faults make them (urt/faults.h), or
  // nullptr for a healthy joint, which then reads the model's exactly as before
  const urt_fault_joint_t* fault = nullptr;
};

// Signals computed along the way, for outputs and for the integrator.
struct JointAux {
  double t_cs;      // gear output torque [N m]
  double t_in;      // WG input torque [N m]
  double i_ref;     // current reference [A]
  double v_sup;     // motor voltage [V]
  double i_fb, qdm_fb, q_fb;  // measurements [A, rad/s, rad]
  int active_set;   // ActiveSet the state is in
  urt_friction_out_t fr;  // friction torque, bristle rate and partials (joint_rates only)
};

// The joint's faults (urt/faults.h), or nullptr for a healthy joint. Context: RT.
inline const urt_fault_joint_t* joint_fault(const urt_data_t* d, int j) noexcept {
  return ((d->faults.joint_mask >> j) & 1u) ? &d->faults.joint[j] : nullptr;
}

// The friction parameters joint j runs on now: its fault's, or the model's. Context: RT.
inline const urt_friction_params_t& friction_now(const urt_model_t* m, const urt_data_t* d,
                                                 int j) noexcept {
  const urt_fault_joint_t* fj = joint_fault(d, j);
  return fj ? fj->friction : m->friction[j];
}

// LuGre's bristles carry at most g(q̇)/σ0: its own solutions keep |z| within that. When a fault
// lowers a joint's Coulomb level (a brake drag released, an intermittent window closing, a
// lubricant fault cleared), bristles loaded beyond the new level slip to it at once instead of
// being carried over: left beyond it, a stuck joint's z stays there (ż = q̇ − σ0|q̇|z/g is 0 at
// rest), every step is implausible and the arm stops. Called only where the level fell; below
// f_c (1 − |asym|), which g never goes under, nothing is evaluated. Context: RT.
inline void bristles_to_level(const urt_friction_params_t& fp, double* x) noexcept {
  double& z = x[URT_X_Z];
  if (!fp.enabled || fp.sigma0 * std::fabs(z) <= fp.f_c * (1.0 - std::fabs(fp.asym))) {
    return;
  }
  const double z_lim = urt_friction_g(&fp, x[URT_X_QD]) / fp.sigma0;
  if (std::fabs(z) > z_lim) {
    z = std::copysign(z_lim, z);
  }
}

// The joint encoder's reading: its filter's output p plus the held error eps_q, through a
// sensor fault when the joint has one (a stuck value, a bias, noise). Context: RT.
inline double joint_q_reading(double p, double eps_q, const urt_fault_joint_t* fj) noexcept {
  double q_fb = p + eps_q;
  if (fj) {
    q_fb = fj->q_stuck ? fj->q_hold : q_fb + fj->q_bias + fj->q_noise;
  }
  return q_fb;
}

// The motor encoder's speed reading: its filter's output w plus the held error eps_w, through a
// sensor fault when the joint has one (a stuck value, a bias, noise, lost counts). Context: RT.
inline double motor_speed_reading(double w, double eps_w, const urt_fault_joint_t* fj) noexcept {
  double qdm_fb = w + eps_w;
  if (fj) {
    qdm_fb = fj->qdm_stuck ? fj->qdm_hold : qdm_fb + fj->qdm_bias + fj->qdm_noise - fj->qdm_missed;
  }
  return qdm_fb;
}

// Rates of the 18 drive-block states (rows 0..17 of f). With forced = kNatural the saturations
// follow the state; otherwise they are forced to `forced` (the set-point's sign decides the
// saturated value). Rows 18..20 (q, q̇, z) are left untouched. Context: RT.
void drive_rhs(const urt_model_t* m, int j, const double* x, const JointInput& in, int forced,
               double* f, JointAux* aux) noexcept;

// The joint's inputs at time s into the current step: the command's quadratic set-point,
// the torque feed-forward as a current, and the held sensor errors. Context: RT.
JointInput joint_input(const urt_model_t* m, const urt_data_t* d, int j, double s) noexcept;

// Rates of the 18 drive-block states plus q and z rows (natural saturations), and the net
// torque the joint puts on the arm (gear output minus friction) as the return value. The q̇
// row is left to the arm. Context: RT.
double joint_rates(const urt_model_t* m, const urt_data_t* d, int j, double s, const double* x,
                   double* f, JointAux* aux) noexcept;

}  // namespace urt::core

#endif
