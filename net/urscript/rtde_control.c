/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/rtde_control.c — ur_rtde 1.6.5's `rtde_control` script, run natively
 * (clients.md §2.4). The script's main loop, its process_cmd() branches and its threads
 * (move, stop, servo, speed, force, jog, contact) become one state machine advanced once per
 * controller tick:
 *
 *   top of the tick:  cmd = input_int_register[0+o] (or the internal 254)
 *                     realtime ids → handle, out_int[0+o] = 1 (ready)
 *                     0            → executing = false, ready
 *                     other ids    → once per command: handle (sync moves block here), DONE (2)
 *   every tick, also while blocked: the "threads" — async move/stop/path completion and the
 *                     async progress word, contact detection, the RTDE watchdog, faults of the
 *                     streamed motions.
 *
 * Nothing is interpreted: arguments come from host->read_registers, results go out through
 * host->write_output_register, motions through host->submit and complete on the snapshot's
 * motion ids, as in the interpreter. A command the script has but urtwin cannot honour is a
 * runtime error that stops the program, as a failing builtin would on the robot.
 */
#include "rtde_control.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "urt/core.h"

#define SUBMIT_RETRY_TICKS 100
#define HIST 2048               /* ticks of joint-position and force history (4 s at 500 Hz)  */
#define CONTACT_FORCE 10.0      /* [N] resisting force along the direction that is a contact   */
#define CONTACT_ONSET 2.5       /* [N] below this the contact had not started yet              */
#define STEADY_SPEED 1e-3       /* [rad/s] is_steady: every joint slower than this             */

/* ids the main loop handles every tick and answers with ready (the script's realtime list) */
static bool is_realtime(int cmd) {
  switch (cmd) {
    case 6: case 9: case 10: case 11: case 24: case 25: case 26: case 27: case 38: case 58:
    case 66: case 67: case 68: case 69: case 70: case 71:
      return true;
    default:
      return false;
  }
}

//---- recognition ----

static const char kTagStart[] = "textmsg(\"RTDE Control Script Loaded (";

/* next line [*b, *e) starting at k; returns the index after it */
static size_t line_at(const char *s, size_t len, size_t k, size_t *b, size_t *e) {
  *b = k;
  while (k < len && s[k] != '\n') k++;
  *e = k;
  return k < len ? k + 1 : k;
}

static size_t skip_blank(const char *s, size_t e, size_t k) {
  while (k < e && (s[k] == ' ' || s[k] == '\t' || s[k] == '\r')) k++;
  return k;
}

static bool starts(const char *s, size_t k, size_t e, const char *word) {
  size_t n = strlen(word);
  return e - k >= n && memcmp(s + k, word, n) == 0;
}

/* `global reg_offset_<kind> = <value>` or `= # comment\n<value>`; -1 if absent or unreadable */
static int parse_offset(const char *s, size_t len, const char *name) {
  size_t n = strlen(name);
  for (size_t k = 0; k + n < len; k++) {
    if (memcmp(s + k, name, n) != 0 || (k > 0 && (isalnum((unsigned char)s[k - 1]) || s[k - 1] == '_'))) {
      continue;
    }
    size_t j = skip_blank(s, len, k + n);
    if (j >= len || s[j] != '=') continue;
    j = skip_blank(s, len, j + 1);
    if (j < len && s[j] == '#') {
      // the injected value lands after the comment, at the start of the next line
      while (j < len && s[j] != '\n') j++;
      j = skip_blank(s, len, j + 1);
    }
    if (j >= len || !isdigit((unsigned char)s[j])) return -1;
    long v = 0;
    while (j < len && isdigit((unsigned char)s[j]) && v < 100000) v = v * 10 + (s[j++] - '0');
    return (int)v;
  }
  return -1;
}

/* a number in [k, e) (the text need not be NUL-terminated): true, *v and *next after it */
static bool num_at(const char *s, size_t k, size_t e, double *v, size_t *next) {
  char buf[64];
  size_t n = 0;
  while (k + n < e && n + 1 < sizeof buf) {
    buf[n] = s[k + n];
    n++;
  }
  buf[n] = 0;
  char *end;
  *v = strtod(buf, &end);
  *next = k + (size_t)(end - buf);
  return end != buf && isfinite(*v);
}

/* `[n, n, n, n, n, n]` after an optional `p`; returns the index after `]` or 0 */
static size_t parse_vec6(const char *s, size_t k, size_t e, double x[6], bool *is_pose) {
  *is_pose = false;
  k = skip_blank(s, e, k);
  if (k < e && s[k] == 'p') {
    *is_pose = true;
    k++;
  }
  if (k >= e || s[k] != '[') return 0;
  k++;
  for (int j = 0; j < 6; j++) {
    k = skip_blank(s, e, k);
    if (!num_at(s, k, e, &x[j], &k)) return 0;
    k = skip_blank(s, e, k);
    if (k >= e || s[k] != (j == 5 ? ']' : ',')) return 0;
    k++;
  }
  return k;
}

/* one injected path line: `movej([…],a=…,v=…,r=…)`; false if not of that form */
static bool parse_move(const char *s, size_t k, size_t e, urt__rc_move *m) {
  static const struct { const char *word; char kind; } kinds[] = {
      {"movej(", 'j'}, {"movel(", 'l'}, {"movep(", 'p'}, {"movec(", 'c'}};
  memset(m, 0, sizeof *m);
  for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++) {
    if (starts(s, k, e, kinds[i].word)) {
      m->kind = kinds[i].kind;
      k += strlen(kinds[i].word);
    }
  }
  if (!m->kind || !(k = parse_vec6(s, k, e, m->x, &m->is_pose))) return false;

  // named arguments a=, v=, r= (any order), then `)`
  m->a = m->kind == 'j' ? 1.4 : 1.2;
  m->v = m->kind == 'j' ? 1.05 : 0.25;
  for (;;) {
    k = skip_blank(s, e, k);
    if (k < e && s[k] == ')') return true;
    if (k >= e || s[k] != ',') return false;
    k = skip_blank(s, e, k + 1);
    if (k + 2 > e || s[k + 1] != '=') return false;
    char key = s[k];
    double v;
    if (!num_at(s, k + 2, e, &v, &k)) return false;
    if (key == 'a') m->a = v;
    else if (key == 'v') m->v = v;
    else if (key == 'r') m->r = v;
    else return false;
  }
}

