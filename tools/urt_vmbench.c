/* SPDX-License-Identifier: Apache-2.0
 * tools/urt_vmbench.c — the URScript VM's cost per controller tick (make bench): a program runs
 * against an in-process controller whose clock advances one tick per wait (no physics, no
 * sleeping), and the time from the scheduler's return out of one wait to its next wait is the
 * VM's work for that tick: every thread's slice plus the coroutine switches. Prints JSON:
 * median, p99 and max per case, and one coroutine round trip (yield + resume).
 *
 *   build/tools/urt_vmbench [ticks]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../net/urscript/script.h"  /* private: drives parse + run directly */

typedef struct bench_host {
  urt_snapshot_t s;
  double *cost;      /* per tick [s] */
  int n, cap;
  struct timespec back;  /* when the last wait returned */
  bool have_back;
  uint64_t motion_done;
} bench_host;

static double secs(const struct timespec *a, const struct timespec *b) {
  return (double)(b->tv_sec - a->tv_sec) + 1e-9 * (double)(b->tv_nsec - a->tv_nsec);
}

static bool b_submit(void *ctx, const urt_ctrl_cmd_t *c) {
  bench_host *h = ctx;
  if (c->id > h->s.motion_done_id) h->s.motion_done_id = c->id;
  return true;
}

static uint64_t b_wait(void *ctx, uint64_t after, int timeout_ms) {
  bench_host *h = ctx;
  struct timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  if (h->have_back && h->n < h->cap) h->cost[h->n++] = secs(&h->back, &now);
  h->s.tick = after + 1;
  h->s.time = (double)h->s.tick * h->s.period;
  clock_gettime(CLOCK_MONOTONIC, &h->back);
  h->have_back = true;
  return h->s.tick;
}

static void b_snapshot(void *ctx, urt_snapshot_t *out) { *out = ((bench_host *)ctx)->s; }
static void b_message(void *ctx, const urt_script_msg_t *m) { (void)ctx; (void)m; }
static void b_read_registers(void *ctx, uint64_t tick, urt_rtde_registers_t *out) { (void)tick; memset(out, 0, sizeof *out); }
static void b_write_register(void *ctx, int kind, int index, double value) {}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static void run_case(const char *name, const char *text, int ticks, bool last) {
  us_prog *p = NULL;
  us_err err;
  if (urt__us_parse(text, strlen(text), &p, &err) != 0) {
    fprintf(stderr, "%s: %s\n", name, err.text);
    exit(1);
  }
  bench_host h = {0};
  h.s.period = 0.002;
  h.s.speed_scaling = 1.0;
  h.s.motion_rate = 1.0;
  h.s.safety_mode = URT_SAFETY_MODE_NORMAL;
  h.s.robot_mode = URT_ROBOT_MODE_RUNNING;
  h.cap = ticks + 16;
  h.cost = calloc((size_t)h.cap, sizeof *h.cost);
  urt_script_host_t host = {.ctx = &h, .submit = b_submit, .wait_tick = b_wait,
                            .snapshot = b_snapshot, .message = b_message,
                            .read_registers = b_read_registers,
                            .write_output_register = b_write_register};
  uint64_t motion_id = 0;
  us_hooks hooks = {.host = &host, .motion_id = &motion_id, .step_budget = 10000,
                    .wait_timeout_ms = 20};
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  int rc = urt__us_run(p, &hooks, &err);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  urt__us_prog_free(p);
  if (rc != 0) {
    fprintf(stderr, "%s: %u:%u %s\n", name, err.line, err.column, err.text);
    exit(1);
  }
  qsort(h.cost, (size_t)h.n, sizeof *h.cost, cmp);
  double med = h.n ? h.cost[h.n / 2] : 0, p99 = h.n ? h.cost[(int)(0.99 * (h.n - 1))] : 0;
  double max = h.n ? h.cost[h.n - 1] : 0;
  printf("    \"%s\": {\"ticks\": %d, \"median_us\": %.3f, \"p99_us\": %.3f, \"max_us\": %.3f, "
         "\"total_s\": %.4f}%s\n",
         name, h.n, med * 1e6, p99 * 1e6, max * 1e6, secs(&t0, &t1), last ? "" : ",");
  free(h.cost);
}

int main(int argc, char **argv) {
  int ticks = argc > 1 ? atoi(argv[1]) : 20000;
  if (ticks < 10) ticks = 10;
  char servoj[512], threads[1024], sync_only[256], burst[512];
  snprintf(servoj, sizeof servoj,
           "def servo_loop():\n"
           "  i = 0\n"
           "  while i < %d:\n"
           "    q = [0.3 * sin(i * 0.002 * 3.14), -1.57, 1.2, -1.2, -1.57, 0]\n"
           "    servoj(q, 0, 0, 0.002, 0.1, 300)\n"
           "    i = i + 1\n"
           "  end\n"
           "end\n",
           ticks);
  snprintf(threads, sizeof threads,
           "def two_threads():\n"
           "  global n = 0\n"
           "  thread io():\n"
           "    while True:\n"
           "      enter_critical\n"
           "      n = n + 1\n"
           "      exit_critical\n"
           "      set_standard_digital_out(0, n %% 2 == 0)\n"
           "      sync()\n"
           "    end\n"
           "  end\n"
           "  t = run io()\n"
           "  i = 0\n"
           "  while i < %d:\n"
           "    servoj([0.3 * sin(i * 0.00628), -1.57, 1.2, -1.2, -1.57, 0], t=0.002)\n"
           "    i = i + 1\n"
           "  end\n"
           "  kill t\n"
           "end\n",
           ticks);
  snprintf(sync_only, sizeof sync_only,
           "def idle():\n  i = 0\n  while i < %d:\n    sync()\n    i = i + 1\n  end\nend\n", ticks);
  // a thread that computes 1250 loop iterations (~8750 steps) in each of its ticks: about what
  // one slice can cost (a thread is preempted after 10000 steps in a tick, the emulator's
  // default step_budget)
  snprintf(burst, sizeof burst,
           "def burst():\n  k = 0\n  while k < %d:\n    i = 0\n    while i < 1250:\n"
           "      i = i + 1\n    end\n    sync()\n    k = k + 1\n  end\nend\n",
           ticks / 20 > 10 ? ticks / 20 : 10);
  printf("{\n  \"tool\": \"tools/urt_vmbench\",\n  \"period_us\": 2000,\n  \"cases\": {\n");
  run_case("sync_loop", sync_only, ticks, false);
  run_case("servoj_loop", servoj, ticks, false);
  run_case("servoj_and_io_thread", threads, ticks, false);
  run_case("compute_1250_iterations_per_tick", burst, ticks, true);
  printf("  }\n}\n");
  return 0;
}
