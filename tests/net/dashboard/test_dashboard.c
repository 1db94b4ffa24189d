/* SPDX-License-Identifier: Apache-2.0
 * tests/net/dashboard/test_dashboard.c — the dashboard protocol without sockets: every reply
 * byte-exact, the state machine as URCL and ur_rtde drive it, version gates, local control,
 * the line framer and the program-directory jail of `load`. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_support.h"
#include "urt/controller.h"
#include "urt/net/dashboard.h"
#include "urt/snapshot.h"

//---- fixture: a programs directory, the dashboard and a toy controller ----

typedef struct fixture {
  char tmp[256];              /* mkdtemp root                      */
  char programs[300];         /* tmp/programs (programs_dir)       */
  urt_dashboard_ctx_t ctx;
  urt_dashboard_robot_t robot;
  urt_dashboard_state_t st;
  urt_dashboard_action_t act;
  char reply[URT_DASHBOARD_REPLY_MAX];
  size_t reply_len;
} fixture_t;

static void write_file(const char *dir, const char *name, const char *text) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

static void mkdir_in(const char *dir, const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  assert_int_equal(mkdir(path, 0755), 0);
}

static void symlink_in(const char *dir, const char *name, const char *target) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  assert_int_equal(symlink(target, path), 0);
}

static int setup(void **state) {
  fixture_t *fx = calloc(1, sizeof *fx);
  snprintf(fx->tmp, sizeof fx->tmp, "/tmp/urt_dash_XXXXXX");
  assert_non_null(mkdtemp(fx->tmp));
  snprintf(fx->programs, sizeof fx->programs, "%s/programs", fx->tmp);
  assert_int_equal(mkdir(fx->programs, 0755), 0);
  mkdir_in(fx->tmp, "outside");

  // programs/: good files, a sub-directory, bad kinds, and links in and out
  write_file(fx->programs, "wait_program.urp", "<urp/>\n");
  write_file(fx->programs, "notes.txt", "not a program\n");
  write_file(fx->programs, "default.installation", "inst\n");
  write_file(fx->programs, "prog.script", "def p():\nend\n");
  mkdir_in(fx->programs, "sub");
  write_file(fx->programs, "sub/inner.urp", "<urp/>\n");
  mkdir_in(fx->programs, "folder.urp");
  char outside[600];
  snprintf(outside, sizeof outside, "%s/outside", fx->tmp);
  write_file(outside, "secret.urp", "secret\n");
  symlink_in(fx->programs, "alias.urp", "wait_program.urp");
  char target[700];
  snprintf(target, sizeof target, "%s/secret.urp", outside);
  symlink_in(fx->programs, "escape.urp", target);
  symlink_in(fx->programs, "escape_dir", outside);
  symlink_in(fx->programs, "dangling.urp", "nowhere.urp");

  // UR5 on PolyScope 5.19, powered off, remote control
  fx->ctx.version = (urt_version_t){5, 19, 0, 1210631, "Oct 23 2024"};
  snprintf(fx->ctx.serial_number, sizeof fx->ctx.serial_number, "20235501783");
  snprintf(fx->ctx.robot_model, sizeof fx->ctx.robot_model, "UR5");
  fx->ctx.programs_dir = fx->programs;
  fx->ctx.programs_alias = "/programs";
  fx->robot = (urt_dashboard_robot_t){URT_ROBOT_MODE_POWER_OFF, URT_SAFETY_MODE_NORMAL,
                                      URT_SAFETY_MODE_NORMAL, URT_PROGRAM_STOPPED, -1.0};
  urt_dashboard_state_init(&fx->st);
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture_t *fx = *state;
  char cmd[400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", fx->tmp);
  assert_int_equal(system(cmd), 0);
  free(fx);
  return 0;
}

/* Send one line (without "\n"), check the reply framing, return the reply without "\n". */
static const char *say_n(fixture_t *fx, const char *text, size_t len) {
  urt_dashboard_line_t line = {text, len, 0};
  fx->reply_len = urt_dashboard_handle(&fx->ctx, &fx->robot, &fx->st, &line, fx->reply,
                                       sizeof fx->reply, &fx->act);
  assert_true(fx->reply_len >= 1);
  assert_int_equal(strlen(fx->reply), fx->reply_len);
  assert_int_equal(fx->reply[fx->reply_len - 1], '\n');
  assert_null(memchr(fx->reply, '\r', fx->reply_len));
  assert_ptr_equal(memchr(fx->reply, '\n', fx->reply_len), fx->reply + fx->reply_len - 1);
  fx->reply[fx->reply_len - 1] = '\0';
  return fx->reply;
}

static const char *say(fixture_t *fx, const char *text) { return say_n(fx, text, strlen(text)); }

/* What the controller and the program runner do with an action, instantly. */
static void apply(fixture_t *fx) {
  urt_dashboard_robot_t *r = &fx->robot;
  switch (fx->act.program) {
    case URT_DASHBOARD_PROG_LOAD: r->program_state = URT_PROGRAM_STOPPED; break;
    case URT_DASHBOARD_PROG_PLAY: r->program_state = URT_PROGRAM_PLAYING; break;
    case URT_DASHBOARD_PROG_PAUSE: r->program_state = URT_PROGRAM_PAUSED; break;
    case URT_DASHBOARD_PROG_STOP: r->program_state = URT_PROGRAM_STOPPED; break;
    default: break;
  }
  for (int i = 0; i < fx->act.n_ctrl; i++) {
    switch (fx->act.ctrl[i]) {
      case URT_CTRL_POWER_ON:
        if (r->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
          r->robot_mode = URT_ROBOT_MODE_IDLE;
        }
        break;
      case URT_CTRL_BRAKE_RELEASE:
        if (r->robot_mode == URT_ROBOT_MODE_IDLE) {
          r->robot_mode = URT_ROBOT_MODE_RUNNING;
        }
        break;
      case URT_CTRL_POWER_OFF: r->robot_mode = URT_ROBOT_MODE_POWER_OFF; break;
      case URT_CTRL_UNLOCK_PSTOP:
        r->safety_mode = r->safety_status = URT_SAFETY_MODE_NORMAL;
        break;
      default: fail_msg("unexpected controller command %d", fx->act.ctrl[i]);
    }
  }
}

static void no_action(const fixture_t *fx) {
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_NONE);
  assert_int_equal(fx->act.n_ctrl, 0);
  assert_int_equal(fx->act.session, URT_DASHBOARD_SESSION_KEEP);
}

