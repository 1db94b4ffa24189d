/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_socket.c — the URScript socket table: host policy, non-blocking
 * connects, receive buffers and sends (see script_socket.h).
 */
#include "script_socket.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

us_sockets *urt__us_sockets_new(const char *const *allow, int n) {
  if (n < 0 || n > US_SOCK_MAX_ALLOW) {
    return NULL;
  }
  us_sockets *t = calloc(1, sizeof *t);
  if (!t) {
    return NULL;
  }
  for (int k = 0; k < n; k++) {
    if (!allow[k] || strlen(allow[k]) >= US_SOCK_HOST) {
      free(t);
      return NULL;
    }
    snprintf(t->allow[k], US_SOCK_HOST, "%s", allow[k]);
  }
  t->n_allow = n;
  for (int k = 0; k < US_SOCK_MAX; k++) {
    t->s[k].fd = -1;
  }
  return t;
}

void urt__us_sock_close(us_sock *s) {
  if (!s || s->state == US_SOCK_FREE) {
    return;
  }
  if (s->fd >= 0) {
    close(s->fd);
  }
  s->fd = -1;
  s->state = US_SOCK_FREE;
  s->eof = s->broken = false;
  s->rx_n = 0;
  s->tx_n = 0;
  s->rx_tick = 0;
  s->name[0] = 0;
}

void urt__us_sockets_close_all(us_sockets *t) {
  if (!t) {
    return;
  }
  for (int k = 0; k < US_SOCK_MAX; k++) {
    urt__us_sock_close(&t->s[k]);
  }
}

/* Shut down every open socket's sending side and wait, at most timeout_ms of wall time in
 * all, until each peer has closed its end too (a read returns 0 or fails), then close them.
 * A peer that closes its end has processed the disconnect: URCL's servers take one client
 * each and accept a new connection before they read the old one's EOF when both arrive in the
 * same select round, so a program re-sent right after the previous one ended had its sockets
 * refused ("maximum number of clients ... already connected") unless the old ones were gone
 * from the server first. A controller takes far longer to start a program than one tick. */
