/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_rtde_control.c — ur_rtde's rtde_control program run natively:
 * recognition (offset quirk, pruned branches, injected path) on a small fixture of the
 * script's own header, tag and offset lines; the register protocol against a lock-step fake
 * client that behaves like RTDEControlInterface::sendCommand (wait ready → send → wait done →
 * clear), on a fake controller whose motions end after N ticks; and the runner's dispatch.
 * The full 1.6.5 scripts are checked by tests/python/test_rtde_control_script.py. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "fake_host.h"
#include "rtde_control.h"
#include "test_model.h"
#include "test_support.h"
#include "urt/controller.h"
#include "urt/core.h"

//---- the fixture: the recognisable lines of the script, in ur_rtde's injected form ----

/* header, offsets as RTDEControlInterface injects them (the value at the start of the next
 * line), a few process_cmd branches (one pruned to `dummy_op = 1` as version pruning leaves
 * it), the move-path hook, the tag line and the end */
static const char *script_with(int off_int, int off_float, const char *path, bool all) {
  static char buf[16384];
  char extra[6144] = "";
  if (all) {
    // a branch with a body for every other id of the table (as the 10.x script has)
    static const int ids[] = {2, 3, 4, 6, 7, 8, 9, 10, 12, 15, 17, 18, 19, 20, 21, 24, 25, 26, 27, 28, 29,
                              30, 34, 36, 37, 38, 39, 40, 41, 42, 44, 47, 51, 52, 53, 54, 58,
                              59, 60, 61, 62, 63, 64, 65, 68, 69, 71, 254};
    size_t n = 0;
    for (size_t k = 0; k < sizeof ids / sizeof ids[0]; k++) {
      n += (size_t)snprintf(extra + n, sizeof extra - n, "        elif cmd == %d:\n            x = %d\n",
                            ids[k], ids[k]);
    }
  }
  snprintf(buf, sizeof buf,
           "def rtde_control():\n"
           "# HEADER_BEGIN\n"
           "    global reg_offset_float = # float register offset\n"
           "%d    global reg_offset_int = # int register offset\n"
           "%d    global force_mode_type = 2\n"
           "    def exec_move_path():\n"
           "        textmsg(\"exec_move_path\")\n"
           "        # inject move path\n"
           "%s"
           "    end\n"
           "    def process_cmd(cmd):\n"
           "        if cmd == 1:\n"
           "            textmsg(\"movej\")\n"
           "        elif cmd == 11:\n"
           "            q = q_from_input_float_registers(0)\n"
           "        elif cmd == 16:\n"
           "            stopl(deceleration_rate)\n"
           "        elif cmd == 31:\n"
           "            protective_stop()\n"
           "        elif cmd == 33:\n"
           "            exec_stopl_stopj(cmd, \"stopl async=\")\n"
           "        elif cmd == 35:\n"
           "            rtde_set_watchdog(\"input_int_register_0\", f, \"stop\")\n"
           "        elif cmd == 43:\n"
           "            forward_kin = get_forward_kin()\n"
           "        elif cmd == 45:\n"
           "            exec_move_path()\n"
           "        elif cmd == 46:\n"
           "            q = get_inverse_kin(x)\n"
           "        elif cmd == 66:\n"
           "              # direct_torque\n"
           "              dummy_op = 1\n"
           "%s%s"
           "        elif cmd == 67:\n"
           "              mass_matrix = get_mass_matrix()\n"
           "        elif cmd == 70:\n"
           "              jacobian = get_jacobian()\n"
           "        elif cmd == 255:\n"
           "              textmsg(\"Received stop script!\")\n"
           "        end\n"
           "        if cmd != 255:\n"
           "              signal_done_with_cmd()\n"
           "        end\n"
           "    end\n"
           "# HEADER_END\n"
           "# NODE_CONTROL_LOOP_BEGINS\n"
           "        textmsg(\"RTDE Control Script Loaded (14.02.2024-12:23)\")\n"
           "# NODE_CONTROL_LOOP_ENDS\n"
           "end\n",
           off_float, off_int, path ? path : "",
           all ? "              direct_torque(torque, viscous_scale=v, coulomb_scale=c)\n" : "", extra);
  return buf;
}

static const char *script(int off_int, int off_float, const char *path) {
  return script_with(off_int, off_float, path, false);
}

static void test_rtde_control_recognise__reads_offsets_after_the_comment(void **state) {
  urt__rc_info rc;
  const char *s = script(24, 0, NULL);
  assert_true(urt__rc_recognise(s, strlen(s), &rc));
  assert_int_equal(rc.reg_offset_int, 24);
  assert_int_equal(rc.reg_offset_float, 0);
  assert_string_equal(rc.tag, "RTDE Control Script Loaded (14.02.2024-12:23)");
  assert_int_equal(rc.n_path, 0);
  urt__rc_info_free(&rc);

  // the plain form too
  const char *plain = "def rtde_control():\n  global reg_offset_float = 0\n  global reg_offset_int = 24\n"
                      "  textmsg(\"RTDE Control Script Loaded (x)\")\nend\n";
  assert_true(urt__rc_recognise(plain, strlen(plain), &rc));
  assert_int_equal(rc.reg_offset_int, 24);
  urt__rc_info_free(&rc);

  int oi = -1, of = -1;
  assert_true(urt_rtde_control_recognise(s, strlen(s), &oi, &of));
  assert_int_equal(oi, 24);
  assert_int_equal(of, 0);
}