static void running_with_program(fixture_t *fx) {
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  assert_string_equal(say(fx, "load wait_program.urp"), "Loading program: /programs/wait_program.urp");
  apply(fx);
}

//---- tests ----

static void test_dashboard__greeting_is_urs_line(void **state) {
  (void)state;
  assert_string_equal(URT_DASHBOARD_GREETING, "Connected: Universal Robots Dashboard Server\n");
}

static void test_dashboard__session_of_protocols_3_4_runs_byte_exact(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "PolyscopeVersion"), "URSoftware 5.19.0.1210631 (Oct 23 2024)");
  assert_string_equal(say(fx, "is in remote control"), "true");
  assert_string_equal(say(fx, "get serial number"), "20235501783");
  assert_string_equal(say(fx, "robotmode"), "Robotmode: POWER_OFF");
  assert_string_equal(say(fx, "power on"), "Powering on");
  assert_int_equal(fx->act.n_ctrl, 1);
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_ON);
  apply(fx);
  assert_string_equal(say(fx, "robotmode"), "Robotmode: IDLE");
  assert_string_equal(say(fx, "brake release"), "Brake releasing");
  assert_int_equal(fx->act.n_ctrl, 1);
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_BRAKE_RELEASE);
  apply(fx);
  assert_string_equal(say(fx, "robotmode"), "Robotmode: RUNNING");
  assert_string_equal(say(fx, "safetystatus"), "Safetystatus: NORMAL");
  assert_string_equal(say(fx, "load /programs/wait_program.urp"),
                      "Loading program: /programs/wait_program.urp");
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_LOAD);
  char real[4096];
  assert_non_null(realpath(fx->programs, real));
  strcat(real, "/wait_program.urp");
  assert_string_equal(fx->act.path, real);
  apply(fx);
  assert_string_equal(say(fx, "programState"), "STOPPED wait_program.urp");
  assert_string_equal(say(fx, "play"), "Starting program");
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_PLAY);
  apply(fx);
  assert_string_equal(say(fx, "running"), "Program running: true");
  assert_string_equal(say(fx, "programState"), "PLAYING wait_program.urp");
  assert_string_equal(say(fx, "stop"), "Stopped");
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_STOP);
  apply(fx);
  assert_string_equal(say(fx, "running"), "Program running: false");
  assert_string_equal(say(fx, "programState"), "STOPPED wait_program.urp");
  assert_string_equal(say(fx, "quit"), "Disconnected");
  assert_int_equal(fx->act.session, URT_DASHBOARD_SESSION_QUIT);
}

