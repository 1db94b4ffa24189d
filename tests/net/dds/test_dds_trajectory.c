/* SPDX-License-Identifier: Apache-2.0
 * tests/net/dds/test_dds_trajectory.c — segment splines (linear, cubic, quintic) hit their
 * points with the given velocities, hold after the end; a late sender delays the trajectory and
 * never skips part of it; trajectory checks refuse bad shapes. */
#include <math.h>
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/dds_messages.h"
#include "urt/net/dds_trajectory.h"

static urt_dds_traj_t two_points(int has_qd, int has_qdd, urt_dds_traj_point_t *p) {
  memset(p, 0, 2 * sizeof *p);
  p[1].t = 2.0;
  for (int j = 0; j < URT_NJ; j++) {
    p[0].q[j] = 0.1 * j;
    p[1].q[j] = 0.1 * j + 1.0;
    p[0].qd[j] = 0.2;
    p[1].qd[j] = -0.3;
    p[0].qdd[j] = 0.5;
    p[1].qdd[j] = -0.4;
  }
  p[0].has_qd = p[1].has_qd = has_qd;
  p[0].has_qdd = p[1].has_qdd = has_qdd;
  urt_dds_traj_t tr = {2, p};
  return tr;
}

static void test_traj__linear_without_velocities(void **state) {
  urt_dds_traj_point_t p[2];
  urt_dds_traj_t tr = two_points(0, 0, p);
  double q[6], qd[6];
  urt_dds_traj_eval(&tr, 0.5, q, qd);
  assert_near(q[3], 0.3 + 0.25, 1e-12);
  assert_near(qd[3], 0.5, 1e-12);
}

static void test_traj__cubic_hits_ends_with_their_velocities(void **state) {
  urt_dds_traj_point_t p[2];
  urt_dds_traj_t tr = two_points(1, 0, p);
  double q[6], qd[6];
  urt_dds_traj_eval(&tr, 0.0, q, qd);
  assert_near(q[2], 0.2, 1e-12);
  assert_near(qd[2], 0.2, 1e-12);
  urt_dds_traj_eval(&tr, 2.0 - 1e-9, q, qd);
  assert_near(q[2], 1.2, 1e-8);
  assert_near(qd[2], -0.3, 1e-7);
}

static void test_traj__quintic_hits_ends_with_velocity_and_acceleration(void **state) {
  urt_dds_traj_point_t p[2];
  urt_dds_traj_t tr = two_points(1, 1, p);
  double q[6], qd[6], q2[6], qd2[6];
  const double h = 1e-6;
  urt_dds_traj_eval(&tr, h, q, qd);
  urt_dds_traj_eval(&tr, 2 * h, q2, qd2);
  assert_near(qd[1], 0.2 + 0.5 * h, 1e-8);
  assert_near((qd2[1] - qd[1]) / h, 0.5, 1e-3);  // start acceleration
  urt_dds_traj_eval(&tr, 2.0 - 2 * h, q, qd);
  urt_dds_traj_eval(&tr, 2.0 - h, q2, qd2);
  assert_near(q2[1], 1.1, 1e-6);
  assert_near((qd2[1] - qd[1]) / h, -0.4, 1e-3);  // end acceleration
}

static void test_traj__holds_the_last_point_at_rest(void **state) {
  urt_dds_traj_point_t p[2];
  urt_dds_traj_t tr = two_points(1, 0, p);
  double q[6], qd[6];
  urt_dds_traj_eval(&tr, 5.0, q, qd);
  for (int j = 0; j < 6; j++) {
    assert_true(q[j] == p[1].q[j]);
    assert_true(qd[j] == 0.0);
  }
  assert_near(urt_dds_traj_duration(&tr), 2.0, 0.0);
}

//---- the trajectory's clock ---------------------------------------------------------------

// The bridge's loop for one set-point per tick (dds_bridge.c, step_trajectory), with the
// command thread asleep over ticks [late_from, late_from + late_for): it sends nothing then and
// sees the newest tick when it wakes. Returns the largest step between consecutive set-points
// of joint 0 and the set-points sent in q_sent (one per send).
static double run_ticks(const urt_dds_traj_t *tr, int ticks, int late_from, int late_for,
                        double *q_sent, int *n_sent) {
  const double period = 0.002;
  urt_dds_traj_clock_t c;
  urt_dds_traj_clock_start(&c, period);  // accepted at tick 0: the start is the next tick
  double prev = tr->p[0].q[0], step_max = 0.0;
  *n_sent = 0;
  for (int k = 0; k < ticks; k++) {
    if (k >= late_from && k < late_from + late_for) {
      continue;
    }
    double time = k * period, q[URT_NJ], qd[URT_NJ];
    double tau = urt_dds_traj_clock_at(&c, time + 2.0 * period);
    urt_dds_traj_eval(tr, tau, q, qd);
    urt_dds_traj_clock_sent(&c, tau, period);
    step_max = fmax(step_max, fabs(q[0] - prev));
    prev = q[0];
    q_sent[(*n_sent)++] = q[0];
  }
  return step_max;
}

