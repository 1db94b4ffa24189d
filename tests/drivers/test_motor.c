/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_motor.c — drivers/motor.c */
#include <math.h>

#include "test_support.h"
#include "urt/drivers/motor.h"

static const urt_motor_params_t kShoulder = {1.877e-4, 0.30, 0.83e-3, 0.1361, 0.1361};

static void test_motor_deriv__standstill_current_follows_ohms_law(void **state) {
  (void)state;
  // at rest with V = R i the current holds and the rotor accelerates with k_t i
  urt_motor_deriv_t d = urt_motor_deriv(&kShoulder, &(urt_motor_state_t){2.0, 0.0, 0.0}, 0.6, 0.0);
  assert_near(d.di, 0.0, 1e-12);
  assert_near(d.dqd, 0.1361 * 2.0 / 1.877e-4, 1e-9);
}

static void test_motor_deriv__back_emf_opposes_speed(void **state) {
  (void)state;
  urt_motor_deriv_t d = urt_motor_deriv(&kShoulder, &(urt_motor_state_t){0.0, 0.0, 100.0}, 0.0, 0.0);
  assert_near(d.di, -0.1361 * 100.0 / 0.83e-3, 1e-6);
  assert_near(d.dq, 100.0, 0.0);
}

static void test_motor_deriv__load_torque_balances_motor_torque(void **state) {
  (void)state;
  urt_motor_deriv_t d = urt_motor_deriv(&kShoulder, &(urt_motor_state_t){3.0, 0.0, 0.0}, 0.9, 0.1361 * 3.0);
  assert_near(d.dqd, 0.0, 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_motor_deriv__standstill_current_follows_ohms_law),
      cmocka_unit_test(test_motor_deriv__back_emf_opposes_speed),
      cmocka_unit_test(test_motor_deriv__load_torque_balances_motor_torque),
  };
  return cmocka_run_group_tests_name("drivers/motor", tests, NULL, NULL);
}
