/* SPDX-License-Identifier: Apache-2.0
 * core/step_internal.h — what urt_step and the CVODE reference share around the integration
 * itself, so both treat commands, time, sensors and outputs identically. Internal. */
#ifndef URT_CORE_STEP_INTERNAL_H
#define URT_CORE_STEP_INTERNAL_H

#include "urt/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where the drive reads joint j now: the joint encoder's filter output with its held error
 * (quantisation, noise) and sensor faults, as the position loop sees it (joint.cpp); not the
 * link angle x[URT_X_Q], nor d->q_fb, which is refreshed only with the outputs. A hold takes this, not the
 * link's continuous position: the position loop is proportional on the quantised reading and
 * the speed loop integrates, so a set-point between two counts is never met and the integrator
 * winds the joint back and forth across the count (a limit cycle: after a power cycle at
 * [0.5, -0.5, 0.5, 0, 0, 0] base and shoulder changed count in 27-31 % of 2 ms samples, noise
 * off). A controller knows only the reading, and holding on it leaves no error to wind. */
double urt__measured_q(const urt_data_t *d, int j);

/* Hold the arm where it is: set-point at the measured joint positions, no motion, no
 * feed-forward. */
void urt__command_hold(urt_data_t *d);

/* Refuse a bad command in d->cmd: protective stop and hold. Returns 0 or URT_EPSTOP. */
int urt__command_check(const urt_model_t *m, urt_data_t *d);

/* After the state has advanced by m->dt from x0: accelerations, time, the command carried
 * forward, sensors sampled and outputs refreshed. Context: RT. */
void urt__step_finish(const urt_model_t *m, urt_data_t *d, const double (*x0)[URT_NXJ]);

/* The wrench the arm feels at the TCP: d->wrench_ext, plus a collision fault's while one is
 * active (then summed into buf, which is returned). Context: RT. */
static inline const double *urt__wrench_total(const urt_data_t *d, double buf[6]) {
  if (d->faults.s.n == 0) {
    return d->wrench_ext;
  }
  for (int i = 0; i < 6; i++) {
    buf[i] = d->wrench_ext[i] + d->faults.wrench[i];
  }
  return buf;
}

/* The payload the physics carries: the run's (urt_data_t.live, what the controller was told)
 * plus any payload fault's point masses, combined into buf as one rigid body (mass, CoG, and
 * the inertia about the new CoG by the parallel-axis theorem). Context: RT. */
static inline const urt_payload_t *urt__payload_physics(const urt_data_t *d, urt_payload_t *buf) {
  const urt_fault_state_t *fs = &d->faults;
  if (fs->s.n == 0 || fs->payload_mass == 0.0) {
    return &d->live.payload;
  }
  const urt_payload_t *p = &d->live.payload;
  const double m1 = p->mass, m2 = fs->payload_mass, m = m1 + m2;
  double c2[3], c[3], r1[3], r2[3];
  for (int i = 0; i < 3; i++) {
    c2[i] = fs->payload_moment[i] / m2;  /* the point masses' common centre */
    c[i] = (m1 * p->cog[i] + m2 * c2[i]) / m;
    r1[i] = p->cog[i] - c[i];
    r2[i] = c2[i] - c[i];
  }
  /* point masses at one centre have no inertia about it (several at different offsets are
   * treated as one at their centre: exact for one, a bound for many) */
  buf->mass = m;
  for (int i = 0; i < 3; i++) {
    buf->cog[i] = c[i];
  }
  const double a1 = r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2];
  const double a2 = r2[0] * r2[0] + r2[1] * r2[1] + r2[2] * r2[2];
  static const int ii[6] = {0, 1, 2, 0, 0, 1}, jj[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; k++) {
    const int a = ii[k], b = jj[k];
    const double e = a == b ? 1.0 : 0.0;
    buf->inertia[k] = p->inertia[k] + m1 * (a1 * e - r1[a] * r1[b]) + m2 * (a2 * e - r2[a] * r2[b]);
  }
  return buf;
}

#ifdef __cplusplus
}
#endif
#endif
