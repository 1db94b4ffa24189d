// SPDX-License-Identifier: Apache-2.0
// core/integrator.cpp — ROS2 with the structured per-joint solve. The scheme and the
// splitting are described in integrator.hpp; the model equations in the drivers' headers.
#include "integrator.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <utility>

#include "arm.hpp"
#include "step_internal.h"
#include "urt/drivers/friction.h"

namespace urt::core {
namespace {

// Below this joint speed [rad/s] the friction Jacobian in W is the mean of its two sides.
constexpr double kStickSpeed = 1e-3;

// A sub-stepped joint that its bristles hold (stick) is left in the macro step: below
// kStickSpeed, with the bristle torque σ0 |z|, plus what this speed adds to it over two
// steps, within this fraction of the lowest level g can take (f_c on the weaker side; g ≥ f_c,±
// at every speed). There T_f = σ0 z + σ1 ż with ∂ż/∂q̇ = 1 − σ0 z sgn(q̇) (1/g − |q̇| g'/g²)
// about in (0.5, 1.5) (|q̇| g'/g is below 0.01 there and → 0 at rest): a damping of at least
// σ1/2 = 50 N m s/rad, far above the Stribeck slope the sub-steps exist for (−0.16 on the
// wrists, which acts only in sliding, z near g/σ0); and ∂ż/∂z = −σ0 |q̇|/g ≤ 0. A stiff, stable
// spring-damper that the L-stable W carries like the gear's springs, coupled to the arm
// instead of frozen. Nearer breakaway, or faster, the joint is sub-stepped as before.
constexpr double kStuckMargin = 0.5;

bool joint_stuck(const urt_model_t* m, const urt_data_t* d, int j, double h) noexcept {
  const urt_friction_params_t& fp =
      ((d->faults.joint_mask >> j) & 1u) ? d->faults.joint[j].friction : m->friction[j];
  const double qd = std::fabs(d->x[j][URT_X_QD]);
  const double t_bristle = fp.sigma0 * (std::fabs(d->x[j][URT_X_Z]) + 2.0 * h * qd);
  return qd < kStickSpeed && t_bristle < kStuckMargin * fp.f_c * (1.0 - std::fabs(fp.asym));
}

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using VecD = Eigen::Matrix<double, URT_NXD, 1>;
using MatD = Eigen::Matrix<double, URT_NXD, URT_NXD>;  // column-major, as the tables store it

//---- the per-joint part of the W solve ----

// Everything the stage solves need about one joint, frozen at the start of the (sub)step.
struct JointW {
  const DriveTables* tab;
  int engaged;
  double gh;           // γ h
  double k_cs, c_cs;   // output spring of the gear [N m/rad, N m s/rad]
  double a_zz;         // ∂ż/∂z
  double f_z;          // k_z = e_z + f_z k_q̇
  double t_z, t_qd;    // ∂T_f/∂z, ∂T_f/∂q̇
  double c1;           // δT_net = c0 + c1 k_q̇
};

// From the rates just evaluated at the (sub)step's start: aux gives the active set and the
// friction partials there, qd the joint speed.
void joint_w_init(const urt_model_t* m, int j, int kind, const JointAux& aux, double qd,
                  JointW* w) noexcept {
  const urt_integrator_tables* tab = m->tables;
  const urt_friction_params_t& fp = m->friction[j];
  w->tab = &tab->t[j][kind][aux.active_set];
  w->engaged = m->drives_engaged;
  w->gh = kGamma * tab->h[kind];
  // in a backlash gap the output spring carries nothing (its tables are the gap set's)
  const bool gap = (aux.active_set & kGearGap) != 0;
  w->k_cs = gap ? 0.0 : m->gear[j].k_cs;
  w->c_cs = gap ? 0.0 : m->gear[j].c_cs;

  // LuGre linearisation: T_f = σ0 z + σ1 ż, ż = q̇ − σ0 |q̇| z / g
  // ∂ż/∂q̇ = 1 − σ0 z ∂(|q̇|/g)/∂q̇ jumps with sgn(q̇) at rest (0 ↔ 2 for a loaded bristle).
  // A W that follows that sign while q̇ dithers around 0 alternates between two wrong
  // linearisations and pumps z at the Nyquist rate; near rest W takes the mean of both sides.
  const urt_friction_out_t& fr = aux.fr;
  // min(1, |q̇|/v) as a compare: std::fmin is a libm call here (its NaN rule: a NaN speed gives
  // 1, as this does) and the only call left in the per-joint setup
  double ratio = std::fabs(qd) / kStickSpeed;
  double blend = ratio < 1.0 ? ratio : 1.0;
  double a_zqd = 1.0 - (1.0 - fr.ddz_dqd) * blend;
  w->a_zz = fr.ddz_dz;
  w->f_z = w->gh * a_zqd / (1.0 - w->gh * fr.ddz_dz);
  w->t_z = fp.enabled ? fp.sigma0 + fp.sigma1 * fr.ddz_dz : 0.0;
  w->t_qd = fp.enabled ? fp.sigma1 * a_zqd : 0.0;

  // the joint's torque as an affine function of its k_q̇: drive block and q row substituted
  w->c1 = -(w->t_z * w->f_z + w->t_qd);
  if (w->engaged) {
    const double* bd = w->tab->bd;
    w->c1 += w->k_cs * bd[URT_X_QCS] + w->c_cs * bd[URT_X_QDCS] - w->k_cs * w->gh - w->c_cs;
  }
}

// a = W⁻¹ r_d for the 18×18 column-major table: each row one multiply-add chain over the
// columns in order, from zero. That is the accumulation Eigen's general matrix-vector kernel
// uses for this size (rows 0–15 in four 4-lanes, rows 16–17 in a 2-lane), so the result is
// the same to the bit; but the kernel's run-time blocking cost more than the arithmetic, and
// here the 18 sums stay in registers. GCC vector types: AVX/FMA where -march has them.
// extra_col · extra, the arm angle's input column, ends the chain as Eigen's a += s v did.
// With rows_apart (rows 16–17 zero in columns 0–15) the 2-lane skips those columns: it would
// only add 0·r = ±0 to +0, which leaves +0, so the sums are the same bits for any finite r (a
// non-finite r fills rows 0–15 with NaN either way, and the step is refused and redone).
typedef double V4 __attribute__((vector_size(32)));
typedef double V2 __attribute__((vector_size(16)));
static_assert(URT_NXD == 18, "drive_solve is written for 18 drive states");

template <bool rows_apart>
inline void drive_solve(const double* winv, const double* r, const double* extra_col,
                        double extra, double* a) noexcept {
  V4 c0 = {0.0, 0.0, 0.0, 0.0}, c1 = c0, c2 = c0, c3 = c0;
  V2 c4 = {0.0, 0.0};
  auto column16 = [&](const double* col, double b) {
    V4 l0, l1, l2, l3;
    std::memcpy(&l0, col, sizeof l0);
    std::memcpy(&l1, col + 4, sizeof l1);
    std::memcpy(&l2, col + 8, sizeof l2);
    std::memcpy(&l3, col + 12, sizeof l3);
    c0 = l0 * b + c0;
    c1 = l1 * b + c1;
    c2 = l2 * b + c2;
    c3 = l3 * b + c3;
  };
  auto column = [&](const double* col, double b) {
    column16(col, b);
    V2 l4;
    std::memcpy(&l4, col + 16, sizeof l4);
    c4 = l4 * b + c4;
  };
  constexpr int kSplit = rows_apart ? URT_NXD - 2 : 0;
  for (int c = 0; c < kSplit; c++) {
    column16(winv + c * URT_NXD, r[c]);
  }
  for (int c = kSplit; c < URT_NXD; c++) {
    column(winv + c * URT_NXD, r[c]);
  }
  column(extra_col, extra);
  std::memcpy(a, &c0, sizeof c0);
  std::memcpy(a + 4, &c1, sizeof c1);
  std::memcpy(a + 8, &c2, sizeof c2);
  std::memcpy(a + 12, &c3, sizeof c3);
  std::memcpy(a + 16, &c4, sizeof c4);
}

// Partial solve of one joint's rows for a stage right-hand side r (21): a_d and e_z are the
// parts of k_d and k_z that do not depend on k_q̇; returns c0.
double joint_reduce(const JointW& w, const double* r, VecD& a_d, double* e_z) noexcept {
  *e_z = r[URT_X_Z] / (1.0 - w.gh * w.a_zz);
  double c0 = -w.t_z * *e_z;
  if (w.engaged) {
    if (w.tab->filter_rows_apart) {
      drive_solve<true>(w.tab->winv, r, w.tab->winv_bq, w.gh * r[URT_X_Q], a_d.data());
    } else {
      drive_solve<false>(w.tab->winv, r, w.tab->winv_bq, w.gh * r[URT_X_Q], a_d.data());
    }
    c0 += w.k_cs * a_d[URT_X_QCS] + w.c_cs * a_d[URT_X_QDCS] - w.k_cs * r[URT_X_Q];
  }
  return c0;
}

// Back-substitution once k_q̇ is known.
void joint_backsub(const JointW& w, const double* r, const VecD& a_d, double e_z, double k_qd,
                   double* k) noexcept {
  if (w.engaged) {
    // k may alias a_d and bd as far as the compiler knows, which kept this loop scalar; with
    // the pointers declared apart it is vectorised (the same multiply-add per entry)
    double* __restrict kd = k;
    const double* __restrict ad = a_d.data();
    const double* __restrict bd = w.tab->bd;
    for (int i = 0; i < URT_NXD; i++) {
      kd[i] = ad[i] + bd[i] * k_qd;
    }
  } else {
    for (int i = 0; i < URT_NXD; i++) {
      k[i] = 0.0;
    }
  }
  k[URT_X_QD] = k_qd;
  k[URT_X_Q] = r[URT_X_Q] + w.gh * k_qd;
  k[URT_X_Z] = e_z + w.f_z * k_qd;
}

// ∂f/∂t of the drive rows: the set-point moves (model.md §5.3a, detail i).
void drive_ft(const JointW& w, const urt_command_t& c, int j, double s, double* ft) noexcept {
  double qd_set = c.qd[j] + c.qdd[j] * s;
  // each entry written once (the drive rows, or zero), the arm rows q, q̇, z zero
  if (w.engaged) {
    for (int i = 0; i < URT_NXD; i++) {
      ft[i] = w.tab->fq_set[i] * qd_set + w.tab->fqd_set[i] * c.qdd[j];
    }
  } else {
    for (int i = 0; i < URT_NXD; i++) {
      ft[i] = 0.0;
    }
  }
  for (int i = URT_NXD; i < URT_NXJ; i++) {
    ft[i] = 0.0;
  }
}

//---- arm ----

// The arm's accelerations for the macro joints given the joint torques, M(q) and the bias
// h = C q̇ + g at q̈ = 0, with the sub-stepped joints' accelerations prescribed. Rows and
// columns of prescribed joints are replaced by identity in M so that one 6×6 Cholesky serves
// (the macro block stays SPD); mass is overwritten with that masked matrix.
void arm_accel(const int* sub, const Vec6& tau, const Vec6& qdd_pres, Mat6& mass,
               const Vec6& h0, Vec6& qdd) noexcept {
  Vec6 qdd_known;
  for (int j = 0; j < URT_NJ; j++) {
    qdd_known[j] = sub[j] ? qdd_pres[j] : 0.0;
  }
  Vec6 rhs = tau - h0 - mass * qdd_known;
  for (int j = 0; j < URT_NJ; j++) {
    if (sub[j]) {
      mass.row(j).setZero();
      mass.col(j).setZero();
      mass(j, j) = 1.0;
      rhs[j] = qdd_pres[j];
    }
  }
  qdd = mass.llt().solve(rhs);
}

// f(t_n + s, X) for the macro joints (all 21 rates) and q, q̇ rates of the sub-stepped ones.
// mass and h0: M and the q̈ = 0 bias at x when the caller has them (have_arm), else computed
// here; on return mass is the masked matrix of arm_accel.
void macro_rates(const urt_model_t* m, const urt_data_t* d, const int* sub, double s,
                 const double (*x)[URT_NXJ], const Vec6& tau_ext, const Vec6& qdd_pres,
                 double (*f)[URT_NXJ], JointAux* aux, bool have_arm, Mat6& mass,
                 Vec6& h0) noexcept {
  Vec6 tau;
  for (int j = 0; j < URT_NJ; j++) {
    if (sub[j]) {
      std::memset(f[j], 0, sizeof f[j]);
      f[j][URT_X_Q] = x[j][URT_X_QD];
      tau[j] = 0.0;
      continue;
    }
    tau[j] = joint_rates(m, d, j, s, x[j], f[j], &aux[j]) + tau_ext[j];
  }
  if (!have_arm) {
    Vec6 q, qd;
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = x[j][URT_X_Q];
      qd[j] = x[j][URT_X_QD];
    }
    urt_payload_t pl;
    mass_and_bias(m->arm, *urt__payload_physics(d, &pl), q, qd, mass, h0);
  }
  Vec6 qdd;
  arm_accel(sub, tau, qdd_pres, mass, h0, qdd);
  for (int j = 0; j < URT_NJ; j++) {
    f[j][URT_X_QD] = qdd[j];
  }
}

// Adds γh B_q̇ + (γh)² B_q to the W matrix of the arm rows and returns B_q (the q rows enter
// the right-hand side too: k_q = r_q + γh k_q̇). Sub-stepped joints keep identity rows.
void arm_linearisation(const urt_model_t* m, const urt_payload_t& load, const int* sub,
                       const double (*x)[URT_NXJ],
                       const double (*f)[URT_NXJ], Mat6& bq, Mat6& wmat, double gh) noexcept {
  Vec6 q, qd, a, t0, t1;
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = x[j][URT_X_Q];
    qd[j] = x[j][URT_X_QD];
    a[j] = f[j][URT_X_QD];
  }
  Mat6 bqd;
  rnea(m->arm, load, q, qd, a, t0);
  for (int c = 0; c < URT_NJ; c++) {
    double eq = 1e-7 * (1.0 + std::fabs(q[c])), ev = 1e-7 * (1.0 + std::fabs(qd[c]));
    Vec6 qp = q;
    qp[c] += eq;
    rnea(m->arm, load, qp, qd, a, t1);
    bq.col(c) = (t1 - t0) / eq;
    Vec6 qdp = qd;
    qdp[c] += ev;
    rnea(m->arm, load, q, qdp, a, t1);
    bqd.col(c) = (t1 - t0) / ev;
  }
  for (int j = 0; j < URT_NJ; j++) {
    if (sub[j]) {
      bq.row(j).setZero();
      bq.col(j).setZero();
      bqd.row(j).setZero();
      bqd.col(j).setZero();
    }
  }
  wmat.noalias() += gh * bqd + (gh * gh) * bq;
}