static void test_dashboard__urcl_run_program_sequence(void **state) {
  // URCL's run_program test: load, power off, power on, brake release, play, pause, play, stop
  fixture_t *fx = *state;
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  assert_string_equal(say(fx, "load wait_program.urp"), "Loading program: /programs/wait_program.urp");
  apply(fx);
  assert_string_equal(say(fx, "power off"), "Powering off");
  apply(fx);
  assert_string_equal(say(fx, "robotmode"), "Robotmode: POWER_OFF");
  assert_string_equal(say(fx, "play"), "Failed to execute: play");
  no_action(fx);
  assert_string_equal(say(fx, "power on"), "Powering on");
  apply(fx);
  assert_string_equal(say(fx, "play"), "Failed to execute: play");  // IDLE: brakes still on
  assert_string_equal(say(fx, "brake release"), "Brake releasing");
  apply(fx);
  assert_string_equal(say(fx, "play"), "Starting program");
  apply(fx);
  assert_string_equal(say(fx, "pause"), "Pausing program");
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_PAUSE);
  apply(fx);
  assert_string_equal(say(fx, "programState"), "PAUSED wait_program.urp");
  assert_string_equal(say(fx, "running"), "Program running: false");
  assert_string_equal(say(fx, "play"), "Starting program");  // resumes
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_PLAY);
  apply(fx);
  assert_string_equal(say(fx, "running"), "Program running: true");
  assert_string_equal(say(fx, "power off"), "Powering off");  // stops the program too
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_STOP);
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_OFF);
  apply(fx);
  assert_string_equal(say(fx, "programState"), "STOPPED wait_program.urp");
}

static void test_dashboard__brake_release_from_power_off_powers_on_first(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "brake release"), "Brake releasing");
  assert_int_equal(fx->act.n_ctrl, 2);
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_ON);
  assert_int_equal(fx->act.ctrl[1], URT_CTRL_BRAKE_RELEASE);
  apply(fx);
  assert_string_equal(say(fx, "robotmode"), "Robotmode: RUNNING");
}

static void test_dashboard__play_fails_without_program_or_in_protective_stop(void **state) {
  fixture_t *fx = *state;
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  assert_string_equal(say(fx, "play"), "Failed to execute: play");
  no_action(fx);
  running_with_program(fx);
  fx->robot.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  assert_string_equal(say(fx, "play"), "Failed to execute: play");
  no_action(fx);
  fx->robot.safety_mode = URT_SAFETY_MODE_REDUCED;
  assert_string_equal(say(fx, "play"), "Starting program");
}

/* a joint fault (safety mode FAULT) keeps the arm off: power on and brake release are
 * refused until `restart safety`, which powers off and clears the fault */
static void test_dashboard__a_joint_fault_refuses_power_on_until_restart_safety(void **state) {
  fixture_t *fx = *state;
  fx->robot.robot_mode = URT_ROBOT_MODE_POWER_OFF;
  fx->robot.safety_mode = fx->robot.safety_status = URT_SAFETY_MODE_FAULT;
  assert_string_equal(say(fx, "safetymode"), "Safetymode: FAULT");
  assert_string_equal(say(fx, "power on"), "Failed to execute: power on");
  no_action(fx);
  assert_string_equal(say(fx, "brake release"), "Failed to execute: brake release");
  no_action(fx);
  assert_string_equal(say(fx, "restart safety"), "Restarting safety");
  assert_int_equal(fx->act.n_ctrl, 2);
  assert_int_equal(fx->act.ctrl[1], URT_CTRL_RESTART_SAFETY);
  fx->robot.safety_mode = fx->robot.safety_status = URT_SAFETY_MODE_NORMAL;
  assert_string_equal(say(fx, "power on"), "Powering on");
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_ON);
}

static void test_dashboard__pause_and_stop_when_nothing_runs(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "pause"), "Failed to execute: pause");
  no_action(fx);
  assert_string_equal(say(fx, "stop"), "Stopped");  // ur_rtde stops defensively
  no_action(fx);
  fx->robot.robot_mode = URT_ROBOT_MODE_BOOTING;
  assert_string_equal(say(fx, "stop"), "Failed to execute: stop");
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  fx->robot.program_state = URT_PROGRAM_PLAYING;  // a script sent on 30003
  assert_string_equal(say(fx, "programState"), "PLAYING <unnamed>");
  assert_string_equal(say(fx, "stop"), "Stopped");
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_STOP);
  apply(fx);
  assert_string_equal(say(fx, "programState"), "STOPPED <unnamed>");
}

