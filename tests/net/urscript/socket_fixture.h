/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/socket_fixture.h — a scripted TCP peer on 127.0.0.1 (an ephemeral port)
 * for the URScript socket tests: it accepts the program's connection and, at given controller
 * ticks of the fake host, writes given bytes or closes, so that data arrives in parts over
 * several ticks, or echoes what the program sent. It runs inside the fake host's wait_tick (the
 * program's thread), and after each write waits until the kernel shows the bytes on the
 * program's side, so the tick at which a read completes is exact. */
#ifndef URT_TEST_SOCKET_FIXTURE_H
#define URT_TEST_SOCKET_FIXTURE_H

#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fake_host.h"
#include "script_socket.h"

#define FIX_MAX_EVENTS 16

typedef struct fix_event {
  uint64_t tick;       /* fake-host tick at which it happens */
  const char *data;    /* bytes to write (NULL: close the connection) */
  size_t len;
} fix_event;

typedef struct fixture {
  int listen_fd, conn_fd;
  int port;
  fix_event ev[FIX_MAX_EVENTS];
  int n_ev;
  us_sockets *table;   /* the program's sockets: where the client side is */
  char got[4096];      /* what the program sent */
  size_t n_got;
  bool echo;           /* send back what the program sent, in the tick it is seen */
  uint64_t accept_from;  /* a busy server: it accepts at this tick at the earliest */
} fixture;

static inline int fix_listen(fixture *x) {
  memset(x, 0, sizeof *x);
  x->conn_fd = -1;
  // non-blocking: a tick without a connection to accept (a refused socket_open waits a tick
  // before it learns the outcome) must not block the program's thread
  x->listen_fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  int one = 1;
  setsockopt(x->listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
  if (bind(x->listen_fd, (struct sockaddr *)&a, sizeof a) != 0 || listen(x->listen_fd, 8) != 0) {
    return -1;
  }
  socklen_t len = sizeof a;
  getsockname(x->listen_fd, (struct sockaddr *)&a, &len);
  x->port = ntohs(a.sin_port);
  return 0;
}

/* a port on 127.0.0.1 that nothing listens on (bound, then closed) */
static inline int fix_dead_port(void) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
  bind(fd, (struct sockaddr *)&a, sizeof a);
  socklen_t len = sizeof a;
  getsockname(fd, (struct sockaddr *)&a, &len);
  close(fd);
  return ntohs(a.sin_port);
}

static inline void fix_at(fixture *x, uint64_t tick, const char *data, size_t len) {
  x->ev[x->n_ev++] = (fix_event){.tick = tick, .data = data, .len = len};
}

static inline void fix_close(fixture *x) {
  if (x->conn_fd >= 0) close(x->conn_fd);
  if (x->listen_fd >= 0) close(x->listen_fd);
  x->conn_fd = x->listen_fd = -1;
}

/* the program's side of the connection (the one socket open in its table), or -1 */
static inline int fix_client_fd(fixture *x) {
  for (int k = 0; x->table && k < US_SOCK_MAX; k++) {
    if (x->table->s[k].state == US_SOCK_OPEN) return x->table->s[k].fd;
  }
  return -1;
}

static inline void fix_drain(fixture *x) {
  if (x->conn_fd < 0) return;
  for (;;) {
    ssize_t k = recv(x->conn_fd, x->got + x->n_got, sizeof x->got - 1 - x->n_got, MSG_DONTWAIT);
    if (k <= 0) break;
    x->n_got += (size_t)k;
  }
  x->got[x->n_got] = 0;
}

/* write to the program and wait until the kernel shows the bytes on its side */
static inline void fix_send(fixture *x, const char *data, size_t len) {
  int client = fix_client_fd(x);
  int before = 0;
  ioctl(client, FIONREAD, &before);
  if (send(x->conn_fd, data, len, MSG_NOSIGNAL) != (ssize_t)len) {
    return;
  }
  for (int w = 0; w < 1000; w++) {
    int now = 0;
    ioctl(client, FIONREAD, &now);
    if (now >= before + (int)len) break;
    usleep(1000);
  }
}

/* what happens at the fake host's tick t */
static inline void fix_tick(fixture *x, uint64_t t) {
  if (x->conn_fd < 0 && t >= x->accept_from) {
    x->conn_fd = accept4(x->listen_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
  }
  const size_t seen = x->n_got;
  fix_drain(x);
  if (x->echo && x->conn_fd >= 0 && x->n_got > seen) {
    fix_send(x, x->got + seen, x->n_got - seen);
  }
  for (int k = 0; k < x->n_ev; k++) {
    if (x->ev[k].tick != t || x->conn_fd < 0) continue;
    if (!x->ev[k].data) {
      int client = fix_client_fd(x);
      close(x->conn_fd);
      x->conn_fd = -1;
      struct pollfd p = {.fd = client, .events = POLLRDHUP};
      poll(&p, 1, 1000);  // the FIN is there before the program looks
      continue;
    }
    fix_send(x, x->ev[k].data, x->ev[k].len);
  }
}

#endif
