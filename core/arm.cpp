// SPDX-License-Identifier: Apache-2.0
// core/arm.cpp — rigid-body kinematics and dynamics of the Hayati-DH chain (see arm.hpp for
// the frames and conventions), and the urt_arm_* C API over them.
#include "arm.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "urt/core.h"

namespace urt::core {
namespace detail {

// A plain 3-vector for the RNEA and CRBA loops. At -O2 Eigen's Vector3d goes through 2+1 SSE
// lanes with shuffles between them; the scalar loops measured 25–40 % faster on the dev
// machine (RNEA 245 against 325 ns, CRBA 300 against 500 ns). Kinematics stays Eigen.
struct V3 {
  double x, y, z;
};
inline V3 operator+(V3 a, V3 b) noexcept { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) noexcept { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, V3 a) noexcept { return {s * a.x, s * a.y, s * a.z}; }
inline V3& operator+=(V3& a, V3 b) noexcept { return a = a + b; }
inline double dot(V3 a, V3 b) noexcept { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline V3 v3(const Vec3& v) noexcept { return {v[0], v[1], v[2]}; }
inline V3 mul(const Mat3& R, V3 v) noexcept {  // R v
  return {R(0, 0) * v.x + R(0, 1) * v.y + R(0, 2) * v.z,
          R(1, 0) * v.x + R(1, 1) * v.y + R(1, 2) * v.z,
          R(2, 0) * v.x + R(2, 1) * v.y + R(2, 2) * v.z};
}
inline V3 tmul(const Mat3& R, V3 v) noexcept {  // Rᵀ v
  return {R(0, 0) * v.x + R(1, 0) * v.y + R(2, 0) * v.z,
          R(0, 1) * v.x + R(1, 1) * v.y + R(2, 1) * v.z,
          R(0, 2) * v.x + R(1, 2) * v.y + R(2, 2) * v.z};
}

// Symmetric 3×3 (an inertia tensor).
struct Sym3 {
  double xx, yy, zz, xy, xz, yz;
};
inline V3 mul(const Sym3& I, V3 v) noexcept {
  return {I.xx * v.x + I.xy * v.y + I.xz * v.z, I.xy * v.x + I.yy * v.y + I.yz * v.z,
          I.xz * v.x + I.yz * v.y + I.zz * v.z};
}

// Constant data of link i in its own DH frame i+1 (zero-based i).
struct Body {
  V3 s;        // joint axis                                     [-]
  V3 sv;       // linear part of the motion subspace S = (s; sv) [m]
  double m;    // mass                                           [kg]
  V3 h;        // first moment m·c                               [kg m]
  Sym3 I_o;    // rotational inertia about the frame origin      [kg m²]
};

// The six bodies' constants, gathered once per call and shared by RNEA and CRBA.
struct Bodies {
  Body b[URT_NJ];
};

inline void body(const urt_arm_params_t& a, int i, Body& b) noexcept {
  const urt_link_params_t& l = a.link[i];
  const double* F = a.fixed[i];

  // joint i turns about ẑ of the parent frame, through its origin. In frame i+1 that axis is
  // s = R_Fᵀ ẑ (row 2 of R_F), and the origin sits at p* = R_Fᵀ (t_F + d ẑ) from it, so the
  // motion subspace is S = (s; s × p*). urt_arm_prepare writes t_F = a x̂ (eq. 8), which
  // makes s × p* = a (row 2 × row 0 of R_F) = a · row 1 of R_F
  b.s = {F[8], F[9], F[10]};
  b.sv = {F[3] * F[4], F[3] * F[5], F[3] * F[6]};

  // spatial inertia about the frame origin from Table 5's CoM values (parallel axes),
  // I_o = I_c + m (|c|² 1 − c cᵀ)
  const double m = l.mass, cx = l.com[0], cy = l.com[1], cz = l.com[2];
  const double* J = l.inertia;  // Ixx Iyy Izz Ixy Ixz Iyz
  b.m = m;
  b.h = {m * cx, m * cy, m * cz};
  b.I_o = {J[0] + m * (cy * cy + cz * cz), J[1] + m * (cx * cx + cz * cz),
           J[2] + m * (cx * cx + cy * cy), J[3] - m * cx * cy,
           J[4] - m * cx * cz,             J[5] - m * cy * cz};
}

inline bool has_load(const urt_payload_t& p) noexcept {
  const double* J = p.inertia;
  return p.mass != 0.0 || J[0] != 0.0 || J[1] != 0.0 || J[2] != 0.0 || J[3] != 0.0 ||
         J[4] != 0.0 || J[5] != 0.0;
}

// Link 6 with the payload rigidly attached: masses, first moments and inertias about the frame
// origin add (the CoG is in the flange frame, which is link 6's DH frame). Without a payload the
// body is left as it is, so that a run without one keeps its bits.
inline void add_load(const urt_payload_t& p, Body& b) noexcept {
  if (!has_load(p)) {
    return;
  }
  const double m = p.mass, cx = p.cog[0], cy = p.cog[1], cz = p.cog[2];
  const double* J = p.inertia;
  b.m += m;
  b.h += V3{m * cx, m * cy, m * cz};
  b.I_o.xx += J[0] + m * (cy * cy + cz * cz);
  b.I_o.yy += J[1] + m * (cx * cx + cz * cz);
  b.I_o.zz += J[2] + m * (cx * cx + cy * cy);
  b.I_o.xy += J[3] - m * cx * cy;
  b.I_o.xz += J[4] - m * cx * cz;
  b.I_o.yz += J[5] - m * cy * cz;
}

inline void bodies(const urt_arm_params_t& a, const urt_payload_t& load, Bodies& B) noexcept {
  for (int i = 0; i < URT_NJ; ++i) {
    body(a, i, B.b[i]);
  }
  add_load(load, B.b[URT_NJ - 1]);
}

// Pose of the TCP in the flange frame (row-major 3×4 of tcp_fixed).
inline void tcp_offset(const urt_arm_params_t& a, Mat3& R, Vec3& p) noexcept {
  const double* T = a.tcp_fixed;
  R << T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10];
  p << T[3], T[7], T[11];
}

}  // namespace detail

//---- kinematics ----

void arm_kinematics(const urt_arm_params_t& a, const Vec6& q, ArmKinematics& k) noexcept {
  for (int i = 0; i < URT_NJ; ++i) {
    const double* F = a.fixed[i];

    // cos/sin of θ + q from the prepared cos/sin θ: one sincos per joint
    const double cq = std::cos(q[i]), sq = std::sin(q[i]);
    const double c = a.cos_theta[i] * cq - a.sin_theta[i] * sq;
    const double s = a.sin_theta[i] * cq + a.cos_theta[i] * sq;

    // A = Transl(z, d) Rot(z, θ + q) · [R_F | t_F]: Rot(z) mixes only the first two rows
    Mat3& R = k.R_PC[i];
    for (int col = 0; col < 3; ++col) {
      R(0, col) = c * F[col] - s * F[4 + col];
      R(1, col) = s * F[col] + c * F[4 + col];
      R(2, col) = F[8 + col];
    }
    k.p_PC[i] << c * F[3] - s * F[7], s * F[3] + c * F[7], F[11] + a.link[i].d;
  }
}

void arm_frame(const urt_arm_params_t& a, const Vec6& q, int i, Mat3& R_BF, Vec3& p_BF) noexcept {
  if (i < 0 || i > URT_NJ + 1) {
    R_BF.setConstant(std::numeric_limits<double>::quiet_NaN());
    p_BF.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  ArmKinematics k;
  arm_kinematics(a, q, k);

  // compose the chain up to frame i (frame 7 is the TCP on top of frame 6)
  R_BF.setIdentity();
  p_BF.setZero();
  const int n = i < URT_NJ ? i : URT_NJ;
  for (int j = 0; j < n; ++j) {
    p_BF += R_BF * k.p_PC[j];
    R_BF = R_BF * k.R_PC[j];
  }
  if (i == URT_NJ + 1) {
    Mat3 R_FT;
    Vec3 p_FT;
    detail::tcp_offset(a, R_FT, p_FT);
    p_BF += R_BF * p_FT;
    R_BF = R_BF * R_FT;
  }
}

void joint_axes(const urt_arm_params_t& a, const Vec6& q, Vec3 z[URT_NJ], Vec3 o[URT_NJ],
                Mat3& R_B6, Vec3& p_B6) noexcept {
  ArmKinematics k;
  arm_kinematics(a, q, k);

  // joint j turns about ẑ of frame j through its origin; collect both in the base frame
  R_B6.setIdentity();
  p_B6.setZero();
  for (int j = 0; j < URT_NJ; ++j) {
    z[j] = R_B6.col(2);
    o[j] = p_B6;
    p_B6 += R_B6 * k.p_PC[j];
    R_B6 = R_B6 * k.R_PC[j];
  }
}

void point_jacobian(const Vec3 z[URT_NJ], const Vec3 o[URT_NJ], const Vec3& p, Mat6& J) noexcept {
  for (int j = 0; j < URT_NJ; ++j) {
    J.block<3, 1>(0, j) = z[j].cross(p - o[j]);
    J.block<3, 1>(3, j) = z[j];
  }
}

void jacobian(const urt_arm_params_t& a, const Vec6& q, Mat6& J) noexcept {
  Vec3 z[URT_NJ], o[URT_NJ];
  Mat3 R;
  Vec3 p;
  joint_axes(a, q, z, o, R, p);
  Mat3 R_FT;
  Vec3 p_FT;
  detail::tcp_offset(a, R_FT, p_FT);
  point_jacobian(z, o, p + R * p_FT, J);
}

//---- dynamics ----

namespace detail {

void rnea(const urt_arm_params_t& a, const Bodies& B, const ArmKinematics& k, const Vec6& qd,
          const Vec6& qdd, Vec6& tau) noexcept {
  const Body* b = B.b;
  V3 n[URT_NJ], f[URT_NJ];

  // forward pass: body velocities and accelerations, each in its own frame; gravity is a base
  // acceleration of −g so the forces below already carry the weights
  V3 w = {0.0, 0.0, 0.0}, v = w, dw = w;
  V3 dv = {-a.gravity[0], -a.gravity[1], -a.gravity[2]};
  for (int i = 0; i < URT_NJ; ++i) {
    const Mat3& R = k.R_PC[i];
    const V3 p = v3(k.p_PC[i]);

    // carry the parent's motion to this frame's origin, then add the joint's own
    const V3 w_p = tmul(R, w);
    const V3 v_p = tmul(R, v - cross(p, w));
    const V3 dw_p = tmul(R, dw);
    const V3 dv_p = tmul(R, dv - cross(p, dw));
    const V3 ws = qd[i] * b[i].s, vs = qd[i] * b[i].sv;
    w = w_p + ws;
    v = v_p + vs;
    dw = dw_p + qdd[i] * b[i].s + cross(w_p, ws);
    dv = dv_p + qdd[i] * b[i].sv + cross(w_p, vs) + cross(v_p, ws);

    // body force f = I a + v ×* (I v), from the momenta about the origin
    const V3 L = mul(b[i].I_o, w) + cross(b[i].h, v);
    const V3 P = b[i].m * v - cross(b[i].h, w);
    n[i] = mul(b[i].I_o, dw) + cross(b[i].h, dv) + cross(w, L) + cross(v, P);
    f[i] = b[i].m * dv - cross(b[i].h, dw) + cross(w, P);
  }

  // backward pass: project on the joint axis, hand the rest to the parent
  for (int i = URT_NJ - 1; i >= 0; --i) {
    tau[i] = dot(b[i].s, n[i]) + dot(b[i].sv, f[i]);
    if (i > 0) {
      const V3 f_p = mul(k.R_PC[i], f[i]);
      f[i - 1] += f_p;
      n[i - 1] += mul(k.R_PC[i], n[i]) + cross(v3(k.p_PC[i]), f_p);
    }
  }
}

void crba(const Bodies& B, const ArmKinematics& k, Mat6& M) noexcept {
  const Body* b = B.b;

  // composite inertias (m, h, I about the frame origin) gather the subtree from the tip
  double m = 0.0;
  V3 h = {0.0, 0.0, 0.0};
  double I[3][3] = {};
  for (int i = URT_NJ - 1; i >= 0; --i) {
    const Sym3& J = b[i].I_o;
    m += b[i].m;
    h += b[i].h;
    I[0][0] += J.xx;
    I[1][1] += J.yy;
    I[2][2] += J.zz;
    I[0][1] = I[1][0] = I[0][1] + J.xy;
    I[0][2] = I[2][0] = I[0][2] + J.xz;
    I[1][2] = I[2][1] = I[1][2] + J.yz;

    // force the subtree needs for a unit rate of joint i, walked down to the base
    const V3 s = b[i].s, sv = b[i].sv;
    V3 n = V3{I[0][0] * s.x + I[0][1] * s.y + I[0][2] * s.z,
              I[1][0] * s.x + I[1][1] * s.y + I[1][2] * s.z,
              I[2][0] * s.x + I[2][1] * s.y + I[2][2] * s.z} + cross(h, sv);
    V3 f = m * sv - cross(h, s);
    M(i, i) = dot(s, n) + dot(sv, f);
    for (int j = i; j > 0; --j) {
      f = mul(k.R_PC[j], f);
      n = mul(k.R_PC[j], n) + cross(v3(k.p_PC[j]), f);
      M(i, j - 1) = M(j - 1, i) = dot(b[j - 1].s, n) + dot(b[j - 1].sv, f);
    }

    // express the composite in the parent's frame: rotate, then shift the origin by p,
    //   I' = R I Rᵀ + (2 p·h' + m |p|²) 1 − h' pᵀ − p h'ᵀ − m p pᵀ,   h' = R h + m p
    // (one triangle of the symmetric result, then mirrored)
    if (i > 0) {
      const Mat3& R = k.R_PC[i];
      const V3 hr = mul(R, h);
      const double p[3] = {k.p_PC[i][0], k.p_PC[i][1], k.p_PC[i][2]};
      const double g[3] = {hr.x, hr.y, hr.z};
      double T[3][3];  // I Rᵀ
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          T[r][c] = I[r][0] * R(c, 0) + I[r][1] * R(c, 1) + I[r][2] * R(c, 2);
        }
      }
      const double diag = 2.0 * (p[0] * g[0] + p[1] * g[1] + p[2] * g[2]) +
                          m * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int r = 0; r < 3; ++r) {
        for (int c = r; c < 3; ++c) {
          I[r][c] = I[c][r] = R(r, 0) * T[0][c] + R(r, 1) * T[1][c] + R(r, 2) * T[2][c] -
                              g[r] * p[c] - p[r] * g[c] - m * p[r] * p[c];
        }
        I[r][r] += diag;
      }
      h = hr + m * V3{p[0], p[1], p[2]};
    }
  }
}

