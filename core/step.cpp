// SPDX-License-Identifier: Apache-2.0
// core/step.cpp — urt_step: guard the command, integrate one step, check the state, sample
// the sensors and refresh the outputs. Also the full right-hand side for the reference.
#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "arm.hpp"
#include "integrator.hpp"
#include "joint.hpp"
#include "step_internal.h"
#include "urt/core.h"
#include "urt/drivers/friction.h"
#include "urt/faults.h"

namespace {

// All 126 states finite: a double is infinite or NaN exactly when its exponent bits are all
// ones. One pass over the raw bits that OR-reduces that test, instead of 126 isfinite calls
// with a branch each (which cost more than the rest of urt_step's own work); same verdict.
bool states_finite(const double (*x)[URT_NXJ]) noexcept {
  constexpr uint64_t kExp = 0x7ff0000000000000ULL;
  uint64_t bad = 0;
  for (int j = 0; j < URT_NJ; j++) {
    for (int i = 0; i < URT_NXJ; i++) {
      uint64_t bits;
      std::memcpy(&bits, &x[j][i], sizeof bits);
      bad |= (uint64_t)((bits & kExp) == kExp);
    }
  }
  return bad == 0;
}

// z_max is LuGre's bound at the joint's speed limit; a joint can run past that limit (a drive
// wound up against a brake drag that is released), where g(q̇) and so the bound are higher:
// within 1.5 g(q̇)/σ0 at the speed it has reached, the bristles are still plausible. Evaluated
// only when z is beyond 1.5 z_max.
bool bristles_within_speed_level(const urt_model_t* m, const urt_data_t* d, int j) {
  const urt_friction_params_t& fp = urt::core::friction_now(m, d, j);
  return std::fabs(d->x[j][URT_X_Z]) <= 1.5 * urt_friction_g(&fp, d->x[j][URT_X_QD]) / fp.sigma0;
}

// A step is implausible when it produced what no motion of the arm can: a non-finite value,
// a bristle deflection far beyond g(q̇_max)/σ0 (LuGre keeps |z| below it), or, with the drives
// engaged, a joint ten times faster than its limit. That is how the W-method fails at a
// stick-to-slip reversal, where the bristle stiffness σ0|q̇|/g changes by orders of magnitude
// within one step and a single linearisation cannot cover it.
bool step_plausible(const urt_model_t* m, const urt_data_t* d) {
  if (!states_finite(d->x)) {
    return false;
  }
  for (int j = 0; j < URT_NJ; j++) {
    // a faulted joint's friction levels bound z by their own g (urt_fault_joint_t.z_max)
    const double z_max = ((d->faults.joint_mask >> j) & 1u) ? d->faults.joint[j].z_max
                                                             : m->tables->z_max[j];
    if (m->friction[j].enabled && std::fabs(d->x[j][URT_X_Z]) > 1.5 * z_max &&
        !bristles_within_speed_level(m, d, j)) {
      return false;
    }
    if (m->drives_engaged && std::fabs(d->x[j][URT_X_QD]) > 10.0 * m->joint[j].qd_max) {
      return false;
    }
  }
  return true;
}

// A step is rough when a joint's mean acceleration over it differs from the step before's by
// more than ten times its acceleration-command limit: what the W-method makes of a
// stick-to-slip reversal it linearised on the wrong side (wrist 2 at 10 kHz, pickplace at
// 8.9112 s: −0.001 → +0.20 rad/s in one step and 59 N m of friction on a 1.7 N m Coulomb
// level; refined, 6.3 N m at most, as at 20 kHz). Smooth motion changes its acceleration far
// less from one step to the next: healthy excitations at 10 and 20 kHz never trip it. Abrupt
// events do (a backlash impact, about one step in 2000 of a backlash run; wrist 1 braked at
// 1280 rad/s² in the hash test's force scenario), and come out more accurate for it.
bool step_rough(const urt_model_t* m, const urt_data_t* d, const double (*x0)[URT_NXJ]) {
  bool rough = false;
  for (int j = 0; j < URT_NJ; j++) {
    const double a = (d->x[j][URT_X_QD] - x0[j][URT_X_QD]) / m->dt;
    rough = rough || std::fabs(a - d->qdd[j]) > 10.0 * m->joint[j].qdd_max;
  }
  return rough;
}

// Undo the step and redo it from x0 as fine steps of the whole model, kind kSub (n_sub of
// them) or kFine (kFinePerSub times as many); each redo counts in refined_count.
void redo_as(const urt_model_t* m, urt_data_t* d, const double (*x0)[URT_NXJ], int kind) {
  std::memcpy(d->x, x0, sizeof d->x);
  const urt_integrator_tables* tab = m->tables;
  const int n = tab->n_sub * (kind == urt::core::kFine ? urt::core::kFinePerSub : 1);
  for (int k = 0; k < n; k++) {
    urt::core::integrator_step(m, d, kind, k * tab->h[kind]);
  }
  d->refined_count++;
}

// The command describes a quadratic from the step's start; carry it to the next step's start
// so that a caller writing commands at a slower rate gets a continuous set-point.
void command_advance(urt_data_t* d, double h) {
  urt_command_t& c = d->cmd;
  for (int j = 0; j < URT_NJ; j++) {
    c.q[j] += c.qd[j] * h + 0.5 * c.qdd[j] * h * h;
    c.qd[j] += c.qdd[j] * h;
  }
}

// Drive signals (torques, voltage, measurements) at the current state, without the TCP pose.
void outputs_drive(const urt_model_t* m, urt_data_t* d) {
  double f[URT_NXJ];
  for (int j = 0; j < URT_NJ; j++) {
    urt::core::JointAux aux;
    urt::core::joint_rates(m, d, j, 0.0, d->x[j], f, &aux);
    d->t_cs[j] = aux.t_cs;
    d->t_in[j] = aux.t_in;
    d->i_ref[j] = aux.i_ref;
    d->v_sup[j] = aux.v_sup;
    d->i_fb[j] = aux.i_fb;
    d->qdm_fb[j] = aux.qdm_fb;
    d->q_fb[j] = aux.q_fb;
    d->t_f[j] = aux.fr.t_f;
  }
}

}  // namespace