static void test_rtde_control_recognise__knows_the_branches_and_pruned_bodies(void **state) {
  urt__rc_info rc;
  const char *s = script(0, 0, NULL);
  assert_true(urt__rc_recognise(s, strlen(s), &rc));
  assert_true(rc.has_cmd[1] && rc.has_body[1]);
  assert_true(rc.has_cmd[66] && !rc.has_body[66]);  // pruned: dummy_op = 1
  assert_true(rc.has_cmd[255] && rc.has_body[255]);
  assert_false(rc.has_cmd[55]);
  assert_int_equal(rc.cmd_line[1], 11);
  urt__rc_info_free(&rc);
}

static void test_rtde_control_recognise__refuses_other_programs(void **state) {
  urt__rc_info rc;
  const char *other = "def rtde_control():\n  global reg_offset_float = 0\n  global reg_offset_int = 0\nend\n";
  assert_false(urt__rc_recognise(other, strlen(other), &rc));  // no tag
  const char *custom = "def my_prog():\n  textmsg(\"RTDE Control Script Loaded (x)\")\nend\n";
  assert_false(urt__rc_recognise(custom, strlen(custom), &rc));
  // ScriptClient.getScript() before the offsets are injected: the robot could not compile it
  char uninjected[16384];
  snprintf(uninjected, sizeof uninjected, "%s", script(0, 0, NULL));
  char *a = strstr(uninjected, "offset\n0");
  memmove(a + 7, a + 8, strlen(a + 8) + 1);
  char *b = strstr(uninjected, "offset\n0");
  memmove(b + 7, b + 8, strlen(b + 8) + 1);
  assert_false(urt__rc_recognise(uninjected, strlen(uninjected), &rc));
  assert_false(urt_rtde_control_recognise(custom, strlen(custom), NULL, NULL));
}

static void test_rtde_control_recognise__reads_the_injected_path(void **state) {
  urt__rc_info rc;
  const char *s = script(0, 0,
                         "\tsignal_async_progress(0)\n"
                         "\tmovej([0.1,-1.5,1e-05,-1.57,0,0],a=1.4,v=1.05,r=0)\n"
                         "\tsignal_async_progress(1)\n"
                         "\tmovel(p[-0.143,-0.435,0.2,-0.001,3.12,0.04],a=0.5,v=0.25,r=0.02)\n");
  assert_true(urt__rc_recognise(s, strlen(s), &rc));
  assert_int_equal(rc.n_path, 2);
  assert_int_equal(rc.path_bad_line, 0);
  assert_int_equal(rc.path[0].kind, 'j');
  assert_false(rc.path[0].is_pose);
  assert_float_equal(rc.path[0].x[2], 1e-5, 0);
  assert_float_equal(rc.path[0].a, 1.4, 0);
  assert_int_equal(rc.path[1].kind, 'l');
  assert_true(rc.path[1].is_pose);
  assert_float_equal(rc.path[1].x[4], 3.12, 0);
  assert_float_equal(rc.path[1].v, 0.25, 0);
  assert_float_equal(rc.path[1].r, 0.02, 0);
  urt__rc_info_free(&rc);

  s = script(0, 0, "\tmovej(get_target_joint_positions())\n");
  assert_true(urt__rc_recognise(s, strlen(s), &rc));
  assert_int_equal(rc.path_bad_line, 9);
  urt__rc_info_free(&rc);
}

//---- a lock-step client and controller ----

#define MAXT 20000

enum { P_REGULAR = 0, P_CONT, P_SILENT, P_STOP };

typedef struct pkg {
  int mode;              /* P_*                                                    */
  int hold;              /* P_CONT: ticks to keep sending it                       */
  int i[8];              /* input_int_register 0..7 (+offset); i[0] is the command  */
  double d[24];          /* input_double_register 0..23 (+offset)                   */
} pkg;

static fake_host F;
static urt_script_host_t H;
static urt_model_t *M;
static urt_rtde_registers_t REG;
static pkg Q[32];
static int NQ, QI, PHASE, HOLD, OFF;
static uint64_t MAX_TICK;
static int TR_OUT0[MAXT], TR_OUT2[MAXT], NTR;
static int DONE_TICK[32], SENT_TICK[32];
static uint64_t FORCE_TICK;   /* from this tick on (0: never) the TCP force is FORCE */
static double FORCE[6];

static void put(const pkg *p) {
  for (int k = 0; k < 8; k++) {
    REG.in_int[k + OFF] = p->i[k];
    REG.in_int_writes[k + OFF]++;
  }
  for (int k = 0; k < 24 && k + OFF < URT_RTDE_NREG; k++) REG.in_double[k + OFF] = p->d[k];
}

/* RTDEControlInterface::sendCommand, one tick at a time */
static void client_step(uint64_t tick) {
  if (FORCE_TICK && tick >= FORCE_TICK) memcpy(F.s.tcp_force, FORCE, sizeof FORCE);
  int out0 = REG.out_int[0 + OFF];
  if (NTR < MAXT) {
    TR_OUT0[NTR] = out0;
    TR_OUT2[NTR] = REG.out_int[2 + OFF];
    NTR++;
  }
  if (QI >= NQ) return;
  pkg *p = &Q[QI];
  switch (PHASE) {
    case 0:  // busy-wait for ready, then send
      if (out0 != 1) return;
      put(p);
      SENT_TICK[QI] = (int)tick;
      if (p->mode == P_REGULAR) {
        PHASE = 1;
      } else if (p->mode == P_CONT) {
        PHASE = 2;
        HOLD = p->hold;
      } else {
        PHASE = 3;  // silent / stop: nothing more
      }
      return;
    case 1:  // wait for done, then clear
      if (out0 != 2) return;
      DONE_TICK[QI] = (int)tick;
      {
        pkg clear = {0};
        put(&clear);
      }
      QI++;
      PHASE = 0;
      return;
    case 2:  // streaming: the same package every tick
      put(p);
      if (--HOLD <= 0) {
        QI++;
        PHASE = 0;
      }
      return;
    default:
      return;
  }
}

