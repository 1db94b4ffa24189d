// SPDX-License-Identifier: Apache-2.0
// core/data.cpp — the initial state: at rest under gravity, every drive in the static
// equilibrium of eq. (6) carrying its joint's gravity torque (model.md §1.5), so nothing moves.
#include <cstring>

#include "urt/core.h"

extern "C" int urt_data_init(const urt_model_t* m, urt_data_t* d, const double* q) {
  std::memset(d, 0, sizeof *d);
  const double* q0 = q ? q : m->q0;
  d->live.payload = m->payload;  // the configured payload; the run may change it
  std::memcpy(d->live.payload_inertia_declared, m->payload.inertia, sizeof d->live.payload_inertia_declared);
  urt_payload_physical(m->payload.inertia, d->live.payload.inertia);

  // the torque each gear output must carry at rest
  double zero[URT_NJ] = {0}, g[URT_NJ];
  urt_arm_rnea(m, q0, zero, zero, g);

  for (int j = 0; j < URT_NJ; j++) {
    double* x = d->x[j];
    x[URT_X_Q] = q0[j];
    x[URT_X_P] = q0[j];  // joint-encoder filter at its measured value
    d->cmd.q[j] = q0[j];

    // gear and motor from the augmented eq. (6): the motor turns a little past τ q so that
    // the gear's springs hold g_j
    double u[5], t_in;
    int rc = urt_harmonic_drive_equilibrium(&m->gear[j], q0[j], m->drives_engaged ? g[j] : 0.0,
                                            u, &t_in);
    if (rc != URT_OK) {
      return rc;
    }
    x[URT_X_QM] = u[0];
    x[URT_X_QWG] = u[1];
    x[URT_X_XFS] = u[2];
    x[URT_X_YFS] = u[3];
    x[URT_X_QCS] = u[4];

    // the current that holds it, and the integrators that produce that current with zero
    // error: V = R i0 needs ξ_c = R i0 / I_cur, i_ref = i0 needs ξ_v = i0 / I_vel. With a
    // measurement offset the loop sees i0 + i_offset, so i_ref must be that.
    double i0 = t_in / m->motor[j].kt;
    double i_ref0 = i0;
    if (m->joint[j].i_offset != 0.0) {
      i_ref0 += m->joint[j].i_offset;
    }
    x[URT_X_I] = i0;
    x[URT_X_I_F] = i0;
    x[URT_X_XI_C] = m->motor[j].r * i0 / m->control[j].i_cur;
    x[URT_X_XI_V] = i_ref0 / m->control[j].i_vel;
  }

  urt_rng_seed(&d->rng, m->seed);
  urt_sensors_sample(m, d);
  urt_data_update_outputs(m, d);
  return URT_OK;
}