//---- the 6×6 stage matrix ----

// LU with partial pivoting of the (unsymmetric) stage matrix, the same arithmetic as Eigen's
// PartialPivLU<Mat6> (its unblocked kernel for fixed sizes up to 16: pivot on the first
// largest |a_ik|, swap whole rows, divide the column by the pivot, rank-1 update; the last
// row is not pivoted), so factors and solutions keep their bits. Eigen's compute() goes
// through run-time-sized blocks and also takes the L1 norm for rcond(), which nothing here
// reads; written out, the factorisation costs a fraction.
struct Lu6 {
  Mat6 lu;
  int tr[URT_NJ];  // row k was swapped with row tr[k] at step k
};

void lu6_factor(const Mat6& a, Lu6& f) noexcept {
  Mat6& lu = f.lu;
  lu = a;
  for (int k = 0; k < URT_NJ - 1; k++) {
    int p = k;
    double big = std::fabs(lu(k, k));
    for (int i = k + 1; i < URT_NJ; i++) {
      double v = std::fabs(lu(i, k));
      if (v > big) {
        big = v;
        p = i;
      }
    }
    f.tr[k] = p;
    if (big != 0.0) {
      if (p != k) {
        lu.row(k).swap(lu.row(p));
      }
      for (int i = k + 1; i < URT_NJ; i++) {
        lu(i, k) /= lu(k, k);
      }
    }
    for (int c = k + 1; c < URT_NJ; c++) {
      for (int i = k + 1; i < URT_NJ; i++) {
        lu(i, c) -= lu(i, k) * lu(k, c);
      }
    }
  }
  f.tr[URT_NJ - 1] = URT_NJ - 1;
}

