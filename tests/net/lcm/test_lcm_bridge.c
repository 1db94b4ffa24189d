/* SPDX-License-Identifier: Apache-2.0
 * tests/net/lcm/test_lcm_bridge.c — the bridge's threads over a fake tick source and real
 * udpm on this host (ttl=0, a port and channels unique to this process): every tick published
 * and counted, lost ticks counted, drive decimation, commands checked, submitted and granted,
 * bounded stop. */
#define _GNU_SOURCE
#include <lcm/lcm.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "test_support.h"
#include "udp_drops.h"
#include "urt/errors.h"
#include "urt/net/lcm_bridge.h"
#include "urt/net/lcm_sender.h"

//---- fake source ------------------------------------------------------------------------------

#define FAKE_DRIVE_HISTORY 100000

typedef struct fake {
  pthread_mutex_t mu;
  pthread_cond_t cv;
  uint64_t newest;            /* newest tick                     */
  uint64_t newest_drive;      /* newest drive sample             */
  double period, drive_dt;
  urt_ctrl_cmd_t cmds[64];
  int ncmd;
  int refuse_submit;          /* 1: submit returns false (ring full) */
  uint64_t granted;
} fake_t;

static uint64_t fake_wait(void *ctx, uint64_t after, int ms) {
  fake_t *f = ctx;
  struct timespec dl;
  clock_gettime(CLOCK_REALTIME, &dl);
  dl.tv_nsec += (long)ms * 1000000L;
  dl.tv_sec += dl.tv_nsec / 1000000000L;
  dl.tv_nsec %= 1000000000L;
  pthread_mutex_lock(&f->mu);
  while (f->newest <= after && ms > 0) {
    if (pthread_cond_timedwait(&f->cv, &f->mu, &dl) != 0) {
      break;
    }
  }
  uint64_t n = f->newest;
  pthread_mutex_unlock(&f->mu);
  return n;
}

static int fake_read(void *ctx, uint64_t tick, urt_snapshot_t *out) {
  fake_t *f = ctx;
  pthread_mutex_lock(&f->mu);
  uint64_t newest = f->newest;
  pthread_mutex_unlock(&f->mu);
  if (tick == 0 || tick > newest) {
    return URT_EAGAIN;
  }
  if (tick + URT_LOOP_HISTORY <= newest) {
    return URT_ERANGE;
  }
  memset(out, 0, sizeof *out);
  out->tick = tick;
  out->period = f->period;
  out->time = tick * f->period;
  out->q[0] = 0.001 * tick;
  out->robot_mode = URT_ROBOT_MODE_RUNNING;
  return 0;
}

static uint64_t fake_latest_drive(void *ctx) {
  fake_t *f = ctx;
  pthread_mutex_lock(&f->mu);
  uint64_t n = f->newest_drive;
  pthread_mutex_unlock(&f->mu);
  return n;
}

static int fake_read_drive(void *ctx, uint64_t seq, urt_drive_sample_t *out) {
  fake_t *f = ctx;
  uint64_t newest = fake_latest_drive(ctx);
  if (seq == 0 || seq > newest) {
    return URT_EAGAIN;
  }
  if (seq + FAKE_DRIVE_HISTORY <= newest) {
    return URT_ERANGE;
  }
  memset(out, 0, sizeof *out);
  out->seq = seq;
  out->time = seq * f->drive_dt;
  return 0;
}

static bool fake_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  fake_t *f = ctx;
  pthread_mutex_lock(&f->mu);
  bool ok = !f->refuse_submit && f->ncmd < 64;
  if (ok) {
    f->cmds[f->ncmd++] = *cmd;
  }
  pthread_mutex_unlock(&f->mu);
  return ok;
}

static void fake_grant(void *ctx, uint64_t n) {
  fake_t *f = ctx;
  pthread_mutex_lock(&f->mu);
  f->granted += n;
  pthread_mutex_unlock(&f->mu);
}

static void fake_set(fake_t *f, uint64_t newest, uint64_t newest_drive) {
  pthread_mutex_lock(&f->mu);
  f->newest = newest;
  f->newest_drive = newest_drive;
  pthread_cond_broadcast(&f->cv);
  pthread_mutex_unlock(&f->mu);
}

static urt_lcm_source_t fake_source(fake_t *f) {
  urt_lcm_source_t s = {f,           fake_wait,  fake_read, fake_latest_drive, fake_read_drive,
                        fake_submit, fake_grant, NULL,      NULL};
  return s;
}

static void fake_init(fake_t *f) {
  memset(f, 0, sizeof *f);
  pthread_mutex_init(&f->mu, NULL);
  pthread_cond_init(&f->cv, NULL);
  f->period = 0.002;
  f->drive_dt = 0.0005;
}