static void test_dashboard__queries_reply_byte_exact(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "get loaded program"), "No program loaded");
  assert_string_equal(say(fx, "isProgramSaved"), "false <unnamed>");
  assert_string_equal(say(fx, "programState"), "STOPPED <unnamed>");
  assert_string_equal(say(fx, "running"), "Program running: false");
  assert_string_equal(say(fx, "safetymode"), "Safetymode: NORMAL");
  assert_string_equal(say(fx, "version"), "5.19.0.1210631");
  assert_string_equal(say(fx, "get robot model"), "UR5");
  assert_string_equal(say(fx, "get operational mode"), "NONE");
  running_with_program(fx);
  assert_string_equal(say(fx, "get loaded program"), "Loaded program: /programs/wait_program.urp");
  assert_string_equal(say(fx, "isProgramSaved"), "true wait_program.urp");

  // every robot mode and a few safety modes by name
  static const char *const modes[] = {"NO_CONTROLLER", "DISCONNECTED", "CONFIRM_SAFETY",
                                      "BOOTING",       "POWER_OFF",    "POWER_ON",
                                      "IDLE",          "BACKDRIVE",    "RUNNING"};
  char want[64];
  for (int m = -1; m <= 7; m++) {
    fx->robot.robot_mode = m;
    snprintf(want, sizeof want, "Robotmode: %s", modes[m + 1]);
    assert_string_equal(say(fx, "robotmode"), want);
  }
  fx->robot.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  assert_string_equal(say(fx, "safetymode"), "Safetymode: PROTECTIVE_STOP");
  fx->robot.safety_status = 7;
  assert_string_equal(say(fx, "safetystatus"), "Safetystatus: ROBOT_EMERGENCY_STOP");
  fx->robot.safety_status = 13;
  assert_string_equal(say(fx, "safetystatus"), "Safetystatus: SYSTEM_THREE_POSITION_ENABLING_STOP");
  fx->robot.safety_mode = 21;
  assert_string_equal(say(fx, "safetymode"), "Safetymode: UNDEFINED_SAFETY_MODE");
}

// An owner's write_log: records the request, answers as the emulator's would
static int g_log_what, g_log_fail;
static char g_log_arg[64];
static int fake_write_log(void *user, int what, const char *arg, size_t arg_len, char *out,
                          size_t out_sz) {
  (void)user;
  g_log_what = what;
  snprintf(g_log_arg, sizeof g_log_arg, "%.*s", (int)arg_len, arg);
  if (g_log_fail) {
    snprintf(out, out_sz, "disk full");
    return -1;
  }
  snprintf(out, out_sz, "%s", what == URT_DASHBOARD_LOG_FLIGHT_REPORT ? "7"
                              : what == URT_DASHBOARD_LOG_SUPPORT_FILE ? "/log/ur_support_file_1.zip"
                                                                       : "/log/log_history.txt");
  return 0;
}

static void test_dashboard__commands_with_fixed_replies(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "popup Hello world"), "showing popup");
  assert_true(fx->st.popup_open);
  assert_string_equal(say(fx, "close popup"), "closing popup");
  assert_false(fx->st.popup_open);
  assert_string_equal(say(fx, "close safety popup"), "closing safety popup");
  assert_string_equal(say(fx, "addToLog Testing Log:"), "Added log message");
  assert_int_equal(fx->act.log_len, strlen("Testing Log:"));
  assert_memory_equal(fx->act.log_text, "Testing Log:", fx->act.log_len);
  assert_string_equal(say(fx, "addToLog"), "No log message to add");
  // without an owner that writes the log, the three log commands are refused, not faked
  assert_string_equal(say(fx, "saveLog"), "Could not save log: this controller keeps no log folder");
  assert_string_equal(say(fx, "generate flight report controller"),
                      "Flight Report could not be generated: this controller keeps no log folder");
  assert_string_equal(say(fx, "generate support file /tmp"),
                      "Support file could not be generated: this controller keeps no log folder");
  assert_int_equal(fx->st.report_count, 0);
  // with one, the reply carries what it wrote (id, file) or why it could not
  fx->ctx.write_log = fake_write_log;
  g_log_fail = 0;
  assert_string_equal(say(fx, "saveLog"), "Log saved to disk");
  assert_int_equal(g_log_what, URT_DASHBOARD_LOG_SAVE);
  assert_string_equal(say(fx, "generate flight report controller"),
                      "Flight Report generated with id: 7");
  assert_int_equal(fx->st.report_count, 1);
  assert_string_equal(say(fx, "generate support file /tmp"),
                      "Completed successfully: /log/ur_support_file_1.zip");
  assert_string_equal(g_log_arg, "/tmp");
  g_log_fail = 1;
  assert_string_equal(say(fx, "saveLog"), "Could not save log: disk full");
  fx->ctx.write_log = NULL;
  assert_string_equal(say(fx, "set operational mode automatic"),
                      "Operational mode 'automatic' is set");
  assert_string_equal(say(fx, "get operational mode"), "AUTOMATIC");
  assert_string_equal(say(fx, "set operational mode MANUAL"), "Operational mode 'MANUAL' is set");
  assert_string_equal(say(fx, "get operational mode"), "MANUAL");
  assert_string_equal(say(fx, "set operational mode sideways"),
                      "Failed setting operational mode: 'sideways'");
  assert_string_equal(say(fx, "clear operational mode"),
                      "No longer controlling the operational mode. Current operational mode: 'manual'.");
  assert_false(fx->st.opmode_by_dashboard);
  assert_string_equal(say(fx, "get operational mode"), "NONE");  /* no mode password */
  assert_string_equal(say(fx, "restart safety"), "Restarting safety");
  assert_int_equal(fx->act.n_ctrl, 2);
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_OFF);
  assert_int_equal(fx->act.ctrl[1], URT_CTRL_RESTART_SAFETY);
  assert_string_equal(say(fx, "shutdown"), "Shutting down");
  assert_int_equal(fx->act.session, URT_DASHBOARD_SESSION_SHUTDOWN);
  assert_string_equal(say(fx, "load installation default.installation"),
                      "Loading installation: default.installation");
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_POWER_OFF);
  assert_string_equal(fx->st.installation, "/programs/default.installation");
  assert_string_equal(say(fx, "load installation missing.installation"),
                      "File not found: missing.installation");
  assert_string_equal(say(fx, "load installation notes.txt"),
                      "Failed to load installation: notes.txt");
}

