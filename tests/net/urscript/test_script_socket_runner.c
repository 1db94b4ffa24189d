/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_socket_runner.c — the runner's side of URScript sockets: a
 * program's sockets close when it ends or is stopped, the old program's before the new program
 * dials (URCL's servers take one client each: external_control.md §2.1, §6), a refused host is
 * a runtime exception naming it, and the allow list's bounds. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fake_host.h"
#include "test_support.h"
#include "urt/errors.h"

static fake_host F;
static urt_script_host_t H;
static urt_runner_t *R;
static int L = -1, port;

static int setup(void **state) {
  fake_init(&F, &H);
  F.tick_sleep_us = 500;  // a blocked program does not spin a core
  urt_runner_config_t cfg = {.step_budget = 20000, .wait_timeout_ms = 1};
  assert_int_equal(urt_runner_create(&H, &cfg, &R), 0);
  L = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
  assert_int_equal(bind(L, (struct sockaddr *)&a, sizeof a), 0);
  assert_int_equal(listen(L, 8), 0);
  socklen_t len = sizeof a;
  getsockname(L, (struct sockaddr *)&a, &len);
  port = ntohs(a.sin_port);
  return 0;
}

static int teardown(void **state) {
  urt_runner_destroy(R);
  R = NULL;
  close(L);
  return 0;
}

static void submit(const char *fmt) {
  char text[1024];
  snprintf(text, sizeof text, fmt, port);
  assert_int_equal(urt_runner_submit(R, text, strlen(text)), 0);
}

/* the next connection to the fixture's port (5 s at most) */
static int accept_one(void) {
  struct pollfd p = {.fd = L, .events = POLLIN};
  assert_int_equal(poll(&p, 1, 5000), 1);
  int fd = accept4(L, NULL, NULL, SOCK_CLOEXEC);
  assert_true(fd >= 0);
  return fd;
}

/* true when the peer closed fd: now (wait_ms 0) or within wait_ms */
static bool closed(int fd, int wait_ms) {
  struct pollfd p = {.fd = fd, .events = POLLIN};
  if (poll(&p, 1, wait_ms) != 1) return false;
  char b;
  return recv(fd, &b, 1, MSG_DONTWAIT) == 0;
}

static void test_socket_runner__program_end_closes_its_sockets(void **state) {
  submit("def p():\n  socket_open(\"127.0.0.1\", %d, \"a\")\n  socket_send_int(5, \"a\")\nend\n");
  int c = accept_one();
  unsigned char b[4];
  assert_int_equal(recv(c, b, 4, MSG_WAITALL), 4);
  assert_memory_equal(b, "\x00\x00\x00\x05", 4);
  assert_true(closed(c, 5000));  // the program never closed it: the runner did
  close(c);
}

static void test_socket_runner__old_program_sockets_close_before_the_new_one_dials(void **state) {
  submit("def a():\n  socket_open(\"127.0.0.1\", %d, \"s\")\n"
         "  socket_read_binary_integer(1, \"s\", 0)\nend\n");
  int a = accept_one();
  assert_false(closed(a, 50));  // a blocks in its read (timeout 0: for ever)
  submit("def b():\n  socket_open(\"127.0.0.1\", %d, \"s\")\n  sleep(10)\nend\n");
  int b = accept_one();
  assert_true(closed(a, 0));    // already closed when b's connection arrived
  assert_false(closed(b, 50));
  urt_runner_stop(R);
  assert_true(closed(b, 5000));  // a stopped program's sockets close too
  assert_true(urt_runner_wait_idle(R, 5000));
  close(a);
  close(b);
}

static void test_socket_runner__refused_host_is_a_runtime_exception(void **state) {
  submit("def r():\n  socket_open(\"192.168.56.101\", %d)\nend\n");
  assert_true(urt_runner_wait_idle(R, 5000));
  bool seen = false;
  for (int k = 0; k < F.n_msg; k++) {
    if (F.msg[k].kind == URT_SCRIPT_MSG_RUNTIME_EXCEPTION) {
      assert_non_null(strstr(F.msg[k].text, "\"192.168.56.101\""));
      assert_int_equal(F.msg[k].line, 2);
      seen = true;
    }
  }
  assert_true(seen);
}

static void test_socket_runner__allow_list_bounds(void **state) {
  const char *hosts[17];
  for (int k = 0; k < 17; k++) hosts[k] = "robot.lab";
  urt_runner_t *r = NULL;
  urt_runner_config_t cfg = {.allow_hosts = hosts, .n_allow_hosts = 17};
  assert_int_equal(urt_runner_create(&H, &cfg, &r), URT_EINVAL);
  assert_null(r);
  cfg.n_allow_hosts = 16;
  assert_int_equal(urt_runner_create(&H, &cfg, &r), 0);
  urt_runner_destroy(r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_socket_runner__program_end_closes_its_sockets, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket_runner__old_program_sockets_close_before_the_new_one_dials, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket_runner__refused_host_is_a_runtime_exception, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket_runner__allow_list_bounds, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
