/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_payload.c — core/payload.cpp (what a payload may be, mounting one on a run)
 * and the payload's way into the arm dynamics (core/arm.cpp) and urt_step. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_model.h"
#include "test_support.h"

static const urt_payload_t kLoad = {3.0, {0.0, 0.0, 0.1}, {0.004, 0.005, 0.003, 0.0005, 0.0, -0.0004}};

static void test_payload__invalid_names_what_no_payload_can_be(void **state) {
  (void)state;
  urt_payload_t p = {0};
  assert_null(urt_payload_invalid(&p));
  assert_null(urt_payload_invalid(&kLoad));
  p = kLoad;
  p.mass = 5.5;
  assert_non_null(strstr(urt_payload_invalid(&p), "mass"));
  p.mass = -0.1;
  assert_non_null(strstr(urt_payload_invalid(&p), "mass"));
  p.mass = NAN;
  assert_non_null(strstr(urt_payload_invalid(&p), "finite"));
  p = kLoad;
  p.cog[1] = -1.2;
  assert_non_null(strstr(urt_payload_invalid(&p), "centre of gravity"));
  p = kLoad;
  p.inertia[0] = -0.001;  // a negative moment: UR refuses it
  assert_non_null(strstr(urt_payload_invalid(&p), "negative"));
  p = kLoad;
  p.inertia[4] = 0.01;  // Ixz² > Ixx Izz: no body's, but UR takes it (its rule is the bounds)
  assert_null(urt_payload_invalid(&p));
  p = kLoad;
  p.inertia[5] = -133.5;
  assert_non_null(strstr(urt_payload_invalid(&p), "133"));
  p = kLoad;
  p.inertia[2] = 200.0;
  assert_non_null(strstr(urt_payload_invalid(&p), "133"));
  // a point mass and a thin rod (one moment zero) are bodies
  urt_payload_t rod = {1.0, {0.0, 0.0, 0.05}, {0.002, 0.002, 0.0, 0.0, 0.0, 0.0}};
  assert_null(urt_payload_invalid(&rod));
}

static void test_payload__set_mounts_a_valid_payload_and_keeps_the_old_on_refusal(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = calloc(1, sizeof *d);
  assert_int_equal(urt_data_init(m, d, NULL), 0);
  assert_int_equal(urt_data_set_payload(m, d, &kLoad), URT_OK);
  assert_memory_equal(&d->live.payload, &kLoad, sizeof kLoad);
  urt_payload_t bad = kLoad;
  bad.mass = 7.0;
  assert_int_equal(urt_data_set_payload(m, d, &bad), URT_EINVAL);
  assert_memory_equal(&d->live.payload, &kLoad, sizeof kLoad);
  free(d);
  urt_model_free(m);
}

static void test_payload__zero_payload_leaves_the_dynamics_bit_for_bit(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  const urt_payload_t none = {0};
  const double q[6] = {0.3, -1.1, 1.2, -0.4, 0.9, -0.2}, qd[6] = {0.5, -0.2, 0.3, 1.0, -0.7, 2.0},
               qdd[6] = {1.0, 2.0, -3.0, 4.0, -5.0, 6.0};
  double a[36], b[36];
  urt_arm_rnea(m, q, qd, qdd, a);
  urt_arm_rnea_payload(m, &none, q, qd, qdd, b);
  assert_memory_equal(a, b, 6 * sizeof *a);
  urt_arm_mass_matrix(m, q, a);
  urt_arm_mass_matrix_payload(m, &none, q, b);
  assert_memory_equal(a, b, 36 * sizeof *a);
  urt_arm_gravity(m, q, a);
  urt_arm_gravity_payload(m, &none, q, b);
  assert_memory_equal(a, b, 6 * sizeof *a);
  urt_model_free(m);
}

/* set_target_payload's transition: linear from the old payload to the new over the time given,
 * one controller period at a time; a change at once ends it */
