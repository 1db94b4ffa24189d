/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_harmonic_drive.c — drivers/harmonic_drive.c */
#include <math.h>

#include "test_support.h"
#include "urt/drivers/harmonic_drive.h"

// size A of Table 3
static urt_harmonic_drive_params_t size_a(void) {
  urt_harmonic_drive_params_t p = {0};
  p.z_fs = 200;
  p.z_cs = 202;
  p.r_g = 30.65e-3;
  p.alpha_t = 30.0 * M_PI / 180.0;
  p.k_wg = 1.92e5;
  p.k_b = 1.9e8;
  p.k_fs = 3.99e5;
  p.k_m = 5.70e8;
  p.k_cs = 1.98e7;
  p.j_wg = 2.60e-5;
  p.j_fs = 2.65e-4;
  p.j_cs = 2.43e-4;
  p.zeta = 0.1;
  urt_harmonic_drive_derive(&p, 1.877e-4);
  return p;
}

static void test_harmonic_drive_derive__ratio_cam_angle_and_dampings(void **state) {
  (void)state;
  urt_harmonic_drive_params_t p = size_a();
  assert_near(p.ratio, 101.0, 1e-12);
  assert_near(p.alpha_n * 180.0 / M_PI, 0.9825, 1e-4);
  assert_near(p.m_fs, 0.2821, 1e-4);
  // model.md §2.2: 0.419, 1464, 1754, 2.06, 13.9
  assert_near(p.c_wg, 0.419, 1e-3);
  assert_near(p.c_b, 1464, 1.0);
  assert_near(p.c_m, 1754, 1.0);
  assert_near(p.c_fs, 2.06, 0.01);
  assert_near(p.c_cs, 13.9, 0.05);
}

static void test_harmonic_drive_equilibrium__is_static_with_ratio_101_03(void **state) {
  (void)state;
  urt_harmonic_drive_params_t p = size_a();
  double u[5], t_in;
  assert_int_equal(urt_harmonic_drive_equilibrium(&p, 0.3, 53.81, u, &t_in), 0);

  // all accelerations vanish at rest and the output carries the load
  urt_harmonic_drive_state_t s = {u[1], 0, u[2], 0, u[3], 0, u[4], 0};
  urt_harmonic_drive_ends_t e = {u[0], 0, 0.3, 0};
  urt_harmonic_drive_out_t o = urt_harmonic_drive_eval(&p, &s, &e);
  assert_near(o.t_cs, 53.81, 1e-9);
  assert_near(o.t_in, t_in, 1e-9);  // K_WG (q_M − q_WG) with q_M ≈ 30 rad: roundoff ≈ 1e-9
  assert_near(o.d.qd_wg * p.j_wg, 0.0, 1e-9);
  assert_near(o.d.xd_fs * p.m_fs, 0.0, 1e-6);
  assert_near(o.d.yd_fs * p.m_fs, 0.0, 1e-6);
  assert_near(o.d.qd_cs * p.j_cs, 0.0, 1e-9);

  // static ratio τ / cos²α_n (model.md §6.1 A4)
  assert_near(o.t_cs / o.t_in, 101.0297, 1e-4);

  // the motor sits near τ q plus the gear's wind-up
  assert_near(u[0] / 101.0, 0.3, 1e-3);
}

static void test_harmonic_drive__output_stiffness_is_about_1_45e5(void **state) {
  (void)state;
  urt_harmonic_drive_params_t p = size_a();
  double u[5], t_in;
  urt_harmonic_drive_equilibrium(&p, 0.0, 53.8, u, &t_in);
  // twist of the output relative to the motor angle over the (kinematic) ratio, model.md §1.5
  double twist = u[0] / p.ratio;
  double k_out = 53.8 / twist;
  assert_true(k_out > 1.2e5 && k_out < 1.7e5);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_harmonic_drive_derive__ratio_cam_angle_and_dampings),
      cmocka_unit_test(test_harmonic_drive_equilibrium__is_static_with_ratio_101_03),
      cmocka_unit_test(test_harmonic_drive__output_stiffness_is_about_1_45e5),
  };
  return cmocka_run_group_tests_name("drivers/harmonic_drive", tests, NULL, NULL);
}