void urt__us_sockets_close_all_wait(us_sockets *t, int timeout_ms) {
  if (!t) {
    return;
  }
  struct pollfd pf[US_SOCK_MAX];
  int n = 0;
  for (int k = 0; k < US_SOCK_MAX; k++) {
    us_sock *s = &t->s[k];
    if (s->state != US_SOCK_FREE && s->fd >= 0 && !s->eof && !s->broken &&
        shutdown(s->fd, SHUT_WR) == 0) {
      pf[n] = (struct pollfd){.fd = s->fd, .events = POLLIN};
      n++;
    }
  }
  struct timespec t0, now;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  int open_n = n;
  while (open_n > 0) {
    clock_gettime(CLOCK_MONOTONIC, &now);
    long left = timeout_ms - (long)((now.tv_sec - t0.tv_sec) * 1000 +
                                    (now.tv_nsec - t0.tv_nsec) / 1000000);
    if (left <= 0 || poll(pf, (nfds_t)n, (int)left) < 0) {
      break;
    }
    for (int i = 0; i < n; i++) {
      if (pf[i].fd >= 0 && pf[i].revents) {
        char buf[4096];
        ssize_t got = recv(pf[i].fd, buf, sizeof buf, MSG_DONTWAIT);
        if (got == 0 || (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          pf[i].fd = -1;  // the peer closed (or the connection broke): done with this one
          open_n--;
        }
      }
    }
  }
  urt__us_sockets_close_all(t);
}

void urt__us_sockets_free(us_sockets *t) {
  urt__us_sockets_close_all(t);
  free(t);
}

us_sock *urt__us_sock_find(us_sockets *t, const char *name) {
  for (int k = 0; k < US_SOCK_MAX; k++) {
    if (t->s[k].state != US_SOCK_FREE && strcmp(t->s[k].name, name) == 0) {
      return &t->s[k];
    }
  }
  return NULL;
}

//---- host policy ----

static bool is_loopback(const struct sockaddr *sa) {
  if (sa->sa_family == AF_INET) {
    uint32_t a = ntohl(((const struct sockaddr_in *)sa)->sin_addr.s_addr);
    return (a >> 24) == 127;
  }
  if (sa->sa_family == AF_INET6) {
    return IN6_IS_ADDR_LOOPBACK(&((const struct sockaddr_in6 *)sa)->sin6_addr);
  }
  return false;
}

static bool is_allowed_name(const us_sockets *t, const char *host) {
  for (int k = 0; k < t->n_allow; k++) {
    if (strcasecmp(t->allow[k], host) == 0) {
      return true;
    }
  }
  return false;
}

/* host → address: literals without any lookup; "localhost" as 127.0.0.1; any other name only
 * when allowed (then the resolver may block: it is the user's explicit choice). */
static int resolve(const us_sockets *t, const char *host, int port, struct sockaddr_storage *out,
                   socklen_t *len, char *text, size_t n) {
  bool allowed = is_allowed_name(t, host);
  const char *lookup = strcasecmp(host, "localhost") == 0 ? "127.0.0.1" : host;
  struct addrinfo hints = {.ai_socktype = SOCK_STREAM, .ai_flags = AI_NUMERICHOST |
                                                                   AI_NUMERICSERV};
  char service[16];
  snprintf(service, sizeof service, "%d", port);
  struct addrinfo *ai = NULL;
  int rc = getaddrinfo(lookup, service, &hints, &ai);
  if (rc != 0 && allowed) {
    hints.ai_flags = AI_NUMERICSERV;
    rc = getaddrinfo(lookup, service, &hints, &ai);
    if (rc != 0) {
      snprintf(text, n, "socket_open: cannot resolve \"%s\": %s", host, gai_strerror(rc));
      return US_SOCK_ERR_RESOLVE;
    }
  }
  if (rc != 0 || (!allowed && !is_loopback(ai->ai_addr))) {
    if (ai) freeaddrinfo(ai);
    snprintf(text, n,
             "socket_open: connections to \"%s\" are not allowed (urtwin dials loopback "
             "addresses only; start it with --script-allow-host %s to allow this host)",
             host, host);
    return US_SOCK_ERR_HOST;
  }
  memcpy(out, ai->ai_addr, ai->ai_addrlen);
  *len = ai->ai_addrlen;
  freeaddrinfo(ai);
  return US_SOCK_OK;
}

//---- connect ----

int urt__us_sock_connect(us_sockets *t, const char *name, const char *host, int port,
                         us_sock **out, char *text, size_t n) {
  *out = NULL;
  if (strlen(name) >= US_SOCK_NAME) {
    snprintf(text, n, "socket_open: socket name longer than %d bytes", US_SOCK_NAME - 1);
    return US_SOCK_ERR_ARG;
  }
  if (port < 1 || port > 65535) {
    snprintf(text, n, "socket_open: port %d outside 1..65535", port);
    return US_SOCK_ERR_ARG;
  }
  struct sockaddr_storage sa;
  socklen_t len = 0;
  int rc = resolve(t, host, port, &sa, &len, text, n);
  if (rc != US_SOCK_OK) {
    return rc;
  }
  // a name opened again replaces the old connection
  urt__us_sock_close(urt__us_sock_find(t, name));
  us_sock *s = NULL;
  for (int k = 0; k < US_SOCK_MAX && !s; k++) {
    if (t->s[k].state == US_SOCK_FREE) s = &t->s[k];
  }
  if (!s) {
    snprintf(text, n, "socket_open: more than %d sockets open", US_SOCK_MAX);
    return US_SOCK_ERR_FULL;
  }
  int fd = socket(sa.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    snprintf(text, n, "socket_open: socket: %s", strerror(errno));
    return US_SOCK_ERR_CONNECT;
  }
  int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  s->eof = s->broken = false;
  s->rx_n = s->tx_n = 0;
  s->rx_tick = 0;
  s->fd = fd;
  snprintf(s->name, sizeof s->name, "%s", name);
  if (connect(fd, (const struct sockaddr *)&sa, len) == 0) {
    s->state = US_SOCK_OPEN;
  } else if (errno == EINPROGRESS) {
    s->state = US_SOCK_CONNECTING;
  } else {
    snprintf(text, n, "socket_open: %s:%d: %s", host, port, strerror(errno));
    close(fd);
    s->fd = -1;
    s->name[0] = 0;
    return US_SOCK_ERR_CONNECT;
  }
  *out = s;
  return US_SOCK_OK;
}

int urt__us_sock_poll_connect(us_sock *s) {
  if (s->state == US_SOCK_OPEN) {
    return 1;
  }
  if (s->state != US_SOCK_CONNECTING) {
    return -1;
  }
  struct pollfd p = {.fd = s->fd, .events = POLLOUT};
  int rc = poll(&p, 1, 0);
  if (rc == 0) {
    return 0;
  }
  int err = 0;
  socklen_t len = sizeof err;
  if (rc < 0 || getsockopt(s->fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0 || err != 0) {
    urt__us_sock_close(s);
    return -1;
  }
  s->state = US_SOCK_OPEN;
  return 1;
}

/* one /proc/self/net/tcp[6] file: the rx_queue of a LISTEN line on port whose address is addr
 * (len 4 or 16 bytes, network order) or the wildcard; -1 if none */
static int listen_backlog_in(const char *path, const uint8_t *addr, size_t alen, int port) {
  FILE *f = fopen(path, "r");
  if (!f) {
    return -1;
  }
  char line[512], local[64];
  unsigned lport, st, txq, rxq;
  int found = -1;
  if (!fgets(line, sizeof line, f)) {  // the header
    fclose(f);
    return -1;
  }
  while (found < 0 && fgets(line, sizeof line, f)) {
    // "  sl  local_address rem_address   st tx_queue:rx_queue ..."
    if (sscanf(line, " %*u: %63[0-9A-Fa-f]:%x %*[0-9A-Fa-f]:%*x %x %x:%x", local, &lport, &st,
               &txq, &rxq) != 5 || st != 0x0A || (int)lport != port) {
      continue;
    }
    // the kernel prints each 32-bit word of the address as it lies in memory, in %08X
    size_t words = strlen(local) / 8;
    if (words * 4 != alen) {
      continue;
    }
    uint8_t a[16];
    bool any = true;
    for (size_t w = 0; w < words; w++) {
      char hex[9];
      memcpy(hex, local + 8 * w, 8);
      hex[8] = 0;
      uint32_t v = (uint32_t)strtoul(hex, NULL, 16);
      memcpy(a + 4 * w, &v, 4);
      any = any && v == 0;
    }
    if (any || memcmp(a, addr, alen) == 0) {
      found = (int)rxq;
    }
  }
  fclose(f);
  return found;
}

int urt__us_sock_peer_backlog(const us_sock *s) {
  if (!s || s->state != US_SOCK_OPEN) {
    return -1;
  }
  struct sockaddr_storage sa;
  socklen_t len = sizeof sa;
  if (getpeername(s->fd, (struct sockaddr *)&sa, &len) != 0 ||
      !is_loopback((const struct sockaddr *)&sa)) {
    return -1;
  }
  if (sa.ss_family == AF_INET) {
    const struct sockaddr_in *in = (const struct sockaddr_in *)&sa;
    int port = ntohs(in->sin_port);
    int n = listen_backlog_in("/proc/self/net/tcp", (const uint8_t *)&in->sin_addr, 4, port);
    if (n < 0) {
      // a dual-stack listener (bound to ::) holds IPv4 connections too
      uint8_t mapped[16] = {0};
      mapped[10] = mapped[11] = 0xff;
      memcpy(mapped + 12, &in->sin_addr, 4);
      n = listen_backlog_in("/proc/self/net/tcp6", mapped, 16, port);
    }
    return n;
  }
  const struct sockaddr_in6 *in6 = (const struct sockaddr_in6 *)&sa;
  return listen_backlog_in("/proc/self/net/tcp6", (const uint8_t *)&in6->sin6_addr, 16,
                           ntohs(in6->sin6_port));
}

//---- data ----

static void flush_tx(us_sock *s) {
  while (s->tx_n > 0) {
    ssize_t k = send(s->fd, s->tx, s->tx_n, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (k <= 0) {
      if (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        s->broken = true;
        s->tx_n = 0;
      }
      return;
    }
    memmove(s->tx, s->tx + k, s->tx_n - (size_t)k);
    s->tx_n -= (size_t)k;
  }
}

void urt__us_sock_fill(us_sock *s, uint64_t tick) {
  if (s->state != US_SOCK_OPEN) {
    return;
  }
  flush_tx(s);
  if (s->rx_tick == tick + 1) {
    return;  // received once this tick already
  }
  s->rx_tick = tick + 1;
  while (!s->eof && s->rx_n < sizeof s->rx) {
    ssize_t k = recv(s->fd, s->rx + s->rx_n, sizeof s->rx - s->rx_n, MSG_DONTWAIT);
    if (k > 0) {
      s->rx_n += (size_t)k;
    } else if (k == 0) {
      s->eof = true;
    } else if (errno == EINTR) {
      continue;
    } else {
      if (errno != EAGAIN && errno != EWOULDBLOCK) s->eof = true;
      break;
    }
  }
}

void urt__us_sock_consume(us_sock *s, size_t n) {
  if (n >= s->rx_n) {
    s->rx_n = 0;
    return;
  }
  memmove(s->rx, s->rx + n, s->rx_n - n);
  s->rx_n -= n;
}

bool urt__us_sock_send(us_sock *s, const void *buf, size_t n) {
  if (!s || s->state != US_SOCK_OPEN || s->broken) {
    return false;
  }
  flush_tx(s);
  if (s->tx_n > 0) {
    // an earlier write is still in flight: queue behind it, never interleave
    if (s->tx_n + n > sizeof s->tx) return false;
    memcpy(s->tx + s->tx_n, buf, n);
    s->tx_n += n;
    return true;
  }
  ssize_t k = send(s->fd, buf, n, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (k < 0) {
    if (errno != EAGAIN && errno != EWOULDBLOCK) {
      s->broken = true;
      return false;
    }
    k = 0;
  }
  size_t rest = n - (size_t)k;
  if (rest == 0) {
    return true;
  }
  if (k == 0 && rest > sizeof s->tx) {
    return false;
  }
  if (rest > sizeof s->tx) {
    // part went out and the rest does not fit: the stream is broken from here on
    s->broken = true;
    return false;
  }
  memcpy(s->tx, (const uint8_t *)buf + k, rest);
  s->tx_n = rest;
  return true;
}
