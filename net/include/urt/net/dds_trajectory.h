/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/dds_trajectory.h — a joint trajectory (trajectory_msgs/JointTrajectory)
 * as ros2_controllers' joint_trajectory_controller samples it: per segment a quintic when both
 * ends give accelerations, a cubic when they give velocities, else linear; a segment from the
 * arm's current set-point to the first point when that point's time is after zero; after the
 * last point the last positions, at rest. The DDS bridge samples it once per controller tick
 * into a URT_CTRL_DIRECT set-point (q, q̇), which the controller interpolates within the period
 * with its cubic Hermite spline (urt/controller.h). Pure: no clock, no thread.
 */
#ifndef URT_NET_DDS_TRAJECTORY_H
#define URT_NET_DDS_TRAJECTORY_H

#include <stddef.h>

#include "urt/data.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_DDS_TRAJ_MAX_POINTS 10000

typedef struct urt_dds_traj_point {
  double t;                                 /* time from start [s]                     */
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  int has_qd, has_qdd;
} urt_dds_traj_point_t;

typedef struct urt_dds_traj {
  size_t n;                     /* points, the start state included (point 0 at t = 0 or the
                                   first given point) */
  urt_dds_traj_point_t *p;      /* owned                                                  */
} urt_dds_traj_t;

/* Sample at time t from the start (t < 0: the first point; after the end: the last point at
 * rest). Context: any, no allocation. */
void urt_dds_traj_eval(const urt_dds_traj_t *tr, double t, double q[URT_NJ], double qd[URT_NJ]);

/* Duration (time of the last point) [s]. */
double urt_dds_traj_duration(const urt_dds_traj_t *tr);

void urt_dds_traj_free(urt_dds_traj_t *tr);

/* The trajectory's own clock. The bridge sends one set-point per controller tick; the time it
 * samples advances one period per set-point sent, not by the ticks that passed, so a command
 * thread that runs late (descheduled, or its ring full) delays the rest of the trajectory and
 * never skips part of it: a skipped stretch is a set-point step the joints cannot make in one
 * period, which the controller protective-stops (direct_jump_joints). On time, it is the
 * controller's clock. */
typedef struct urt_dds_traj_clock {
  double t0;    /* controller time of the trajectory's start [s]                              */
  double next;  /* trajectory time of the next set-point [s]; NAN until the first is sent      */
} urt_dds_traj_clock_t;

void urt_dds_traj_clock_start(urt_dds_traj_clock_t *c, double t0);

/* Trajectory time of the set-point for the period ending at controller time `end` [s]. */
double urt_dds_traj_clock_at(const urt_dds_traj_clock_t *c, double end);

/* The set-point at trajectory time tau was sent; the next one is a period later. */
void urt_dds_traj_clock_sent(urt_dds_traj_clock_t *c, double tau, double period);

#ifdef __cplusplus
}
#endif
#endif
