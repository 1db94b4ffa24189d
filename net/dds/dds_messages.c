/* SPDX-License-Identifier: Apache-2.0
 * net/dds/dds_messages.c — filling the UR ROS 2 driver's messages from a snapshot and checking
 * the commands of the forward and trajectory controllers. Pure; see dds_messages.h. */
#include "urt/net/dds_messages.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "urt/errors.h"

const char *const urt_dds_joint_names[URT_NJ] = {"shoulder_pan_joint", "shoulder_lift_joint",
                                                 "elbow_joint",        "wrist_1_joint",
                                                 "wrist_2_joint",      "wrist_3_joint"};

// the UR ROS 2 driver's servoj parameters (ur_robot_driver: servoj_lookahead_time, servoj_gain)
#define SERVOJ_LOOKAHEAD 0.03
#define SERVOJ_GAIN 2000.0

void urt_dds_out_init(urt_dds_out_t *o) {
  memset(o, 0, sizeof *o);
  for (int j = 0; j < URT_NJ; j++) {
    o->names[j] = (char *)urt_dds_joint_names[j];
  }
  for (int i = 0; i < URT_DDS_DIGITAL_PINS; i++) {
    o->din[i].pin = (uint8_t)i;
    o->dout[i].pin = (uint8_t)i;
  }
}

builtin_interfaces_msg_dds__Time_ urt_dds_time(int64_t ns) {
  builtin_interfaces_msg_dds__Time_ t;
  int64_t sec = ns / 1000000000, rem = ns % 1000000000;
  if (rem < 0) {
    rem += 1000000000;
    sec--;
  }
  t.sec = (int32_t)sec;
  t.nanosec = (uint32_t)rem;
  return t;
}

static dds_sequence_double seq_double(double *v, uint32_t n) {
  dds_sequence_double s = {._maximum = n, ._length = n, ._buffer = v, ._release = false};
  return s;
}

void urt_dds_fill_joint_state(const urt_snapshot_t *s, int64_t stamp_ns, urt_dds_out_t *o,
                              sensor_msgs_msg_dds__JointState_ *msg) {
  memset(msg, 0, sizeof *msg);
  msg->header.stamp = urt_dds_time(stamp_ns);
  msg->header.frame_id = "base_link";  // joint_state_broadcaster's default
  for (int j = 0; j < URT_NJ; j++) {
    o->position[j] = s->q[j];
    o->velocity[j] = s->qd[j];
    o->effort[j] = s->i_actual[j];  // the driver's effort is the motor current
  }
  msg->name._maximum = msg->name._length = URT_NJ;
  msg->name._buffer = o->names;
  msg->position = seq_double(o->position, URT_NJ);
  msg->velocity = seq_double(o->velocity, URT_NJ);
  msg->effort = seq_double(o->effort, URT_NJ);
}

void urt_dds_fill_wrench(const urt_snapshot_t *s, int64_t stamp_ns,
                         geometry_msgs_msg_dds__WrenchStamped_ *msg) {
  memset(msg, 0, sizeof *msg);
  msg->header.stamp = urt_dds_time(stamp_ns);
  msg->header.frame_id = "tool0_controller";
  msg->wrench.force.x = s->tcp_force[0];
  msg->wrench.force.y = s->tcp_force[1];
  msg->wrench.force.z = s->tcp_force[2];
  msg->wrench.torque.x = s->tcp_force[3];
  msg->wrench.torque.y = s->tcp_force[4];
  msg->wrench.torque.z = s->tcp_force[5];
}

void urt_dds_fill_pose(const urt_snapshot_t *s, int64_t stamp_ns,
                       geometry_msgs_msg_dds__PoseStamped_ *msg) {
  memset(msg, 0, sizeof *msg);
  msg->header.stamp = urt_dds_time(stamp_ns);
  msg->header.frame_id = "base";
  msg->pose.position.x = s->tcp_pose[0];
  msg->pose.position.y = s->tcp_pose[1];
  msg->pose.position.z = s->tcp_pose[2];
  const double rx = s->tcp_pose[3], ry = s->tcp_pose[4], rz = s->tcp_pose[5];
  const double theta = sqrt(rx * rx + ry * ry + rz * rz);
  if (theta > 0.0) {
    const double k = sin(theta / 2.0) / theta;
    msg->pose.orientation.x = rx * k;
    msg->pose.orientation.y = ry * k;
    msg->pose.orientation.z = rz * k;
    msg->pose.orientation.w = cos(theta / 2.0);
  } else {
    msg->pose.orientation.w = 1.0;  // the language default is not on the wire
  }
}