static uint64_t ls_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  uint64_t t = fake_wait_tick(ctx, after, timeout_ms);
  client_step(t);
  return t;
}

static void ls_read(void *ctx, urt_rtde_registers_t *out) { *out = REG; }

static void ls_write(void *ctx, int kind, int index, double value) {
  if (kind == URT_SCRIPT_REG_INT) REG.out_int[index] = (int32_t)value;
  else if (kind == URT_SCRIPT_REG_DOUBLE) REG.out_double[index] = value;
  else REG.out_bit[index] = value != 0;
}

static const urt_model_t *ls_model(void *ctx) { return M; }

static int ls_ik(void *ctx, const double pose[6], const double qnear[6], double q[6]) {
  return urt_ctrl_inverse_kinematics(M, pose, qnear, q);
}

static int ls_fk(void *ctx, const double q[6], double pose[6]) {
  urt_ctrl_forward_kinematics_tcp(M, M->arm.tcp, q, pose);
  return 0;
}

static int ls_poll(void *ctx) { return F.s.tick > MAX_TICK; }

static int setup(void **state) {
  if (!M) M = urt_test_model(NULL);
  fake_init(&F, &H);
  H.wait_tick = ls_wait_tick;
  H.read_registers = ls_read;
  H.write_output_register = ls_write;
  H.model = ls_model;
  H.inverse_kinematics = ls_ik;
  H.forward_kinematics = ls_fk;
  memcpy(F.s.q, M->q0, sizeof F.s.q);
  F.motion_ticks = 10;
  memset(&REG, 0, sizeof REG);
  memset(Q, 0, sizeof Q);
  NQ = QI = PHASE = HOLD = OFF = NTR = 0;
  memset(DONE_TICK, 0, sizeof DONE_TICK);
  memset(SENT_TICK, 0, sizeof SENT_TICK);
  MAX_TICK = 5000;
  FORCE_TICK = 0;
  memset(FORCE, 0, sizeof FORCE);
  return 0;
}

static pkg *add(int mode, int cmd) {
  pkg *p = &Q[NQ++];
  p->mode = mode;
  p->i[0] = cmd;
  return p;
}

/* run the program over the queued client packages; returns urt__rc_run's result */
static int run(const char *text, us_err *err) {
  urt__rc_info rc;
  assert_true(urt__rc_recognise(text, strlen(text), &rc));
  uint64_t mid = 0;
  us_hooks h = {.host = &H, .motion_id = &mid, .step_budget = 1000, .wait_timeout_ms = 1,
                .poll = ls_poll};
  int r = urt__rc_run(&rc, &h, err);
  urt__rc_info_free(&rc);
  return r;
}

static bool has_text(const char *t) {
  for (int k = 0; k < F.n_msg; k++) {
    if (strstr(F.msg[k].text, t)) return true;
  }
  return false;
}

//---- the protocol ----

static void test_rtde_control_run__movej_sync_handshake(void **state) {
  pkg *p = add(P_REGULAR, 1);
  double q[6] = {0.1, -1.2, 1.3, -1.5, -1.6, 0.2};
  memcpy(p->d, q, sizeof q);
  p->d[6] = 1.05;  // v
  p->d[7] = 1.4;   // a
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);

  // ready before the command, DONE only once the motion (10 ticks) has finished
  assert_int_equal(TR_OUT0[0], 1);
  int k = fake_find_cmd(&F, URT_CTRL_MOVEJ, 0);
  assert_true(k >= 0);
  for (int j = 0; j < 6; j++) assert_float_equal(F.cmd[k].q[j], q[j], 0);
  assert_float_equal(F.cmd[k].v, 1.05, 0);
  assert_float_equal(F.cmd[k].a, 1.4, 0);
  assert_true(DONE_TICK[0] - SENT_TICK[0] >= 10);

  // the whole status sequence: 1 … 2 … 1 (after the clear) and no 2 after stopScript
  int seen = 0;
  for (int t = 0; t < NTR; t++) {
    if (seen == 0 && TR_OUT0[t] == 2) seen = 1;
    if (seen == 1 && TR_OUT0[t] == 1) seen = 2;
    if (seen == 2) assert_int_not_equal(TR_OUT0[t], 2);
  }
  assert_int_equal(seen, 2);
  assert_true(has_text("RTDE Control Script Loaded (14.02.2024-12:23)"));
  assert_true(has_text("Received stop script!"));
}

/* ur_rtde's getAsyncOperationProgress(): progress while running, else (op_id % 2) − 2 */
static int progress_of(int32_t reg) {
  return (reg & 32768) ? (reg & 32767) : ((reg >> 24) & 127) % 2 - 2;
}

static void test_rtde_control_run__movej_async_and_progress_word(void **state) {
  F.motion_ticks = 50;
  pkg *p = add(P_REGULAR, 1);
  p->d[0] = 0.5;
  p->d[6] = 1.0;
  p->d[7] = 1.0;
  p->i[1] = 1;  // async
  add(P_CONT, 0)->hold = 80;  // stay idle (cleared) for a while
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);

  // DONE before the motion ended
  assert_true(DONE_TICK[0] - SENT_TICK[0] < 50);
  // reset (finished: counter 1, op 0), started (counter 2, op 1, running, progress 0),
  // finished (counter 3, op 1)
  int32_t reset = 1 * 65536, started = 2 * 65536 + 1 * 16777216 + 32768, finished = 3 * 65536 + 16777216;
  assert_int_equal(TR_OUT2[0], reset);
  int a = -1, b = -1;
  for (int t = 0; t < NTR; t++) {
    if (a < 0 && TR_OUT2[t] == started) a = t;
    if (a >= 0 && b < 0 && TR_OUT2[t] == finished) b = t;
  }
  assert_true(a >= 0 && b > a);
  assert_true(b - a >= 45);
  assert_int_equal(progress_of(reset), -2);
  assert_int_equal(progress_of(started), 0);
  assert_int_equal(progress_of(finished), -1);
}

