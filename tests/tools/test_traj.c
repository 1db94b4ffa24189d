/* SPDX-License-Identifier: Apache-2.0
 * tests/tools/test_traj.c — the trajectory generators of tools/traj.cpp: rest conditions,
 * bounds, analytic derivatives against finite differences, determinism, movej synchronisation
 * and the wrist-2 stress stop of model.md §6.2. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_support.h"
#include "traj.h"
#include "urt/errors.h"

#define PI 3.14159265358979323846

static const double home[URT_NJ] = {0.0, -PI / 2, PI / 2, -PI / 2, -PI / 2, 0.0};

//---- helpers ----

static double max_abs6(const double *x) {
  double m = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    m = fmax(m, fabs(x[j]));
  }
  return m;
}

/* central differences of q and q̇ at t against the analytic q̇ and q̈ */
static void check_derivatives(const urt_traj_t *tr, double t, double h, double tol_qd,
                              double tol_qdd) {
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  double qp[URT_NJ], qdp[URT_NJ], qm[URT_NJ], qdm[URT_NJ];
  urt_traj_eval(tr, t, q, qd, qdd);
  urt_traj_eval(tr, t + h, qp, qdp, NULL);
  urt_traj_eval(tr, t - h, qm, qdm, NULL);
  for (int j = 0; j < URT_NJ; j++) {
    assert_near((qp[j] - qm[j]) / (2 * h), qd[j], tol_qd);
    assert_near((qdp[j] - qdm[j]) / (2 * h), qdd[j], tol_qdd);
  }
}

/* every phase boundary of a pick-and-place, to keep finite differences off the kinks */
static int near_boundary(const urt_traj_pickplace_t *p, double t, double h) {
  for (int k = 0; k < p->n; k++) {
    const urt_traj_move_t *mv = &p->move[k];
    double b[4] = {mv->t0, mv->t0 + mv->t_acc, mv->t0 + mv->t_acc + mv->t_cruise, mv->t_stop};
    for (int i = 0; i < 4; i++) {
      if (fabs(t - b[i]) <= 2 * h) {
        return 1;
      }
    }
  }
  return 0;
}

//---- excitation ----

static void test_traj_fourier__starts_and_ends_at_rest_at_q0(void **state) {
  (void)state;
  for (uint64_t seed = 1; seed <= 20; seed++) {
    urt_traj_fourier_t f;
    assert_int_equal(urt_traj_fourier_random(&f, home, NULL, seed), 0);
    double T = 1.0 / f.f_f;
    assert_near(T, 10.0, 1e-12);

    // the rest conditions hold on the coefficients themselves
    for (int i = 0; i < URT_NJ; i++) {
      double sa = 0.0, slb = 0.0;
      for (int l = 1; l <= f.n; l++) {
        sa += f.a[i][l - 1];
        slb += l * f.b[i][l - 1];
      }
      assert_near(sa, 0.0, 1e-14);
      assert_near(slb, 0.0, 1e-14);
    }

    // evaluate the series just inside both ends (outside, eval holds q0 by definition)
    const double ends[2] = {1e-300, T * (1.0 - 1e-15)};
    for (int e = 0; e < 2; e++) {
      double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
      urt_traj_fourier_eval(&f, ends[e], q, qd, qdd);
      for (int j = 0; j < URT_NJ; j++) {
        assert_near(q[j], home[j], 1e-12);
        assert_near(qd[j], 0.0, 1e-12);
        assert_near(qdd[j], 0.0, 1e-12);
      }
    }
  }
}

static void test_traj_fourier__holds_q0_at_rest_outside_its_duration(void **state) {
  (void)state;
  urt_traj_fourier_t f;
  assert_int_equal(urt_traj_fourier_random(&f, home, NULL, 7), 0);
  const double ts[3] = {-1.0, 0.0, 10.0 + 1e-9};
  for (int k = 0; k < 3; k++) {
    double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
    urt_traj_fourier_eval(&f, ts[k], q, qd, qdd);
    assert_memory_equal(q, home, sizeof q);
    assert_true(max_abs6(qd) == 0.0 && max_abs6(qdd) == 0.0);
  }
}

/* dense sampling (5× the generator's grid, offset from it) never exceeds a bound, and the
 * tightest bound of each joint is met to within the certified margin */