//---- per-run URL and channels -----------------------------------------------------------------

typedef struct names {
  char url[128], status[64], drive[64], command[64];
} names_t;

// a port and channel names of this process, so parallel runs never cross
static names_t unique_names(int k) {
  names_t n;
  int pid = (int)getpid();
  snprintf(n.url, sizeof n.url, "udpm://239.255.76.67:%d?" UDP_DROPS_URL_OPTIONS,
           10000 + (pid * 7 + k) % 20000);
  snprintf(n.status, sizeof n.status, "URTWIN_STATUS_T%d_%d", pid, k);
  snprintf(n.drive, sizeof n.drive, "URTWIN_DRIVE_T%d_%d", pid, k);
  snprintf(n.command, sizeof n.command, "URTWIN_COMMAND_T%d_%d", pid, k);
  return n;
}

static urt_lcm_config_t config_for(const names_t *n) {
  urt_lcm_config_t c;
  urt_lcm_config_default(&c);
  c.url = n->url;
  c.status_channel = n->status;
  c.drive_channel = n->drive;
  c.command_channel = n->command;
  return c;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

// poll a bridge counter until it reaches want or the timeout passes
#define WAIT_FOR(b, field, want, timeout)                  \
  do {                                                     \
    double t_end_ = now_s() + (timeout);                   \
    urt_lcm_stats_t st_;                                   \
    for (;;) {                                             \
      urt_lcm_bridge_get_stats((b), &st_);                 \
      if (st_.field >= (want) || now_s() > t_end_) break;  \
      sleep_s(0.002);                                      \
    }                                                      \
  } while (0)

// until n commands have been handled to the end (accepted, rejected or dropped): cmd_received
// counts a command as it arrives, before the submit that the test's refusal switch decides
static void wait_handled(urt_lcm_bridge_t *b, uint64_t n, double timeout) {
  double t_end = now_s() + timeout;
  urt_lcm_stats_t st;
  for (;;) {
    urt_lcm_bridge_get_stats(b, &st);
    if (st.cmd_accepted + st.cmd_rejected + st.cmd_dropped >= n || now_s() > t_end) break;
    sleep_s(0.002);
  }
}

//---- a status listener on its own thread ------------------------------------------------------

typedef struct listener {
  lcm_t *lcm;
  urtwin_lcmt_urtwin_status_subscription_t *sub;
  pthread_t thread;
  atomic_int stop;
  long count, gaps, disorder;  // disorder: a tick not after the one before (repeated, reordered)
  int64_t first_tick, last_tick;
  double last_q0;
} listener_t;

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch,
                      const urtwin_lcmt_urtwin_status *m, void *user) {
  listener_t *l = user;
  if (l->count == 0) {
    l->first_tick = m->tick;
  } else if (m->tick <= l->last_tick) {
    l->disorder++;
  } else if (m->tick != l->last_tick + 1) {
    l->gaps++;
  }
  l->last_tick = m->tick;
  l->last_q0 = m->q_actual[0];
  l->count++;
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
  l->lcm = lcm_create(n->url);
  assert_non_null(l->lcm);
  l->sub = urtwin_lcmt_urtwin_status_subscribe(l->lcm, n->status, on_status, l);
  assert_non_null(l->sub);
  urtwin_lcmt_urtwin_status_subscription_set_queue_capacity(l->sub, 1000);
  assert_int_equal(pthread_create(&l->thread, NULL, listen_main, l), 0);
}

static void listener_stop(listener_t *l) {
  atomic_store(&l->stop, 1);
  pthread_join(l->thread, NULL);
  urtwin_lcmt_urtwin_status_unsubscribe(l->lcm, l->sub);
  lcm_destroy(l->lcm);
}

//---- tests ------------------------------------------------------------------------------------

typedef struct ticker {
  fake_t *f;
  double period;
  int n;
} ticker_t;

