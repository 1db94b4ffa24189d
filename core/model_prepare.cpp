// SPDX-License-Identifier: Apache-2.0
// core/model_prepare.cpp — derived parameters and the integrator's tables, computed once
// after loading; and the model's destructor.
#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

#include "arm.hpp"
#include "integrator.hpp"
#include "urt/core.h"

namespace urt::core {
namespace {

using MatD = Eigen::Matrix<double, URT_NXD, URT_NXD>;
using VecD = Eigen::Matrix<double, URT_NXD, 1>;

// Most negative slope of the friction law g(q̇): the Stribeck dip is a genuine instability of
// growth rate |g'|/J_out that the step size must respect (model.md §5.3d–e). The slope of g
// on the negative side is −dg/dq̇ there; with an asymmetric Coulomb level (a ≠ 0) the side
// with the larger level has the steeper dip, so both sides are searched.
double friction_slope_min(const urt_friction_params_t* fp) {
  double worst = 0.0;
  for (int k = 0; k <= 400; k++) {
    double v = 1e-6 * std::pow(10.0, 7.0 * k / 400.0);  // 1e-6 … 10 rad/s
    worst = std::fmin(worst, urt_friction_dg(fp, v));
    if (fp->asym != 0.0) {
      worst = std::fmin(worst, -urt_friction_dg(fp, -v));
    }
  }
  return worst;
}

// Where the Stribeck dip ends: the largest speed of friction_slope_min's grid with g' < 0 on
// either side (0 if there is none). Above it the slope is positive, a damping the L-stable
// macro step takes in its W. Scaling f_c and f_v together (a lubricant fault) or adding to f_c
// at a fixed f_c k_static (brake drag) leaves the sign of g', so this speed, unchanged.
double friction_dip_end(const urt_friction_params_t* fp) {
  double end = 0.0;
  for (int k = 0; k <= 400; k++) {
    double v = 1e-6 * std::pow(10.0, 7.0 * k / 400.0);  // 1e-6 … 10 rad/s
    if (urt_friction_dg(fp, v) < 0.0 || (fp->asym != 0.0 && -urt_friction_dg(fp, -v) < 0.0)) {
      end = 1e-6 * std::pow(10.0, 7.0 * (k + 1) / 400.0);
    }
  }
  return end;
}

// Smallest arm inertia a joint sees, over a few configurations (wrist inertias barely vary).
// Without a payload: one only adds a positive semi-definite term to M, so the bare arm's
// bound holds for any payload a run mounts, and the sub-stepping chosen from it stays safe
// without recomputing these tables when the payload changes.
double output_inertia_min(const urt_model_t* m, int j) {
  const urt_payload_t none = {};
  double lo = INFINITY;
  for (int k = 0; k < 64; k++) {
    Eigen::Matrix<double, 6, 1> q;
    for (int i = 0; i < URT_NJ; i++) {
      q[i] = std::sin(1.7 * k + 2.3 * i) * M_PI;  // deterministic spread over the range
    }
    Eigen::Matrix<double, 6, 6> mass;
    crba(m->arm, none, q, mass);
    lo = std::fmin(lo, mass(j, j));
  }
  return lo + m->gear[j].j_cs;
}

// Columns of the drive block's affine rates: f(e_k) − f(0) at a forced active set is exact.
void drive_columns(const urt_model_t* m, int j, int set, MatD& a, VecD& b_q, VecD& b_qd,
                   VecD& f_qset, VecD& f_qdset) {
  double x[URT_NXJ] = {0}, f0[URT_NXJ], f1[URT_NXJ];
  // the affine columns are differences, so the current offset (a constant input) is left 0
  JointInput in = {0, 0, 0, 0, 0, 0, 0.0, 1, 0};
  JointAux aux;
  drive_rhs(m, j, x, in, set, f0, &aux);
  auto column = [&](VecD& col) {
    drive_rhs(m, j, x, in, set, f1, &aux);
    for (int i = 0; i < URT_NXD; i++) {
      col[i] = f1[i] - f0[i];
    }
  };
  for (int k = 0; k < URT_NXD; k++) {
    x[k] = 1.0;
    VecD col;
    column(col);
    a.col(k) = col;
    x[k] = 0.0;
  }
  x[URT_X_Q] = 1.0;
  column(b_q);
  x[URT_X_Q] = 0.0;
  x[URT_X_QD] = 1.0;
  column(b_qd);
  x[URT_X_QD] = 0.0;
  in.q_set = 1.0;
  column(f_qset);
  in.q_set = 0.0;
  in.qd_set = 1.0;
  column(f_qdset);
}

}  // namespace

int integrator_prepare(const urt_model_t* m, urt_integrator_tables* tab) noexcept {
  // which joints need sub-steps, and how many
  tab->h[kMacro] = m->dt;
  tab->n_sub = (int)std::ceil(m->dt / m->substep_h_max - 1e-9);
  if (tab->n_sub < 1) {
    tab->n_sub = 1;
  }
  tab->h[kSub] = m->dt / tab->n_sub;
  tab->h[kFine] = tab->h[kSub] / kFinePerSub;
  for (int j = 0; j < URT_NJ; j++) {
    tab->g_slope_min[j] = friction_slope_min(&m->friction[j]);
    tab->j_out[j] = output_inertia_min(m, j);
    double ratio = m->dt * std::fabs(tab->g_slope_min[j]) / tab->j_out[j];
    tab->substepped[j] = m->friction[j].enabled && tab->n_sub > 1 && ratio > m->substep_ratio;
    tab->v_sub[j] = 2.0 * friction_dip_end(&m->friction[j]);
    const urt_friction_params_t& fp = m->friction[j];
    double g_max = std::fmax(urt_friction_g(&fp, m->joint[j].qd_max),
                             urt_friction_g(&fp, -m->joint[j].qd_max));
    tab->z_max[j] = fp.enabled ? g_max / fp.sigma0 : 0.0;
  }

  // W_d⁻¹ and couplings for every joint, step kind and active set
  for (int j = 0; j < URT_NJ; j++) {
    for (int kind = 0; kind < kNumStepKinds; kind++) {
      double gh = kGamma * tab->h[kind];
      for (int set = 0; set < kNumActiveSets; set++) {
        MatD a;
        VecD b_q, b_qd, f_qset, f_qdset;
        drive_columns(m, j, set, a, b_q, b_qd, f_qset, f_qdset);
        MatD w = MatD::Identity() - gh * a;
        // rows span 1 … 1e5 in scale (gear springs over tiny masses), so judge the inverse by
        // its residual rather than by a pivot threshold
        Eigen::PartialPivLU<MatD> lu(w);
        MatD winv = lu.inverse();
        if (!((w * winv - MatD::Identity()).cwiseAbs().maxCoeff() < 1e-6)) {
          return URT_ESOLVER;
        }
        VecD winv_bq = winv * b_q;
        VecD bd = gh * (gh * winv_bq + winv * b_qd);
        DriveTables& t = tab->t[j][kind][set];
        Eigen::Map<Eigen::Matrix<double, URT_NXD, URT_NXD>>(t.winv) = winv;
        Eigen::Map<VecD>(t.winv_bq) = winv_bq;
        Eigen::Map<VecD>(t.bd) = bd;
        Eigen::Map<VecD>(t.fq_set) = f_qset;
        Eigen::Map<VecD>(t.fqd_set) = f_qdset;
        t.filter_rows_apart = winv.bottomLeftCorner<2, URT_NXD - 2>().isZero(0.0);
        if (!winv.allFinite()) {
          return URT_ESOLVER;
        }
      }
    }
  }
  return URT_OK;
}

}  // namespace urt::core

extern "C" int urt_model_prepare(urt_model_t* m) {
  // derived gear parameters (k_e, i_max and the sensor quanta come with the loader, which
  // needs i_max for the current quantum)
  for (int j = 0; j < URT_NJ; j++) {
    urt_harmonic_drive_derive(&m->gear[j], m->motor[j].j);
  }
  urt_arm_prepare(&m->arm);

  // integrator tables (about 460 kB: three step sizes, four saturation sets, each with and
  // without a backlash gap): allocated here, never in the step
  if (!m->tables) {
    m->tables = static_cast<urt_integrator_tables*>(std::calloc(1, sizeof(urt_integrator_tables)));
    if (!m->tables) {
      return URT_ENOMEM;
    }
  }
  return urt::core::integrator_prepare(m, m->tables);
}

extern "C" void urt_model_free(urt_model_t* m) {
  if (!m) {
    return;
  }
  std::free(m->tables);
  std::free(m);
}
