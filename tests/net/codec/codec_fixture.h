/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/codec_fixture.h — a snapshot with a distinct, recognisable value in every
 * field the codecs send, and a small big-endian reader for decoding in tests. The same values
 * are restated in tests/python/test_codec_urx.py. */
#ifndef URT_TEST_CODEC_FIXTURE_H
#define URT_TEST_CODEC_FIXTURE_H

#include <stdint.h>
#include <string.h>

#include "urt/controller.h"
#include "urt/snapshot.h"

/* vector field k of the fixture: element j = k + 0.01·(j + 1) */
static inline void fixture_vec(double *x, int n, double k) {
  for (int j = 0; j < n; j++) {
    x[j] = k + 0.01 * (j + 1);
  }
}

static inline void fixture_snapshot(urt_snapshot_t *s) {
  memset(s, 0, sizeof *s);
  s->tick = 6250;
  s->period = 0.002;
  s->time = 12.5;
  s->sim_time = 12.5;
  fixture_vec(s->q_target, URT_NJ, 1);
  fixture_vec(s->qd_target, URT_NJ, 2);
  fixture_vec(s->qdd_target, URT_NJ, 3);
  fixture_vec(s->i_target, URT_NJ, 4);
  fixture_vec(s->m_target, URT_NJ, 5);
  fixture_vec(s->q, URT_NJ, -1);
  fixture_vec(s->qd, URT_NJ, 7);
  fixture_vec(s->i_actual, URT_NJ, 8);
  fixture_vec(s->i_control, URT_NJ, 9);
  fixture_vec(s->tcp_pose, 6, 10);
  fixture_vec(s->tcp_speed, 6, 11);
  fixture_vec(s->tcp_force, 6, 12);
  fixture_vec(s->tcp_pose_target, 6, 13);
  fixture_vec(s->tcp_speed_target, 6, 14);
  fixture_vec(s->temperature, URT_NJ, 30);
  fixture_vec(s->tool_accel, 3, 15);
  fixture_vec(s->elbow_pos, 3, 16);
  fixture_vec(s->elbow_vel, 3, 17);
  fixture_vec(s->v_actual, URT_NJ, 47);
  fixture_vec(s->tcp_offset, 6, 18);
  for (int j = 0; j < URT_NJ; j++) {
    s->joint_mode[j] = URT_JOINT_MODE_RUNNING;
  }
  s->v_main = 48.5;
  s->v_robot = 48.25;
  s->i_robot = 1.75;
  s->digital_in = 5;
  s->digital_out = 0x30002;
  s->analog_out[0] = 0.25;
  s->analog_out[1] = 0.75;
  s->robot_mode = URT_ROBOT_MODE_RUNNING;
  s->safety_mode = URT_SAFETY_MODE_NORMAL;
  s->safety_status = URT_SAFETY_MODE_NORMAL;
  s->program_state = URT_PROGRAM_PLAYING;
  s->control_mode = 0;
  s->speed_slider = 0.9;
  s->speed_scaling = 0.8;
  s->exec_time = 0.000321;
}

//---- big-endian reader ----

static inline uint32_t rd_u32(const uint8_t *p) {
  return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}
static inline int32_t rd_i32(const uint8_t *p) { return (int32_t)rd_u32(p); }
static inline uint64_t rd_u64(const uint8_t *p) {
  return (uint64_t)rd_u32(p) << 32 | rd_u32(p + 4);
}
static inline double rd_f64(const uint8_t *p) {
  uint64_t u = rd_u64(p);
  double x;
  memcpy(&x, &u, sizeof x);
  return x;
}
static inline float rd_f32(const uint8_t *p) {
  uint32_t u = rd_u32(p);
  float x;
  memcpy(&x, &u, sizeof x);
  return x;
}

#endif
