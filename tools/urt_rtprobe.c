/* SPDX-License-Identifier: Apache-2.0
 * tools/urt_rtprobe.c — what a 30003 client sees: connects N clients from one epoll thread,
 * timestamps every packet on arrival (CLOCK_MONOTONIC) and reports the inter-packet period
 * (p50/p99/p99.9/max over all clients), packet counts and gaps in the controller timestamps.
 *
 *   urt_rtprobe [--host 127.0.0.1] [--port 30003] [--clients 8] [--seconds 60] [--period 0.002]
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

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  const char *host = "127.0.0.1";
  int port = 30003, n_clients = 8;
  double seconds = 60.0, period = 0.002;
  static const struct option opts[] = {{"host", required_argument, 0, 'H'},
                                        {"port", required_argument, 0, 'p'},
                                        {"clients", required_argument, 0, 'n'},
                                        {"seconds", required_argument, 0, 's'},
                                        {"period", required_argument, 0, 'P'},
                                        {0, 0, 0, 0}};
  int o;
  while ((o = getopt_long(argc, argv, "H:p:n:s:P:", opts, NULL)) != -1) {
    switch (o) {
      case 'H': host = optarg; break;
      case 'p': port = atoi(optarg); break;
      case 'n': n_clients = atoi(optarg); break;
      case 's': seconds = atof(optarg); break;
      case 'P': period = atof(optarg); break;
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
        uint32_t size = ((uint32_t)c->buf[off] << 24) | ((uint32_t)c->buf[off + 1] << 16) |
                        ((uint32_t)c->buf[off + 2] << 8) | c->buf[off + 3];
        if (size < 12 || size > 4096) {
          fprintf(stderr, "urt_rtprobe: bad packet size %u\n", size);
          return 1;
        }
        if (c->len - off < size) {
          break;
        }
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
