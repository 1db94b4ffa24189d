/* SPDX-License-Identifier: Apache-2.0
 * net/dashboard/dashboard.c — the dashboard server protocol of port 29999 (protocols.md §3):
 * a line framer and a pure command handler. No socket, no clock, no global state.
 *
 * Reply texts follow UR's dashboard documentation and the expectations of URCL's G5 dashboard
 * client (src/ur/dashboard_client_implementation_g5.cpp) and ur_rtde's DashboardClient. Texts
 * marked "unconfirmed" below are the best available guess; no client depends on them.
 */
#define _GNU_SOURCE
#include "urt/net/dashboard.h"

#include <errno.h>
#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "urt/controller.h"
#include "urt/snapshot.h"

//---- fixed texts ----

static const char kLocalRefusal[] =
    "Command is not allowed due to safety reasons, please switch robot to Remote Control mode "
    "and reconnect to port 29999";
static const char kUnprotectTooSoon[] =
    "Cannot unlock protective stop until 5s after occurrence. Always inspect cause of protective "
    "stop before unlocking";
static const char kUnnamed[] = "<unnamed>";

//---- enum names (protocols.md §2.8) ----

static const char *robot_mode_name(int32_t m) {
  switch (m) {
    case -1: return "NO_CONTROLLER";
    case 0: return "DISCONNECTED";
    case 1: return "CONFIRM_SAFETY";
    case 2: return "BOOTING";
    case 3: return "POWER_OFF";
    case 4: return "POWER_ON";
    case 5: return "IDLE";
    case 6: return "BACKDRIVE";
    case 7: return "RUNNING";
    case 8: return "UPDATING_FIRMWARE";
    default: return "NO_CONTROLLER";
  }
}

/* Safety mode and safety status share their names (1…22). */
static const char *safety_name(int32_t m) {
  static const char *const names[] = {
      NULL,
      "NORMAL",
      "REDUCED",
      "PROTECTIVE_STOP",
      "RECOVERY",
      "SAFEGUARD_STOP",
      "SYSTEM_EMERGENCY_STOP",
      "ROBOT_EMERGENCY_STOP",
      "VIOLATION",
      "FAULT",
      "VALIDATE_JOINT_ID",
      "UNDEFINED_SAFETY_MODE",
      "AUTOMATIC_MODE_SAFEGUARD_STOP",
      "SYSTEM_THREE_POSITION_ENABLING_STOP",
      "TP_THREE_POSITION_ENABLING_STOP",
      "IMMI_EMERGENCY_STOP",
      "IMMI_SAFEGUARD_STOP",
      "PROFISAFE_WAITING_FOR_PARAMETERS",
      "PROFISAFE_AUTOMATIC_MODE_SAFEGUARD_STOP",
      "PROFISAFE_SAFEGUARD_STOP",
      "PROFISAFE_EMERGENCY_STOP",
      NULL,
      "SAFETY_API_SAFEGUARD_STOP",
  };
  if (m >= 1 && m < (int32_t)(sizeof names / sizeof names[0]) && names[m]) {
    return names[m];
  }
  return "UNDEFINED_SAFETY_MODE";
}

static const char *const kRoleNames[] = {"PROGRAMMER", "OPERATOR", "NONE", "LOCKED", "RESTRICTED"};

//---- bounded reply writer ----

/* Writes at most cap - 2 bytes of text so "\n" and the NUL always fit. Bytes that would break
 * the one-line framing (\n, \r, NUL) are written as '?'. */
typedef struct writer {
  char *p;
  size_t cap, len;
} writer_t;

static void put_n(writer_t *w, const char *s, size_t n) {
  for (size_t i = 0; i < n && w->len + 2 < w->cap; i++) {
    char c = s[i];
    w->p[w->len++] = (c == '\n' || c == '\r' || c == '\0') ? '?' : c;
  }
}

static void put(writer_t *w, const char *s) { put_n(w, s, strlen(s)); }

static void put_u64(writer_t *w, uint64_t x) {
  char tmp[24];
  int n = 0;
  do {
    tmp[n++] = (char)('0' + x % 10);
    x /= 10;
  } while (x);
  while (n) {
    put_n(w, &tmp[--n], 1);
  }
}

static void put_int(writer_t *w, int x) {
  if (x < 0) {
    put(w, "-");
    put_u64(w, (uint64_t)(-(int64_t)x));
  } else {
    put_u64(w, (uint64_t)x);
  }
}

