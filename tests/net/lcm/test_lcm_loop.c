/* SPDX-License-Identifier: Apache-2.0
 * tests/net/lcm/test_lcm_loop.c — the bridge on the real loop and model, over udpm on this
 * host (ttl=0; a port and channels unique to this process): a status message for every
 * controller tick at the controller rate, drive messages at their rate, a command stream that
 * moves the arm, and lockstep (one tick per command, Drake's LcmDrivenLoop). */
#include <lcm/lcm.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "test_model.h"
#include "test_support.h"
#include "udp_drops.h"
#include "urt/core.h"
#include "urt/errors.h"
#include "urt/loop.h"
#include "urt/net/lcm_bridge.h"
#include "urt/net/lcm_sender.h"

#define MAX_TICKS 4096 /* longest run recorded per tick: 8 s at 500 Hz */

static urt_model_t *g_model;

static int setup(void **state) {
  g_model = urt_test_model(NULL);
  return g_model ? 0 : -1;
}

static int teardown(void **state) {
  urt_model_free(g_model);
  return 0;
}

//---- helpers ----------------------------------------------------------------------------------

typedef struct names {
  char url[128], status[64], drive[64], command[64];
} names_t;

static names_t unique_names(int k) {
  names_t n;
  int pid = (int)getpid();
  snprintf(n.url, sizeof n.url, "udpm://239.255.76.67:%d?" UDP_DROPS_URL_OPTIONS,
           10000 + (pid * 7 + 100 + k) % 20000);
  snprintf(n.status, sizeof n.status, "URTWIN_STATUS_L%d_%d", pid, k);
  snprintf(n.drive, sizeof n.drive, "URTWIN_DRIVE_L%d_%d", pid, k);
  snprintf(n.command, sizeof n.command, "URTWIN_COMMAND_L%d_%d", pid, k);
  return n;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// the loop's latest tick and the wall time it was read at, read between two clock readings less
// than 0.2 ms apart (a preempted read is taken again) so that the pair is one instant
static uint64_t tick_at(urt_loop_t *loop, double *t) {
  uint64_t k = 0;
  for (int tries = 0; tries < 1000; ++tries) {
    double ta = now_s();
    k = urt_loop_latest_tick(loop);
    double tb = now_s();
    *t = 0.5 * (ta + tb);
    if (tb - ta < 2e-4) {
      break;
    }
  }
  return k;
}

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

typedef struct rig {
  names_t n;
  urt_loop_t *loop;
  urt_lcm_bridge_t *bridge;
} rig_t;

static void rig_start(rig_t *r, int k, urt_pacing_t pacing, double drive_rate) {
  r->n = unique_names(k);
  urt_loop_config_t lc = {.period = 0.002, .pacing = pacing, .powered = 1,
                          .drive_rate = drive_rate};
  char err[256] = "";
  assert_int_equal(urt_loop_create(g_model, &lc, NULL, &r->loop, err, sizeof err), 0);
  urt_lcm_config_t bc;
  urt_lcm_config_default(&bc);
  bc.url = r->n.url;
  bc.status_channel = r->n.status;
  bc.drive_channel = r->n.drive;
  bc.command_channel = r->n.command;
  bc.lockstep = pacing == URT_PACING_LOCKSTEP;
  int rc = urt_lcm_bridge_create(r->loop, &bc, &r->bridge, err, sizeof err);
  if (rc != 0) {
    fail_msg("bridge: %s (%s)", urt_strerror(rc), err);
  }
}

static void rig_stop(rig_t *r) {
  urt_lcm_bridge_stop(r->bridge);
  urt_loop_stop(r->loop);
  urt_lcm_bridge_destroy(r->bridge);
  urt_loop_destroy(r->loop);
}

//---- a listener on its own thread ---------------------------------------------------------------

typedef struct listener {
  lcm_t *lcm;
  urtwin_lcmt_urtwin_status_subscription_t *sub;
  urtwin_lcmt_urtwin_drive_subscription_t *dsub;
  pthread_t thread;
  atomic_int stop;
  pthread_mutex_t mu;
  // status: how often each tick arrived (ticks beyond MAX_TICKS are not recorded)
  long count, gaps, repeats, disorder;  // disorder: a tick before the one before (reordered)
  int64_t last_tick;
  urtwin_lcmt_urtwin_status last;
  uint8_t tick_seen[MAX_TICKS];
  // drive: arrivals per millisecond of physics time
  long drive_count;
  uint8_t drive_ms_seen[MAX_TICKS * 2];
} listener_t;

// arrivals of ticks in (lo, hi]
static long ticks_seen(const listener_t *l, uint64_t lo, uint64_t hi) {
  long n = 0;
  for (uint64_t k = lo + 1; k <= hi && k < MAX_TICKS; ++k) {
    n += l->tick_seen[k];
  }
  return n;
}

// drive messages with physics time in (lo, hi] milliseconds
static long drive_seen(const listener_t *l, uint64_t lo_ms, uint64_t hi_ms) {
  long n = 0;
  for (uint64_t k = lo_ms + 1; k <= hi_ms && k < 2 * MAX_TICKS; ++k) {
    n += l->drive_ms_seen[k];
  }
  return n;
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch,
                      const urtwin_lcmt_urtwin_status *m, void *user) {
  listener_t *l = user;
  pthread_mutex_lock(&l->mu);
  if (l->count > 0 && m->tick == l->last_tick) {
    l->repeats++;  // lockstep repeats the newest status while idle
    pthread_mutex_unlock(&l->mu);
    return;
  }
  if (l->count > 0 && m->tick < l->last_tick) {
    l->disorder++;
  } else if (l->count > 0 && m->tick != l->last_tick + 1) {
    l->gaps++;
  }
  if (m->tick >= 0 && m->tick < MAX_TICKS) {
    l->tick_seen[m->tick]++;
  }
  l->last_tick = m->tick;
  l->last = *m;
  l->count++;
  pthread_mutex_unlock(&l->mu);
}

static void on_drive(const lcm_recv_buf_t *rbuf, const char *ch,
                     const urtwin_lcmt_urtwin_drive *m, void *user) {
  listener_t *l = user;
  pthread_mutex_lock(&l->mu);
  l->drive_count++;
  int64_t ms = llround(m->time * 1e3);
  if (ms >= 0 && ms < 2 * MAX_TICKS) {
    l->drive_ms_seen[ms]++;
  }
  pthread_mutex_unlock(&l->mu);
}

static void *listen_main(void *arg) {
  listener_t *l = arg;
  while (!atomic_load(&l->stop)) {
    lcm_handle_timeout(l->lcm, 20);
  }
  return NULL;
}

static void listener_start(listener_t *l, const names_t *n) {
  memset(l, 0, sizeof *l);
  pthread_mutex_init(&l->mu, NULL);
  l->lcm = lcm_create(n->url);
  assert_non_null(l->lcm);
  l->sub = urtwin_lcmt_urtwin_status_subscribe(l->lcm, n->status, on_status, l);
  l->dsub = urtwin_lcmt_urtwin_drive_subscribe(l->lcm, n->drive, on_drive, l);
  assert_non_null(l->sub);
  assert_non_null(l->dsub);
  urtwin_lcmt_urtwin_status_subscription_set_queue_capacity(l->sub, 2000);
  urtwin_lcmt_urtwin_drive_subscription_set_queue_capacity(l->dsub, 4000);
  assert_int_equal(pthread_create(&l->thread, NULL, listen_main, l), 0);
}

static void listener_stop(listener_t *l) {
  atomic_store(&l->stop, 1);
  pthread_join(l->thread, NULL);
  urtwin_lcmt_urtwin_status_unsubscribe(l->lcm, l->sub);
  urtwin_lcmt_urtwin_drive_unsubscribe(l->lcm, l->dsub);
  lcm_destroy(l->lcm);
}

static urtwin_lcmt_urtwin_status listener_last(listener_t *l) {
  pthread_mutex_lock(&l->mu);
  urtwin_lcmt_urtwin_status s = l->last;
  pthread_mutex_unlock(&l->mu);
  return s;
}

static void send_command(lcm_t *lcm, const char *ch, const double q[6], const double qd[6]) {
  urtwin_lcmt_urtwin_command c = {.utime = 0, .num_joints = 6, .joint_position = (double *)q,
                                  .num_velocities = 6, .joint_velocity = (double *)qd,
                                  .num_torques = 0, .joint_torque = NULL};
  assert_int_equal(urtwin_lcmt_urtwin_command_publish(lcm, ch, &c), 0);
}

//---- tests ------------------------------------------------------------------------------------

// 2 s of tick pacing: every tick in the window arrives once, in order, at 500 Hz of wall time
// (within the loop's catch-up bound) if no period was missed; drive messages at 1 kHz of
// physics time
static void test_lcm_loop__status_every_tick_at_the_controller_rate(void **state) {
  rig_t r;
  rig_start(&r, 1, URT_PACING_TICK, 1000);
  listener_t l;
  listener_start(&l, &r.n);
  assert_int_equal(urt_loop_start(r.loop), 0);
  assert_int_equal(urt_lcm_bridge_start(r.bridge), 0);
  sleep_s(0.2);
  long drops0 = udp_drops_now();

  // the window: ticks made during 2 s of wall time
  double t0, t1;
  uint64_t k0 = tick_at(r.loop, &t0);
  sleep_s(2.0);
  uint64_t k1 = tick_at(r.loop, &t1);
  sleep_s(0.2);

  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(r.bridge, &st);
  urt_loop_stats_t ls;
  urt_loop_get_stats(r.loop, &ls);
  rig_stop(&r);
  listener_stop(&l);
  long dropped = udp_drops_now() - drops0;
  long in_window = ticks_seen(&l, k0, k1);
  long drive_in_window = drive_seen(&l, 2 * k0, 2 * k1);

  double wall = t1 - t0, ticks = (double)(k1 - k0);
  double rate = ticks / wall;
  print_message("ticks %.0f in %.3f s (%.1f Hz); status in window %ld, total %ld, gaps %ld; "
                "drive in window %ld (%.1f Hz of physics time); lost %lu/%lu; loop overruns "
                "%lu, missed periods %lu, exec max %.0f us; the kernel dropped %ld datagrams\n",
                ticks, wall, rate, in_window, l.count, l.gaps, drive_in_window,
                drive_in_window / (ticks * 0.002), (unsigned long)st.ticks_lost,
                (unsigned long)st.drive_lost, (unsigned long)ls.overruns,
                (unsigned long)ls.missed_periods, ls.exec_max * 1e6, dropped);

  // every tick published and received once, in order, but for what loopback UDP dropped
  // (udp_drops.h: each missing status and drive message among the kernel's drops)
  assert_int_equal(st.ticks_lost, 0);
  assert_int_equal(st.publish_errors, 0);
  assert_int_equal(l.disorder, 0);
  for (uint64_t k = k0 + 1; k <= k1 && k < MAX_TICKS; ++k) {
    assert_true(l.tick_seen[k] <= 1);
  }
  long missing = (long)(k1 - k0) - in_window;
  assert_true(missing >= 0 && missing <= dropped);
  if (dropped == 0) {
    assert_int_equal(l.gaps, 0);
  }
  // drive: one message per millisecond of physics time (±1 %), short by at most the drops left
  double drive_tol = 0.01 * 2.0 * ticks + 1;
  assert_true(drive_in_window <= 2.0 * ticks + drive_tol);
  assert_true(2.0 * ticks - drive_in_window <= drive_tol + (double)(dropped - missing));
  // the controller keeps wall time: with no missed periods the loop is never ahead of its clock
  // and never more than URT_LOOP_CATCH_UP_LIMIT periods behind it, at either end of the window
  // (late ticks under a slow build are caught up, not lost: a rate of 493.5 Hz was measured here
  // with 428 overruns, the window ending 13 ticks behind). Without the catch-up the ticks would
  // fall short by every overrun's lateness
  if (ls.missed_periods == 0) {
    double expected = wall * 500.0;
    print_message("ticks %.0f against %.1f of wall time (bound ±%d)\n", ticks, expected,
                  URT_LOOP_CATCH_UP_LIMIT + 1);
    assert_true(fabs(ticks - expected) <= URT_LOOP_CATCH_UP_LIMIT + 1);
  } else {
    print_message("loop missed periods on this machine: rate not checked\n");
  }
}

// a streamed joint ramp on the command channel (Drake-style, one command per status) moves
// joint 0 by 0.05 rad and the status shows it
static void test_lcm_loop__command_stream_moves_the_arm(void **state) {
  rig_t r;
  rig_start(&r, 2, URT_PACING_TICK, 0);
  listener_t l;
  listener_start(&l, &r.n);
  assert_int_equal(urt_loop_start(r.loop), 0);
  assert_int_equal(urt_lcm_bridge_start(r.bridge), 0);
  sleep_s(0.2);
  urtwin_lcmt_urtwin_status s0 = listener_last(&l);
  assert_true(s0.tick > 0);
  assert_int_equal(s0.robot_mode, URT_ROBOT_MODE_RUNNING);

  // 0.5 s smooth ramp (5th-order, zero speed at both ends), then 0.5 s hold
  lcm_t *lcm = lcm_create(r.n.url);
  assert_non_null(lcm);
  long drops0 = udp_drops_now();
  const double T = 0.5, dq = 0.05;
  double q[6], qd[6];
  for (int k = 1; k <= 500; ++k) {
    double t = k * 0.002, u = t < T ? t / T : 1.0;
    double s = u * u * u * (10 - 15 * u + 6 * u * u);
    double sd = t < T ? 30 * u * u * (1 - u) * (1 - u) / T : 0.0;
    memcpy(q, s0.q_target, sizeof q);
    memset(qd, 0, sizeof qd);
    q[0] += dq * s;
    qd[0] = dq * sd;
    send_command(lcm, r.n.command, q, qd);
    sleep_s(0.002);
  }
  sleep_s(0.1);
  lcm_destroy(lcm);
  urtwin_lcmt_urtwin_status s1 = listener_last(&l);
  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(r.bridge, &st);
  rig_stop(&r);
  listener_stop(&l);
  long dropped = udp_drops_now() - drops0;

  print_message("joint 0: %.5f -> %.5f rad (target %.5f); commands received %lu accepted %lu "
                "rejected %lu dropped %lu; motion %d, safety %d, fault 0x%x; the kernel dropped "
                "%ld datagrams\n",
                s0.q_actual[0], s1.q_actual[0], s1.q_target[0], (unsigned long)st.cmd_received,
                (unsigned long)st.cmd_accepted, (unsigned long)st.cmd_rejected,
                (unsigned long)st.cmd_dropped, s1.motion, s1.safety_mode, s1.ctrl_fault, dropped);
  // every command received and accepted, but for what loopback UDP dropped (udp_drops.h); the
  // hold's commands repeat the end, so a dropped one changes nothing below
  assert_true(st.cmd_received <= 500 && 500 - (long)st.cmd_received <= dropped);
  assert_int_equal(st.cmd_accepted, st.cmd_received);
  assert_int_equal(s1.safety_mode, URT_SAFETY_MODE_NORMAL);
  assert_int_equal(s1.motion, URT_MOTION_DIRECT);
  assert_true(fabs(s1.q_target[0] - (s0.q_target[0] + dq)) < 1e-9);
  assert_true(fabs(s1.q_actual[0] - (s0.q_actual[0] + dq)) < 0.005);
  for (int j = 1; j < 6; ++j) {
    assert_true(fabs(s1.q_actual[j] - s0.q_actual[j]) < 0.005);
  }
}

// lockstep: the bridge grants the first tick, then exactly one per accepted command; a
// malformed command grants nothing
static void test_lcm_loop__lockstep_one_tick_per_command(void **state) {
  rig_t r;
  rig_start(&r, 3, URT_PACING_LOCKSTEP, 0);
  listener_t l;
  listener_start(&l, &r.n);
  assert_int_equal(urt_loop_start(r.loop), 0);
  assert_int_equal(urt_lcm_bridge_start(r.bridge), 0);

  // the first status comes without a command
  double t_end = now_s() + 2.0;
  while (listener_last(&l).tick < 1 && now_s() < t_end) {
    sleep_s(0.002);
  }
  urtwin_lcmt_urtwin_status s0 = listener_last(&l);
  assert_int_equal(s0.tick, 1);

  // 100 commands, each sent after the status it answers (the Drake client loop)
  lcm_t *lcm = lcm_create(r.n.url);
  double qd[6] = {0};
  for (int k = 1; k <= 100; ++k) {
    send_command(lcm, r.n.command, s0.q_target, qd);
    t_end = now_s() + 2.0;
    while (listener_last(&l).tick < k + 1 && now_s() < t_end) {
      sleep_s(0.0005);
    }
    assert_int_equal(listener_last(&l).tick, k + 1);
  }

  // a malformed command: no tick
  urtwin_lcmt_urtwin_command bad = {.num_joints = 5, .joint_position = qd};
  urtwin_lcmt_urtwin_command_publish(lcm, r.n.command, &bad);
  sleep_s(0.2);
  lcm_destroy(lcm);
  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(r.bridge, &st);
  uint64_t ticks = urt_loop_latest_tick(r.loop);
  rig_stop(&r);
  listener_stop(&l);
  assert_int_equal(ticks, 101);
  assert_int_equal(st.cmd_accepted, 100);
  assert_int_equal(st.cmd_rejected, 1);
  assert_int_equal(st.status_sent, 101);
  assert_true(st.status_repeated >= 1);  // idle for 0.2 s after the last command
  assert_int_equal(l.count, 101);
  assert_int_equal(l.gaps, 0);
  assert_true(l.repeats >= 1);
}


// free pacing: the physics runs as fast as it can; the publisher sends every tick or counts it
// as lost, never silently skips one
static void test_lcm_loop__free_pacing_sends_or_counts_every_tick(void **state) {
  rig_t r;
  rig_start(&r, 4, URT_PACING_FREE, 0);
  listener_t l;
  listener_start(&l, &r.n);
  assert_int_equal(urt_lcm_bridge_start(r.bridge), 0);  // before the loop: from tick 1 on
  sleep_s(0.05);
  long drops0 = udp_drops_now();
  assert_int_equal(urt_loop_start(r.loop), 0);
  sleep_s(1.0);
  urt_loop_stop(r.loop);
  uint64_t ticks = urt_loop_latest_tick(r.loop);
  urt_lcm_stats_t st;
  double t_end = now_s() + 2.0;
  do {
    sleep_s(0.01);
    urt_lcm_bridge_get_stats(r.bridge, &st);
  } while (st.status_sent + st.ticks_lost < ticks && now_s() < t_end);
  sleep_s(0.1);
  rig_stop(&r);
  listener_stop(&l);
  long dropped = udp_drops_now() - drops0;
  print_message("free pacing: %lu ticks in 1 s, sent %lu, lost %lu, received %ld; the kernel "
                "dropped %ld datagrams\n", (unsigned long)ticks, (unsigned long)st.status_sent,
                (unsigned long)st.ticks_lost, l.count, dropped);
  assert_true(ticks > 10);  // free pacing runs as fast as it can: under sanitizers that is
                            // below real time; what matters is that every tick is sent or counted
  assert_int_equal(st.status_sent + st.ticks_lost, ticks);
  assert_int_equal(st.last_tick, ticks);
  // every status sent arrives once, in order, but for what loopback UDP dropped (udp_drops.h)
  assert_int_equal(l.disorder, 0);
  assert_true(l.count <= (long)st.status_sent && (long)st.status_sent - l.count <= dropped);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lcm_loop__status_every_tick_at_the_controller_rate),
      cmocka_unit_test(test_lcm_loop__command_stream_moves_the_arm),
      cmocka_unit_test(test_lcm_loop__lockstep_one_tick_per_command),
      cmocka_unit_test(test_lcm_loop__free_pacing_sends_or_counts_every_tick),
  };
  return cmocka_run_group_tests_name("net/lcm/loop", tests, setup, teardown);
}
