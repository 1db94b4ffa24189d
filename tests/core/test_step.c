/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_step.c — core/step.cpp, core/integrator.cpp, core/command.c */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fault_spec.h"
#include "test_model.h"
#include "test_support.h"
#include "traj.h"

// A smooth motion on every joint: q0 + A sin(ω t), with consistent speed and acceleration.
static void sine_command(const urt_model_t *m, double t, urt_command_t *c) {
  memset(c, 0, sizeof *c);
  for (int j = 0; j < URT_NJ; j++) {
    double a = 0.3, w = 2.0 + 0.5 * j;
    c->q[j] = m->q0[j] + a * sin(w * t);
    c->qd[j] = a * w * cos(w * t);
    c->qdd[j] = -a * w * w * sin(w * t);
  }
}

static urt_data_t *new_data(const urt_model_t *m) {
  urt_data_t *d = calloc(1, sizeof *d);
  assert_non_null(d);
  assert_int_equal(urt_data_init(m, d, NULL), 0);
  return d;
}

static void test_step__makes_no_heap_allocations(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = new_data(m);
  urt_command_t c;
  long before = urt_test_malloc_count();
  urt_test_malloc_arm(1);
  for (int k = 0; k < 10000; k++) {
    sine_command(m, d->t, &c);
    urt_command_set(m, d, &c);
    urt_step(m, d);
  }
  urt_test_malloc_arm(0);
  long calls = urt_test_malloc_count() - before;
  print_message("heap calls during 10000 steps: %ld\n", calls);
  assert_int_equal(calls, 0);
  assert_int_equal(d->pstop, 0);
  free(d);
  urt_model_free(m);
}

static void expect_refused(const urt_model_t *m, urt_data_t *d, const urt_command_t *c,
                           uint32_t bit) {
  assert_int_equal(urt_command_set(m, d, c), URT_EPSTOP);
  assert_true(d->pstop & bit);
  for (int k = 0; k < 200; k++) {
    urt_step(m, d);
  }
  assert_true(urt_test_state_finite(d));
  for (int j = 0; j < URT_NJ; j++) {
    assert_true(isfinite(d->cmd.q[j]));
    assert_near(d->x[j][URT_X_Q], m->q0[j], 1e-3);  // held where it was
  }
  urt_pstop_reset(m, d);
  assert_int_equal(d->pstop, 0);
}

static void test_command_set__refuses_nan_inf_and_out_of_range_with_protective_stop(
    void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = new_data(m);
  urt_command_t c;

  sine_command(m, 0.0, &c);
  c.q[2] = NAN;
  expect_refused(m, d, &c, URT_PSTOP_NONFINITE_CMD);

  sine_command(m, 0.0, &c);
  c.qd[4] = INFINITY;
  expect_refused(m, d, &c, URT_PSTOP_NONFINITE_CMD);

  sine_command(m, 0.0, &c);
  c.q[0] = m->joint[0].q_max + 0.1;
  expect_refused(m, d, &c, URT_PSTOP_POS_LIMIT);

  sine_command(m, 0.0, &c);
  c.qd[1] = 2.0 * m->joint[1].qd_max;
  expect_refused(m, d, &c, URT_PSTOP_SPEED_LIMIT);

  sine_command(m, 0.0, &c);
  c.tau_ff[5] = -1e6;
  expect_refused(m, d, &c, URT_PSTOP_TORQUE_LIMIT);

  // a command is refused while the stop holds
  sine_command(m, 0.0, &c);
  c.q[0] = NAN;
  urt_command_set(m, d, &c);
  sine_command(m, 0.0, &c);
  assert_int_equal(urt_command_set(m, d, &c), URT_EPSTOP);
  free(d);
  urt_model_free(m);
}

static void test_step__refuses_nan_written_straight_into_the_command(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = new_data(m);
  d->cmd.qdd[3] = NAN;
  urt_step(m, d);
  assert_true(d->pstop & URT_PSTOP_NONFINITE_CMD);
  assert_true(urt_test_state_finite(d));
  free(d);
  urt_model_free(m);
}

static void run_noisy(const urt_model_t *m, urt_data_t *d, int n) {
  urt_command_t c;
  for (int k = 0; k < n; k++) {
    sine_command(m, d->t, &c);
    urt_command_set(m, d, &c);
    urt_step(m, d);
  }
}

