/* SPDX-License-Identifier: Apache-2.0
 * tests/support/test_model.c — load config/ur5.yaml with overrides, failing the test on error. */
#include "test_model.h"

#include <math.h>

#include "test_support.h"

const char *const urt_test_quiet[] = {"sensors.noise=false", "sensors.quantise=false", NULL};

urt_model_t *urt_test_model(const char *const *overrides) {
  urt_model_t *m = NULL;
  char err[512] = "";
  int rc = urt_model_load(urt_test_path("config/ur5.yaml"), overrides, &m, err, sizeof err);
  if (rc != 0 || !m) {
    fail_msg("urt_model_load: %d %s", rc, err);
  }
  return m;
}

int urt_test_state_finite(const urt_data_t *d) {
  for (int j = 0; j < URT_NJ; j++) {
    for (int i = 0; i < URT_NXJ; i++) {
      if (!isfinite(d->x[j][i])) {
        return 0;
      }
    }
  }
  return 1;
}
