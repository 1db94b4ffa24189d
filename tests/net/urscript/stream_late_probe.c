/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/stream_late_probe.c — a spline stream of speedj steps (the way URCL's
 * external-control script runs trajectory points: each 10 ms quintic starts from
 * get_joint_positions(), one speedj per controller period) played by the VM on the real
 * controller and physics, the physics in lockstep with the runner so that the runner's
 * lateness is chosen, not suffered: at each wait the controller runs 1 tick (on time) or, with
 * probability P, 2–4 ticks (the runner descheduled; its slices then run back to back and their
 * commands reach later ticks, as in urtwin).
 *
 *   stream_late_probe CONFIG SEED P SLIDER PERIOD [CSV]
 *
 * Prints one JSON line: the set-point's largest |qdd| and |moment| per joint, the late slices,
 * whether a protective stop came, the program's end. CSV: per tick target q, qd, qdd of joints
 * 1 and 2. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "urt/core.h"
#include "urt/loop.h"
#include "urt/net/urscript.h"
#include "script.h"

typedef struct probe {
  urt_loop_t *l;
  int producer;
  uint64_t granted;
  unsigned seed;
  double p_late;
  uint64_t seen;  // newest tick summarised
  double qdd_max[URT_NJ], moment_max[URT_NJ];
  int pstop;
  FILE *csv;
} probe;

static double uniform(probe *pr) {
  pr->seed = pr->seed * 1103515245u + 12345u;
  return (double)((pr->seed >> 8) & 0xffffff) / 16777216.0;
}

static void summarise(probe *pr) {
  uint64_t last = urt_loop_latest_tick(pr->l);
  for (uint64_t t = pr->seen + 1; t <= last; t++) {
    urt_snapshot_t s;
    if (urt_loop_read(pr->l, t, &s) != 0) continue;
    for (int j = 0; j < URT_NJ; j++) {
      pr->qdd_max[j] = fmax(pr->qdd_max[j], fabs(s.qdd_target[j]));
      pr->moment_max[j] = fmax(pr->moment_max[j], fabs(s.m_target[j]));
    }
    if (s.pstop || s.safety_mode == 3) pr->pstop = 1;
    if (pr->csv) {
      fprintf(pr->csv, "%llu %.9g %.9g %.9g %.9g %.9g %.9g %.6g\n", (unsigned long long)t,
              s.q_target[1], s.qd_target[1], s.qdd_target[1], s.q_target[2], s.qd_target[2],
              s.qdd_target[2], s.speed_scaling);
    }
  }
  pr->seen = last;
}

static void run_to(probe *pr, uint64_t tick) {
  if (tick > pr->granted) {
    urt_loop_grant(pr->l, tick - pr->granted);
    pr->granted = tick;
  }
  while (urt_loop_latest_tick(pr->l) < tick) urt_loop_wait(pr->l, urt_loop_latest_tick(pr->l), 100);
  summarise(pr);
}

static bool h_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  probe *pr = ctx;
  return urt_loop_submit(pr->l, pr->producer, cmd);
}
static uint64_t h_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  (void)timeout_ms;
  probe *pr = ctx;
  uint64_t extra = uniform(pr) < pr->p_late ? 1 + (uint64_t)(uniform(pr) * 3.0) : 0;
  run_to(pr, after + 1 + extra);
  return urt_loop_latest_tick(pr->l);
}
static void h_snapshot(void *ctx, urt_snapshot_t *out) {
  probe *pr = ctx;
  urt_loop_read_latest(pr->l, out);
}
static int h_snapshot_at(void *ctx, uint64_t tick, urt_snapshot_t *out) {
  probe *pr = ctx;
  return urt_loop_read(pr->l, tick, out);
}
static void h_tick_done(void *ctx, uint64_t tick, bool running) {
  probe *pr = ctx;
  urt_loop_note_program_slice(pr->l, running ? tick : 0);
}
static void h_message(void *ctx, const urt_script_msg_t *m) {
  (void)ctx;
  fprintf(stderr, "script: %s\n", m->text);
}