static void test_rtde_control_run__servoj_streams_and_stays_ready(void **state) {
  F.motion_ticks = 1000000;  // a servo never ends by itself
  pkg *p = add(P_CONT, 11);
  p->hold = 20;
  p->d[0] = 0.3;
  p->d[8] = 0.002;
  p->d[9] = 0.1;
  p->d[10] = 300;
  p = add(P_CONT, 11);
  p->hold = 20;
  p->d[0] = 0.31;
  p->d[8] = 0.002;
  p->d[9] = 0.1;
  p->d[10] = 300;
  p = add(P_REGULAR, 16);  // servoStop
  p->d[0] = 10;
  add(P_STOP, 255);
  F.motion_ticks = 5;
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);

  // two distinct targets: two SERVOJ commands, ready throughout the stream
  int k1 = fake_find_cmd(&F, URT_CTRL_SERVOJ, 0);
  int k2 = fake_find_cmd(&F, URT_CTRL_SERVOJ, k1 + 1);
  assert_true(k1 >= 0 && k2 > k1);
  assert_int_equal(fake_find_cmd(&F, URT_CTRL_SERVOJ, k2 + 1), -1);
  assert_float_equal(F.cmd[k1].q[0], 0.3, 0);
  assert_float_equal(F.cmd[k2].q[0], 0.31, 0);
  assert_float_equal(F.cmd[k1].t, 0.002, 0);
  assert_float_equal(F.cmd[k1].lookahead_time, 0.1, 0);
  assert_float_equal(F.cmd[k1].gain, 300, 0);
  for (int t = SENT_TICK[0]; t < SENT_TICK[2] - 1; t++) assert_int_equal(TR_OUT0[t], 1);
  int s = fake_find_cmd(&F, URT_CTRL_STOPL, k2);
  assert_true(s > k2);
  assert_float_equal(F.cmd[s].a, 10, 0);
}

static void test_rtde_control_run__ik_and_fk_answers(void **state) {
  double q[6] = {0.2, -1.4, 1.5, -1.7, -1.5, 0.3}, pose[6], qr[6];
  memcpy(F.s.q, q, sizeof q);
  urt_ctrl_forward_kinematics_tcp(M, M->arm.tcp, q, pose);
  add(P_REGULAR, 43);
  pkg *p = add(P_REGULAR, 46);
  memcpy(p->d, pose, sizeof pose);
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);

  // the last answer stays in the registers: IK of FK(q) near q is q
  assert_int_equal(urt_ctrl_inverse_kinematics(M, pose, q, qr), 0);
  for (int j = 0; j < 6; j++) {
    assert_float_equal(REG.out_double[j], qr[j], 0);
    assert_float_equal(REG.out_double[j], q[j], 1e-9);
  }
}

static void test_rtde_control_run__fk_default_is_the_actual_pose(void **state) {
  double q[6] = {0.2, -1.4, 1.5, -1.7, -1.5, 0.3}, pose[6];
  memcpy(F.s.q, q, sizeof q);
  urt_ctrl_forward_kinematics_tcp(M, M->arm.tcp, q, pose);
  add(P_REGULAR, 43);
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);
  for (int j = 0; j < 6; j++) assert_float_equal(REG.out_double[j], pose[j], 0);
}

static void test_rtde_control_run__mass_matrix_and_jacobian_are_the_model(void **state) {
  double q[6] = {0.2, -1.4, 1.5, -1.7, -1.5, 0.3}, A[36];
  memcpy(F.s.q, q, sizeof q);
  add(P_CONT, 67)->hold = 1;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);
  urt_arm_mass_matrix(M, q, A);
  for (int c = 0; c < 6; c++) {
    for (int r = 0; r < 6; r++) {
      int k = c < 4 ? 6 * c + r : 36 + 6 * (c - 4) + r;
      assert_float_equal(REG.out_double[k], A[6 * r + c], 0);
    }
  }

  setup(state);
  memcpy(F.s.q, q, sizeof q);
  add(P_CONT, 70)->hold = 1;
  add(P_STOP, 255);
  assert_int_equal(run(script(0, 0, NULL), &e), 0);
  urt_arm_jacobian(M, q, A);
  for (int c = 0; c < 6; c++) {
    for (int r = 0; r < 6; r++) {
      int k = c < 4 ? 6 * c + r : 36 + 6 * (c - 4) + r;
      assert_float_equal(REG.out_double[k], A[6 * r + c], 0);
    }
  }
}

static void test_rtde_control_run__watchdog_stops_the_program(void **state) {
  pkg *p = add(P_REGULAR, 35);
  p->d[0] = 10;  // 10 Hz: 0.1 s = 50 ticks
  add(P_CONT, 0)->hold = 100;   // refreshed every tick: no timeout
  add(P_SILENT, 0);             // the client goes quiet
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), -1);
  assert_int_equal(e.kind, US_ERR_RUNTIME);
  assert_non_null(strstr(e.text, "watchdog"));
  // it fired 50–51 ticks after the last refresh, not before
  uint64_t quiet = (uint64_t)SENT_TICK[2];
  assert_true(F.s.tick >= quiet + 50 && F.s.tick <= quiet + 53);
}