/* the body of exec_move_path(): waypoints; signal_async_progress/textmsg lines are ours */
static bool parse_path(const char *s, size_t len, size_t k, uint32_t line, urt__rc_info *out) {
  int cap = 0;
  for (;;) {
    size_t b, e;
    if (k >= len) return true;
    k = line_at(s, len, k, &b, &e);
    line++;
    b = skip_blank(s, e, b);
    if (b == e || s[b] == '#') continue;
    if (starts(s, b, e, "end") && skip_blank(s, e, b + 3) == e) return true;
    if (starts(s, b, e, "signal_async_progress(") || starts(s, b, e, "textmsg(")) continue;
    urt__rc_move m;
    if (!parse_move(s, b, e, &m)) {
      if (!out->path_bad_line) out->path_bad_line = line;
      continue;
    }
    m.line = line;
    if (out->n_path == cap) {
      cap = cap ? 2 * cap : 16;
      urt__rc_move *p = realloc(out->path, (size_t)cap * sizeof *p);
      if (!p) return false;
      out->path = p;
    }
    out->path[out->n_path++] = m;
  }
}

bool urt__rc_recognise(const char *s, size_t len, urt__rc_info *out) {
  memset(out, 0, sizeof *out);
  if (!s) return false;

  // the header: `def rtde_control():` first (after blank lines and comments)
  size_t k = 0, b, e;
  for (;;) {
    if (k >= len) return false;
    k = line_at(s, len, k, &b, &e);
    b = skip_blank(s, e, b);
    if (b == e || s[b] == '#') continue;
    if (!starts(s, b, e, "def rtde_control():")) return false;
    break;
  }

  // the register offsets, quirk included
  out->reg_offset_int = parse_offset(s, len, "reg_offset_int");
  out->reg_offset_float = parse_offset(s, len, "reg_offset_float");
  if (out->reg_offset_int < 0 || out->reg_offset_float < 0) {
    memset(out, 0, sizeof *out);
    return false;
  }

  // line by line: the tag, process_cmd's branches and their bodies, the injected path
  bool tag = false;
  int cur = -1;  // branch whose body is being read
  uint32_t line = 1;
  for (size_t j = 0; j < len; line++) {
    j = line_at(s, len, j, &b, &e);
    b = skip_blank(s, e, b);
    if (b == e) continue;
    if (starts(s, b, e, kTagStart)) {
      size_t t0 = b + strlen("textmsg(\""), t1 = t0;
      while (t1 < e && s[t1] != '"') t1++;
      if (t1 < e && t1 > t0 && s[t1 - 1] == ')') {
        tag = true;
        snprintf(out->tag, sizeof out->tag, "%.*s", (int)(t1 - t0), s + t0);
      }
      continue;
    }
    if (starts(s, b, e, "def exec_move_path():")) {
      if (!parse_path(s, len, j, line, out)) {
        urt__rc_info_free(out);
        return false;
      }
      continue;
    }
    size_t c = starts(s, b, e, "elif cmd == ") ? b + 12 : starts(s, b, e, "if cmd == ") ? b + 10 : 0;
    if (c) {
      int id = 0, nd = 0;
      while (c < e && isdigit((unsigned char)s[c]) && nd < 4) id = id * 10 + (s[c++] - '0'), nd++;
      if (nd > 0 && c < e && s[c] == ':' && id < URT_RC_MAX_CMD) {
        cur = id;
        if (!out->has_cmd[id]) {
          out->has_cmd[id] = 1;
          out->cmd_line[id] = line;
        }
        continue;
      }
    }
    if (cur >= 0) {
      // a branch's body runs to the next branch; pruned bodies hold only comments and
      // `dummy_op = 1`, real ones at least one other line
      if (s[b] != '#' && !starts(s, b, e, "dummy_op = 1")) out->has_body[cur] = 1;
      if (starts(s, b, e, "if cmd != 255:")) cur = -1;
    }
  }
  if (!tag) {
    urt__rc_info_free(out);
    memset(out, 0, sizeof *out);
    return false;
  }
  return true;
}

void urt__rc_info_free(urt__rc_info *info) {
  if (info) {
    free(info->path);
    info->path = NULL;
    info->n_path = 0;
  }
}

//---- the running program ----

enum { ASYNC_NONE = 0, ASYNC_MOVE, ASYNC_STOP, ASYNC_PATH };

typedef struct rc {
  const urt__rc_info *info;
  const us_hooks *h;
  const urt_script_host_t *host;
  us_err *err;
  int oi, of;                   /* register offsets                                  */
  int cmd;                      /* the command being handled (error lines)           */

  /* this tick */
  uint64_t tick;
  urt_snapshot_t s;
  urt_rtde_registers_t reg;

  /* handshake */
  bool executing;
  int internal_cmd;

  /* async operations and the progress word */
  int wr_count, op_id;
  int async_kind;
  uint64_t async_id;            /* motion the async operation waits on               */
  int path_next;                /* ASYNC_PATH: next waypoint to start                */
  int stop_type;                /* 0 stopj, 1 stopl (the script's global)             */

  /* streamed modes (the script's threads) */
  bool servoing, speeding, forcing, jogging, torquing;
  int speed_type;               /* 0 speedl, 1 speedj                                */
  urt_ctrl_cmd_t last_stream;   /* last streamed command submitted                   */
  uint64_t stream_id;
  double damping, gain_scaling;
  double jog_frame[6];
  double waypoint[6];           /* target pose of the last move submitted            */
  bool have_waypoint;
  uint64_t waypoint_id;

  /* contact detection (the contact thread) */
  int contact_phase;            /* 0 off, 1 waiting for no contact, 2 waiting for contact */
  double contact_dir[6];
  int contact_step_back;
  double ft_bias[6];            /* zero_ftsensor                                     */

  /* rtde_set_watchdog */
  bool wd_on;
  double wd_period, wd_last;
  int wd_reg;
  uint32_t wd_count;

  bool in_service;              /* service() runs (a submit retry inside it must not re-enter) */

  /* history, one entry per tick */
  uint64_t hist_n;
  double hist_q[HIST][URT_NJ], hist_f[HIST][6];
} rc;

static int fail(rc *R, const char *fmt, ...) {
  if (R->err->kind != US_ERR_NONE) return -1;
  R->err->kind = US_ERR_RUNTIME;
  R->err->line = R->cmd >= 0 && R->cmd < URT_RC_MAX_CMD ? R->info->cmd_line[R->cmd] : 0;
  R->err->column = R->err->line ? 1 : 0;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(R->err->text, sizeof R->err->text, fmt, ap);
  va_end(ap);
  return -1;
}

