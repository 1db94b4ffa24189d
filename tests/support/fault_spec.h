/* SPDX-License-Identifier: Apache-2.0
 * tests/support/fault_spec.h — a fault of the tests' scenarios: one class on one joint, a step
 * at time 0 of the given severity, every other field 0 (the caller sets component, onset,
 * profile, ... where it needs them), and its installation as a one-fault scenario. */
#ifndef URT_TEST_FAULT_SPEC_H
#define URT_TEST_FAULT_SPEC_H

#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/faults.h"

static inline urt_fault_spec_t fault_spec(int cls, int joint, double severity) {
  urt_fault_spec_t f;
  memset(&f, 0, sizeof f);
  f.cls = cls;
  f.joint = joint;
  f.severity = severity;
  f.profile = URT_FAULT_STEP;
  return f;
}

/* the n faults f (n = 0: none) as d's scenario; fails the test if refused */
static inline void fault_install(const urt_model_t *m, urt_data_t *d, const urt_fault_spec_t *f,
                                 int n) {
  urt_fault_scenario_t s;
  memset(&s, 0, sizeof s);
  s.n = n;
  if (n > 0) memcpy(s.f, f, (size_t)n * sizeof *f);
  assert_int_equal(urt_data_set_faults(m, d, &s), URT_OK);
}

#endif
