/* SPDX-License-Identifier: Apache-2.0
 * net/dds/dds_bridge.c — the DDS entities, the publisher thread and the command thread.
 * Context: non-RT throughout; nothing here runs on the physics thread. */
#include "urt/net/dds_bridge.h"

#include <ctype.h>
#include <dds/dds.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "urt/errors.h"
#include "urt/net/dds_config_check.h"
#include "urt/net/dds_messages.h"
#include "urt/thread.h"

#define WAIT_MS 50             /* how often the threads look at the stop flag             */
#define JOIN_TIMEOUT_S 2
#define EPOCH_TICKS 20         /* ticks watched to fix the stamp epoch                     */
#define CONFIG_MAX (1 << 20)   /* largest configuration file read                          */

// RIHS01 type hashes (REP-2011) of the ROS 2 types, as rmw puts them into USER_DATA; recomputed
// from the .msg definitions by tests/python/ros2_typehash.py
#define H_JOINT_STATE "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"
#define H_WRENCH_STAMPED "RIHS01_8dc3deaf06b2ab281f9f9a742a8961c328ca7cec16e3fd6586d3a5c83fa78f77"
#define H_POSE_STAMPED "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
#define H_FLOAT64 "RIHS01_705ba9c3d1a09df43737eb67095534de36fd426c0587779bda2bc51fe790182a"
#define H_BOOL "RIHS01_feb91e995ff9ebd09c0cb3d2aed18b11077585839fb5db80193b62d74528f6c9"
#define H_IO_STATES "RIHS01_7a62606d52c4b2aaa3fd3c5bc565cfda9c6fe8c2d69bbc7e3eadccde4cfc2a32"
#define H_ROBOT_MODE "RIHS01_ba3c379b3c995f660b38d03a195dc23ed7571a1bc06ceed2cec38c75ae9bd634"
#define H_SAFETY_MODE "RIHS01_9eb2716e6905f06e4eb60af26712660486e909026aa89c553dd633f1fb22f592"
#define H_FLOAT64_MULTI "RIHS01_1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f"
#define H_JOINT_TRAJ "RIHS01_179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e"
#define H_DRIVE "RIHS01_b9d9ead2f062d64ef3dbf56f71eb590eece52604e6418770f3dd92eff48488e2"
#define H_PARTICIPANT_INFO "RIHS01_91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e"

enum { W_JOINT_STATES, W_WRENCH, W_POSE, W_SPEED_SCALING, W_IO_STATES, W_ROBOT_MODE,
       W_SAFETY_MODE, W_PROGRAM_RUNNING, W_DRIVE, W_COUNT };
enum { R_FORWARD_POSITION, R_FORWARD_VELOCITY, R_TRAJECTORY, R_COUNT };

typedef struct endpoint_spec {
  const char *topic;   /* ROS name without the leading / and the prefix */
  const dds_topic_descriptor_t *desc;
  const char *hash;
  int latched;         /* 1: TRANSIENT_LOCAL; 2: that, and a graph topic (no rt/, no namespace) */
  int depth;           /* history: 0 = the driver's KEEP_LAST 1 */
} endpoint_spec_t;

static const endpoint_spec_t kWriters[W_COUNT] = {
    [W_JOINT_STATES] = {"joint_states", &sensor_msgs_msg_dds__JointState__desc, H_JOINT_STATE, 0},
    [W_WRENCH] = {"force_torque_sensor_broadcaster/wrench",
                  &geometry_msgs_msg_dds__WrenchStamped__desc, H_WRENCH_STAMPED, 0},
    [W_POSE] = {"tcp_pose_broadcaster/pose", &geometry_msgs_msg_dds__PoseStamped__desc,
                H_POSE_STAMPED, 0},
    [W_SPEED_SCALING] = {"speed_scaling_state_broadcaster/speed_scaling",
                         &std_msgs_msg_dds__Float64__desc, H_FLOAT64, 0},
    [W_IO_STATES] = {"io_and_status_controller/io_states", &ur_msgs_msg_dds__IOStates__desc,
                     H_IO_STATES, 0},
    [W_ROBOT_MODE] = {"io_and_status_controller/robot_mode",
                      &ur_dashboard_msgs_msg_dds__RobotMode__desc, H_ROBOT_MODE, 1},
    [W_SAFETY_MODE] = {"io_and_status_controller/safety_mode",
                       &ur_dashboard_msgs_msg_dds__SafetyMode__desc, H_SAFETY_MODE, 1},
    [W_PROGRAM_RUNNING] = {"io_and_status_controller/robot_program_running",
                           &std_msgs_msg_dds__Bool__desc, H_BOOL, 1},
    // urtwin's own: a deeper writer history, so that a reliable reader can have every batch
    // repaired (with KEEP_LAST 1 a lost fragment of a batch already replaced is gone)
    [W_DRIVE] = {"urtwin/drive", &urtwin_msgs_msg_dds__Drive__desc, H_DRIVE, 0, 100},
};