static void test_dashboard__unlock_protective_stop_waits_5_s(void **state) {
  fixture_t *fx = *state;
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  fx->robot.safety_mode = fx->robot.safety_status = URT_SAFETY_MODE_PROTECTIVE_STOP;
  fx->robot.pstop_age = 1.0;
  assert_string_equal(say(fx, "unlock protective stop"),
                      "Cannot unlock protective stop until 5s after occurrence. Always inspect "
                      "cause of protective stop before unlocking");
  no_action(fx);
  fx->robot.pstop_age = 5.0;
  assert_string_equal(say(fx, "unlock protective stop"), "Protective stop releasing");
  assert_int_equal(fx->act.ctrl[0], URT_CTRL_UNLOCK_PSTOP);
  apply(fx);
  assert_string_equal(say(fx, "safetymode"), "Safetymode: NORMAL");
  assert_string_equal(say(fx, "robotmode"), "Robotmode: RUNNING");
}

static void test_dashboard__unknown_commands_echo_the_line(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "fly"), "could not understand: 'fly'");
  assert_string_equal(say(fx, ""), "could not understand: ''");
  assert_string_equal(say(fx, "playx"), "could not understand: 'playx'");
  assert_string_equal(say(fx, "play now"), "could not understand: 'play now'");
  assert_string_equal(say(fx, "poweron"), "could not understand: 'poweron'");
  assert_string_equal(say(fx, "is program saved"), "could not understand: 'is program saved'");
  no_action(fx);
}

static void test_dashboard__commands_are_case_insensitive(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "polyscopeVersion"), "URSoftware 5.19.0.1210631 (Oct 23 2024)");
  assert_string_equal(say(fx, "POLYSCOPEVERSION"), "URSoftware 5.19.0.1210631 (Oct 23 2024)");
  assert_string_equal(say(fx, "RobotMode"), "Robotmode: POWER_OFF");
  assert_string_equal(say(fx, "Power  ON"), "Powering on");
  assert_string_equal(say(fx, "  get   SERIAL number \t"), "20235501783");
  assert_string_equal(say(fx, "ISPROGRAMSAVED"), "false <unnamed>");
  // arguments keep their case: file names are case-sensitive
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  assert_string_equal(say(fx, "LOAD Wait_Program.urp"), "File not found: Wait_Program.urp");
}

static void test_dashboard__load_resolves_inside_the_programs_directory(void **state) {
  fixture_t *fx = *state;
  assert_string_equal(say(fx, "load sub/inner.urp"), "Loading program: /programs/sub/inner.urp");
  assert_string_equal(say(fx, "programState"), "STOPPED inner.urp");
  assert_string_equal(say(fx, "load ./sub/../wait_program.urp"),
                      "Loading program: /programs/./sub/../wait_program.urp");
  assert_string_equal(say(fx, "load alias.urp"), "Loading program: /programs/alias.urp");
  assert_non_null(strstr(fx->act.path, "/wait_program.urp"));  // link inside: allowed
  char abs[700];
  snprintf(abs, sizeof abs, "load %s/wait_program.urp", fx->programs);
  char want[700];
  snprintf(want, sizeof want, "Loading program: %s/wait_program.urp", fx->programs);
  assert_string_equal(say(fx, abs), want);
  assert_string_equal(say(fx, "load prog.script"), "Error while loading program: prog.script");
  fx->ctx.program_exts = ".urp,.script";
  assert_string_equal(say(fx, "load prog.script"), "Loading program: /programs/prog.script");
}