static void check_fourier_bounds(const urt_traj_fourier_t *f, const urt_traj_fourier_opts_t *o) {
  double amp[URT_NJ] = {0}, qd_pk[URT_NJ] = {0}, qdd_pk[URT_NJ] = {0};
  double T = f->periods / f->f_f;
  const int n = 20480;
  for (int k = 0; k <= n; k++) {
    double t = T * (k + 0.37) / n, q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
    urt_traj_fourier_eval(f, t, q, qd, qdd);
    for (int j = 0; j < URT_NJ; j++) {
      amp[j] = fmax(amp[j], fabs(q[j] - f->q0[j]));
      qd_pk[j] = fmax(qd_pk[j], fabs(qd[j]));
      qdd_pk[j] = fmax(qdd_pk[j], fabs(qdd[j]));
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    assert_true(amp[j] <= o->amp_max[j]);
    assert_true(qd_pk[j] <= o->qd_max[j]);
    assert_true(qdd_pk[j] <= o->qdd_max[j]);
    double use = fmax(amp[j] / o->amp_max[j],
                      fmax(qd_pk[j] / o->qd_max[j], qdd_pk[j] / o->qdd_max[j]));
    assert_true(use > 0.999);
  }
}

static void test_traj_fourier__respects_its_bounds_and_meets_the_tightest(void **state) {
  (void)state;
  urt_traj_fourier_opts_t o;
  urt_traj_fourier_opts_default(&o);
  for (uint64_t seed = 1; seed <= 10; seed++) {
    urt_traj_fourier_t f;
    assert_int_equal(urt_traj_fourier_random(&f, home, &o, seed), 0);
    check_fourier_bounds(&f, &o);
  }

  // faster and with more harmonics, so that the speed and acceleration bounds bind too
  o.f_f = 0.5;
  o.n = 8;
  o.periods = 2;
  for (int j = 0; j < URT_NJ; j++) {
    o.amp_max[j] = 2.0;
    o.qd_max[j] = 0.5 + 0.1 * j;
    o.qdd_max[j] = j % 2 ? 2.0 : 20.0;
  }
  for (uint64_t seed = 100; seed < 110; seed++) {
    urt_traj_fourier_t f;
    assert_int_equal(urt_traj_fourier_random(&f, home, &o, seed), 0);
    check_fourier_bounds(&f, &o);
  }
}

static void test_traj_fourier__derivatives_match_finite_differences(void **state) {
  (void)state;
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_excitation(&tr, home, NULL, 42), 0);
  for (int k = 1; k < 200; k++) {
    check_derivatives(&tr, 0.05 * k + 0.001, 1e-5, 1e-8, 1e-8);
  }
}

static void test_traj_fourier__same_seed_gives_same_bits(void **state) {
  (void)state;
  urt_traj_fourier_t f1, f2, f3;
  assert_int_equal(urt_traj_fourier_random(&f1, home, NULL, 12345), 0);
  assert_int_equal(urt_traj_fourier_random(&f2, home, NULL, 12345), 0);
  assert_int_equal(urt_traj_fourier_random(&f3, home, NULL, 12346), 0);
  assert_memory_equal(f1.a, f2.a, sizeof f1.a);
  assert_memory_equal(f1.b, f2.b, sizeof f1.b);
  assert_memory_not_equal(f1.a, f3.a, sizeof f1.a);

  double q1[URT_NJ], q2[URT_NJ];
  urt_traj_fourier_eval(&f1, 3.3, q1, NULL, NULL);
  urt_traj_fourier_eval(&f2, 3.3, q2, NULL, NULL);
  assert_memory_equal(q1, q2, sizeof q1);
}

static void test_traj_fourier__rejects_bad_options_and_leaves_f_untouched(void **state) {
  (void)state;
  urt_traj_fourier_t f, before;
  memset(&f, 0xab, sizeof f);
  before = f;
  urt_traj_fourier_opts_t o;

  urt_traj_fourier_opts_default(&o);
  o.n = 0;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);
  o.n = URT_TRAJ_FOURIER_NMAX + 1;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  urt_traj_fourier_opts_default(&o);
  o.f_f = 0.0;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  urt_traj_fourier_opts_default(&o);
  o.periods = 0;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  urt_traj_fourier_opts_default(&o);
  o.qd_max[3] = -1.0;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  urt_traj_fourier_opts_default(&o);
  o.qdd_max[5] = NAN;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  urt_traj_fourier_opts_default(&o);
  o.amp_max[0] = 0.0;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 1), URT_EINVAL);

  double bad_q0[URT_NJ] = {0, 0, NAN, 0, 0, 0};
  assert_int_equal(urt_traj_fourier_random(&f, bad_q0, NULL, 1), URT_EINVAL);

  assert_memory_equal(&f, &before, sizeof f);
}