static const endpoint_spec_t kReaders[R_COUNT] = {
    [R_FORWARD_POSITION] = {"forward_position_controller/commands",
                            &std_msgs_msg_dds__Float64MultiArray__desc, H_FLOAT64_MULTI, 0},
    [R_FORWARD_VELOCITY] = {"forward_velocity_controller/commands",
                            &std_msgs_msg_dds__Float64MultiArray__desc, H_FLOAT64_MULTI, 0},
    [R_TRAJECTORY] = {"scaled_joint_trajectory_controller/joint_trajectory",
                      &trajectory_msgs_msg_dds__JointTrajectory__desc, H_JOINT_TRAJ, 0},
};

typedef struct counters {
  _Atomic uint64_t ticks_published, ticks_lost, drive_messages, drive_samples, drive_lost,
      write_errors, cmd_received, cmd_accepted, cmd_invalid, cmd_refused, cmd_dropped,
      traj_ticks_late;
} counters_t;

struct urt_dds_bridge {
  urt_loop_t *loop;
  int producer;
  urt_dds_config_t cfg;
  dds_entity_t domain, participant;
  dds_entity_t writers[W_COUNT], readers[R_COUNT];
  dds_entity_t waitset;
  dds_entity_t node_info;     /* ros_discovery_info writer, 0 without --dds-node-info */

  pthread_t pub_thread, cmd_thread;
  int pub_running, cmd_running, abandoned;
  atomic_int stop;
  _Atomic int64_t epoch_ns;   /* wall clock of controller time 0 [ns]; 0 until fixed */

  // command thread only
  uint64_t cmd_id;
  urt_dds_traj_t traj;
  int traj_active;
  urt_dds_traj_clock_t traj_clock;
  uint64_t traj_last_tick;
  counters_t n;
};

//---- helpers ----------------------------------------------------------------------------------

static void set_err(char *err, size_t err_sz, const char *fmt, const char *a, const char *b) {
  if (err != NULL && err_sz > 0) {
    snprintf(err, err_sz, fmt, a, b);
  }
}

static int64_t wall_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void bump(_Atomic uint64_t *c, uint64_t n) {
  atomic_fetch_add_explicit(c, n, memory_order_relaxed);
}

// a ROS namespace: segments of [A-Za-z0-9_], not starting with a digit, separated by '/'
static int valid_prefix(const char *p) {
  if (p[0] == '\0') {
    return 1;
  }
  const char *seg = p;
  for (const char *c = p;; c++) {
    if (*c == '/' || *c == '\0') {
      if (c == seg || isdigit((unsigned char)*seg)) {
        return 0;
      }
      if (*c == '\0') {
        return 1;
      }
      seg = c + 1;
    } else if (!isalnum((unsigned char)*c) && *c != '_') {
      return 0;
    }
  }
}

// the configuration file's text, or NULL (err says why)
static char *read_config(const char *path, char *err, size_t err_sz) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    set_err(err, err_sz, "dds: cannot read --dds-config %s: %s", path, strerror(errno));
    return NULL;
  }
  char *text = malloc(CONFIG_MAX + 1);
  size_t len = text != NULL ? fread(text, 1, CONFIG_MAX + 1, f) : 0;
  fclose(f);
  if (text == NULL || len == 0 || len > CONFIG_MAX) {
    set_err(err, err_sz, "dds: --dds-config %s: %s", path,
            text == NULL ? "out of memory" : len == 0 ? "empty file" : "larger than 1 MiB");
    free(text);
    return NULL;
  }
  text[len] = '\0';
  char why[160];
  if (urt_dds_config_check(text, why, sizeof why) != 0) {
    set_err(err, err_sz, "dds: --dds-config %s is not a well-formed Cyclone DDS configuration: %s",
            path, why);
    free(text);
    return NULL;
  }
  return text;
}

