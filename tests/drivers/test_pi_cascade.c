/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_pi_cascade.c — drivers/pi_cascade.c */
#include <math.h>

#include "test_support.h"
#include "urt/drivers/pi_cascade.h"

// shoulder gains of Table 1
static const urt_pi_cascade_params_t kShoulder = {7500, 1, 0.2, 10, 10000, 10.91, 48};

static void test_pi_cascade__position_gain_is_not_multiplied_by_the_ratio(void **state) {
  (void)state;
  urt_pi_cascade_in_t in = {1e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0};
  urt_pi_cascade_state_t st = {0.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_near(o.qdm_ref, 7.5, 1e-12);  // P_pos e, motor side (model.md §0.2)
}

static void test_pi_cascade__speed_feedforward_is_ratio_times_joint_speed(void **state) {
  (void)state;
  urt_pi_cascade_in_t in = {0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0};
  urt_pi_cascade_state_t st = {0.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_near(o.qdm_ref, 50.5, 1e-12);
}

static void test_pi_cascade__current_saturates_at_i_max_and_integrator_holds(void **state) {
  (void)state;
  urt_pi_cascade_in_t in = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0};
  urt_pi_cascade_state_t st = {0.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_true(o.i_sat);
  assert_near(o.i_ref, 10.91, 0.0);
  assert_near(o.d.xi_v, 0.0, 0.0);
}

static void test_pi_cascade__saturated_integrator_unwinds_when_error_reverses(void **state) {
  (void)state;
  // integrator wound up positive, error now negative but output still above the limit
  urt_pi_cascade_in_t in = {0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0};
  urt_pi_cascade_state_t st = {100.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_true(o.i_sat);
  assert_true(o.d.xi_v < 0.0);
}

static void test_pi_cascade__voltage_saturates_at_the_supply(void **state) {
  (void)state;
  urt_pi_cascade_in_t in = {0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0};
  urt_pi_cascade_state_t st = {0.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_true(o.v_sat);
  assert_near(o.v_sup, 48.0, 0.0);
  assert_near(o.d.xi_c, 0.0, 0.0);
}

static void test_pi_cascade__torque_mode_follows_the_feedforward_alone(void **state) {
  (void)state;
  // a position error, a speed error and a wound-up integrator: none reaches i_ref
  urt_pi_cascade_in_t in = {0.1, 0.5, 2.0, 0.0, 3.0, 2.0, 1};
  urt_pi_cascade_state_t st = {7.0, 0.0};
  urt_pi_cascade_out_t o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_near(o.i_ref, 2.0, 0.0);
  assert_false(o.i_sat);
  assert_near(o.d.xi_v, 0.0, 0.0);  // held for the return to position control
  assert_near(o.d.xi_c, 0.0, 0.0);  // i_ref = i_fb here
  // clamped at ±i_max like the speed loop's output
  in.i_ff = -50.0;
  o = urt_pi_cascade_eval(&kShoulder, 101.0, &st, &in);
  assert_near(o.i_ref, -10.91, 0.0);
  assert_true(o.i_sat);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pi_cascade__position_gain_is_not_multiplied_by_the_ratio),
      cmocka_unit_test(test_pi_cascade__speed_feedforward_is_ratio_times_joint_speed),
      cmocka_unit_test(test_pi_cascade__current_saturates_at_i_max_and_integrator_holds),
      cmocka_unit_test(test_pi_cascade__saturated_integrator_unwinds_when_error_reverses),
      cmocka_unit_test(test_pi_cascade__voltage_saturates_at_the_supply),
      cmocka_unit_test(test_pi_cascade__torque_mode_follows_the_feedforward_alone),
  };
  return cmocka_run_group_tests_name("drivers/pi_cascade", tests, NULL, NULL);
}