// Solve M x = y in place (x holds y on entry) by Cholesky M = L Lᵀ, written out for 6×6:
// Eigen's in-place LLT goes through dynamic-size blocks, which costs more than the factoring.
// M is overwritten by L (lower triangle). Returns false if M is not positive definite.
bool cholesky_solve(Mat6& M, Vec6& x) noexcept {
  for (int j = 0; j < URT_NJ; ++j) {
    double d = M(j, j);
    for (int c = 0; c < j; ++c) {
      d -= M(j, c) * M(j, c);
    }
    if (!(d > 0.0)) {
      return false;
    }
    d = std::sqrt(d);
    M(j, j) = d;
    for (int r = j + 1; r < URT_NJ; ++r) {
      double s = M(r, j);
      for (int c = 0; c < j; ++c) {
        s -= M(r, c) * M(j, c);
      }
      M(r, j) = s / d;
    }
  }
  for (int r = 0; r < URT_NJ; ++r) {
    double s = x[r];
    for (int c = 0; c < r; ++c) {
      s -= M(r, c) * x[c];
    }
    x[r] = s / M(r, r);
  }
  for (int r = URT_NJ - 1; r >= 0; --r) {
    double s = x[r];
    for (int c = r + 1; c < URT_NJ; ++c) {
      s -= M(c, r) * x[c];
    }
    x[r] = s / M(r, r);
  }
  return true;
}

}  // namespace detail

