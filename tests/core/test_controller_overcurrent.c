/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_controller_overcurrent.c — the controller's over-current check
 * (core/controller_overcurrent.cpp): a joint whose drive asks for its current limit for
 * URT_OVERCURRENT_TIME faults (safety mode FAULT, arm powered off, the joint in FAULT mode)
 * and stays off until the safety system is restarted; a drive that reaches its limit for less
 * than that, or never, runs on. */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "controller_harness.h"
#include "fault_spec.h"
#include "test_support.h"
#include "urt/snapshot.h"

static const char *const kQuiet[] = {"sensors.noise=false", NULL};

static bool joint_faulted(const rig_t *r) {
  return r->c->safety_mode == URT_SAFETY_MODE_FAULT && (r->c->fault & URT_CTRL_FAULT_JOINT);
}

/* One controller period as the loop runs it: the command, tick and physics steps, then the
 * outputs of the new state (the loop's snapshot refreshes them; the tick's check reads them). */
static void period(rig_t *r, const urt_ctrl_cmd_t *cmd) {
  rig_period(r, cmd);
  urt_data_update_outputs(r->m, r->d);
}

static void periods_for(rig_t *r, double t) {
  for (int i = 0, n = (int)lround(t / r->c->period); i < n; i++) period(r, NULL);
}

/* whether joint j's drive asks for its current limit now (the outputs at the period's end) */
static bool at_limit(const rig_t *r, int j) {
  return fabs(r->d->i_ref[j]) >= r->m->control[j].i_max * (1.0 - 1e-6);
}

typedef struct {
  double t_fault;              /* when a joint faulted [s], −1: not within the run */
  double t_sat;                /* when joint j's drive last began to ask for its limit [s], −1 */
  double sat_longest[URT_NJ];  /* each joint's longest stretch at its limit the test saw [s] */
} run_t;

/* periods (the first with cmd) until a joint faults or max_t [s] passes, watching joint j */
static run_t run_watching(rig_t *r, const urt_ctrl_cmd_t *cmd, int j, double max_t) {
  run_t out = {-1.0, -1.0, {0.0}};
  double since[URT_NJ] = {0.0};
  int n = (int)lround(max_t / r->c->period);
  for (int i = 0; i < n; i++) {
    bool was[URT_NJ];
    for (int k = 0; k < URT_NJ; k++) was[k] = at_limit(r, k);
    period(r, i == 0 ? cmd : NULL);
    double t = (i + 1) * r->c->period;
    if (joint_faulted(r)) {
      out.t_fault = t;
      return out;
    }
    for (int k = 0; k < URT_NJ; k++) {
      if (!at_limit(r, k)) continue;
      if (!was[k] || i == 0) {
        since[k] = t;
        if (k == j) out.t_sat = t;
      }
      out.sat_longest[k] = fmax(out.sat_longest[k], t - since[k] + r->c->period);
    }
  }
  return out;
}

static void test_overcurrent__a_brake_dragging_at_the_joints_peak_torque_faults_it(void **state) {
  (void)state;
  rig_t r = rig_new(kQuiet, 0.002, 1);
  // wrist 3's brake drags with its peak torque (28 N m = torque_max): its drive, at its
  // current limit, cannot turn it; the controller's model does not know the drag
  urt_fault_spec_t f = fault_spec(URT_FAULT_BRAKE_DRAG, 5, 28.0);
  fault_install(r.m, r.d, &f, 1);
  periods_for(&r, 0.5);  // standing still the drag carries no load: no fault
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
  double q[6], q5 = r.d->x[5][URT_X_Q];
  for (int j = 0; j < 6; j++) q[j] = r.c->q1[j];
  q[5] += 1.0;
  urt_ctrl_cmd_t mv = rig_movej(&r, q, 4.0, 1.0);
  run_t run = run_watching(&r, &mv, 5, 3.0);
  print_message("wrist 3 at its limit from %.3f s, faulted at %.3f s, turned %.4f rad\n",
                run.t_sat, run.t_fault, r.d->x[5][URT_X_Q] - q5);
  assert_true(run.t_sat > 0.0 && run.t_fault > 0.0);
  // the fault comes URT_OVERCURRENT_TIME after the drive reached its limit and stayed there
  // (the check reads the state the next tick starts from: the same period's end)
  assert_true(fabs(run.t_fault - run.t_sat - URT_OVERCURRENT_TIME) < 0.5 * r.c->period + 1e-9);
  assert_int_equal(r.c->fault_joint, 5);
  assert_int_equal(r.c->robot_mode, URT_ROBOT_MODE_POWER_OFF);
  assert_true(fabs(r.d->x[5][URT_X_Q] - q5) < 0.1);  // it barely turned

  // the snapshot: wrist 3 in FAULT, the others powered off
  urt_snapshot_t s;
  urt_snapshot_fill(r.m, r.c, r.d, &s);
  assert_int_equal(s.fault_joint, 5);
  for (int j = 0; j < 6; j++) {
    assert_int_equal(s.joint_mode[j], j == 5 ? URT_JOINT_MODE_FAULT : URT_JOINT_MODE_POWER_OFF);
  }

  // off until the safety system restarts: motion, power on and brake release are refused
  urt_ctrl_cmd_t again = rig_movej(&r, q, 4.0, 1.0);
  period(&r, &again);
  assert_true(r.c->fault & URT_CTRL_FAULT_NOT_RUNNING);
  urt_ctrl_cmd_t on = rig_cmd(&r, URT_CTRL_POWER_ON), rel = rig_cmd(&r, URT_CTRL_BRAKE_RELEASE);
  period(&r, &on);
  period(&r, &rel);
  assert_int_equal(r.c->robot_mode, URT_ROBOT_MODE_POWER_OFF);
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_FAULT);
  urt_ctrl_cmd_t restart = rig_cmd(&r, URT_CTRL_RESTART_SAFETY);
  period(&r, &restart);
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
  assert_int_equal(r.c->robot_mode, URT_ROBOT_MODE_POWER_OFF);
  assert_int_equal(r.c->fault_joint, -1);

  // powered on again, the drag still there: standing, the drive is within its limit (the gear
  // still carries what the drive pushed, less than the drag holds) and the arm runs; another
  // joint's move is taken and made
  on = rig_cmd(&r, URT_CTRL_POWER_ON);
  rel = rig_cmd(&r, URT_CTRL_BRAKE_RELEASE);
  period(&r, &on);
  period(&r, &rel);
  assert_int_equal(r.c->robot_mode, URT_ROBOT_MODE_RUNNING);
  run = run_watching(&r, NULL, 5, 1.0);
  assert_true(run.t_fault < 0.0);
  for (int j = 0; j < 6; j++) q[j] = r.c->q1[j];
  q[4] += 0.3;
  mv = rig_movej(&r, q, 4.0, 1.0);
  run = run_watching(&r, &mv, 4, 1.5);
  assert_true(run.t_fault < 0.0);
  assert_true(fabs(r.d->x[4][URT_X_Q] - q[4]) < 1e-3);
  rig_free(&r);
}

