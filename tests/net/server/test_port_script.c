/* SPDX-License-Identifier: Apache-2.0
 * tests/net/server/test_port_script.c — what the primary port (net/server/port_script.c) reports
 * around a protective stop, in-process around a real hard loop, read as URCL reads it
 * (external_control.md §1.3): no SAFETY_MODE message before the first change; on a program's
 * protective stop one SAFETY_MODE(PROTECTIVE_STOP) and exactly one ERROR_CODE C209A0 WARNING;
 * the robot state with the flag in the same tick as that message; `set unlock protective stop`
 * sent right after the stop takes effect at once (the dashboard keeps the 5 s rule: URCL's
 * primary-client tests expect this of URSim, port_script.c); on unlock SAFETY_MODE(NORMAL)
 * arrives before the robot state that clears the flag. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/controller.h"
#include "urt/core.h"
#include "urt/loop.h"
#include "urt/net/emulator.h"
#include "urt/net/primary.h"

static const char *kHost;  // urt_test_host: one of this process, UR's own ports
static int g_offset;

typedef struct fixture {
  urt_model_t *m;
  urt_loop_t *loop;
  urt_emulator_t *emu;
  int producer;
} fixture_t;

static int setup(void **state) {
  static fixture_t f;
  f.m = urt_test_model(NULL);
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  char err[256];
  if (urt_loop_create(f.m, &lc, NULL, &f.loop, err, sizeof err) != 0) {
    return -1;
  }
  kHost = urt_test_host(2, 1);  // an address of our own: parallel runs never collide
  g_offset = 0;
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = g_offset};
  if (urt_version_parse("5.19", &ec.version) != 0 ||
      urt_emulator_create(f.loop, &ec, &f.emu, err, sizeof err) != 0) {
    fprintf(stderr, "%s\n", err);
    return -1;
  }
  f.producer = urt_loop_add_producer(f.loop, "test");  // stands in for a program's protective_stop()
  if (f.producer < 0) {
    return -1;
  }
  urt_loop_start(f.loop);
  urt_emulator_start(f.emu);
  *state = &f;
  return 0;
}

static int teardown(void **state) {
  fixture_t *f = *state;
  urt_emulator_destroy(f->emu);
  urt_loop_destroy(f->loop);
  urt_model_free(f->m);
  return 0;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int connect_primary(void) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)(30001 + g_offset))};
  inet_pton(AF_INET, kHost, &sa.sin_addr);
  struct timeval tv = {.tv_sec = 2};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  assert_int_equal(connect(fd, (struct sockaddr *)&sa, sizeof sa), 0);
  return fd;
}

static int recv_all(int fd, uint8_t *buf, size_t n) {
  size_t got = 0;
  while (got < n) {
    ssize_t r = recv(fd, buf + got, n - got, 0);
    if (r <= 0) {
      return -1;
    }
    got += (size_t)r;
  }
  return 0;
}

static uint32_t be_u32(const uint8_t *p) {
  return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

/* What one primary package says, as far as these tests care. */
typedef struct event {
  int type;            /* 16 state, 20 message                       */
  int msg_type;        /* ROBOT_MESSAGE subtype                       */
  int safety_mode;     /* SAFETY_MODE message                         */
  int32_t code, arg, level;  /* ERROR_CODE                             */
  int pstopped;        /* ROBOT_STATE: RobotModeData's protective flag */
  double time;         /* RobotModeData's controller time, or a message's timestamp [s] */
  char text[256];      /* TEXT                                        */
} event_t;

static void next_event(int fd, event_t *ev) {
  static uint8_t b[4096];
  memset(ev, 0, sizeof *ev);
  ev->pstopped = -1;
  assert_int_equal(recv_all(fd, b, 5), 0);
  uint32_t size = be_u32(b);
  assert_true(size >= 5 && size < 4092);  // URCL discards packages of 4092 bytes or more
  assert_int_equal(recv_all(fd, b + 5, size - 5), 0);
  ev->type = b[4];
  if (ev->type == URT_PRIMARY_ROBOT_STATE) {
    // the first sub-package is RobotModeData: 8 bytes of time, then 5th flag = protective
    assert_int_equal(b[9], URT_PRIMARY_ROBOT_MODE_DATA);
    ev->pstopped = b[10 + 8 + 4];
    ev->time = (((uint64_t)be_u32(b + 10) << 32) | be_u32(b + 14)) * 1e-6;
  } else if (ev->type == URT_PRIMARY_ROBOT_MESSAGE) {
    const uint8_t *p = b + 5 + 8 + 1;
    ev->time = (((uint64_t)be_u32(b + 5) << 32) | be_u32(b + 9)) * 1e-6;
    ev->msg_type = p[0];
    p++;
    if (ev->msg_type == URT_PRIMARY_MSG_SAFETY_MODE) {
      ev->safety_mode = p[8];
    } else if (ev->msg_type == URT_PRIMARY_MSG_ERROR_CODE) {
      ev->code = (int32_t)be_u32(p);
      ev->arg = (int32_t)be_u32(p + 4);
      ev->level = (int32_t)be_u32(p + 8);
    } else if (ev->msg_type == URT_PRIMARY_MSG_TEXT) {
      size_t n = size - (size_t)(p - b);
      n = n < sizeof ev->text - 1 ? n : sizeof ev->text - 1;
      memcpy(ev->text, p, n);
    }
  }
}

