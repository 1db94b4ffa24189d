/* SPDX-License-Identifier: Apache-2.0
 * net/server/tcp.c — listeners, an accept that survives a full descriptor table, and
 * connections whose output grows on demand within bounds (tcp.h). */
#define _GNU_SOURCE
#include "urt/net/tcp.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "urt/errors.h"

int urt_tcp_listen(const char *addr, int port, char *err, size_t err_sz) {
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
  if (inet_pton(AF_INET, addr, &sa.sin_addr) != 1) {
    snprintf(err, err_sz, "bind %s:%d: not an IPv4 address", addr, port);
    return URT_EINVAL;
  }
  int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    snprintf(err, err_sz, "socket: %s", strerror(errno));
    return URT_EIO;
  }
  int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (bind(fd, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(fd, 64) != 0) {
    snprintf(err, err_sz, "bind %s:%d: %s", addr, port, strerror(errno));
    close(fd);
    return URT_EIO;
  }
  return fd;
}

int urt_tcp_reserve_open(void) { return open("/dev/null", O_RDONLY | O_CLOEXEC); }

int urt_tcp_accept_fd(int listen_fd, int *reserve_fd) {
  int fd = accept4(listen_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd >= 0) {
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return fd;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK) {
    return URT_TCP_NONE;
  }
  if (errno != EMFILE && errno != ENFILE) {
    return URT_TCP_FAILED;
  }
  if (!reserve_fd || *reserve_fd < 0) {
    return URT_TCP_NO_FDS_STUCK;
  }
  // the reserve trick: free one descriptor, take the connection with it, close it (the peer
  // sees an orderly close), then hold the spare again
  close(*reserve_fd);
  // (Linux reserves the descriptor before it looks at the queue: EMFILE comes even when
  // nothing is pending, which only this second accept tells)
  fd = accept4(listen_fd, NULL, NULL, SOCK_CLOEXEC);
  int why = errno;
  if (fd >= 0) {
    close(fd);
  }
  *reserve_fd = urt_tcp_reserve_open();
  if (fd >= 0) {
    return URT_TCP_NO_FDS;
  }
  if (why == EAGAIN || why == EWOULDBLOCK) {
    return URT_TCP_NONE;
  }
  // another thread took the freed descriptor first: as if there were no reserve
  return why == EMFILE || why == ENFILE ? URT_TCP_NO_FDS_STUCK : URT_TCP_FAILED;
}

#define OUT_INITIAL 4096  /* the first buffer; most clients never need more than a few */

urt_tcp_conn_t *urt_tcp_conn_new(int fd, int port_kind, size_t out_max, urt_tcp_budget_t *budget) {
  urt_tcp_conn_t *c = calloc(1, sizeof *c);
  size_t cap = out_max < OUT_INITIAL ? out_max : OUT_INITIAL;
  uint8_t *out = malloc(cap);
  if (!c || !out) {
    free(c);
    free(out);
    return NULL;
  }
  c->fd = fd;
  c->port_kind = port_kind;
  c->out = out;
  c->out_cap = cap;
  c->out_max = out_max;
  c->budget = budget;
  if (budget) {
    budget->used += cap;  // always granted: a client gets at least its first buffer
  }
  return c;
}

// Make room for len more bytes at out_len: false when the caps or the budget forbid it.
static bool grow(urt_tcp_conn_t *c, size_t len) {
  size_t need = c->out_len + len;
  if (need > c->out_max) {
    return false;
  }
  size_t cap = c->out_cap;
  while (cap < need) {
    cap = cap > c->out_max / 2 ? c->out_max : cap * 2;
  }
  size_t more = cap - c->out_cap;
  if (c->budget && c->budget->used + more > c->budget->limit) {
    c->budget->refused++;
    return false;
  }
  uint8_t *out = realloc(c->out, cap);
  if (!out) {
    return false;
  }
  c->out = out;
  c->out_cap = cap;
  if (c->budget) {
    c->budget->used += more;
  }
  return true;
}

size_t urt_tcp_pending(const urt_tcp_conn_t *c) { return c->out_len - c->out_head; }

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

double urt_tcp_stalled_for(const urt_tcp_conn_t *c) {
  return urt_tcp_pending(c) == 0 ? 0.0 : (now_ns() - c->last_progress_ns) * 1e-9;
}

void urt_tcp_set_sndbuf(urt_tcp_conn_t *c, int bytes) {
  setsockopt(c->fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
}

bool urt_tcp_flush(urt_tcp_conn_t *c) {
  while (c->out_head < c->out_len) {
    ssize_t n = send(c->fd, c->out + c->out_head, c->out_len - c->out_head, MSG_NOSIGNAL);
    if (n > 0) {
      c->out_head += (size_t)n;
      c->last_progress_ns = now_ns();
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      c->write_blocked = true;
      break;
    }
    if (n < 0 && errno == EINTR) {
      continue;
    }
    return false;
  }
  if (c->out_head == c->out_len) {
    c->out_head = c->out_len = 0;
  }
  return true;
}

bool urt_tcp_send(urt_tcp_conn_t *c, const void *msg, size_t len) {
  if (c->closing) {
    return false;
  }
  if (c->out_cap - c->out_len < len && c->out_head > 0) {
    // compact: slide the unsent bytes to the front
    memmove(c->out, c->out + c->out_head, c->out_len - c->out_head);
    c->out_len -= c->out_head;
    c->out_head = 0;
  }
  if (c->out_cap - c->out_len < len && !grow(c, len)) {
    c->dropped_msgs++;
    return false;
  }
  if (c->out_len == c->out_head) {
    c->last_progress_ns = now_ns();  // a new backlog starts now
  }
  memcpy(c->out + c->out_len, msg, len);
  c->out_len += len;
  c->sent_msgs++;
  return true;
}

void urt_tcp_close(urt_tcp_conn_t *c) {
  if (!c) {
    return;
  }
  close(c->fd);
  if (c->budget) {
    c->budget->used -= c->out_cap;
  }
  free(c->out);
  free(c);
}