// The owner's prepare hook (the emulator compiles a .urp there): it sees the resolved host
// path, and a refusal is UR's load error plus the reason, the loaded program unchanged.
static char g_prepared[1024];
static int prepare_refusing_bad(void *user, const char *host_path, char *why, size_t why_sz) {
  (void)user;
  snprintf(g_prepared, sizeof g_prepared, "%s", host_path);
  if (strstr(host_path, "/sub/")) {
    snprintf(why, why_sz, "unsupported program node 'Timer'");
    return -1;
  }
  return 0;
}

static void test_dashboard__load_refused_by_prepare_keeps_the_loaded_program(void **state) {
  fixture_t *fx = *state;
  fx->ctx.prepare_program = prepare_refusing_bad;
  assert_string_equal(say(fx, "load wait_program.urp"),
                      "Loading program: /programs/wait_program.urp");
  assert_non_null(strstr(g_prepared, "/programs/wait_program.urp"));
  assert_string_equal(say(fx, "load sub/inner.urp"),
                      "Error while loading program: sub/inner.urp: unsupported program node "
                      "'Timer'");
  assert_non_null(strstr(g_prepared, "/programs/sub/inner.urp"));
  assert_int_equal(fx->act.program, URT_DASHBOARD_PROG_NONE);  // nothing stops, nothing loads
  assert_string_equal(say(fx, "get loaded program"), "Loaded program: /programs/wait_program.urp");
  // a file that is not there never reaches the hook
  g_prepared[0] = '\0';
  assert_string_equal(say(fx, "load missing.urp"), "File not found: missing.urp");
  assert_string_equal(g_prepared, "");
}

static void test_dashboard__load_refuses_escapes_and_bad_files(void **state) {
  fixture_t *fx = *state;
  fx->robot.robot_mode = URT_ROBOT_MODE_RUNNING;
  assert_string_equal(say(fx, "load missing.urp"), "File not found: missing.urp");
  assert_string_equal(say(fx, "load ../etc/passwd"), "File not found: ../etc/passwd");
  assert_string_equal(say(fx, "load ../../../../../../etc/passwd"),
                      "File not found: ../../../../../../etc/passwd");
  assert_string_equal(say(fx, "load ../outside/secret.urp"), "File not found: ../outside/secret.urp");
  assert_string_equal(say(fx, "load /etc/passwd"), "File not found: /etc/passwd");
  assert_string_equal(say(fx, "load /programs/../../etc/passwd"),
                      "File not found: /programs/../../etc/passwd");
  assert_string_equal(say(fx, "load escape.urp"), "File not found: escape.urp");
  assert_string_equal(say(fx, "load escape_dir/secret.urp"), "File not found: escape_dir/secret.urp");
  assert_string_equal(say(fx, "load dangling.urp"), "File not found: dangling.urp");
  char abs[700];
  snprintf(abs, sizeof abs, "load %s/outside/secret.urp", fx->tmp);
  char want[700];
  snprintf(want, sizeof want, "File not found: %s/outside/secret.urp", fx->tmp);
  assert_string_equal(say(fx, abs), want);
  assert_string_equal(say(fx, "load"), "File not found: ");
  assert_string_equal(say(fx, "load notes.txt"), "Error while loading program: notes.txt");
  assert_string_equal(say(fx, "load folder.urp"), "Error while loading program: folder.urp");
  assert_string_equal(say(fx, "load sub"), "Error while loading program: sub");
  assert_string_equal(say_n(fx, "load wait\0program.urp", 21), "File not found: wait?program.urp");
  // nothing got loaded by any of these
  assert_false(fx->st.program_loaded);
  no_action(fx);
  fx->ctx.programs_dir = NULL;
  assert_string_equal(say(fx, "load wait_program.urp"), "File not found: wait_program.urp");
}

static void test_dashboard__local_control_refuses_state_changes(void **state) {
  fixture_t *fx = *state;
  running_with_program(fx);
  fx->st.remote_control = 0;
  static const char *const refused[] = {
      "load wait_program.urp", "load installation default.installation",
      "play", "stop", "pause", "power on", "power off", "brake release",
      "unlock protective stop", "restart safety"};
  for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++) {
    assert_string_equal(say(fx, refused[i]),
                        "Command is not allowed due to safety reasons, please switch robot to "
                        "Remote Control mode and reconnect to port 29999");
    no_action(fx);
  }
  // queries still work
  assert_string_equal(say(fx, "is in remote control"), "false");
  assert_string_equal(say(fx, "robotmode"), "Robotmode: RUNNING");
  assert_string_equal(say(fx, "programState"), "STOPPED wait_program.urp");
  assert_string_equal(say(fx, "popup hi"), "showing popup");
}

