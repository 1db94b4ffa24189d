/* SPDX-License-Identifier: Apache-2.0
 * tests/drivers/test_friction.c — drivers/friction.c */
#include <math.h>

#include "test_support.h"
#include "urt/drivers/friction.h"
#include "urt/drivers/friction_inline.h"

static const urt_friction_params_t kWrist = {1, 5e6, 100, 0.5, 0.3, 2.0, 2.0, 10.0, 0.0, 0.0};

static void test_friction_g__is_even_and_finite_for_negative_speed(void **state) {
  (void)state;
  for (double v = 1e-4; v < 4.0; v *= 1.7) {
    assert_true(isfinite(urt_friction_g(&kWrist, -v)));
    assert_near(urt_friction_g(&kWrist, v), urt_friction_g(&kWrist, -v), 0.0);
  }
  assert_near(urt_friction_g(&kWrist, 0.0), 2.0 * 1.3, 1e-12);  // static level f_c (1 + K_s)
}

static void test_friction__steady_sliding_gives_g_sign_v(void **state) {
  (void)state;
  double v = -0.7;
  double z = -urt_friction_g(&kWrist, v) / kWrist.sigma0;  // ż = 0
  urt_friction_out_t o = urt_friction_eval(&kWrist, &(urt_friction_state_t){z}, v);
  assert_near(o.dz, 0.0, 1e-12);
  assert_near(o.t_f, -urt_friction_g(&kWrist, v), 1e-9);
}

static void test_friction__partials_match_finite_differences(void **state) {
  (void)state;
  double v = 0.03, z = 1e-7, h = 1e-8;
  urt_friction_out_t o = urt_friction_eval(&kWrist, &(urt_friction_state_t){z}, v);
  double dz_dv = (urt_friction_eval(&kWrist, &(urt_friction_state_t){z}, v + h).dz -
                  urt_friction_eval(&kWrist, &(urt_friction_state_t){z}, v - h).dz) / (2 * h);
  double dz_dz = (urt_friction_eval(&kWrist, &(urt_friction_state_t){z + 1e-12}, v).dz -
                  urt_friction_eval(&kWrist, &(urt_friction_state_t){z - 1e-12}, v).dz) / 2e-12;
  assert_near(o.ddz_dqd, dz_dv, 1e-5 * fabs(dz_dv) + 1e-9);
  assert_near(o.ddz_dz, dz_dz, 1e-4 * fabs(dz_dz));
}

static void test_friction_dg__stribeck_dip_is_about_minus_3_7(void **state) {
  (void)state;
  double worst = 0.0;
  for (double v = 1e-5; v < 1.0; v *= 1.01) {
    worst = fmin(worst, urt_friction_dg(&kWrist, v));
  }
  assert_near(worst, -3.7, 0.2);  // model.md §2.2
}

// asym scales the Coulomb and Stribeck level by 1 ± a per direction; the viscous part stays
static void test_friction__asymmetry_scales_the_coulomb_level_per_direction(void **state) {
  (void)state;
  urt_friction_params_t p = kWrist;
  p.asym = 0.2;
  double v = 0.4, sym = urt_friction_g(&kWrist, v), visc = kWrist.f_v * cbrt(v * v);
  assert_near(urt_friction_g(&p, v) - visc, 1.2 * (sym - visc), 1e-12);
  assert_near(urt_friction_g(&p, -v) - visc, 0.8 * (sym - visc), 1e-12);
  // steady sliding backwards gives −g(q̇ < 0)
  double z = -urt_friction_g(&p, -v) / p.sigma0;
  urt_friction_out_t o = urt_friction_eval(&p, &(urt_friction_state_t){z}, -v);
  assert_near(o.dz, 0.0, 1e-12);
  assert_near(o.t_f, -urt_friction_g(&p, -v), 1e-9);
  // ż is continuous through rest from both sides
  double zs = 1e-7;
  double dz_p = urt_friction_eval(&p, &(urt_friction_state_t){zs}, 1e-12).dz;
  double dz_m = urt_friction_eval(&p, &(urt_friction_state_t){zs}, -1e-12).dz;
  assert_near(dz_p, dz_m, 1e-11);
}

static void test_friction__disabled_is_zero(void **state) {
  (void)state;
  urt_friction_params_t p = kWrist;
  p.enabled = 0;
  urt_friction_out_t o = urt_friction_eval(&p, &(urt_friction_state_t){1e-6}, 1.0);
  assert_near(o.t_f, 0.0, 0.0);
  assert_near(o.dz, 0.0, 0.0);
}