static dds_qos_t *endpoint_qos(const endpoint_spec_t *e, int writer) {
  // the UR driver's SystemDefaultsQoS on Cyclone: RELIABLE, VOLATILE, KEEP_LAST 1; latched
  // topics TRANSIENT_LOCAL (dds.md §2.2, §2.5)
  dds_qos_t *q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_INFINITY);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, e->depth > 0 ? e->depth : 1);
  if (e->latched) {
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_durability_service(q, 0, DDS_HISTORY_KEEP_LAST, 1, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  } else {
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  }
  if (writer) {
    dds_qset_writer_data_lifecycle(q, false);
  }
  // classic CDR only, as rmw_cyclonedds
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  char ud[96];
  int n = snprintf(ud, sizeof ud, "typehash=%s;", e->hash);
  dds_qset_userdata(q, ud, (size_t)n);
  return q;
}

static dds_entity_t make_endpoint(urt_dds_bridge_t *b, const endpoint_spec_t *e, int writer,
                                  char *err, size_t err_sz) {
  char name[256];
  const char *pre = b->cfg.prefix;
  if (e->latched == 2) {  // a graph topic: no rt/ prefix, no namespace (rmw's avoid_ros_namespace)
    snprintf(name, sizeof name, "%s", e->topic);
  } else {
    snprintf(name, sizeof name, "rt/%s%s%s", pre, pre[0] ? "/" : "", e->topic);
  }
  dds_entity_t topic = dds_create_topic(b->participant, e->desc, name, NULL, NULL);
  if (topic < 0) {
    set_err(err, err_sz, "dds: cannot create topic %s: %s", name, dds_strretcode(topic));
    return topic;
  }
  dds_qos_t *q = endpoint_qos(e, writer);
  dds_entity_t ep = writer ? dds_create_writer(b->participant, topic, q, NULL)
                           : dds_create_reader(b->participant, topic, q, NULL);
  dds_delete_qos(q);
  if (ep < 0) {
    set_err(err, err_sz, "dds: cannot create an endpoint on %s: %s", name, dds_strretcode(ep));
  }
  return ep;
}

// ros_discovery_info: one sample for this participant, one node owning every endpoint; ROS
// readers are RELIABLE, TRANSIENT_LOCAL, KEEP_ALL: latched, written once (the endpoints never
// change). GIDs are the DDS GUIDs (rmw's convert_guid_to_gid).
static int announce_node(urt_dds_bridge_t *b, char *err, size_t err_sz) {
  static const endpoint_spec_t spec = {"ros_discovery_info",
                                       &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                                       H_PARTICIPANT_INFO, 2, 0};
  b->node_info = make_endpoint(b, &spec, 1, err, err_sz);
  if (b->node_info < 0) {
    return URT_EIO;
  }
  rmw_dds_common_msg_dds__Gid_ rgid[R_COUNT], wgid[W_COUNT];
  dds_guid_t g;
  for (int r = 0; r < R_COUNT; r++) {
    dds_get_guid(b->readers[r], &g);
    memcpy(rgid[r].data, g.v, 16);
  }
  for (int w = 0; w < W_COUNT; w++) {
    dds_get_guid(b->writers[w], &g);
    memcpy(wgid[w].data, g.v, 16);
  }
  rmw_dds_common_msg_dds__NodeEntitiesInfo_ node;
  memset(&node, 0, sizeof node);
  snprintf(node.node_namespace, sizeof node.node_namespace, "/%s", b->cfg.prefix);
  snprintf(node.node_name, sizeof node.node_name, "urtwin");
  node.reader_gid_seq = (dds_sequence_rmw_dds_common_msg_dds__Gid_){R_COUNT, R_COUNT, rgid, false};
  node.writer_gid_seq = (dds_sequence_rmw_dds_common_msg_dds__Gid_){W_COUNT, W_COUNT, wgid, false};
  rmw_dds_common_msg_dds__ParticipantEntitiesInfo_ info;
  memset(&info, 0, sizeof info);
  dds_get_guid(b->participant, &g);
  memcpy(info.gid.data, g.v, 16);
  info.node_entities_info_seq._maximum = info.node_entities_info_seq._length = 1;
  info.node_entities_info_seq._buffer = &node;
  dds_return_t rc = dds_write(b->node_info, &info);
  if (rc < 0) {
    set_err(err, err_sz, "dds: cannot write ros_discovery_info: %s%s", dds_strretcode(rc), "");
    return URT_EIO;
  }
  return 0;
}

