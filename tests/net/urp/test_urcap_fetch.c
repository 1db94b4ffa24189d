/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urp/test_urcap_fetch.c — the External Control URCap's request_program against a
 * local fake of URCL's ScriptSender (127.0.0.1, ephemeral port): the reply read whole even when
 * it arrives in pieces, the header/body split, the URCap's popups for a timeout and a refused
 * connection, and no dialling outside loopback. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "test_support.h"
#include "urt/net/urp.h"

//---- a fake ScriptSender: one connection, checks the request, sends its parts ----

typedef struct fake {
  int listen_fd, port;
  const char *parts[4];     /* sent one after the other, pause_ms apart; NULL ends */
  int pause_ms;
  int close_after;          /* close the connection after sending (else hold it open) */
  char request[64];         /* what the client sent */
  pthread_t thread;
} fake_t;

static void sleep_ms(int ms) {
  struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
  nanosleep(&ts, NULL);
}

static void *fake_main(void *arg) {
  fake_t *f = arg;
  int c = accept(f->listen_fd, NULL, NULL);
  if (c < 0) return NULL;
  size_t n = 0;
  while (n < sizeof f->request - 1 && !memchr(f->request, '\n', n)) {
    ssize_t got = recv(c, f->request + n, sizeof f->request - 1 - n, 0);
    if (got <= 0) break;
    n += (size_t)got;
  }
  for (int k = 0; k < 4 && f->parts[k]; k++) {
    if (k) sleep_ms(f->pause_ms);
    send(c, f->parts[k], strlen(f->parts[k]), MSG_NOSIGNAL);
  }
  if (!f->close_after) sleep_ms(900);  // quiet but open, as URCL's ScriptSender leaves it
  close(c);
  return NULL;
}

static void fake_start(fake_t *f) {
  f->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET};
  inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
  assert_int_equal(bind(f->listen_fd, (struct sockaddr *)&sa, sizeof sa), 0);
  socklen_t sl = sizeof sa;
  getsockname(f->listen_fd, (struct sockaddr *)&sa, &sl);
  f->port = ntohs(sa.sin_port);
  assert_int_equal(listen(f->listen_fd, 1), 0);
  pthread_create(&f->thread, NULL, fake_main, f);
}

static void fake_stop(fake_t *f) {
  pthread_join(f->thread, NULL);
  close(f->listen_fd);
}

static urt_urcap_config_t config(int port) {
  urt_urcap_config_t c = {.host = "127.0.0.1", .port = port};
  return c;
}

//---- tests ----

static const char kProgram[] =
    "# HEADER_BEGIN\n"
    "steptime = get_steptime()\n"
    "# HEADER_END\n"
    "# NODE_CONTROL_LOOP_BEGINS\n"
    "textmsg(\"control\")\n"
    "# NODE_CONTROL_LOOP_ENDS\n";

static void test_fetch_and_split(void **state) {
  (void)state;
  // the reply comes in two pieces 200 ms apart: both are read (the URCap could cut it short)
  fake_t f = {.parts = {"# HEADER_BEGIN\nsteptime = get_steptime()\n# HEAD",
                        "ER_END\n# NODE_CONTROL_LOOP_BEGINS\ntextmsg(\"control\")\n"
                        "# NODE_CONTROL_LOOP_ENDS\n"},
              .pause_ms = 200};
  fake_start(&f);
  urt_urcap_config_t c = config(f.port);
  char *text;
  size_t len;
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), 0);
  fake_stop(&f);
  assert_string_equal(f.request, "request_program\n");
  assert_int_equal(len, strlen(kProgram));
  assert_memory_equal(text, kProgram, len);

  char *header, *body;
  assert_int_equal(urt_urcap_split(text, len, &header, &body), 0);
  assert_string_equal(header, "# HEADER_BEGIN\nsteptime = get_steptime()\n# HEADER_END\n");
  assert_string_equal(body, "# NODE_CONTROL_LOOP_BEGINS\ntextmsg(\"control\")\n"
                            "# NODE_CONTROL_LOOP_ENDS\n");
  free(header);
  free(body);
  free(text);
}

static void test_reply_ending_in_a_newline_is_taken_without_the_read_timeout(void **state) {
  (void)state;
  // URCL's ScriptSender: the program in one write ending in "\n", the socket left open; the
  // fetch must not wait out the 500 ms read timeout (URCL waits 500 ms for the program after
  // play); the old rule (quiet for 500 ms) took at least that long by construction
  fake_t f = {.parts = {kProgram}};
  fake_start(&f);
  urt_urcap_config_t c = config(f.port);
  char *text;
  size_t len;
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), 0);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  fake_stop(&f);
  double ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6;
  assert_true(ms < 500.0);
  assert_int_equal(len, strlen(kProgram));
  assert_memory_equal(text, kProgram, len);
  free(text);
}

static void test_split_without_markers(void **state) {
  (void)state;
  char *header, *body;
  const char *t = "textmsg(1)\n";
  assert_int_equal(urt_urcap_split(t, strlen(t), &header, &body), 0);
  assert_string_equal(header, "");
  assert_string_equal(body, t);
  free(header);
  free(body);
  // a begin without an end is no header either (the URCap's rule); markers may be indented
  t = "  # HEADER_BEGIN\nx = 1\n";
  assert_int_equal(urt_urcap_split(t, strlen(t), &header, &body), 0);
  assert_string_equal(header, "");
  assert_string_equal(body, t);
  free(header);
  free(body);
  t = "pre()\n\t# HEADER_BEGIN \nx = 1\n  # HEADER_END\npost()";
  assert_int_equal(urt_urcap_split(t, strlen(t), &header, &body), 0);
  assert_string_equal(header, "\t# HEADER_BEGIN \nx = 1\n  # HEADER_END\n");
  assert_string_equal(body, "post()\n");
  free(header);
  free(body);
}

