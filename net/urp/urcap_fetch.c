/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urcap_fetch.c — what the External Control URCap does when its program node is
 * generated (its RequestProgram.java, v1.0.5; external_control.md §1.1): connect to the remote
 * PC (5 s), write "request_program\n", read the reply with a 500 ms socket timeout, and split
 * it at "# HEADER_BEGIN" / "# HEADER_END". A failure becomes the URCap's blocking popup.
 *
 * Differences from the URCap, on purpose: the URCap reads one line and then only what is
 * already buffered (BufferedReader.ready()), so a reply split across TCP segments can be cut
 * short; here the reply is read until the server has been quiet for the read timeout or closes,
 * or, once what came ends with a newline, quiet for SETTLE_MS.
 * The whole exchange is bounded (total_timeout_ms, FETCH_MAX bytes) and cancellable.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "urp_text.h"
#include "urt/net/urp.h"

#define STEP_MS 50              /* how often a wait looks at the cancel flag        */
#define FETCH_MAX (1u << 20)    /* longest reply: the runner's URT_SCRIPT_MAX_TEXT */
#define SETTLE_MS 20            /* quiet time that ends a reply ending in a newline */

static long long now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (long long)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

static int cancelled(const urt_urcap_config_t *cfg) {
  return cfg->cancel && atomic_load(cfg->cancel);
}

int urt_urcap_host_is_loopback(const char *host) {
  if (!host) return 0;
  if (strcmp(host, "localhost") == 0) return 1;
  struct in_addr a;
  return inet_pton(AF_INET, host, &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

/* The URCap's popup text for a failed fetch, then sync(). The host goes into a string
 * literal: anything but an address's characters is shown as '?'. */
static char *failure(const urt_urcap_config_t *in, int timeout, const char *reason, size_t *len) {
  char host[64];
  size_t n = 0;
  for (const char *s = in->host; *s && n < sizeof host - 1; s++, n++) {
    host[n] = (isalnum((unsigned char)*s) || *s == '.' || *s == '-' || *s == ':') ? *s : '?';
  }
  host[n] = '\0';
  urt_urcap_config_t c = *in;
  c.host = host;
  const urt_urcap_config_t *cfg = &c;
  urp_text t = {0};
  if (timeout) {
    urp_text_printf(&t, "popup(\"Timeout while reading requested program from %s:%d\",",
                    cfg->host, cfg->port);
  } else {
    urp_text_printf(&t,
                    "popup(\"The connection to the remote PC at %s:%d could not be established. "
                    "Reason: %s\",",
                    cfg->host, cfg->port, reason);
  }
  urp_text_puts(&t, "\"Receive program failed\", False, True, blocking=True)\nsync()\n");
  if (t.oom) {
    urp_text_free(&t);
    return NULL;
  }
  *len = t.len;
  return t.p;
}

/* Wait for fd to become ready for events, in STEP_MS steps, until deadline (ms, monotonic).
 * 1 ready, 0 timed out, -1 cancelled or error. */
static int wait_fd(const urt_urcap_config_t *cfg, int fd, short events, long long deadline) {
  for (;;) {
    if (cancelled(cfg)) return -1;
    long long left = deadline - now_ms();
    if (left <= 0) return 0;
    struct pollfd p = {.fd = fd, .events = events};
    int rc = poll(&p, 1, (int)(left < STEP_MS ? left : STEP_MS));
    if (rc > 0) return 1;
    if (rc < 0 && errno != EINTR) return -1;
  }
}

int urt_urcap_fetch(const urt_urcap_config_t *in, char **text, size_t *len) {
  urt_urcap_config_t cfg = *in;
  if (cfg.connect_timeout_ms <= 0) cfg.connect_timeout_ms = 5000;
  if (cfg.read_timeout_ms <= 0) cfg.read_timeout_ms = 500;
  if (cfg.total_timeout_ms <= 0) cfg.total_timeout_ms = 10000;
  const char *host = cfg.host ? cfg.host : "";
  cfg.host = host;
  *text = NULL;
  *len = 0;

  // loopback only: an emulator never dials out of the host
  if (!urt_urcap_host_is_loopback(host)) {
    *text = failure(&cfg, 0, "urtwin connects to loopback addresses (127.0.0.0/8) only", len);
    return -1;
  }
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)cfg.port)};
  inet_pton(AF_INET, strcmp(host, "localhost") == 0 ? "127.0.0.1" : host, &sa.sin_addr);
  if (cfg.port <= 0 || cfg.port > 65535) {
    *text = failure(&cfg, 0, "bad port", len);
    return -1;
  }

  long long start = now_ms(), end_all = start + cfg.total_timeout_ms;
  int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *text = failure(&cfg, 0, strerror(errno), len);
    return -1;
  }
  int err = 0;
  if (connect(fd, (struct sockaddr *)&sa, sizeof sa) != 0) {
    err = errno;
    if (err == EINPROGRESS) {
      int w = wait_fd(&cfg, fd, POLLOUT, start + cfg.connect_timeout_ms);
      socklen_t el = sizeof err;
      if (w == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &el) != 0) err = errno;
      if (w == 0) err = ETIMEDOUT;
      if (w < 0) err = ECANCELED;
    }
  }
  if (err) {
    close(fd);
    *text = failure(&cfg, 0, err == ETIMEDOUT ? "connect timed out" : strerror(err), len);
    return -1;
  }

  // the request, then the reply until the server is quiet for read_timeout_ms
  static const char kRequest[] = "request_program\n";
  size_t sent = 0;
  while (sent < sizeof kRequest - 1) {
    ssize_t n = send(fd, kRequest + sent, sizeof kRequest - 1 - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += (size_t)n;
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      if (wait_fd(&cfg, fd, POLLOUT, end_all) != 1) break;
    } else {
      break;
    }
  }
  if (sent < sizeof kRequest - 1) {
    int e = errno;
    close(fd);
    *text = failure(&cfg, 0, strerror(e ? e : EPIPE), len);
    return -1;
  }

  urp_text got = {0};
  int timeout = 0, closed = 0;
  for (;;) {
    // a reply that ends with a whole line is taken once the server has been quiet for
    // SETTLE_MS (the URCap takes what is buffered at once; URCL writes the program in one
    // write): waiting the full read timeout after it would delay every play by 500 ms, and
    // URCL's URCap tests wait only 500 ms for the program after `play`
    bool whole = got.len && got.p[got.len - 1] == '\n';
    long long quiet_until = now_ms() + (whole ? SETTLE_MS : cfg.read_timeout_ms);
    long long until = quiet_until < end_all ? quiet_until : end_all;
    int w = wait_fd(&cfg, fd, POLLIN, until);
    if (w < 0) {
      timeout = 1;  // cancelled: nothing will run it anyway
      break;
    }
    if (w == 0) {
      // quiet: the end of the reply if a whole line came, the URCap's timeout otherwise; a
      // server still trickling at the overall deadline is a timeout too
      timeout = !(got.p && memchr(got.p, '\n', got.len)) || now_ms() >= end_all;
      break;
    }
    char buf[8192];
    ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n > 0) {
      urp_text_put(&got, buf, (size_t)n);
      if (got.oom || got.len > FETCH_MAX) {
        close(fd);
        urp_text_free(&got);
        *text = failure(&cfg, 0, "the program is too long", len);
        return -1;
      }
    } else if (n == 0) {
      closed = 1;
      break;
    } else if (errno != EAGAIN && errno != EINTR) {
      int e = errno;
      close(fd);
      urp_text_free(&got);
      *text = failure(&cfg, 0, strerror(e), len);
      return -1;
    }
  }
  close(fd);
  if (timeout || (closed && got.len == 0)) {
    urp_text_free(&got);
    *text = timeout ? failure(&cfg, 1, NULL, len)
                    : failure(&cfg, 0, "the remote PC closed the connection without a program", len);
    return -1;
  }
  *text = got.p;
  *len = got.len;
  return 0;
}

