// SPDX-License-Identifier: Apache-2.0
// core/arm.hpp — rigid-body kinematics and dynamics of the 6-joint Hayati-DH chain
// (paper eqs. 8–9, Tables 4–5; model.md §1.8), for the integrator to call directly.
//
// Frames. Frame 0 is the base (the controller's Base frame); frame i (i = 1..6) is DH frame
// i, at the distal end of link i, so that
//   ^{i−1}A_i = Transl(z, d_i) · Rot(z, θ_i + q_i) · Transl(x, a_i) · Rot(x, α_i) · Rot(y, β_i).
// Joint i turns link i about z_{i−1}, the line through the origin of frame i−1. Link i's mass,
// CoM and inertia (about the CoM, axes of frame i) are given in frame i.
//
// Algorithms. Featherstone's spatial RNEA and CRBA, with every body quantity expressed in its
// own DH frame i. In those coordinates both the joint axis s_i = R_F^T ẑ and the joint's
// motion subspace S_i = (s_i; a_i R_F^T ŷ) are constant (R_F = Rot(x, α) Rot(y, β)), so
// only the 6 link transforms depend on q. A spatial motion (ω; v) has v = velocity of the
// body point at the frame origin; a spatial force (n; f) has n = moment about the origin.
// Gravity enters RNEA as a base acceleration −g. Every function reads the derived fields of
// urt_arm_params_t, so urt_arm_prepare() must have run.
//
// Everything here lives on the stack (fixed-size Eigen, plain arrays inside): no heap, no
// exceptions. Context: RT. Cost per call at -O2 on the dev machine (AMD EPYC, shared):
// arm_kinematics 80 ns (six sincos), rnea 245 ns, gravity 125 ns, crba 290 ns,
// mass_and_bias 470 ns, forward_dynamics 550 ns, jacobian 170 ns. Calls that share q
// should share the ArmKinematics (the overloads below take one).
#ifndef URT_CORE_ARM_HPP
#define URT_CORE_ARM_HPP

#include <Eigen/Core>

#include "urt/model.h"

namespace urt::core {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// The q-dependent link transforms: X_PC[i] is the pose of DH frame i+1 in frame i
// (R_PC rotation, p_PC origin of frame i+1 measured from frame i, in frame-i axes) [m].
struct ArmKinematics {
  Mat3 R_PC[URT_NJ];
  Vec3 p_PC[URT_NJ];
};

// Fill the link transforms for joint angles q [rad].
void arm_kinematics(const urt_arm_params_t& a, const Vec6& q, ArmKinematics& k) noexcept;

// Pose of frame i (0 = base, 1..6 = DH frames, 7 = TCP) in the base frame:
// R_BF rotation, p_BF origin [m]. i outside 0..7 gives NaN.
void arm_frame(const urt_arm_params_t& a, const Vec6& q, int i, Mat3& R_BF, Vec3& p_BF) noexcept;

// Geometric Jacobian of the TCP in the base frame: rows (v; ω), v of the TCP point.
void jacobian(const urt_arm_params_t& a, const Vec6& q, Mat6& J) noexcept;

// The joint axes at q, in the base frame: joint j turns about z[j] (ẑ of frame j) through o[j]
// (origin of frame j) [m]; R_B6, p_B6 is the flange pose (frame 6). With point_jacobian, what
// every geometric Jacobian here is built from (the TCP offset is the caller's).
void joint_axes(const urt_arm_params_t& a, const Vec6& q, Vec3 z[URT_NJ], Vec3 o[URT_NJ],
                Mat3& R_B6, Vec3& p_B6) noexcept;

// Geometric Jacobian of the point p (base frame) carried by the last link: rows (v; ω).
void point_jacobian(const Vec3 z[URT_NJ], const Vec3 o[URT_NJ], const Vec3& p, Mat6& J) noexcept;

// Joint torques of an external wrench (force; torque) [N, N m] applied at the TCP and given in
// the base frame: τ = Jᵀ w, frozen over a step. All zero (no Jacobian) when w is zero.
void wrench_torque(const urt_arm_params_t& a, const Vec6& q, const double w[6], Vec6& tau) noexcept;

// The dynamics below take the payload link 6 carries (`load`, in the flange frame) beside the
// arm: the arm's parameters are the model's and constant, the payload is the run's
// (urt_data_t.live.payload; the C API urt_arm_* uses the model's, urt_model_t.payload). It is
// added to link 6's body; an all-zero payload leaves every result bit for bit as without one.

// Inverse dynamics with gravity: tau = M(q) qdd + C(q, qd) qd + g(q) [N m].
void rnea(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q, const Vec6& qd,
          const Vec6& qdd, Vec6& tau) noexcept;
void rnea(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
          const Vec6& qd, const Vec6& qdd, Vec6& tau) noexcept;

// Gravity torque g(q) [N m] (RNEA without the velocity and acceleration terms).
void gravity(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
             Vec6& g) noexcept;

// Joint-space mass matrix M(q) by CRBA [kg m²]. Both triangles are written.
void crba(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q, Mat6& M) noexcept;
void crba(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
          Mat6& M) noexcept;

// M(q) and the bias torque b = C(q, qd) qd + g(q) from one set of link transforms: what a
// step needs to form qdd = M⁻¹ (tau − b).
void mass_and_bias(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
                   const Vec6& qd, Mat6& M, Vec6& bias) noexcept;
void mass_and_bias(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
                   const Vec6& qd, Mat6& M, Vec6& bias) noexcept;

// Forward dynamics qdd = M⁻¹ (tau − C qd − g) by Cholesky of M. Returns false (qdd NaN) if M
// is not positive definite, which only corrupt parameters can cause.
bool forward_dynamics(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
                      const Vec6& qd, const Vec6& tau, Vec6& qdd) noexcept;

// Kinetic energy ½ qdᵀ M qd plus potential energy −Σ m_i g·p_com_i (zero at the base
// origin) [J].
double energy(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
              const Vec6& qd) noexcept;

// Rotation ↔ axis-angle rotation vector (UR convention, angle in [0, π]).
Mat3 rotation_from_rotvec(const Vec3& r) noexcept;
Vec3 rotvec_from_rotation(const Mat3& R) noexcept;

}  // namespace urt::core

#endif
