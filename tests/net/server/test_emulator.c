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

static const char *kHost;  // urt_test_host: one of this process, UR's own ports
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
  // an address of our own so parallel test runs do not collide (urt_test_host)
  kHost = urt_test_host(1, 1);
  g_offset = 0;
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
  if (!f) {
    return 0;  // setup failed (e.g. a port in use): nothing to free, no crash on top
  }
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

// Read the dashboard's greeting line: 1 when it came, 0 on an orderly close first.
static int dashboard_greeted(int fd) {
  char buf[128];
  size_t got = 0;
  while (got < sizeof buf - 1) {
    ssize_t r = recv(fd, buf + got, sizeof buf - 1 - got, 0);
    if (r <= 0) {
      return 0;
    }
    got += (size_t)r;
    if (memchr(buf, '\n', got)) {
      buf[got] = 0;
      return strstr(buf, "Connected: Universal Robots Dashboard Server") != NULL;
    }
  }
  return 0;
}

// A second emulator with a cap of 2 clients per port: the third dashboard client is accepted and
// closed without a greeting (counted), 30003 keeps its own count, and once a client leaves, a
// new one gets in.
static void test_emulator__clients_beyond_the_cap_are_closed(void **state) {
  fixture_t *f = *state;
  int offset = 100;  // beside the fixture's emulator on the same address
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = offset, .max_clients = 2};
  assert_int_equal(urt_version_parse("5.19", &ec.version), 0);
  urt_emulator_t *emu = NULL;
  urt_loop_t *loop = NULL;
  char err[256];
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  assert_int_equal(urt_loop_create(f->m, &lc, NULL, &loop, err, sizeof err), 0);
  assert_int_equal(urt_emulator_create(loop, &ec, &emu, err, sizeof err), 0);
  urt_loop_start(loop);
  assert_int_equal(urt_emulator_start(emu), 0);
  int a = connect_to(29999 + offset), b = connect_to(29999 + offset);
  assert_true(a >= 0 && b >= 0);
  assert_int_equal(dashboard_greeted(a), 1);
  assert_int_equal(dashboard_greeted(b), 1);
  int c = connect_to(29999 + offset);  // the kernel completes the handshake; urtwin closes it
  assert_true(c >= 0);
  assert_int_equal(dashboard_greeted(c), 0);
  close(c);
  int rt1 = connect_to(30003 + offset), rt2 = connect_to(30003 + offset);  // another port's cap
  uint8_t hdr[4];
  assert_int_equal(recv_all(rt1, hdr, 4), 0);
  assert_int_equal(recv_all(rt2, hdr, 4), 0);
  urt_emulator_stats_t st;
  urt_emulator_get_stats(emu, &st);
  assert_int_equal(st.refused_cap, 1);
  assert_int_equal(st.clients, 4);
  close(a);
  int greeted = 0;
  for (int attempt = 0; attempt < 50 && !greeted; attempt++) {  // the close takes a moment
    int d = connect_to(29999 + offset);
    greeted = d >= 0 && dashboard_greeted(d);
    close(d);
    if (!greeted) {
      usleep(20000);
    }
  }
  assert_int_equal(greeted, 1);
  close(b);
  close(rt1);
  close(rt2);
  urt_emulator_destroy(emu);
  urt_loop_destroy(loop);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_emulator__rt_packets_carry_the_loops_state),
      cmocka_unit_test(test_emulator__primary_starts_with_version),
      cmocka_unit_test(test_emulator__clients_beyond_the_cap_are_closed),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
