/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_arm.c — rigid-arm kinematics and dynamics (core/arm.cpp) against the paper
 * (eq. 8, Table A1 as read in model.md §3, the q = 0 gravity and holding current) and against
 * their own identities: RNEA = M q̈ + bias, forward dynamics inverts RNEA, the Jacobian is the
 * derivative of the pose, gravity is the gradient of the potential energy. Energy conservation
 * over time is tested with the step; Pinocchio cross-checks are in tests/python. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "test_support.h"
#include "urt/core.h"

#define PI 3.14159265358979323846

static urt_model_t *model;

static int setup(void **state) {
  (void)state;
  char err[256] = "";
  if (urt_model_load(urt_test_path("config/ur5.yaml"), NULL, &model, err, sizeof err) != 0) {
    fprintf(stderr, "urt_model_load: %s\n", err);
    return -1;
  }
  return 0;
}

static int teardown(void **state) {
  (void)state;
  urt_model_free(model);
  return 0;
}

//---- helpers ----

/* Uniform numbers in [lo, hi) from splitmix64 with a fixed seed, so a failure reproduces. */
static uint64_t rng_state = 0x5eed2023u;
static double uniform(double lo, double hi) {
  uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return lo + (hi - lo) * (double)(z >> 11) * 0x1.0p-53;
}

static void random_vec(double *x, int n, double lo, double hi) {
  for (int i = 0; i < n; ++i) {
    x[i] = uniform(lo, hi);
  }
}

static double max_abs(const double *x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; ++i) {
    m = fmax(m, fabs(x[i]));
  }
  return m;
}

/* C = A B for row-major 4×4 homogeneous transforms. */
static void mat4_mul(const double A[16], const double B[16], double C[16]) {
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      C[4 * i + j] = A[4 * i] * B[j] + A[4 * i + 1] * B[4 + j] + A[4 * i + 2] * B[8 + j] +
                     A[4 * i + 3] * B[12 + j];
    }
  }
}

/* R = exp([r×]), row-major 3×3, written independently of the code under test. */
static void rotvec_to_matrix(const double r[3], double R[9]) {
  double t = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  double n[3] = {1.0, 0.0, 0.0};
  if (t > 0.0) {
    n[0] = r[0] / t, n[1] = r[1] / t, n[2] = r[2] / t;
  }
  double c = cos(t), s = sin(t), v = 1.0 - c;
  R[0] = c + n[0] * n[0] * v, R[1] = n[0] * n[1] * v - n[2] * s, R[2] = n[0] * n[2] * v + n[1] * s;
  R[3] = n[1] * n[0] * v + n[2] * s, R[4] = c + n[1] * n[1] * v, R[5] = n[1] * n[2] * v - n[0] * s;
  R[6] = n[2] * n[0] * v - n[1] * s, R[7] = n[2] * n[1] * v + n[0] * s, R[8] = c + n[2] * n[2] * v;
}

/* The printed closed form of eq. (8) for link i at joint angle q, row-major 4×4. */
static void eq8(const urt_link_params_t *l, double q, double A[16]) {
  double ct = cos(l->theta + q), st = sin(l->theta + q);
  double ca = cos(l->alpha), sa = sin(l->alpha), cb = cos(l->beta), sb = sin(l->beta);
  const double T[16] = {ct * cb - st * sa * sb, -st * ca, ct * sb + st * sa * cb, l->a * ct,
                        st * cb + ct * sa * sb, ct * ca, st * sb - ct * sa * cb, l->a * st,
                        -ca * sb, sa, ca * cb, l->d,
                        0.0, 0.0, 0.0, 1.0};
  memcpy(A, T, sizeof T);
}

//---- kinematics ----

static void test_arm_frame__chains_the_printed_link_transform_of_eq_8(void **state) {
  (void)state;
  for (int trial = 0; trial < 20; ++trial) {
    double q[URT_NJ], T[16], want[16], next[16];
    random_vec(q, URT_NJ, -PI, PI);
    const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    memcpy(want, id, sizeof want);
    for (int i = 0; i <= URT_NJ; ++i) {
      urt_arm_frame(model, q, i, T);
      for (int k = 0; k < 16; ++k) {
        assert_near(T[k], want[k], 1e-12);
      }
      if (i < URT_NJ) {
        double A[16];
        eq8(&model->arm.link[i], q[i], A);
        mat4_mul(want, A, next);
        memcpy(want, next, sizeof want);
      }
    }
  }
}

