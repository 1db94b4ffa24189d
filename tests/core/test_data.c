/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_data.c — core/data.cpp: the eq. (6) start under gravity. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"

static void test_data_init__start_at_rest_under_gravity_does_not_move(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(urt_test_quiet);
  urt_data_t *d = calloc(1, sizeof *d);
  const double poses[3][URT_NJ] = {{0, -1.5708, 1.5708, -1.5708, -1.5708, 0},
                                   {0.3, -0.4, 0.9, -1.9, 1.2, 2.0},
                                   {0, 0, 0, 0, 0, 0}};
  for (int p = 0; p < 3; p++) {
    assert_int_equal(urt_data_init(m, d, poses[p]), 0);
    double worst = 0.0;

    // 10 ms at the step rate (model.md §6.1 A3): |q̇| < 1e-6 rad/s throughout
    int n = (int)lround(0.01 / m->dt);
    for (int k = 0; k < n; k++) {
      assert_int_equal(urt_step(m, d), 0);
      for (int j = 0; j < URT_NJ; j++) {
        worst = fmax(worst, fabs(d->x[j][URT_X_QD]));
      }
    }
    print_message("pose %d: max |qd| over 10 ms = %.3g rad/s\n", p, worst);
    assert_true(worst < 1e-6);
  }
  free(d);
  urt_model_free(m);
}

static void test_data_init__shoulder_holds_with_3_913_A_at_q0(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(urt_test_quiet);
  urt_data_t d;
  const double q[URT_NJ] = {0, 0, 0, 0, 0, 0};
  assert_int_equal(urt_data_init(m, &d, q), 0);
  // model.md §3: 53.81 / (0.1361 · 101.03) = 3.913 A, and the gravity torque is negative
  assert_near(fabs(d.x[1][URT_X_I]), 3.913, 0.005 * 3.913);
  free(NULL);
  urt_model_free(m);
}

// A current-measurement offset shows in the measured current, not in the motor's: the start
// stays at rest, the motor carries the gravity current and the measurement reads 0.3 A more.
static void test_data_init__current_offset_shows_in_the_measurement_only(void **state) {
  (void)state;
  const char *const set[] = {"sensors.noise=false", "sensors.quantise=false",
                             "joints.1.current_offset=0.3", NULL};
  urt_model_t *m = urt_test_model(set), *m0 = urt_test_model(urt_test_quiet);
  urt_data_t *d = calloc(1, sizeof *d), *d0 = calloc(1, sizeof *d0);
  assert_int_equal(urt_data_init(m, d, NULL), 0);
  assert_int_equal(urt_data_init(m0, d0, NULL), 0);
  int n = (int)lround(0.2 / m->dt);
  for (int k = 0; k < n; k++) {
    assert_int_equal(urt_step(m, d), 0);
    assert_int_equal(urt_step(m0, d0), 0);
  }
  assert_true(fabs(d->x[1][URT_X_QD]) < 1e-6);
  assert_near(d->x[1][URT_X_I], d0->x[1][URT_X_I], 1e-6);
  assert_near(d->i_fb[1] - d0->i_fb[1], 0.3, 1e-6);
  assert_near(d->i_fb[2], d0->i_fb[2], 0.0);  // other joints untouched, bit for bit
  free(d);
  free(d0);
  urt_model_free(m);
  urt_model_free(m0);
}

// The causes in bit order, "none" without any, and a short buffer cut, never overrun
static void test_pstop_text__names_the_causes_in_order(void **state) {
  (void)state;
  char buf[64];
  assert_string_equal(urt_pstop_text(0, buf, sizeof buf), "none");
  assert_string_equal(urt_pstop_text(URT_PSTOP_SPEED_LIMIT | URT_PSTOP_POS_LIMIT, buf, sizeof buf),
                      "position limit, speed limit");
  char small[12];
  memset(small, 'x', sizeof small);
  urt_pstop_text(URT_PSTOP_NONFINITE_CMD | URT_PSTOP_TORQUE_LIMIT, small, sizeof small);
  assert_int_equal(strlen(small), sizeof small - 1);
  assert_memory_equal(small, "non-finite ", sizeof small - 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_data_init__start_at_rest_under_gravity_does_not_move),
      cmocka_unit_test(test_data_init__shoulder_holds_with_3_913_A_at_q0),
      cmocka_unit_test(test_data_init__current_offset_shows_in_the_measurement_only),
      cmocka_unit_test(test_pstop_text__names_the_causes_in_order),
  };
  return cmocka_run_group_tests_name("core/data", tests, NULL, NULL);
}
