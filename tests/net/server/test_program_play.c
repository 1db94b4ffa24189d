/* SPDX-License-Identifier: Apache-2.0
 * tests/net/server/test_program_play.c — the dashboard's programs in-process: an External
 * Control node's fetch runs off the I/O thread (the dashboard answers while it is in flight)
 * and is bounded (destroying the emulator mid-fetch returns promptly, against a server that
 * trickles bytes and would hold the URCap for its whole timeout), and a non-loopback External
 * Control host is refused at create. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/core.h"
#include "urt/loop.h"
#include "urt/net/emulator.h"

static const char *kHost;  // urt_test_host: one of this process, UR's own ports

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

//---- a ScriptSender that answers one byte every 100 ms, forever (until told to stop) ----

typedef struct trickler {
  int listen_fd, port;
  _Atomic int got_request, stop;
  pthread_t thread;
} trickler_t;

static void *trickle_main(void *arg) {
  trickler_t *t = arg;
  int c = accept(t->listen_fd, NULL, NULL);
  if (c < 0) return NULL;
  char req[64];
  if (recv(c, req, sizeof req, 0) > 0) atomic_store(&t->got_request, 1);
  while (!atomic_load(&t->stop)) {
    if (send(c, "#", 1, MSG_NOSIGNAL) != 1) break;  // never a newline, never quiet
    struct timespec ts = {0, 100 * 1000000L};
    nanosleep(&ts, NULL);
  }
  close(c);
  return NULL;
}

static void trickler_start(trickler_t *t) {
  t->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET};
  inet_pton(AF_INET, kHost, &sa.sin_addr);
  assert_int_equal(bind(t->listen_fd, (struct sockaddr *)&sa, sizeof sa), 0);
  socklen_t sl = sizeof sa;
  getsockname(t->listen_fd, (struct sockaddr *)&sa, &sl);
  t->port = ntohs(sa.sin_port);
  assert_int_equal(listen(t->listen_fd, 1), 0);
  pthread_create(&t->thread, NULL, trickle_main, t);
}

//---- helpers ----

static void write_urp(const char *path, const char *xml) {
  gzFile f = gzopen(path, "wb");
  assert_non_null(f);
  gzputs(f, xml);
  gzclose(f);
}

static int dash_connect(int port) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
  inet_pton(AF_INET, kHost, &sa.sin_addr);
  struct timeval tv = {.tv_sec = 2};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  assert_int_equal(connect(fd, (struct sockaddr *)&sa, sizeof sa), 0);
  return fd;
}

/* One line (without "\n") into reply. */
static void read_line(int fd, char *reply, size_t cap) {
  size_t n = 0;
  while (n + 1 < cap) {
    ssize_t r = recv(fd, reply + n, 1, 0);
    assert_true(r == 1);
    if (reply[n] == '\n') break;
    n++;
  }
  reply[n] = '\0';
}

/* One request line, its reply line. */
static void ask(int fd, const char *line, char *reply, size_t cap) {
  send(fd, line, strlen(line), MSG_NOSIGNAL);
  send(fd, "\n", 1, MSG_NOSIGNAL);
  read_line(fd, reply, cap);
}

static const char kExternalControlUrp[] =
    "<URProgram name=\"external_control\"><children><InitVariablesNode/>"
    "<MainProgram runOnlyOnce=\"true\"><children>"
    "<Contributed strategyClass=\"com.fzi.externalcontrol.ExternalControlNode\" "
    "strategyProgramNodeType=\"External Control\"><dataModel/></Contributed>"
    "</children></MainProgram></children></URProgram>";

//---- tests ----