void rnea(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
          const Vec6& qd, const Vec6& qdd, Vec6& tau) noexcept {
  detail::Bodies B;
  detail::bodies(a, load, B);
  detail::rnea(a, B, k, qd, qdd, tau);
}

void rnea(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q, const Vec6& qd,
          const Vec6& qdd, Vec6& tau) noexcept {
  ArmKinematics k;
  arm_kinematics(a, q, k);
  rnea(a, load, k, qd, qdd, tau);
}

void gravity(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
             Vec6& g) noexcept {
  using detail::V3;
  ArmKinematics k;
  arm_kinematics(a, q, k);

  // at rest only the base acceleration −g survives: each body carries m (−g) at its CoM
  V3 n[URT_NJ], f[URT_NJ];
  V3 dv = {-a.gravity[0], -a.gravity[1], -a.gravity[2]};
  for (int i = 0; i < URT_NJ; ++i) {
    const urt_link_params_t& l = a.link[i];
    dv = detail::tmul(k.R_PC[i], dv);
    f[i] = l.mass * dv;
    n[i] = detail::cross(V3{l.com[0], l.com[1], l.com[2]}, f[i]);
  }
  if (load.mass != 0.0) {  // the payload's weight at its CoG (its inertia needs no motion here)
    const V3 f_p = load.mass * dv;
    f[URT_NJ - 1] += f_p;
    n[URT_NJ - 1] += detail::cross(V3{load.cog[0], load.cog[1], load.cog[2]}, f_p);
  }
  for (int i = URT_NJ - 1; i >= 0; --i) {
    const double* F = a.fixed[i];  // the motion subspace as in detail::body
    const V3 s = {F[8], F[9], F[10]}, sv = {F[3] * F[4], F[3] * F[5], F[3] * F[6]};
    g[i] = detail::dot(s, n[i]) + detail::dot(sv, f[i]);
    if (i > 0) {
      const V3 f_p = detail::mul(k.R_PC[i], f[i]);
      f[i - 1] += f_p;
      n[i - 1] += detail::mul(k.R_PC[i], n[i]) + detail::cross(detail::v3(k.p_PC[i]), f_p);
    }
  }
}