/* "<blanks># HEADER_BEGIN<blanks>" (the URCap's pattern, \p{Zs} read as space and tab) */
static int is_marker(const char *s, size_t n, const char *word) {
  while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r')) n--;
  while (n > 0 && (*s == ' ' || *s == '\t')) s++, n--;
  size_t w = strlen(word);
  return n == w + 2 && s[0] == '#' && s[1] == ' ' && memcmp(s + 2, word, w) == 0;
}

int urt_urcap_split(const char *text, size_t len, char **header, char **body) {
  urp_text h = {0}, b = {0};
  int in_header = 0, found_end = 0;
  size_t i = 0;
  while (i < len) {
    size_t j = i;
    while (j < len && text[j] != '\n') j++;
    const char *s = text + i;
    size_t n = j - i;
    if (is_marker(s, n, "HEADER_BEGIN")) {
      in_header = 1;
      urp_text_put(&h, s, n);
      urp_text_put(&h, "\n", 1);
    } else if (in_header && is_marker(s, n, "HEADER_END")) {
      in_header = 0;
      found_end = 1;
      urp_text_put(&h, s, n);
      urp_text_put(&h, "\n", 1);
    } else if (in_header) {
      urp_text_put(&h, s, n);
      urp_text_put(&h, "\n", 1);
    } else if (found_end) {
      urp_text_put(&b, s, n);
      urp_text_put(&b, "\n", 1);
    }
    i = j + 1;
  }
  if (!found_end) {
    // no anchors: the whole text is the node's body
    urp_text_free(&h);
    urp_text_free(&b);
    urp_text_put(&b, text, len);
  }
  urp_text_put(&h, "", 0);  // allocates: an empty part is "", not NULL
  urp_text_put(&b, "", 0);
  if (h.oom || b.oom) {
    urp_text_free(&h);
    urp_text_free(&b);
    return -1;
  }
  *header = h.p;
  *body = b.p;
  return 0;
}