static void test_rtde_control_run__stop_script_ends_without_done(void **state) {
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);
  for (int t = 0; t < NTR; t++) assert_int_not_equal(TR_OUT0[t], 2);
  assert_true(has_text("RTDE Control Script Terminated"));
}

static void test_rtde_control_run__unsupported_command_fails_and_stops(void **state) {
  add(P_REGULAR, 31);  // protective_stop: in the script, not emulated
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), -1);
  assert_int_equal(e.kind, US_ERR_RUNTIME);
  assert_string_equal(e.text, "protective_stop is not supported by urtwin");
  assert_int_equal(e.line, 17);  // its branch in the script
  assert_int_equal(DONE_TICK[0], 0);
}

static void test_rtde_control_run__ids_the_script_lacks_do_nothing_and_answer_done(void **state) {
  add(P_REGULAR, 200);  // no branch: the script's process_cmd falls through to DONE
  add(P_CONT, 66)->hold = 3;  // pruned branch: ready, nothing submitted
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(0, 0, NULL), &e), 0);
  assert_true(DONE_TICK[0] > 0);
  assert_int_equal(fake_find_cmd(&F, URT_CTRL_TORQUE, 0), -1);
  assert_int_equal(F.n_cmd, 0);
}

static void test_rtde_control_run__upper_range_offsets(void **state) {
  OFF = 24;
  pkg *p = add(P_REGULAR, 1);
  p->d[6] = 1;
  p->d[7] = 1;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script(24, 24, NULL), &e), 0);
  assert_true(DONE_TICK[0] > 0);
  assert_int_equal(REG.out_int[0], 0);  // nothing written below the offset
  assert_int_not_equal(REG.out_int[24 + 2], 0);
}

static void test_rtde_control_run__move_path_async_progress(void **state) {
  F.motion_ticks = 20;
  const char *s = script(0, 0,
                         "\tsignal_async_progress(0)\n"
                         "\tmovej([0.1,-1.5,1.5,-1.57,-1.5,0],a=1.4,v=1.05,r=0)\n"
                         "\tsignal_async_progress(1)\n"
                         "\tmovej([0.2,-1.5,1.5,-1.57,-1.5,0],a=1.4,v=1.05,r=0.05)\n");
  add(P_REGULAR, 45)->i[1] = 1;
  add(P_CONT, 0)->hold = 80;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(s, &e), 0);
  int k1 = fake_find_cmd(&F, URT_CTRL_MOVEJ, 0), k2 = fake_find_cmd(&F, URT_CTRL_MOVEJ, k1 + 1);
  assert_true(k1 >= 0 && k2 > k1);
  assert_float_equal(F.cmd[k2].q[0], 0.2, 0);
  assert_float_equal(F.cmd[k2].r, 0, 0);  // blends are not honoured
  // progress 0 (running) … 1 (running) … finished
  int seen = 0;
  for (int t = 0; t < NTR; t++) {
    int pr = progress_of(TR_OUT2[t]);
    if (seen == 0 && pr == 0) seen = 1;
    if (seen == 1 && pr == 1) seen = 2;
    if (seen == 2 && pr < 0) seen = 3;
  }
  assert_int_equal(seen, 3);
}

static void test_rtde_control_run__settings_reach_the_controller(void **state) {
  F.s.payload_cog[2] = 0.05;
  pkg *p = add(P_REGULAR, 29);  // setTcp
  p->d[2] = 0.1;
  p = add(P_REGULAR, 17);  // setPayload, CoG 0: keep the current one
  p->d[0] = 1.5;
  p = add(P_REGULAR, 59);  // setGravity: UR's direction (up)
  p->d[2] = 9.82;
  add(P_REGULAR, 18);  // teachMode
  add(P_REGULAR, 19);  // endTeachMode
  p = add(P_REGULAR, 52);  // freedriveMode, axes 1 and 3 free
  p->i[1] = 1;
  p->i[3] = 1;
  p = add(P_CONT, 66);  // directTorque
  p->hold = 3;
  p->d[1] = 12.5;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);

  int k = fake_find_cmd(&F, URT_CTRL_SET_TCP, 0);
  assert_true(k >= 0);
  assert_float_equal(F.cmd[k].pose[2], 0.1, 0);
  k = fake_find_cmd(&F, URT_CTRL_SET_PAYLOAD, 0);
  assert_true(k >= 0);
  assert_float_equal(F.cmd[k].value, 1.5, 0);
  assert_float_equal(F.cmd[k].pose[2], 0.05, 0);
  k = fake_find_cmd(&F, URT_CTRL_SET_GRAVITY, 0);
  assert_true(k >= 0);
  assert_float_equal(F.cmd[k].pose[2], -9.82, 0);  // the gravity vector points down
  k = fake_find_cmd(&F, URT_CTRL_FREEDRIVE, 0);
  assert_int_equal(F.cmd[k].index, 1);
  for (int j = 0; j < 6; j++) assert_float_equal(F.cmd[k].q[j], 1, 0);
  k = fake_find_cmd(&F, URT_CTRL_FREEDRIVE, k + 1);
  assert_int_equal(F.cmd[k].index, 0);
  k = fake_find_cmd(&F, URT_CTRL_FREEDRIVE, k + 1);
  assert_int_equal(F.cmd[k].index, 1);
  assert_float_equal(F.cmd[k].q[0], 1, 0);  // i1..i6: the axes
  assert_float_equal(F.cmd[k].q[1], 0, 0);
  assert_float_equal(F.cmd[k].q[2], 1, 0);
  k = fake_find_cmd(&F, URT_CTRL_TORQUE, 0);
  assert_true(k >= 0);
  assert_float_equal(F.cmd[k].tau[1], 12.5, 0);
  assert_int_equal(fake_find_cmd(&F, URT_CTRL_TORQUE, k + 1), -1);  // one per distinct torque
}

