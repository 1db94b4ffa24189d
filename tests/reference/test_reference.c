/* SPDX-License-Identifier: Apache-2.0
 * tests/reference/test_reference.c — urt_step against the CVODE reference (core/reference.cpp)
 * on the first second of an excitation trajectory, noise off. The full 10 s comparison is
 * `make reference-compare` (minutes). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "test_model.h"
#include "test_support.h"
#include "traj.h"
#include "urt/reference.h"

static double seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void compare(const char *rate_override, double duration) {
  const char *const ov[] = {"sensors.noise=false", "sensors.quantise=false", rate_override, NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *a = calloc(1, sizeof *a), *b = calloc(1, sizeof *b);
  assert_int_equal(urt_data_init(m, a, NULL), 0);
  memcpy(b, a, sizeof *a);
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_excitation(&tr, m->q0, NULL, 1), 0);
  urt_reference_t *r = NULL;
  assert_int_equal(urt_reference_create(m, b, 1e-10, &r), 0);

  double dq_max[URT_NJ] = {0}, di2[URT_NJ] = {0}, i2[URT_NJ] = {0}, track[URT_NJ] = {0};
  int n = (int)lround(duration / m->dt);
  double t0 = seconds();
  for (int k = 0; k < n; k++) {
    urt_command_t c;
    memset(&c, 0, sizeof c);
    urt_traj_eval(&tr, a->t, c.q, c.qd, c.qdd);
    assert_int_equal(urt_command_set(m, a, &c), 0);
    assert_int_equal(urt_command_set(m, b, &c), 0);
    assert_int_equal(urt_step(m, a), 0);
    assert_int_equal(urt_reference_step(r, m, b), 0);
    for (int j = 0; j < URT_NJ; j++) {
      double dq = a->x[j][URT_X_Q] - b->x[j][URT_X_Q];
      double di = a->x[j][URT_X_I] - b->x[j][URT_X_I];
      dq_max[j] = fmax(dq_max[j], fabs(dq));
      di2[j] += di * di;
      i2[j] += b->x[j][URT_X_I] * b->x[j][URT_X_I];
      track[j] = fmax(track[j], fabs(b->cmd.q[j] - b->x[j][URT_X_Q]));
    }
  }
  print_message("%s: %.2f s simulated, reference %ld CVODE steps, %.1f s wall\n", rate_override,
                duration, urt_reference_nsteps(r), seconds() - t0);
  for (int j = 0; j < URT_NJ; j++) {
    double rms_rel = sqrt(di2[j] / i2[j]);
    print_message("  joint %d: max |dq| %.3g rad, RMS current error %.3g %%, "
                  "tracking %.4f deg\n", j + 1, dq_max[j], 100.0 * rms_rel,
                  track[j] * 180.0 / M_PI);
    assert_true(dq_max[j] <= 1e-5);
    assert_true(rms_rel <= 0.02);
  }
  urt_reference_free(r);
  free(a);
  free(b);
  urt_model_free(m);
}

static void test_reference__20khz_matches_cvode_on_1_s_of_excitation(void **state) {
  (void)state;
  compare("simulation.dt=5e-5", 1.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_reference__20khz_matches_cvode_on_1_s_of_excitation),
  };
  return cmocka_run_group_tests_name("reference/reference", tests, NULL, NULL);
}