static void test_traj_fourier__one_harmonic_cannot_move_and_stays_at_q0(void **state) {
  (void)state;
  urt_traj_fourier_opts_t o;
  urt_traj_fourier_opts_default(&o);
  o.n = 1;
  urt_traj_fourier_t f;
  assert_int_equal(urt_traj_fourier_random(&f, home, &o, 3), 0);
  double q[URT_NJ], qd[URT_NJ];
  urt_traj_fourier_eval(&f, 2.5, q, qd, NULL);
  for (int j = 0; j < URT_NJ; j++) {
    assert_near(q[j], home[j], 1e-15);
  }
  assert_true(max_abs6(qd) == 0.0);
}

//---- pick-and-place ----

static void test_traj_pickplace__reaches_every_target_at_rest(void **state) {
  (void)state;
  urt_traj_pickplace_t p;
  assert_int_equal(urt_traj_pickplace_default(&p, home), 0);
  assert_true(p.n >= 8);
  for (int k = 0; k < p.n; k++) {
    const urt_traj_move_t *mv = &p.move[k];
    assert_near(mv->t_stop, mv->t0 + mv->t_acc + mv->t_cruise + mv->t_dec, 1e-12);

    // exactly on target at the stop (where the next move may already accelerate when there
    // is no dwell), and still there at rest through the dwell
    double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
    urt_traj_pickplace_eval(&p, mv->t_stop, q, qd, NULL);
    assert_memory_equal(q, mv->q, sizeof q);
    assert_true(max_abs6(qd) == 0.0);
    if (mv->dwell > 0.0) {
      urt_traj_pickplace_eval(&p, mv->t_stop + 0.5 * mv->dwell, q, qd, qdd);
      assert_memory_equal(q, mv->q, sizeof q);
      assert_true(max_abs6(qd) == 0.0 && max_abs6(qdd) == 0.0);
    }
  }

  // and back home at the end
  double q[URT_NJ];
  urt_traj_pickplace_eval(&p, p.duration + 1.0, q, NULL, NULL);
  assert_memory_equal(q, home, sizeof q);
}

static void test_traj_pickplace__joints_start_and_stop_together(void **state) {
  (void)state;
  urt_traj_pickplace_t p;
  const double to[URT_NJ] = {1.0, -1.2, 1.0, -2.0, -1.3, 0.5};
  urt_traj_pickplace_init(&p, home);
  assert_int_equal(urt_traj_pickplace_add(&p, to, 1.05, 1.4, 0.0, 0.0), 0);
  const urt_traj_move_t *mv = &p.move[0];
  double T = mv->t_acc + mv->t_cruise + mv->t_dec;

  // the lead is the base (|Δq| = 1.0); every joint is a scaled copy of its profile, so each
  // joint's fraction of its own distance is the same at every instant
  assert_int_equal(mv->lead, 0);
  for (int k = 1; k < 100; k++) {
    double t = T * k / 100.0, q[URT_NJ], qd[URT_NJ];
    urt_traj_pickplace_eval(&p, t, q, qd, NULL);
    double frac0 = (q[0] - home[0]) / (to[0] - home[0]);
    assert_true(frac0 > 0.0 && frac0 < 1.0);
    for (int j = 1; j < URT_NJ; j++) {
      assert_near((q[j] - home[j]) / (to[j] - home[j]), frac0, 1e-12);
      assert_true(fabs(qd[j]) > 0.0);
    }
  }
  double q[URT_NJ], qd[URT_NJ];
  urt_traj_pickplace_eval(&p, T, q, qd, NULL);
  assert_memory_equal(q, to, sizeof q);
  assert_true(max_abs6(qd) == 0.0);
}