void crba(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
          Mat6& M) noexcept {
  detail::Bodies B;
  detail::bodies(a, load, B);
  detail::crba(B, k, M);
}

void crba(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
          Mat6& M) noexcept {
  ArmKinematics k;
  arm_kinematics(a, q, k);
  crba(a, load, k, M);
}

void mass_and_bias(const urt_arm_params_t& a, const urt_payload_t& load, const ArmKinematics& k,
                   const Vec6& qd, Mat6& M, Vec6& bias) noexcept {
  detail::Bodies B;
  detail::bodies(a, load, B);
  detail::crba(B, k, M);
  detail::rnea(a, B, k, qd, Vec6::Zero(), bias);
}

void mass_and_bias(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
                   const Vec6& qd, Mat6& M, Vec6& bias) noexcept {
  ArmKinematics k;
  arm_kinematics(a, q, k);
  mass_and_bias(a, load, k, qd, M, bias);
}

bool forward_dynamics(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
                      const Vec6& qd, const Vec6& tau, Vec6& qdd) noexcept {
  Mat6 M;
  Vec6 bias;
  mass_and_bias(a, load, q, qd, M, bias);
  qdd = tau - bias;
  if (!detail::cholesky_solve(M, qdd)) {
    qdd.setConstant(std::numeric_limits<double>::quiet_NaN());
    return false;
  }
  return true;
}

