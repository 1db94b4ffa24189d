/* SPDX-License-Identifier: Apache-2.0
 * tests/net/server/test_tcp.c — the I/O thread's TCP plumbing (tcp.c): output buffers start
 * small and grow to their cap within a shared budget, and an accept on a full descriptor table
 * drains the listener with the reserve descriptor (the peer reads an orderly close) instead of
 * leaving it readable for ever. Loopback, an ephemeral port, everything closed at the end. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdint.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include "test_support.h"
#include "urt/net/tcp.h"

// A listener on 127.0.0.1 at a port the kernel picks; *port receives it.
static int listen_any(int *port) {
  char err[128];
  int fd = urt_tcp_listen("127.0.0.1", 0, err, sizeof err);
  assert_true(fd >= 0);
  struct sockaddr_in sa;
  socklen_t len = sizeof sa;
  assert_int_equal(getsockname(fd, (struct sockaddr *)&sa, &len), 0);
  *port = ntohs(sa.sin_port);
  return fd;
}

static int connect_to(int port) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
  inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
  assert_int_equal(connect(fd, (struct sockaddr *)&sa, sizeof sa), 0);
  return fd;
}

// Wait up to 2 s for the listener to have a connection pending.
static void wait_pending(int listen_fd) {
  struct pollfd p = {.fd = listen_fd, .events = POLLIN};
  assert_int_equal(poll(&p, 1, 2000), 1);
}

// A connection's buffer doubles from 4 KiB to its cap and no further; the budget's account
// follows every growth and the close; a growth beyond the budget is refused and counted.
static void test_tcp__output_grows_to_its_cap_within_the_budget(void **state) {
  (void)state;
  int port, lfd = listen_any(&port);
  int cfd = connect_to(port);
  wait_pending(lfd);
  int fd = urt_tcp_accept_fd(lfd, NULL);
  assert_true(fd >= 0);
  urt_tcp_budget_t budget = {.limit = 38 * 1024};
  urt_tcp_conn_t *c = urt_tcp_conn_new(fd, 7, 32 * 1024, &budget);
  assert_non_null(c);
  assert_int_equal(c->port_kind, 7);
  assert_int_equal(c->out_cap, 4096);
  assert_int_equal(budget.used, 4096);
  static uint8_t msg[3000];
  // nothing is flushed: the queue only grows
  for (int i = 0; i < 10; i++) {
    assert_true(urt_tcp_send(c, msg, sizeof msg));
  }
  assert_int_equal(c->out_cap, 32 * 1024);  // 4 → 8 → 16 → 32 KiB for 30 000 bytes
  assert_int_equal(budget.used, 32 * 1024);
  assert_false(urt_tcp_send(c, msg, sizeof msg));  // 33 000 > the cap
  assert_int_equal(c->dropped_msgs, 1);
  assert_int_equal(budget.refused, 0);  // the connection's own cap, not the budget
  // a second connection may grow only by what the budget has left: 38 − 32 = 6 KiB
  int cfd2 = connect_to(port);
  wait_pending(lfd);
  int fd2 = urt_tcp_accept_fd(lfd, NULL);
  assert_true(fd2 >= 0);
  urt_tcp_conn_t *c2 = urt_tcp_conn_new(fd2, 7, 32 * 1024, &budget);
  assert_int_equal(budget.used, 36 * 1024);
  assert_true(urt_tcp_send(c2, msg, sizeof msg));
  assert_false(urt_tcp_send(c2, msg, sizeof msg));  // would need 4 KiB more: 40 KiB > 38
  assert_int_equal(budget.refused, 1);
  assert_int_equal(c2->dropped_msgs, 1);
  urt_tcp_close(c);
  assert_int_equal(budget.used, 4096);
  assert_true(urt_tcp_send(c2, msg, sizeof msg));  // room again
  urt_tcp_close(c2);
  assert_int_equal(budget.used, 0);
  close(cfd);
  close(cfd2);
  close(lfd);
}

// Fill the descriptor table (a lowered soft limit keeps it quick), then accept: with the
// reserve the pending connection is taken and closed (the peer reads EOF) and the listener has
// nothing pending any more; without one the caller is told to pause. After descriptors are
// freed, accept works again.
static void test_tcp__full_descriptor_table_drains_the_listener(void **state) {
  (void)state;
  struct rlimit saved;
  assert_int_equal(getrlimit(RLIMIT_NOFILE, &saved), 0);
  int port, lfd = listen_any(&port);
  int reserve = urt_tcp_reserve_open();
  assert_true(reserve >= 0);
  int peer1 = connect_to(port), peer2 = connect_to(port);
  wait_pending(lfd);
  struct rlimit low = {.rlim_cur = 128, .rlim_max = saved.rlim_max};
  assert_int_equal(setrlimit(RLIMIT_NOFILE, &low), 0);
  int filler[128], n_fill = 0;
  for (;;) {
    int fd = dup(0);
    if (fd < 0) {
      assert_int_equal(errno, EMFILE);
      break;
    }
    assert_true(n_fill < 128);
    filler[n_fill++] = fd;
  }
  assert_int_equal(urt_tcp_accept_fd(lfd, &reserve), URT_TCP_NO_FDS);
  assert_true(reserve >= 0);  // held again
  char b;
  struct timeval tv = {.tv_sec = 2};
  setsockopt(peer1, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  assert_int_equal(recv(peer1, &b, 1, 0), 0);  // an orderly close
  // without a spare: nothing can drain, the caller must stop listening for a while
  int none = -1;
  assert_int_equal(urt_tcp_accept_fd(lfd, &none), URT_TCP_NO_FDS_STUCK);
  assert_int_equal(urt_tcp_accept_fd(lfd, NULL), URT_TCP_NO_FDS_STUCK);
  // the reserve drains the second one too; then nothing is pending
  assert_int_equal(urt_tcp_accept_fd(lfd, &reserve), URT_TCP_NO_FDS);
  assert_int_equal(recv(peer2, &b, 1, 0), 0);
  assert_int_equal(urt_tcp_accept_fd(lfd, &reserve), URT_TCP_NONE);
  for (int i = 0; i < n_fill; i++) {
    close(filler[i]);
  }
  assert_int_equal(setrlimit(RLIMIT_NOFILE, &saved), 0);
  int peer3 = connect_to(port);
  wait_pending(lfd);
  int fd = urt_tcp_accept_fd(lfd, &reserve);
  assert_true(fd >= 0);
  close(fd);
  close(peer1);
  close(peer2);
  close(peer3);
  close(reserve);
  close(lfd);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tcp__output_grows_to_its_cap_within_the_budget),
      cmocka_unit_test(test_tcp__full_descriptor_table_drains_the_listener),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