static void text(rc *R, const char *fmt, ...) {
  urt_script_msg_t m;
  memset(&m, 0, sizeof m);
  m.kind = URT_SCRIPT_MSG_TEXT;
  m.time = R->s.time;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(m.text, sizeof m.text, fmt, ap);
  va_end(ap);
  R->host->message(R->host->ctx, &m);
}

//---- registers ----

static double in_d(rc *R, int k) { return R->reg.in_double[k + R->of]; }
static int in_i(rc *R, int k) { return R->reg.in_int[k + R->oi]; }
static void in_vec6(rc *R, int k, double x[6]) {
  for (int j = 0; j < 6; j++) x[j] = in_d(R, k + j);
}

static int out_int(rc *R, int k, int v) {
  if (k + R->oi >= URT_RTDE_NREG) return fail(R, "Index out of range: output_int_register_%d", k + R->oi);
  R->host->write_output_register(R->host->ctx, URT_SCRIPT_REG_INT, k + R->oi, (double)v);
  return 0;
}

static int out_double(rc *R, int k, double v) {
  if (k + R->of >= URT_RTDE_NREG) return fail(R, "Index out of range: output_double_register_%d", k + R->of);
  R->host->write_output_register(R->host->ctx, URT_SCRIPT_REG_DOUBLE, k + R->of, v);
  return 0;
}

static int out_vec6(rc *R, const double x[6]) {
  for (int j = 0; j < 6; j++) {
    if (out_double(R, j, x[j]) != 0) return -1;
  }
  return 0;
}

/* a 6×6 row-major matrix the way the script writes get_mass_matrix()/get_jacobian(): column
 * by column, columns 0–3 to registers 0–23 and columns 4–5 to 36–47 */
static int out_mat6(rc *R, const double A[36]) {
  for (int c = 0; c < 6; c++) {
    for (int r = 0; r < 6; r++) {
      int k = c < 4 ? 6 * c + r : 36 + 6 * (c - 4) + r;
      if (out_double(R, k, A[6 * r + c]) != 0) return -1;
    }
  }
  return 0;
}

/* write_async_progress_register(value): bits 0–14 progress, 15 running, 16–22 write counter,
 * 24–30 operation id; value 0 starts an operation, a negative value finishes it */
static int write_progress(rc *R, int value) {
  R->wr_count = R->wr_count + 1 > 127 ? 0 : R->wr_count + 1;
  if (value == 0) R->op_id = R->op_id + 1 > 127 ? 0 : R->op_id + 1;
  int32_t reg = R->wr_count * 65536 + R->op_id * 16777216;
  if (value >= 0) reg += (value > 32767 ? 32767 : value) + 32768;
  return out_int(R, 2, reg);
}

//---- time: one controller tick, and everything the script's threads do in it ----

static int service(rc *R);

static void record(rc *R) {
  uint64_t k = R->hist_n++ % HIST;
  memcpy(R->hist_q[k], R->s.q, sizeof R->hist_q[k]);
  for (int j = 0; j < 6; j++) R->hist_f[k][j] = R->s.tcp_force[j] - R->ft_bias[j];
}

/* wait for the next tick (or the wait timeout); a new tick is recorded and serviced */
static int wait_once(rc *R) {
  uint64_t t = R->host->wait_tick(R->host->ctx, R->tick, R->h->wait_timeout_ms);
  if (R->h->poll && R->h->poll(R->h->poll_ctx)) {
    if (R->err->kind == US_ERR_NONE) {
      R->err->kind = US_ERR_CANCEL;
      snprintf(R->err->text, sizeof R->err->text, "stopped");
    }
    return -1;
  }
  if (t <= R->tick) return 0;
  R->tick = t;
  R->host->snapshot(R->host->ctx, &R->s);
  R->host->read_registers(R->host->ctx, &R->reg);
  record(R);
  return service(R);
}

/* the script's sync(): block until a newer tick */
static int sync_tick(rc *R) {
  uint64_t t0 = R->tick;
  while (R->tick <= t0) {
    if (wait_once(R) != 0) return -1;
  }
  return 0;
}

static int submit(rc *R, const urt_ctrl_cmd_t *c) {
  for (int k = 0; k <= SUBMIT_RETRY_TICKS; k++) {
    if (R->host->submit(R->host->ctx, c)) return 0;
    if (wait_once(R) != 0) return -1;
  }
  return fail(R, "Controller command queue is full");
}

static int submit_motion(rc *R, urt_ctrl_cmd_t *c) {
  c->id = ++*R->h->motion_id;
  return submit(R, c);
}

static int motion_check(rc *R, const char *what) {
  char text[sizeof R->err->text];
  if (urt__us_motion_refused(&R->s, what, "safety stop", text, sizeof text)) {
    return fail(R, "%s", text);
  }
  return 0;
}

/* submit a motion and block until the controller reports it done (a blocking builtin) */
static int move_wait(rc *R, urt_ctrl_cmd_t *c, const char *what) {
  if (submit_motion(R, c) != 0) return -1;
  for (;;) {
    R->host->snapshot(R->host->ctx, &R->s);
    if (R->s.motion_done_id >= c->id) break;
    if (!urt__us_safety_ok(&R->s) || R->s.robot_mode != URT_ROBOT_MODE_RUNNING) break;
    if (wait_once(R) != 0) return -1;
  }
  return motion_check(R, what);
}

//---- kinematics and the model ----

static int ik(rc *R, const double pose[6], const double qnear[6], double q[6]) {
  if (!R->host->inverse_kinematics) return fail(R, "get_inverse_kin: inverse kinematics is not available");
  if (R->host->inverse_kinematics(R->host->ctx, pose, qnear, q) != 0) {
    return fail(R, "get_inverse_kin: no solution for p[%g, %g, %g, %g, %g, %g]", pose[0], pose[1],
                pose[2], pose[3], pose[4], pose[5]);
  }
  return 0;
}

static int fk(rc *R, const double q[6], double pose[6]) {
  if (!R->host->forward_kinematics) return fail(R, "get_forward_kin: forward kinematics is not available");
  if (R->host->forward_kinematics(R->host->ctx, q, pose) != 0) return fail(R, "get_forward_kin failed");
  return 0;
}