static void test_program_play__fetch_is_off_the_io_thread_and_bounded(void **state) {
  (void)state;
  kHost = urt_test_host(3, 1);  // an address of our own: parallel runs never collide
  char dir[] = "/tmp/urt_play_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/external_control.urp", dir);
  write_urp(path, kExternalControlUrp);

  trickler_t t = {0};
  trickler_start(&t);

  urt_model_t *m = urt_test_model(NULL);
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  urt_loop_t *loop = NULL;
  char err[256];
  assert_int_equal(urt_loop_create(m, &lc, NULL, &loop, err, sizeof err), 0);
  int offset = 0;
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = offset, .programs_dir = dir,
                              .external_control_host = kHost,
                              .external_control_port = t.port};
  assert_int_equal(urt_version_parse("5.19", &ec.version), 0);
  urt_emulator_t *emu = NULL;
  if (urt_emulator_create(loop, &ec, &emu, err, sizeof err) != 0) fail_msg("%s", err);
  urt_loop_start(loop);
  urt_emulator_start(emu);

  int d = dash_connect(29999 + offset);
  char reply[512];
  read_line(d, reply, sizeof reply);
  assert_string_equal(reply, "Connected: Universal Robots Dashboard Server");
  ask(d, "load external_control.urp", reply, sizeof reply);
  assert_string_equal(reply, "Loading program: /programs/external_control.urp");
  ask(d, "play", reply, sizeof reply);
  assert_string_equal(reply, "Starting program");
  double t0 = now_s();
  while (!atomic_load(&t.got_request) && now_s() - t0 < 5) {
    struct timespec ts = {0, 10 * 1000000L};
    nanosleep(&ts, NULL);
  }
  assert_true(atomic_load(&t.got_request));

  // the fetch is in flight (the server trickles): the dashboard still answers at once
  ask(d, "get loaded program", reply, sizeof reply);
  assert_string_equal(reply, "Loaded program: /programs/external_control.urp");
  close(d);

  // and destroying the emulator cancels it: far sooner than the 10 s the exchange may take
  double t1 = now_s();
  urt_emulator_destroy(emu);
  double took = now_s() - t1;
  print_message("destroy mid-fetch took %.3f s\n", took);
  assert_true(took < 3.0);  // a bound on a cancel that polls every 50 ms, not a timing claim

  urt_loop_destroy(loop);
  urt_model_free(m);
  atomic_store(&t.stop, 1);
  pthread_join(t.thread, NULL);
  close(t.listen_fd);
  unlink(path);
  rmdir(dir);
}

//---- a ScriptSender that answers every connection, 100 ms late (two in a row stay well inside
// the 500 ms read timeout) ----

typedef struct answerer {
  int listen_fd, port;
  _Atomic int requests, stop;
  pthread_t thread;
} answerer_t;

static void *answer_main(void *arg) {
  answerer_t *a = arg;
  while (!atomic_load(&a->stop)) {
    int c = accept(a->listen_fd, NULL, NULL);
    if (c < 0) break;
    char req[64];
    if (recv(c, req, sizeof req, 0) > 0) atomic_fetch_add(&a->requests, 1);
    struct timespec ts = {0, 100 * 1000000L};
    nanosleep(&ts, NULL);
    const char *prog = "textmsg(\"fetched\")\nsleep(5)\n";
    send(c, prog, strlen(prog), MSG_NOSIGNAL);
    close(c);
  }
  return NULL;
}