static void test_arm_tcp_pose__puts_the_flange_at_a2_plus_a3_and_minus_d4_d6_at_zero(void **state) {
  (void)state;
  const double q[URT_NJ] = {0};
  const urt_link_params_t *l = model->arm.link;
  double T6[16], T7[16], pose[6];
  urt_arm_frame(model, q, URT_NJ, T6);
  urt_arm_frame(model, q, URT_NJ + 1, T7);
  urt_arm_tcp_pose(model, q, pose);
  print_message("flange at q = 0: (%.6f, %.6f, %.6f) m; TCP pose (%.6f, %.6f, %.6f, %.6f, %.6f, "
                "%.6f)\n", T6[3], T6[7], T6[11], pose[0], pose[1], pose[2], pose[3], pose[4],
                pose[5]);

  // the arm lies stretched along −x of the Base frame (model.md §1.8); the calibrated
  // α, β and θ offsets move the flange by a few tenths of a millimetre only
  assert_near(T6[3], l[1].a + l[2].a, 2e-3);
  assert_near(T6[7], -(l[3].d + l[5].d), 2e-3);
  assert_near(T6[11], l[0].d - l[4].d, 2e-3);
  assert_near(T6[3], -0.817, 2e-3);
  assert_near(T6[7], -0.191, 3e-3);  // nominal; the calibrated d4 is 1 mm longer

  // the pose is frame 7 (the TCP) as position + rotation vector
  double R[9];
  rotvec_to_matrix(pose + 3, R);
  for (int k = 0; k < 3; ++k) {
    assert_near(pose[k], T7[4 * k + 3], 1e-15);
    for (int j = 0; j < 3; ++j) {
      assert_near(R[3 * k + j], T7[4 * k + j], 1e-12);
    }
  }
}

static void test_arm_prepare__places_the_tcp_by_offset_and_rotation_vector(void **state) {
  (void)state;
  static urt_model_t m;  // a shallow copy with another TCP; model->tables is not touched
  m = *model;
  const double tcp[6] = {0.01, -0.02, 0.15, 0.3, -1.2, 2.0};
  memcpy(m.arm.tcp, tcp, sizeof tcp);
  urt_arm_prepare(&m.arm);

  double q[URT_NJ], T6[16], T7[16], X[16] = {0}, want[16], R[9];
  random_vec(q, URT_NJ, -PI, PI);
  rotvec_to_matrix(tcp + 3, R);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      X[4 * i + j] = R[3 * i + j];
    }
    X[4 * i + 3] = tcp[i];
  }
  X[15] = 1.0;
  urt_arm_frame(&m, q, URT_NJ, T6);
  urt_arm_frame(&m, q, URT_NJ + 1, T7);
  mat4_mul(T6, X, want);
  for (int k = 0; k < 16; ++k) {
    assert_near(T7[k], want[k], 1e-12);
  }
}

/* The rotation vector must stay exact where the textbook formula r = θ/(2 sin θ) · vee(R − Rᵀ)
 * breaks down: at θ → 0 (0/0) and θ → π (the skew part vanishes). */