static const urt_model_t *model(rc *R, const char *what) {
  const urt_model_t *m = R->host->model ? R->host->model(R->host->ctx) : NULL;
  if (!m) fail(R, "%s: the robot model is not available", what);
  return m;
}

static bool joints_within_limits(const urt_model_t *m, const double q[6]) {
  for (int j = 0; j < URT_NJ; j++) {
    if (!isfinite(q[j]) || q[j] < m->joint[j].q_min || q[j] > m->joint[j].q_max) return false;
  }
  return true;
}

//---- async operations (the move and stop threads) ----

static int async_start(rc *R, int kind, uint64_t id) {
  R->async_kind = kind;
  R->async_id = id;
  return write_progress(R, 0);  // signal_async_operation_started()
}

static int async_finish(rc *R) {
  R->async_kind = ASYNC_NONE;
  return write_progress(R, -1);  // signal_async_operation_finished()
}

/* stop_async_move(): a running move thread is killed and reported finished */
static int stop_async_move(rc *R) {
  if (R->async_kind == ASYNC_MOVE || R->async_kind == ASYNC_PATH) return async_finish(R);
  return 0;
}

/* one waypoint of the injected path; wait: block until it is done */
static int path_move(rc *R, int i, bool wait) {
  const urt__rc_move *m = &R->info->path[i];
  urt_ctrl_cmd_t c = {.a = m->a, .v = m->v, .r = 0};  // blends are not honoured: r = 0 (stop)

  // the injected code signals progress before each waypoint: signal_async_progress(i)
  if (write_progress(R, i) != 0) return -1;
  if (m->kind == 'p' || m->kind == 'c') {
    return fail(R, "%s is not supported by urtwin (line %u of the move path)",
                m->kind == 'p' ? "movep" : "movec", m->line);
  }
  if (m->kind == 'j') {
    c.kind = URT_CTRL_MOVEJ;
    if (m->is_pose) {
      if (ik(R, m->x, R->s.q, c.q) != 0) return -1;
    } else {
      memcpy(c.q, m->x, sizeof c.q);
    }
  } else {
    c.kind = URT_CTRL_MOVEL;
    if (m->is_pose) {
      memcpy(c.pose, m->x, sizeof c.pose);
    } else if (fk(R, m->x, c.pose) != 0) {
      return -1;
    }
  }
  if (wait) return move_wait(R, &c, m->kind == 'j' ? "movej" : "movel");
  if (submit_motion(R, &c) != 0) return -1;
  R->async_id = c.id;
  return 0;
}

/* the threads' work for one tick */
static int service_async(rc *R) {
  if (R->async_kind == ASYNC_NONE) return 0;
  if (R->s.motion_done_id < R->async_id) {
    if (!urt__us_safety_ok(&R->s) || R->s.robot_mode != URT_ROBOT_MODE_RUNNING) {
      return motion_check(R, R->async_kind == ASYNC_STOP ? "stop" : "move");
    }
    return 0;
  }
  if (motion_check(R, R->async_kind == ASYNC_STOP ? "stop" : "move") != 0) return -1;
  if (R->async_kind == ASYNC_PATH && R->path_next < R->info->n_path) {
    return path_move(R, R->path_next++, false);
  }
  return async_finish(R);
}

//---- contact ----

/* tool_contact(direction): ticks back to just before a contact along the direction's
 * translation started, or 0 without a contact. A contact is a resisting force (opposite to the
 * direction) above CONTACT_FORCE in the TCP force, which is zeroed by zero_ftsensor. An all-zero
 * direction considers contacts from every direction (UR's tool_contact): the force's size. */
static int tool_contact(rc *R, const double dir[6]) {
  double n = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  if (R->hist_n == 0) return 0;
  uint64_t avail = R->hist_n < HIST ? R->hist_n : HIST;
  int steps = 0;
  for (uint64_t k = 0; k < avail; k++) {
    const double *f = R->hist_f[(R->hist_n - 1 - k) % HIST];
    double resist = n < 1e-12 ? sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                              : -(f[0] * dir[0] + f[1] * dir[1] + f[2] * dir[2]) / n;
    if (k == 0 && resist <= CONTACT_FORCE) return 0;
    if (resist <= CONTACT_ONSET) break;
    steps = (int)k + 1;
  }
  return steps;
}

/* get_actual_joint_positions_history(steps) */
static int history_q(rc *R, int steps, double q[6]) {
  if (steps < 0 || steps >= HIST) {
    return fail(R, "get_actual_joint_positions_history: %d steps is outside 0..%d", steps, HIST - 1);
  }
  uint64_t back = (uint64_t)steps < R->hist_n ? (uint64_t)steps : R->hist_n - 1;
  memcpy(q, R->hist_q[(R->hist_n - 1 - back) % HIST], 6 * sizeof *q);
  return 0;
}

/* pose_is_null(p) as the script writes it: the sum of the six numbers below 1e-10 (so a
 * direction with a negative sum counts as null and the target TCP speed is used instead) */
static bool pose_is_null(const double p[6]) {
  return p[0] + p[1] + p[2] + p[3] + p[4] + p[5] < 1e-10;
}

static int service_contact(rc *R) {
  if (R->contact_phase == 0) return 0;
  const double *dir = pose_is_null(R->contact_dir) ? R->s.tcp_speed_target : R->contact_dir;
  int step_back = tool_contact(R, dir);
  if (R->contact_phase == 1) {
    if (step_back == 0) R->contact_phase = 2;  // first no contact, then wait for one
    return 0;
  }
  if (step_back > 0) {
    R->contact_phase = 0;
    R->contact_step_back = step_back;
    R->internal_cmd = 254;  // the main loop handles it when idle
  }
  return 0;
}

//---- watchdog and streamed-motion faults ----

static int service_tick(rc *R);

static int service(rc *R) {
  if (R->in_service) return 0;
  R->in_service = true;
  int r = service_tick(R);
  R->in_service = false;
  return r;
}

