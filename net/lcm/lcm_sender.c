/* SPDX-License-Identifier: Apache-2.0
 * net/lcm/lcm_sender.c — status and drive messages from loop data, commands into the
 * controller. Pure: no socket, clock, thread or global. */
#include "urt/net/lcm_sender.h"

#include <math.h>
#include <string.h>

#include "urt/errors.h"

#define COPY6(dst, src) memcpy((dst), (src), 6 * sizeof(double))

//---- status and drive -------------------------------------------------------------------------

void urt_lcm_status_fill(const urt_snapshot_t *s, int64_t publish_utime, int64_t ticks_lost,
                         urtwin_lcmt_urtwin_status *msg) {
  // time: the controller's clock in microseconds, like Drake's simulated status
  msg->utime = (int64_t)llround(s->time * 1e6);
  msg->tick = (int64_t)s->tick;
  msg->time = s->time;
  msg->period = s->period;
  msg->publish_utime = publish_utime;
  msg->ticks_lost = ticks_lost;

  // joints: target, then actual
  COPY6(msg->q_target, s->q_target);
  COPY6(msg->qd_target, s->qd_target);
  COPY6(msg->qdd_target, s->qdd_target);
  COPY6(msg->q_actual, s->q);
  COPY6(msg->qd_actual, s->qd);
  COPY6(msg->qdd_actual, s->qdd);

  // motor currents, torques, voltage, temperature
  COPY6(msg->current_actual, s->i_actual);
  COPY6(msg->current_target, s->i_target);
  COPY6(msg->current_control, s->i_control);
  COPY6(msg->torque_actual, s->tau);
  COPY6(msg->torque_target, s->m_target);
  COPY6(msg->voltage_actual, s->v_actual);
  COPY6(msg->temperature, s->temperature);

  // tool
  COPY6(msg->tcp_pose_actual, s->tcp_pose);
  COPY6(msg->tcp_pose_target, s->tcp_pose_target);
  COPY6(msg->tcp_speed_actual, s->tcp_speed);
  COPY6(msg->tcp_speed_target, s->tcp_speed_target);
  COPY6(msg->tcp_force, s->tcp_force);

  // modes
  msg->robot_mode = s->robot_mode;
  msg->safety_mode = s->safety_mode;
  msg->program_state = s->program_state;
  for (int j = 0; j < 6; ++j) {
    msg->joint_mode[j] = s->joint_mode[j];
  }
  msg->motion = s->motion;
  msg->ctrl_fault = (int32_t)s->ctrl_fault;
  msg->pstop = (int32_t)s->pstop;
  msg->speed_scaling = s->speed_scaling;

  // loop diagnostics
  msg->exec_time = s->exec_time;
  msg->overruns = (int64_t)s->overruns;
  msg->missed_periods = (int64_t)s->missed_periods;
}

void urt_lcm_drive_fill(const urt_drive_sample_t *d, int64_t samples_lost,
                        urtwin_lcmt_urtwin_drive *msg) {
  msg->utime = (int64_t)llround(d->time * 1e6);
  msg->seq = (int64_t)d->seq;
  msg->time = d->time;
  msg->samples_lost = samples_lost;
  COPY6(msg->q, d->q);
  COPY6(msg->qd, d->qd);
  COPY6(msg->motor_angle, d->motor_angle);
  COPY6(msg->motor_speed, d->motor_speed);
  COPY6(msg->current, d->i);
  COPY6(msg->current_reference, d->i_ref);
  COPY6(msg->voltage, d->v);
  COPY6(msg->gear_input_torque, d->gear_in_torque);
  COPY6(msg->gear_output_torque, d->gear_out_torque);
  COPY6(msg->friction_torque, d->friction_torque);
  COPY6(msg->bristle_z, d->bristle_z);
  COPY6(msg->flexspline_x, d->flex_x);
  COPY6(msg->flexspline_y, d->flex_y);
}

//---- commands ---------------------------------------------------------------------------------

static int all_finite(const double *x, int n) {
  for (int i = 0; i < n; ++i) {
    if (!isfinite(x[i])) {
      return 0;
    }
  }
  return 1;
}

// an optional per-joint array: count 0 (absent) or 6 with data
static int optional_ok(int32_t n, const double *x) {
  return n == 0 || (n == URT_NJ && x != NULL);
}