static void test_arm_tcp_pose__rotation_vector_is_exact_near_0_and_pi(void **state) {
  (void)state;
  static urt_model_t m;
  m = *model;
  const double q[URT_NJ] = {0.3, -1.1, 0.7, -0.4, 1.3, 2.1};
  double T6[16];
  urt_arm_frame(&m, q, URT_NJ, T6);

  const double angles[] = {0.0, 1e-12, 1e-7, 1e-3, 0.5, PI / 2, 2.0, PI - 1e-3, PI - 1e-7,
                           PI - 1e-12, PI};
  const double axes[][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.48, -0.6, 0.64},
                            {-0.2, 0.4, -0.893}};
  double worst = 0.0;
  for (size_t ia = 0; ia < sizeof axes / sizeof axes[0]; ++ia) {
    double n = sqrt(axes[ia][0] * axes[ia][0] + axes[ia][1] * axes[ia][1] +
                    axes[ia][2] * axes[ia][2]);
    for (size_t it = 0; it < sizeof angles / sizeof angles[0]; ++it) {
      double r[3], R[9], pose[6];
      for (int k = 0; k < 3; ++k) {
        r[k] = angles[it] * axes[ia][k] / n;
      }

      // choose the flange→TCP rotation R6ᵀ R so that the TCP orientation is exactly R
      rotvec_to_matrix(r, R);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          m.arm.tcp_fixed[4 * i + j] = T6[i] * R[j] + T6[4 + i] * R[3 + j] + T6[8 + i] * R[6 + j];
        }
      }
      urt_arm_tcp_pose(&m, q, pose);
      double err = 0.0, err_flip = 0.0;
      for (int k = 0; k < 3; ++k) {
        err = fmax(err, fabs(pose[3 + k] - r[k]));
        err_flip = fmax(err_flip, fabs(pose[3 + k] + r[k]));
      }

      // at exactly π, r and −r are the same rotation and either is correct
      double got = angles[it] == PI ? fmin(err, err_flip) : err;
      if (!(got <= 1e-9)) {
        fail_msg("angle %.17g about axis %zu: rotvec error %.3g", angles[it], ia, got);
      }
      worst = fmax(worst, got);
      double t = sqrt(pose[3] * pose[3] + pose[4] * pose[4] + pose[5] * pose[5]);
      assert_true(t <= PI);
    }
  }
  print_message("rotation vector near 0 and π: max error %.2g rad\n", worst);
}

static void test_arm_jacobian__matches_finite_differences_of_the_tcp_pose(void **state) {
  (void)state;
  const double h = 1e-6;
  double worst_v = 0.0, worst_w = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    double q[URT_NJ], J[36];
    random_vec(q, URT_NJ, -PI, PI);
    urt_arm_jacobian(model, q, J);
    for (int j = 0; j < URT_NJ; ++j) {
      double qp[URT_NJ], qm[URT_NJ], Tp[16], Tm[16];
      memcpy(qp, q, sizeof qp);
      memcpy(qm, q, sizeof qm);
      qp[j] += h;
      qm[j] -= h;
      urt_arm_frame(model, qp, URT_NJ + 1, Tp);
      urt_arm_frame(model, qm, URT_NJ + 1, Tm);

      // linear rows: central difference of the TCP position; angular rows: the small rotation
      // Rp Rmᵀ ≈ 1 + [2h ω×], read from its skew part
      double D[9];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          D[3 * a + b] = Tp[4 * a] * Tm[4 * b] + Tp[4 * a + 1] * Tm[4 * b + 1] +
                         Tp[4 * a + 2] * Tm[4 * b + 2];
        }
      }
      const double w[3] = {(D[7] - D[5]) / (4 * h), (D[2] - D[6]) / (4 * h),
                           (D[3] - D[1]) / (4 * h)};
      for (int k = 0; k < 3; ++k) {
        double v = (Tp[4 * k + 3] - Tm[4 * k + 3]) / (2 * h);
        worst_v = fmax(worst_v, fabs(J[6 * k + j] - v));
        worst_w = fmax(worst_w, fabs(J[6 * (3 + k) + j] - w[k]));
      }
    }
  }
  print_message("Jacobian vs finite differences: max error %.2g m/rad (v), %.2g (ω)\n", worst_v,
                worst_w);
  assert_true(worst_v < 1e-8);
  assert_true(worst_w < 1e-8);
}

//---- dynamics ----