void urt_dds_fill_io_states(const urt_snapshot_t *s, urt_dds_out_t *o,
                            ur_msgs_msg_dds__IOStates_ *msg) {
  memset(msg, 0, sizeof *msg);
  for (int i = 0; i < URT_DDS_DIGITAL_PINS; i++) {
    o->din[i].state = (s->digital_in >> i) & 1u;
    o->dout[i].state = (s->digital_out >> i) & 1u;
  }
  // analog outputs: the values RTDE reports as standard_analog_outputN; urtwin models no
  // analog inputs and no output domain, so analog_in_states stays empty (not faked) and the
  // outputs carry domain 0
  for (int i = 0; i < 2; i++) {
    o->aout[i].pin = (uint8_t)i;
    o->aout[i].domain = 0;
    o->aout[i].state = (float)s->analog_out[i];
  }
  msg->digital_in_states._maximum = msg->digital_in_states._length = URT_DDS_DIGITAL_PINS;
  msg->digital_in_states._buffer = o->din;
  msg->digital_out_states._maximum = msg->digital_out_states._length = URT_DDS_DIGITAL_PINS;
  msg->digital_out_states._buffer = o->dout;
  msg->analog_out_states._maximum = msg->analog_out_states._length = 2;
  msg->analog_out_states._buffer = o->aout;
}

void urt_dds_fill_drive_sample(const urt_drive_sample_t *d, urtwin_msgs_msg_dds__DriveSample_ *out) {
  out->seq = d->seq;
  out->time = d->time;
  for (int j = 0; j < URT_NJ; j++) {
    out->current[j] = d->i[j];
    out->current_measured[j] = d->i_meas[j];
    out->motor_speed[j] = d->motor_speed[j];
    out->gear_output_torque[j] = d->gear_out_torque[j];
    out->friction_torque[j] = d->friction_torque[j];
    out->voltage[j] = d->v[j];
    out->temperature[j] = d->temperature[j];
  }
}

void urt_dds_fill_drive(int64_t stamp_ns, uint64_t samples_lost, uint32_t n, urt_dds_out_t *o,
                        urtwin_msgs_msg_dds__Drive_ *msg) {
  memset(msg, 0, sizeof *msg);
  msg->header.stamp = urt_dds_time(stamp_ns);
  msg->header.frame_id = "base";
  msg->samples_lost = samples_lost;
  msg->samples._maximum = msg->samples._length = n;
  msg->samples._buffer = o->drive;
}

static int all_finite(const double *v, size_t n) {
  for (size_t i = 0; i < n; i++) {
    if (!isfinite(v[i])) {
      return 0;
    }
  }
  return 1;
}

int urt_dds_forward_to_ctrl(const std_msgs_msg_dds__Float64MultiArray_ *msg, int velocity,
                            double timeout, double accel, uint64_t id, urt_ctrl_cmd_t *out) {
  if (msg->data._length != URT_NJ || msg->data._buffer == NULL) {
    return URT_EPROTO;
  }
  if (!all_finite(msg->data._buffer, URT_NJ)) {
    return URT_ERANGE;
  }
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  c.id = id;
  memcpy(c.q, msg->data._buffer, sizeof c.q);
  c.t = timeout;
  if (velocity) {
    c.kind = URT_CTRL_SPEEDJ;
    c.a = accel;
  } else {
    c.kind = URT_CTRL_SERVOJ;
    c.lookahead_time = SERVOJ_LOOKAHEAD;
    c.gain = SERVOJ_GAIN;
  }
  *out = c;
  return 0;
}

static int fail(char *err, size_t err_sz, int rc, const char *fmt, unsigned long a) {
  if (err != NULL && err_sz > 0) {
    snprintf(err, err_sz, fmt, a);
  }
  return rc;
}

static int optional6(const dds_sequence_double *s) {
  return s->_length == 0 || (s->_length == URT_NJ && s->_buffer != NULL);
}

