/* SPDX-License-Identifier: Apache-2.0
 * net/codec/rt_packet.c — the port 30003 real-time packet (protocols.md §1.2–1.3). */
#include "urt/net/rt_packet.h"

#include "urt/net/be_codec.h"

/* A joint-indexed int field (modes) as six doubles. */
static void put_modes(urt_wbuf_t *w, const int32_t x[URT_NJ]) {
  for (int j = 0; j < URT_NJ; j++) {
    urt_be_put_f64(w, (double)x[j]);
  }
}

size_t urt_rt_packet_encode(const urt_version_t *v, const urt_snapshot_t *s, uint8_t *buf,
                            size_t cap) {
  size_t size = urt_version_rt_packet_size(v);
  if (!buf || cap < size) {
    return 0;
  }
  urt_wbuf_t w = urt_wbuf_make(buf, size);

  // header and time
  urt_be_put_i32(&w, (int32_t)size);
  urt_be_put_f64(&w, s->time);

  // joint targets and actuals (offsets 12 … 444)
  urt_be_put_f64v(&w, s->q_target, URT_NJ);
  urt_be_put_f64v(&w, s->qd_target, URT_NJ);
  urt_be_put_f64v(&w, s->qdd_target, URT_NJ);
  urt_be_put_f64v(&w, s->i_target, URT_NJ);
  urt_be_put_f64v(&w, s->m_target, URT_NJ);
  urt_be_put_f64v(&w, s->q, URT_NJ);
  urt_be_put_f64v(&w, s->qd, URT_NJ);
  urt_be_put_f64v(&w, s->i_actual, URT_NJ);
  urt_be_put_f64v(&w, s->i_control, URT_NJ);

  // tool (444 … 684)
  urt_be_put_f64v(&w, s->tcp_pose, 6);
  urt_be_put_f64v(&w, s->tcp_speed, 6);
  urt_be_put_f64v(&w, s->tcp_force, 6);
  urt_be_put_f64v(&w, s->tcp_pose_target, 6);
  urt_be_put_f64v(&w, s->tcp_speed_target, 6);

  // digital inputs, temperatures, timer, test value (684 … 756)
  urt_be_put_f64(&w, (double)s->digital_in);
  urt_be_put_f64v(&w, s->temperature, URT_NJ);
  urt_be_put_f64(&w, s->exec_time);
  urt_be_put_f64(&w, 0.0);

  // modes (756 … 868)
  urt_be_put_f64(&w, (double)s->robot_mode);
  put_modes(&w, s->joint_mode);
  urt_be_put_f64(&w, (double)s->safety_mode);
  urt_be_put_zeros(&w, 6 * 8);

  // accelerometer, reserved, scaling, momentum, two reserved (868 … 972)
  urt_be_put_f64v(&w, s->tool_accel, 3);
  urt_be_put_zeros(&w, 6 * 8);
  urt_be_put_f64(&w, s->speed_scaling);
  urt_be_put_f64(&w, s->momentum);
  urt_be_put_zeros(&w, 2 * 8);

  // power (972 … 1044)
  urt_be_put_f64(&w, s->v_main);
  urt_be_put_f64(&w, s->v_robot);
  urt_be_put_f64(&w, s->i_robot);
  urt_be_put_f64v(&w, s->v_actual, URT_NJ);

  // 3.2+: digital outputs and program state (1044 … 1060)
  if (size >= 1060) {
    urt_be_put_f64(&w, (double)s->digital_out);
    urt_be_put_f64(&w, (double)s->program_state);
  }

  // 3.5+ / 5.0+: elbow (1060 … 1108)
  if (size >= 1108) {
    urt_be_put_f64v(&w, s->elbow_pos, 3);
    urt_be_put_f64v(&w, s->elbow_vel, 3);
  }

  // 3.10+ / 5.4+: safety status (1108 … 1116)
  if (size >= 1116) {
    urt_be_put_f64(&w, (double)s->safety_status);
  }

  // the layout above must fill the packet exactly
  if (w.err || urt_wbuf_len(&w) != size) {
    return 0;
  }
  return size;
}