// the fake physics: one tick per period on an absolute clock, as the loop's tick pacing does
static void *ticker_main(void *arg) {
  ticker_t *t = arg;
  struct timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (int k = 1; k <= t->n; ++k) {
    next.tv_nsec += (long)(t->period * 1e9);
    if (next.tv_nsec >= 1000000000L) {
      next.tv_sec++;
      next.tv_nsec -= 1000000000L;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    fake_set(t->f, (uint64_t)k, (uint64_t)k * 4);
  }
  return NULL;
}

static void test_lcm_bridge__publishes_every_tick_at_the_controller_rate(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(1);
  urt_lcm_config_t cfg = config_for(&n);
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  char err[256] = "";
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), 0);

  listener_t l;
  listener_start(&l, &n);
  sleep_s(0.05);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  sleep_s(0.05);  // the publisher starts at the newest tick: let it start before tick 1
  long drops0 = udp_drops_now();

  // 1 s at 500 Hz
  ticker_t t = {&f, 0.002, 500};
  pthread_t th;
  double t0 = now_s();
  assert_int_equal(pthread_create(&th, NULL, ticker_main, &t), 0);
  pthread_join(th, NULL);
  double elapsed = now_s() - t0;
  WAIT_FOR(b, last_tick, 500, 1.0);
  sleep_s(0.05);
  listener_stop(&l);
  long dropped = udp_drops_now() - drops0;

  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(b, &st);
  urt_lcm_bridge_destroy(b);
  printf("# 500 ticks in %.3f s: sent %lu, received %ld (ticks %ld..%ld), gaps %ld, "
         "drive sent %lu; the kernel dropped %ld datagrams meanwhile\n", elapsed,
         (unsigned long)st.status_sent, l.count, (long)l.first_tick, (long)l.last_tick, l.gaps,
         (unsigned long)st.drive_sent, dropped);
  assert_int_equal(st.status_sent, 500);
  assert_int_equal(st.ticks_lost, 0);
  assert_int_equal(st.publish_errors, 0);
  // every status received once and in order, but for what loopback UDP dropped (udp_drops.h)
  assert_int_equal(l.disorder, 0);
  assert_true(l.count <= 500);
  assert_true(500 - l.count <= dropped);
  if (l.count == 500) {
    assert_int_equal(l.gaps, 0);
    assert_int_equal(l.last_tick, 500);
    assert_true(fabs(l.last_q0 - 0.5) < 1e-12);
  }
  assert_int_equal(st.drive_sent, 2000);  // 4 drive samples a tick, drive_rate 0: all
}

static void test_lcm_bridge__counts_ticks_lost_behind_the_history(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(2);
  urt_lcm_config_t cfg = config_for(&n);
  cfg.drive_channel = "";
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  fake_set(&f, 1, 0);
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, NULL, 0), 0);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  WAIT_FOR(b, status_sent, 1, 1.0);

  // the loop runs 2000 ticks ahead at once: ticks 2 .. 2000-HISTORY are gone
  fake_set(&f, 2000, 0);
  WAIT_FOR(b, last_tick, 2000, 2.0);
  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(b, &st);
  urt_lcm_bridge_destroy(b);
  assert_int_equal(st.last_tick, 2000);
  assert_true(st.ticks_lost >= 2000 - URT_LOOP_HISTORY - 1);
  assert_int_equal(st.status_sent + st.ticks_lost, 2000);  // each tick either sent or counted
  assert_int_equal(st.drive_sent, 0);
}

static void test_lcm_bridge__decimates_drive_messages_by_sample_time(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(3);
  urt_lcm_config_t cfg = config_for(&n);
  cfg.status_channel = "";
  cfg.drive_rate = 500;  // samples every 0.5 ms: one in four
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  fake_set(&f, 1, 1);  // the publisher starts at the newest sample
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, NULL, 0), 0);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  sleep_s(0.05);
  fake_set(&f, 1, 4000);  // 2 s of drive samples
  sleep_s(0.3);
  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(b, &st);
  urt_lcm_bridge_destroy(b);
  printf("# drive: sent %lu, lost %lu, errors %lu\n", (unsigned long)st.drive_sent,
         (unsigned long)st.drive_lost, (unsigned long)st.publish_errors);
  assert_int_equal(st.status_sent, 0);
  assert_true(st.drive_sent >= 999 && st.drive_sent <= 1001);
  assert_int_equal(st.drive_lost, 0);
}

static void publish_command(lcm_t *lcm, const char *ch, int nj, double q0) {
  double q[6] = {q0, -1.5, 1.5, -1.5, -1.5, 0}, tau[6] = {0, 0, 0, 0, 0, 1};
  urtwin_lcmt_urtwin_command c = {.utime = 1, .num_joints = nj, .joint_position = q,
                                  .num_velocities = 0, .joint_velocity = NULL,
                                  .num_torques = 6, .joint_torque = tau};
  assert_int_equal(urtwin_lcmt_urtwin_command_publish(lcm, ch, &c), 0);
}

