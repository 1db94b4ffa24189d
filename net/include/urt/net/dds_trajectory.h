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

#ifdef __cplusplus
}
#endif
#endif