int urt_dds_trajectory_from_msg(const trajectory_msgs_msg_dds__JointTrajectory_ *msg,
                                const double q0[URT_NJ], const double qd0[URT_NJ],
                                const double qdd0[URT_NJ], urt_dds_traj_t *out, char *err,
                                size_t err_sz) {
  // joint order: the message's index of each of our joints
  int index[URT_NJ];
  if (msg->joint_names._length != URT_NJ || msg->joint_names._buffer == NULL) {
    return fail(err, err_sz, URT_EPROTO, "joint_names has %lu names, expected the 6 joints",
                (unsigned long)msg->joint_names._length);
  }
  for (int j = 0; j < URT_NJ; j++) {
    index[j] = -1;
    for (int k = 0; k < URT_NJ; k++) {
      const char *name = msg->joint_names._buffer[k];
      if (name != NULL && strcmp(name, urt_dds_joint_names[j]) == 0) {
        if (index[j] >= 0) {
          return fail(err, err_sz, URT_EPROTO, "joint %lu named twice", (unsigned long)j);
        }
        index[j] = k;
      }
    }
    if (index[j] < 0) {
      return fail(err, err_sz, URT_EPROTO, "joint_names lacks joint %lu", (unsigned long)j);
    }
  }
  const uint32_t n = msg->points._length;
  if (n == 0 || msg->points._buffer == NULL) {
    return fail(err, err_sz, URT_EPROTO, "the trajectory has %lu points", 0);
  }
  if (n > URT_DDS_TRAJ_MAX_POINTS) {
    return fail(err, err_sz, URT_EPROTO, "more than %lu points", URT_DDS_TRAJ_MAX_POINTS);
  }

  // check every point before building anything
  double t_prev = -1.0;
  for (uint32_t i = 0; i < n; i++) {
    const trajectory_msgs_msg_dds__JointTrajectoryPoint_ *p = &msg->points._buffer[i];
    if (p->positions._length != URT_NJ || p->positions._buffer == NULL || !optional6(&p->velocities) ||
        !optional6(&p->accelerations) || !optional6(&p->effort)) {
      return fail(err, err_sz, URT_EPROTO,
                  "point %lu: expected 6 positions and 0 or 6 velocities, accelerations, efforts",
                  (unsigned long)i);
    }
    if (!all_finite(p->positions._buffer, URT_NJ) ||
        (p->velocities._length && !all_finite(p->velocities._buffer, URT_NJ)) ||
        (p->accelerations._length && !all_finite(p->accelerations._buffer, URT_NJ)) ||
        (p->effort._length && !all_finite(p->effort._buffer, URT_NJ))) {
      return fail(err, err_sz, URT_ERANGE, "point %lu: NaN or infinite value", (unsigned long)i);
    }
    if (p->time_from_start.sec < 0 || p->time_from_start.nanosec >= 1000000000u) {
      return fail(err, err_sz, URT_ERANGE, "point %lu: bad time_from_start", (unsigned long)i);
    }
    double t = p->time_from_start.sec + 1e-9 * p->time_from_start.nanosec;
    if (!(t > t_prev)) {
      return fail(err, err_sz, URT_ERANGE, "point %lu: time_from_start not increasing",
                  (unsigned long)i);
    }
    t_prev = t;
  }

  const trajectory_msgs_msg_dds__JointTrajectoryPoint_ *first = &msg->points._buffer[0];
  const int lead = first->time_from_start.sec > 0 || first->time_from_start.nanosec > 0;
  urt_dds_traj_point_t *pts = calloc(n + (size_t)lead, sizeof *pts);
  if (pts == NULL) {
    return fail(err, err_sz, URT_ENOMEM, "out of memory (%lu points)", (unsigned long)n);
  }
  size_t k = 0;
  if (lead) {  // from where the arm's set-point is now
    pts[0].t = 0.0;
    memcpy(pts[0].q, q0, sizeof pts[0].q);
    memcpy(pts[0].qd, qd0, sizeof pts[0].qd);
    memcpy(pts[0].qdd, qdd0, sizeof pts[0].qdd);
    pts[0].has_qd = pts[0].has_qdd = 1;
    k = 1;
  }
  for (uint32_t i = 0; i < n; i++, k++) {
    const trajectory_msgs_msg_dds__JointTrajectoryPoint_ *p = &msg->points._buffer[i];
    pts[k].t = p->time_from_start.sec + 1e-9 * p->time_from_start.nanosec;
    pts[k].has_qd = p->velocities._length == URT_NJ;
    pts[k].has_qdd = p->accelerations._length == URT_NJ;
    for (int j = 0; j < URT_NJ; j++) {
      pts[k].q[j] = p->positions._buffer[index[j]];
      pts[k].qd[j] = pts[k].has_qd ? p->velocities._buffer[index[j]] : 0.0;
      pts[k].qdd[j] = pts[k].has_qdd ? p->accelerations._buffer[index[j]] : 0.0;
    }
  }
  out->n = k;
  out->p = pts;
  return 0;
}