static void test_traj_pickplace__peak_speed_and_acceleration_are_respected(void **state) {
  (void)state;
  urt_traj_pickplace_t p;
  assert_int_equal(urt_traj_pickplace_default(&p, home), 0);

  // sample densely; the lead joint of each move runs at exactly its (v, a, d), others lower
  double qd_pk[URT_TRAJ_PICKPLACE_NMAX] = {0}, qdd_pk[URT_TRAJ_PICKPLACE_NMAX] = {0};
  for (int k = 0; k < p.n; k++) {
    const urt_traj_move_t *mv = &p.move[k];
    double T = mv->t_acc + mv->t_cruise + mv->t_dec;
    for (int i = 0; i <= 2000 && mv->lead >= 0; i++) {
      double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
      urt_traj_pickplace_eval(&p, mv->t0 + T * i / 2000.0, q, qd, qdd);
      for (int j = 0; j < URT_NJ; j++) {
        assert_true(fabs(qd[j]) <= mv->v);
        assert_true(fabs(qdd[j]) <= fmax(mv->a, mv->d));
      }
      qd_pk[k] = fmax(qd_pk[k], max_abs6(qd));
      qdd_pk[k] = fmax(qdd_pk[k], max_abs6(qdd));
    }
    if (mv->lead >= 0) {
      assert_near(qdd_pk[k], fmax(mv->a, mv->d), 0.0);
      assert_near(qd_pk[k], mv->v_peak, fmax(mv->a, mv->d) * T / 2000.0);
    }
  }

  // every move except the stress event is at or below UR's movej defaults
  int at_defaults = 0;
  for (int k = 0; k < p.n; k++) {
    const urt_traj_move_t *mv = &p.move[k];
    if (mv->v == URT_TRAJ_STRESS_V) {
      continue;
    }
    assert_true(mv->v <= URT_TRAJ_MOVEJ_V && mv->a <= URT_TRAJ_MOVEJ_A);
    at_defaults += mv->lead >= 0 && mv->v == URT_TRAJ_MOVEJ_V && mv->a == URT_TRAJ_MOVEJ_A;
  }
  assert_true(at_defaults >= 3);
}

static void test_traj_pickplace__short_moves_are_triangular(void **state) {
  (void)state;
  urt_traj_pickplace_t p;
  double to[URT_NJ];
  memcpy(to, home, sizeof to);
  to[2] += 0.2;  // 0.2 rad < v²/a = 0.7875 rad needed to reach 1.05 rad/s
  urt_traj_pickplace_init(&p, home);
  assert_int_equal(urt_traj_pickplace_add(&p, to, 1.05, 1.4, 0.0, 0.0), 0);
  const urt_traj_move_t *mv = &p.move[0];
  assert_true(mv->t_cruise == 0.0);
  assert_near(mv->v_peak, sqrt(0.2 * 1.4), 1e-12);
  assert_near(mv->t_acc, mv->t_dec, 1e-15);
  double q[URT_NJ], qd[URT_NJ];
  urt_traj_pickplace_eval(&p, mv->t_acc, q, qd, NULL);
  assert_near(qd[2], mv->v_peak, 1e-12);
  assert_near(q[2], home[2] + 0.1, 1e-12);

  // asymmetric: the peak solves v²/2a + v²/2d = D
  urt_traj_pickplace_init(&p, home);
  assert_int_equal(urt_traj_pickplace_add(&p, to, 1.05, 1.0, 3.0, 0.0), 0);
  mv = &p.move[0];
  assert_near(mv->v_peak * mv->v_peak * (1 / 2.0 + 1 / 6.0), 0.2, 1e-12);
  assert_near(mv->t_acc, 3 * mv->t_dec, 1e-12);
}

static void test_traj_pickplace__derivatives_match_finite_differences(void **state) {
  (void)state;
  urt_traj_t tr;
  assert_int_equal(urt_traj_make_pickplace(&tr, home), 0);
  const double h = 1e-6;
  int n = 0;
  for (double t = 0.0013; t < tr.u.pp.duration; t += 0.0101) {
    if (near_boundary(&tr.u.pp, t, h)) {
      continue;
    }
    // q is piecewise quadratic, so central differences are exact up to rounding
    check_derivatives(&tr, t, h, 1e-7, 1e-7);
    n++;
  }
  assert_true(n > 1000);

  // and q, q̇ are continuous across every phase boundary
  for (int k = 0; k < tr.u.pp.n; k++) {
    const urt_traj_move_t *mv = &tr.u.pp.move[k];
    double b[3] = {mv->t0 + mv->t_acc, mv->t0 + mv->t_acc + mv->t_cruise, mv->t_stop};
    for (int i = 0; i < 3; i++) {
      double qa[URT_NJ], qda[URT_NJ], qb[URT_NJ], qdb[URT_NJ];
      urt_traj_eval(&tr, b[i] - 1e-9, qa, qda, NULL);
      urt_traj_eval(&tr, b[i] + 1e-9, qb, qdb, NULL);
      for (int j = 0; j < URT_NJ; j++) {
        assert_near(qa[j], qb[j], 1e-8);
        assert_near(qda[j], qdb[j], 1e-6);
      }
    }
  }
}