double energy(const urt_arm_params_t& a, const urt_payload_t& load, const Vec6& q,
              const Vec6& qd) noexcept {
  using namespace detail;
  ArmKinematics k;
  arm_kinematics(a, q, k);
  Bodies B;
  bodies(a, load, B);
  const V3 g = {a.gravity[0], a.gravity[1], a.gravity[2]};

  // kinetic ½ vᵀ I v per body from the body velocities (equal to ½ qdᵀ M qd, without forming
  // M); potential −g·(m c) with each CoM placed in the base frame
  double e = 0.0;
  V3 w = {0.0, 0.0, 0.0}, v = w;
  Mat3 R_B = Mat3::Identity();
  Vec3 p_B = Vec3::Zero();
  for (int i = 0; i < URT_NJ; ++i) {
    const Body& b = B.b[i];
    const Mat3& R = k.R_PC[i];
    v = tmul(R, v - cross(v3(k.p_PC[i]), w)) + qd[i] * b.sv;
    w = tmul(R, w) + qd[i] * b.s;
    e += 0.5 * (dot(w, mul(b.I_o, w)) + b.m * dot(v, v)) + dot(w, cross(b.h, v));

    p_B += R_B * k.p_PC[i];
    R_B = R_B * R;
    e -= dot(g, b.m * v3(p_B) + mul(R_B, b.h));
  }
  return e;
}