static void test_clock__a_late_thread_delays_the_trajectory_never_skips_it(void **state) {
  urt_dds_traj_point_t p[2];
  urt_dds_traj_t tr = two_points(1, 0, p);  // 2 s, cubic, joint 0 from 0 to 1 rad
  static double on_time[2000], late[2000];
  int n_on, n_late;
  double step_on = run_ticks(&tr, 1200, 0, 0, on_time, &n_on);
  // asleep 150 ms (75 ticks) mid-way, as a descheduled host thread was in a failed CI run
  double step_late = run_ticks(&tr, 1200, 500, 75, late, &n_late);
  assert_int_equal(n_on, 1200);
  assert_int_equal(n_late, 1200 - 75);
  // the same set-points in the same order: the path is the same, only later
  for (int i = 0; i < n_late; i++) {
    assert_true(late[i] == on_time[i]);
  }
  // no step larger than on time
  assert_true(step_late <= step_on);
  assert_true(step_on < 3.0 * 0.002);  // ≤ 1.5 rad/s peak for this cubic: no step to refuse
}

static void test_clock__on_time_it_is_the_controllers_clock(void **state) {
  urt_dds_traj_clock_t c;
  urt_dds_traj_clock_start(&c, 1.0);
  double tau = urt_dds_traj_clock_at(&c, 0.6);  // a start 0.4 s ahead (header stamp)
  assert_near(tau, -0.4, 1e-15);
  for (int k = 1; k <= 1000; k++) {
    urt_dds_traj_clock_sent(&c, tau, 0.002);
    tau = urt_dds_traj_clock_at(&c, 0.6 + k * 0.002);
    assert_near(tau, -0.4 + k * 0.002, 1e-12);
  }
}

//---- from a message -----------------------------------------------------------------------

static const char *kNames[6] = {"wrist_3_joint",      "shoulder_pan_joint", "shoulder_lift_joint",
                                "elbow_joint",        "wrist_1_joint",      "wrist_2_joint"};

typedef struct fixture {
  char *names[6];
  double pos[2][6], vel[2][6];
  trajectory_msgs_msg_dds__JointTrajectoryPoint_ pts[2];
  trajectory_msgs_msg_dds__JointTrajectory_ msg;
} fixture_t;

static dds_sequence_double seq(double *v, uint32_t n) {
  dds_sequence_double s = {n, n, v, false};
  return s;
}

static void make_msg(fixture_t *f) {
  memset(f, 0, sizeof *f);
  for (int k = 0; k < 6; k++) {
    f->names[k] = (char *)kNames[k];
    f->pos[0][k] = 0.01 * k;
    f->pos[1][k] = 0.02 * k;
  }
  for (int i = 0; i < 2; i++) {
    f->pts[i].positions = seq(f->pos[i], 6);
    f->pts[i].velocities = seq(f->vel[i], 6);
    f->pts[i].time_from_start.sec = i + 1;
  }
  f->msg.joint_names._length = f->msg.joint_names._maximum = 6;
  f->msg.joint_names._buffer = f->names;
  f->msg.points._length = f->msg.points._maximum = 2;
  f->msg.points._buffer = f->pts;
}

static const double kZero[6] = {0};

static void test_from_msg__maps_by_name_and_starts_at_the_setpoint(void **state) {
  fixture_t f;
  make_msg(&f);
  double q0[6] = {1, 2, 3, 4, 5, 6};
  urt_dds_traj_t tr;
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, q0, kZero, kZero, &tr, NULL, 0), 0);
  assert_int_equal(tr.n, 3);  // the start state, then the two points
  assert_true(tr.p[0].t == 0.0 && tr.p[0].q[4] == 5.0);
  // message index 0 is wrist 3 (joint 5), index 1 shoulder pan (joint 0)
  assert_true(tr.p[1].q[5] == 0.0 && tr.p[1].q[0] == 0.01 && tr.p[2].q[0] == 0.02);
  assert_true(tr.p[2].t == 2.0 && tr.p[2].has_qd && !tr.p[2].has_qdd);
  urt_dds_traj_free(&tr);
}