extern "C" double urt__measured_q(const urt_data_t* d, int j) {
  return urt::core::joint_q_reading(d->x[j][URT_X_P], d->eps_q[j], urt::core::joint_fault(d, j));
}

extern "C" void urt_sensors_sample(const urt_model_t* m, urt_data_t* d) {
  // with noise off on every joint the draws change nothing (the held errors ignore them) and
  // nothing else reads the generator, so they are skipped: a noise-free run gives the same bits
  // as before and no longer pays the 18 normal draws a step (the model's noise flags
  // are fixed once it is loaded)
  bool any_noise = false;
  for (int j = 0; j < URT_NJ; j++) {
    any_noise = any_noise || m->sensors[j].noise;
  }
  for (int j = 0; j < URT_NJ; j++) {
    const urt_sensors_params_t& sp = m->sensors[j];
    const double* x = d->x[j];

    // with noise on anywhere, draw all three normals for every joint, noise on or off, so that
    // switching one joint's noise does not shift the random sequence of the others
    double n_i = 0.0, n_w = 0.0, n_q = 0.0;
    if (any_noise) {
      n_i = urt_rng_normal(&d->rng);
      n_w = urt_rng_normal(&d->rng);
      n_q = urt_rng_normal(&d->rng);
    }
    d->eps_i[j] = urt_sensors_held_error(x[URT_X_I_F], sp.sigma_i, n_i, sp.lsb_i, sp.noise,
                                         sp.quantise);
    d->eps_w[j] = urt_sensors_held_error(x[URT_X_W], sp.sigma_w, n_w, sp.lsb_w, sp.noise,
                                         sp.quantise);
    d->eps_q[j] = urt_sensors_held_error(x[URT_X_P], sp.sigma_q, n_q, sp.lsb_q, sp.noise,
                                         sp.quantise);
  }
}