// x = A⁻¹ b: the row swaps in order, then Eigen's own unrolled triangular solves.
Vec6 lu6_solve(const Lu6& f, const Vec6& b) noexcept {
  Vec6 x = b;
  for (int k = 0; k < URT_NJ; k++) {
    std::swap(x[k], x[f.tr[k]]);
  }
  f.lu.triangularView<Eigen::UnitLower>().solveInPlace(x);
  f.lu.triangularView<Eigen::Upper>().solveInPlace(x);
  return x;
}

//---- sub-stepped joints ----

// One joint as a 1-DoF system on the frozen arm: M_pp q̈ = T_net + τ_ext − b.
double sub_rates(const urt_model_t* m, const urt_data_t* d, int p, double s, const double* x,
                 double m_pp, double b, double tau_ext, double* f, JointAux* aux) noexcept {
  double t_net = joint_rates(m, d, p, s, x, f, aux);
  f[URT_X_QD] = (t_net + tau_ext - b) / m_pp;
  return t_net;
}

// Advances x, joint p's 21 states, over one macro step in n_sub sub-steps.
void substep_joint(const urt_model_t* m, const urt_data_t* d, int p, double m_pp, double b,
                   double tau_ext, double s0, double* x) noexcept {
  const urt_integrator_tables* tab = m->tables;
  const double h = tab->h[kSub];
  double f[URT_NXJ], ft[URT_NXJ], r[URT_NXJ], k1[URT_NXJ], k2[URT_NXJ], x2[URT_NXJ];
  JointAux aux;
  JointW w;
  VecD a_d;
  double e_z;

  for (int n = 0; n < tab->n_sub; n++) {
    double s = s0 + n * h;

    // stage 1 at the sub-step's start, where W is frozen
    sub_rates(m, d, p, s, x, m_pp, b, tau_ext, f, &aux);
    joint_w_init(m, p, kSub, aux, x[URT_X_QD], &w);
    double den = m_pp - w.gh * w.c1;
    drive_ft(w, d->cmd, p, s, ft);
    for (int i = 0; i < URT_NXJ; i++) {
      r[i] = f[i] + w.gh * ft[i];
    }
    double c0 = joint_reduce(w, r, a_d, &e_z);
    joint_backsub(w, r, a_d, e_z, (m_pp * r[URT_X_QD] + w.gh * c0) / den, k1);

    // stage 2 at the sub-step's end
    for (int i = 0; i < URT_NXJ; i++) {
      x2[i] = x[i] + h * k1[i];
    }
    sub_rates(m, d, p, s + h, x2, m_pp, b, tau_ext, f, &aux);
    for (int i = 0; i < URT_NXJ; i++) {
      r[i] = f[i] - 2.0 * k1[i] - w.gh * ft[i];
    }
    c0 = joint_reduce(w, r, a_d, &e_z);
    joint_backsub(w, r, a_d, e_z, (m_pp * r[URT_X_QD] + w.gh * c0) / den, k2);

    for (int i = 0; i < URT_NXJ; i++) {
      x[i] += h * (1.5 * k1[i] + 0.5 * k2[i]);
    }
  }
}

}  // namespace