static void test_step__same_seed_is_bit_identical_and_another_seed_is_not(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  const char *const seed2[] = {"simulation.seed=2", NULL};
  urt_model_t *m2 = urt_test_model(seed2);
  urt_data_t *a = new_data(m), *b = new_data(m), *c = new_data(m2);
  run_noisy(m, a, 4000);
  run_noisy(m, b, 4000);
  run_noisy(m2, c, 4000);
  urt_data_update_outputs(m, a);
  urt_data_update_outputs(m, b);
  assert_memory_equal(a->x, b->x, sizeof a->x);
  assert_memory_equal(a->i_fb, b->i_fb, sizeof a->i_fb);
  assert_true(memcmp(a->x, c->x, sizeof a->x) != 0);
  free(a);
  free(b);
  free(c);
  urt_model_free(m);
  urt_model_free(m2);
}

static void test_step__settled_current_equals_gravity_over_kt_ratio_without_friction(
    void **state) {
  (void)state;
  const char *const ov[] = {"sensors.noise=false", "sensors.quantise=false",
                            "friction_common.enabled=false", NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = new_data(m);
  const double poses[5][URT_NJ] = {{0.0, -1.2, 1.0, -1.4, -1.5708, 0.0},
                                   {0.5, -0.3, 0.4, -0.8, 1.0, 0.5},
                                   {-0.7, -2.0, 2.2, 0.3, -0.5, 1.0},
                                   {1.2, -0.8, -1.0, -2.0, 0.7, -1.0},
                                   {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}};
  double worst = 0.0;
  for (int p = 0; p < 5; p++) {
    // a 2 s cosine blend from where the arm is to the pose, then 0.5 s to settle
    const double tm = 2.0;
    double from[URT_NJ];
    for (int j = 0; j < URT_NJ; j++) {
      from[j] = d->x[j][URT_X_Q];
    }
    int n_move = (int)lround(tm / m->dt), n_hold = (int)lround(0.5 / m->dt);
    for (int k = 0; k < n_move + n_hold; k++) {
      urt_command_t c;
      memset(&c, 0, sizeof c);
      double s = fmin(k * m->dt / tm, 1.0), w = M_PI / tm;
      for (int j = 0; j < URT_NJ; j++) {
        double dq = poses[p][j] - from[j];
        c.q[j] = from[j] + dq * 0.5 * (1.0 - cos(M_PI * s));
        c.qd[j] = k < n_move ? dq * 0.5 * w * sin(M_PI * s) : 0.0;
        c.qdd[j] = k < n_move ? dq * 0.5 * w * w * cos(M_PI * s) : 0.0;
      }
      assert_int_equal(urt_command_set(m, d, &c), 0);
      assert_int_equal(urt_step(m, d), 0);
    }

    // compare with g(q) / (k_t τ): every joint whose holding current is not negligible
    double q[URT_NJ], g[URT_NJ];
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = d->x[j][URT_X_Q];
    }
    urt_arm_gravity(m, q, g);
    for (int j = 0; j < URT_NJ; j++) {
      double expect = g[j] / (m->motor[j].kt * m->gear[j].ratio);
      double got = d->x[j][URT_X_I];
      double tol = fmax(0.01 * fabs(expect), 1e-4 * m->control[j].i_max);
      print_message("pose %d joint %d: i = %+.6f A, g/(kt tau) = %+.6f A, rel %.2e\n", p, j + 1,
                    got, expect, fabs(expect) > 1e-9 ? fabs(got / expect - 1.0) : 0.0);
      if (fabs(expect) > 0.01) {
        worst = fmax(worst, fabs(got / expect - 1.0));
      }
      assert_near(got, expect, tol);
    }
  }
  print_message("worst relative error over joints with |i| > 10 mA: %.3g\n", worst);
  free(d);
  urt_model_free(m);
}