extern "C" void urt_data_update_outputs(const urt_model_t* m, urt_data_t* d) {
  outputs_drive(m, d);
  double q[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = d->x[j][URT_X_Q];
  }
  urt_arm_tcp_pose(m, q, d->tcp_pose);
}

extern "C" int urt_step(const urt_model_t* m, urt_data_t* d) {
  // a command written straight into d->cmd gets the same scrutiny as urt_command_set
  urt__command_check(m, d);

  // integrate; keep the start state so that a failed step can be undone
  double x0[URT_NJ][URT_NXJ];
  std::memcpy(x0, d->x, sizeof x0);
  urt::core::integrator_step(m, d, urt::core::kMacro, 0.0);

  // an implausible step is redone as fine steps of the whole model (rare: a few per second of
  // stick-slip; each costs about n_sub macro steps). simulation.refine_every forces the path on
  // every N-th step, so that its cost can be measured where healthy runs never take it.
  const bool forced = m->refine_every != 0 && (d->steps + 1) % m->refine_every == 0;
  if (forced || !step_plausible(m, d) || step_rough(m, d, x0)) {
    redo_as(m, d, x0, urt::core::kSub);
  }
  // still implausible: once more at a quarter of the sub-step. A backlash impact (the circular
  // spline's contact rings near 45 kHz on the shoulder) can shake a stuck wrist loose within
  // one step, a reversal that 5 µs sub-steps still overshoot (bristles beyond 1.5 g/σ0, seed 1
  // of the dataset demo's shoulder backlash at 1.45 and 2.9 mrad); 1.25 µs resolve it.
  if (!step_plausible(m, d)) {
    redo_as(m, d, x0, urt::core::kFine);
  }
  if (!step_plausible(m, d)) {
    std::memcpy(d->x, x0, sizeof x0);
    d->pstop |= URT_PSTOP_NONFINITE_STATE;
    urt__command_hold(d);
    return URT_ESOLVER;
  }

  urt__step_finish(m, d, x0);
  return URT_OK;
}

extern "C" void urt__step_finish(const urt_model_t* m, urt_data_t* d,
                                 const double (*x0)[URT_NXJ]) {
  const double h = m->dt;

  // time, mean accelerations over the step, and the command carried to the new step
  for (int j = 0; j < URT_NJ; j++) {
    d->qdd[j] = (d->x[j][URT_X_QD] - x0[j][URT_X_QD]) / h;
  }
  d->steps++;
  d->t = (double)d->steps * h;
  command_advance(d, h);

  // sample and hold the sensors for the next step; the outputs that show them are computed
  // at the rate someone reads them (urt_data_update_outputs), not at every physics step
  urt_sensors_sample(m, d);

  // the faults at the new step's start time: severities, effective parameters, sensor errors
  if (d->faults.s.n > 0) {
    urt_faults_advance(m, d);
  }
}

extern "C" void urt_rhs(const urt_model_t* m, const urt_data_t* d, double s, const double* x,
                        double* xdot) {
  using urt::core::Vec6;
  Vec6 tau, q, qd, tau_ext, bias;
  double w_tot[6];

  // joints: drives and friction; the arm's external wrench enters as Jᵀ F at the current q
  for (int j = 0; j < URT_NJ; j++) {
    urt::core::JointAux aux;
    const double* xj = x + j * URT_NXJ;
    tau[j] = urt::core::joint_rates(m, d, j, s, xj, xdot + j * URT_NXJ, &aux);
    q[j] = xj[URT_X_Q];
    qd[j] = xj[URT_X_QD];
  }
  urt::core::wrench_torque(m->arm, q, urt__wrench_total(d, w_tot), tau_ext);
  tau += tau_ext;

  // arm: the whole coupled 6-DoF forward dynamics, no splitting
  urt::core::Mat6 mass;
  urt_payload_t pl;
  urt::core::mass_and_bias(m->arm, *urt__payload_physics(d, &pl), q, qd, mass, bias);
  Vec6 qdd = mass.llt().solve(tau - bias);
  for (int j = 0; j < URT_NJ; j++) {
    xdot[j * URT_NXJ + URT_X_QD] = qdd[j];
  }
}
