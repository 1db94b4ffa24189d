/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/dashboard.h — the dashboard server protocol (port 29999), without a socket
 * (protocols.md §3, §6).
 *
 *   bytes ──urt_dashboard_framer_next()──▶ one line ──urt_dashboard_handle()──▶ one reply line
 *                                                                              + an action
 *
 * The caller owns the socket, sends URT_DASHBOARD_GREETING on connect, feeds received bytes
 * through one framer per connection, and for every line calls urt_dashboard_handle() with the
 * robot state read from the latest snapshot. It sends the reply and then performs the action:
 * controller commands into the command ring, program control on the program runner, closing
 * the connection (quit) or stopping the emulator (shutdown).
 *
 * Every reply is exactly one line: it ends with "\n" and contains no other "\n" and no "\r".
 * Reply texts are UR's (PolyScope 5 / CB3 "G5" dialect); see the table in dashboard.c.
 */
#ifndef URT_NET_DASHBOARD_H
#define URT_NET_DASHBOARD_H

#include <stddef.h>
#include <stdint.h>

#include "urt/net/version.h"

#ifdef __cplusplus
extern "C" {
#endif

struct urt_snapshot;

/* The first line the server sends on every connection. */
#define URT_DASHBOARD_GREETING "Connected: Universal Robots Dashboard Server\n"

#define URT_DASHBOARD_LINE_MAX 4096   /* longest accepted request line, without "\n"  [bytes] */
#define URT_DASHBOARD_REPLY_MAX 4200  /* a reply buffer of this size never truncates  [bytes] */
#define URT_DASHBOARD_PATH_MAX 4096   /* longest program / installation path          [bytes] */

//---- configuration (constant while the emulator runs) ----

typedef struct urt_dashboard_ctx {
  urt_version_t version;      /* emulated controller version: PolyscopeVersion and command gates */
  char serial_number[32];     /* digits, e.g. "20235501783" (get serial number)             */
  char robot_model[16];       /* e.g. "UR5" (get robot model)                                */
  /* Directory holding programs and installations on the host. NULL: every load is refused
   * with "File not found". Nullable. */
  const char *programs_dir;
  /* The path clients see for programs_dir, e.g. "/programs" (real e-Series) or
   * "/ursim/programs" (URSim). Absolute names under it map into programs_dir, and replies
   * show it. NULL: clients see programs_dir itself. Nullable. */
  const char *programs_alias;
  /* Comma-separated file name endings `load` accepts, e.g. ".urp,.script". NULL: ".urp".
   * Nullable. */
  const char *program_exts;
  /* Called by `load` with the resolved host path of a program it is about to accept: the
   * owner reads and compiles it (a .urp into URScript) and keeps the result for `play`.
   * Returns 0 to accept; otherwise fills why (one line, e.g. "unsupported program node
   * 'Timer'") and `load` replies "Error while loading program: <name>: <why>", the loaded
   * program staying what it was. Runs on the thread that calls urt_dashboard_handle() and may
   * allocate. Nullable (every existing file is accepted). */
  int (*prepare_program)(void *user, const char *host_path, char *why, size_t why_sz);
  void *prepare_user;
  /* saveLog, generate flight report, generate support file DIR: the owner writes the
   * controller's log (what = URT_DASHBOARD_LOG_*; arg: the command's argument). Returns 0 with
   * out = the report id (flight report) or the file written (support file), or nonzero with
   * out = why (one line); the reply says which. NULL: every such command is refused as by a
   * controller that cannot write it. Runs on the thread that calls urt_dashboard_handle().
   * Nullable. */
  int (*write_log)(void *user, int what, const char *arg, size_t arg_len, char *out,
                   size_t out_sz);
  void *write_log_user;
} urt_dashboard_ctx_t;

enum { URT_DASHBOARD_LOG_SAVE = 1, URT_DASHBOARD_LOG_FLIGHT_REPORT, URT_DASHBOARD_LOG_SUPPORT_FILE };

//---- robot state (filled by the caller from the snapshot before each line) ----

typedef struct urt_dashboard_robot {
  int32_t robot_mode;         /* URT_ROBOT_MODE_*                                            */
  int32_t safety_mode;        /* URT_SAFETY_MODE_* (protocols.md §2.8.2)                      */
  int32_t safety_status;      /* safety status (§2.8.3)                                      */
  int32_t program_state;      /* URT_PROGRAM_* of the program runner                          */
  double pstop_age;           /* time since the protective stop began [s]; < 0: unknown       */
} urt_dashboard_robot_t;

/* Copy the modes from a snapshot; pstop_age becomes -1 (unknown). Context: any. */
void urt_dashboard_robot_from_snapshot(const struct urt_snapshot *s, urt_dashboard_robot_t *r);

//---- dashboard-owned state (one per emulator, shared by all connections) ----
/* Not locked: call urt_dashboard_handle() for every connection from one thread (the I/O
 * thread), as the real controller's single dashboard server does. */

enum {
  URT_DASHBOARD_OPMODE_NONE = 0,
  URT_DASHBOARD_OPMODE_MANUAL,
  URT_DASHBOARD_OPMODE_AUTOMATIC
};

enum {
  URT_DASHBOARD_ROLE_PROGRAMMER = 0,
  URT_DASHBOARD_ROLE_OPERATOR,
  URT_DASHBOARD_ROLE_NONE,
  URT_DASHBOARD_ROLE_LOCKED,
  URT_DASHBOARD_ROLE_RESTRICTED
};

typedef struct urt_dashboard_state {
  int remote_control;         /* e-Series: 1 remote control, 0 local (refuses state changes) */
  int remote_control_off;     /* e-Series: the remote-control feature is disabled in Settings
                                 (URSim's default): `is in remote control` answers false and
                                 nothing is refused                                          */
  int program_loaded;         /* a program was loaded                                         */
  char program_display[URT_DASHBOARD_PATH_MAX]; /* as clients see it, "/programs/x.urp"      */
  char program_path[URT_DASHBOARD_PATH_MAX];    /* resolved host path (realpath)             */
  char installation[URT_DASHBOARD_PATH_MAX];    /* as clients see it; "" default             */
  int operational_mode;       /* URT_DASHBOARD_OPMODE_*                                       */
  int opmode_by_dashboard;    /* set operational mode in force (clear operational mode ends it) */
  int user_role;              /* URT_DASHBOARD_ROLE_* (CB3)                                   */
  int popup_open, safety_popup_open;
  uint64_t log_count;         /* addToLog messages accepted                                  */
  uint64_t report_count;      /* flight reports "generated" (their ids)                       */
} urt_dashboard_state_t;

/* Initial state: remote control on, no program, operational mode NONE, role PROGRAMMER.
 * Context: any. */
void urt_dashboard_state_init(urt_dashboard_state_t *st);

//---- line framer (one per connection) ----

typedef struct urt_dashboard_framer {
  char buf[URT_DASHBOARD_LINE_MAX + 1];
  size_t len;                 /* bytes of the current line held in buf                      */
  int overlong;               /* the current line passed URT_DASHBOARD_LINE_MAX; discarding */
} urt_dashboard_framer_t;

/* One request line: text without "\n" and without a trailing "\r"; may hold any bytes,
 * including NUL. overlong: the line was longer than URT_DASHBOARD_LINE_MAX and text holds only
 * its first URT_DASHBOARD_LINE_MAX bytes (it gets the unknown-command reply). */
typedef struct urt_dashboard_line {
  const char *text;
  size_t len;
  int overlong;
} urt_dashboard_line_t;

void urt_dashboard_framer_init(urt_dashboard_framer_t *f);

/* Consume bytes from data[0..n) up to and including the first "\n". Returns 1 when that
 * completed a line (*line then points into the framer and stays valid until the next call),
 * 0 when all n bytes were consumed without completing one. *consumed receives the bytes used;
 * call again with the rest. Context: any; no allocation. */
int urt_dashboard_framer_next(urt_dashboard_framer_t *f, const char *data, size_t n,
                              size_t *consumed, urt_dashboard_line_t *line);

//---- command handler ----

/* What the program runner must do. */
typedef enum urt_dashboard_program_op {
  URT_DASHBOARD_PROG_NONE = 0,
  URT_DASHBOARD_PROG_LOAD,    /* load action.path (stopping any running program first)       */
  URT_DASHBOARD_PROG_PLAY,    /* start the loaded program, or resume it when paused          */
  URT_DASHBOARD_PROG_PAUSE,
  URT_DASHBOARD_PROG_STOP     /* stop whatever program runs (loaded or sent as script)       */
} urt_dashboard_program_op_t;

typedef enum urt_dashboard_session_op {
  URT_DASHBOARD_SESSION_KEEP = 0,
  URT_DASHBOARD_SESSION_QUIT,     /* close this connection after sending the reply           */
  URT_DASHBOARD_SESSION_SHUTDOWN  /* send the reply, then stop the emulator                   */
} urt_dashboard_session_op_t;

/* The action(s) that follow a reply, to be done in this order: program, controller
 * commands, session. */
typedef struct urt_dashboard_action {
  int program;                /* urt_dashboard_program_op_t                                  */
  int n_ctrl;                 /* number of controller commands in ctrl[]                      */
  int32_t ctrl[2];            /* urt_ctrl_cmd_kind_t: POWER_ON, POWER_OFF, BRAKE_RELEASE,
                               * UNLOCK_PSTOP, RESTART_SAFETY                            */
  int session;                /* urt_dashboard_session_op_t                                  */
  const char *log_text;       /* addToLog text (points into the request line), or NULL      */
  size_t log_len;
  char path[URT_DASHBOARD_PATH_MAX]; /* PROG_LOAD: resolved host path of the program         */
} urt_dashboard_action_t;

/* Answer one request line. Reads the configuration and the robot state, updates the
 * dashboard-owned state (loaded program, popups, operational mode, …) and writes exactly one
 * reply line into reply[0..cap) (NUL-terminated; variable parts are cut to fit, so with
 * cap >= URT_DASHBOARD_REPLY_MAX nothing is cut). *action tells the caller what to do next.
 * `load` and `load installation` resolve names with realpath() under ctx->programs_dir and
 * refuse anything outside it. Context: non-RT (load touches the file system); no allocation
 * here, though ctx->prepare_program may allocate.
 * Returns the reply length in bytes (without the NUL), or 0 if cap < 2. */
size_t urt_dashboard_handle(const urt_dashboard_ctx_t *ctx, const urt_dashboard_robot_t *robot,
                            urt_dashboard_state_t *st, const urt_dashboard_line_t *line,
                            char *reply, size_t cap, urt_dashboard_action_t *action);

#ifdef __cplusplus
}
#endif
#endif
