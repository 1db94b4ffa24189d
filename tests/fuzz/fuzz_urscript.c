/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_urscript.c — libFuzzer target for the URScript parser and interpreter.
 * Parse the input; if it parses, run it against an instant fake controller (every motion is
 * done at once, every wait advances one tick) with a small step budget and at most 2000 ticks,
 * so it can neither crash nor hang.
 *
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -Inet/include -Icore/include \
 *     -Idrivers/include tests/fuzz/fuzz_urscript.c net/urscript/script_parse.c \
 *     net/urscript/script_interp.c -o /tmp/fuzz_urscript -lm -lpthread
 *   /tmp/fuzz_urscript -max_total_time=60 -rss_limit_mb=1024
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../../net/urscript/script.h"  /* private: the fuzzer drives parse + run directly */

typedef struct fake {
  urt_snapshot_t s;
  int ticks;
} fake;

static bool f_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  fake *f = ctx;
  if (cmd->id > f->s.motion_done_id) {
    f->s.motion_done_id = cmd->id;
  }
  if (cmd->kind == URT_CTRL_SET_DIGITAL_OUT && cmd->index >= 0 && cmd->index < 32) {
    f->s.digital_out = cmd->value != 0 ? f->s.digital_out | (1u << cmd->index)
                                       : f->s.digital_out & ~(1u << cmd->index);
  }
  return true;
}

static uint64_t f_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  fake *f = ctx;
  f->ticks++;
  f->s.tick++;
  f->s.time = (double)f->s.tick * 0.002;
  return f->s.tick;
}

static void f_snapshot(void *ctx, urt_snapshot_t *out) { *out = ((fake *)ctx)->s; }

static void f_message(void *ctx, const urt_script_msg_t *m) { (void)ctx; (void)m; }

static int f_ik(void *ctx, const double pose[6], const double qnear[URT_NJ], double q[URT_NJ]) {
  memcpy(q, pose, 6 * sizeof *q);
  return pose[0] > 10 ? 1 : 0;
}

static int f_fk(void *ctx, const double q[URT_NJ], double pose[6]) {
  memcpy(pose, q, 6 * sizeof *pose);
  return 0;
}

static int f_poll(void *ctx) { return ((fake *)ctx)->ticks > 2000; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  us_prog *p = NULL;
  us_err err;
  if (urt__us_parse((const char *)data, size, &p, &err) != 0) {
    return 0;
  }
  static fake f;
  memset(&f, 0, sizeof f);
  f.s.safety_mode = URT_SAFETY_MODE_NORMAL;
  f.s.robot_mode = URT_ROBOT_MODE_RUNNING;
  f.s.period = 0.002;
  f.s.speed_scaling = 1.0;  // slider 100 %: speedj waits in motion time
  f.s.motion_rate = 1.0;
  urt_script_host_t host = {.ctx = &f, .submit = f_submit, .wait_tick = f_wait_tick,
                            .snapshot = f_snapshot, .message = f_message,
                            .inverse_kinematics = f_ik, .forward_kinematics = f_fk};
  uint64_t motion_id = 0;
  us_hooks h = {.host = &host, .motion_id = &motion_id, .step_budget = 5000,
                .wait_timeout_ms = 1, .poll = f_poll, .poll_ctx = &f};
  urt__us_run(p, &h, &err);
  urt__us_prog_free(p);
  return 0;
}