static void test_step__released_arm_conserves_energy_for_10_s(void **state) {
  (void)state;
  const char *const ov[] = {"simulation.drives_engaged=false", "friction_common.enabled=false",
                            NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = calloc(1, sizeof *d);
  const double q0[URT_NJ] = {0.2, -0.7, 0.3, -0.5, 0.8, 0.1};
  assert_int_equal(urt_data_init(m, d, q0), 0);
  double qd[URT_NJ] = {0}, q[URT_NJ];
  double e0 = urt_arm_energy(m, q0, qd), worst = 0.0, ke_max = 0.0;
  int n = (int)lround(10.0 / m->dt);
  for (int k = 0; k < n; k++) {
    assert_int_equal(urt_step(m, d), 0);
    if (k % 20 == 0 || k == n - 1) {
      for (int j = 0; j < URT_NJ; j++) {
        q[j] = d->x[j][URT_X_Q];
        qd[j] = d->x[j][URT_X_QD];
      }
      double e = urt_arm_energy(m, q, qd);
      double zero[URT_NJ] = {0};
      ke_max = fmax(ke_max, e - urt_arm_energy(m, q, zero));
      worst = fmax(worst, fabs(e - e0));
    }
  }
  print_message("E0 = %.6f J, max kinetic %.3f J, max |E - E0| = %.3g J (%.3g relative)\n", e0,
                ke_max, worst, worst / fabs(e0));
  assert_true(ke_max > 1.0);  // the arm really swung
  assert_true(worst <= 1e-4 * fabs(e0));
  free(d);
  urt_model_free(m);
}

// One step on trajectory tr: its set-point at the data's time as the command, then urt_step.
static int traj_step(const urt_model_t *m, urt_data_t *d, const urt_traj_t *tr) {
  urt_command_t c;
  memset(&c, 0, sizeof c);
  urt_traj_eval(tr, d->t, c.q, c.qd, c.qdd);
  assert_int_equal(urt_command_set(m, d, &c), 0);
  return urt_step(m, d);
}

// Noisy excitation runs in which single W steps at stick-to-slip reversals used to blow up
// (wrist 2 at 20 kHz, wrist 1 at 10 kHz): urt_step must redo them as sub-steps and never stop.
static void run_excitation(const char *rate, uint64_t seed) {
  const char *const ov[] = {rate, NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = new_data(m);
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_excitation(&tr, m->q0, NULL, seed), 0);
  double worst = 0.0;
  int n = (int)lround(10.0 / m->dt);
  for (int k = 0; k < n; k++) {
    assert_int_equal(traj_step(m, d, &tr), 0);
    for (int j = 0; j < URT_NJ; j++) {
      worst = fmax(worst, fabs(d->cmd.q[j] - d->x[j][URT_X_Q]));
    }
  }
  print_message("%s seed %d: max tracking error %.4f deg, %u steps refined of %d\n", rate,
                (int)seed, worst * 180.0 / M_PI, d->refined_count, n);
  assert_int_equal(d->pstop, 0);
  assert_true(worst < 0.01);
  free(d);
  urt_model_free(m);
}

// The pick-and-place's wrist 2 over its first 9.0 s, which hold its fast stop and, at 8.91 s,
// a stick-to-slip reversal: the largest friction torque on it.
static double pickplace_wrist2_friction_max(const char *rate) {
  const char *const ov[] = {rate, NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = new_data(m);
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_pickplace(&tr, m->q0), 0);
  double worst = 0.0;
  const int n = (int)lround(9.0 / m->dt);
  for (int k = 0; k < n; k++) {
    assert_int_equal(traj_step(m, d, &tr), URT_OK);
    urt_data_update_outputs(m, d);
    worst = fmax(worst, fabs(d->t_f[4]));
  }
  free(d);
  urt_model_free(m);
  return worst;
}

// At 10 kHz the macro step took that reversal on the wrong side of its linearisation: wrist 2
// went from −0.001 to +0.20 rad/s in one step with 59 N m of friction (f_c 1.7 N m). A step
// whose acceleration jumps (step_rough) is refined; the friction peak is then the 20 kHz one.
static void test_step__a_rough_step_is_refined_so_10_khz_has_the_20_khz_friction(void **state) {
  (void)state;
  const double f10 = pickplace_wrist2_friction_max("simulation.dt=1e-4");
  const double f20 = pickplace_wrist2_friction_max("simulation.dt=5e-5");
  print_message("wrist 2's largest friction torque over 9 s of pick-and-place: %.3f N m at "
                "10 kHz, %.3f N m at 20 kHz\n", f10, f20);
  assert_true(fabs(f10 - f20) <= 0.05 * f20);
}

// The dataset demo's shoulder backlash runs that stopped (payload 0, seed 1, onset 2 s): an
// impact of the circular spline on the output at 8.77 s (1.45 mrad) and 8.23 s (2.9 mrad)
// shook the stuck wrist 2 loose within one step, a reversal that the 5 µs sub-steps also
// overshot; urt_step redoes such a step at a quarter of the sub-step and goes on.
static void run_backlash_excitation(double width) {
  const char *const ov[] = {"payload.mass=0", "payload.cog=[0, 0, 0]",
                            "payload.inertia=[0, 0, 0, 0, 0, 0]", NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = new_data(m);
  urt_fault_spec_t f = fault_spec(URT_FAULT_BACKLASH, 1, width);
  f.onset = 2.0;
  fault_install(m, d, &f, 1);
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_excitation(&tr, m->q0, NULL, 1), 0);
  int n = (int)lround(10.0 / m->dt);
  for (int k = 0; k < n; k++) {
    if (traj_step(m, d, &tr) != URT_OK) {
      print_message("backlash %.3g rad: stopped at t = %.4f s\n", width, d->t);
      fail();
    }
  }
  print_message("backlash %.3g rad: 10 s, %u steps refined of %d\n", width, d->refined_count, n);
  assert_int_equal(d->pstop, 0);
  free(d);
  urt_model_free(m);
}

static void test_step__shoulder_backlash_impacts_never_stop_an_excitation(void **state) {
  (void)state;
  run_backlash_excitation(1.45e-3);
  run_backlash_excitation(2.9e-3);
}

static void test_step__noisy_excitations_at_10_and_20_khz_never_stop(void **state) {
  (void)state;
  run_excitation("simulation.dt=1e-4", 2);
  run_excitation("simulation.dt=1e-4", 4);
  run_excitation("simulation.dt=5e-5", 1);
  run_excitation("simulation.dt=5e-5", 3);
}

// simulation.refine_every = 4: steps 4, 8, ... take the refined path (the macro step is undone
// and redone as n_sub fine steps), the others do not; the fine path integrates the same model,
// so the arm ends where the unforced run does, to within the macro step's own error.
static void test_step__refine_every_forces_the_fine_path_on_every_nth_step(void **state) {
  (void)state;
  const char *const ov[] = {"simulation.refine_every=4", NULL};
  urt_model_t *mf = urt_test_model(ov);
  urt_model_t *m = urt_test_model(NULL);
  assert_int_equal(m->refine_every, 0);
  assert_int_equal(mf->refine_every, 4);
  urt_data_t *df = new_data(mf), *d = new_data(m);
  urt_command_t c;
  for (int k = 0; k < 2000; k++) {
    sine_command(m, d->t, &c);
    urt_command_set(m, d, &c);
    urt_command_set(mf, df, &c);
    assert_int_equal(urt_step(m, d), URT_OK);
    assert_int_equal(urt_step(mf, df), URT_OK);
    assert_int_equal(df->refined_count, (k + 1) / 4);
  }
  assert_int_equal(d->refined_count, 0);
  double worst = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    worst = fmax(worst, fabs(df->x[j][URT_X_Q] - d->x[j][URT_X_Q]));
  }
  print_message("|q_forced - q| after 0.1 s: %.3g rad\n", worst);
  assert_true(worst > 0.0);   // the fine path ran: its rounding differs
  assert_true(worst < 1e-5);  // and it integrates the same model
  free(df);
  free(d);
  urt_model_free(mf);
  urt_model_free(m);
}