// play, stop while the fetch is in flight, play again at once: the second play is not lost
// (it starts once the cancelled fetch has wound down), and the stopped one never runs
static void test_program_play__stop_then_play_during_a_fetch(void **state) {
  (void)state;
  kHost = urt_test_host(3, 2);
  char dir[] = "/tmp/urt_play_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/external_control.urp", dir);
  write_urp(path, kExternalControlUrp);
  answerer_t a = {0};
  a.listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in sa = {.sin_family = AF_INET};
  inet_pton(AF_INET, kHost, &sa.sin_addr);
  assert_int_equal(bind(a.listen_fd, (struct sockaddr *)&sa, sizeof sa), 0);
  socklen_t sl = sizeof sa;
  getsockname(a.listen_fd, (struct sockaddr *)&sa, &sl);
  a.port = ntohs(sa.sin_port);
  assert_int_equal(listen(a.listen_fd, 4), 0);
  pthread_create(&a.thread, NULL, answer_main, &a);

  urt_model_t *m = urt_test_model(NULL);
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  urt_loop_t *loop = NULL;
  char err[256];
  assert_int_equal(urt_loop_create(m, &lc, NULL, &loop, err, sizeof err), 0);
  int offset = 0;
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = offset, .programs_dir = dir,
                              .external_control_host = kHost, .external_control_port = a.port};
  assert_int_equal(urt_version_parse("5.19", &ec.version), 0);
  urt_emulator_t *emu = NULL;
  if (urt_emulator_create(loop, &ec, &emu, err, sizeof err) != 0) fail_msg("%s", err);
  urt_loop_start(loop);
  urt_emulator_start(emu);

  int d = dash_connect(29999 + offset);
  char reply[512];
  read_line(d, reply, sizeof reply);
  ask(d, "load external_control.urp", reply, sizeof reply);
  assert_string_equal(reply, "Loading program: /programs/external_control.urp");
  ask(d, "play", reply, sizeof reply);
  assert_string_equal(reply, "Starting program");
  // while its program is being fetched, the program is starting: it plays for the dashboard
  ask(d, "programState", reply, sizeof reply);
  assert_string_equal(reply, "PLAYING external_control.urp");
  // both in one write: the I/O thread handles them microseconds apart, well inside the
  // cancelled fetch's wind-down (up to one 50 ms step)
  send(d, "stop\nplay\n", 10, MSG_NOSIGNAL);
  read_line(d, reply, sizeof reply);
  assert_string_equal(reply, "Stopped");
  read_line(d, reply, sizeof reply);
  assert_string_equal(reply, "Starting program");
  double t0 = now_s();
  do {
    ask(d, "programState", reply, sizeof reply);
    struct timespec ts = {0, 20 * 1000000L};
    nanosleep(&ts, NULL);
  } while (strncmp(reply, "PLAYING", 7) != 0 && now_s() - t0 < 5.0);
  assert_string_equal(reply, "PLAYING external_control.urp");
  // a second request went out, and once it is answered (100 ms, then its close) the
  // runner has the program: the state then comes from the controller, not from the fetch
  while (atomic_load(&a.requests) < 2 && now_s() - t0 < 5.0) {
    struct timespec ts = {0, 20 * 1000000L};
    nanosleep(&ts, NULL);
  }
  assert_int_equal(atomic_load(&a.requests), 2);
  struct timespec settle = {1, 500 * 1000000L};
  nanosleep(&settle, NULL);
  ask(d, "programState", reply, sizeof reply);
  assert_string_equal(reply, "PLAYING external_control.urp");
  assert_int_equal(atomic_load(&a.requests), 2);  // the stopped fetch was never retried
  ask(d, "stop", reply, sizeof reply);
  assert_string_equal(reply, "Stopped");
  close(d);

  urt_emulator_destroy(emu);
  urt_loop_destroy(loop);
  urt_model_free(m);
  atomic_store(&a.stop, 1);
  shutdown(a.listen_fd, SHUT_RDWR);
  close(a.listen_fd);
  pthread_join(a.thread, NULL);
  unlink(path);
  rmdir(dir);
}

static void test_program_play__non_loopback_external_control_host_refused(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  urt_loop_config_t lc = {.period = 0.002, .pacing = URT_PACING_TICK, .powered = 1};
  urt_loop_t *loop = NULL;
  char err[256];
  assert_int_equal(urt_loop_create(m, &lc, NULL, &loop, err, sizeof err), 0);
  kHost = urt_test_host(3, 3);
  urt_emulator_config_t ec = {.bind = kHost, .port_offset = 0,
                              .external_control_host = "192.168.56.1"};
  assert_int_equal(urt_version_parse("5.19", &ec.version), 0);
  urt_emulator_t *emu = NULL;
  assert_int_not_equal(urt_emulator_create(loop, &ec, &emu, err, sizeof err), 0);
  assert_non_null(strstr(err, "192.168.56.1:50002: only loopback addresses"));
  urt_loop_destroy(loop);
  urt_model_free(m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_program_play__fetch_is_off_the_io_thread_and_bounded),
      cmocka_unit_test(test_program_play__stop_then_play_during_a_fetch),
      cmocka_unit_test(test_program_play__non_loopback_external_control_host_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