static void test_overcurrent__a_drag_the_joint_can_overcome_and_fast_moves_do_not_fault(
    void **state) {
  (void)state;
  rig_t r = rig_new(kQuiet, 0.002, 1);
  urt_fault_spec_t f = fault_spec(URT_FAULT_BRAKE_DRAG, 5, 10.0);
  fault_install(r.m, r.d, &f, 1);
  double q[6];
  for (int j = 0; j < 6; j++) q[j] = r.c->q1[j];
  q[5] += 1.0;
  urt_ctrl_cmd_t mv = rig_movej(&r, q, 4.0, 1.0);
  run_t run = run_watching(&r, &mv, 5, 2.5);
  assert_true(run.t_fault < 0.0);
  assert_true(fabs(r.d->x[5][URT_X_Q] - q[5]) < 1e-3);
  assert_true(run.sat_longest[5] == 0.0);  // 10 + friction < 28 N m: never at the limit
  // every joint at once, at 3 rad/s² and 3 rad/s (faster than the movej defaults)
  for (int j = 0; j < 6; j++) q[j] += j < 3 ? -1.0 : 1.5;
  mv = rig_movej(&r, q, 3.0, 3.0);
  run = run_watching(&r, &mv, 0, 3.0);
  assert_true(run.t_fault < 0.0);
  double longest = 0.0;
  for (int j = 0; j < 6; j++) longest = fmax(longest, run.sat_longest[j]);
  print_message("longest stretch at a current limit: %.3f s\n", longest);
  assert_true(longest < URT_OVERCURRENT_TIME);
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
  rig_free(&r);
}

static void test_overcurrent__a_collision_shorter_than_the_time_runs_on_a_longer_one_faults(
    void **state) {
  (void)state;
  rig_t r = rig_new(kQuiet, 0.002, 1);
  // 400 N pressing the TCP down: more than the shoulder's and elbow's peak torques carry at
  // the rig's pose, in windows of 0.05 s every 0.5 s
  urt_fault_spec_t f = fault_spec(URT_FAULT_COLLISION, 0, 400.0);
  f.direction[2] = -1.0;
  f.onset = 0.1;
  f.profile = URT_FAULT_INTERMITTENT;
  f.on = 0.05;
  f.off = 0.45;
  fault_install(r.m, r.d, &f, 1);
  run_t run = run_watching(&r, NULL, 1, 2.0);
  print_message("shoulder at its limit for up to %.3f s a window; fault at %.3f s\n",
                run.sat_longest[1], run.t_fault);
  assert_true(run.sat_longest[1] > 0.05);  // the windows do saturate it
  assert_true(run.t_fault < 0.0);
  assert_int_equal(r.c->safety_mode, URT_SAFETY_MODE_NORMAL);
  // the same force held: a fault, at a joint whose drive was at its limit
  f.profile = URT_FAULT_STEP;
  f.onset = 2.2;
  fault_install(r.m, r.d, &f, 1);
  run = run_watching(&r, NULL, 1, 2.0);
  print_message("held: fault at %.3f s (onset at 0.2 s), joint %d\n", run.t_fault,
                r.c->fault_joint);
  assert_true(run.t_fault > 0.2 + URT_OVERCURRENT_TIME - 1e-9 &&
              run.t_fault < 0.2 + URT_OVERCURRENT_TIME + 0.05);
  assert_true(r.c->fault_joint >= 1 && r.c->fault_joint <= 2);
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_overcurrent__a_brake_dragging_at_the_joints_peak_torque_faults_it),
      cmocka_unit_test(test_overcurrent__a_drag_the_joint_can_overcome_and_fast_moves_do_not_fault),
      cmocka_unit_test(test_overcurrent__a_collision_shorter_than_the_time_runs_on_a_longer_one_faults),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