// A standing arm (set-point q0 at rest) with sensor noise: wrist 3's bristles hold it, so the
// integrator takes it in the macro step instead of sub-stepping it (integrator.cpp,
// joint_stuck). Against the fine path of the whole model (refine_every = 1: every step as
// n_sub coupled steps of 5 µs, nothing split off), wrist 3 must stay where the fine path has
// it, and its current, which follows the held noise, no further from it than wrist 2's (the
// same drive size, always in the macro step). Quantisation off, so that both runs draw and
// hold the same noise whatever their states' last bits.
static void run_standing(const char *rate) {
  const char *const ov[] = {rate, "sensors.quantise=false", NULL};
  const char *const ovf[] = {rate, "sensors.quantise=false", "simulation.refine_every=1", NULL};
  urt_model_t *m = urt_test_model(ov), *mf = urt_test_model(ovf);
  urt_data_t *d = new_data(m), *df = new_data(mf);
  urt_command_t c;
  memset(&c, 0, sizeof c);
  memcpy(c.q, m->q0, sizeof c.q);
  double dq[URT_NJ] = {0}, di2[URT_NJ] = {0}, qd6 = 0.0;
  int n = (int)lround(0.5 / m->dt);
  for (int k = 0; k < n; k++) {
    assert_int_equal(urt_command_set(m, d, &c), 0);
    assert_int_equal(urt_command_set(mf, df, &c), 0);
    assert_int_equal(urt_step(m, d), URT_OK);
    assert_int_equal(urt_step(mf, df), URT_OK);
    for (int j = 0; j < URT_NJ; j++) {
      dq[j] = fmax(dq[j], fabs(d->x[j][URT_X_Q] - df->x[j][URT_X_Q]));
      double e = d->x[j][URT_X_I] - df->x[j][URT_X_I];
      di2[j] += e * e;
    }
    qd6 = fmax(qd6, fabs(d->x[5][URT_X_QD]));
  }
  double di5 = sqrt(di2[4] / n), di6 = sqrt(di2[5] / n);
  print_message("%s: max |q - q_fine| wrist 3 %.3g rad (others up to %.3g), RMS |i - i_fine| "
                "wrist 3 %.3g A, wrist 2 %.3g A; max |qd| wrist 3 %.3g rad/s; %u steps refined\n",
                rate, dq[5], fmax(fmax(dq[0], dq[1]), fmax(fmax(dq[2], dq[3]), dq[4])), di6, di5,
                qd6, d->refined_count);
  assert_int_equal(d->refined_count, 0);
  assert_int_equal(d->pstop, 0);
  assert_true(qd6 < 1e-4);
  assert_true(dq[5] < 1e-8);
  for (int j = 0; j < URT_NJ; j++) {
    assert_true(dq[j] < 1e-7);
  }
  assert_true(di6 < 1.25 * di5);
  free(df);
  free(d);
  urt_model_free(mf);
  urt_model_free(m);
}