static void test_rtde_control_run__getters_answer_in_the_output_registers(void **state) {
  double q[6] = {0.2, -1.4, 1.5, -1.7, -1.5, 0.3};
  memcpy(F.s.q, q, sizeof q);
  for (int j = 0; j < 6; j++) F.s.tau[j] = j + 0.5;
  add(P_CONT, 38)->hold = 1;  // getJointTorques
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  for (int j = 0; j < 6; j++) assert_float_equal(REG.out_double[j], j + 0.5, 0);

  setup(state);
  add(P_CONT, 26)->hold = 1;  // getStepTime
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_float_equal(REG.out_double[0], 0.002, 0);

  setup(state);
  pkg *p = add(P_REGULAR, 39);  // poseTrans: p[1,0,0, 0,0,π/2] ∘ p[1,0,0, 0,0,0] = p[1,1,0, 0,0,π/2]
  p->d[0] = 1;
  p->d[5] = M_PI / 2;
  p->d[6] = 1;
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_float_equal(REG.out_double[0], 1, 1e-12);
  assert_float_equal(REG.out_double[1], 1, 1e-12);
  assert_float_equal(REG.out_double[5], M_PI / 2, 1e-12);

  setup(state);
  p = add(P_REGULAR, 37);  // isJointsWithinSafetyLimits: beyond the first joint's limit
  p->d[0] = M->joint[0].q_max + 0.1;
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_int_equal(REG.out_int[1], 0);

  setup(state);
  memcpy(F.s.q, q, sizeof q);
  p = add(P_REGULAR, 37);
  memcpy(p->d, q, sizeof q);
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_int_equal(REG.out_int[1], 1);

  setup(state);
  add(P_REGULAR, 47);  // isSteady: at rest
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_int_equal(REG.out_int[1], 1);
}

static void test_rtde_control_run__speedj_then_speed_stop(void **state) {
  F.motion_ticks = 5;
  pkg *p = add(P_CONT, 9);
  p->hold = 10;
  p->d[0] = 0.2;
  p->d[6] = 0.5;  // a
  p = add(P_REGULAR, 15);  // speedStop
  p->d[0] = 2.0;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  int k = fake_find_cmd(&F, URT_CTRL_SPEEDJ, 0);
  assert_true(k >= 0);
  assert_float_equal(F.cmd[k].q[0], 0.2, 0);
  assert_float_equal(F.cmd[k].a, 0.5, 0);
  assert_float_equal(F.cmd[k].t, 0, 0);  // the script's speed thread keeps it going
  assert_int_equal(fake_find_cmd(&F, URT_CTRL_SPEEDJ, k + 1), -1);
  int st = fake_find_cmd(&F, URT_CTRL_STOPJ, k);  // after speedj: stopj
  assert_true(st > k);
  assert_float_equal(F.cmd[st].a, 2.0, 0);
}

static void test_rtde_control_run__stops_follow_the_script(void **state) {
  F.motion_ticks = 30;
  pkg *p = add(P_REGULAR, 33);  // stopL sync before any async stop: the script's stop_type 0 → stopj
  p->d[0] = 1.5;
  p = add(P_REGULAR, 34);  // stopJ async: always stopl
  p->d[0] = 2.5;
  p->i[1] = 1;
  add(P_CONT, 0)->hold = 60;
  p = add(P_REGULAR, 33);  // now sync stops follow stop_type 1 → stopl
  p->d[0] = 3.5;
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  int a = fake_find_cmd(&F, URT_CTRL_STOPJ, 0);
  assert_true(a >= 0);
  assert_float_equal(F.cmd[a].a, 1.5, 0);
  int b = fake_find_cmd(&F, URT_CTRL_STOPL, a);
  assert_float_equal(F.cmd[b].a, 2.5, 0);
  int c = fake_find_cmd(&F, URT_CTRL_STOPL, b + 1);
  assert_float_equal(F.cmd[c].a, 3.5, 0);
  assert_true(DONE_TICK[1] - SENT_TICK[1] < 30);  // async: done before the stop ended
  assert_true(DONE_TICK[3] - SENT_TICK[3] >= 30);
}

static void test_rtde_control_run__force_mode_and_damping(void **state) {
  pkg *p = add(P_CONT, 6);
  p->hold = 5;
  p->i[1] = 2;  // type
  p->i[4] = 1;  // z selected
  p->d[8] = -10;  // wrench z
  p->d[14] = 0.1;  // limit z
  p = add(P_REGULAR, 20);  // setDamping
  p->d[0] = 0.3;
  add(P_REGULAR, 7);  // forceModeStop
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  int k = fake_find_cmd(&F, URT_CTRL_FORCE_MODE, 0);
  assert_true(k >= 0);
  assert_int_equal(F.cmd[k].index, 2);
  assert_float_equal(F.cmd[k].q[2], 1, 0);
  assert_float_equal(F.cmd[k].tau[2], -10, 0);
  assert_float_equal(F.cmd[k].qd[2], 0.1, 0);
  assert_float_equal(F.cmd[k].value, 0.025, 0);  // the script's default damping
  assert_float_equal(F.cmd[k].gain, 0.5, 0);     // and gain scaling
  int d = fake_find_cmd(&F, URT_CTRL_FORCE_MODE, k + 1);
  assert_true(d > k);
  assert_float_equal(F.cmd[d].value, 0.3, 0);
  int end = fake_find_cmd(&F, URT_CTRL_FORCE_MODE_END, d);
  assert_true(end > d);
  int st = fake_find_cmd(&F, URT_CTRL_STOPL, end);
  assert_float_equal(F.cmd[st].a, 10, 0);
}