static void submit(fixture_t *f, int kind) {
  urt_ctrl_cmd_t cmd = {.kind = kind};
  assert_true(urt_loop_submit(f->loop, f->producer, &cmd));
}

static void test_port_script__protective_stop_messages_and_an_unlock_at_once(void **state) {
  fixture_t *f = *state;
  int fd = connect_primary();

  // a second of state and messages before anything happens: no SAFETY_MODE message
  event_t ev;
  double t0 = now_s();
  while (now_s() - t0 < 1.0) {
    next_event(fd, &ev);
    assert_false(ev.type == 20 && ev.msg_type == URT_PRIMARY_MSG_SAFETY_MODE);
  }

  // the protective stop: one SAFETY_MODE(PROTECTIVE_STOP), one ERROR_CODE C209A0 WARNING
  submit(f, URT_CTRL_PROTECTIVE_STOP);
  double t_stop = now_s();
  int safety = 0, errors = 0, saw_flag = 0;
  double t_flag = 0.0;  /* controller time of the first state with the flag: the rule's clock */
  double t_safety = -1.0;
  double t_last_flag = 0.0; /* the newest state with the flag */
  while (now_s() - t_stop < 1.0) {
    next_event(fd, &ev);
    if (ev.type == 20 && ev.msg_type == URT_PRIMARY_MSG_SAFETY_MODE) {
      assert_int_equal(ev.safety_mode, URT_SAFETY_MODE_PROTECTIVE_STOP);
      t_safety = ev.time;
      safety++;
    } else if (ev.type == 20 && ev.msg_type == URT_PRIMARY_MSG_ERROR_CODE) {
      assert_int_equal(ev.code, 209);
      assert_int_equal(ev.arg, 0);
      assert_int_equal(ev.level, URT_PRIMARY_REPORT_WARNING);
      errors++;
    } else if (ev.type == 16 && ev.pstopped == 1) {
      if (!saw_flag) t_flag = ev.time;
      saw_flag = 1;
      t_last_flag = ev.time;
    }
  }
  assert_int_equal(safety, 1);
  assert_int_equal(errors, 1);
  assert_true(saw_flag);
  // the state that carries the flag goes out in the message's tick, not at the next 10 Hz one
  // (URCL reads the flag right after it has seen the message)
  print_message("SAFETY_MODE at %.6f s, first state with the flag at %.6f s\n", t_safety, t_flag);
  assert_true(fabs(t_flag - t_safety) < 1.5e-6);

  // an unlock sent right away takes effect at once, not 5 s after the stop: SAFETY_MODE(NORMAL)
  // before the first state with the flag cleared, a few ticks of controller time after the last
  // state that still had it. Judged in controller time; the wall bound only ends a hung run
  const char unlock[] = "set unlock protective stop\n";
  assert_int_equal(send(fd, unlock, sizeof unlock - 1, 0), (ssize_t)(sizeof unlock - 1));
  int normal_seen = 0, cleared = 0;
  double t_cleared = 0.0;
  while (!cleared && now_s() - t_stop < 60.0) {
    next_event(fd, &ev);
    if (ev.type == 20 && ev.msg_type == URT_PRIMARY_MSG_SAFETY_MODE) {
      assert_int_equal(ev.safety_mode, URT_SAFETY_MODE_NORMAL);
      normal_seen++;
    } else if (ev.type == 16 && ev.pstopped == 1) {
      t_last_flag = ev.time;
    } else if (ev.type == 16 && ev.pstopped == 0) {
      assert_int_equal(normal_seen, 1);
      cleared = 1;
      t_cleared = ev.time;
    }
  }
  assert_true(cleared);
  print_message("unlock took effect %.3f s after the stop, %.3f s after the last flagged state\n",
                t_cleared - t_flag, t_cleared - t_last_flag);
  // the flagged states come at 10 Hz: the clear one follows the last of them within a period
  assert_true(t_cleared - t_last_flag <= 0.1 + 1e-6);
  assert_true(t_cleared < t_flag + 5.0);
  close(fd);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_port_script__protective_stop_messages_and_an_unlock_at_once),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