static void test_traj_pickplace__default_stops_wrist2_from_180_at_2500_deg_s2(void **state) {
  (void)state;
  urt_traj_pickplace_t p;
  assert_int_equal(urt_traj_pickplace_default(&p, home), 0);

  // exactly one move is the stress event, and only wrist 2 moves in it
  const urt_traj_move_t *mv = NULL;
  for (int k = 0; k < p.n; k++) {
    if (p.move[k].v == URT_TRAJ_STRESS_V) {
      assert_null(mv);
      mv = &p.move[k];
    }
  }
  assert_non_null(mv);
  assert_int_equal(mv->lead, 4);
  for (int j = 0; j < URT_NJ; j++) {
    if (j != 4) {
      assert_true(mv->ratio[j] == 0.0);
    }
  }
  double a_stop = 2500.0 * PI / 180.0;
  assert_near(mv->d, a_stop, 1e-12);
  assert_true(mv->v_peak == PI);  // a cruise at 180°/s, not a triangle
  assert_true(mv->t_cruise > 0.2);
  assert_near(mv->t_dec, 0.072, 0.0005);

  // the profile: 180°/s up to the stop, then q̈ = −2500°/s² until q̇ = 0, then rest
  double t_stop = mv->t0 + mv->t_acc + mv->t_cruise;
  double t_end = mv->t_stop;
  assert_near(t_end, 8.5, 0.1);
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  urt_traj_pickplace_eval(&p, t_stop - 0.01, q, qd, qdd);
  assert_true(qd[4] == PI && qdd[4] == 0.0);
  for (int i = 0; i < 10; i++) {
    double t = t_stop + mv->t_dec * (i + 0.5) / 10.0;
    urt_traj_pickplace_eval(&p, t, q, qd, qdd);
    assert_true(qdd[4] == -a_stop);
    assert_near(qd[4], a_stop * (t_end - t), 1e-9);
    assert_true(max_abs6(qd) == fabs(qd[4]));
  }
  urt_traj_pickplace_eval(&p, t_end, q, qd, qdd);
  assert_memory_equal(q, mv->q, sizeof q);
  assert_true(qd[4] == 0.0 && qdd[4] == 0.0);
}

static void test_traj_pickplace__add_rejects_bad_moves_and_overflow(void **state) {
  (void)state;
  urt_traj_pickplace_t p, before;
  urt_traj_pickplace_init(&p, home);
  before = p;
  double bad_q[URT_NJ] = {0, 0, 0, INFINITY, 0, 0};
  assert_int_equal(urt_traj_pickplace_add(&p, bad_q, 1, 1, 0, 0), URT_EINVAL);
  assert_int_equal(urt_traj_pickplace_add(&p, home, 0, 1, 0, 0), URT_EINVAL);
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, -1, 0, 0), URT_EINVAL);
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, 1, -1, 0), URT_EINVAL);
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, 1, 0, -0.1), URT_EINVAL);
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, NAN, 0, 0), URT_EINVAL);
  assert_memory_equal(&p, &before, sizeof p);

  // a move to where the arm is, is a pure dwell
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, 1, 0, 0.25), 0);
  assert_int_equal(p.move[0].lead, -1);
  assert_near(p.duration, 0.25, 0.0);

  for (int k = 1; k < URT_TRAJ_PICKPLACE_NMAX; k++) {
    assert_int_equal(urt_traj_pickplace_add(&p, home, 1, 1, 0, 0.01), 0);
  }
  before = p;
  assert_int_equal(urt_traj_pickplace_add(&p, home, 1, 1, 0, 0.01), URT_ENOSPC);
  assert_memory_equal(&p, &before, sizeof p);

  double non_finite[URT_NJ] = {NAN, 0, 0, 0, 0, 0};
  assert_int_equal(urt_traj_pickplace_default(&p, non_finite), URT_EINVAL);
}

//---- any trajectory, and the check against a model ----

