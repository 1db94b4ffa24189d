// SPDX-License-Identifier: Apache-2.0
// core/controller_internal.hpp — kinematics with a runtime TCP offset, shared by the controller
// (core/controller.cpp) and the snapshot (core/snapshot.cpp). Internal. Context: RT.
#ifndef URT_CORE_CONTROLLER_INTERNAL_HPP
#define URT_CORE_CONTROLLER_INTERNAL_HPP

#include "arm.hpp"

namespace urt::core {

// The TCP (flange · offset, offset = x y z rx ry rz) at q: pose R_BT, p_BT in the base frame and,
// if J is not null, the geometric Jacobian of the TCP point, rows (v; ω), base frame.
// frames (optional, 7 entries): origin of every DH frame 0..6 in the base frame.
void tcp_kinematics(const urt_arm_params_t& a, const double tcp[6], const Vec6& q, Mat3& R_BT,
                    Vec3& p_BT, Mat6* J) noexcept;

// Solve J x = b by damped least squares, x = Jᵀ (J Jᵀ + λ² 1)⁻¹ b; λ = 0 gives the exact
// inverse (LU) for a well-conditioned J.
Vec6 dls_solve(const Mat6& J, const Vec6& b, double lambda) noexcept;

}  // namespace urt::core

#endif