//---- publisher thread -------------------------------------------------------------------------

typedef struct pub_state {
  uint64_t next_tick, next_seq;
  urt_dds_out_t out;
  int have_modes;
  int32_t robot_mode, safety_mode, running;
} pub_state_t;

// the DDS source timestamp of a tick's messages is the wall time the loop published the tick
// (the header stamp identifies the tick; this one lets a subscriber measure tick → arrival)
static void write_or_count(urt_dds_bridge_t *b, int w, const void *msg, int64_t source_ns) {
  dds_return_t rc = source_ns > 0 ? dds_write_ts(b->writers[w], msg, source_ns)
                                  : dds_write(b->writers[w], msg);
  if (rc < 0) {
    bump(&b->n.write_errors, 1);
  }
}

static void publish_tick(urt_dds_bridge_t *b, pub_state_t *ps, const urt_snapshot_t *s) {
  const int64_t stamp = atomic_load(&b->epoch_ns) + llround(s->time * 1e9);
  sensor_msgs_msg_dds__JointState_ js;
  urt_dds_fill_joint_state(s, stamp, &ps->out, &js);
  write_or_count(b, W_JOINT_STATES, &js, s->published_wall_ns);
  geometry_msgs_msg_dds__WrenchStamped_ wr;
  urt_dds_fill_wrench(s, stamp, &wr);
  write_or_count(b, W_WRENCH, &wr, s->published_wall_ns);
  geometry_msgs_msg_dds__PoseStamped_ po;
  urt_dds_fill_pose(s, stamp, &po);
  write_or_count(b, W_POSE, &po, s->published_wall_ns);
  std_msgs_msg_dds__Float64_ sc = {.data = s->speed_scaling * 100.0};  // percent, as the driver
  write_or_count(b, W_SPEED_SCALING, &sc, s->published_wall_ns);
  ur_msgs_msg_dds__IOStates_ io;
  urt_dds_fill_io_states(s, &ps->out, &io);
  write_or_count(b, W_IO_STATES, &io, s->published_wall_ns);

  // latched: at start, then on change
  const int32_t running = s->program_state == URT_PROGRAM_PLAYING;
  if (!ps->have_modes || s->robot_mode != ps->robot_mode) {
    ur_dashboard_msgs_msg_dds__RobotMode_ m = {.mode = (int8_t)s->robot_mode};
    write_or_count(b, W_ROBOT_MODE, &m, s->published_wall_ns);
  }
  if (!ps->have_modes || s->safety_mode != ps->safety_mode) {
    ur_dashboard_msgs_msg_dds__SafetyMode_ m = {.mode = (uint8_t)s->safety_mode};
    write_or_count(b, W_SAFETY_MODE, &m, s->published_wall_ns);
  }
  if (!ps->have_modes || running != ps->running) {
    std_msgs_msg_dds__Bool_ m = {.data = running != 0};
    write_or_count(b, W_PROGRAM_RUNNING, &m, s->published_wall_ns);
  }
  ps->have_modes = 1;
  ps->robot_mode = s->robot_mode;
  ps->safety_mode = s->safety_mode;
  ps->running = running;
  bump(&b->n.ticks_published, 1);
}

// the drive samples made since the last call, URT_DDS_DRIVE_BATCH per message at most
static void publish_drive(urt_dds_bridge_t *b, pub_state_t *ps) {
  uint64_t newest = urt_loop_latest_drive(b->loop);
  uint32_t n = 0;
  urt_drive_sample_t d;
  while (ps->next_seq <= newest) {
    int rc = urt_loop_read_drive(b->loop, ps->next_seq, &d);
    if (rc == URT_ERANGE) {
      uint64_t resume = newest > ps->next_seq ? newest : ps->next_seq + 1;
      bump(&b->n.drive_lost, resume - ps->next_seq);
      ps->next_seq = resume;
      continue;
    }
    if (rc != 0) {
      break;
    }
    urt_dds_fill_drive_sample(&d, &ps->out.drive[n++]);
    ps->next_seq++;
    if (n == URT_DDS_DRIVE_BATCH || ps->next_seq > newest) {
      urtwin_msgs_msg_dds__Drive_ msg;
      urt_dds_fill_drive(wall_ns(), atomic_load(&b->n.drive_lost), n, &ps->out, &msg);
      write_or_count(b, W_DRIVE, &msg, 0);
      bump(&b->n.drive_messages, 1);
      bump(&b->n.drive_samples, n);
      n = 0;
    }
  }
}

