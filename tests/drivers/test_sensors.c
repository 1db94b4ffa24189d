/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_sensors.c — drivers/sensors.c */
#include <math.h>

#include "test_support.h"
#include "urt/drivers/sensors.h"

static void test_sensors_quantise__is_mid_tread(void **state) {
  (void)state;
  assert_near(urt_sensors_quantise(0.4e-3, 1e-3), 0.0, 0.0);
  assert_near(urt_sensors_quantise(0.6e-3, 1e-3), 1e-3, 1e-18);
  assert_near(urt_sensors_quantise(-2.6e-3, 1e-3), -3e-3, 1e-18);
  assert_near(urt_sensors_quantise(0.123, 0.0), 0.123, 0.0);
}

static void test_sensors_held_error__is_zero_with_noise_and_quantisation_off(void **state) {
  (void)state;
  assert_near(urt_sensors_held_error(1.234, 0.1, 2.0, 1e-3, 0, 0), 0.0, 0.0);
}

static void test_rng__same_seed_same_sequence_and_unit_variance(void **state) {
  (void)state;
  urt_rng_t a, b;
  urt_rng_seed(&a, 42);
  urt_rng_seed(&b, 42);
  double sum = 0, sum2 = 0;
  const int n = 200000;
  for (int k = 0; k < n; k++) {
    double x = urt_rng_normal(&a);
    assert_true(x == urt_rng_normal(&b));
    sum += x;
    sum2 += x * x;
  }
  assert_near(sum / n, 0.0, 0.01);
  assert_near(sum2 / n, 1.0, 0.02);
}

static void test_sensors_deriv__filters_rest_at_their_inputs(void **state) {
  (void)state;
  urt_sensors_params_t p = {20e3, 5e3, 0.7, 1e3, 0.7, 0, 0, 0, 0, 0, 0, 0, 0};
  urt_sensors_state_t s = {1.5, 30.0, 0.0, 0.2, 0.0};
  urt_sensors_state_t d = urt_sensors_deriv(&p, &s, 1.5, 30.0, 0.2);
  assert_near(d.i_f, 0.0, 0.0);
  assert_near(d.wd, 0.0, 0.0);
  assert_near(d.pd, 0.0, 0.0);
  // a current step is followed with the 20 kHz time constant
  d = urt_sensors_deriv(&p, &s, 2.5, 30.0, 0.2);
  assert_near(d.i_f, 1.0 * 2.0 * M_PI * 20e3, 1e-6);
}

static void test_rng__different_seeds_differ(void **state) {
  (void)state;
  urt_rng_t a, b;
  urt_rng_seed(&a, 1);
  urt_rng_seed(&b, 2);
  assert_true(urt_rng_next(&a) != urt_rng_next(&b));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sensors_quantise__is_mid_tread),
      cmocka_unit_test(test_sensors_held_error__is_zero_with_noise_and_quantisation_off),
      cmocka_unit_test(test_rng__same_seed_same_sequence_and_unit_variance),
      cmocka_unit_test(test_sensors_deriv__filters_rest_at_their_inputs),
      cmocka_unit_test(test_rng__different_seeds_differ),
  };
  return cmocka_run_group_tests_name("drivers/sensors", tests, NULL, NULL);
}
