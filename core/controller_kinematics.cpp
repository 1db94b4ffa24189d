// SPDX-License-Identifier: Apache-2.0
// core/controller_kinematics.cpp — the controller's kinematics with a runtime TCP offset: the
// TCP pose and Jacobian (shared with the snapshot), the damped least-squares solve of J x = b,
// and urt/controller.h's forward and inverse kinematics. IK runs Newton on the calibrated chain,
// from the previous set-point or from the closed-form seeds of the nominal UR chain. Fixed-size
// Eigen on the stack, no allocation, no exceptions. Context: RT.
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "controller_internal.hpp"
#include "urt/controller.h"
#include "urt/core.h"

namespace urt::core {

// ---- kinematics shared with the snapshot ----

void tcp_kinematics(const urt_arm_params_t& a, const double tcp[6], const Vec6& q, Mat3& R_BT,
                    Vec3& p_BT, Mat6* J) noexcept {
  Vec3 z[URT_NJ], o[URT_NJ];
  Mat3 R;
  Vec3 p;
  joint_axes(a, q, z, o, R, p);
  const Vec3 p_FT(tcp[0], tcp[1], tcp[2]);
  R_BT = R * rotation_from_rotvec(Vec3(tcp[3], tcp[4], tcp[5]));
  p_BT = p + R * p_FT;
  if (J) {
    point_jacobian(z, o, p_BT, *J);
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

}  // extern "C"
