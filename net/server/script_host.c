/* SPDX-License-Identifier: Apache-2.0
 * net/server/script_host.c — the URScript runner's host (urt_script_host_t): the hard loop,
 * the RTDE register bank and the message queue to 30001/30002, seen from the runner thread.
 */
#define _GNU_SOURCE
#include <pthread.h>
#include <string.h>
#include <unistd.h>

#include "emulator_internal.h"
#include "urt/core.h"

static bool host_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  urt_emulator_t *e = ctx;
  return urt_loop_submit(e->loop, e->runner_producer, cmd);
}

static uint64_t host_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  urt_emulator_t *e = ctx;
  return urt_loop_wait(e->loop, after, timeout_ms);
}

static void host_snapshot(void *ctx, urt_snapshot_t *out) {
  urt_emulator_t *e = ctx;
  urt_loop_read_latest(e->loop, out);
}

static void host_message(void *ctx, const urt_script_msg_t *msg) {
  urt_emulator_t *e = ctx;
  pthread_mutex_lock(&e->msg_lock);
  if (e->msg_len < MSG_QUEUE) {
    e->msg_queue[(e->msg_head + e->msg_len) % MSG_QUEUE] = *msg;
    e->msg_len++;
  } else {
    e->msg_dropped++;
  }
  pthread_mutex_unlock(&e->msg_lock);
  uint64_t one = 1;
  ssize_t rc = write(e->msg_fd, &one, sizeof one);
  (void)rc;  // a full eventfd counter still wakes the reader
}

static int host_inverse_kinematics(void *ctx, const double pose[6], const double qnear[URT_NJ],
                                   double q[URT_NJ]) {
  urt_emulator_t *e = ctx;
  urt_snapshot_t s;
  urt_loop_read_latest(e->loop, &s);
  return urt_ctrl_inverse_kinematics_tcp(e->m, s.tcp_offset, pose, qnear, q);
}

static int host_forward_kinematics(void *ctx, const double q[URT_NJ], double pose[6]) {
  urt_emulator_t *e = ctx;
  urt_snapshot_t s;
  urt_loop_read_latest(e->loop, &s);
  urt_ctrl_forward_kinematics_tcp(e->m, s.tcp_offset, q, pose);
  return 0;
}

static void host_read_registers(void *ctx, uint64_t tick, urt_rtde_registers_t *out) {
  urt_emulator_t *e = ctx;
  pthread_mutex_lock(&e->reg_lock);
  *out = e->regs;
  if (tick != UINT64_MAX) {
    urt__inputs_read(e, tick, out);
  }
  pthread_mutex_unlock(&e->reg_lock);
}

static void host_write_output_register(void *ctx, int kind, int index, double value) {
  urt_emulator_t *e = ctx;
  pthread_mutex_lock(&e->reg_lock);
  if (kind == URT_SCRIPT_REG_INT && index >= 0 && index < URT_RTDE_NREG) {
    e->regs.out_int[index] = (int32_t)value;
  } else if (kind == URT_SCRIPT_REG_DOUBLE && index >= 0 && index < URT_RTDE_NREG) {
    e->regs.out_double[index] = value;
  } else if (kind == URT_SCRIPT_REG_BIT && index >= 0 && index < URT_RTDE_NBITREG) {
    e->regs.out_bit[index] = value != 0.0;
  }
  pthread_mutex_unlock(&e->reg_lock);
}

static int host_snapshot_at(void *ctx, uint64_t tick, urt_snapshot_t *out) {
  urt_emulator_t *e = ctx;
  return urt_loop_read(e->loop, tick, out);  // the loop keeps URT_LOOP_HISTORY ticks
}

// a program has run its slice of tick: keep the output registers it left for the data package
// of the next tick (port_rtde.c). The controller does not wait for the slice: a loop that
// waited (bounded at 5 ms) made URCL's driver_example lose its RTDE packages in 2 of 4 runs
// (0 of 6 without the wait), so a late runner's commands still reach a later tick.
static void host_tick_done(void *ctx, uint64_t tick, bool running) {
  urt_emulator_t *e = ctx;
  // the controller sees whether the program's next command is still to come (motion_speedj.cpp)
  urt_loop_note_program_slice(e->loop, running ? tick : 0);
  pthread_mutex_lock(&e->reg_lock);
  e->out_running = running;
  if (!running) {
    pthread_mutex_unlock(&e->reg_lock);
    return;
  }
  struct urt__out_regs *h = &e->out_hist[tick % URT_LOOP_HISTORY];
  e->out_done = h->slice = tick + 1;
  memcpy(h->out_int, e->regs.out_int, sizeof h->out_int);
  memcpy(h->out_double, e->regs.out_double, sizeof h->out_double);
  memcpy(h->out_bit, e->regs.out_bit, sizeof h->out_bit);
  pthread_mutex_unlock(&e->reg_lock);
}

static const urt_model_t *host_model(void *ctx) {
  const urt_emulator_t *e = ctx;
  return e->m;
}

urt_script_host_t urt__script_host(urt_emulator_t *e) {
  return (urt_script_host_t){
      .ctx = e,
      .submit = host_submit,
      .wait_tick = host_wait_tick,
      .snapshot = host_snapshot,
      .message = host_message,
      .inverse_kinematics = host_inverse_kinematics,
      .forward_kinematics = host_forward_kinematics,
      .read_registers = host_read_registers,
      .write_output_register = host_write_output_register,
      .model = host_model,
      .snapshot_at = host_snapshot_at,
      .tick_done = host_tick_done,
  };
}
