/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/dds_bridge.h — urtwin as a ROS 2 system sees the UR ROS 2 driver, over
 * plain Cyclone DDS (no ROS installed): the driver's topics, types, QoS and rates, urtwin's own
 * /urtwin/drive, and ros2_control's forward and trajectory command topics
 * (../shared/docs/dds.md).
 *
 *   physics thread ──snapshot history──▶ [publisher thread] ──▶ rt/joint_states, …/wrench,
 *                                        …/pose, …/speed_scaling, …/io_states, robot_mode,
 *                                        safety_mode, robot_program_running (latched),
 *                                        rt/urtwin/drive (batched drive samples)
 *   rt/forward_*_controller/commands, rt/scaled_joint_trajectory_controller/joint_trajectory
 *        ──▶ [command thread] ──urt_loop_submit() (its own ring)──▶ physics thread
 *
 * Every entity is created by urt_dds_bridge_create; the threads only write and take. Both are
 * non-RT; the physics thread never waits for them. Every writer and reader carries
 * USER_DATA "typehash=RIHS01_…;" and the participant "enclave=/;", as rmw_cyclonedds does, so
 * Jazzy and later print no warnings. Commands are refused and counted unless the robot is in
 * remote control, RUNNING and NORMAL.
 */
#ifndef URT_NET_DDS_BRIDGE_H
#define URT_NET_DDS_BRIDGE_H

#include <stddef.h>
#include <stdint.h>

#include "urt/loop.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_DDS_MAX_DOMAIN 232   /* the highest id Cyclone's default port mapping allows */

typedef struct urt_dds_config {
  int domain;               /* DDS domain = ROS_DOMAIN_ID, 0..URT_DDS_MAX_DOMAIN           */
  const char *config_file;  /* Cyclone XML configuration; NULL: Cyclone's own (CYCLONEDDS_URI) */
  const char *prefix;       /* namespace for every topic ("" or NULL: none), e.g. "robot1"    */
  double command_timeout;   /* forward commands: the arm stops this long after the last [s]   */
  double velocity_accel;    /* forward velocity commands: speedj acceleration [rad/s²]       */
  int local_control;        /* 1: the pendant has control: every command is refused          */
  int rt_priority;          /* > 0: SCHED_FIFO priority of both threads (best effort), as the
                               I/O threads: on a loaded host they keep up with the ticks      */
  int node_info;            /* 1: announce a ROS node "urtwin" (namespace "/" + prefix) owning
                               every endpoint on ros_discovery_info, so `ros2 node list` shows
                               it — Iron/Jazzy/Kilted/Rolling layout (16-byte GIDs); Humble's
                               24-byte layout would be mis-decoded, hence off by default      */
} urt_dds_config_t;

void urt_dds_config_default(urt_dds_config_t *cfg);

typedef struct urt_dds_stats {
  uint64_t ticks_published;  /* controller ticks published (one joint state each)            */
  uint64_t ticks_lost;       /* ticks overwritten before the publisher read them             */
  uint64_t drive_messages, drive_samples, drive_lost;
  uint64_t write_errors;     /* dds_write failures                                           */
  uint64_t cmd_received;     /* command samples taken, all three topics                     */
  uint64_t cmd_accepted;     /* forward commands submitted, trajectories started             */
  uint64_t cmd_invalid;      /* wrong length, NaN/Inf, bad joint names or times               */
  uint64_t cmd_refused;      /* valid, but not in remote control / not RUNNING + NORMAL       */
  uint64_t cmd_dropped;      /* valid, but the command ring was full                          */
  uint64_t traj_ticks_late;  /* ticks a running trajectory was held: this thread was late      */
} urt_dds_stats_t;

typedef struct urt_dds_bridge urt_dds_bridge_t;

/* Create the domain (with the configuration file), participant, topics, writers and readers;
 * claim a command ring ("dds"). Context: non-RT. Returns 0, URT_EINVAL (domain out of range,
 * bad prefix, timeout or acceleration not > 0), URT_ECONFIG (the configuration file cannot be
 * read or Cyclone rejects it), URT_EIO (an entity cannot be created), URT_ENOSPC (no command
 * ring) or URT_ENOMEM; err receives a message. Nullable: cfg, err. */
int urt_dds_bridge_create(urt_loop_t *loop, const urt_dds_config_t *cfg, urt_dds_bridge_t **out,
                          char *err, size_t err_sz);

/* Start the publisher and command threads. Returns 0, URT_EINVAL (already started) or URT_EIO. */
int urt_dds_bridge_start(urt_dds_bridge_t *b);

/* Stop and join both threads (idempotent; each notices within about 50 ms). */
void urt_dds_bridge_stop(urt_dds_bridge_t *b);

/* Stop if running, delete every entity, free. Nullable: b. */
void urt_dds_bridge_destroy(urt_dds_bridge_t *b);

void urt_dds_bridge_get_stats(const urt_dds_bridge_t *b, urt_dds_stats_t *out);

#ifdef __cplusplus
}
#endif
#endif