static void test_step__standing_wrist_3_in_the_macro_step_follows_the_fine_path(void **state) {
  (void)state;
  run_standing("simulation.dt=5e-5");
  run_standing("simulation.dt=1e-4");
}

// With sub-stepping switched off and model.md's steeper wrist Stribeck dip (k_q = 10), wrist 3
// is unstable at 50 µs: urt_step must first redo implausible steps as fine steps, and when that
// cannot save the state, stop with a finite state instead of diverging.
static void test_step__unstable_settings_end_in_a_protective_stop_not_in_nan(void **state) {
  (void)state;
  const char *const ov[] = {"simulation.substep_ratio=100", "joints.3.friction.k_q=10",
                            "joints.4.friction.k_q=10", "joints.5.friction.k_q=10", NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = new_data(m);
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_excitation(&tr, m->q0, NULL, 1), 0);
  int rc = 0, n = (int)lround(5.0 / m->dt), k;
  for (k = 0; k < n && rc == 0; k++) {
    urt_command_t c;
    memset(&c, 0, sizeof c);
    urt_traj_eval(&tr, d->t, c.q, c.qd, c.qdd);
    urt_command_set(m, d, &c);
    rc = urt_step(m, d);
  }
  print_message("stopped at t = %.4f s after %u refined steps\n", d->t, d->refined_count);
  assert_int_equal(rc, URT_ESOLVER);
  assert_true(d->pstop & URT_PSTOP_NONFINITE_STATE);
  assert_true(d->refined_count > 0);
  assert_true(urt_test_state_finite(d));
  for (int j = 0; j < URT_NJ; j++) {
    assert_true(fabs(d->x[j][URT_X_QD]) < 10.0 * m->joint[j].qd_max);
  }
  free(d);
  urt_model_free(m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_step__makes_no_heap_allocations),
      cmocka_unit_test(test_command_set__refuses_nan_inf_and_out_of_range_with_protective_stop),
      cmocka_unit_test(test_step__refuses_nan_written_straight_into_the_command),
      cmocka_unit_test(test_step__same_seed_is_bit_identical_and_another_seed_is_not),
      cmocka_unit_test(test_step__settled_current_equals_gravity_over_kt_ratio_without_friction),
      cmocka_unit_test(test_step__released_arm_conserves_energy_for_10_s),
      cmocka_unit_test(test_step__noisy_excitations_at_10_and_20_khz_never_stop),
      cmocka_unit_test(test_step__shoulder_backlash_impacts_never_stop_an_excitation),
      cmocka_unit_test(test_step__a_rough_step_is_refined_so_10_khz_has_the_20_khz_friction),
      cmocka_unit_test(test_step__refine_every_forces_the_fine_path_on_every_nth_step),
      cmocka_unit_test(test_step__standing_wrist_3_in_the_macro_step_follows_the_fine_path),
      cmocka_unit_test(test_step__unstable_settings_end_in_a_protective_stop_not_in_nan),
  };
  return cmocka_run_group_tests_name("core/step", tests, NULL, NULL);
}
