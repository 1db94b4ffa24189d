// SPDX-License-Identifier: Apache-2.0
// core/integrator.hpp — the fixed-step, non-autonomous, L-stable Rosenbrock-W scheme ROS2
// (Verwer et al. 1999; model.md §5.3) with the structured solve of model.md §5.6:
//
//   W = I − γ h J(t_n, x_n),   γ = 1 + 1/√2
//   W k1 = f(t_n, x_n) + γ h f_t
//   W k2 = f(t_n + h, x_n + h k1) − 2 k1 − γ h f_t
//   x_{n+1} = x_n + (3/2) h k1 + (1/2) h k2
//
// Each joint's 18-state drive block is affine within a saturation active set, so
// (I − γ h A_d)⁻¹ and its coupling to (q, q̇) are precomputed per active set and step size.
// Substituting them, the per-joint LuGre z and q rows turns each stage solve into one 6×6
// SPD system (M(q_n) − γ h diag(c1)) k_q̇ = M r_q̇ + γ h c0, solved by Cholesky.
//
// Joints whose output inertia is too small for the Stribeck slope at h (wrist 3: model.md
// §5.3e) are sub-stepped, while they are slower than twice the speed where the dip ends and
// not stuck (bristles within half the Coulomb level at |q̇| < 1e-3 rad/s: then the macro step
// carries them), as 1-DoF systems with their arm coupling frozen over the macro step
// (inertia M_jj and bias from the macro step's start and the other joints' accelerations
// from the previous step); the macro step then sees their mean acceleration as prescribed.
#ifndef URT_CORE_INTEGRATOR_HPP
#define URT_CORE_INTEGRATOR_HPP

#include "joint.hpp"
#include "urt/core.h"

namespace urt::core {

constexpr double kGamma = 1.7071067811865475244;  // 1 + 1/√2: L-stable ROS2

// Tables for one joint at one step size and one active set.
struct DriveTables {
  double winv[URT_NXD * URT_NXD];  // (I − γ h A_d)⁻¹, column-major
  double winv_bq[URT_NXD];         // (I − γ h A_d)⁻¹ ∂f_d/∂q   (input from the arm angle)
  double bd[URT_NXD];              // k_d = W⁻¹ r_d + γ h W⁻¹ B_q r_q + bd · k_q̇
  double fq_set[URT_NXD];          // ∂f_d/∂q_set    (for the ∂f/∂t term)
  double fqd_set[URT_NXD];         // ∂f_d/∂q̇_set
  // 1: rows 16–17 of winv (the joint-position filter, driven by q alone) are zero in columns
  // 0–15, so the solve leaves those products out (set by integrator_prepare from the numbers)
  int filter_rows_apart;
};

// kFine: a step that stays implausible as sub-steps is redone once more, each sub-step as
// kFinePerSub steps of this size (urt_step)
enum StepKind { kMacro = 0, kSub = 1, kFine = 2, kNumStepKinds = 3 };
constexpr int kFinePerSub = 4;

}  // namespace urt::core

// The integrator's precomputed tables, owned by the model.
struct urt_integrator_tables {
  double h[urt::core::kNumStepKinds];   // macro step, sub-step and fine step [s]
  int n_sub;                            // sub-steps per macro step
  int substepped[URT_NJ];               // 1: joint j is sub-stepped (while |q̇| < v_sub)
  double v_sub[URT_NJ];                 // a sub-stepped joint's macro step splits it off only
                                        // below this speed: twice where its Stribeck dip ends
                                        // (g' < 0 nowhere above) [rad/s]
  double g_slope_min[URT_NJ];           // most negative dg/dq̇ of the friction law [N m s/rad]
  double j_out[URT_NJ];                 // smallest output inertia M_jj + J_CS seen [kg m²]
  double z_max[URT_NJ];                 // LuGre bound g(q̇_max)/σ0 on |z| (0: no friction) [rad]
  urt::core::DriveTables t[URT_NJ][urt::core::kNumStepKinds][urt::core::kNumActiveSets];
};

namespace urt::core {

// Build the tables for a prepared model. Context: non-RT. Returns 0 or URT_ESOLVER.
int integrator_prepare(const urt_model_t* m, urt_integrator_tables* tab) noexcept;

// One step of kind kMacro (size m->dt, the stiff-friction joints sub-stepped) or kSub (the
// sub-step size, every joint together), starting s0 seconds into the current command. The
// caller handles sensors, outputs and the plausibility check. Context: RT.
void integrator_step(const urt_model_t* m, urt_data_t* d, int kind, double s0) noexcept;

}  // namespace urt::core

#endif
