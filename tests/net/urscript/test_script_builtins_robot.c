/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_builtins_robot.c — the motion builtins across UR's releases:
 * optimovej and optimovel exist from 5.21 (none on CB3), a runtime error naming 5.21 before it;
 * from 5.21 they reach the controller with the script manual's defaults (a = v = 0.3). */
#include "script_run.h"

static script_run R;

static int setup(void **state) {
  (void)state;
  sr_reset(&R);
  return 0;
}

static const char kOptimovej[] = "optimovej([0.1, -1.5, 1.2, -1.0, -1.5, 0.0])\n";
static const char kOptimovel[] = "optimovel(p[0.3, -0.2, 0.4, 0, 3.14, 0])\n";

static void test_robot__optimove_is_unknown_before_5_21_and_on_cb3(void **state) {
  (void)state;
  sr_version(&R, 5, 19, 0);
  sr_fails_with(&R, kOptimovej, "optimovej is not available on software 5.19.0 (UR added it in 5.21)");
  sr_fails_with(&R, kOptimovel, "optimovel is not available on software 5.19.0 (UR added it in 5.21)");
  sr_version(&R, 5, 20, 9);
  sr_fails_with(&R, kOptimovej, "5.21");
  sr_version(&R, 3, 15, 8);
  sr_fails_with(&R, kOptimovel, "5.21");
  assert_int_equal(R.f.n_cmd, 0);  // nothing reached the controller
}

static void test_robot__optimove_from_5_21_with_the_manuals_defaults(void **state) {
  (void)state;
  const int versions[][3] = {{5, 21, 0}, {5, 25, 1}, {0, 0, 0}};  // 0.0.0: the newest
  for (int k = 0; k < 3; k++) {
    sr_version(&R, versions[k][0], versions[k][1], versions[k][2]);
    R.f.n_cmd = 0;
    sr_must(&R, kOptimovej);
    sr_must(&R, kOptimovel);
    assert_int_equal(R.f.n_cmd, 2);
    assert_int_equal(R.f.cmd[0].kind, URT_CTRL_OPTIMOVEJ);
    assert_int_equal(R.f.cmd[1].kind, URT_CTRL_OPTIMOVEL);
    for (int i = 0; i < 2; i++) {
      assert_true(R.f.cmd[i].a == 0.3 && R.f.cmd[i].v == 0.3 && R.f.cmd[i].r == 0.0);
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_robot__optimove_is_unknown_before_5_21_and_on_cb3, setup),
      cmocka_unit_test_setup(test_robot__optimove_from_5_21_with_the_manuals_defaults, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