// stamps are wall clock = epoch + controller time: the epoch is the least (wall − controller
// time) seen over the first ticks, i.e. the wall time of controller time 0 as early as a
// reader sees ticks; then a stamp tells a subscriber which tick a message is
static void fix_epoch(urt_dds_bridge_t *b) {
  int64_t best = INT64_MAX;
  uint64_t tick = urt_loop_latest_tick(b->loop);
  urt_snapshot_t s;
  for (int i = 0; i < EPOCH_TICKS && !atomic_load(&b->stop); i++) {
    uint64_t t = urt_loop_wait(b->loop, tick, WAIT_MS);
    int64_t now = wall_ns();
    if (t == tick || urt_loop_read(b->loop, t, &s) != 0) {
      continue;
    }
    tick = t;
    int64_t e = now - llround(s.time * 1e9);
    best = e < best ? e : best;
  }
  if (best == INT64_MAX) {  // no ticks (lockstep waiting): from the newest snapshot
    urt_loop_read_latest(b->loop, &s);
    best = wall_ns() - llround(s.time * 1e9);
  }
  atomic_store(&b->epoch_ns, best);
}

static void *pub_main(void *arg) {
  urt_dds_bridge_t *b = arg;
  pub_state_t *ps = calloc(1, sizeof *ps);
  if (ps == NULL) {
    fprintf(stderr, "urt_dds: publisher out of memory\n");
    return NULL;
  }
  urt_dds_out_init(&ps->out);
  fix_epoch(b);
  uint64_t newest = urt_loop_latest_tick(b->loop);
  ps->next_tick = newest > 0 ? newest : 1;
  uint64_t dnewest = urt_loop_latest_drive(b->loop);
  ps->next_seq = dnewest > 0 ? dnewest : 1;

  urt_snapshot_t snap;
  while (!atomic_load(&b->stop)) {
    newest = urt_loop_wait(b->loop, ps->next_tick - 1, WAIT_MS);
    while (ps->next_tick <= newest && !atomic_load(&b->stop)) {
      int rc = urt_loop_read(b->loop, ps->next_tick, &snap);
      if (rc == URT_ERANGE) {
        // fell out of the history: resume half a history behind the newest
        uint64_t resume = newest > URT_LOOP_HISTORY / 2 ? newest - URT_LOOP_HISTORY / 2 : 0;
        if (resume <= ps->next_tick) {
          resume = ps->next_tick + 1;
        }
        bump(&b->n.ticks_lost, resume - ps->next_tick);
        ps->next_tick = resume;
        continue;
      }
      if (rc != 0) {
        break;
      }
      publish_tick(b, ps, &snap);
      ps->next_tick++;
    }
    publish_drive(b, ps);
  }
  free(ps);
  return NULL;
}

//---- command thread ---------------------------------------------------------------------------

// motion is taken only in remote control, RUNNING and NORMAL (as the other command paths: the
// controller would refuse it anyway, but here it is counted before it reaches the ring)
static int may_command(urt_dds_bridge_t *b, urt_snapshot_t *s) {
  urt_loop_read_latest(b->loop, s);
  return !b->cfg.local_control && s->robot_mode == URT_ROBOT_MODE_RUNNING &&
         s->safety_mode == URT_SAFETY_MODE_NORMAL;
}

static int submit(urt_dds_bridge_t *b, const urt_ctrl_cmd_t *cmd) {
  if (urt_loop_submit(b->loop, b->producer, cmd)) {
    b->cmd_id = cmd->id;
    return 1;
  }
  bump(&b->n.cmd_dropped, 1);
  return 0;
}

static void end_trajectory(urt_dds_bridge_t *b) {
  urt_dds_traj_free(&b->traj);
  b->traj_active = 0;
}

