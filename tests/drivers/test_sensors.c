/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_sensors.c — drivers/sensors.c */
#include <math.h>
#include <stdlib.h>

#include "test_support.h"
#include "urt/drivers/sensors.h"
#include "ziggurat_table.h"

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

// the table tools/gen_ziggurat.py wrote, with this machine's libm: every layer has the area V,
// the base layer's rectangle plus tail too, and the edges fall from R to 0
static void test_rng_ziggurat__layers_have_equal_area(void **state) {
  (void)state;
  const double v = URT_ZIG_V, r = URT_ZIG_R;
  assert_near(r * exp(-0.5 * r * r) + sqrt(M_PI / 2) * erfc(r / sqrt(2.0)), v, 1e-15);
  assert_near(urt_zig_x[0] * exp(-0.5 * r * r), v, 1e-15);
  assert_true(urt_zig_x[1] == r && urt_zig_x[256] == 0.0 && urt_zig_f[256] == 1.0);
  for (int i = 1; i < 256; i++) {
    assert_true(urt_zig_x[i + 1] < urt_zig_x[i]);
    assert_near(urt_zig_f[i], exp(-0.5 * urt_zig_x[i] * urt_zig_x[i]), 1e-15);
    assert_near(urt_zig_x[i] * (urt_zig_f[i + 1] - urt_zig_f[i]), v, 1e-14);
  }
}

static double phi(double x) { return 0.5 * erfc(-x / sqrt(2.0)); }

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

// the draws against the standard normal's CDF: Kolmogorov–Smirnov over 10^6 (the 1 % critical
// value 1.63/sqrt(n)), the fourth moment (3), the tail beyond R (the ziggurat's own branch)
// and beyond 4.5 as often as the CDF says, within 5 standard deviations of the count, and the
// tail's mean excess over R
static void test_rng_normal__is_standard_normal_in_body_and_tails(void **state) {
  (void)state;
  urt_rng_t g;
  urt_rng_seed(&g, 7);
  enum { n = 1000000, n_tail = 8000000 };
  double *x = malloc(n * sizeof *x);
  assert_non_null(x);
  double m4 = 0.0;
  for (int k = 0; k < n; k++) {
    x[k] = urt_rng_normal(&g);
    m4 += x[k] * x[k] * x[k] * x[k];
  }
  qsort(x, n, sizeof *x, cmp_double);
  double d = 0.0;
  for (int k = 0; k < n; k++) {
    const double c = phi(x[k]);
    d = fmax(d, fmax(fabs(c - (double)k / n), fabs(c - (double)(k + 1) / n)));
  }
  free(x);
  assert_true(d < 1.63 / sqrt((double)n));
  assert_near(m4 / n, 3.0, 0.03);  // sd of the 4th-moment mean: sqrt(96/n) ~ 0.01
  long beyond_r = 0, beyond_45 = 0, neg = 0;
  double excess = 0.0;  // sum of |z| - R beyond R
  for (int k = 0; k < n_tail; k++) {
    const double z = urt_rng_normal(&g);
    if (fabs(z) > URT_ZIG_R) {
      beyond_r++;
      excess += fabs(z) - URT_ZIG_R;
    }
    beyond_45 += fabs(z) > 4.5;
    neg += z < 0.0;
  }
  const double p_r = 2.0 * phi(-URT_ZIG_R), p_45 = 2.0 * phi(-4.5);
  assert_near((double)beyond_r, n_tail * p_r, 5.0 * sqrt(n_tail * p_r));
  assert_near((double)beyond_45, n_tail * p_45, 5.0 * sqrt(n_tail * p_45));
  assert_near((double)neg, 0.5 * n_tail, 5.0 * sqrt(0.25 * n_tail));
  // E[X - R | X > R] = phi(R)/Q(R) - R (0.25); the excess's sd is about as large, so its mean
  // over ~2000 draws is good to 5 sd = 0.03
  const double dens_r = exp(-0.5 * URT_ZIG_R * URT_ZIG_R) / sqrt(2.0 * M_PI);
  assert_near(excess / (double)beyond_r, dens_r / phi(-URT_ZIG_R) - URT_ZIG_R,
              5.0 * 0.25 / sqrt((double)beyond_r));
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
      cmocka_unit_test(test_rng_ziggurat__layers_have_equal_area),
      cmocka_unit_test(test_rng_normal__is_standard_normal_in_body_and_tails),
      cmocka_unit_test(test_sensors_deriv__filters_rest_at_their_inputs),
      cmocka_unit_test(test_rng__different_seeds_differ),
  };
  return cmocka_run_group_tests_name("drivers/sensors", tests, NULL, NULL);
}
