/* SPDX-License-Identifier: Apache-2.0
 * tools/urt_rtprobe.c — what a streaming client sees: connects N clients from one epoll thread,
 * timestamps every packet on arrival (CLOCK_MONOTONIC) and reports the inter-packet period
 * (p50/p99/p99.9/max over all clients), packet counts and gaps in the controller timestamps.
 * Port 30003 by default; with --rtde each client does the RTDE v2 handshake (V, O "timestamp,
 * actual_q" at 1/period Hz, S) on port 30004 and the data packages are timed instead.
 *
 *   urt_rtprobe [--host 127.0.0.1] [--port 30003] [--clients 8] [--seconds 60] [--period 0.002]
 *               [--rtde]
 *
 * Output: one JSON object on stdout. Exit 1 when a connection fails.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <getopt.h>
#include <math.h>
#include <netinet/in.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define MAX_CLIENTS 64
#define BUF 65536

typedef struct client {
  int fd;
  uint8_t buf[BUF];
  size_t len;
  uint64_t packets, gaps;
  double last_time;          /* controller time of the last packet [s] */
  int64_t last_arrival_ns;
} client_t;

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
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

// Blocking RTDE v2 set-up on a fresh connection: V 2, O at freq with timestamp + actual_q, S.
// Each request has exactly one reply; returns 0 when all were accepted.
static int rtde_handshake(int fd, double freq) {
  uint8_t req[128], rep[512];
  const char *names = "timestamp,actual_q";
  size_t nl = strlen(names);
  uint8_t v[] = {0, 5, 'V', 0, 2};
  req[2] = 'O';
  uint64_t fbits;
  memcpy(&fbits, &freq, sizeof fbits);
  for (int i = 0; i < 8; i++) {
    req[3 + i] = (uint8_t)(fbits >> (56 - 8 * i));
  }
  memcpy(req + 11, names, nl);
  size_t olen = 11 + nl;
  req[0] = (uint8_t)(olen >> 8);
  req[1] = (uint8_t)olen;
  uint8_t start[] = {0, 3, 'S'};
  const uint8_t *msgs[] = {v, req, start};
  size_t lens[] = {sizeof v, olen, sizeof start};
  for (int k = 0; k < 3; k++) {
    if (send(fd, msgs[k], lens[k], 0) != (ssize_t)lens[k]) {
      return -1;
    }
    size_t got = 0;
    while (got < 3 || got < (size_t)((rep[0] << 8) | rep[1])) {
      ssize_t r = recv(fd, rep + got, got < 3 ? 3 - got : (size_t)((rep[0] << 8) | rep[1]) - got, 0);
      if (r <= 0) {
        return -1;
      }
      got += (size_t)r;
    }
    if (rep[2] != msgs[k][2] || (k != 1 && rep[3] != 1) || (k == 1 && rep[3] == 0)) {
      return -1;
    }
  }
  return 0;
}

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  const char *host = "127.0.0.1";
  int port = 30003, n_clients = 8;
  double seconds = 60.0, period = 0.002;
  int rtde = 0;
  static const struct option opts[] = {{"host", required_argument, 0, 'H'},
                                        {"port", required_argument, 0, 'p'},
                                        {"clients", required_argument, 0, 'n'},
                                        {"seconds", required_argument, 0, 's'},
                                        {"period", required_argument, 0, 'P'},
                                        {"rtde", no_argument, 0, 'R'},
                                        {0, 0, 0, 0}};
  int o;
  while ((o = getopt_long(argc, argv, "H:p:n:s:P:R", opts, NULL)) != -1) {
    switch (o) {
      case 'H': host = optarg; break;
      case 'p': port = atoi(optarg); break;
      case 'n': n_clients = atoi(optarg); break;
      case 's': seconds = atof(optarg); break;
      case 'P': period = atof(optarg); break;
      case 'R': rtde = 1; break;
      default: fprintf(stderr, "usage: urt_rtprobe [--host H] [--port P] [--clients N] [--seconds S]\n"); return 2;
    }
  }
  if (n_clients < 1 || n_clients > MAX_CLIENTS || seconds <= 0) {
    fprintf(stderr, "urt_rtprobe: --clients 1..%d, --seconds > 0\n", MAX_CLIENTS);
    return 2;
  }
  static client_t clients[MAX_CLIENTS];
  int ep = epoll_create1(0);
  for (int i = 0; i < n_clients; i++) {
    client_t *c = &clients[i];
    c->fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    inet_pton(AF_INET, host, &sa.sin_addr);
    if (connect(c->fd, (struct sockaddr *)&sa, sizeof sa) != 0) {
      fprintf(stderr, "urt_rtprobe: connect %s:%d failed\n", host, port);
      return 1;
    }
    if (rtde && rtde_handshake(c->fd, 1.0 / period) != 0) {
      fprintf(stderr, "urt_rtprobe: RTDE set-up refused on %s:%d\n", host, port);
      return 1;
    }
    c->last_time = -1;
    struct epoll_event ev = {.events = EPOLLIN, .data.ptr = c};
    epoll_ctl(ep, EPOLL_CTL_ADD, c->fd, &ev);
  }
  size_t cap = (size_t)(seconds * 600 * n_clients) + 1024, n_int = 0;
  int64_t *intervals = malloc(cap * sizeof *intervals);
  int64_t t_end = now_ns() + (int64_t)(seconds * 1e9);
  struct epoll_event evs[MAX_CLIENTS];
  while (now_ns() < t_end) {
    int n = epoll_wait(ep, evs, MAX_CLIENTS, 100);
    int64_t arrival = now_ns();
    for (int i = 0; i < n; i++) {
      client_t *c = evs[i].data.ptr;
      ssize_t r = recv(c->fd, c->buf + c->len, BUF - c->len, 0);
      if (r <= 0) {
        fprintf(stderr, "urt_rtprobe: connection closed\n");
        return 1;
      }
      c->len += (size_t)r;
      size_t off = 0;
      while (c->len - off >= 4) {
        uint32_t size = rtde ? ((uint32_t)c->buf[off] << 8) | c->buf[off + 1]
                             : ((uint32_t)c->buf[off] << 24) | ((uint32_t)c->buf[off + 1] << 16) |
                                   ((uint32_t)c->buf[off + 2] << 8) | c->buf[off + 3];
        if (size < 12 || size > 4096) {
          fprintf(stderr, "urt_rtprobe: bad packet size %u\n", size);
          return 1;
        }
        if (c->len - off < size) {
          break;
        }
        if (rtde && c->buf[off + 2] != 'U') {  // a text message: not a period
          off += size;
          continue;
        }
        // the time sits at byte 4 in both: after 30003's int32 size, after RTDE's uint16 size,
        // type and recipe id
        double t = be_double(c->buf + off + 4);
        if (c->last_time >= 0) {
          double step = t - c->last_time;
          if (fabs(step - period) > 0.5 * period) {
            c->gaps++;
          }
          if (c->last_arrival_ns && n_int < cap) {
            intervals[n_int++] = arrival - c->last_arrival_ns;
          }
        }
        c->last_time = t;
        c->last_arrival_ns = arrival;
        c->packets++;
        off += size;
      }
      memmove(c->buf, c->buf + off, c->len - off);
      c->len -= off;
    }
  }
  qsort(intervals, n_int, sizeof *intervals, cmp_i64);
#define PCT(p) (n_int ? intervals[(size_t)fmin((double)n_int - 1, floor((p) / 100.0 * n_int))] * 1e-3 : NAN)
  uint64_t packets = 0, gaps = 0;
  for (int i = 0; i < n_clients; i++) {
    packets += clients[i].packets;
    gaps += clients[i].gaps;
  }
  printf("{\"clients\": %d, \"seconds\": %.1f, \"packets\": %llu, \"timestamp_gaps\": %llu, "
         "\"interval_us\": {\"n\": %zu, \"p50\": %.1f, \"p99\": %.1f, \"p99_9\": %.1f, \"max\": %.1f}}\n",
         n_clients, seconds, (unsigned long long)packets, (unsigned long long)gaps, n_int, PCT(50),
         PCT(99), PCT(99.9), n_int ? intervals[n_int - 1] * 1e-3 : NAN);
  free(intervals);
  return 0;
}