// Remote control disabled in Settings (URSim's default, URCL's CI): not "in remote control",
// yet nothing is refused.
static void test_dashboard__remote_control_off_refuses_nothing(void **state) {
  fixture_t *fx = *state;
  running_with_program(fx);
  fx->st.remote_control_off = 1;
  assert_string_equal(say(fx, "is in remote control"), "false");
  assert_string_equal(say(fx, "play"), "Starting program");
  assert_string_equal(say(fx, "stop"), "Stopped");
  assert_string_equal(say(fx, "power off"), "Powering off");
}

static void test_dashboard__version_gates_follow_the_emulated_controller(void **state) {
  fixture_t *fx = *state;

  // e-Series 5.3: no safetystatus (5.4), no serial/model/remote/opmode query (5.6), no reports (5.8)
  fx->ctx.version = (urt_version_t){5, 3, 1, 1000, "Jan 1 2019"};
  assert_string_equal(say(fx, "safetystatus"), "could not understand: 'safetystatus'");
  assert_string_equal(say(fx, "get serial number"), "could not understand: 'get serial number'");
  assert_string_equal(say(fx, "is in remote control"), "could not understand: 'is in remote control'");
  assert_string_equal(say(fx, "get operational mode"), "could not understand: 'get operational mode'");
  assert_string_equal(say(fx, "saveLog"), "could not understand: 'saveLog'");
  assert_string_equal(say(fx, "setUserRole operator"), "could not understand: 'setUserRole operator'");
  assert_string_equal(say(fx, "restart safety"), "Restarting safety");
  fx->ctx.version.minor = 0;
  assert_string_equal(say(fx, "restart safety"), "could not understand: 'restart safety'");

  // CB3 3.15: user roles, no e-Series-only commands, no local control
  fx->ctx.version = (urt_version_t){3, 15, 8, 106339, "Sep 14 2023"};
  fx->st.remote_control = 0;
  assert_string_equal(say(fx, "PolyscopeVersion"), "URSoftware 3.15.8.106339 (Sep 14 2023)");
  assert_string_equal(say(fx, "getUserRole"), "PROGRAMMER");
  assert_string_equal(say(fx, "setUserRole restricted"), "Setting user role: restricted");
  assert_string_equal(say(fx, "getUserRole"), "RESTRICTED");
  assert_string_equal(say(fx, "setUserRole king"), "Failed setting user role: king");
  assert_string_equal(say(fx, "is in remote control"), "could not understand: 'is in remote control'");
  assert_string_equal(say(fx, "safetystatus"), "could not understand: 'safetystatus'");
  assert_string_equal(say(fx, "version"), "could not understand: 'version'");
  assert_string_equal(say(fx, "set operational mode manual"),
                      "could not understand: 'set operational mode manual'");
  assert_string_equal(say(fx, "get serial number"), "20235501783");
  assert_string_equal(say(fx, "power on"), "Powering on");  // CB3 has no local control
  fx->ctx.version.minor = 11;
  assert_string_equal(say(fx, "get robot model"), "could not understand: 'get robot model'");
}

//---- framer ----

typedef struct fed {
  int lines;
  char text[8][URT_DASHBOARD_LINE_MAX + 1];
  size_t len[8];
  int overlong[8];
} fed_t;

static void feed(urt_dashboard_framer_t *f, const char *data, size_t n, fed_t *out) {
  while (n > 0) {
    size_t used = 0;
    urt_dashboard_line_t line;
    int got = urt_dashboard_framer_next(f, data, n, &used, &line);
    assert_true(used >= 1 && used <= n);
    data += used;
    n -= used;
    if (got) {
      assert_true(out->lines < 8);
      memcpy(out->text[out->lines], line.text, line.len);
      out->len[out->lines] = line.len;
      out->overlong[out->lines] = line.overlong;
      out->lines++;
    }
  }
}

static void test_dashboard_framer__splits_lines_across_chunks(void **state) {
  (void)state;
  urt_dashboard_framer_t f;
  urt_dashboard_framer_init(&f);
  fed_t out = {0};
  feed(&f, "robot", 5, &out);
  assert_int_equal(out.lines, 0);
  feed(&f, "mode\npow", 8, &out);
  feed(&f, "er on\r\nplay\n\n", 13, &out);
  assert_int_equal(out.lines, 4);
  assert_int_equal(out.len[0], 9);
  assert_memory_equal(out.text[0], "robotmode", 9);
  assert_int_equal(out.len[1], 8);  // "\r\n" tolerated
  assert_memory_equal(out.text[1], "power on", 8);
  assert_memory_equal(out.text[2], "play", 4);
  assert_int_equal(out.len[3], 0);
  feed(&f, "tail", 4, &out);  // incomplete line stays pending
  assert_int_equal(out.lines, 4);
}