static void on_forward(urt_dds_bridge_t *b, const std_msgs_msg_dds__Float64MultiArray_ *msg,
                       int velocity) {
  urt_ctrl_cmd_t cmd;
  urt_snapshot_t s;
  if (urt_dds_forward_to_ctrl(msg, velocity, b->cfg.command_timeout, b->cfg.velocity_accel,
                              b->cmd_id + 1, &cmd) != 0) {
    bump(&b->n.cmd_invalid, 1);
    return;
  }
  if (!may_command(b, &s)) {
    bump(&b->n.cmd_refused, 1);
    return;
  }
  end_trajectory(b);  // the newest command source wins, as switching controllers would
  submit(b, &cmd);
  bump(&b->n.cmd_accepted, 1);
}

static void on_trajectory(urt_dds_bridge_t *b, const trajectory_msgs_msg_dds__JointTrajectory_ *msg) {
  urt_snapshot_t s;
  char why[160];
  if (msg->points._length == 0) {
    // joint_trajectory_controller: an empty trajectory cancels the current one; hold
    if (!may_command(b, &s)) {
      bump(&b->n.cmd_refused, 1);
      return;
    }
    if (b->traj_active) {
      end_trajectory(b);
      urt_ctrl_cmd_t stop = {.kind = URT_CTRL_STOPJ, .id = b->cmd_id + 1, .a = 2.0};
      submit(b, &stop);
    }
    bump(&b->n.cmd_accepted, 1);
    return;
  }
  urt_loop_read_latest(b->loop, &s);
  urt_dds_traj_t tr;
  int rc = urt_dds_trajectory_from_msg(msg, s.q_target, s.qd_target, s.qdd_target, &tr, why,
                                       sizeof why);
  if (rc != 0) {
    fprintf(stderr, "urt_dds: trajectory refused: %s\n", why);
    bump(&b->n.cmd_invalid, 1);
    return;
  }
  if (!may_command(b, &s)) {
    urt_dds_traj_free(&tr);
    bump(&b->n.cmd_refused, 1);
    return;
  }
  end_trajectory(b);
  b->traj = tr;
  b->traj_active = 1;
  // start: the header's stamp (wall clock) when given, else the next tick
  int64_t stamp = (int64_t)msg->header.stamp.sec * 1000000000 + msg->header.stamp.nanosec;
  int64_t epoch = atomic_load(&b->epoch_ns);
  double t0 = s.time + s.period;
  if (stamp != 0 && epoch != 0) {
    double t = (double)(stamp - epoch) * 1e-9;
    t0 = t > t0 ? t : t0;  // JTC: a start in the past is now
  }
  urt_dds_traj_clock_start(&b->traj_clock, t0);
  b->traj_last_tick = s.tick;
  bump(&b->n.cmd_accepted, 1);
}

// One DIRECT set-point per tick: the trajectory where the next period ends, on the
// trajectory's own clock (dds_trajectory.h): when this thread is late the arm holds the last
// set-point and the trajectory resumes from it, late, along the same path. Sampled at the
// controller's clock instead, the first set-point after a 150 ms stall of this thread was a
// step the joints cannot make in a period, and the controller protective-stopped mid-way.
static void step_trajectory(urt_dds_bridge_t *b) {
  urt_snapshot_t s;
  uint64_t newest = urt_loop_wait(b->loop, b->traj_last_tick, 5);
  if (newest == b->traj_last_tick) {
    return;
  }
  if (newest - b->traj_last_tick > 1 && !isnan(b->traj_clock.next)) {
    bump(&b->n.traj_ticks_late, newest - b->traj_last_tick - 1);
  }
  b->traj_last_tick = newest;
  if (!may_command(b, &s)) {
    end_trajectory(b);  // stopped, protective stop, local: the trajectory is over
    return;
  }
  double tau = urt_dds_traj_clock_at(&b->traj_clock, s.time + 2.0 * s.period);
  urt_ctrl_cmd_t cmd = {.kind = URT_CTRL_DIRECT, .id = b->cmd_id + 1};
  urt_dds_traj_eval(&b->traj, tau, cmd.q, cmd.qd);
  if (!submit(b, &cmd)) {
    return;  // the ring was full: the same set-point again next tick
  }
  urt_dds_traj_clock_sent(&b->traj_clock, tau, s.period);
  if (tau >= urt_dds_traj_duration(&b->traj)) {
    end_trajectory(b);  // the last set-point holds (DIRECT keeps it)
  }
}