/* Table A1 = M_ii(q) + τ² J_M (model.md §0.1, §3); the paper's printed values are expected. */
static void test_arm_mass_matrix__plus_reflected_rotor_inertia_reproduces_table_a1(void **state) {
  (void)state;
  static const double paper[3][URT_NJ] = {{5.628, 5.719, 2.649, 0.228, 0.215, 0.212},
                                          {3.194, 4.144, 2.526, 0.227, 0.215, 0.212},
                                          {2.061, 2.752, 2.405, 0.226, 0.215, 0.212}};
  static const char *row[3] = {"max", "mean", "min"};
  double got[3][URT_NJ];
  for (int i = 0; i < URT_NJ; ++i) {
    const double tau = model->gear[i].ratio;
    const double reflected = tau * tau * model->motor[i].j;

    // sweep joints i+1 and i+2 (those that exist) over [−π, π) on a 1° grid, others at 0
    const int n1 = i + 1 < URT_NJ ? 360 : 1, n2 = i + 2 < URT_NJ ? 360 : 1;
    double hi = -INFINITY, lo = INFINITY, sum = 0.0;
    for (int s1 = 0; s1 < n1; ++s1) {
      for (int s2 = 0; s2 < n2; ++s2) {
        double q[URT_NJ] = {0}, M[36];
        if (i + 1 < URT_NJ) {
          q[i + 1] = -PI + s1 * PI / 180.0;
        }
        if (i + 2 < URT_NJ) {
          q[i + 2] = -PI + s2 * PI / 180.0;
        }
        urt_arm_mass_matrix(model, q, M);
        double v = M[7 * i] + reflected;
        hi = fmax(hi, v);
        lo = fmin(lo, v);
        sum += v;
      }
    }
    got[0][i] = hi;
    got[1][i] = sum / (n1 * n2);
    got[2][i] = lo;
  }
  for (int r = 0; r < 3; ++r) {
    print_message("Table A1 %-4s:", row[r]);
    for (int i = 0; i < URT_NJ; ++i) {
      print_message(" %.4f/%.3f (%+.2f%%)", got[r][i], paper[r][i],
                    100.0 * (got[r][i] / paper[r][i] - 1.0));
    }
    print_message("\n");
  }
  for (int r = 0; r < 3; ++r) {
    for (int i = 0; i < URT_NJ; ++i) {
      if (!(fabs(got[r][i] / paper[r][i] - 1.0) <= 0.02)) {
        fail_msg("Table A1 %s, joint %d: %.4f vs paper %.3f", row[r], i + 1, got[r][i],
                 paper[r][i]);
      }
    }
  }
}

static void test_arm_gravity__matches_model_md_at_zero_pose(void **state) {
  (void)state;
  static const double want[URT_NJ] = {0.0, -53.81, -15.63, -1.4e-3, 2.4e-4, 0.0};
  const double q[URT_NJ] = {0};
  double g[URT_NJ];
  urt_arm_gravity(model, q, g);
  print_message("gravity at q = 0: [%.6g, %.6g, %.6g, %.4g, %.4g, %.4g] N m\n", g[0], g[1], g[2],
                g[3], g[4], g[5]);
  for (int i = 0; i < URT_NJ; ++i) {
    // 0.5 % on the shoulder and elbow; the wrist values are small differences of calibration
    // offsets, so they get an absolute tolerance
    double tol = fabs(want[i]) > 1.0 ? 5e-3 * fabs(want[i]) : 1e-4;
    assert_near(g[i], want[i], tol);
  }
}

static void test_arm_gravity__needs_3_913_a_of_shoulder_current_at_zero_pose(void **state) {
  (void)state;
  const double q[URT_NJ] = {0};
  double g[URT_NJ];
  urt_arm_gravity(model, q, g);

  // static torque ratio of the gear, τ / cos² α_n = 101.03 (harmonic_drive.h)
  const urt_harmonic_drive_params_t *gear = &model->gear[1];
  const double ratio = gear->ratio / (cos(gear->alpha_n) * cos(gear->alpha_n));
  const double current = fabs(g[1]) / (model->motor[1].kt * ratio);
  print_message("shoulder holding current at q = 0: %.4f A (static ratio %.4f)\n", current, ratio);
  assert_near(current, 3.913, 5e-3 * 3.913);
}

static void test_arm_gravity__is_the_gradient_of_the_potential_energy(void **state) {
  (void)state;
  const double h = 1e-5, zero[URT_NJ] = {0};
  for (int trial = 0; trial < 20; ++trial) {
    double q[URT_NJ], g[URT_NJ];
    random_vec(q, URT_NJ, -PI, PI);
    urt_arm_gravity(model, q, g);
    for (int j = 0; j < URT_NJ; ++j) {
      double qp[URT_NJ], qm[URT_NJ];
      memcpy(qp, q, sizeof qp);
      memcpy(qm, q, sizeof qm);
      qp[j] += h;
      qm[j] -= h;
      double dv = (urt_arm_energy(model, qp, zero) - urt_arm_energy(model, qm, zero)) / (2 * h);
      assert_near(g[j], dv, 1e-6);
    }
  }
}