int urt_lcm_command_to_ctrl(const urtwin_lcmt_urtwin_command *msg, uint64_t id,
                            urt_ctrl_cmd_t *out) {
  // shape: six positions, velocities and torques optional
  if (msg->num_joints != URT_NJ || msg->joint_position == NULL ||
      !optional_ok(msg->num_velocities, msg->joint_velocity) ||
      !optional_ok(msg->num_torques, msg->joint_torque)) {
    return URT_EPROTO;
  }

  // values: a NaN must never reach the controller's set-point
  if (!all_finite(msg->joint_position, URT_NJ) ||
      !all_finite(msg->joint_velocity, msg->num_velocities) ||
      !all_finite(msg->joint_torque, msg->num_torques)) {
    return URT_ERANGE;
  }

  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = URT_CTRL_DIRECT;
  c.id = id;
  memcpy(c.q, msg->joint_position, URT_NJ * sizeof(double));
  if (msg->num_velocities == URT_NJ) {
    memcpy(c.qd, msg->joint_velocity, URT_NJ * sizeof(double));
  }
  if (msg->num_torques == URT_NJ) {
    memcpy(c.tau, msg->joint_torque, URT_NJ * sizeof(double));
  }
  *out = c;
  return 0;
}

static int32_t be32_at(const uint8_t *p) {
  return (int32_t)((uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 |
                   (uint32_t)p[3]);
}

int urt_lcm_command_decode(const void *buf, size_t len, uint64_t id, urt_ctrl_cmd_t *out) {
  const uint8_t *b = (const uint8_t *)buf;

  // walk the three counts before the generated decoder sees them: it would allocate whatever
  // a peer's count asks for (layout: hash 8, utime 8, then count 4 + 8·count, three times)
  size_t off = 16;
  for (int k = 0; k < 3; ++k) {
    if (len < off + 4) {
      return URT_EPROTO;
    }
    int32_t n = be32_at(b + off);
    if (n != URT_NJ && !(k > 0 && n == 0)) {
      return URT_EPROTO;
    }
    off += 4 + 8 * (size_t)n;
  }
  if (off != len || len > (size_t)INT32_MAX) {
    return URT_EPROTO;
  }

  // decode (checks the fingerprint), then the same checks as for an in-memory message
  urtwin_lcmt_urtwin_command msg;
  memset(&msg, 0, sizeof msg);
  int used = urtwin_lcmt_urtwin_command_decode(buf, 0, (int)len, &msg);
  int rc = used == (int)len ? urt_lcm_command_to_ctrl(&msg, id, out) : URT_EPROTO;
  urtwin_lcmt_urtwin_command_decode_cleanup(&msg);
  return rc;
}

int urt_lcm_io_decode(const void *buf, size_t len, urt_ctrl_cmd_t *out) {
  if (len > (size_t)INT32_MAX) {
    return URT_EPROTO;
  }
  urtwin_lcmt_urtwin_io msg;
  memset(&msg, 0, sizeof msg);
  if (urtwin_lcmt_urtwin_io_decode(buf, 0, (int)len, &msg) != (int)len) {
    return URT_EPROTO;  // wrong fingerprint, truncated or trailing bytes
  }
  uint32_t dmask = (uint32_t)msg.digital_mask, levels = (uint32_t)msg.digital_levels;
  uint32_t amask = (uint32_t)(uint8_t)msg.analog_mask;
  if (msg.digital_mask < 0 || dmask >= (1u << 18) || (levels & ~dmask) != 0 || amask >= 16u) {
    return URT_ERANGE;
  }
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.kind = URT_CTRL_SET_INPUTS;
  c.index = (int32_t)dmask;
  c.value = (double)levels;
  c.a = (double)amask;
  for (int k = 0; k < 4; k++) {
    if (amask & (1u << k)) {
      if (!(msg.analog[k] >= 0.0 && msg.analog[k] <= 10.0)) {  // NaN fails too
        return URT_ERANGE;
      }
      c.q[k] = msg.analog[k];
    }
  }
  *out = c;
  return 0;
}

//---- faults -----------------------------------------------------------------------------------

// index of name in a table of names (n entries from get(i)), or -1
static int name_index(const char *name, const char *(*get)(int), int n) {
  for (int i = 0; name != NULL && i < n; i++) {
    if (strcmp(name, get(i)) == 0) {
      return i;
    }
  }
  return -1;
}

static const char *location_name(int i) {
  static const char *const kNames[] = {"outer", "inner", "ball"};
  return kNames[i];
}

static int fault_from_msg(const urtwin_lcmt_urtwin_fault *msg, const urt_model_t *m,
                          urt_ctrl_cmd_t *out) {
  urt_fault_spec_t f;
  memset(&f, 0, sizeof f);
  if (msg->inject != 0 && msg->inject != 1) {
    return URT_ERANGE;
  }

  // clearing: "" / −1 match any
  if (msg->inject == 0) {
    const int any_class = msg->fault_class == NULL || msg->fault_class[0] == '\0';
    f.cls = any_class ? -1 : name_index(msg->fault_class, urt_fault_class_name,
                                        urt_fault_class_count());
    if (!any_class && f.cls < 0) {
      return URT_ERANGE;
    }
    if (msg->joint < -1 || msg->joint >= URT_NJ || msg->component < -1 || msg->component > 1) {
      return URT_ERANGE;
    }
    f.joint = msg->joint;
    f.component = msg->component;
    urt_fault_cmd_pack(&f, 0, out);
    return 0;
  }

  // injection: names to numbers, then the scenario file's checks
  f.cls = name_index(msg->fault_class, urt_fault_class_name, urt_fault_class_count());
  f.profile = name_index(msg->profile, urt_fault_profile_name, 5);
  if (f.cls < 0 || f.profile < 0) {
    return URT_ERANGE;
  }
  const int at_tcp = f.cls == URT_FAULT_COLLISION || f.cls == URT_FAULT_PAYLOAD;
  f.joint = at_tcp ? 0 : msg->joint;
  if (at_tcp && msg->joint != -1 && msg->joint != 0) {
    return URT_ERANGE;
  }
  f.component = msg->component;
  f.severity = msg->severity;
  f.onset = msg->onset;
  f.ramp = msg->ramp;
  f.tau = msg->tau;
  f.on = msg->on;
  f.off = msg->off;
  f.sigma = msg->sigma;
  if (msg->seed < 0 || msg->seed >= (INT64_C(1) << 53)) {
    return URT_ERANGE;
  }
  f.seed = (uint64_t)msg->seed;
  if (f.cls == URT_FAULT_COLLISION) {
    const double *u = msg->direction;
    double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(n > 0.0) || !isfinite(n)) {
      return URT_ERANGE;
    }
    for (int i = 0; i < 3; i++) {
      f.direction[i] = u[i] / n;
    }
  }
  if (f.cls == URT_FAULT_PAYLOAD) {
    memcpy(f.offset, msg->offset, sizeof f.offset);
  }
  if (f.cls == URT_FAULT_WG_BEARING) {
    f.location = name_index(msg->location, location_name, 3);
    if (f.location < 0) {
      return URT_ERANGE;
    }
    f.balls = msg->balls;
    f.ball_ratio = msg->ball_ratio;
  } else if ((msg->location != NULL && msg->location[0] != '\0') || msg->balls != 0 ||
             msg->ball_ratio != 0.0) {
    return URT_ERANGE;
  }
  if (m != NULL && urt_fault_spec_invalid(m, &f) != NULL) {
    return URT_ERANGE;
  }
  if (m == NULL && !(isfinite(f.severity) && isfinite(f.onset))) {
    return URT_ERANGE;
  }
  urt_fault_cmd_pack(&f, 1, out);
  return 0;
}