// a quintic Hermite from A to B over 2 s, sampled at 200 points of 10 ms; each point runs as
// a quintic from the controller's target (get_joint_positions) with the last commanded speed
// and acceleration, one speedj per controller period and the rest of the 10 ms at the end
static const char *kProgram =
    "def stream():\n"
    "  st = get_steptime()\n"
    "  qa = [-1.57, -1.57, 0.0, -1.57, 0.0, 0.0]\n"
    "  qb = [-1.57, -1.20, 0.5, -1.57, 0.0, 0.0]\n"
    "  d = qb - qa\n"
    "  vq = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n"
    "  aq = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n"
    "  def max_abs(l):\n"
    "    m = 0.0\n"
    "    k = 0\n"
    "    while k < 6:\n"
    "      if norm(l[k]) > m:\n"
    "        m = norm(l[k])\n"
    "      end\n"
    "      k = k + 1\n"
    "    end\n"
    "    return m\n"
    "  end\n"
    "  def step(c1, c2, c3, c4, c5, tt, dt):\n"
    "    last = vq\n"
    "    vq = c1 + 2.0 * tt * c2 + 3.0 * pow(tt, 2) * c3 + 4.0 * pow(tt, 3) * c4 + 5.0 * pow(tt, 4) * c5\n"
    "    aq = 2.0 * c2 + 6.0 * tt * c3 + 12.0 * pow(tt, 2) * c4 + 20.0 * pow(tt, 3) * c5\n"
    "    speedj(vq, max_abs((vq - last) / dt), dt)\n"
    "  end\n"
    "  i = 1\n"
    "  T = 0.009999999776482582\n"
    "  while i <= 200:\n"
    "    s = i / 200.0\n"
    "    qe = qa + d * (10.0 * pow(s, 3) - 15.0 * pow(s, 4) + 6.0 * pow(s, 5))\n"
    "    ve = d * ((30.0 * pow(s, 2) - 60.0 * pow(s, 3) + 30.0 * pow(s, 4)) / 2.0)\n"
    "    ae = d * ((60.0 * s - 180.0 * pow(s, 2) + 120.0 * pow(s, 3)) / 4.0)\n"
    "    q0 = get_joint_positions()\n"
    "    c1 = vq\n"
    "    c2 = 0.5 * aq\n"
    "    c3 = (-20.0 * q0 + 20.0 * qe - 3.0 * aq * T * T + ae * T * T - 12.0 * vq * T - 8.0 * ve * T) / (2.0 * pow(T, 3))\n"
    "    c4 = (30.0 * q0 - 30.0 * qe + 3.0 * aq * T * T - 2.0 * ae * T * T + 16.0 * vq * T + 14.0 * ve * T) / (2.0 * pow(T, 4))\n"
    "    c5 = (-12.0 * q0 + 12.0 * qe - aq * T * T + ae * T * T - 6.0 * vq * T - 6.0 * ve * T) / (2.0 * pow(T, 5))\n"
    "    tt = 0.0\n"
    "    while T - tt > st:\n"
    "      tt = tt + st\n"
    "      step(c1, c2, c3, c4, c5, tt, st)\n"
    "    end\n"
    "    step(c1, c2, c3, c4, c5, T, T - tt)\n"
    "    i = i + 1\n"
    "  end\n"
    "  stopj(2.0)\n"
    "  q = get_joint_positions()\n"
    "  textmsg(\"end \", q)\n"
    "end\n";

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: stream_late_probe CONFIG SEED P SLIDER PERIOD [CSV]\n");
    return 2;
  }
  const char *ov[] = {"sensors.noise=false", NULL};
  urt_model_t *m = NULL;
  char err[512];
  if (urt_model_load(argv[1], ov, &m, err, sizeof err) != 0) {
    fprintf(stderr, "%s\n", err);
    return 2;
  }
  probe pr = {.seed = (unsigned)atoi(argv[2]), .p_late = atof(argv[3])};
  double slider = atof(argv[4]);
  urt_loop_config_t cfg = {.period = atof(argv[5]), .pacing = URT_PACING_LOCKSTEP, .powered = 1};
  const double qa[URT_NJ] = {-1.57, -1.57, 0.0, -1.57, 0.0, 0.0};
  if (urt_loop_create(m, &cfg, qa, &pr.l, err, sizeof err) != 0) {
    fprintf(stderr, "%s\n", err);
    return 2;
  }
  pr.producer = urt_loop_add_producer(pr.l, "probe");
  pr.csv = argc > 6 ? fopen(argv[6], "w") : NULL;
  urt_loop_start(pr.l);
  urt_ctrl_cmd_t sl = {.kind = URT_CTRL_SET_SPEED_SLIDER, .value = slider};
  urt_loop_submit(pr.l, pr.producer, &sl);
  run_to(&pr, 10);
  pr.seen = 10;
  memset(pr.qdd_max, 0, sizeof pr.qdd_max);
  memset(pr.moment_max, 0, sizeof pr.moment_max);
  urt_script_host_t host = {.ctx = &pr, .submit = h_submit, .wait_tick = h_wait_tick,
                            .snapshot = h_snapshot, .message = h_message,
                            .snapshot_at = h_snapshot_at, .tick_done = h_tick_done};
  us_prog *p = NULL;
  us_err e;
  if (urt__us_parse(kProgram, strlen(kProgram), &p, &e) != 0) {
    fprintf(stderr, "parse %u:%u %s\n", e.line, e.column, e.text);
    return 2;
  }
  uint64_t motion_id = 0, late = 0, late_max = 0;
  us_hooks hk = {.host = &host, .motion_id = &motion_id, .step_budget = 200000,
                 .wait_timeout_ms = 100, .late_slices = &late, .late_max = &late_max};
  int rc = urt__us_run(p, &hk, &e);
  uint64_t ticks = urt_loop_latest_tick(pr.l);
  urt_loop_grant(pr.l, 1u << 30);  // let the loop run free so that it can stop
  urt_loop_stop(pr.l);
  printf("{\"rc\": %d, \"error\": \"%s\", \"ticks\": %llu, \"late_slices\": %llu, \"late_max\": %llu, "
         "\"pstop\": %d, \"qdd_max\": [%.3f, %.3f, %.3f], \"moment_max\": [%.1f, %.1f, %.1f]}\n",
         rc, rc ? e.text : "", (unsigned long long)ticks, (unsigned long long)late,
         (unsigned long long)late_max, pr.pstop, pr.qdd_max[0], pr.qdd_max[1], pr.qdd_max[2],
         pr.moment_max[0], pr.moment_max[1], pr.moment_max[2]);
  if (pr.csv) fclose(pr.csv);
  urt__us_prog_free(p);
  urt_loop_destroy(pr.l);
  urt_model_free(m);
  return 0;
}