// Bristle relaxation λ: at rest ż = −λ z (the stuck friction decays); in sliding it lowers the
// steady deflection to q̇/(σ0 |q̇|/g + λ); λ = 0 is the paper's law.
static void test_friction__relaxation_decays_stuck_bristles_and_zero_is_the_paper(void **state) {
  (void)state;
  urt_friction_params_t p = kWrist;
  p.relax = 300.0;
  const double z = 2e-7;
  urt_friction_out_t o = urt_friction_eval(&p, &(urt_friction_state_t){z}, 0.0);
  assert_near(o.dz, -300.0 * z, 1e-20);
  assert_near(o.ddz_dz, -300.0, 0.0);
  assert_near(o.t_f, p.sigma0 * z + p.sigma1 * o.dz, 1e-12);
  const double v = 0.01, g = urt_friction_g(&p, v);
  const double z_ss = v / (p.sigma0 * v / g + p.relax);
  assert_near(urt_friction_eval(&p, &(urt_friction_state_t){z_ss}, v).dz, 0.0, 1e-15);
  // 1.6 % below g at 10 mrad/s: σ0 |q̇|/g ≈ 1.9e4 against λ = 300
  assert_true(p.sigma0 * z_ss < g && p.sigma0 * z_ss > 0.98 * g);
  // λ = 0: the paper's ż = q̇ − σ0 |q̇| z/g
  p.relax = 0.0;
  o = urt_friction_eval(&p, &(urt_friction_state_t){z}, v);
  assert_true(o.dz == v - p.sigma0 * (v / g) * z);
}

// The friction law's own cube root (friction_inline.h) against long double cbrtl rounded to
// double: at most 1 ulp off, over the speeds a joint sees, and the edge cases pass through.
static void test_friction_cbrt__is_within_one_ulp_of_cbrtl(void **state) {
  (void)state;
  int off = 0, n = 0;
  for (double v = 1e-12; v < 20.0; v *= 1.0001) {
    double a = v * v, y = urt__friction_cbrt(a), ref = (double)cbrtl((long double)a);
    assert_true(fabs(y - ref) <= nextafter(ref, INFINITY) - ref);
    off += y != ref;
    n++;
  }
  assert_true(off * 1000 < n);  // correctly rounded but for a few in 10⁴
  assert_true(urt__friction_cbrt(0.0) == 0.0);
  assert_true(urt__friction_cbrt(8.0) == 2.0);
  assert_true(urt__friction_cbrt(1e-310) == cbrt(1e-310));
  assert_true(isinf(urt__friction_cbrt(INFINITY)));
  assert_true(isnan(urt__friction_cbrt(NAN)));
}

// A mass J under a constant torque F, from rest with z = 0, by linearly implicit Euler on
// (q̇, z): the joint's displacement after t_end and its speed over the last half.
static void hold_under_load(double F, double t_end, double *q_end, double *q_half,
                            double *z_end) {
  const double J = 0.05, h = 1e-6;  // [kg m²] about a wrist's output inertia; [s]
  double q = 0.0, qd = 0.0, z = 0.0;
  long n = lround(t_end / h);
  for (long k = 0; k < n; k++) {
    urt_friction_out_t o = urt_friction_eval(&kWrist, &(urt_friction_state_t){z}, qd);
    double f1 = (F - o.t_f) / J, f2 = o.dz;
    double a11 = 1.0 + h * kWrist.sigma1 * o.ddz_dqd / J;
    double a12 = h * (kWrist.sigma0 + kWrist.sigma1 * o.ddz_dz) / J;
    double a21 = -h * o.ddz_dqd, a22 = 1.0 - h * o.ddz_dz;
    double det = a11 * a22 - a12 * a21;
    double d1 = h * (a22 * f1 - a12 * f2) / det, d2 = h * (a11 * f2 - a21 * f1) / det;
    qd += d1;
    z += d2;
    q += h * qd;
    if (k == n / 2) {
      *q_half = q;
    }
  }
  *q_end = q;
  *z_end = z;
}

// Presliding is elastic: a load below the breakaway level g(0) deflects the bristles to
// z = F/σ0 and the joint stops there, with no drift (ż = q̇ (1 − F/g) → 0 with q̇); above it the
// joint slides. The standstill creep seen in replays is not in the friction law.
static void test_friction__below_breakaway_a_constant_load_sticks_without_drift(void **state) {
  (void)state;
  double g0 = urt_friction_g(&kWrist, 0.0), q_end, q_half, z_end;
  hold_under_load(0.9 * g0, 1.0, &q_end, &q_half, &z_end);
  assert_near(z_end, 0.9 * g0 / kWrist.sigma0, 1e-12);
  assert_true(fabs(q_end) < 1e-4);            // a presliding deflection, not a slide
  assert_true(fabs(q_end - q_half) < 1e-12);  // [rad] over the last 0.5 s: < 2e-12 rad/s
  hold_under_load(1.1 * g0, 0.2, &q_end, &q_half, &z_end);
  assert_true(fabs(q_end - q_half) > 1e-3);   // above breakaway it slides
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_friction_g__is_even_and_finite_for_negative_speed),
      cmocka_unit_test(test_friction__steady_sliding_gives_g_sign_v),
      cmocka_unit_test(test_friction__partials_match_finite_differences),
      cmocka_unit_test(test_friction_dg__stribeck_dip_is_about_minus_3_7),
      cmocka_unit_test(test_friction__asymmetry_scales_the_coulomb_level_per_direction),
      cmocka_unit_test(test_friction__disabled_is_zero),
      cmocka_unit_test(test_friction__relaxation_decays_stuck_bristles_and_zero_is_the_paper),
      cmocka_unit_test(test_friction_cbrt__is_within_one_ulp_of_cbrtl),
      cmocka_unit_test(test_friction__below_breakaway_a_constant_load_sticks_without_drift),
  };
  return cmocka_run_group_tests_name("drivers/friction", tests, NULL, NULL);
}
