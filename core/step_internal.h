/* SPDX-License-Identifier: Apache-2.0
 * core/step_internal.h — what urt_step and the CVODE reference share around the integration
 * itself, so both treat commands, time, sensors and outputs identically. Internal. */
#ifndef URT_CORE_STEP_INTERNAL_H
#define URT_CORE_STEP_INTERNAL_H

#include "urt/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Hold the arm where it is: set-point at the joint positions, no motion, no feed-forward. */
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

#ifdef __cplusplus
}
#endif
#endif