// URCL's own script (the text its ScriptSender sends, before rendering): the header is its
// first 1046 lines, the body starts at the control loop.
static void test_split_urcl_script(void **state) {
  (void)state;
  char path[1024];
  FILE *f = NULL;
  const char *roots[] = {"/../shared", "/../../shared"};
  for (int k = 0; k < 2 && !f; k++) {
    snprintf(path, sizeof path,
             "%s%s/clients/Universal_Robots_Client_Library-2.14.0/resources/"
             "external_control.urscript",
             URT_SOURCE_DIR, roots[k]);
    f = fopen(path, "rb");
  }
  if (!f) {
    print_message("SKIP: ../shared (URCL 2.14.0's external_control.urscript) is absent\n");
    skip();
  }
  static char text[1 << 20];
  size_t len = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  char *header, *body;
  assert_int_equal(urt_urcap_split(text, len, &header, &body), 0);
  assert_int_equal(strncmp(header, "# HEADER_BEGIN\n", 15), 0);
  size_t hl = strlen(header), lines = 0;
  for (size_t k = 0; k < hl; k++) lines += header[k] == '\n';
  assert_int_equal(lines, 1046);
  assert_int_equal(strcmp(header + hl - 13, "# HEADER_END\n"), 0);
  assert_non_null(strstr(body, "# NODE_CONTROL_LOOP_BEGINS\n"));
  assert_null(strstr(body, "# HEADER_END"));
  assert_int_equal(hl + strlen(body), len + (text[len - 1] == '\n' ? 0 : 1));
  free(header);
  free(body);
}

static void test_timeout_popup(void **state) {
  (void)state;
  // the server accepts and reads but never answers
  fake_t f = {.parts = {NULL}};
  fake_start(&f);
  urt_urcap_config_t c = config(f.port);
  char *text;
  size_t len;
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), -1);
  fake_stop(&f);
  char expect[256];
  snprintf(expect, sizeof expect,
           "popup(\"Timeout while reading requested program from 127.0.0.1:%d\",\"Receive "
           "program failed\", False, True, blocking=True)\nsync()\n",
           f.port);
  assert_string_equal(text, expect);
  free(text);

  // half a line, then silence: a timeout too
  fake_t g = {.parts = {"textmsg(\"no newline"}};
  fake_start(&g);
  c = config(g.port);
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), -1);
  fake_stop(&g);
  assert_non_null(strstr(text, "Timeout while reading requested program"));
  free(text);
}

static void test_connection_refused_popup(void **state) {
  (void)state;
  // a port that nothing listens on any more
  fake_t f = {0};
  f.listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET};
  inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
  bind(f.listen_fd, (struct sockaddr *)&sa, sizeof sa);
  socklen_t sl = sizeof sa;
  getsockname(f.listen_fd, (struct sockaddr *)&sa, &sl);
  close(f.listen_fd);
  urt_urcap_config_t c = config(ntohs(sa.sin_port));
  char *text;
  size_t len;
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), -1);
  char expect[256];
  snprintf(expect, sizeof expect,
           "popup(\"The connection to the remote PC at 127.0.0.1:%d could not be established. "
           "Reason: Connection refused\",\"Receive program failed\", False, True, "
           "blocking=True)\nsync()\n",
           ntohs(sa.sin_port));
  assert_string_equal(text, expect);
  free(text);
}

static void test_loopback_only(void **state) {
  (void)state;
  assert_true(urt_urcap_host_is_loopback("127.0.0.1"));
  assert_true(urt_urcap_host_is_loopback("127.1.2.3"));
  assert_true(urt_urcap_host_is_loopback("localhost"));
  assert_false(urt_urcap_host_is_loopback("192.168.56.1"));
  assert_false(urt_urcap_host_is_loopback("128.0.0.1"));
  assert_false(urt_urcap_host_is_loopback("example.com"));
  // a non-loopback host is never dialled: the popup says why, at once
  urt_urcap_config_t c = {.host = "192.168.56.1", .port = 50002};
  char *text;
  size_t len;
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), -1);
  assert_non_null(strstr(text, "remote PC at 192.168.56.1:50002 could not be established. "
                               "Reason: urtwin connects to loopback addresses"));
  free(text);
}

static void test_cancel(void **state) {
  (void)state;
  // a quiet server and a cancel flag already set: the fetch gives up within a step
  fake_t f = {.parts = {NULL}};
  fake_start(&f);
  _Atomic int cancel = 1;
  urt_urcap_config_t c = config(f.port);
  c.cancel = &cancel;
  c.read_timeout_ms = 5000;
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  char *text;
  size_t len;
  assert_int_equal(urt_urcap_fetch(&c, &text, &len), -1);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  free(text);
  // a bound, not a timing figure: far below the 5 s read timeout it would otherwise wait
  assert_true((t1.tv_sec - t0.tv_sec) < 3);
  fake_stop(&f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_fetch_and_split),
      cmocka_unit_test(test_reply_ending_in_a_newline_is_taken_without_the_read_timeout),
      cmocka_unit_test(test_split_without_markers),
      cmocka_unit_test(test_split_urcl_script),
      cmocka_unit_test(test_timeout_popup),
      cmocka_unit_test(test_connection_refused_popup),
      cmocka_unit_test(test_loopback_only),
      cmocka_unit_test(test_cancel),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