//---- rotations ----

Mat3 rotation_from_rotvec(const Vec3& r) noexcept {
  // Rodrigues, R = 1 + (sin θ/θ) [r×] + ((1 − cos θ)/θ²) [r×]², with series near θ = 0
  const double t2 = r.squaredNorm();
  double A, B;
  if (t2 < 1e-12) {
    A = 1.0 - t2 / 6.0;
    B = 0.5 - t2 / 24.0;
  } else {
    const double t = std::sqrt(t2);
    A = std::sin(t) / t;
    B = (1.0 - std::cos(t)) / t2;
  }
  Mat3 K;
  K << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return Mat3::Identity() + A * K + B * K * K;
}

Vec3 rotvec_from_rotation(const Mat3& R) noexcept {
  // the skew part gives 2 sin θ · n, the trace 1 + 2 cos θ; atan2 of both keeps θ accurate
  // over all of [0, π]
  const Vec3 u(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const double s2 = u.norm();               // 2 sin θ
  const double c2 = R.trace() - 1.0;        // 2 cos θ
  const double t = std::atan2(s2, c2);

  // up to 90°, n = u / (2 sin θ) is well conditioned (series for θ/(2 sin θ) near 0)
  if (c2 > 0.0) {
    const double k = s2 > 1e-8 ? t / s2 : 0.5 + t * t / 12.0;
    return k * u;
  }

  // beyond 90°, sin θ → 0 near π, so take n from the symmetric part,
  // (R + Rᵀ)/2 = cos θ 1 + (1 − cos θ) n nᵀ, from its largest diagonal entry; the sign of n
  // comes from the skew part (arbitrary at exactly π, where both signs are the same rotation)
  const double c = 0.5 * c2;
  const Mat3 nn = (0.5 * (R + R.transpose()) - c * Mat3::Identity()) / (1.0 - c);
  int j = 0;
  nn.diagonal().maxCoeff(&j);
  Vec3 n = nn.col(j) / std::sqrt(nn(j, j));
  if (n.dot(u) < 0.0) {
    n = -n;
  }
  return t * n.normalized();
}

}  // namespace urt::core

//---- C API ----

namespace {

using urt::core::Mat3;
using urt::core::Mat6;
using urt::core::Vec3;
using urt::core::Vec6;
using RowMat6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

inline Vec6 vec6(const double* x) { return Eigen::Map<const Vec6>(x); }

// row-major 3×4 [R | p]
inline void put_3x4(double* T, const Mat3& R, const Vec3& p) {
  for (int r = 0; r < 3; ++r) {
    T[4 * r] = R(r, 0);
    T[4 * r + 1] = R(r, 1);
    T[4 * r + 2] = R(r, 2);
    T[4 * r + 3] = p[r];
  }
}

}  // namespace