//---- one macro step ----

void integrator_step(const urt_model_t* m, urt_data_t* d, int kind, double s0) noexcept {
  const urt_integrator_tables* tab = m->tables;
  const double h = tab->h[kind];
  double (*x)[URT_NXJ] = d->x;

  // a fine step (kind kSub or kFine) takes every joint at its size, with no splitting. A
  // stiff-friction joint is split off only while it is in or near its Stribeck dip (|q̇| below
  // v_sub, twice the dip's end): the negative slope the sub-steps exist for lies there, and so
  // do the stick-to-slip reversals. Faster, its slope is a positive damping that the macro
  // step's W carries like any other joint's; stuck (joint_stuck), so is its bristles' spring
  int sub[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    sub[j] = kind == kMacro && tab->substepped[j] &&
             !(std::fabs(x[j][URT_X_QD]) >= tab->v_sub[j]) && !joint_stuck(m, d, j, h);
  }

  Vec6 tau_ext, q_n;
  for (int j = 0; j < URT_NJ; j++) {
    q_n[j] = x[j][URT_X_Q];
  }
  double w_tot[6];
  wrench_torque(m->arm, q_n, urt__wrench_total(d, w_tot), tau_ext);

  // the arm at x_n, once for the sub-steps and the macro step's first stage
  Mat6 mass_n;
  Vec6 h_n;
  {
    Vec6 q, qd;
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = x[j][URT_X_Q];
      qd[j] = x[j][URT_X_QD];
    }
    urt_payload_t pl;
    mass_and_bias(m->arm, *urt__payload_physics(d, &pl), q, qd, mass_n, h_n);
  }
  // sub-stepped joints first, on the arm frozen at t_n: their inertia M_pp and bias
  // (Coriolis, gravity, and the other joints' accelerations through M_pk)
  Vec6 qdd_pres = Vec6::Zero();
  double sub_end[URT_NJ][URT_NXJ];
  bool any_sub = false;
  for (int p = 0; p < URT_NJ; p++) {
    any_sub = any_sub || sub[p];
  }
  if (any_sub) {
    for (int p = 0; p < URT_NJ; p++) {
      if (!sub[p]) {
        continue;
      }
      // every other joint pushes through M_pk with its acceleration. Driven joints follow
      // their set-point, so its q̈ is the smooth estimate; the last step's mean q̈ carries the
      // drives' Nyquist-rate ripple into this joint as torque noise (79 % RMS current error
      // on wrist 1 at 10 kHz). Free joints have only their last mean q̈.
      Vec6 qdd_other;
      for (int j = 0; j < URT_NJ; j++) {
        qdd_other[j] = j == p ? 0.0 : (m->drives_engaged ? d->cmd.qdd[j] : d->qdd[j]);
      }
      double bias_p = h_n[p] + mass_n.row(p).dot(qdd_other);

      // the joint runs ahead on a copy; the macro step integrates its q, q̇ from t_n with the
      // mean acceleration, then takes the copy as the joint's end state
      std::memcpy(sub_end[p], x[p], sizeof sub_end[p]);
      substep_joint(m, d, p, mass_n(p, p), bias_p, tau_ext[p], s0, sub_end[p]);
      qdd_pres[p] = (sub_end[p][URT_X_QD] - x[p][URT_X_QD]) / h;
    }
  }

  // stage 1: f(t_n, x_n), W from the active sets and friction slopes at x_n
  double f[URT_NJ][URT_NXJ], k1[URT_NJ][URT_NXJ], k2[URT_NJ][URT_NXJ], x2[URT_NJ][URT_NXJ];
  double r[URT_NJ][URT_NXJ], ft[URT_NJ][URT_NXJ];
  JointAux aux[URT_NJ];
  JointW w[URT_NJ];
  VecD a_d[URT_NJ];
  double e_z[URT_NJ];
  Mat6 mm = mass_n;
  macro_rates(m, d, sub, s0, x, tau_ext, qdd_pres, f, aux, true, mm, h_n);

  Mat6 wmat = mm;
  const double gh = kGamma * h;
  for (int j = 0; j < URT_NJ; j++) {
    if (sub[j]) {
      std::memset(ft[j], 0, sizeof ft[j]);
      continue;
    }
    joint_w_init(m, j, kind, aux[j], x[j][URT_X_QD], &w[j]);
    wmat(j, j) -= gh * w[j].c1;
    drive_ft(w[j], d->cmd, j, s0, ft[j]);
    d->isat_count += kind == kMacro && (aux[j].active_set & kCurrentSat) != 0;
    d->vsat_count += kind == kMacro && (aux[j].active_set & kVoltageSat) != 0;
  }
  // the arm's own linearisation B_q = ∂τ_id/∂q, B_q̇ = ∂τ_id/∂q̇ (inverse dynamics at the
  // stage-1 accelerations). With the drives engaged their stiffness dominates W and this adds
  // nothing measurable; with free joints the gyroscopic terms of a fast wrist need it
  // (energy drift 1.7e-4 → 8e-6 over a 10 s free swing). Finite differences of RNEA: 12 calls.
  Mat6 bq = Mat6::Zero();
  if (!m->drives_engaged) {
    urt_payload_t pl;
    arm_linearisation(m, *urt__payload_physics(d, &pl), sub, x, f, bq, wmat, gh);
  }
  Lu6 wfac;
  lu6_factor(wmat, wfac);

  // one stage solve: per-joint reduction, the 6×6 arm system, back-substitution
  auto solve = [&](double (*rr)[URT_NXJ], double (*k)[URT_NXJ]) {
    Vec6 rqd, c0 = Vec6::Zero();
    for (int j = 0; j < URT_NJ; j++) {
      rqd[j] = rr[j][URT_X_QD];
      if (!sub[j]) {
        c0[j] = joint_reduce(w[j], rr[j], a_d[j], &e_z[j]);
      }
    }
    Vec6 rhs = mm * rqd + gh * c0;
    if (!m->drives_engaged) {
      Vec6 rq;
      for (int j = 0; j < URT_NJ; j++) {
        rq[j] = rr[j][URT_X_Q];
      }
      rhs.noalias() -= gh * bq * rq;
    }
    Vec6 kqd = lu6_solve(wfac, rhs);
    for (int j = 0; j < URT_NJ; j++) {
      if (sub[j]) {
        std::memset(k[j], 0, sizeof k[j]);
        k[j][URT_X_QD] = kqd[j];
        k[j][URT_X_Q] = rr[j][URT_X_Q] + gh * kqd[j];
      } else {
        joint_backsub(w[j], rr[j], a_d[j], e_z[j], kqd[j], k[j]);
      }
    }
  };

  for (int j = 0; j < URT_NJ; j++) {
    for (int i = 0; i < URT_NXJ; i++) {
      r[j][i] = f[j][i] + gh * ft[j][i];
    }
  }
  solve(r, k1);

  // stage 2: f(t_n + h, x_n + h k1)
  for (int j = 0; j < URT_NJ; j++) {
    for (int i = 0; i < URT_NXJ; i++) {
      x2[j][i] = x[j][i] + h * k1[j][i];
    }
  }
  Mat6 mass_2;
  Vec6 h_2;
  macro_rates(m, d, sub, s0 + h, x2, tau_ext, qdd_pres, f, aux, false, mass_2, h_2);
  for (int j = 0; j < URT_NJ; j++) {
    for (int i = 0; i < URT_NXJ; i++) {
      r[j][i] = f[j][i] - 2.0 * k1[j][i] - gh * ft[j][i];
    }
  }
  solve(r, k2);

  // update; the sub-stepped joints take their own end state
  for (int j = 0; j < URT_NJ; j++) {
    if (sub[j]) {
      std::memcpy(x[j], sub_end[j], sizeof x[j]);
      continue;
    }
    for (int i = 0; i < URT_NXJ; i++) {
      x[j][i] += h * (1.5 * k1[j][i] + 0.5 * k2[j][i]);
    }
  }
}

}  // namespace urt::core
