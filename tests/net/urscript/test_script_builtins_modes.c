/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_builtins_modes.c — the control-mode builtins' arguments as the
 * controller receives them: direct_torque across UR's releases (none before 5.23; friction_comp
 * from 5.23; viscous_scale and coulomb_scale from 5.25.1 with the manual's defaults). */
#include <math.h>

#include "script_run.h"

static script_run R;

static int setup(void **state) {
  (void)state;
  sr_reset(&R);
  return 0;
}

/* the last command the controller got, which must be a TORQUE */
static const urt_ctrl_cmd_t *torque_cmd(void) {
  assert_true(R.f.n_cmd > 0);
  const urt_ctrl_cmd_t *c = &R.f.cmd[R.f.n_cmd - 1];
  assert_int_equal(c->kind, URT_CTRL_TORQUE);
  return c;
}

static void test_modes__direct_torque_is_unknown_before_5_23_and_on_cb3(void **state) {
  sr_version(&R, 5, 19, 0);
  sr_fails_with(&R, "direct_torque([0,0,0,0,0,0])\n", "5.23");
  sr_version(&R, 3, 15, 8);
  sr_fails_with(&R, "direct_torque([0,0,0,0,0,0])\n", "5.23");
  assert_int_equal(R.f.n_cmd, 0);
}

static void test_modes__direct_torque_5_23_takes_friction_comp(void **state) {
  sr_version(&R, 5, 23, 0);
  sr_must(&R, "direct_torque([1,2,3,4,5,6])\n");
  const urt_ctrl_cmd_t *c = torque_cmd();
  assert_int_equal(c->index, 1);  // friction_comp defaults to True: the whole model
  for (int j = 0; j < 6; j++) assert_true(c->tau[j] == j + 1.0);
  sr_must(&R, "direct_torque([0,0,0,0,0,0], friction_comp=False)\n");
  assert_int_equal(torque_cmd()->index, 0);
  sr_fails_with(&R, "direct_torque([0,0,0,0,0,0], viscous_scale=[0,0,0,0,0,0])\n", "5.25.1");
}

static void test_modes__direct_torque_5_25_1_scales_with_the_manuals_defaults(void **state) {
  static const double visc[6] = {0.9, 0.9, 0.8, 0.9, 0.9, 0.9}, coul[6] = {0.8, 0.8, 0.7, 0.8, 0.8, 0.8};
  sr_version(&R, 5, 25, 1);
  sr_must(&R, "direct_torque([0,0,0,0,0,0])\n");
  const urt_ctrl_cmd_t *c = torque_cmd();
  assert_int_equal(c->index, 2);
  for (int j = 0; j < 6; j++) {
    assert_true(c->q[j] == visc[j] && c->qd[j] == coul[j]);
  }
  // one scale given: the other keeps its default; friction_comp is ignored beside a scale
  sr_must(&R, "direct_torque([0,0,0,0,0,0], coulomb_scale=[0,0.1,0.2,0.3,0.4,1], friction_comp=False)\n");
  c = torque_cmd();
  assert_int_equal(c->index, 2);
  for (int j = 0; j < 6; j++) {
    assert_true(c->q[j] == visc[j]);
    assert_true(fabs(c->qd[j] - (j == 5 ? 1.0 : 0.1 * j)) < 1e-15);
  }
  // friction_comp alone still works (deprecated): the previous friction model
  sr_must(&R, "direct_torque([0,0,0,0,0,0], friction_comp=True)\n");
  assert_int_equal(torque_cmd()->index, 1);
  // a scale outside [0, 1] is refused
  sr_fails_with(&R, "direct_torque([0,0,0,0,0,0], viscous_scale=[0,0,0,0,0,1.5])\n", "[0, 1]");
  // the newest version (all 0) is the same
  sr_version(&R, 0, 0, 0);
  sr_must(&R, "direct_torque([0,0,0,0,0,0])\n");
  assert_int_equal(torque_cmd()->index, 2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_modes__direct_torque_is_unknown_before_5_23_and_on_cb3, setup),
      cmocka_unit_test_setup(test_modes__direct_torque_5_23_takes_friction_comp, setup),
      cmocka_unit_test_setup(test_modes__direct_torque_5_25_1_scales_with_the_manuals_defaults, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