static void test_rtde_control_run__move_until_contact(void **state) {
  F.motion_ticks = 3;
  FORCE_TICK = 40;
  FORCE[2] = 25;  // resisting a motion along −z
  pkg *p = add(P_REGULAR, 51);
  p->d[2] = -0.05;  // xd
  p->d[8] = -1;     // direction
  p->d[12] = 0.5;   // a
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  int sp = fake_find_cmd(&F, URT_CTRL_SPEEDL, 0);
  assert_true(sp >= 0);
  assert_float_equal(F.cmd[sp].pose[2], -0.05, 0);
  int st = fake_find_cmd(&F, URT_CTRL_STOPL, sp);
  assert_true(st > sp);
  assert_float_equal(F.cmd[st].a, 3, 0);
  int mv = fake_find_cmd(&F, URT_CTRL_MOVEL, st);
  assert_true(mv > st);
  assert_true(DONE_TICK[0] >= 40);
}

static void test_rtde_control_run__contact_detection_runs_the_internal_command(void **state) {
  F.motion_ticks = 3;
  FORCE_TICK = 30;
  FORCE[0] = -20;  // resisting a motion along +x
  pkg *p = add(P_REGULAR, 62);  // startContactDetection along +x
  p->d[0] = 1;
  add(P_CONT, 0)->hold = 40;
  add(P_REGULAR, 64);  // readContactDetection
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_true(has_text("cmd == 254 - contact detected"));
  int st = fake_find_cmd(&F, URT_CTRL_STOPL, 0);
  assert_true(st >= 0);
  assert_true(fake_find_cmd(&F, URT_CTRL_MOVEL, st) > st);
  assert_int_equal(REG.out_int[1], 1);  // steps back: the force appeared at once
}

static void test_rtde_control_run__target_waypoint_and_history(void **state) {
  F.motion_ticks = 200;
  F.s.tcp_pose_target[0] = 0.7;
  pkg *p = add(P_REGULAR, 3);  // moveL async
  double pose[6] = {0.3, -0.4, 0.5, 0, 3.1, 0};
  memcpy(p->d, pose, sizeof pose);
  p->d[6] = 0.25;
  p->d[7] = 1.2;
  p->i[1] = 1;
  add(P_REGULAR, 28);  // getTargetWaypoint while it moves
  add(P_STOP, 255);
  us_err e;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  for (int j = 0; j < 6; j++) assert_float_equal(REG.out_double[j], pose[j], 0);

  setup(state);
  F.s.tcp_pose_target[0] = 0.7;
  add(P_REGULAR, 28);  // at rest: the target TCP pose
  p = add(P_CONT, 27);  // getActualJointPositionsHistory(0)
  p->hold = 1;
  add(P_STOP, 255);
  F.s.q[4] = -1.25;
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_float_equal(REG.out_double[4], -1.25, 0);

  setup(state);
  F.s.tcp_pose_target[0] = 0.7;
  add(P_REGULAR, 28);
  add(P_STOP, 255);
  assert_int_equal(run(script_with(0, 0, NULL, true), &e), 0);
  assert_float_equal(REG.out_double[0], 0.7, 0);
}

//---- the runner ----