static void test_dashboard_framer__overlong_line_resyncs_at_newline(void **state) {
  fixture_t *fx = *state;
  urt_dashboard_framer_t f;
  urt_dashboard_framer_init(&f);
  size_t big = 3 * URT_DASHBOARD_LINE_MAX;
  char *data = malloc(big + 32);
  memset(data, 'a', big);
  memcpy(data, "load ", 5);
  memcpy(data + big, "\nrobotmode\n", 11);
  fed_t out = {0};
  feed(&f, data, 1000, &out);
  feed(&f, data + 1000, big + 11 - 1000, &out);
  assert_int_equal(out.lines, 2);
  assert_true(out.overlong[0]);
  assert_int_equal(out.len[0], URT_DASHBOARD_LINE_MAX);
  assert_false(out.overlong[1]);

  // the overlong line gets the unknown-command reply, cut to the prefix that was kept
  urt_dashboard_line_t line = {out.text[0], out.len[0], 1};
  size_t n = urt_dashboard_handle(&fx->ctx, &fx->robot, &fx->st, &line, fx->reply,
                                  sizeof fx->reply, &fx->act);
  assert_int_equal(n, strlen("could not understand: ''\n") + URT_DASHBOARD_LINE_MAX);
  assert_memory_equal(fx->reply, "could not understand: 'load aaa", 31);
  assert_memory_equal(fx->reply + n - 3, "a'\n", 3);
  no_action(fx);
  assert_string_equal(say_n(fx, out.text[1], out.len[1]), "Robotmode: POWER_OFF");
  free(data);
}

static void test_dashboard__binary_bytes_never_break_the_reply_line(void **state) {
  fixture_t *fx = *state;
  const char bin[] = {'x', '\0', '\r', (char)0xff, '\x01', 'y', '\r'};
  assert_string_equal(say_n(fx, bin, sizeof bin), "could not understand: 'x??\xff\x01y'");

  // small reply buffers still get one terminated line
  urt_dashboard_line_t line = {"PolyscopeVersion", 16, 0};
  char small[8];
  size_t n = urt_dashboard_handle(&fx->ctx, &fx->robot, &fx->st, &line, small, sizeof small,
                                  &fx->act);
  assert_int_equal(n, 7);
  assert_string_equal(small, "URSoft\n");
  assert_int_equal(urt_dashboard_handle(&fx->ctx, &fx->robot, &fx->st, &line, small, 1, &fx->act), 0);
}

static void test_dashboard__robot_from_snapshot_copies_modes(void **state) {
  (void)state;
  static urt_snapshot_t s;
  s.robot_mode = URT_ROBOT_MODE_IDLE;
  s.safety_mode = URT_SAFETY_MODE_REDUCED;
  s.safety_status = URT_SAFETY_MODE_REDUCED;
  s.program_state = URT_PROGRAM_PAUSED;
  urt_dashboard_robot_t r;
  urt_dashboard_robot_from_snapshot(&s, &r);
  assert_int_equal(r.robot_mode, URT_ROBOT_MODE_IDLE);
  assert_int_equal(r.safety_mode, URT_SAFETY_MODE_REDUCED);
  assert_int_equal(r.safety_status, URT_SAFETY_MODE_REDUCED);
  assert_int_equal(r.program_state, URT_PROGRAM_PAUSED);
  assert_true(r.pstop_age < 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_dashboard__greeting_is_urs_line),
      cmocka_unit_test_setup_teardown(test_dashboard__session_of_protocols_3_4_runs_byte_exact, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__urcl_run_program_sequence, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__brake_release_from_power_off_powers_on_first, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__play_fails_without_program_or_in_protective_stop, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__a_joint_fault_refuses_power_on_until_restart_safety, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__pause_and_stop_when_nothing_runs, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__queries_reply_byte_exact, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__commands_with_fixed_replies, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__unlock_protective_stop_waits_5_s, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__unknown_commands_echo_the_line, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__commands_are_case_insensitive, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__load_resolves_inside_the_programs_directory, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__load_refuses_escapes_and_bad_files, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__local_control_refuses_state_changes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__remote_control_off_refuses_nothing, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__version_gates_follow_the_emulated_controller, setup, teardown),
      cmocka_unit_test(test_dashboard_framer__splits_lines_across_chunks),
      cmocka_unit_test_setup_teardown(test_dashboard_framer__overlong_line_resyncs_at_newline, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__binary_bytes_never_break_the_reply_line, setup, teardown),
      cmocka_unit_test_setup_teardown(test_dashboard__load_refused_by_prepare_keeps_the_loaded_program, setup, teardown),
      cmocka_unit_test(test_dashboard__robot_from_snapshot_copies_modes),
  };
  return cmocka_run_group_tests_name("net/dashboard", tests, NULL, NULL);
}