static void test_arm_energy__kinetic_part_is_half_qd_m_qd(void **state) {
  (void)state;
  const double zero[URT_NJ] = {0};
  for (int trial = 0; trial < 100; ++trial) {
    double q[URT_NJ], qd[URT_NJ], M[36];
    random_vec(q, URT_NJ, -PI, PI);
    random_vec(qd, URT_NJ, -3.0, 3.0);
    urt_arm_mass_matrix(model, q, M);
    double t = 0.0;
    for (int i = 0; i < URT_NJ; ++i) {
      for (int j = 0; j < URT_NJ; ++j) {
        t += 0.5 * qd[i] * M[6 * i + j] * qd[j];
      }
    }
    double e = urt_arm_energy(model, q, qd) - urt_arm_energy(model, q, zero);
    assert_near(e, t, 1e-12 * (1.0 + t) + 1e-12);
  }
}

static void test_arm_rnea__equals_m_qdd_plus_bias_and_inverts_forward_dynamics(void **state) {
  (void)state;
  const double zero[URT_NJ] = {0};
  double worst_m = 0.0, worst_fd = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ], tau[URT_NJ], bias[URT_NJ], g[URT_NJ],
        g_rnea[URT_NJ], M[36], back[URT_NJ];
    random_vec(q, URT_NJ, -PI, PI);
    random_vec(qd, URT_NJ, -3.0, 3.0);
    random_vec(qdd, URT_NJ, -10.0, 10.0);
    urt_arm_rnea(model, q, qd, qdd, tau);
    urt_arm_rnea(model, q, qd, zero, bias);
    urt_arm_rnea(model, q, zero, zero, g_rnea);
    urt_arm_gravity(model, q, g);
    urt_arm_mass_matrix(model, q, M);
    double scale = 1.0 + max_abs(tau, URT_NJ);

    // M is symmetric and M q̈ + (C q̇ + g) is what RNEA returns
    for (int i = 0; i < URT_NJ; ++i) {
      double mq = bias[i];
      for (int j = 0; j < URT_NJ; ++j) {
        assert_near(M[6 * i + j], M[6 * j + i], 1e-14);
        mq += M[6 * i + j] * qdd[j];
      }
      worst_m = fmax(worst_m, fabs(mq - tau[i]) / scale);
      assert_near(g[i], g_rnea[i], 1e-12 * scale);
    }

    // forward dynamics takes the torque back to the acceleration
    urt_arm_forward_dynamics(model, q, qd, tau, back);
    for (int i = 0; i < URT_NJ; ++i) {
      worst_fd = fmax(worst_fd, fabs(back[i] - qdd[i]) / (1.0 + max_abs(qdd, URT_NJ)));
    }
  }
  print_message("RNEA vs M qdd + bias: max rel error %.2g; forward dynamics round trip: %.2g\n",
                worst_m, worst_fd);
  assert_true(worst_m < 1e-12);
  assert_true(worst_fd < 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_arm_frame__chains_the_printed_link_transform_of_eq_8),
      cmocka_unit_test(test_arm_tcp_pose__puts_the_flange_at_a2_plus_a3_and_minus_d4_d6_at_zero),
      cmocka_unit_test(test_arm_prepare__places_the_tcp_by_offset_and_rotation_vector),
      cmocka_unit_test(test_arm_tcp_pose__rotation_vector_is_exact_near_0_and_pi),
      cmocka_unit_test(test_arm_jacobian__matches_finite_differences_of_the_tcp_pose),
      cmocka_unit_test(test_arm_mass_matrix__plus_reflected_rotor_inertia_reproduces_table_a1),
      cmocka_unit_test(test_arm_gravity__matches_model_md_at_zero_pose),
      cmocka_unit_test(test_arm_gravity__needs_3_913_a_of_shoulder_current_at_zero_pose),
      cmocka_unit_test(test_arm_gravity__is_the_gradient_of_the_potential_energy),
      cmocka_unit_test(test_arm_energy__kinetic_part_is_half_qd_m_qd),
      cmocka_unit_test(test_arm_rnea__equals_m_qdd_plus_bias_and_inverts_forward_dynamics),
  };
  return cmocka_run_group_tests_name("core/arm", tests, setup, teardown);
}
