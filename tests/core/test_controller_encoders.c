/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_controller_encoders.c — the controller's motor/joint encoder check
 * (core/controller_encoders.cpp): a joint encoder that sticks while its joint moves, or a motor
 * encoder whose speed reads a bias, stops the arm once the two encoders disagree by
 * URT_ENCODER_TOLERANCE; a healthy arm and a gear at the catalogue's worst stiffness do not. */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "controller_harness.h"
#include "fault_spec.h"
#include "test_support.h"

static const char *const kQuiet[] = {"sensors.noise=false", NULL};

static urt_fault_spec_t spec(int cls, int joint, int component, double severity, double onset) {
  urt_fault_spec_t f = fault_spec(cls, joint, severity);
  f.component = component;
  f.onset = onset;
  return f;
}

static void install(rig_t *r, const urt_fault_spec_t *f) {
  fault_install(r->m, r->d, f, f ? 1 : 0);
}

static bool encoder_stopped(const rig_t *r) {
  return r->c->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP &&
         (r->c->fault & URT_CTRL_FAULT_ENCODER) && (r->d->pstop & URT_PSTOP_ENCODER);
}

/* periods until the encoder check stops the arm or max_t [s] passes; returns the time */
static double run_until_stopped(rig_t *r, const urt_ctrl_cmd_t *first, double max_t) {
  int n = (int)lround(max_t / r->c->period);
  for (int i = 0; i < n; i++) {
    rig_period(r, i == 0 ? first : NULL);
    if (encoder_stopped(r)) {
      return (i + 1) * r->c->period;
    }
  }
  return -1.0;
}

static void test_encoders__a_joint_encoder_stuck_while_moving_stops_the_arm(void **state) {
  (void)state;
  rig_t r = rig_new(kQuiet, 0.002, 1);
  // the base turns +1 rad at 1 rad/s; its joint encoder sticks 0.3 s into the move
  urt_fault_spec_t f = spec(URT_FAULT_ENCODER_STUCK, 0, URT_FAULT_ENC_JOINT, 1.0, 0.3);
  install(&r, &f);
  double q[6];
  for (int j = 0; j < 6; j++) q[j] = r.c->q1[j];
  q[0] += 1.0;
  urt_ctrl_cmd_t mv = rig_movej(&r, q, 4.0, 1.0);
  double t = run_until_stopped(&r, &mv, 2.0);
  assert_true(t > 0.3);
  assert_int_equal(r.c->enc_joint, 0);
  // the true angle ran ahead of the stuck reading by the tolerance, plus at most a period or
  // two at the arm's speed (the loop, closed on the stuck reading, speeds the joint up)
  double ahead = r.d->x[0][URT_X_Q] - r.d->faults.joint[0].q_hold;
  print_message("stopped %.3f s after the fault, true angle %.4f rad past the stuck reading\n",
                t - 0.3, ahead);
  assert_true(ahead > URT_ENCODER_TOLERANCE - 0.005 && ahead < URT_ENCODER_TOLERANCE + 0.02);
  // no motion is accepted while stopped
  urt_ctrl_cmd_t again = rig_movej(&r, q, 4.0, 1.0);
  rig_period(&r, &again);
  assert_true(r.c->fault & URT_CTRL_FAULT_NOT_RUNNING);
  rig_free(&r);
}

static void test_encoders__a_motor_encoder_bias_trips_when_its_angle_error_reaches_the_tolerance(
    void **state) {
  (void)state;
  rig_t r = rig_new(kQuiet, 0.002, 1);
  // wrist 3 at rest; from 0.1 s its motor-speed reading is 10 rad/s high: the motor-side angle
  // a drive counts runs away at 10/ratio rad/s on the joint side, while the loop holds the joint
  const double bias = 10.0;
  urt_fault_spec_t f = spec(URT_FAULT_ENCODER_BIAS, 5, URT_FAULT_ENC_MOTOR, bias, 0.1);
  install(&r, &f);
  double t = run_until_stopped(&r, NULL, 2.0);
  const double want = 0.1 + URT_ENCODER_TOLERANCE / (bias / r.m->gear[5].ratio);
  print_message("stopped at %.3f s, expected %.3f s\n", t, want);
  assert_true(fabs(t - want) < 0.02);
  assert_int_equal(r.c->enc_joint, 5);
  rig_free(&r);
}

static void test_encoders__healthy_and_worn_gears_run_without_a_stop(void **state) {
  (void)state;
  // large, fast moves of every joint: once healthy, once with the shoulder's gear at the
  // catalogue's lowest stiffness (4 %), whose deflection is the largest without a sensor fault
  for (int worn = 0; worn <= 1; worn++) {
    rig_t r = rig_new(kQuiet, 0.002, 1);
    urt_fault_spec_t f = spec(URT_FAULT_GEAR_STIFFNESS, 1, 0, 0.96, 0.0);
    install(&r, worn ? &f : NULL);
    double q0[6], q[6];
    for (int j = 0; j < 6; j++) q0[j] = q[j] = r.c->q1[j];
    for (int j = 0; j < 6; j++) q[j] += (j == 1 ? -0.8 : 1.0);
    urt_ctrl_cmd_t there = rig_movej(&r, q, 8.0, 3.0);
    assert_true(run_until_stopped(&r, &there, 3.0) < 0);
    urt_ctrl_cmd_t back = rig_movej(&r, q0, 8.0, 3.0);
    assert_true(run_until_stopped(&r, &back, 3.0) < 0);
    assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
    // back where it began (the worn shoulder sags 0.014 rad under gravity at its 4 %)
    print_message("worn %d: shoulder at %.4f rad, started at %.4f\n", worn, r.d->x[1][URT_X_Q],
                  q0[1]);
    assert_true(fabs(r.d->x[1][URT_X_Q] - q0[1]) < 0.03);
    rig_free(&r);
  }
}

static void test_encoders__a_stopped_arm_takes_the_disagreement_as_its_new_reference(
    void **state) {
  (void)state;
  // a joint-encoder bias of 0.08 rad appears while the arm is powered off: no stop at power
  // on (the reference is taken while not running); the same bias appearing while running stops
  rig_t r = rig_new(kQuiet, 0.002, 0);
  urt_fault_spec_t f = spec(URT_FAULT_ENCODER_BIAS, 2, URT_FAULT_ENC_JOINT, 0.08, 0.05);
  install(&r, &f);
  run_for(&r, 0.2);
  urt_ctrl_cmd_t on = rig_cmd(&r, URT_CTRL_POWER_ON);
  rig_period(&r, &on);
  urt_ctrl_cmd_t release = rig_cmd(&r, URT_CTRL_BRAKE_RELEASE);
  rig_period(&r, &release);
  assert_true(run_until_stopped(&r, NULL, 0.5) < 0);
  rig_free(&r);

  rig_t s = rig_new(kQuiet, 0.002, 1);
  install(&s, &f);
  double t = run_until_stopped(&s, NULL, 0.5);
  assert_true(t > 0.05 && t < 0.06);
  assert_int_equal(s.c->enc_joint, 2);
  rig_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_encoders__a_joint_encoder_stuck_while_moving_stops_the_arm),
      cmocka_unit_test(test_encoders__a_motor_encoder_bias_trips_when_its_angle_error_reaches_the_tolerance),
      cmocka_unit_test(test_encoders__healthy_and_worn_gears_run_without_a_stop),
      cmocka_unit_test(test_encoders__a_stopped_arm_takes_the_disagreement_as_its_new_reference),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