static void test_rtde_control_runner__dispatches_and_reports_the_life_cycle(void **state) {
  add(P_STOP, 255);
  urt_runner_t *r;
  urt_runner_config_t cfg = {.wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  const char *s = script(0, 0, NULL);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  assert_true(urt_runner_wait_idle(r, 5000));
  urt_runner_destroy(r);

  assert_int_equal(F.msg[0].kind, URT_SCRIPT_MSG_KEY);
  assert_string_equal(F.msg[0].title, "PROGRAM_XXX_STARTED");
  assert_string_equal(F.msg[0].text, "rtde_control");
  assert_string_equal(F.msg[F.n_msg - 1].title, "PROGRAM_XXX_STOPPED");
  assert_string_equal(F.msg[F.n_msg - 1].text, "rtde_control");
  int k = fake_find_cmd(&F, URT_CTRL_PROGRAM_STATE, 0);
  assert_int_equal(F.cmd[k].index, URT_PROGRAM_PLAYING);
  int h = fake_find_cmd(&F, URT_CTRL_HALT, k);
  int st = fake_find_cmd(&F, URT_CTRL_PROGRAM_STATE, k + 1);
  assert_true(h > k && st > h);
  assert_int_equal(F.cmd[st].index, URT_PROGRAM_STOPPED);
}

static void test_rtde_control_runner__a_new_upload_replaces_the_running_one(void **state) {
  // no client: both programs wait for commands until replaced or stopped
  urt_runner_t *r;
  urt_runner_config_t cfg = {.wait_timeout_ms = 1};
  F.tick_sleep_us = 50;
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  const char *s = script(0, 0, NULL);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  for (int k = 0; k < 5000 && F.n_msg < 2; k++) usleep(1000);
  assert_int_equal(urt_runner_state(r), URT_PROGRAM_PLAYING);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  for (int k = 0; k < 5000 && F.n_msg < 4; k++) usleep(1000);
  urt_runner_stop(r);
  assert_true(urt_runner_wait_idle(r, 5000));
  urt_runner_destroy(r);
  const char *want[][2] = {{"PROGRAM_XXX_STARTED", "rtde_control"}, {"", "RTDE Control Script Loaded"},
                           {"PROGRAM_XXX_STOPPED", "rtde_control"}, {"PROGRAM_XXX_STARTED", "rtde_control"},
                           {"", "RTDE Control Script Loaded"}, {"PROGRAM_XXX_STOPPED", "rtde_control"}};
  assert_int_equal(F.n_msg, 6);
  for (int k = 0; k < 6; k++) {
    assert_string_equal(F.msg[k].title, want[k][0]);
    assert_non_null(strstr(F.msg[k].text, want[k][1]));
  }
}

static void test_rtde_control_runner__watchdog_error_is_a_runtime_exception(void **state) {
  add(P_REGULAR, 35)->d[0] = 25;
  add(P_SILENT, 0);
  urt_runner_t *r;
  urt_runner_config_t cfg = {.wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  const char *s = script(0, 0, NULL);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  assert_true(urt_runner_wait_idle(r, 5000));
  urt_runner_destroy(r);
  assert_int_equal(F.msg[F.n_msg - 2].kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_non_null(strstr(F.msg[F.n_msg - 2].text, "RTDE watchdog"));
  assert_string_equal(F.msg[F.n_msg - 1].title, "PROGRAM_XXX_STOPPED");
}

static void test_rtde_control_runner__custom_script_function_writes_the_registers(void **state) {
  // sendCustomScriptFunction's program goes through the interpreter
  const char *s = "def my_func():\n\twrite_output_integer_register(0 +0, 1)\n\ttextmsg(\"hi\")\n"
                  "\twrite_output_float_register(3, 2.5)\n\tx = read_input_integer_register(5)\n"
                  "\twrite_output_integer_register(1, x + 1)\n\twrite_output_integer_register(0 +0, 2)\nend\n";
  REG.in_int[5] = 41;
  urt_runner_t *r;
  urt_runner_config_t cfg = {.wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  assert_true(urt_runner_wait_idle(r, 5000));
  urt_runner_destroy(r);
  assert_int_equal(REG.out_int[0], 2);
  assert_int_equal(REG.out_int[1], 42);
  assert_float_equal(REG.out_double[3], 2.5, 0);
  assert_string_equal(F.msg[0].text, "my_func");
  assert_int_equal(F.n_msg, 3);  // started, hi, stopped: no error
}

static void test_rtde_control_runner__register_index_out_of_range_is_an_error(void **state) {
  const char *s = "def bad():\n  write_output_integer_register(48, 1)\nend\n";
  urt_runner_t *r;
  urt_runner_config_t cfg = {.wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  assert_int_equal(urt_runner_submit(r, s, strlen(s)), 0);
  assert_true(urt_runner_wait_idle(r, 5000));
  urt_runner_destroy(r);
  assert_int_equal(F.msg[1].kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_non_null(strstr(F.msg[1].text, "out of range"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rtde_control_recognise__reads_offsets_after_the_comment),
      cmocka_unit_test(test_rtde_control_recognise__knows_the_branches_and_pruned_bodies),
      cmocka_unit_test(test_rtde_control_recognise__refuses_other_programs),
      cmocka_unit_test(test_rtde_control_recognise__reads_the_injected_path),
      cmocka_unit_test_setup(test_rtde_control_run__movej_sync_handshake, setup),
      cmocka_unit_test_setup(test_rtde_control_run__movej_async_and_progress_word, setup),
      cmocka_unit_test_setup(test_rtde_control_run__servoj_streams_and_stays_ready, setup),
      cmocka_unit_test_setup(test_rtde_control_run__ik_and_fk_answers, setup),
      cmocka_unit_test_setup(test_rtde_control_run__fk_default_is_the_actual_pose, setup),
      cmocka_unit_test_setup(test_rtde_control_run__mass_matrix_and_jacobian_are_the_model, setup),
      cmocka_unit_test_setup(test_rtde_control_run__watchdog_stops_the_program, setup),
      cmocka_unit_test_setup(test_rtde_control_run__stop_script_ends_without_done, setup),
      cmocka_unit_test_setup(test_rtde_control_run__unsupported_command_fails_and_stops, setup),
      cmocka_unit_test_setup(test_rtde_control_run__ids_the_script_lacks_do_nothing_and_answer_done, setup),
      cmocka_unit_test_setup(test_rtde_control_run__upper_range_offsets, setup),
      cmocka_unit_test_setup(test_rtde_control_run__move_path_async_progress, setup),
      cmocka_unit_test_setup(test_rtde_control_run__settings_reach_the_controller, setup),
      cmocka_unit_test_setup(test_rtde_control_run__getters_answer_in_the_output_registers, setup),
      cmocka_unit_test_setup(test_rtde_control_run__speedj_then_speed_stop, setup),
      cmocka_unit_test_setup(test_rtde_control_run__stops_follow_the_script, setup),
      cmocka_unit_test_setup(test_rtde_control_run__force_mode_and_damping, setup),
      cmocka_unit_test_setup(test_rtde_control_run__move_until_contact, setup),
      cmocka_unit_test_setup(test_rtde_control_run__contact_detection_runs_the_internal_command, setup),
      cmocka_unit_test_setup(test_rtde_control_run__target_waypoint_and_history, setup),
      cmocka_unit_test_setup(test_rtde_control_runner__dispatches_and_reports_the_life_cycle, setup),
      cmocka_unit_test_setup(test_rtde_control_runner__a_new_upload_replaces_the_running_one, setup),
      cmocka_unit_test_setup(test_rtde_control_runner__watchdog_error_is_a_runtime_exception, setup),
      cmocka_unit_test_setup(test_rtde_control_runner__custom_script_function_writes_the_registers, setup),
      cmocka_unit_test_setup(test_rtde_control_runner__register_index_out_of_range_is_an_error, setup),
  };
  return cmocka_run_group_tests_name("net/urscript/rtde_control", tests, NULL, NULL);
}