static void take_all(urt_dds_bridge_t *b) {
  for (int r = 0; r < R_COUNT; r++) {
    void *buf[1] = {NULL};
    dds_sample_info_t info[1];
    for (;;) {
      int n = dds_take(b->readers[r], buf, info, 1, 1);
      if (n <= 0) {
        break;
      }
      if (info[0].valid_data) {
        bump(&b->n.cmd_received, 1);
        if (r == R_TRAJECTORY) {
          on_trajectory(b, buf[0]);
        } else {
          on_forward(b, buf[0], r == R_FORWARD_VELOCITY);
        }
      }
      dds_return_loan(b->readers[r], buf, n);
    }
  }
}

static void *cmd_main(void *arg) {
  urt_dds_bridge_t *b = arg;
  while (!atomic_load(&b->stop)) {
    if (b->traj_active) {
      step_trajectory(b);  // paced by the ticks; commands are looked at every tick
    } else {
      dds_waitset_wait(b->waitset, NULL, 0, DDS_MSECS(WAIT_MS));
    }
    take_all(b);
  }
  end_trajectory(b);
  return NULL;
}

//---- lifecycle --------------------------------------------------------------------------------

void urt_dds_config_default(urt_dds_config_t *cfg) {
  memset(cfg, 0, sizeof *cfg);
  cfg->prefix = "";
  cfg->command_timeout = 0.1;
  cfg->velocity_accel = 10.0;
}

int urt_dds_bridge_create(urt_loop_t *loop, const urt_dds_config_t *cfg, urt_dds_bridge_t **out,
                          char *err, size_t err_sz) {
  urt_dds_config_t defaults;
  if (cfg == NULL) {
    urt_dds_config_default(&defaults);
    cfg = &defaults;
  }
  const char *prefix = cfg->prefix != NULL ? cfg->prefix : "";
  while (prefix[0] == '/') {
    prefix++;
  }
  if (loop == NULL || out == NULL) {
    return URT_EINVAL;
  }
  if (cfg->domain < 0 || cfg->domain > URT_DDS_MAX_DOMAIN) {
    char d[24];
    snprintf(d, sizeof d, "%d", cfg->domain);
    set_err(err, err_sz, "dds: domain %s out of range (0..%s)", d, "232");
    return URT_EINVAL;
  }
  if (strlen(prefix) > 100 || !valid_prefix(prefix)) {
    set_err(err, err_sz, "dds: prefix '%s' is not a ROS namespace (%s)", prefix,
            "segments of letters, digits and _ separated by /");
    return URT_EINVAL;
  }
  if (!(cfg->command_timeout > 0) || !isfinite(cfg->command_timeout) ||
      !(cfg->velocity_accel > 0) || !isfinite(cfg->velocity_accel)) {
    set_err(err, err_sz, "dds: %s%s", "command timeout and velocity acceleration must be > 0", "");
    return URT_EINVAL;
  }

  urt_dds_bridge_t *b = calloc(1, sizeof *b);
  if (b == NULL) {
    return URT_ENOMEM;
  }
  b->loop = loop;
  b->cfg = *cfg;
  b->cfg.prefix = strdup(prefix);
  if (b->cfg.prefix == NULL) {
    free(b);
    return URT_ENOMEM;
  }

  // the domain, from the configuration file's text (so that a missing file says so)
  char *xml = NULL;
  if (cfg->config_file != NULL) {
    xml = read_config(cfg->config_file, err, err_sz);
    if (xml == NULL) {
      free((char *)b->cfg.prefix);
      free(b);
      return URT_ECONFIG;
    }
  }
  b->domain = dds_create_domain((dds_domainid_t)cfg->domain, xml);
  free(xml);
  if (b->domain < 0) {
    set_err(err, err_sz, "dds: Cyclone DDS rejected the configuration %s (%s)",
            cfg->config_file ? cfg->config_file : "(CYCLONEDDS_URI)", dds_strretcode(b->domain));
    free((char *)b->cfg.prefix);
    free(b);
    return URT_ECONFIG;
  }
  int rc = URT_EIO;
  dds_qos_t *pq = dds_create_qos();
  dds_qset_userdata(pq, "enclave=/;", 10);  // as rmw: ROS's graph then knows the participant
  dds_qset_entity_name(pq, "urtwin");
  b->participant = dds_create_participant((dds_domainid_t)cfg->domain, pq, NULL);
  dds_delete_qos(pq);
  if (b->participant < 0) {
    set_err(err, err_sz, "dds: cannot create a participant: %s%s",
            dds_strretcode(b->participant), "");
    goto fail;
  }
  for (int w = 0; w < W_COUNT; w++) {
    if ((b->writers[w] = make_endpoint(b, &kWriters[w], 1, err, err_sz)) < 0) {
      goto fail;
    }
  }
  b->waitset = dds_create_waitset(b->participant);
  if (b->waitset < 0) {
    set_err(err, err_sz, "dds: cannot create a waitset: %s%s", dds_strretcode(b->waitset), "");
    goto fail;
  }
  for (int r = 0; r < R_COUNT; r++) {
    if ((b->readers[r] = make_endpoint(b, &kReaders[r], 0, err, err_sz)) < 0) {
      goto fail;
    }
    dds_entity_t cond = dds_create_readcondition(b->readers[r], DDS_ANY_STATE);
    if (cond < 0 || dds_waitset_attach(b->waitset, cond, r) < 0) {
      set_err(err, err_sz, "dds: cannot wait on a reader%s%s", "", "");
      goto fail;
    }
  }
  if (cfg->node_info && announce_node(b, err, err_sz) != 0) {
    goto fail;
  }
  // the command thread is this ring's only producer
  b->producer = urt_loop_add_producer(loop, "dds");
  if (b->producer < 0) {
    rc = b->producer;
    set_err(err, err_sz, "dds: no free command ring%s%s", "", "");
    goto fail;
  }
  *out = b;
  return 0;

fail:
  dds_delete(b->domain);
  free((char *)b->cfg.prefix);
  free(b);
  return rc;
}