static int service_tick(rc *R) {
  // rtde_set_watchdog(input_int_register_N, f, "stop"): a refresh within 1/f (one tick of slack)
  if (R->wd_on) {
    uint32_t n = R->reg.in_int_writes[R->wd_reg];
    if (n != R->wd_count) {
      R->wd_count = n;
      R->wd_last = R->s.time;
    } else if (R->s.time - R->wd_last > R->wd_period + R->s.period + 1e-9) {
      R->cmd = -1;
      return fail(R, "RTDE watchdog: input_int_register_%d was not updated for %.3f s "
                     "(minimum frequency %g Hz); program stopped",
                  R->wd_reg, R->s.time - R->wd_last, 1.0 / R->wd_period);
    }
  }

  // a streamed motion (servo, speed, force, torque, jog) that the controller refused or aborted
  if (R->servoing || R->speeding || R->forcing || R->torquing || R->jogging) {
    bool applied = R->s.motion_id >= R->stream_id || R->s.motion_done_id >= R->stream_id;
    if (!urt__us_safety_ok(&R->s) || R->s.robot_mode != URT_ROBOT_MODE_RUNNING ||
        (applied && R->s.ctrl_fault)) {
      R->servoing = R->speeding = R->forcing = R->torquing = R->jogging = false;
      return motion_check(R, "streamed motion");
    }
  }
  if (service_async(R) != 0) return -1;
  return service_contact(R);
}

/* submit a streamed command unless it equals the last one of the same mode */
static int stream(rc *R, urt_ctrl_cmd_t *c, bool *active) {
  urt_ctrl_cmd_t a = *c, b = R->last_stream;
  a.id = b.id = 0;
  if (*active && memcmp(&a, &b, sizeof a) == 0) return 0;
  if (submit_motion(R, c) != 0) return -1;
  R->last_stream = *c;
  R->stream_id = c->id;
  *active = true;
  return 0;
}

static void end_streams(rc *R) {
  R->servoing = R->speeding = R->forcing = R->torquing = R->jogging = false;
  memset(&R->last_stream, 0, sizeof R->last_stream);
}

//---- commands ----

static int stop_wait(rc *R, int type, double a, const char *what) {
  urt_ctrl_cmd_t c = {.kind = type == 1 ? URT_CTRL_STOPL : URT_CTRL_STOPJ, .a = a};
  return move_wait(R, &c, what);
}

/* moveJ (1), moveJ_IK (2), moveL (3), moveL_FK (4): d0..5 target, d6 v, d7 a, i1 async */
static int cmd_move(rc *R, int cmd) {
  double x[6];
  in_vec6(R, 0, x);
  urt_ctrl_cmd_t c = {.v = in_d(R, 6), .a = in_d(R, 7)};
  bool async = in_i(R, 1) == 1;
  const char *what = cmd <= 2 ? "movej" : "movel";

  // the target in the controller's terms
  if (cmd == 1 || cmd == 2) {
    c.kind = URT_CTRL_MOVEJ;
    if (cmd == 2) {
      if (ik(R, x, R->s.q, c.q) != 0) return -1;
    } else {
      memcpy(c.q, x, sizeof c.q);
    }
  } else {
    c.kind = URT_CTRL_MOVEL;
    if (cmd == 4) {
      if (fk(R, x, c.pose) != 0) return -1;
    } else {
      memcpy(c.pose, x, sizeof c.pose);
    }
  }

  // get_target_waypoint() answers this target while the move runs (a joint target as its pose)
  R->have_waypoint = c.kind == URT_CTRL_MOVEL || R->host->forward_kinematics;
  if (c.kind == URT_CTRL_MOVEL) {
    memcpy(R->waypoint, c.pose, sizeof c.pose);
  } else if (R->have_waypoint && fk(R, c.q, R->waypoint) != 0) {
    return -1;
  }
  R->waypoint_id = *R->h->motion_id + 1;  // the id submit_motion gives it

  end_streams(R);
  if (stop_async_move(R) != 0) return -1;
  if (!async) return move_wait(R, &c, what);
  if (submit_motion(R, &c) != 0) return -1;
  return async_start(R, ASYNC_MOVE, c.id);
}

/* stopL (33) / stopJ (34): d0 deceleration, i1 async (exec_stopl_stopj) */
static int cmd_stop(rc *R) {
  double dec = in_d(R, 0);
  bool async = in_i(R, 1) == 1;
  bool stop_move = true;
  if (R->async_kind == ASYNC_STOP) {
    // an async stop already runs: restart it with the new parameters
    stop_move = false;
    if (async_finish(R) != 0) return -1;
  }
  if (stop_move && stop_async_move(R) != 0) return -1;
  end_streams(R);
  if (async) {
    R->stop_type = 1;  // the script always stops async with stopl
    urt_ctrl_cmd_t c = {.kind = URT_CTRL_STOPL, .a = dec};
    if (submit_motion(R, &c) != 0) return -1;
    return async_start(R, ASYNC_STOP, c.id);
  }
  // the script's sync stop follows the stop_type of the last async stop (stopj before any)
  return stop_wait(R, R->stop_type, dec, R->stop_type == 1 ? "stopl" : "stopj");
}

/* movePath (45): the waypoints injected into exec_move_path(), i1 async */
static int cmd_path(rc *R) {
  bool async = in_i(R, 1) == 1;
  if (R->info->path_bad_line) {
    R->cmd = -1;
    R->err->line = 0;
    return fail(R, "move path: urtwin cannot run line %u of exec_move_path()", R->info->path_bad_line);
  }
  end_streams(R);
  if (stop_async_move(R) != 0) return -1;
  if (async) {
    if (write_progress(R, 0) != 0) return -1;  // signal_async_operation_started()
    R->async_kind = ASYNC_PATH;
    R->path_next = 0;
    if (R->info->n_path == 0) return async_finish(R);
    return path_move(R, R->path_next++, false);
  }
  // sync: like the script, progress is written per waypoint and never finished
  for (int i = 0; i < R->info->n_path; i++) {
    if (path_move(R, i, true) != 0) return -1;
  }
  return 0;
}

/* moveUntilContact (51): d0..5 tool speed, d6..11 contact direction, d12 acceleration */
static int cmd_move_until_contact(rc *R) {
  double xd[6], dir[6];
  in_vec6(R, 0, xd);
  in_vec6(R, 6, dir);
  double acc = in_d(R, 12);
  end_streams(R);
  for (;;) {
    int step_back = tool_contact(R, dir);
    if (step_back <= 0) {
      urt_ctrl_cmd_t c = {.kind = URT_CTRL_SPEEDL, .a = acc, .a_rot = acc};
      memcpy(c.pose, xd, sizeof c.pose);
      if (stream(R, &c, &R->speeding) != 0 || sync_tick(R) != 0) return -1;
      continue;
    }

    // contact: back to where it was first seen
    R->speeding = false;
    double q[6], p[6];
    if (history_q(R, step_back, q) != 0 || stop_wait(R, 1, 3.0, "stopl") != 0 || fk(R, q, p) != 0) {
      return -1;
    }
    urt_ctrl_cmd_t c = {.kind = URT_CTRL_MOVEL, .a = 1.2, .v = 0.25};
    memcpy(c.pose, p, sizeof c.pose);
    return move_wait(R, &c, "movel");
  }
}

