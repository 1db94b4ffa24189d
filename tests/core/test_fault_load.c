/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_fault_load.c — core/fault_load.cpp: a fault scenario file read into a
 * urt_fault_scenario_t (every class's keys, profiles, units), and its errors named by file,
 * line, key and reason with nothing half-written. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/faults.h"

static const char kGood[] =
    "faults:\n"
    "  - class: demagnetisation\n"
    "    joint: 1\n"
    "    severity: 0.2\n"
    "    unit: \"1\"\n"
    "    profile: {kind: linear, onset: 0.5, ramp: 2.0}\n"
    "  - class: encoder_bias\n"
    "    joint: 3\n"
    "    component: motor\n"
    "    severity: -0.5\n"
    "    unit: rad/s\n"
    "    profile: {kind: intermittent, onset: 1, on: 0.1, off: 0.4}\n"
    "  - class: collision\n"
    "    severity: 80\n"
    "    unit: N\n"
    "    direction: [0, 3, -4]\n"
    "    profile: {kind: random_walk, onset: 2, sigma: 1.5, seed: 9}\n"
    "  - class: payload\n"
    "    severity: 0.5\n"
    "    unit: kg\n"
    "    offset: [0, 0.02, 0.06]\n"
    "    profile: {kind: step, onset: 3}\n"
    "  - class: wg_bearing\n"
    "    joint: 5\n"
    "    severity: 0.01\n"
    "    unit: N m\n"
    "    location: inner\n"
    "    balls: 13\n"
    "    ball_ratio: 0.2\n"
    "    profile: {kind: step, onset: 0}\n"
    "  - class: backlash\n"
    "    joint: 2\n"
    "    severity: 0.001\n"
    "    unit: rad\n"
    "    profile: {kind: step, onset: 0}\n"
    "  - class: encoder_missed\n"
    "    joint: 0\n"
    "    component: joint\n"
    "    severity: 0.01\n"
    "    unit: \"1\"\n"
    "    seed: 4\n"
    "    profile: {kind: step, onset: 0}\n";

static void test_fault_load__parse_reads_a_scenario(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_fault_scenario_t s;
  char err[512] = "";
  assert_int_equal(urt_faults_parse(m, kGood, "good.yaml", &s, err, sizeof err), URT_OK);
  assert_int_equal(s.n, 7);
  assert_int_equal(s.f[4].cls, URT_FAULT_WG_BEARING);
  assert_int_equal(s.f[4].location, URT_FAULT_BEARING_INNER);
  assert_true(s.f[4].balls == 13 && s.f[4].ball_ratio == 0.2);
  assert_int_equal(s.f[5].cls, URT_FAULT_BACKLASH);
  assert_int_equal(s.f[6].cls, URT_FAULT_ENCODER_MISSED);
  assert_true(s.f[6].seed == 4 && s.f[6].component == URT_FAULT_ENC_JOINT);
  assert_int_equal(s.f[3].cls, URT_FAULT_PAYLOAD);
  assert_true(s.f[3].offset[1] == 0.02 && s.f[3].offset[2] == 0.06);
  assert_int_equal(s.f[0].cls, URT_FAULT_DEMAGNETISATION);
  assert_int_equal(s.f[0].profile, URT_FAULT_LINEAR);
  assert_true(s.f[0].ramp == 2.0 && s.f[0].onset == 0.5);
  assert_int_equal(s.f[1].component, URT_FAULT_ENC_MOTOR);
  assert_true(s.f[1].on == 0.1 && s.f[1].off == 0.4);
  assert_true(fabs(s.f[2].direction[1] - 0.6) < 1e-15 && fabs(s.f[2].direction[2] + 0.8) < 1e-15);
  assert_true(s.f[2].seed == 9 && s.f[2].sigma == 1.5);
  urt_model_free(m);
}

static void expect_error(const urt_model_t *m, const char *from, const char *to,
                         const char *want) {
  char text[2048], err[512] = "";
  const char *at = strstr(kGood, from);
  assert_non_null(at);
  snprintf(text, sizeof text, "%.*s%s%s", (int)(at - kGood), kGood, to, at + strlen(from));
  urt_fault_scenario_t s;
  memset(&s, 0x5a, sizeof s);
  urt_fault_scenario_t before = s;
  assert_int_equal(urt_faults_parse(m, text, "bad.yaml", &s, err, sizeof err), URT_ECONFIG);
  print_message("%s\n", err);
  if (!strstr(err, want)) {
    print_message("expected to contain: %s\n", want);
  }
  assert_non_null(strstr(err, want));
  assert_memory_equal(&s, &before, sizeof s);  // nothing half-written
}

static void test_fault_load__parse_errors_name_file_line_key_and_reason(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  expect_error(m, "    joint: 1\n", "    joint: 1\n    jiont: 2\n",
               "bad.yaml:4: faults[0].jiont: unknown key");
  expect_error(m, "class: demagnetisation", "class: demagnetization",
               "bad.yaml:2: faults[0].class: unknown fault class 'demagnetization'");
  expect_error(m, "unit: rad/s", "unit: rad",
               "bad.yaml:11: faults[1].unit: must be \"rad/s\" for encoder_bias (motor encoder)");
  expect_error(m, "severity: 0.2", "severity: 0.5",
               "bad.yaml:4: faults[0].severity: must be in [0, 0.3] (got 0.5)");
  expect_error(m, "ramp: 2.0}", "ramp: 2.0, on: 1}",
               "bad.yaml:6: faults[0].profile.on: not a key of a linear profile");
  expect_error(m, "on: 0.1, off: 0.4", "on: 0.1", "faults[1].profile.off: missing key");
  expect_error(m, "    joint: 1\n", "", "bad.yaml:2: faults[0].joint: missing key");
  expect_error(m, "direction: [0, 3, -4]", "direction: [0, 0, 0]",
               "faults[2].direction: must not be the zero vector");
  expect_error(m, "kind: linear", "kind: sawtooth", "faults[0].profile.kind: must be step");
  expect_error(m, "offset: [0, 0.02, 0.06]", "offset: [0, 0.02, 1.5]",
               "bad.yaml:21: faults[3].offset[2]: must be in [-1, 1] (got 1.5)");
  // the new classes' ranges and keys: backlash up to 10 arcmin, the bearing pulse up to 10 %
  // of the wrist's k_t i_max (0.1 k_t i_max = 0.0277 N m, i_max as the loader derives it), the bearing's geometry
  expect_error(m, "severity: 0.001", "severity: 0.003",
               "faults[5].severity: must be in [0, 0.00290888] (got 0.003)");
  expect_error(m, "severity: 0.01\n    unit: N m", "severity: 0.03\n    unit: N m",
               "faults[4].severity: must be in [0, 0.0277228] (got 0.03)");
  expect_error(m, "location: inner", "location: cage",
               "faults[4].location: must be outer, inner or ball (got 'cage')");
  expect_error(m, "    balls: 13\n", "", "faults[4].balls: missing key");
  expect_error(m, "ball_ratio: 0.2", "ball_ratio: 0.7", "faults[4].ball_ratio: must be in");
  expect_error(m, "    unit: rad\n", "    unit: rad\n    balls: 9\n",
               "faults[5].balls: only a wg_bearing fault has");
  expect_error(m, "severity: 0.01\n    unit: \"1\"", "severity: 0.6\n    unit: \"1\"",
               "faults[6].severity: must be in [0, 0.5] (got 0.6)");
  urt_fault_scenario_t s;
  char err[256];
  assert_int_equal(urt_faults_load(m, "/nonexistent/faults.yaml", &s, err, sizeof err), URT_EIO);
  assert_non_null(strstr(err, "/nonexistent/faults.yaml: cannot open"));
  urt_model_free(m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_fault_load__parse_reads_a_scenario),
      cmocka_unit_test(test_fault_load__parse_errors_name_file_line_key_and_reason),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