int urt_lcm_fault_decode(const void *buf, size_t len, const urt_model_t *m, urt_ctrl_cmd_t *out) {
  if (len > (size_t)INT32_MAX) {
    return URT_EPROTO;
  }
  urtwin_lcmt_urtwin_fault msg;
  memset(&msg, 0, sizeof msg);
  // (on a failed decode the strings read so far are allocated and the rest NULL: the cleanup
  // frees them either way)
  int used = urtwin_lcmt_urtwin_fault_decode(buf, 0, (int)len, &msg);
  urt_ctrl_cmd_t c;
  int rc = used == (int)len ? fault_from_msg(&msg, m, &c) : URT_EPROTO;
  urtwin_lcmt_urtwin_fault_decode_cleanup(&msg);
  if (rc == 0) {
    *out = c;
  }
  return rc;
}

void urt_lcm_fault_truth_fill(const urt_snapshot_t *s, urt_lcm_fault_truth_buf_t *b) {
  const urt_fault_truth_t *t = &s->fault_truth;
  const int n = t->n < 0 ? 0 : (t->n > URT_MAX_FAULTS ? URT_MAX_FAULTS : t->n);
  urtwin_lcmt_urtwin_fault_truth *msg = &b->msg;
  msg->utime = (int64_t)llround(s->time * 1e6);
  msg->tick = (int64_t)s->tick;
  msg->sim_time = s->sim_time;
  msg->faults_applied = (int32_t)s->faults_applied;
  msg->faults_refused = (int32_t)s->faults_refused;
  msg->num_faults = n;
  for (int k = 0; k < n; k++) {
    const int at_tcp = t->cls[k] == URT_FAULT_COLLISION || t->cls[k] == URT_FAULT_PAYLOAD;
    b->fault_class[k] = (char *)urt_fault_class_name(t->cls[k]);
    b->joint[k] = at_tcp ? -1 : t->joint[k];
    b->component[k] = t->component[k];
    b->active[k] = (int8_t)t->active[k];
    b->severity[k] = t->severity[k];
    b->onset[k] = t->onset[k];
  }
  msg->fault_class = b->fault_class;
  msg->joint = b->joint;
  msg->component = b->component;
  msg->active = b->active;
  msg->severity = b->severity;
  msg->onset = b->onset;
}
