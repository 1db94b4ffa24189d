/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/reference.h — the same right-hand side as urt_step, integrated by SUNDIALS
 * CVODE (BDF, dense direct solver, tight tolerances). Tests and tools use it to judge the
 * fixed-step scheme; it is far too slow for real time (minutes per simulated second).
 *
 * Usage mirrors urt_step: urt_command_set(m, d, &cmd); urt_reference_step(r, m, d);
 * The reference samples the sensors at the same instants with the same RNG, so with noise
 * off (or the same seed) both see identical inputs.
 */
#ifndef URT_REFERENCE_H
#define URT_REFERENCE_H

#include "urt/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_reference urt_reference_t;

/* Create a CVODE integrator starting from d's state. rtol: relative tolerance (1e-10 is the
 * recommended reference; absolute tolerances per state follow model.md §5.1, scaled by
 * rtol/1e-11). Context: non-RT. Returns 0 or URT_ENOMEM / URT_ESOLVER. */
int urt_reference_create(const urt_model_t *m, const urt_data_t *d, double rtol,
                         urt_reference_t **out);

/* Advance d by exactly m->dt with CVODE (stopping at the step boundary, where the set-point
 * and held sensor errors change). Updates d's state, time and derived outputs like urt_step.
 * Context: non-RT. Returns 0 or URT_ESOLVER. */
int urt_reference_step(urt_reference_t *r, const urt_model_t *m, urt_data_t *d);

/* Internal steps CVODE has taken so far. */
long urt_reference_nsteps(const urt_reference_t *r);

void urt_reference_free(urt_reference_t *r);

#ifdef __cplusplus
}
#endif
#endif