static void test_lcm_bridge__submits_checked_commands_and_grants_in_lockstep(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(4);
  urt_lcm_config_t cfg = config_for(&n);
  cfg.lockstep = 1;
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, NULL, 0), 0);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  assert_int_equal(f.granted, 1);  // the first tick, for the first status
  sleep_s(0.05);

  // three good commands around a malformed one (5 joints) and one the ring refuses
  lcm_t *lcm = lcm_create(n.url);
  assert_non_null(lcm);
  publish_command(lcm, n.command, 6, 0.1);
  publish_command(lcm, n.command, 5, 0.2);
  publish_command(lcm, n.command, 6, 0.3);
  wait_handled(b, 3, 1.0);
  pthread_mutex_lock(&f.mu);
  f.refuse_submit = 1;
  pthread_mutex_unlock(&f.mu);
  publish_command(lcm, n.command, 6, 0.4);
  wait_handled(b, 4, 1.0);
  pthread_mutex_lock(&f.mu);
  f.refuse_submit = 0;
  pthread_mutex_unlock(&f.mu);
  publish_command(lcm, n.command, 6, 0.5);
  wait_handled(b, 5, 1.0);
  lcm_destroy(lcm);

  urt_lcm_stats_t st;
  urt_lcm_bridge_get_stats(b, &st);
  urt_lcm_bridge_destroy(b);
  assert_int_equal(st.cmd_received, 5);
  assert_int_equal(st.cmd_accepted, 3);
  assert_int_equal(st.cmd_rejected, 1);
  assert_int_equal(st.cmd_dropped, 1);
  assert_int_equal(f.ncmd, 3);
  assert_int_equal(f.granted, 1 + 3);
  double want[3] = {0.1, 0.3, 0.5};
  for (int k = 0; k < 3; ++k) {
    assert_int_equal(f.cmds[k].kind, URT_CTRL_DIRECT);
    assert_int_equal(f.cmds[k].id, (uint64_t)k + 1);  // ids increase, none spent on refusals
    assert_true(f.cmds[k].q[0] == want[k]);
    assert_true(f.cmds[k].tau[5] == 1.0 && f.cmds[k].qd[0] == 0.0);
  }
}

static void test_lcm_bridge__never_grants_outside_lockstep(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(5);
  urt_lcm_config_t cfg = config_for(&n);
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, NULL, 0), 0);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  sleep_s(0.05);
  lcm_t *lcm = lcm_create(n.url);
  publish_command(lcm, n.command, 6, 0.1);
  WAIT_FOR(b, cmd_accepted, 1, 1.0);
  lcm_destroy(lcm);
  urt_lcm_bridge_destroy(b);
  assert_int_equal(f.ncmd, 1);
  assert_int_equal(f.granted, 0);
}

static void test_lcm_bridge__stops_within_a_bound(void **state) {
  fake_t f;
  fake_init(&f);
  names_t n = unique_names(6);
  urt_lcm_config_t cfg = config_for(&n);
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, NULL, 0), 0);
  assert_int_equal(urt_lcm_bridge_start(b), 0);
  assert_int_equal(urt_lcm_bridge_start(b), URT_EINVAL);
  sleep_s(0.05);
  double t0 = now_s();
  urt_lcm_bridge_stop(b);
  double dt = now_s() - t0;
  urt_lcm_bridge_stop(b);  // idempotent
  urt_lcm_bridge_destroy(b);
  printf("# stop took %.1f ms\n", dt * 1e3);
  assert_true(dt < 0.2);
}

static void test_lcm_bridge_create__refuses_bad_config(void **state) {
  fake_t f;
  fake_init(&f);
  urt_lcm_source_t src = fake_source(&f);
  urt_lcm_bridge_t *b = NULL;
  urt_lcm_config_t cfg;
  char err[256] = "";

  urt_lcm_config_default(&cfg);
  cfg.url = "nosuchprovider://x";
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), URT_EIO);
  assert_null(b);
  assert_non_null(strstr(err, "nosuchprovider"));

  urt_lcm_config_default(&cfg);
  cfg.drive_rate = -1;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), URT_EINVAL);
  cfg.drive_rate = NAN;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), URT_EINVAL);

  urt_lcm_config_default(&cfg);
  cfg.status_channel = "URTWIN_STATUS_WITH_A_NAME_FAR_TOO_LONG_FOR_LCM_WHICH_STOPS_AT_63_CHARS";
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), URT_EINVAL);
  assert_null(b);
  assert_non_null(strstr(err, "63"));

  urt_lcm_config_default(&cfg);
  src.submit = NULL;
  assert_int_equal(urt_lcm_bridge_create_source(&src, &cfg, &b, err, sizeof err), URT_EINVAL);
  assert_null(b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lcm_bridge__publishes_every_tick_at_the_controller_rate),
      cmocka_unit_test(test_lcm_bridge__counts_ticks_lost_behind_the_history),
      cmocka_unit_test(test_lcm_bridge__decimates_drive_messages_by_sample_time),
      cmocka_unit_test(test_lcm_bridge__submits_checked_commands_and_grants_in_lockstep),
      cmocka_unit_test(test_lcm_bridge__never_grants_outside_lockstep),
      cmocka_unit_test(test_lcm_bridge__stops_within_a_bound),
      cmocka_unit_test(test_lcm_bridge_create__refuses_bad_config),
  };
  return cmocka_run_group_tests_name("net/lcm/bridge", tests, NULL, NULL);
}