/* the internal 254: contact detection found a contact */
static int cmd_contact_detected(rc *R) {
  text(R, "cmd == 254 - contact detected");
  if (stop_async_move(R) != 0) return -1;
  end_streams(R);
  double q[6], p[6];
  if (history_q(R, R->contact_step_back, q) != 0 || stop_wait(R, 1, 3.0, "stopl") != 0 ||
      fk(R, q, p) != 0) {
    return -1;
  }
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_MOVEL, .a = 1.2, .v = 0.25};
  memcpy(c.pose, p, sizeof c.pose);
  return move_wait(R, &c, "movel");
}

static int force_mode_submit(rc *R) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_FORCE_MODE, .index = in_i(R, 1)};
  in_vec6(R, 0, c.pose);  // task frame
  for (int j = 0; j < 6; j++) c.q[j] = in_i(R, 2 + j);  // selection vector
  in_vec6(R, 6, c.tau);   // wrench
  in_vec6(R, 12, c.qd);   // limits
  c.value = R->damping;   // force_mode_set_damping
  c.gain = R->gain_scaling;  // force_mode_set_gain_scaling
  if (R->servoing || R->speeding || R->jogging || R->torquing) {
    R->servoing = R->speeding = R->jogging = R->torquing = false;
    memset(&R->last_stream, 0, sizeof R->last_stream);
  }
  return stream(R, &c, &R->forcing);
}

/* the 6×6 matrices of the model at the actual joint positions */
static int cmd_matrix(rc *R, int cmd) {
  const urt_model_t *m = model(R, cmd == 67 ? "get_mass_matrix" : cmd == 70 ? "get_jacobian"
                                                               : "get_jacobian_time_derivative");
  if (!m) return -1;
  double A[36];
  if (cmd == 67) {
    urt_arm_mass_matrix(m, R->s.q, A);
  } else if (cmd == 70) {
    urt_arm_jacobian(m, R->s.q, A);
  } else {
    // dJ/dt = Σ_j ∂J/∂q_j q̇_j: a central difference along q̇
    double h = 1e-6, qp[6], qm[6], Jp[36], Jm[36];
    for (int j = 0; j < 6; j++) {
      qp[j] = R->s.q[j] + h * R->s.qd[j];
      qm[j] = R->s.q[j] - h * R->s.qd[j];
    }
    urt_arm_jacobian(m, qp, Jp);
    urt_arm_jacobian(m, qm, Jm);
    for (int k = 0; k < 36; k++) A[k] = (Jp[k] - Jm[k]) / (2 * h);
  }
  return out_mat6(R, A);
}