int urt_dds_bridge_start(urt_dds_bridge_t *b) {
  if (b->pub_running || b->cmd_running) {
    return URT_EINVAL;
  }
  atomic_store(&b->stop, 0);
  if (urt_thread_start(&b->pub_thread, pub_main, b, 1024 * 1024) != 0) {
    return URT_EIO;
  }
  b->pub_running = 1;
  if (urt_thread_start(&b->cmd_thread, cmd_main, b, 1024 * 1024) != 0) {
    urt_dds_bridge_stop(b);
    return URT_EIO;
  }
  b->cmd_running = 1;
  if (b->cfg.rt_priority > 0) {
    urt_thread_set_fifo(b->pub_thread, b->cfg.rt_priority, "dds publisher");
    urt_thread_set_fifo(b->cmd_thread, b->cfg.rt_priority, "dds commands");
  }
  return 0;
}

static void join_bounded(urt_dds_bridge_t *b, pthread_t t, const char *name) {
  char who[64];
  snprintf(who, sizeof who, "urt_dds: %s", name);
  if (urt_thread_join_bounded(t, JOIN_TIMEOUT_S, who) != 0) {
    b->abandoned = 1;
  }
}

void urt_dds_bridge_stop(urt_dds_bridge_t *b) {
  atomic_store(&b->stop, 1);
  dds_waitset_set_trigger(b->waitset, true);
  if (b->pub_running) {
    join_bounded(b, b->pub_thread, "publisher");
    b->pub_running = 0;
  }
  if (b->cmd_running) {
    join_bounded(b, b->cmd_thread, "command");
    b->cmd_running = 0;
  }
}

void urt_dds_bridge_destroy(urt_dds_bridge_t *b) {
  if (b == NULL) {
    return;
  }
  urt_dds_bridge_stop(b);
  if (b->abandoned) {
    return;  // a thread may still touch it
  }
  dds_delete(b->domain);
  free((char *)b->cfg.prefix);
  free(b);
}

void urt_dds_bridge_get_stats(const urt_dds_bridge_t *b, urt_dds_stats_t *out) {
  counters_t *n = (counters_t *)&b->n;
  out->ticks_published = atomic_load(&n->ticks_published);
  out->ticks_lost = atomic_load(&n->ticks_lost);
  out->drive_messages = atomic_load(&n->drive_messages);
  out->drive_samples = atomic_load(&n->drive_samples);
  out->drive_lost = atomic_load(&n->drive_lost);
  out->write_errors = atomic_load(&n->write_errors);
  out->cmd_received = atomic_load(&n->cmd_received);
  out->cmd_accepted = atomic_load(&n->cmd_accepted);
  out->cmd_invalid = atomic_load(&n->cmd_invalid);
  out->cmd_refused = atomic_load(&n->cmd_refused);
  out->cmd_dropped = atomic_load(&n->cmd_dropped);
  out->traj_ticks_late = atomic_load(&n->traj_ticks_late);
}
