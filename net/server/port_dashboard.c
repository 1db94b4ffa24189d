/* SPDX-License-Identifier: Apache-2.0
 * net/server/port_dashboard.c — port 29999: the greeting, then one reply line per request
 * line (urt_dashboard_handle), and the actions that follow a reply: programs on the runner
 * (program_play.c), robot-mode changes through the controller, quit and shutdown. */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "emulator_internal.h"

static void perform(urt_emulator_t *e, urt__client_t *c, const urt_dashboard_action_t *a,
                    const urt_dashboard_robot_t *robot) {
  switch (a->program) {
    case URT_DASHBOARD_PROG_LOAD:
    case URT_DASHBOARD_PROG_STOP:
      urt__program_cancel(e);  // first: an External Control fetch must not submit after this
      urt_runner_stop(e->runner);
      urt__submit_kind(e, URT__RING_DASHBOARD, URT_CTRL_RESUME);  // a stopped program is no longer paused
      break;
    case URT_DASHBOARD_PROG_PLAY:
      if (robot->program_state == URT_PROGRAM_PAUSED) {
        urt__submit_kind(e, URT__RING_DASHBOARD, URT_CTRL_RESUME);
      } else {
        urt__program_play(e);
      }
      break;
    case URT_DASHBOARD_PROG_PAUSE:
      urt__submit_kind(e, URT__RING_DASHBOARD, URT_CTRL_PAUSE);
      break;
    default:
      break;
  }
  for (int i = 0; i < a->n_ctrl; i++) {
    urt__submit_kind(e, URT__RING_DASHBOARD, a->ctrl[i]);
  }
  if (a->log_text) {
    char text[512];
    snprintf(text, sizeof text, "%.*s", (int)a->log_len, a->log_text);
    urt__script_broadcast_text(e, text);
  }
  if (a->session == URT_DASHBOARD_SESSION_QUIT) {
    c->conn->closing = true;
  } else if (a->session == URT_DASHBOARD_SESSION_SHUTDOWN) {
    atomic_store(&e->shutdown_requested, 1);
  }
}

static bool dashboard_open(urt_emulator_t *e, urt__client_t *c) {
  urt_dashboard_framer_t *f = malloc(sizeof *f);
  if (!f) {
    return false;
  }
  urt_dashboard_framer_init(f);
  c->proto = f;
  urt_tcp_send(c->conn, URT_DASHBOARD_GREETING, strlen(URT_DASHBOARD_GREETING));
  return true;
}

static bool dashboard_input(urt_emulator_t *e, urt__client_t *c, const uint8_t *data, size_t n) {
  urt_dashboard_framer_t *f = c->proto;
  static _Thread_local char reply[URT_DASHBOARD_REPLY_MAX];
  while (n > 0 && !c->conn->closing) {
    size_t used = 0;
    urt_dashboard_line_t line;
    int have = urt_dashboard_framer_next(f, (const char *)data, n, &used, &line);
    data += used;
    n -= used;
    if (!have) {
      break;
    }
    urt_snapshot_t s;
    urt_loop_read_latest(e->loop, &s);
    urt_dashboard_robot_t robot;
    urt_dashboard_robot_from_snapshot(&s, &robot);
    robot.program_state = urt__program_state(e, robot.program_state);
    robot.pstop_age = e->pstop_since >= 0 ? s.time - e->pstop_since : -1.0;
    urt_dashboard_action_t action;
    size_t len = urt_dashboard_handle(&e->dash_ctx, &robot, &e->dash, &line, reply, sizeof reply,
                                      &action);
    if (!urt_tcp_send(c->conn, reply, len)) {
      return false;  // a client that never reads its replies
    }
    perform(e, c, &action, &robot);
  }
  return true;
}

static void dashboard_close(urt_emulator_t *e, urt__client_t *c) {
  free(c->proto);
  c->proto = NULL;
}

// saveLog & co.: the controller's log into the log folder (ctrl_log.h), with a header of who
// and what the robot is for the reports
int urt__dashboard_write_log(void *user, int what, const char *arg, size_t arg_len, char *out,
                             size_t out_sz) {
  (void)arg;
  (void)arg_len;
  urt_emulator_t *e = user;
  if (e->log_dir[0] == '\0') {
    snprintf(out, out_sz, "no log folder (start urtwin with --log-dir DIR)");
    return -1;
  }
  urt_snapshot_t s;
  urt_loop_read_latest(e->loop, &s);
  char header[512];
  snprintf(header, sizeof header,
           "urtwin flight report\nrobot: %s, serial number %s\ncontroller: %d.%d.%d\n"
           "controller time: %.3f s\nrobot mode %d, safety mode %d, program state %d\n"
           "joint positions [rad]: %.6f %.6f %.6f %.6f %.6f %.6f\n--- log ---\n",
           e->dash_ctx.robot_model, e->dash_ctx.serial_number, e->cfg.version.major,
           e->cfg.version.minor, e->cfg.version.bugfix, s.time, s.robot_mode, s.safety_mode,
           urt__program_state(e, s.program_state), s.q[0], s.q[1], s.q[2], s.q[3], s.q[4],
           s.q[5]);
  uint64_t id = 0;
  switch (what) {
    case URT_DASHBOARD_LOG_SAVE:
      return urt_ctrl_log_save(&e->log, e->log_dir, out, out_sz);
    case URT_DASHBOARD_LOG_FLIGHT_REPORT:
      if (urt_ctrl_log_flight_report(&e->log, e->log_dir, header, &id, out, out_sz) != 0) {
        return -1;
      }
      snprintf(out, out_sz, "%llu", (unsigned long long)id);
      return 0;
    case URT_DASHBOARD_LOG_SUPPORT_FILE:
      return urt_ctrl_log_support_file(&e->log, e->log_dir, header, out, out_sz);
    default:
      snprintf(out, out_sz, "unknown log request");
      return -1;
  }
}

const urt__port_ops_t urt__port_dashboard_ops = {.open = dashboard_open, .input = dashboard_input,
                                                 .close = dashboard_close};

// Per tick: start a play held back by a winding-down fetch, and remember when a protective
// stop began (the dashboard refuses to unlock it for 5 s).
void urt__dashboard_tick(urt_emulator_t *e, const urt_snapshot_t *s) {
  urt__program_tick(e);
  if (s->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP) {
    if (e->pstop_since < 0) {
      e->pstop_since = s->time;
    }
  } else {
    e->pstop_since = -1.0;
  }
}