static void test_payload__transition_is_linear_and_ends_on_the_target(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = calloc(1, sizeof *d);
  assert_int_equal(urt_data_init(m, d, NULL), 0);
  assert_int_equal(urt_data_set_payload_target(m, d, &kLoad, 0.1), URT_OK);
  assert_true(d->live.payload.mass == 0.0);  // nothing yet: the controller's tick advances it
  for (int k = 1; k <= 60; k++) {
    urt_data_live_advance(m, d, 0.002);
    double s = fmin(k * 0.002 / 0.1, 1.0);
    assert_near(d->live.payload.mass, s * kLoad.mass, 1e-12);
    assert_near(d->live.payload.cog[2], s * kLoad.cog[2], 1e-12);
    assert_near(d->live.payload.inertia[5], s * kLoad.inertia[5], 1e-15);
    assert_null(urt_payload_invalid(&d->live.payload));
  }
  assert_memory_equal(&d->live.payload, &kLoad, sizeof kLoad);  // exactly the target at the end
  assert_true(d->live.payload_time_left == 0.0);
  // a transition interrupted by a change at once stops there
  const urt_payload_t none = {0};
  assert_int_equal(urt_data_set_payload_target(m, d, &none, 1.0), URT_OK);
  urt_data_live_advance(m, d, 0.002);
  assert_int_equal(urt_data_set_payload(m, d, &kLoad), URT_OK);
  urt_data_live_advance(m, d, 0.002);
  assert_memory_equal(&d->live.payload, &kLoad, sizeof kLoad);
  // a bad time or payload changes nothing
  assert_int_equal(urt_data_set_payload_target(m, d, &none, -1.0), URT_EINVAL);
  assert_int_equal(urt_data_set_payload_target(m, d, &none, NAN), URT_EINVAL);
  urt_payload_t bad = kLoad;
  bad.mass = 9.0;
  assert_int_equal(urt_data_set_payload_target(m, d, &bad, 1.0), URT_EINVAL);
  assert_true(d->live.payload_time_left == 0.0);
  free(d);
  urt_model_free(m);
}

/* the payload's weight through the flange: Δg = −J_v(c)ᵀ m g, J_v the linear Jacobian of its
 * CoG point (from urt_arm_frame, by central differences) */
static void test_payload__gravity_rises_by_the_weight_at_the_cog(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  const double q[6] = {0.5, -0.3, 0.4, -0.8, 1.0, 0.5};
  double g0[6], g1[6];
  urt_arm_gravity_payload(m, &(urt_payload_t){0}, q, g0);
  urt_arm_gravity_payload(m, &kLoad, q, g1);
  double worst = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    double qp[6], qm[6], Tp[16], Tm[16], dz = 0.0, h = 1e-6;
    memcpy(qp, q, sizeof qp);
    memcpy(qm, q, sizeof qm);
    qp[j] += h;
    qm[j] -= h;
    urt_arm_frame(m, qp, 6, Tp);
    urt_arm_frame(m, qm, 6, Tm);
    for (int k = 0; k < 3; k++) {
      double cp = Tp[4 * k] * kLoad.cog[0] + Tp[4 * k + 1] * kLoad.cog[1] + Tp[4 * k + 2] * kLoad.cog[2] + Tp[4 * k + 3];
      double cm = Tm[4 * k] * kLoad.cog[0] + Tm[4 * k + 1] * kLoad.cog[1] + Tm[4 * k + 2] * kLoad.cog[2] + Tm[4 * k + 3];
      dz -= kLoad.mass * m->arm.gravity[k] * (cp - cm) / (2 * h);
    }
    print_message("joint %d: Δg = %+.9f N m, weight through the Jacobian %+.9f N m\n", j + 1,
                  g1[j] - g0[j], dz);
    worst = fmax(worst, fabs(g1[j] - g0[j] - dz));
  }
  assert_true(worst < 1e-6);
  assert_true(fabs(g1[1] - g0[1]) > 5.0);  // the shoulder carries it
  urt_model_free(m);
}

/* mounted on a running arm, the drive settles at the loaded gravity: i = g(q)/(k_t τ) */
static void test_payload__steps_settle_at_the_loaded_holding_current(void **state) {
  (void)state;
  const char *const ov[] = {"sensors.noise=false", "sensors.quantise=false",
                            "friction_common.enabled=false", NULL};
  urt_model_t *m = urt_test_model(ov);
  urt_data_t *d = calloc(1, sizeof *d);
  const double q0[6] = {0.0, -1.2, 1.0, -1.4, -1.5708, 0.0};
  assert_int_equal(urt_data_init(m, d, q0), 0);
  assert_int_equal(urt_data_set_payload(m, d, &kLoad), URT_OK);
  long before = urt_test_malloc_count();
  urt_test_malloc_arm(1);
  int rc = 0;
  for (int k = 0; k < (int)lround(3.0 / m->dt); k++) {
    rc |= urt_step(m, d);
  }
  urt_test_malloc_arm(0);
  assert_int_equal(urt_test_malloc_count() - before, 0);  // the loaded step allocates nothing
  assert_int_equal(rc, 0);
  double q[6], g[6];
  for (int j = 0; j < URT_NJ; j++) q[j] = d->x[j][URT_X_Q];
  urt_arm_gravity_payload(m, &kLoad, q, g);
  for (int j = 0; j < 3; j++) {
    double want = g[j] / (m->motor[j].kt * m->gear[j].ratio), got = d->x[j][URT_X_I];
    print_message("joint %d: i = %+.6f A, g/(kt τ) with the payload %+.6f A\n", j + 1, got, want);
    assert_near(got, want, fmax(0.01 * fabs(want), 1e-3));
  }
  free(d);
  urt_model_free(m);
}