static void test_from_msg__refuses_bad_shapes_and_values(void **state) {
  fixture_t f;
  urt_dds_traj_t tr;
  char err[160];
  make_msg(&f);
  f.msg.joint_names._length = 5;
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_EPROTO);
  make_msg(&f);
  f.names[3] = "wrist_3_joint";  // twice
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_EPROTO);
  make_msg(&f);
  f.pts[1].positions._length = 5;
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_EPROTO);
  make_msg(&f);
  f.vel[0][2] = NAN;
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_ERANGE);
  make_msg(&f);
  f.pts[1].time_from_start.sec = 1;  // not increasing
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_ERANGE);
  assert_non_null(strstr(err, "not increasing"));
  make_msg(&f);
  f.msg.points._length = 0;
  assert_int_equal(urt_dds_trajectory_from_msg(&f.msg, kZero, kZero, kZero, &tr, err, sizeof err),
                   URT_EPROTO);
}

static void test_forward__servoj_speedj_and_refusals(void **state) {
  double v[7] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7};
  std_msgs_msg_dds__Float64MultiArray_ m;
  memset(&m, 0, sizeof m);
  m.data = seq(v, 6);
  urt_ctrl_cmd_t c;
  assert_int_equal(urt_dds_forward_to_ctrl(&m, 0, 0.1, 10.0, 7, &c), 0);
  assert_int_equal(c.kind, URT_CTRL_SERVOJ);
  assert_true(c.q[5] == 0.6 && c.t == 0.1 && c.id == 7 && c.gain == 2000.0 && c.lookahead_time == 0.03);
  assert_int_equal(urt_dds_forward_to_ctrl(&m, 1, 0.1, 10.0, 8, &c), 0);
  assert_int_equal(c.kind, URT_CTRL_SPEEDJ);
  assert_true(c.a == 10.0 && c.t == 0.1);
  urt_ctrl_cmd_t untouched = c;
  m.data = seq(v, 7);
  assert_int_equal(urt_dds_forward_to_ctrl(&m, 0, 0.1, 10.0, 9, &c), URT_EPROTO);
  m.data = seq(v, 5);
  assert_int_equal(urt_dds_forward_to_ctrl(&m, 0, 0.1, 10.0, 9, &c), URT_EPROTO);
  v[2] = INFINITY;
  m.data = seq(v, 6);
  assert_int_equal(urt_dds_forward_to_ctrl(&m, 0, 0.1, 10.0, 9, &c), URT_ERANGE);
  assert_memory_equal(&c, &untouched, sizeof c);
}

static void test_pose__quaternion_of_the_axis_angle(void **state) {
  urt_snapshot_t s;
  memset(&s, 0, sizeof s);
  geometry_msgs_msg_dds__PoseStamped_ p;
  urt_dds_fill_pose(&s, 0, &p);
  assert_true(p.pose.orientation.w == 1.0 && p.pose.orientation.x == 0.0);
  s.tcp_pose[5] = M_PI / 2;  // 90° about z
  urt_dds_fill_pose(&s, 1500000000, &p);
  assert_near(p.pose.orientation.z, sqrt(0.5), 1e-15);
  assert_near(p.pose.orientation.w, sqrt(0.5), 1e-15);
  assert_int_equal(p.header.stamp.sec, 1);
  assert_int_equal(p.header.stamp.nanosec, 500000000);
  assert_string_equal(p.header.frame_id, "base");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_traj__linear_without_velocities),
      cmocka_unit_test(test_traj__cubic_hits_ends_with_their_velocities),
      cmocka_unit_test(test_traj__quintic_hits_ends_with_velocity_and_acceleration),
      cmocka_unit_test(test_traj__holds_the_last_point_at_rest),
      cmocka_unit_test(test_clock__a_late_thread_delays_the_trajectory_never_skips_it),
      cmocka_unit_test(test_clock__on_time_it_is_the_controllers_clock),
      cmocka_unit_test(test_from_msg__maps_by_name_and_starts_at_the_setpoint),
      cmocka_unit_test(test_from_msg__refuses_bad_shapes_and_values),
      cmocka_unit_test(test_forward__servoj_speedj_and_refusals),
      cmocka_unit_test(test_pose__quaternion_of_the_axis_angle),
  };
  return cmocka_run_group_tests_name("net/dds/trajectory", tests, NULL, NULL);
}