/* process_cmd(cmd): 0 go on, 1 stop script, -1 error */
static int process(rc *R, int cmd) {
  R->cmd = cmd;
  const urt__rc_info *I = R->info;
  if (cmd == 0) return 0;

  // an id the uploaded script has no branch for, or a branch its version pruned to
  // `dummy_op = 1`: the script does nothing (and answers DONE / ready)
  if (cmd <= 0 || cmd >= URT_RC_MAX_CMD || !I->has_cmd[cmd] || !I->has_body[cmd]) return 0;

  double x[6], y[6], q[6], p[6];
  urt_ctrl_cmd_t c;
  memset(&c, 0, sizeof c);
  switch (cmd) {
    case 1: case 2: case 3: case 4:
      return cmd_move(R, cmd);

    case 6:  // forceMode: i1 type, i2..7 selection, d0..5 frame, d6..11 wrench, d12..17 limits
      return force_mode_submit(R);
    case 7:  // forceModeStop: end_force_mode(); stopl(10)
      R->forcing = false;
      c.kind = URT_CTRL_FORCE_MODE_END;
      if (submit(R, &c) != 0) return -1;
      return stop_wait(R, 1, 10.0, "stopl");
    case 8:  // zeroFtSensor: the native contact detection measures from here
      memcpy(R->ft_bias, R->s.tcp_force, sizeof R->ft_bias);
      return 0;

    case 9: case 10: {  // speedJ / speedL: d0..5 speeds, d6 a, d7 t (the thread loops: continuous)
      if (R->servoing || R->forcing || R->jogging || R->torquing) end_streams(R);
      c.kind = cmd == 9 ? URT_CTRL_SPEEDJ : URT_CTRL_SPEEDL;
      in_vec6(R, 0, cmd == 9 ? c.q : c.pose);
      c.a = in_d(R, 6);
      if (cmd == 10) c.a_rot = c.a;
      if (R->speeding && R->speed_type != (cmd == 9)) R->speeding = false;
      R->speed_type = cmd == 9;
      return stream(R, &c, &R->speeding);
    }
    case 11: case 24:  // servoJ / servoL: d0..5 target, d8 t, d9 lookahead, d10 gain
      if (R->speeding || R->forcing || R->jogging || R->torquing) end_streams(R);
      c.kind = cmd == 11 ? URT_CTRL_SERVOJ : URT_CTRL_SERVOL;
      in_vec6(R, 0, cmd == 11 ? c.q : c.pose);
      c.t = in_d(R, 8);
      c.lookahead_time = in_d(R, 9);
      c.gain = in_d(R, 10);
      if (R->servoing && R->last_stream.kind != c.kind) R->servoing = false;
      return stream(R, &c, &R->servoing);
    case 12:  // servoC: d0..5 pose, d6 v, d7 a, d8 blend
      if (R->speeding || R->forcing || R->jogging || R->torquing) end_streams(R);
      c.kind = URT_CTRL_SERVOC;
      in_vec6(R, 0, c.pose);
      c.v = in_d(R, 6);
      c.a = in_d(R, 7);
      c.r = in_d(R, 8);
      if (R->servoing && R->last_stream.kind != c.kind) R->servoing = false;
      return stream(R, &c, &R->servoing);
    case 15:  // speedStop: d0 deceleration; stopl or stopj after the last speed type
      R->speeding = false;
      return stop_wait(R, R->speed_type == 0 ? 1 : 0, in_d(R, 0), R->speed_type == 0 ? "stopl" : "stopj");
    case 16:  // servoStop: d0 deceleration
      R->servoing = false;
      return stop_wait(R, 1, in_d(R, 0), "stopl");

    case 17: case 65: {  // setPayload / setTargetPayload: d0 mass, d1..3 CoG (0: keep), d4..9 inertia
      c.kind = URT_CTRL_SET_PAYLOAD;
      c.value = in_d(R, 0);
      for (int j = 0; j < 3; j++) c.pose[j] = in_d(R, 1 + j);
      if (c.pose[0] == 0 && c.pose[1] == 0 && c.pose[2] == 0) memcpy(c.pose, R->s.payload_cog, 3 * sizeof(double));
      if (cmd == 65) {
        for (int j = 0; j < 6; j++) c.tau[j] = in_d(R, 4 + j);  // inertia: see report, no field yet
      }
      if (!(c.value >= 0)) return fail(R, "set_payload: invalid mass %g", c.value);
      return submit(R, &c);
    }
    case 18: case 52:  // teachMode / freedriveMode: i1..6 free axes, d0..5 feature
      end_streams(R);
      c.kind = URT_CTRL_FREEDRIVE;
      c.index = 1;
      for (int j = 0; j < 6; j++) c.q[j] = cmd == 18 ? 1 : in_i(R, 1 + j);
      if (cmd == 52) in_vec6(R, 0, c.pose);
      return submit_motion(R, &c);
    case 19: case 53:  // endTeachMode / endFreedriveMode
      c.kind = URT_CTRL_FREEDRIVE;
      c.index = 0;
      return submit_motion(R, &c);
    case 54:  // getFreedriveStatus
      return out_int(R, 1, R->s.motion == URT_MOTION_FREEDRIVE ? 1 : 0);
    case 20: case 21:  // forceModeSetDamping / forceModeSetGainScaling: d0
      if (cmd == 20) R->damping = in_d(R, 0);
      else R->gain_scaling = in_d(R, 0);
      if (R->forcing) {
        urt_ctrl_cmd_t f = R->last_stream;
        f.value = R->damping;
        f.gain = R->gain_scaling;
        return stream(R, &f, &R->forcing);
      }
      return 0;

    case 25:  // toolContact: d0..5 direction → i1 steps
      in_vec6(R, 0, x);
      return out_int(R, 1, tool_contact(R, x));
    case 26:  // getStepTime → d0
      return out_double(R, 0, R->s.period);
    case 27:  // getActualJointPositionsHistory: i1 steps → d0..5
      if (history_q(R, in_i(R, 1), q) != 0) return -1;
      return out_vec6(R, q);
    case 28:  // getTargetWaypoint → d0..5
      if (R->have_waypoint && R->s.motion_done_id < R->waypoint_id) return out_vec6(R, R->waypoint);
      return out_vec6(R, R->s.tcp_pose_target);
    case 29:  // setTcp: d0..5
      c.kind = URT_CTRL_SET_TCP;
      in_vec6(R, 0, c.pose);
      return submit(R, &c);
    case 30: case 61: {  // IK with qnear (d6..11) and tolerances (d12, d13)
      in_vec6(R, 0, x);
      in_vec6(R, 6, y);
      if (cmd == 61) {
        bool ok = R->host->inverse_kinematics && R->host->inverse_kinematics(R->host->ctx, x, y, q) == 0;
        return out_int(R, 1, ok ? 1 : 0);
      }
      if (ik(R, x, y, q) != 0) return -1;
      return out_vec6(R, q);
    }
    case 46: case 60:  // IK default (qnear: the actual joint positions)
      in_vec6(R, 0, x);
      if (cmd == 60) {
        bool ok = R->host->inverse_kinematics && R->host->inverse_kinematics(R->host->ctx, x, R->s.q, q) == 0;
        return out_int(R, 1, ok ? 1 : 0);
      }
      if (ik(R, x, R->s.q, q) != 0) return -1;
      return out_vec6(R, q);
    case 43:  // FK default: the actual joint positions, active TCP
      if (fk(R, R->s.q, p) != 0) return -1;
      return out_vec6(R, p);
    case 44: {  // FK args: d0..5 q, d6..11 TCP offset
      const urt_model_t *m = model(R, "get_forward_kin");
      if (!m) return -1;
      in_vec6(R, 0, q);
      in_vec6(R, 6, y);
      urt_ctrl_forward_kinematics_tcp(m, y, q, p);
      return out_vec6(R, p);
    }
    case 58: {  // getActualToolFlangePose: FK with a zero TCP
      const urt_model_t *m = model(R, "get_actual_tool_flange_pose");
      if (!m) return -1;
      double zero[6] = {0};
      urt_ctrl_forward_kinematics_tcp(m, zero, R->s.q, p);
      return out_vec6(R, p);
    }
    case 33: case 34:
      return cmd_stop(R);
    case 35: {  // setWatchdog: d0 minimum frequency → rtde_set_watchdog(input_int_register_0|24)
      double f = in_d(R, 0);
      R->wd_reg = R->oi == 24 ? 24 : 0;
      R->wd_on = f > 0;
      R->wd_period = f > 0 ? 1.0 / f : 0;
      R->wd_count = R->reg.in_int_writes[R->wd_reg];
      R->wd_last = R->s.time;
      return 0;
    }
    case 36: case 37: {  // isPoseWithinSafetyLimits / isJointsWithinSafetyLimits → i1
      const urt_model_t *m = model(R, "is_within_safety_limits");
      if (!m) return -1;
      in_vec6(R, 0, x);
      bool ok;
      if (cmd == 36) {
        ok = R->host->inverse_kinematics && R->host->inverse_kinematics(R->host->ctx, x, R->s.q, q) == 0 &&
             joints_within_limits(m, q);
      } else {
        ok = joints_within_limits(m, x);
      }
      return out_int(R, 1, ok ? 1 : 0);
    }
    case 38:  // getJointTorques → d0..5
      return out_vec6(R, R->s.tau);
    case 39:  // poseTrans: d0..5 p_from, d6..11 p_from_to → d0..5
      in_vec6(R, 0, x);
      in_vec6(R, 6, y);
      urt__us_pose_trans(x, y, p);
      return out_vec6(R, p);
    case 40:  // getTCPOffset → d0..5
      return out_vec6(R, R->s.tcp_offset);
    case 41: {  // jogStart: d0..5 speeds, d6 feature (0 base, 1 tool, 2 custom), d7 a, d8..13 custom
      double v[6], Rm[9];
      in_vec6(R, 0, v);
      if (!R->jogging) {
        // the jog thread fixes its frame when it starts
        int feature = (int)in_d(R, 6);
        static const double base[6] = {0};
        if (feature == 1) memcpy(R->jog_frame, R->s.tcp_pose, sizeof R->jog_frame);
        else if (feature == 2) in_vec6(R, 8, R->jog_frame);
        else memcpy(R->jog_frame, base, sizeof R->jog_frame);
        end_streams(R);
      }
      urt__us_rotvec_to_mat(R->jog_frame + 3, Rm);
      c.kind = URT_CTRL_SPEEDL;
      for (int i = 0; i < 3; i++) {
        c.pose[i] = Rm[3 * i] * v[0] + Rm[3 * i + 1] * v[1] + Rm[3 * i + 2] * v[2];
        c.pose[3 + i] = Rm[3 * i] * v[3] + Rm[3 * i + 1] * v[4] + Rm[3 * i + 2] * v[5];
      }
      c.a = c.a_rot = in_d(R, 7);
      return stream(R, &c, &R->jogging);
    }
    case 42:  // jogStop
      R->jogging = false;
      return stop_wait(R, 1, 1.2, "stopl");
    case 45:
      return cmd_path(R);
    case 47: {  // isSteady → i1
      bool steady = R->s.motion == URT_MOTION_IDLE;
      for (int j = 0; j < URT_NJ; j++) steady = steady && fabs(R->s.qd[j]) <= STEADY_SPEED;
      return out_int(R, 1, steady ? 1 : 0);
    }
    case 51:
      return cmd_move_until_contact(R);
    case 59:  // setGravity: d0..2 is UR's "direction": the acceleration away from the earth
      c.kind = URT_CTRL_SET_GRAVITY;
      for (int j = 0; j < 3; j++) c.pose[j] = -in_d(R, j);
      return submit(R, &c);
    case 62:  // startContactDetection: d0..5 direction (null: the target TCP speed)
      in_vec6(R, 0, R->contact_dir);
      R->contact_phase = 1;
      R->contact_step_back = 0;
      return 0;
    case 63:  // stopContactDetection → i1
      R->contact_phase = 0;
      return out_int(R, 1, R->contact_step_back);
    case 64:  // readContactDetection → i1
      return out_int(R, 1, R->contact_step_back);
    case 66:  // directTorque: d0..5 torques; the script passes zero friction scales
      if (R->servoing || R->speeding || R->forcing || R->jogging) end_streams(R);
      c.kind = URT_CTRL_TORQUE;
      in_vec6(R, 0, c.tau);
      c.index = 0;
      return stream(R, &c, &R->torquing);
    case 67: case 70: case 71:
      return cmd_matrix(R, cmd);
    case 68: {  // getCoriolisAndCentrifugal: C(q, q̇) q̇ = rnea(q, q̇, 0) − g(q)
      const urt_model_t *m = model(R, "get_coriolis_and_centrifugal_torques");
      if (!m) return -1;
      double zero[6] = {0}, tau[6], g[6];
      urt_arm_rnea(m, R->s.q, R->s.qd, zero, tau);
      urt_arm_gravity(m, R->s.q, g);
      for (int j = 0; j < 6; j++) tau[j] -= g[j];
      return out_vec6(R, tau);
    }
    case 69:  // getTargetJointAccelerations → d0..5
      return out_vec6(R, R->s.qdd_target);
    case 254:
      return cmd_contact_detected(R);
    case 255:
      text(R, "Received stop script!");
      return 1;

    case 31:
      return fail(R, "protective_stop is not supported by urtwin");
    case 56:
      return fail(R, "ft_rtde_input_enable is not supported by urtwin");
    case 57:
      return fail(R, "enable_external_ft_sensor is not supported by urtwin");
    default:
      return fail(R, "rtde_control command %d is not supported by urtwin", cmd);
  }
}