static void test_traj__hold_stays_put_and_reports_its_duration(void **state) {
  (void)state;
  urt_traj_t tr;
  urt_traj_make_hold(&tr, home, 2.5);
  assert_near(urt_traj_duration(&tr), 2.5, 0.0);
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  urt_traj_eval(&tr, 1.0, q, qd, qdd);
  assert_memory_equal(q, home, sizeof q);
  assert_true(max_abs6(qd) == 0.0 && max_abs6(qdd) == 0.0);
  assert_string_equal(urt_traj_kind_name(tr.kind), "hold");

  assert_int_equal(urt_traj_make_excitation(&tr, home, NULL, 1), 0);
  assert_near(urt_traj_duration(&tr), 10.0, 1e-12);
  assert_string_equal(urt_traj_kind_name(tr.kind), "excitation");
  assert_int_equal(urt_traj_make_pickplace(&tr, home), 0);
  assert_near(urt_traj_duration(&tr), tr.u.pp.duration, 0.0);
  assert_string_equal(urt_traj_kind_name(tr.kind), "pickplace");
}

static urt_model_t model;

static void set_limits(double q_range, double qd_max, double qdd_max) {
  memset(&model, 0, sizeof model);
  for (int j = 0; j < URT_NJ; j++) {
    snprintf(model.joint[j].name, sizeof model.joint[j].name, "j%d", j + 1);
    model.joint[j].q_min = -q_range;
    model.joint[j].q_max = q_range;
    model.joint[j].qd_max = qd_max;
    model.joint[j].qdd_max = qdd_max;
  }
}

static void test_traj_check__accepts_within_limits_and_refuses_each_violation(void **state) {
  (void)state;
  char err[256];
  urt_traj_t tr;

  // UR5-like limits that let the stress event through
  assert_int_equal(urt_traj_make_pickplace(&tr, home), 0);
  set_limits(2 * PI, PI, 50.0);
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), 0);

  // 180°/s is exactly allowed at qd_max = π, not above a hair less
  model.joint[4].qd_max = 3.14;
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), URT_ERANGE);
  assert_non_null(strstr(err, "joint 5 (j5): peak speed"));
  assert_non_null(strstr(err, "qd_max"));

  set_limits(2 * PI, PI, 40.0);
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), URT_ERANGE);
  assert_non_null(strstr(err, "peak acceleration"));

  set_limits(1.6, PI, 50.0);  // home has |q| = π/2 < 1.6 but the pick site needs 1.85
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), URT_ERANGE);
  assert_non_null(strstr(err, "joint 3 (j3): highest position 1.85 rad > q_max 1.6 rad"));

  // the excitation checks against its certified bounds
  assert_int_equal(urt_traj_make_excitation(&tr, home, NULL, 5), 0);
  set_limits(2 * PI, 1.0, 3.0);
  assert_int_equal(urt_traj_check(&tr, &model, NULL, 0), 0);
  set_limits(2 * PI, 0.1, 3.0);
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), URT_ERANGE);
  assert_non_null(strstr(err, "excitation trajectory"));
  set_limits(PI / 2 + 0.1, 1.0, 3.0);
  assert_int_equal(urt_traj_check(&tr, &model, err, sizeof err), URT_ERANGE);
  assert_non_null(strstr(err, "position"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_traj_fourier__starts_and_ends_at_rest_at_q0),
      cmocka_unit_test(test_traj_fourier__holds_q0_at_rest_outside_its_duration),
      cmocka_unit_test(test_traj_fourier__respects_its_bounds_and_meets_the_tightest),
      cmocka_unit_test(test_traj_fourier__derivatives_match_finite_differences),
      cmocka_unit_test(test_traj_fourier__same_seed_gives_same_bits),
      cmocka_unit_test(test_traj_fourier__rejects_bad_options_and_leaves_f_untouched),
      cmocka_unit_test(test_traj_fourier__one_harmonic_cannot_move_and_stays_at_q0),
      cmocka_unit_test(test_traj_pickplace__reaches_every_target_at_rest),
      cmocka_unit_test(test_traj_pickplace__joints_start_and_stop_together),
      cmocka_unit_test(test_traj_pickplace__peak_speed_and_acceleration_are_respected),
      cmocka_unit_test(test_traj_pickplace__short_moves_are_triangular),
      cmocka_unit_test(test_traj_pickplace__derivatives_match_finite_differences),
      cmocka_unit_test(test_traj_pickplace__default_stops_wrist2_from_180_at_2500_deg_s2),
      cmocka_unit_test(test_traj_pickplace__add_rejects_bad_moves_and_overflow),
      cmocka_unit_test(test_traj__hold_stays_put_and_reports_its_duration),
      cmocka_unit_test(test_traj_check__accepts_within_limits_and_refuses_each_violation),
  };
  return cmocka_run_group_tests_name("tools/traj", tests, NULL, NULL);
}