extern "C" {

void urt_arm_prepare(urt_arm_params_t* a) {
  for (int i = 0; i < URT_NJ; ++i) {
    const urt_link_params_t& l = a->link[i];

    // Transl(x, a) · Rot(x, α) · Rot(y, β), the part of eq. (8) after the joint rotation
    const double ca = std::cos(l.alpha), sa = std::sin(l.alpha);
    const double cb = std::cos(l.beta), sb = std::sin(l.beta);
    Mat3 R;
    R << cb, 0.0, sb,
         sa * sb, ca, -sa * cb,
         -ca * sb, sa, ca * cb;
    put_3x4(a->fixed[i], R, Vec3(l.a, 0.0, 0.0));
    a->cos_theta[i] = std::cos(l.theta);
    a->sin_theta[i] = std::sin(l.theta);
  }
  const Vec3 p(a->tcp[0], a->tcp[1], a->tcp[2]);
  const Vec3 r(a->tcp[3], a->tcp[4], a->tcp[5]);
  put_3x4(a->tcp_fixed, urt::core::rotation_from_rotvec(r), p);
}

void urt_arm_tcp_pose(const urt_model_t* m, const double q[URT_NJ], double pose[6]) {
  Mat3 R;
  Vec3 p;
  urt::core::arm_frame(m->arm, vec6(q), URT_NJ + 1, R, p);
  const Vec3 r = urt::core::rotvec_from_rotation(R);
  for (int i = 0; i < 3; ++i) {
    pose[i] = p[i];
    pose[3 + i] = r[i];
  }
}

void urt_arm_frame(const urt_model_t* m, const double q[URT_NJ], int i, double T[16]) {
  Mat3 R;
  Vec3 p;
  urt::core::arm_frame(m->arm, vec6(q), i, R, p);
  put_3x4(T, R, p);
  T[12] = T[13] = T[14] = 0.0;
  T[15] = 1.0;
}

void urt_arm_jacobian(const urt_model_t* m, const double q[URT_NJ], double J[36]) {
  Mat6 Jc;
  urt::core::jacobian(m->arm, vec6(q), Jc);
  Eigen::Map<RowMat6>{J} = Jc;
}

void urt_arm_rnea(const urt_model_t* m, const double q[URT_NJ], const double qd[URT_NJ],
                  const double qdd[URT_NJ], double tau[URT_NJ]) {
  Vec6 t;
  urt::core::rnea(m->arm, m->payload, vec6(q), vec6(qd), vec6(qdd), t);
  Eigen::Map<Vec6>{tau} = t;
}

void urt_arm_mass_matrix(const urt_model_t* m, const double q[URT_NJ], double M[36]) {
  Mat6 Mc;
  urt::core::crba(m->arm, m->payload, vec6(q), Mc);
  Eigen::Map<RowMat6>{M} = Mc;
}

void urt_arm_gravity(const urt_model_t* m, const double q[URT_NJ], double g[URT_NJ]) {
  Vec6 t;
  urt::core::gravity(m->arm, m->payload, vec6(q), t);
  Eigen::Map<Vec6>{g} = t;
}

void urt_arm_forward_dynamics(const urt_model_t* m, const double q[URT_NJ],
                              const double qd[URT_NJ], const double tau[URT_NJ],
                              double qdd[URT_NJ]) {
  Vec6 a;
  urt::core::forward_dynamics(m->arm, m->payload, vec6(q), vec6(qd), vec6(tau), a);
  Eigen::Map<Vec6>{qdd} = a;
}

double urt_arm_energy(const urt_model_t* m, const double q[URT_NJ], const double qd[URT_NJ]) {
  return urt::core::energy(m->arm, m->payload, vec6(q), vec6(qd));
}

}  // extern "C"

namespace urt::core {

void wrench_torque(const urt_arm_params_t& a, const Vec6& q, const double w[6], Vec6& tau) noexcept {
  tau.setZero();
  bool any = false;
  for (int i = 0; i < 6; i++) {
    any = any || w[i] != 0.0;
  }
  if (!any) {
    return;
  }
  Mat6 J;
  jacobian(a, q, J);
  tau.noalias() = J.transpose() * Eigen::Map<const Vec6>(w);
}

}  // namespace urt::core
