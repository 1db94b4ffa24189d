/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_exec_hist.c — core/exec_hist.c */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"
#include "urt/exec_hist.h"

static urt_exec_hist_t *fresh(void) {
  urt_exec_hist_t *h = calloc(1, sizeof *h);
  assert_non_null(h);
  return h;
}

static void test_exec_hist__empty_reports_zero(void **state) {
  (void)state;
  urt_exec_hist_t *h = fresh();
  assert_true(urt_exec_hist_quantile(h, 0.99) == 0.0);
  assert_true(urt_exec_hist_max(h) == 0.0);
  assert_int_equal(urt_exec_hist_count(h), 0);
  free(h);
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

// Every quantile lies in [true value, true value · (1 + 1/16)], and never above the maximum.
static void test_exec_hist__quantiles_bound_the_true_value_within_one_bin(void **state) {
  (void)state;
  urt_exec_hist_t *h = fresh();
  enum { N = 100000 };
  static uint64_t v[N];
  uint64_t x = 88172645463325252ull;
  for (int i = 0; i < N; i++) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;  // xorshift64: spread over 100 ns … 10 ms
    v[i] = (uint64_t)(100.0 * pow(1e5, (double)(x >> 11) / 9007199254740992.0));
    urt_exec_hist_add(h, v[i]);
  }
  qsort(v, N, sizeof v[0], cmp_u64);  // the exact quantiles
  const double qs[] = {0.5, 0.9, 0.99, 0.999, 1.0};
  for (size_t k = 0; k < sizeof qs / sizeof qs[0]; k++) {
    size_t rank = (size_t)ceil(qs[k] * N);
    double exact = v[rank - 1] * 1e-9;
    double got = urt_exec_hist_quantile(h, qs[k]);
    print_message("q %.3f: exact %.3f us, reported %.3f us\n", qs[k], exact * 1e6, got * 1e6);
    assert_true(got >= exact);
    assert_true(got <= exact * (1.0 + 1.0 / 16) + 64e-9);  // 64 ns: the linear bins' width
  }
  assert_true(urt_exec_hist_max(h) == v[N - 1] * 1e-9);
  assert_true(urt_exec_hist_quantile(h, 1.0) == v[N - 1] * 1e-9);
  assert_int_equal(urt_exec_hist_count(h), N);
  free(h);
}

// A duration beyond the last octave is counted (in the last bin) and the maximum stays exact.
static void test_exec_hist__an_enormous_duration_is_counted_not_lost(void **state) {
  (void)state;
  urt_exec_hist_t *h = fresh();
  urt_exec_hist_add(h, 1000);
  urt_exec_hist_add(h, 100000000000ull);  // 100 s
  assert_int_equal(urt_exec_hist_count(h), 2);
  assert_true(urt_exec_hist_max(h) == 100.0);
  assert_true(urt_exec_hist_quantile(h, 1.0) > 30.0);
  assert_true(urt_exec_hist_quantile(h, 0.5) <= 1024e-9);
  free(h);
}

// count_from(s) counts every sample >= s and none below s·(1 − 1/16): 1 ms of a 2 ms period.
static void test_exec_hist__count_from_counts_what_reached_a_threshold(void **state) {
  (void)state;
  urt_exec_hist_t *h = fresh();
  const uint64_t below[] = {200000, 500000, 900000, 936000};  // < 1 ms · (1 − 1/16) = 937.5 µs
  const uint64_t above[] = {1000000, 1000001, 1300000, 4000000, 40000000000ull};
  for (int k = 0; k < 1000; k++) {
    urt_exec_hist_add(h, below[k % 4]);
  }
  for (size_t k = 0; k < sizeof above / sizeof above[0]; k++) {
    urt_exec_hist_add(h, above[k]);
  }
  assert_int_equal(urt_exec_hist_count_from(h, 1e-3), 5);
  assert_int_equal(urt_exec_hist_count_from(h, 0.0), 1005);
  assert_int_equal(urt_exec_hist_count_from(h, 1e3), 1);  // the last bin holds the enormous one
  uint64_t near = urt_exec_hist_count_from(h, 999e-6);  // 999 µs: the 1 ms samples' bin
  assert_int_equal(near, 5);
  free(h);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_exec_hist__empty_reports_zero),
      cmocka_unit_test(test_exec_hist__count_from_counts_what_reached_a_threshold),
      cmocka_unit_test(test_exec_hist__quantiles_bound_the_true_value_within_one_bin),
      cmocka_unit_test(test_exec_hist__an_enormous_duration_is_counted_not_lost),
  };
  return cmocka_run_group_tests_name("core/exec_hist", tests, NULL, NULL);
}