// The physics carries the nearest PSD tensor: a body's comes back bit for bit; URCL's
// set_target_payload tensor (a negative determinant) gets its negative principal moment raised
// to 0, the other axes and moments kept: the result is PSD, symmetric, and no PSD tensor is
// nearer than it along the removed axis (the difference is −λ v vᵀ).
static void test_payload__physical_is_the_nearest_psd_tensor(void **state) {
  (void)state;
  double out[6];
  urt_payload_physical(kLoad.inertia, out);
  assert_memory_equal(out, kLoad.inertia, sizeof out);
  const double urcl[6] = {0.4, 0.7, 0.8, 0.2, 0.5, 0.6};  // URCL's test tensor: det = -0.007
  urt_payload_t p = {1.0, {0.2, 0.3, 0.1}, {0}};
  memcpy(p.inertia, urcl, sizeof p.inertia);
  assert_null(urt_payload_invalid(&p));
  urt_payload_physical(urcl, out);
  // PSD: every principal minor of the result ≥ 0 (up to rounding)
  double xx = out[0], yy = out[1], zz = out[2], xy = out[3], xz = out[4], yz = out[5];
  double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  assert_true(xx >= 0 && yy >= 0 && zz >= 0);
  assert_true(xx * yy - xy * xy >= -1e-15 && xx * zz - xz * xz >= -1e-15 && yy * zz - yz * yz >= -1e-15);
  assert_true(fabs(det) < 1e-15);  // one principal moment raised to exactly 0
  // nearer than other PSD tensors: the zero tensor, and A shifted by its smallest eigenvalue
  // (A + 0.1 I is PSD here: the negative moment is about -0.05)
  double d2 = 0, d0 = 0, ds = 0;
  for (int i = 0; i < 6; i++) {
    double w = i < 3 ? 1.0 : 2.0;  // off-diagonal elements count twice in the Frobenius norm
    d2 += w * (out[i] - urcl[i]) * (out[i] - urcl[i]);
    d0 += w * urcl[i] * urcl[i];
    ds += i < 3 ? 0.1 * 0.1 : 0.0;
  }
  assert_true(d2 > 0.0 && d2 < d0 && d2 < ds);
  // numpy.linalg.eigh: eigenvalues -0.01308339, 0.34014702, 1.57293637; V diag(max(λ, 0)) Vᵀ
  const double want[6] = {0.4051330304655869, 0.7020054012757757, 0.8059449562435602,
                          0.20320839303145502, 0.4944759035567094, 0.5965471717628471};
  for (int i = 0; i < 6; i++) assert_true(fabs(out[i] - want[i]) < 1e-12);
  // mounting it: the run's physics carries the PSD tensor, the declared one is kept as declared
  const urt_model_t *m = urt_test_model(NULL);
  urt_data_t *d = calloc(1, sizeof *d);
  assert_int_equal(urt_data_init(m, d, NULL), URT_OK);
  assert_int_equal(urt_data_set_payload(m, d, &p), URT_OK);
  assert_memory_equal(d->live.payload_inertia_declared, urcl, sizeof urcl);
  assert_memory_equal(d->live.payload.inertia, out, sizeof out);
  assert_int_equal(urt_data_set_payload_target(m, d, &p, 0.5), URT_OK);
  assert_memory_equal(d->live.payload_target.inertia, out, sizeof out);
  free(d);
  urt_model_free((urt_model_t *)m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_payload__invalid_names_what_no_payload_can_be),
      cmocka_unit_test(test_payload__physical_is_the_nearest_psd_tensor),
      cmocka_unit_test(test_payload__set_mounts_a_valid_payload_and_keeps_the_old_on_refusal),
      cmocka_unit_test(test_payload__zero_payload_leaves_the_dynamics_bit_for_bit),
      cmocka_unit_test(test_payload__transition_is_linear_and_ends_on_the_target),
      cmocka_unit_test(test_payload__gravity_rises_by_the_weight_at_the_cog),
      cmocka_unit_test(test_payload__steps_settle_at_the_loaded_holding_current),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
