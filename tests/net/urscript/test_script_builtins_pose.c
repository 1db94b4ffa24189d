/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_builtins_pose.c — the pose algebra and the string, list and
 * math functions against values computed independently: the worked examples of UR's script
 * manual (module urmath) and transforms worked out by hand. */
#include <math.h>

#include "script_run.h"

static script_run R;

static int setup(void **state) {
  memset(&R, 0, sizeof R);
  fake_init(&R.f, &R.host);
  return 0;
}

#define EXPECT(k, tol, ...)                                     \
  do {                                                          \
    const double want_[] = {__VA_ARGS__};                       \
    sr_expect(&R, k, want_, (int)(sizeof want_ / sizeof want_[0]), tol); \
  } while (0)

/* a rotation vector as a matrix (Rodrigues), written out here, not the code under test */
static void rot(const double r[3], double M[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  double k[3] = {r[0] / th, r[1] / th, r[2] / th}, c = cos(th), s = sin(th), v = 1 - c;
  double A[9] = {c + k[0] * k[0] * v, k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s,
                 k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v, k[1] * k[2] * v - k[0] * s,
                 k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v};
  memcpy(M, A, sizeof A);
}

static void test_pose__trans_inv_sub_as_the_manual(void **state) {
  sr_must(&R, "textmsg(pose_trans(p[.2,.5,.1,1.57,0,0], p[.2,.5,.6,1.57,0,0]))\n"
              "textmsg(pose_inv(p[.2,.5,.1,1.57,0,3.14]))\n"
              "textmsg(pose_sub(p[.2,.5,.1,1.57,0,0], p[.2,.5,.6,1.57,0,0]))\n");
  EXPECT(0, 1e-4, 0.4, -0.0996, 0.60048, 3.14, 0, 0);
  // the manual's inverse: its position, and the same rotation as its rotation vector
  double x[6], M[9], W[9];
  assert_int_equal(sr_nums(&R, 1, x, 6), 6);
  const double want[6] = {0.19324, 0.41794, -0.29662, 1.23993, 0.0, 2.47985};
  for (int j = 0; j < 3; j++) assert_true(fabs(x[j] - want[j]) < 1e-4);
  rot(x + 3, M);
  rot(want + 3, W);
  for (int j = 0; j < 9; j++) assert_true(fabs(M[j] - W[j]) < 1e-4);
  EXPECT(2, 1e-9, 0, 0, -0.5, 0, 0, 0);
}

static void test_pose__sub_undoes_add(void **state) {
  sr_must(&R, "a = p[0.3, -0.1, 0.5, 0.4, -1.1, 2.0]\n"
              "b = p[-0.2, 0.4, 0.1, -2.2, 0.3, 0.7]\n"
              "c = pose_add(a, pose_sub(b, a))\n"
              "textmsg(pose_dist(c, b) < 1e-9)\n");
  assert_string_equal(R.f.msg[0].text, "True");
}

static void test_pose__distances_as_the_manual(void **state) {
  // manual: pose_dist 2.50394 and point_dist 1.42116 for these two
  sr_must(&R, "a = p[0.4,-0.2,0.4,-3.1,2.8,-2.3]\nb = p[-0.01,-1.5,-0.002,-1.5,1.5,-2.3]\n"
              "textmsg(pose_dist(a, b))\ntextmsg(point_dist(a, b))\n"
              "textmsg(norm(p[-.2,.2,-.2,-1.57,0,3.14]))\n");
  EXPECT(0, 1e-5, 2.50394);
  EXPECT(1, 1e-5, 1.42116);
  EXPECT(2, 1e-5, 3.52768);
}

static void test_pose__interpolate(void **state) {
  sr_must(&R, "textmsg(interpolate_pose(p[.2,.2,.4,0,0,0], p[.2,.2,.6,0,0,0], .5))\n"
              "textmsg(interpolate_pose(p[0,0,0,0,0,0.4], p[1,0,0,0,0,1.2], 0.25))\n"
              "textmsg(interpolate_pose(p[0,0,0,0,0,0.4], p[1,0,0,0,0,1.2], 2))\n"
              "textmsg(interpolate_pose(p[0,0,0,0,0,0.4], p[1,0,0,0,0,1.2], 0))\n");
  EXPECT(0, 1e-9, .2, .2, .5, 0, 0, 0);
  EXPECT(1, 1e-6, 0.25, 0, 0, 0, 0, 0.6);  // about one axis the angle goes linearly
  EXPECT(2, 1e-6, 2, 0, 0, 0, 0, 2.0);     // extrapolated past p_to
  EXPECT(3, 1e-6, 0, 0, 0, 0, 0, 0.4);
}

static void test_pose__interpolate_geodesic_between_two_axes(void **state) {
  // from identity to 90° about x: half way is 45° about x, whatever the path in the numbers
  sr_must(&R, "textmsg(interpolate_pose(p[0,0,0,0,0,0], p[0,0,0,1.5707963267948966,0,0], 0.5))\n"
              "q = interpolate_pose(p[0,0,0,1.5707963267948966,0,0], p[0,0,0,0,1.5707963267948966,0], 0.5)\n"
              "textmsg(norm([q[3], q[4], q[5]]))\n");
  EXPECT(0, 1e-6, 0, 0, 0, M_PI / 4, 0, 0);
  // Rx(90°) to Ry(90°): the relative rotation is 120° (Rxᵀ Ry has trace 0), half of it is 60°
  // from Rx(90°): the result's angle from the identity, by hand, is acos((tr − 1)/2) = 1.23096
  double x[1] = {0};
  assert_int_equal(sr_nums(&R, 1, x, 1), 1);
  assert_true(fabs(x[0] - 1.23096) < 1e-4);
}

static void test_pose__rpy_as_the_manual(void **state) {
  sr_must(&R, "textmsg(rotvec2rpy([3.14,1.57,0]))\ntextmsg(rpy2rotvec([3.14,1.57,0]))\n"
              "textmsg(rotvec2rpy(rpy2rotvec([0.3,-0.2,1.1])))\n");
  EXPECT(0, 1e-5, -2.80856, -0.16202, 0.9);
  EXPECT(1, 1e-5, 2.22153, 0.00177, -2.21976);
  EXPECT(2, 1e-6, 0.3, -0.2, 1.1);
}

static void test_pose__normalize(void **state) {
  sr_must(&R, "textmsg(normalize([0, 1, 1]))\ntextmsg(normalize([0, 5, 0]))\n");
  EXPECT(0, 1e-6, 0, M_SQRT1_2, M_SQRT1_2);
  EXPECT(1, 0, 0, 1, 0);
  assert_int_not_equal(sr_run(&R, "normalize([0, 0, 0])\n"), 0);
  assert_non_null(strstr(R.err.text, "normalize"));
}

static void test_text__bits(void **state) {
  sr_must(&R, "textmsg(binary_list_to_integer([True,False,False,True]))\n"
              "textmsg(binary_list_to_integer(integer_to_binary_list(57)))\n"
              "textmsg(binary_list_to_integer(integer_to_binary_list(-123456)))\n"
              "l = integer_to_binary_list(-1)\ntextmsg(length(l))\ntextmsg(l[31])\n"
              "textmsg(integer_to_binary_list(5)[2])\ntextmsg(binary_list_to_integer([]))\n");
  const char *want[] = {"9", "57", "-123456", "32", "True", "True", "0"};
  for (int k = 0; k < 7; k++) assert_string_equal(R.f.msg[k].text, want[k]);
}

static void test_text__strings(void **state) {
  sr_must(&R, "textmsg(length(\"here I am\"))\ntextmsg(size([1,3,3,6,2]))\n"
              "textmsg(str_find(\"hello world\", \"o\"))\ntextmsg(str_find(\"hello world\", \"o\", 5))\n"
              "textmsg(str_find(\"hello\", \"z\"))\ntextmsg(str_sub(\"hello\", 1, 3))\n"
              "textmsg(str_sub(\"hello\", 2))\ntextmsg(str_at(\"abc\", 1))\n"
              "textmsg(str_empty(\"\"))\ntextmsg(to_num(\"42\") + 1)\ntextmsg(to_num(\"4.5\") + 1)\n");
  const char *want[] = {"9", "5", "4", "7", "-1", "ell", "llo", "b", "True", "43", "5.5"};
  for (int k = 0; k < 11; k++) assert_string_equal(R.f.msg[k].text, want[k]);
  assert_int_not_equal(sr_run(&R, "to_num(\"x1\")\n"), 0);
  assert_non_null(strstr(R.err.text, "not a number"));
  memset(&R.err, 0, sizeof R.err);
  assert_int_not_equal(sr_run(&R, "str_at(\"abc\", 3)\n"), 0);
}

static void test_math__log_takes_the_base_first(void **state) {
  sr_must(&R, "textmsg(log(10., 4.))\n");
  EXPECT(0, 1e-5, 0.60206);  // the manual's example
  assert_int_not_equal(sr_run(&R, "log(1, 4)\n"), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_pose__trans_inv_sub_as_the_manual, setup),
      cmocka_unit_test_setup(test_pose__sub_undoes_add, setup),
      cmocka_unit_test_setup(test_pose__distances_as_the_manual, setup),
      cmocka_unit_test_setup(test_pose__interpolate, setup),
      cmocka_unit_test_setup(test_pose__interpolate_geodesic_between_two_axes, setup),
      cmocka_unit_test_setup(test_pose__rpy_as_the_manual, setup),
      cmocka_unit_test_setup(test_pose__normalize, setup),
      cmocka_unit_test_setup(test_text__bits, setup),
      cmocka_unit_test_setup(test_text__strings, setup),
      cmocka_unit_test_setup(test_math__log_takes_the_base_first, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