//---- small string helpers ----

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

static char lower(char c) { return (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c; }

static int equals_nocase(const char *s, size_t n, const char *lit) {
  size_t m = strlen(lit);
  if (n != m) {
    return 0;
  }
  for (size_t i = 0; i < n; i++) {
    if (lower(s[i]) != lower(lit[i])) {
      return 0;
    }
  }
  return 1;
}

/* The part after the last '/' (the whole string if none). */
static const char *base_name(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash ? slash + 1 : path;
}

//---- one call of a command ----

typedef struct call {
  const urt_dashboard_ctx_t *ctx;
  const urt_dashboard_robot_t *robot;
  urt_dashboard_state_t *st;
  const char *line;           /* the request, right-trimmed  */
  size_t line_len;
  const char *arg;            /* text after the command words, trimmed; "" if none */
  size_t arg_len;
  writer_t *w;
  urt_dashboard_action_t *act;
} call_t;

static void add_ctrl(urt_dashboard_action_t *a, int32_t kind) {
  if (a->n_ctrl < (int)(sizeof a->ctrl / sizeof a->ctrl[0])) {
    a->ctrl[a->n_ctrl++] = kind;
  }
}

static int program_active(int32_t s) { return s != URT_PROGRAM_STOPPED; }
static int program_playing(int32_t s) { return s == URT_PROGRAM_PLAYING || s == URT_PROGRAM_RESUMING; }

/* A controller that can run programs at all (not booting, not disconnected). */
static int controller_up(int32_t m) { return m >= URT_ROBOT_MODE_POWER_OFF; }

static void stop_if_active(const call_t *c) {
  if (program_active(c->robot->program_state)) {
    c->act->program = URT_DASHBOARD_PROG_STOP;
  }
}

//---- file name resolution for load / load installation ----

enum { RESOLVE_OK = 0, RESOLVE_NOT_FOUND, RESOLVE_BAD };

static int ends_with_nocase(const char *s, const char *end, size_t end_len) {
  size_t n = strlen(s);
  return n >= end_len && equals_nocase(s + n - end_len, end_len, end) && end_len > 0;
}

/* Does the resolved path end with one of the comma-separated endings in exts? */
static int has_ext(const char *path, const char *exts) {
  const char *p = exts;
  while (*p) {
    const char *comma = strchr(p, ',');
    size_t n = comma ? (size_t)(comma - p) : strlen(p);
    char one[32];
    if (n > 0 && n < sizeof one) {
      memcpy(one, p, n);
      one[n] = '\0';
      if (ends_with_nocase(path, one, n)) {
        return 1;
      }
    }
    if (!comma) {
      break;
    }
    p = comma + 1;
  }
  return 0;
}

/* Join a and b with one '/' into out[PATH_MAX]; 0 if it does not fit. */
static int join(char *out, const char *a, const char *b, size_t b_len) {
  size_t a_len = strlen(a);
  while (a_len > 1 && a[a_len - 1] == '/') {
    a_len--;
  }
  if (a_len + 1 + b_len + 1 > PATH_MAX) {
    return 0;
  }
  memcpy(out, a, a_len);
  out[a_len] = '/';
  memcpy(out + a_len + 1, b, b_len);
  out[a_len + 1 + b_len] = '\0';
  return 1;
}

/* Resolve a client-given name to a regular, readable file with one of the endings in exts,
 * strictly inside ctx->programs_dir after following every symlink (realpath). display
 * receives the name as the client sees it; host the resolved host path. Anything outside the
 * directory, or not there at all, is "not found"; there but unusable is "bad". */
static int resolve_file(const urt_dashboard_ctx_t *ctx, const char *arg, size_t arg_len,
                        const char *exts, char *display, char *host) {
  char root[PATH_MAX], cand[PATH_MAX], real[PATH_MAX];

  // names with NUL bytes or too long cannot name a file
  if (arg_len == 0 || memchr(arg, '\0', arg_len) || arg_len >= URT_DASHBOARD_PATH_MAX - 1 ||
      !ctx->programs_dir || !realpath(ctx->programs_dir, root)) {
    return RESOLVE_NOT_FOUND;
  }

  // the name as the client sees it, and where that is on the host
  const char *shown = ctx->programs_alias ? ctx->programs_alias : ctx->programs_dir;
  size_t alias_len = ctx->programs_alias ? strlen(ctx->programs_alias) : 0;
  while (alias_len > 1 && ctx->programs_alias[alias_len - 1] == '/') {
    alias_len--;
  }
  if (arg[0] == '/') {
    if (arg_len >= URT_DASHBOARD_PATH_MAX) {
      return RESOLVE_NOT_FOUND;
    }
    memcpy(display, arg, arg_len);
    display[arg_len] = '\0';
    if (alias_len > 0 && arg_len > alias_len && strncmp(arg, ctx->programs_alias, alias_len) == 0 &&
        arg[alias_len] == '/') {
      if (!join(cand, ctx->programs_dir, arg + alias_len + 1, arg_len - alias_len - 1)) {
        return RESOLVE_NOT_FOUND;
      }
    } else {
      memcpy(cand, display, arg_len + 1);
    }
  } else {
    if (!join(display, shown, arg, arg_len) || strlen(display) >= URT_DASHBOARD_PATH_MAX ||
        !join(cand, ctx->programs_dir, arg, arg_len)) {
      return RESOLVE_NOT_FOUND;
    }
  }

  // follow every symlink and "..", then require the result to lie strictly inside root
  if (!realpath(cand, real)) {
    return RESOLVE_NOT_FOUND;
  }
  size_t root_len = strlen(root);
  int inside = (root_len == 1) ? (real[0] == '/' && real[1] != '\0')
                               : (strncmp(real, root, root_len) == 0 && real[root_len] == '/');
  if (!inside) {
    return RESOLVE_NOT_FOUND;
  }

  // a readable regular file of the right kind
  struct stat sb;
  if (stat(real, &sb) != 0 || !S_ISREG(sb.st_mode) || access(real, R_OK) != 0 ||
      !has_ext(real, exts) || strlen(real) >= URT_DASHBOARD_PATH_MAX) {
    return RESOLVE_BAD;
  }
  strcpy(host, real);
  return RESOLVE_OK;
}

//---- command handlers ----

static void cmd_load(const call_t *c) {
  char display[PATH_MAX], host[PATH_MAX];
  const char *exts = c->ctx->program_exts ? c->ctx->program_exts : ".urp";
  int rc = resolve_file(c->ctx, c->arg, c->arg_len, exts, display, host);
  if (rc == RESOLVE_NOT_FOUND) {
    put(c->w, "File not found: ");
    put_n(c->w, c->arg, c->arg_len);
    return;
  }
  if (rc == RESOLVE_BAD) {
    put(c->w, "Error while loading program: ");
    put_n(c->w, c->arg, c->arg_len);
    return;
  }
  // the owner compiles it (a .urp); UR's failure reply, then why, e.g. the unsupported node
  char why[256] = "";
  if (c->ctx->prepare_program &&
      c->ctx->prepare_program(c->ctx->prepare_user, host, why, sizeof why) != 0) {
    put(c->w, "Error while loading program: ");
    put_n(c->w, c->arg, c->arg_len);
    if (why[0]) {
      put(c->w, ": ");
      put(c->w, why);
    }
    return;
  }
  strcpy(c->st->program_display, display);
  strcpy(c->st->program_path, host);
  c->st->program_loaded = 1;
  strcpy(c->act->path, host);
  c->act->program = URT_DASHBOARD_PROG_LOAD;
  put(c->w, "Loading program: ");
  put(c->w, display);
}

static void cmd_load_installation(const call_t *c) {
  char display[PATH_MAX], host[PATH_MAX];
  int rc = resolve_file(c->ctx, c->arg, c->arg_len, ".installation", display, host);
  if (rc == RESOLVE_NOT_FOUND) {
    put(c->w, "File not found: ");
    put_n(c->w, c->arg, c->arg_len);
    return;
  }
  if (rc == RESOLVE_BAD) {
    put(c->w, "Failed to load installation: ");
    put_n(c->w, c->arg, c->arg_len);
    return;
  }
  strcpy(c->st->installation, display);
  // loading an installation stops the program and leaves the robot powered off
  stop_if_active(c);
  add_ctrl(c->act, URT_CTRL_POWER_OFF);
  put(c->w, "Loading installation: ");
  put_n(c->w, c->arg, c->arg_len);
}

static void cmd_play(const call_t *c) {
  const urt_dashboard_robot_t *r = c->robot;
  int safe = r->safety_mode == URT_SAFETY_MODE_NORMAL || r->safety_mode == URT_SAFETY_MODE_REDUCED;
  // a paused program resumes whatever sent it: one on 30001-30003 has nothing loaded, and a
  // protective stop paused it (core/controller.cpp protective_stop)
  bool have = c->st->program_loaded || r->program_state == URT_PROGRAM_PAUSED;
  if (!have || r->robot_mode != URT_ROBOT_MODE_RUNNING || !safe) {
    put(c->w, "Failed to execute: play");
    return;
  }
  if (!program_playing(r->program_state)) {
    c->act->program = URT_DASHBOARD_PROG_PLAY;
  }
  put(c->w, "Starting program");
}

static void cmd_stop(const call_t *c) {
  if (!controller_up(c->robot->robot_mode)) {
    put(c->w, "Failed to execute: stop");
    return;
  }
  stop_if_active(c);
  put(c->w, "Stopped");
}

static void cmd_pause(const call_t *c) {
  int32_t s = c->robot->program_state;
  if (!controller_up(c->robot->robot_mode) ||
      !(program_playing(s) || s == URT_PROGRAM_PAUSING || s == URT_PROGRAM_PAUSED)) {
    put(c->w, "Failed to execute: pause");
    return;
  }
  if (program_playing(s)) {
    c->act->program = URT_DASHBOARD_PROG_PAUSE;
  }
  put(c->w, "Pausing program");
}

static void cmd_quit(const call_t *c) {
  c->act->session = URT_DASHBOARD_SESSION_QUIT;
  put(c->w, "Disconnected");
}

static void cmd_shutdown(const call_t *c) {
  stop_if_active(c);
  add_ctrl(c->act, URT_CTRL_POWER_OFF);
  c->act->session = URT_DASHBOARD_SESSION_SHUTDOWN;
  put(c->w, "Shutting down");
}

static void cmd_running(const call_t *c) {
  put(c->w, program_playing(c->robot->program_state) ? "Program running: true"
                                                       : "Program running: false");
}

static void cmd_robotmode(const call_t *c) {
  put(c->w, "Robotmode: ");
  put(c->w, robot_mode_name(c->robot->robot_mode));
}

static void cmd_get_loaded_program(const call_t *c) {
  if (!c->st->program_loaded) {
    put(c->w, "No program loaded");
    return;
  }
  put(c->w, "Loaded program: ");
  put(c->w, c->st->program_display);
}

static void cmd_popup(const call_t *c) {
  c->st->popup_open = 1;
  put(c->w, "showing popup");
}

static void cmd_close_popup(const call_t *c) {
  c->st->popup_open = 0;
  put(c->w, "closing popup");
}

static void cmd_close_safety_popup(const call_t *c) {
  c->st->safety_popup_open = 0;
  put(c->w, "closing safety popup");
}

static void cmd_add_to_log(const call_t *c) {
  if (c->arg_len == 0) {
    put(c->w, "No log message to add");
    return;
  }
  c->st->log_count++;
  c->act->log_text = c->arg;
  c->act->log_len = c->arg_len;
  put(c->w, "Added log message");
}

static const char *program_name(const urt_dashboard_state_t *st) {
  return st->program_loaded ? base_name(st->program_display) : kUnnamed;
}

static void cmd_is_program_saved(const call_t *c) {
  // programs come from files and are never edited here, so a loaded program is saved
  put(c->w, c->st->program_loaded ? "true " : "false ");
  put(c->w, program_name(c->st));
}

static void cmd_program_state(const call_t *c) {
  int32_t s = c->robot->program_state;
  put(c->w, program_playing(s) ? "PLAYING "
            : (s == URT_PROGRAM_PAUSED || s == URT_PROGRAM_PAUSING) ? "PAUSED "
                                                                     : "STOPPED ");
  put(c->w, program_name(c->st));
}

static void put_version(writer_t *w, const urt_version_t *v) {
  put_int(w, v->major);
  put(w, ".");
  put_int(w, v->minor);
  put(w, ".");
  put_int(w, v->bugfix);
  put(w, ".");
  put_int(w, v->build);
}

static void cmd_polyscope_version(const call_t *c) {
  put(c->w, "URSoftware ");
  put_version(c->w, &c->ctx->version);
  put(c->w, " (");
  put_n(c->w, c->ctx->version.date, strnlen(c->ctx->version.date, sizeof c->ctx->version.date));
  put(c->w, ")");
}

static void cmd_version(const call_t *c) { put_version(c->w, &c->ctx->version); }

static void cmd_set_user_role(const call_t *c) {
  for (int i = 0; i < (int)(sizeof kRoleNames / sizeof kRoleNames[0]); i++) {
    if (equals_nocase(c->arg, c->arg_len, kRoleNames[i])) {
      c->st->user_role = i;
      put(c->w, "Setting user role: ");
      put_n(c->w, c->arg, c->arg_len);
      return;
    }
  }
  put(c->w, "Failed setting user role: ");  // unconfirmed wording
  put_n(c->w, c->arg, c->arg_len);
}

static void cmd_get_user_role(const call_t *c) {
  int r = c->st->user_role;
  put(c->w, (r >= 0 && r < 5) ? kRoleNames[r] : "NONE");
}

static void cmd_set_operational_mode(const call_t *c) {
  int mode = equals_nocase(c->arg, c->arg_len, "manual")      ? URT_DASHBOARD_OPMODE_MANUAL
             : equals_nocase(c->arg, c->arg_len, "automatic") ? URT_DASHBOARD_OPMODE_AUTOMATIC
                                                              : -1;
  if (mode < 0) {
    put(c->w, "Failed setting operational mode: '");  // unconfirmed wording
    put_n(c->w, c->arg, c->arg_len);
    put(c->w, "'");
    return;
  }
  c->st->operational_mode = mode;
  c->st->opmode_by_dashboard = 1;
  put(c->w, "Operational mode '");
  put_n(c->w, c->arg, c->arg_len);
  put(c->w, "' is set");
}

static const char *opmode_name(int m) {
  return m == URT_DASHBOARD_OPMODE_MANUAL      ? "MANUAL"
         : m == URT_DASHBOARD_OPMODE_AUTOMATIC ? "AUTOMATIC"
                                               : "NONE";
}

static void cmd_get_operational_mode(const call_t *c) {
  put(c->w, opmode_name(c->st->operational_mode));
}

static void cmd_clear_operational_mode(const call_t *c) {
  const char *m = c->st->operational_mode == URT_DASHBOARD_OPMODE_MANUAL      ? "manual"
                  : c->st->operational_mode == URT_DASHBOARD_OPMODE_AUTOMATIC ? "automatic"
                                                                              : "none";
  c->st->opmode_by_dashboard = 0;
  put(c->w, "No longer controlling the operational mode. Current operational mode: '");
  put(c->w, m);
  put(c->w, "'.");
  // Handed back to the pendant, which has no mode password set (urtwin models none, URSim's
  // default): `get operational mode` then answers NONE, as UR documents and URCL's
  // DashboardClientTestG5.operational_mode checks against URSim.
  c->st->operational_mode = URT_DASHBOARD_OPMODE_NONE;
}

/* a joint in its fault state keeps the arm off until `restart safety` (the controller refuses
 * POWER_ON and BRAKE_RELEASE then, core/controller.cpp); the refusal's words are urtwin's */
static int faulted(const call_t *c) { return c->robot->safety_mode == URT_SAFETY_MODE_FAULT; }

static void cmd_power_on(const call_t *c) {
  if (faulted(c)) {
    put(c->w, "Failed to execute: power on");
    return;
  }
  add_ctrl(c->act, URT_CTRL_POWER_ON);
  put(c->w, "Powering on");
}

static void cmd_power_off(const call_t *c) {
  stop_if_active(c);
  add_ctrl(c->act, URT_CTRL_POWER_OFF);
  put(c->w, "Powering off");
}

static void cmd_brake_release(const call_t *c) {
  if (faulted(c)) {
    put(c->w, "Failed to execute: brake release");
    return;
  }
  // from POWER_OFF the real controller powers on on the way (ur_robot_driver documents this)
  if (c->robot->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
    add_ctrl(c->act, URT_CTRL_POWER_ON);
  }
  add_ctrl(c->act, URT_CTRL_BRAKE_RELEASE);
  put(c->w, "Brake releasing");
}

static void cmd_safetymode(const call_t *c) {
  put(c->w, "Safetymode: ");
  put(c->w, safety_name(c->robot->safety_mode));
}

static void cmd_safetystatus(const call_t *c) {
  put(c->w, "Safetystatus: ");
  put(c->w, safety_name(c->robot->safety_status));
}

static void cmd_unlock_protective_stop(const call_t *c) {
  const urt_dashboard_robot_t *r = c->robot;
  if (r->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP && r->pstop_age >= 0.0 &&
      r->pstop_age < 5.0) {
    put(c->w, kUnprotectTooSoon);
    return;
  }
  // unlocking stops the program and closes the safety popup
  stop_if_active(c);
  c->st->safety_popup_open = 0;
  add_ctrl(c->act, URT_CTRL_UNLOCK_PSTOP);
  put(c->w, "Protective stop releasing");
}

static void cmd_restart_safety(const call_t *c) {
  stop_if_active(c);
  add_ctrl(c->act, URT_CTRL_POWER_OFF);
  add_ctrl(c->act, URT_CTRL_RESTART_SAFETY);
  put(c->w, "Restarting safety");
}

static void cmd_is_in_remote_control(const call_t *c) {
  put(c->w, c->st->remote_control && !c->st->remote_control_off ? "true" : "false");
}

static void cmd_get_serial_number(const call_t *c) {
  put_n(c->w, c->ctx->serial_number, strnlen(c->ctx->serial_number, sizeof c->ctx->serial_number));
}

static void cmd_get_robot_model(const call_t *c) {
  put_n(c->w, c->ctx->robot_model, strnlen(c->ctx->robot_model, sizeof c->ctx->robot_model));
}

// The owner writes the log (ctx->write_log); out is the id, the file, or why not.
static int write_log(const call_t *c, int what, char *out, size_t out_sz) {
  if (!c->ctx->write_log) {
    snprintf(out, out_sz, "this controller keeps no log folder");
    return -1;
  }
  out[0] = '\0';
  return c->ctx->write_log(c->ctx->write_log_user, what, c->arg, c->arg_len, out, out_sz);
}

static void cmd_generate_flight_report(const call_t *c) {
  // the success text as URCL matches it; the failure's wording is urtwin's (undocumented)
  char out[1024];
  if (write_log(c, URT_DASHBOARD_LOG_FLIGHT_REPORT, out, sizeof out) == 0) {
    c->st->report_count++;
    put(c->w, "Flight Report generated with id: ");
  } else {
    put(c->w, "Flight Report could not be generated: ");
  }
  put(c->w, out);
}

static void cmd_generate_support_file(const call_t *c) {
  // written into the log folder, whatever folder the client names (unconfirmed wording after
  // the colon): the reply says where
  char out[1024];
  put(c->w, write_log(c, URT_DASHBOARD_LOG_SUPPORT_FILE, out, sizeof out) == 0
                ? "Completed successfully: "
                : "Support file could not be generated: ");
  put(c->w, out);
}

static void cmd_save_log(const call_t *c) {
  char out[1024];
  if (write_log(c, URT_DASHBOARD_LOG_SAVE, out, sizeof out) == 0) {
    put(c->w, "Log saved to disk");
  } else {
    put(c->w, "Could not save log: ");
    put(c->w, out);
  }
}

//---- the command table ----

/* Versions as {major, minor, bugfix}; kNever: the command does not exist on that line. */
typedef struct ver3 {
  int major, minor, bugfix;
} ver3_t;

#define V(a, b) \
  { a, b, 0 }
#define NEVER \
  { 99, 0, 0 }

enum { NO_ARG = 0, ARG = 1 };
enum { ANY = 0, REMOTE = 1 };

typedef struct command {
  const char *name;           /* words separated by one space; matched case-insensitively    */
  int takes_arg;              /* ARG: the rest of the line is the argument                    */
  ver3_t min_cb3, min_e;      /* first version on CB3 / e-Series that has the command         */
  int remote_only;            /* REMOTE: refused on e-Series in local control                 */
  void (*fn)(const call_t *c);
} command_t;

/* First match wins, so "load installation" precedes "load". Minimum versions are URCL's
 * (assertHasCommand), which UR documents per command. */
static const command_t kCommands[] = {
    {"load installation", ARG, V(3, 2), V(5, 0), REMOTE, cmd_load_installation},
    {"load", ARG, V(1, 4), V(5, 0), REMOTE, cmd_load},
    {"play", NO_ARG, V(1, 4), V(5, 0), REMOTE, cmd_play},
    {"stop", NO_ARG, V(1, 4), V(5, 0), REMOTE, cmd_stop},
    {"pause", NO_ARG, V(1, 4), V(5, 0), REMOTE, cmd_pause},
    {"quit", NO_ARG, V(1, 4), V(5, 0), ANY, cmd_quit},
    {"shutdown", NO_ARG, V(1, 4), V(5, 0), ANY, cmd_shutdown},
    {"running", NO_ARG, V(1, 6), V(5, 0), ANY, cmd_running},
    {"robotmode", NO_ARG, V(1, 6), V(5, 0), ANY, cmd_robotmode},
    {"get loaded program", NO_ARG, V(1, 6), V(5, 0), ANY, cmd_get_loaded_program},
    {"popup", ARG, V(1, 6), V(5, 0), ANY, cmd_popup},
    {"close popup", NO_ARG, V(1, 6), V(5, 0), ANY, cmd_close_popup},
    {"addToLog", ARG, V(1, 8), V(5, 0), ANY, cmd_add_to_log},
    {"isProgramSaved", NO_ARG, V(1, 8), V(5, 0), ANY, cmd_is_program_saved},
    {"programState", NO_ARG, V(1, 8), V(5, 0), ANY, cmd_program_state},
    {"PolyscopeVersion", NO_ARG, V(1, 8), V(5, 0), ANY, cmd_polyscope_version},
    {"version", NO_ARG, NEVER, V(5, 0), ANY, cmd_version},
    {"setUserRole", ARG, V(3, 1), NEVER, ANY, cmd_set_user_role},
    {"getUserRole", NO_ARG, V(3, 1), NEVER, ANY, cmd_get_user_role},
    {"set operational mode", ARG, NEVER, V(5, 0), ANY, cmd_set_operational_mode},
    {"get operational mode", NO_ARG, NEVER, V(5, 6), ANY, cmd_get_operational_mode},
    {"clear operational mode", NO_ARG, NEVER, V(5, 0), ANY, cmd_clear_operational_mode},
    {"power on", NO_ARG, V(3, 0), V(5, 0), REMOTE, cmd_power_on},
    {"power off", NO_ARG, V(3, 0), V(5, 0), REMOTE, cmd_power_off},
    {"brake release", NO_ARG, V(3, 0), V(5, 0), REMOTE, cmd_brake_release},
    {"safetymode", NO_ARG, V(3, 0), V(5, 0), ANY, cmd_safetymode},
    {"safetystatus", NO_ARG, NEVER, V(5, 4), ANY, cmd_safetystatus},
    {"unlock protective stop", NO_ARG, V(3, 1), V(5, 0), REMOTE, cmd_unlock_protective_stop},
    {"close safety popup", NO_ARG, V(3, 1), V(5, 0), ANY, cmd_close_safety_popup},
    {"restart safety", NO_ARG, V(3, 7), V(5, 1), REMOTE, cmd_restart_safety},
    {"is in remote control", NO_ARG, NEVER, V(5, 6), ANY, cmd_is_in_remote_control},
    {"get serial number", NO_ARG, V(3, 12), V(5, 6), ANY, cmd_get_serial_number},
    {"get robot model", NO_ARG, V(3, 12), V(5, 6), ANY, cmd_get_robot_model},
    {"generate flight report", ARG, V(3, 13), V(5, 8), ANY, cmd_generate_flight_report},
    {"generate support file", ARG, V(3, 13), V(5, 8), ANY, cmd_generate_support_file},
    {"saveLog", NO_ARG, V(3, 13), V(5, 8), ANY, cmd_save_log},
};

static int is_eseries(const urt_version_t *v) { return v->major >= 5; }

static int version_at_least(const urt_version_t *v, ver3_t min) {
  if (v->major != min.major) {
    return v->major > min.major;
  }
  if (v->minor != min.minor) {
    return v->minor > min.minor;
  }
  return v->bugfix >= min.bugfix;
}

/* Match the command words against the start of s[0..n): each space in the name matches one or
 * more blanks. On a match *rest points just after the words. */
static int match_words(const char *name, const char *s, size_t n, size_t *rest) {
  size_t i = 0;
  for (const char *p = name; *p; p++) {
    if (*p == ' ') {
      if (i >= n || !is_space(s[i])) {
        return 0;
      }
      while (i < n && is_space(s[i])) {
        i++;
      }
    } else {
      if (i >= n || lower(s[i]) != lower(*p)) {
        return 0;
      }
      i++;
    }
  }
  *rest = i;
  return 1;
}

static const command_t *find_command(const char *s, size_t n, const char **arg, size_t *arg_len) {
  for (size_t k = 0; k < sizeof kCommands / sizeof kCommands[0]; k++) {
    const command_t *cmd = &kCommands[k];
    size_t i;
    if (!match_words(cmd->name, s, n, &i)) {
      continue;
    }
    if (i == n) {
      *arg = s + n;
      *arg_len = 0;
      return cmd;
    }
    if (!is_space(s[i]) || !cmd->takes_arg) {
      continue;  // "playx", or "play now" for a command without an argument
    }
    while (i < n && is_space(s[i])) {
      i++;
    }
    *arg = s + i;
    *arg_len = n - i;
    return cmd;
  }
  return NULL;
}

//---- public API ----

void urt_dashboard_robot_from_snapshot(const struct urt_snapshot *s, urt_dashboard_robot_t *r) {
  r->robot_mode = s->robot_mode;
  r->safety_mode = s->safety_mode;
  r->safety_status = s->safety_status;
  r->program_state = s->program_state;
  r->pstop_age = -1.0;
}

void urt_dashboard_state_init(urt_dashboard_state_t *st) {
  memset(st, 0, sizeof *st);
  st->remote_control = 1;
  st->operational_mode = URT_DASHBOARD_OPMODE_NONE;
  st->user_role = URT_DASHBOARD_ROLE_PROGRAMMER;
}

void urt_dashboard_framer_init(urt_dashboard_framer_t *f) {
  f->len = 0;
  f->overlong = 0;
  f->buf[0] = '\0';
}

int urt_dashboard_framer_next(urt_dashboard_framer_t *f, const char *data, size_t n,
                              size_t *consumed, urt_dashboard_line_t *line) {
  const char *nl = n ? memchr(data, '\n', n) : NULL;
  size_t take = nl ? (size_t)(nl - data) : n;

  // keep what fits; past URT_DASHBOARD_LINE_MAX the rest of the line is dropped
  size_t room = URT_DASHBOARD_LINE_MAX - f->len;
  size_t keep = take < room ? take : room;
  memcpy(f->buf + f->len, data, keep);
  f->len += keep;
  if (keep < take) {
    f->overlong = 1;
  }
  if (!nl) {
    *consumed = n;
    return 0;
  }

  // a complete line: drop one trailing "\r" and hand it out
  *consumed = take + 1;
  size_t len = f->len;
  if (len > 0 && f->buf[len - 1] == '\r' && !f->overlong) {
    len--;
  }
  f->buf[len] = '\0';
  line->text = f->buf;
  line->len = len;
  line->overlong = f->overlong;
  f->len = 0;
  f->overlong = 0;
  return 1;
}

size_t urt_dashboard_handle(const urt_dashboard_ctx_t *ctx, const urt_dashboard_robot_t *robot,
                            urt_dashboard_state_t *st, const urt_dashboard_line_t *line,
                            char *reply, size_t cap, urt_dashboard_action_t *action) {
  action->program = URT_DASHBOARD_PROG_NONE;
  action->n_ctrl = 0;
  action->session = URT_DASHBOARD_SESSION_KEEP;
  action->log_text = NULL;
  action->log_len = 0;
  action->path[0] = '\0';
  if (cap < 2) {
    if (cap == 1) {
      reply[0] = '\0';
    }
    return 0;
  }
  writer_t w = {reply, cap, 0};

  // trim blanks at both ends; commands are matched on what is left
  const char *s = line->text;
  size_t n = line->len;
  while (n > 0 && is_space(s[n - 1])) {
    n--;
  }
  size_t lead = 0;
  while (lead < n && is_space(s[lead])) {
    lead++;
  }

  const char *arg = NULL;
  size_t arg_len = 0;
  const command_t *cmd =
      line->overlong ? NULL : find_command(s + lead, n - lead, &arg, &arg_len);

  // a command the emulated version does not have is as unknown as a typo
  if (cmd && !version_at_least(&ctx->version, is_eseries(&ctx->version) ? cmd->min_e
                                                                          : cmd->min_cb3)) {
    cmd = NULL;
  }

  if (!cmd) {
    put(&w, "could not understand: '");
    put_n(&w, s, n);
    put(&w, "'");
  } else if (cmd->remote_only && is_eseries(&ctx->version) && !st->remote_control &&
             !st->remote_control_off) {
    put(&w, kLocalRefusal);
  } else {
    call_t c = {ctx, robot, st, s, n, arg, arg_len, &w, action};
    cmd->fn(&c);
  }

  w.p[w.len++] = '\n';
  w.p[w.len] = '\0';
  return w.len;
}