//---- the main loop ----

int urt__rc_run(const urt__rc_info *info, const us_hooks *h, us_err *err) {
  memset(err, 0, sizeof *err);
  rc *R = calloc(1, sizeof *R);
  if (!R) {
    err->kind = US_ERR_RUNTIME;
    snprintf(err->text, sizeof err->text, "Out of memory");
    return -1;
  }
  R->info = info;
  R->h = h;
  R->host = h->host;
  R->err = err;
  R->oi = info->reg_offset_int;
  R->of = info->reg_offset_float;
  R->cmd = -1;
  int rc_ = 0;

  // what the program needs from the host and the register offsets it can address
  if (!R->host->read_registers || !R->host->write_output_register) {
    rc_ = fail(R, "rtde_control: the RTDE registers are not available");
  } else if (R->oi > URT_RTDE_NREG - 8 || R->of > URT_RTDE_NREG - 18) {
    rc_ = fail(R, "Index out of range: register offsets %d/%d", R->oi, R->of);
  }
  if (rc_ == 0) {
    R->host->snapshot(R->host->ctx, &R->s);
    R->host->read_registers(R->host->ctx, &R->reg);
    R->tick = R->s.tick;
    record(R);

    // init: the tag, force-mode defaults, reset_async_progress(), signal_ready()
    text(R, "%s", info->tag);
    R->gain_scaling = 0.5;
    R->damping = 0.025;
    rc_ = write_progress(R, -1);
    if (rc_ == 0) rc_ = out_int(R, 0, 1);
  }

  while (rc_ == 0) {
    // rtde_cmd(): the client's command, or an internal one when idle
    int cmd = in_i(R, 0);
    if (cmd == 0) {
      cmd = R->internal_cmd;
      R->internal_cmd = 0;
    }
    int r = 0;
    if (is_realtime(cmd)) {
      r = process(R, cmd);
      if (r == 0) r = out_int(R, 0, 1);
    } else if (cmd == 0) {
      R->executing = false;
      r = out_int(R, 0, 1);
    } else if (!R->executing) {
      R->executing = true;
      r = process(R, cmd);
      if (r == 0) r = out_int(R, 0, 2);  // signal_done_with_cmd()
    }
    if (r == 1) {
      text(R, "RTDE Control Script Terminated");
      break;
    }
    if (r != 0 || sync_tick(R) != 0) {
      rc_ = -1;
      break;
    }
  }
  free(R);
  return rc_ == 0 ? 0 : -1;
}
