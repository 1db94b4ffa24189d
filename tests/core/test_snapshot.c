/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_snapshot.c — urt_snapshot_fill: what the snapshot reports comes from what a
 * controller can know (the encoders), not from the physics' true state. */
#include <string.h>

#include "controller_harness.h"
#include "test_support.h"
#include "urt/snapshot.h"

// The actual TCP pose is the forward kinematics of the measured joint angles (s.q), exactly:
// with the default sensors (noise and quantisation) the true state differs from s.q, so a pose
// computed from the true state would not match.
static void test_snapshot__tcp_pose_is_the_kinematics_of_the_measured_q(void **state) {
  (void)state;
  rig_t r = rig_new(NULL, 0.002, 1);
  run_for(&r, 0.2);
  urt_snapshot_t s;
  memset(&s, 0, sizeof s);
  urt_snapshot_fill(r.m, r.c, r.d, &s);
  double pose[6], truth[6];
  urt_ctrl_forward_kinematics_tcp(r.m, r.c->tcp_offset, s.q, pose);
  tcp_actual(&r, truth);
  int differs = 0;
  for (int i = 0; i < 6; i++) {
    assert_true(s.tcp_pose[i] == pose[i]);
    differs |= truth[i] != pose[i];
  }
  assert_true(differs);  // the rig's sensors are not ideal: the test can tell the two apart
  rig_free(&r);
}

// At rest with ideal-but-quantised encoders the measured q does not change while the true
// state creeps, so two readings of the actual TCP pose are identical (URCL compares them with
// EXPECT_FLOAT_EQ after a refused motion).
static void test_snapshot__tcp_pose_at_rest_is_steady_when_the_encoders_are(void **state) {
  (void)state;
  const char *const quiet[] = {"sensors.noise=false", NULL};
  rig_t r = rig_new(quiet, 0.002, 1);
  run_for(&r, 1.0);
  urt_snapshot_t a, b;
  urt_snapshot_fill(r.m, r.c, r.d, &a);
  run_for(&r, 0.5);
  urt_snapshot_fill(r.m, r.c, r.d, &b);
  if (memcmp(a.q, b.q, sizeof a.q) == 0) {
    for (int i = 0; i < 6; i++) {
      assert_true(a.tcp_pose[i] == b.tcp_pose[i]);
    }
  } else {
    fail_msg("the encoders changed at rest; the test's premise does not hold");
  }
  rig_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_snapshot__tcp_pose_is_the_kinematics_of_the_measured_q),
      cmocka_unit_test(test_snapshot__tcp_pose_at_rest_is_steady_when_the_encoders_are),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
