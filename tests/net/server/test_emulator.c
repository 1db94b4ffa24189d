/* SPDX-License-Identifier: Apache-2.0
 * tests/net/server/test_emulator.c — the TCP servers in-process around a real hard loop: every
 * 30003 packet carries exactly the state the loop published for its tick, and the primary port
 * opens with the version message. */
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
#include "urt/core.h"
#include "urt/loop.h"
#include "urt/net/emulator.h"

static const char *kHost = "127.0.0.1";
static int g_offset;

static int connect_to(int port) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
  inet_pton(AF_INET, kHost, &sa.sin_addr);
  struct timeval tv = {.tv_sec = 2};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  if (connect(fd, (struct sockaddr *)&sa, sizeof sa) != 0) {
    close(fd);
    return -1;
  }
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

static double be_double(const uint8_t *p) {
  uint64_t u = 0;
  for (int i = 0; i < 8; i++) {
    u = (u << 8) | p[i];
  }
  double d;
  memcpy(&d, &u, sizeof d);
  return d;
}

static uint32_t be_u32(const uint8_t *p) {
  return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

typedef struct fixture {
  urt_model_t *m;
  urt_loop_t *loop;
  urt_emulator_t *emu;
} fixture_t;

static int setup(void **state) {
  static fixture_t f;
  f.m = urt_test_model(NULL);
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  char err[256];
  if (urt_loop_create(f.m, &lc, NULL, &f.loop, err, sizeof err) != 0) {
    return -1;
  }
  // a port offset of our own so parallel test runs do not collide
  g_offset = 20000 + (getpid() % 500) * 20;
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = g_offset};
  if (urt_version_parse("5.19", &ec.version) != 0 ||
      urt_emulator_create(f.loop, &ec, &f.emu, err, sizeof err) != 0) {
    fprintf(stderr, "%s\n", err);
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

// Two seconds of 30003: every packet is 1116 bytes, consecutive ticks, and its q, target q and
// currents are bit-for-bit the loop's snapshot of that tick.
static void test_emulator__rt_packets_carry_the_loops_state(void **state) {
  fixture_t *f = *state;
  int fd = connect_to(30003 + g_offset);
  assert_true(fd >= 0);
  uint8_t pkt[1116];
  urt_snapshot_t s;
  double last_time = -1;
  int n = 0, mismatches = 0, gaps = 0, checked = 0;
  while (n < 1000) {
    assert_int_equal(recv_all(fd, pkt, 4), 0);
    assert_int_equal(be_u32(pkt), 1116);
    assert_int_equal(recv_all(fd, pkt + 4, 1112), 0);
    double t = be_double(pkt + 4);
    if (last_time >= 0 && fabs(t - last_time - 0.002) > 1e-9) {
      gaps++;
    }
    last_time = t;
    uint64_t tick = (uint64_t)llround(t / 0.002);
    if (urt_loop_read(f->loop, tick, &s) == 0) {
      checked++;
      for (int j = 0; j < URT_NJ; j++) {
        if (be_double(pkt + 252 + 8 * j) != s.q[j] || be_double(pkt + 12 + 8 * j) != s.q_target[j] ||
            be_double(pkt + 348 + 8 * j) != s.i_actual[j]) {
          mismatches++;
        }
      }
    }
    n++;
  }
  close(fd);
  print_message("%d packets, %d compared with the loop's snapshot, %d mismatches, %d gaps\n", n,
                checked, mismatches, gaps);
  assert_int_equal(gaps, 0);
  assert_int_equal(mismatches, 0);
  assert_true(checked > 900);
}

// The primary and secondary ports open with the VERSION message (ROBOT_MESSAGE 20, subtype 3).
static void test_emulator__primary_starts_with_version(void **state) {
  (void)state;
  for (int port = 30001; port <= 30002; port++) {
    int fd = connect_to(port + g_offset);
    assert_true(fd >= 0);
    uint8_t hdr[5], body[256];
    assert_int_equal(recv_all(fd, hdr, 5), 0);
    uint32_t size = be_u32(hdr);
    assert_int_equal(hdr[4], 20);
    assert_true(size > 15 && size < 256);
    assert_int_equal(recv_all(fd, body, size - 5), 0);
    assert_int_equal(body[9], 3);                   // VERSION
    assert_memory_equal(body + 11, "URControl", 9);
    assert_int_equal(body[20], 5);                  // major
    assert_int_equal(body[21], 19);                 // minor
    close(fd);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_emulator__rt_packets_carry_the_loops_state),
      cmocka_unit_test(test_emulator__primary_starts_with_version),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
