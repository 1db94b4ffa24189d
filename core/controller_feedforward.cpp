// SPDX-License-Identifier: Apache-2.0
// core/controller_feedforward.cpp — the controller's model of the arm: inverse dynamics with the
// controller's gravity (SET_GRAVITY changes it, not the world's), the steady friction, the
// feed-forward torque every set-point carries, and the bound on any torque the controller hands
// the drives. No allocation. Context: RT.
//
// Feed-forward: τ_ff = RNEA(q, q̇, q̈) + friction(q̇) − τ_bias, with τ_bias = g(q_init):
// urt_data_init starts the speed-loop integrators carrying g(q_init), so the feed-forward adds
// only the change from there. The speed loop's integral time is ~10 s (P_vel/I_vel), far too
// slow to take up gravity changes within a move.
#include <cmath>
#include <cstring>

#include "controller_internal.hpp"
#include "urt/drivers/friction.h"

namespace urt::core {

namespace {

constexpr double kFrictionVEps = 2e-3;  // speed over which the friction feed-forward turns on [rad/s]

}  // namespace

// inverse dynamics of the controller's arm model: the model's, with the controller's gravity
// and the mounted payload
void ctrl_rnea(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
               const Vec6& q, const Vec6& qd, const Vec6& qdd, Vec6& tau) noexcept {
  if (std::memcmp(c->gravity, m->arm.gravity, sizeof c->gravity) == 0) {
    rnea(m->arm, load, q, qd, qdd, tau);
    return;
  }
  urt_arm_params_t a = m->arm;
  std::memcpy(a.gravity, c->gravity, sizeof a.gravity);
  rnea(a, load, q, qd, qdd, tau);
}

// steady-state LuGre friction (σ0 z = g(q̇) sign q̇), faded in over a small speed
double friction_ff(const urt_model_t* m, int j, double qd) noexcept {
  if (!m->friction[j].enabled) {
    return 0.0;
  }
  return urt_friction_g(&m->friction[j], qd) * std::tanh(qd / kFrictionVEps);
}

double feasible_accel(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
                      const double* q, const double* d) noexcept {
  Vec6 g, t;
  ctrl_rnea(m, c, load, vec6(q), Vec6::Zero(), Vec6::Zero(), g);
  ctrl_rnea(m, c, load, vec6(q), Vec6::Zero(), vec6(d), t);  // g + M d
  double A = HUGE_VAL;
  for (int j = 0; j < URT_NJ; j++) {
    const double md = std::fabs(t[j] - g[j]);
    if (md > 1e-12) {
      const double head = kOptTorqueShare * m->joint[j].torque_max - std::fabs(g[j]);
      A = std::fmin(A, std::fmax(head, 0.0) / md);
    }
  }
  return std::fmax(A, kOptMinAccel);
}

double feasible_joint_move_accel(const urt_model_t* m, const urt_ctrl_t* c,
                                 const urt_payload_t& load, const double* q_s, const double* dq,
                                 double D) noexcept {
  if (!(D > 0.0)) {
    return HUGE_VAL;
  }
  double d[URT_NJ], q[URT_NJ], A = HUGE_VAL;
  for (int j = 0; j < URT_NJ; j++) {
    d[j] = dq[j] / D;
  }
  for (int k = 0; k <= 2; k++) {  // start, middle, end
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = q_s[j] + 0.5 * k * dq[j];
    }
    A = std::fmin(A, feasible_accel(m, c, load, q, d));
  }
  return A;
}

double friction_ff_scaled(const urt_model_t* m, int j, double qd, double viscous,
                          double coulomb) noexcept {
  if (!m->friction[j].enabled || (viscous == 0.0 && coulomb == 0.0)) {
    return 0.0;
  }
  if (viscous == 1.0 && coulomb == 1.0) {
    return friction_ff(m, j, qd);  // the same bits as the whole model's feed-forward
  }
  const urt_friction_params_t& p = m->friction[j];
  const double g = urt_friction_g(&p, qd), visc = p.f_v * std::cbrt(qd * qd);
  return (coulomb * (g - visc) + viscous * visc) * std::tanh(qd / kFrictionVEps);
}

// the model feed-forward at a set-point
void model_torque(const urt_model_t* m, const urt_ctrl_t* c, const urt_payload_t& load,
                  const double* q, const double* qd, const double* qdd, double* tau) noexcept {
  Vec6 t;
  ctrl_rnea(m, c, load, vec6(q), vec6(qd), vec6(qdd), t);
  for (int j = 0; j < URT_NJ; j++) {
    tau[j] = t[j] + friction_ff(m, j, qd[j]) - c->tau_bias[j];
  }
}

// joint torques within what the drives (and urt_command_set) accept
double clamp_torque(const urt_model_t* m, int j, double tau) noexcept {
  const double lim = 0.999 * m->joint[j].torque_max;
  return std::fmax(-lim, std::fmin(lim, tau));
}

}  // namespace urt::core
