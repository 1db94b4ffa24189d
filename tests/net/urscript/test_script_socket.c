/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_socket.c — the URScript socket builtins against a scripted
 * peer on 127.0.0.1 (socket_fixture.h) and a fake controller: each read with its data arriving
 * in parts over several ticks, timeouts counted in ticks, a peer that closes, sends as the
 * peer receives them, a refused host; and determinism (issue 9): two threads, one exchanging
 * with an echo peer each tick, give the same per-tick command stream in every run, also with the
 * runner late. The echo answers inside the fake host's wait, so the replies arrive at the same
 * ticks each run: what varies is only the OS's timing, which must change nothing. */
#define _GNU_SOURCE
#include <pthread.h>
#include <math.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fake_host.h"
#include "script.h"
#include "socket_fixture.h"
#include "test_support.h"

static fake_host F;
static urt_script_host_t H;
static fixture X;
static us_sockets *T;
static us_err E;
static uint64_t motion_id;

static uint64_t wait_tick_with_peer(void *ctx, uint64_t after, int timeout_ms) {
  uint64_t t = fake_wait_tick(ctx, after, timeout_ms);
  fix_tick(&X, t);
  return t;
}

static int setup(void **state) {
  fake_init(&F, &H);
  H.wait_tick = wait_tick_with_peer;
  assert_int_equal(fix_listen(&X), 0);
  T = urt__us_sockets_new(NULL, 0);
  assert_non_null(T);
  X.table = T;
  memset(&E, 0, sizeof E);
  return 0;
}

static int teardown(void **state) {
  urt__us_sockets_free(T);
  fix_close(&X);
  return 0;
}

/* run a program whose text has %d for the fixture's port; returns urt__us_run's result */
static int run(const char *fmt) {
  char text[4096];
  snprintf(text, sizeof text, fmt, X.port);
  us_prog *p = NULL;
  if (urt__us_parse(text, strlen(text), &p, &E) != 0) {
    fail_msg("parse: %u:%u %s", E.line, E.column, E.text);
  }
  us_hooks h = {.host = &H, .sockets = T, .motion_id = &motion_id, .step_budget = 100000,
                .wait_timeout_ms = 1};
  int rc = urt__us_run(p, &h, &E);
  urt__us_prog_free(p);
  fix_drain(&X);
  return rc;
}

static void must_run(const char *fmt) {
  if (run(fmt) != 0) fail_msg("run: %u:%u %s", E.line, E.column, E.text);
}

/* message k is text at tick (the fake's time is tick × 2 ms) */
static void assert_msg(int k, const char *text, uint64_t tick) {
  if (k >= F.n_msg) fail_msg("message %d of %d", k, F.n_msg);
  assert_string_equal(F.msg[k].text, text);
  if (fabs(F.msg[k].time - (double)tick * 0.002) > 1e-9) {
    fail_msg("message %d (%s) at tick %.0f, expected %llu", k, text, F.msg[k].time / 0.002,
             (unsigned long long)tick);
  }
}

static void test_socket__binary_integers_in_parts_over_ticks(void **state) {
  // 3 big-endian int32s split 3 + 6 + 3 bytes at ticks 10, 20, 30: the read completes at 30
  static const char rec[] = "\x00\x00\x01\x02" "\xff\xff\xff\xfb" "\x7f\xff\xff\xff";
  fix_at(&X, 10, rec, 3);
  fix_at(&X, 20, rec + 3, 6);
  fix_at(&X, 30, rec + 9, 3);
  must_run("ok = socket_open(\"127.0.0.1\", %d, \"s\")\n"
           "textmsg(ok)\n"
           "r = socket_read_binary_integer(3, \"s\", 1.0)\n"
           "textmsg(r)\n"
           "textmsg(r[1] + r[2])\n");
  assert_string_equal(F.msg[0].text, "True");
  assert_msg(1, "[3,258,-5,2147483647]", 30);
  assert_msg(2, "253", 30);
}

static void test_socket__timeout_counts_ticks_and_keeps_a_partial_record(void **state) {
  // 2 of 4 bytes come: the read (from tick 1, socket_open's cycle over) times out after
  // 0.1 s = 50 ticks; the rest completes the next
  fix_at(&X, 5, "\x00\x00", 2);
  fix_at(&X, 100, "\x00\x07", 2);
  must_run("socket_open(\"127.0.0.1\", %d, \"s\")\n"
           "textmsg(socket_read_binary_integer(1, \"s\", 0.1))\n"
           "textmsg(socket_read_binary_integer(1, \"s\", 0))\n");
  assert_msg(0, "[0,-1]", 51);
  assert_msg(1, "[1,7]", 100);  // timeout 0: waits for ever (until the data comes)
}

static void test_socket__byte_list_and_default_socket_name(void **state) {
  fix_at(&X, 3, "\x01\xfe", 2);
  fix_at(&X, 7, "\x80", 1);
  must_run("socket_open(\"localhost\", %d)\n"
           "textmsg(socket_read_byte_list(3))\n"
           "textmsg(socket_read_byte_list(2, timeout=0.01))\n");
  assert_msg(0, "[3,1,254,128]", 7);
  assert_msg(1, "[0,-1,-1]", 12);  // 0.01 s = 5 ticks
}

static void test_socket__ascii_floats_in_parts(void **state) {
  fix_at(&X, 4, "junk( 1.5, -2", 13);
  fix_at(&X, 9, "5e-1 , 3)(1,2)", 14);
  must_run("socket_open(\"127.0.0.1\", %d, \"f\")\n"
           "textmsg(socket_read_ascii_float(3, \"f\"))\n"
           "textmsg(socket_read_ascii_float(3, \"f\", 0.01))\n"
           "textmsg(socket_read_ascii_float(1, \"f\", 0.01))\n");
  assert_msg(0, "[3,1.5,-2.5,3]", 9);
  assert_msg(1, "[2,1,2,nan]", 9);   // fewer numbers than asked: the count says how many
  assert_msg(2, "[0,nan]", 14);      // nothing more: timeout after 5 ticks
}

static void test_socket__ascii_floats_invalid_reply(void **state) {
  fix_at(&X, 2, "(1, x, 3)", 9);
  must_run("socket_open(\"127.0.0.1\", %d)\n"
           "textmsg(socket_read_ascii_float(3))\n");
  assert_msg(0, "[0,nan,nan,nan]", 2);
}

static void test_socket__lines_in_parts(void **state) {
  fix_at(&X, 6, "hel", 3);
  fix_at(&X, 12, "lo\r\nworld\nre", 12);
  must_run("socket_open(\"127.0.0.1\", %d, \"l\")\n"
           "textmsg(socket_read_line(\"l\"))\n"
           "textmsg(socket_read_line(\"l\"))\n"
           "x = socket_read_line(\"l\", timeout=0.02)\n"
           "textmsg(str_len(x))\n");
  assert_msg(0, "hello", 12);
  assert_msg(1, "world", 12);
  assert_msg(2, "0", 22);  // "re" has no newline: "" after 10 ticks
}

static void test_socket__strings_with_prefix_and_suffix(void **state) {
  // UR's example: ">hello<>world<" read with prefix ">" and suffix "<"
  fix_at(&X, 5, "xx>hel", 6);
  fix_at(&X, 10, "lo<>wor", 7);
  fix_at(&X, 15, "ld<tail", 7);
  must_run("socket_open(\"127.0.0.1\", %d, \"t\")\n"
           "textmsg(socket_read_string(\"t\", prefix=\">\", suffix=\"<\"))\n"
           "textmsg(socket_read_string(\"t\", prefix=\">\", suffix=\"<\"))\n"
           "textmsg(socket_read_string(\"t\"))\n");
  assert_msg(0, "hello", 10);
  assert_msg(1, "world", 15);
  assert_msg(2, "tail", 15);  // no prefix or suffix: everything there is
}

static void test_socket__string_suffix_with_interpret_escape(void **state) {
  fix_at(&X, 5, "a b\nc\\n", 7);
  must_run("socket_open(\"127.0.0.1\", %d)\n"
           "textmsg(socket_read_string(suffix=\"\\\\n\", interpret_escape=True))\n"
           "textmsg(socket_read_string(suffix=\"\\\\n\"))\n");
  // escapes on: the suffix is a newline; off: the two characters backslash and n
  assert_msg(0, "a b", 5);
  assert_msg(1, "c", 5);
}

/* the peer writes a record when the program sets digital out 3, i.e. while the slice runs */
static bool submit_then_peer_writes(void *ctx, const urt_ctrl_cmd_t *c) {
  bool ok = fake_submit(ctx, c);
  if (c->kind == URT_CTRL_SET_DIGITAL_OUT && c->index == 3) {
    fix_send(&X, "\x00\x00\x00\x02", 4);
  }
  return ok;
}

static void test_socket__bytes_that_arrive_while_the_slice_runs_are_read_the_next_tick(void **state) {
  // record 1 is there when tick 5 starts; record 2 comes in the middle of tick 5's slice: a
  // second read in that slice waits for tick 6, as it would had the slice run faster
  H.submit = submit_then_peer_writes;
  fix_at(&X, 5, "\x00\x00\x00\x01", 4);
  must_run("socket_open(\"127.0.0.1\", %d, \"s\")\n"
           "textmsg(socket_read_binary_integer(1, \"s\", 0))\n"
           "set_standard_digital_out(3, True)\n"
           "textmsg(socket_read_binary_integer(1, \"s\", 0))\n");
  assert_msg(0, "[1,1]", 5);
  assert_msg(1, "[1,2]", 6);
}

/* a client that writes without pause (URCL's tool_contact_example), from its own thread */
typedef struct flood {
  int fd;
  volatile bool stop;
  long sent;
} flood;

static void *flood_main(void *arg) {
  flood *f = arg;
  static const char rec[4] = {0, 0, 0, 1};
  while (!f->stop) {
    ssize_t k = send(f->fd, rec, sizeof rec, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (k > 0) f->sent += k;
    else usleep(50);
  }
  return NULL;
}

static flood g_flood;
static pthread_t g_flood_thread;
static bool g_flood_on;

static uint64_t wait_tick_start_flood(void *ctx, uint64_t after, int timeout_ms) {
  uint64_t t = wait_tick_with_peer(ctx, after, timeout_ms);
  if (!g_flood_on && X.conn_fd >= 0) {
    g_flood = (flood){.fd = X.conn_fd};
    g_flood_on = pthread_create(&g_flood_thread, NULL, flood_main, &g_flood) == 0;
  }
  usleep(200);  // the peer keeps writing while the program waits, as a real client does
  return t;
}

static void test_socket__a_flooding_peer_is_drained_one_buffer_per_tick(void **state) {
  // the loop reads a record per iteration and only waits when the buffer is empty; with the
  // peer writing all the while, a read that went back to the kernel in the same slice never
  // found it empty and ran into the step budget ("Runtime is too much behind")
  H.wait_tick = wait_tick_start_flood;
  g_flood_on = false;
  int rc = run("def flooded():\n"
               "global ticks = 0\n"
               "thread clock():\n"
               "  while True:\n"
               "    ticks = ticks + 1\n"
               "    sync()\n"
               "  end\n"
               "end\n"
               "c = run clock()\n"
               "socket_open(\"127.0.0.1\", %d, \"s\")\n"
               "n = 0\n"
               "most = 0\n"
               "t0 = 0\n"
               "in_tick = 0\n"
               "while n < 20000:\n"
               "  r = socket_read_binary_integer(1, \"s\", 0)\n"
               "  n = n + r[1]\n"
               "  t = ticks\n"
               "  if t == t0:\n"
               "    in_tick = in_tick + 1\n"
               "  else:\n"
               "    t0 = t\n"
               "    in_tick = 1\n"
               "  end\n"
               "  if in_tick > most:\n"
               "    most = in_tick\n"
               "  end\n"
               "end\n"
               "kill c\n"
               "textmsg(most)\n"
               "end\n");
  g_flood.stop = true;
  if (g_flood_on) pthread_join(g_flood_thread, NULL);
  if (rc != 0) fail_msg("run: %u:%u %s", E.line, E.column, E.text);
  int most = atoi(F.msg[F.n_msg - 1].text);
  print_message("flood: %ld bytes sent, at most %d records read in one tick (buffer %d)\n",
                g_flood.sent, most, US_SOCK_RX / 4);
  assert_true(most >= 1 && most <= US_SOCK_RX / 4);
}

static void test_socket__peer_that_closes_fails_reads_at_once(void **state) {
  fix_at(&X, 4, "\x00\x00\x00\x09\x00", 5);
  fix_at(&X, 8, NULL, 0);
  must_run("socket_open(\"127.0.0.1\", %d)\n"
           "textmsg(socket_read_binary_integer(1, timeout=10))\n"
           "textmsg(socket_read_binary_integer(1, timeout=10))\n"
           "textmsg(socket_send_int(1))\n"
           "textmsg(socket_read_line(timeout=10))\n");
  assert_msg(0, "[1,9]", 4);
  assert_msg(1, "[0,-1]", 8);  // one byte was left: the close ends the read, no timeout
  assert_msg(3, "", 8);
}

static void test_socket__a_thread_polling_a_closed_socket_is_preempted_not_stopped(void **state) {
  // URCL's script_commands thread: a read with timeout 0 in a loop. Once the peer has closed
  // (tick 8) the read fails at once and the loop never waits; it is preempted at the end of
  // each slice (100000 steps here), the body goes on and ends it at tick 50. Before, it was
  // "Runtime is too much behind" in the first tick after the close.
  fix_at(&X, 8, NULL, 0);
  must_run("def p():\n"
           "  global stop = False\n"
           "  global fails = 0\n"
           "  thread poll():\n"
           "    while not stop:\n"
           "      r = socket_read_binary_integer(1, \"s\", 0)\n"
           "      if r[0] == 0:\n"
           "        fails = fails + 1\n"
           "      end\n"
           "    end\n"
           "  end\n"
           "  socket_open(\"127.0.0.1\", %d, \"s\")\n"
           "  h = run poll()\n"
           "  sleep(0.1)\n"
           "  stop = True\n"
           "  join h\n"
           "  textmsg(fails > 1000)\n"
           "end\n");
  assert_msg(0, "True", 52);  // opened at tick 1, stopped at 51, joined at 52
}

static void test_socket__sends_reach_the_peer(void **state) {
  must_run("socket_open(\"127.0.0.1\", %d, \"o\")\n"
           "socket_send_int(-2, \"o\")\n"
           "socket_send_byte(10, \"o\")\n"
           "socket_send_string(\"ab\", \"o\")\n"
           "socket_send_line(\"cd\", \"o\")\n"
           "socket_send_string(p[1, 0, 0, 0, 0, 0.5], \"o\")\n"
           "socket_set_var(\"POS\", 7, \"o\")\n"
           "textmsg(socket_send_int(1, \"nope\"))\n"
           "sync()\n");
  static const char want[] = "\xff\xff\xff\xfe\nabcd\np[1,0,0,0,0,0.5]SET POS 7\n";
  assert_int_equal(X.n_got, sizeof want - 1);
  assert_memory_equal(X.got, want, sizeof want - 1);
  assert_msg(0, "False", 1);  // a socket that is not open: False (after socket_open's tick)
}

static void test_socket__get_var_round_trip(void **state) {
  fix_at(&X, 10, "PRE 77\n", 7);
  fix_at(&X, 1100, "LATE 1\n", 7);
  must_run("socket_open(\"127.0.0.1\", %d, \"g\")\n"
           "textmsg(socket_get_var(\"PRE\", \"g\"))\n"
           "textmsg(socket_get_var(\"LATE\", \"g\"))\n");
  assert_string_equal(X.got, "GET PRE\nGET LATE\n");
  assert_msg(0, "77", 10);
  assert_msg(1, "0", 1010);  // no answer within 2 s = 1000 ticks: 0
}

static void test_socket__sends_have_nodelay(void **state) {
  // URCL acts only on a recv() of exactly 4 bytes: each socket_send_int is its own segment
  must_run("socket_open(\"127.0.0.1\", %d, \"n\")\n");
  int fd = fix_client_fd(&X), on = 0;
  socklen_t len = sizeof on;
  assert_true(fd >= 0);
  assert_int_equal(getsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, &len), 0);
  assert_true(on != 0);
}

/* socket_open blocks its thread into the next cycle even when the loopback connect completes
 * at once (URCL's servers, a thread each, must accept the trajectory socket before the
 * program's reverse connection, opened after it, lets the client send) */
static void test_socket__open_takes_a_cycle_even_on_loopback(void **state) {
  must_run("textmsg(\"start\")\n"
           "textmsg(socket_open(\"127.0.0.1\", %d, \"a\"))\n");
  assert_msg(0, "start", 0);
  assert_msg(1, "True", 1);
}

// A server on this machine that accepts late (a descheduled thread): socket_open ends when
// it has accepted, so that a program's next step (URCL's: open the reverse socket, which makes
// URCL send a point to this one) finds it accepted; at most 0.1 s (50 ticks) later.
static void test_socket__open_on_loopback_ends_when_the_server_has_accepted(void **state) {
  X.accept_from = 20;
  must_run("textmsg(socket_open(\"127.0.0.1\", %d, \"a\"))\n");
  assert_msg(0, "True", 20);
  assert_int_equal(T->accept_waits, 1);
  assert_int_equal(T->accept_wait_max, 19);
}

static void test_socket__open_waits_for_an_accept_at_most_a_tenth_of_a_second(void **state) {
  X.accept_from = 1000;
  must_run("textmsg(socket_open(\"127.0.0.1\", %d, \"a\"))\n"
           "textmsg(socket_send_int(7, \"a\"))\n");
  assert_msg(0, "True", 51);  // connected at tick 1, then 50 ticks
  assert_msg(1, "True", 51);  // open all along: the kernel took the connection
}

static void test_socket__open_refused_port_is_false(void **state) {
  char text[256];
  snprintf(text, sizeof text, "textmsg(socket_open(\"127.0.0.1\", %d, \"r\", 0.1))\n",
           fix_dead_port());
  must_run(text);
  assert_string_equal(F.msg[0].text, "False");
}

static void test_socket__open_non_loopback_host_is_a_runtime_error(void **state) {
  // refused before anything is dialled: no packet leaves 127.0.0.0/8
  assert_int_not_equal(run("socket_open(\"10.20.30.40\", %d)\n"), 0);
  assert_int_equal(E.kind, US_ERR_RUNTIME);
  assert_non_null(strstr(E.text, "\"10.20.30.40\""));
  assert_non_null(strstr(E.text, "--script-allow-host"));
  memset(&E, 0, sizeof E);
  // a name is never looked up unless allowed
  assert_int_not_equal(run("socket_open(\"robot.example.invalid\", %d)\n"), 0);
  assert_non_null(strstr(E.text, "robot.example.invalid"));
}

static void test_socket__reopen_and_close(void **state) {
  must_run("a = socket_open(\"127.0.0.1\", %d, \"s\")\n"
           "socket_close(\"s\")\n"
           "textmsg(socket_send_int(1, \"s\"))\n"
           "socket_close(\"never_opened\")\n");
  assert_msg(0, "False", 1);
}

/* the peer of close_all_wait: reads until EOF, waits 50 ms (a busy server), marks, closes */
static volatile int peer_closed;
static void *peer_reads_eof_then_closes(void *arg) {
  int fd = *(int *)arg;
  struct pollfd pf = {.fd = fd, .events = POLLIN};
  char b[64];
  while (poll(&pf, 1, 5000) > 0 && recv(fd, b, sizeof b, MSG_DONTWAIT) > 0) {
  }
  usleep(50000);
  peer_closed = 1;
  close(fd);
  return NULL;
}

// At a program's end the runner closes its sockets with close_all_wait: it returns only after
// the peer has seen the EOF and closed its end (URCL's one-client servers must have dropped
// the old connection before the next program dials them).
static void test_socket__close_all_wait_returns_after_the_peer_closed(void **state) {
  must_run("socket_open(\"127.0.0.1\", %d)\nsync()\n");
  assert_true(X.conn_fd >= 0);
  int fd = X.conn_fd;
  X.conn_fd = -1;  // the peer thread owns it now
  peer_closed = 0;
  pthread_t th;
  assert_int_equal(pthread_create(&th, NULL, peer_reads_eof_then_closes, &fd), 0);
  urt__us_sockets_close_all_wait(T, 5000);
  assert_true(peer_closed);
  assert_int_equal(fix_client_fd(&X), -1);
  pthread_join(th, NULL);
}

// A peer that never closes does not hold the program's end beyond the bound: the socket is
// closed all the same.
static void test_socket__close_all_wait_is_bounded(void **state) {
  must_run("socket_open(\"127.0.0.1\", %d)\nsync()\n");
  assert_true(X.conn_fd >= 0);
  urt__us_sockets_close_all_wait(T, 50);
  assert_int_equal(fix_client_fd(&X), -1);
  for (int k = 0; k < US_SOCK_MAX; k++) {
    assert_int_equal(T->s[k].state, US_SOCK_FREE);
  }
}

static void test_socket__bad_arguments_are_runtime_errors(void **state) {
  assert_int_not_equal(run("socket_read_binary_integer(31)\n"), 0);
  assert_non_null(strstr(E.text, "outside 1..30"));
  memset(&E, 0, sizeof E);
  assert_int_not_equal(run("socket_send_byte(256)\n"), 0);
  assert_non_null(strstr(E.text, "not a byte"));
  memset(&E, 0, sizeof E);
  assert_int_not_equal(run("socket_open(\"127.0.0.1\", \"%d\")\n"), 0);
  assert_int_equal(E.kind, US_ERR_RUNTIME);
}

static void test_socket__no_table_is_a_runtime_error(void **state) {
  us_prog *p = NULL;
  const char *text = "socket_close()\n";
  assert_int_equal(urt__us_parse(text, strlen(text), &p, &E), 0);
  us_hooks h = {.host = &H, .motion_id = &motion_id, .step_budget = 1000, .wait_timeout_ms = 1};
  assert_int_not_equal(urt__us_run(p, &h, &E), 0);
  assert_non_null(strstr(E.text, "sockets are not available"));
  urt__us_prog_free(p);
}

/* two threads, one of them asking an echo peer for each servoj target: the program the issue's
 * determinism check names */
static const char kEchoThreads[] =
    "def echo_two():\n"
    "  global total = 0\n"
    "  thread io():\n"
    "    k = 0\n"
    "    while k < 10:\n"
    "      set_standard_digital_out(k %% 8, k %% 2 == 0)\n"
    "      sleep(0.006)\n"
    "      k = k + 1\n"
    "    end\n"
    "  end\n"
    "  t = run io()\n"
    "  socket_open(\"127.0.0.1\", %d, \"echo\")\n"
    "  i = 0\n"
    "  while i < 20:\n"
    "    socket_send_line(str_cat(str_cat(\"(\", i), str_cat(\",\", str_cat(0.5 * i, \")\"))), \"echo\")\n"
    "    v = socket_read_ascii_float(2, \"echo\")\n"
    "    servoj([v[1], v[2], 0, 0, 0, 0], t=0.002)\n"
    "    total = total + v[1]\n"
    "    i = i + 1\n"
    "  end\n"
    "  join t\n"
    "  set_standard_digital_out(7, total == 190)\n"
    "end\n";

/* FNV-1a over each command (kind, index, value, q, t) and the VM tick it came in */
static uint64_t stream_hash(void) {
  uint64_t h = 1469598103934665603ull;
  for (int k = 0; k < F.n_cmd; k++) {
    const urt_ctrl_cmd_t *c = &F.cmd[k];
    double v[9] = {(double)c->kind, (double)c->index, c->value, c->t,
                   c->q[0], c->q[1], c->q[2], (double)F.cmd_vm_tick[k], 0};
    const unsigned char *b = (const unsigned char *)v;
    for (size_t j = 0; j < sizeof v; j++) h = (h ^ b[j]) * 1099511628211ull;
  }
  return h;
}

static void test_socket__echo_and_threads_give_the_same_stream_every_run(void **state) {
  X.echo = true;
  must_run(kEchoThreads);
  const uint64_t first = stream_hash();
  const int n_first = F.n_cmd;
  // the echoed targets drove servoj, one exchange per tick after the first
  int servo = 0;
  for (int k = 0; k < F.n_cmd; k++) {
    if (F.cmd[k].kind == URT_CTRL_SERVOJ) {
      assert_true(F.cmd[k].q[0] == servo && F.cmd[k].q[1] == 0.5 * servo);
      servo++;
    }
  }
  assert_int_equal(servo, 20);
  const urt_ctrl_cmd_t *last = &F.cmd[F.n_cmd - 1];
  assert_true(last->kind == URT_CTRL_SET_DIGITAL_OUT && last->index == 7 && last->value == 1);

  // again, from scratch; then once more with the controller 1–4 ticks ahead at every wait and
  // the runner descheduled meanwhile: the same commands at the same VM ticks
  for (int run_k = 0; run_k < 2; run_k++) {
    teardown(state);
    setup(state);
    X.echo = true;
    if (run_k == 1) {
      F.jump_seed = 4242;
      F.tick_sleep_us = 200;
    }
    must_run(kEchoThreads);
    assert_int_equal(F.n_cmd, n_first);
    assert_true(stream_hash() == first);
  }
  print_message("echo + threads: %d commands, stream hash %016llx in three runs (one late)\n",
                n_first, (unsigned long long)first);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_socket__binary_integers_in_parts_over_ticks, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__echo_and_threads_give_the_same_stream_every_run, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__timeout_counts_ticks_and_keeps_a_partial_record, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__byte_list_and_default_socket_name, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__ascii_floats_in_parts, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__ascii_floats_invalid_reply, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__lines_in_parts, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__strings_with_prefix_and_suffix, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__string_suffix_with_interpret_escape, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__peer_that_closes_fails_reads_at_once, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__bytes_that_arrive_while_the_slice_runs_are_read_the_next_tick, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__a_flooding_peer_is_drained_one_buffer_per_tick, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__a_thread_polling_a_closed_socket_is_preempted_not_stopped, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__sends_reach_the_peer, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__get_var_round_trip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__sends_have_nodelay, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__open_takes_a_cycle_even_on_loopback, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__open_on_loopback_ends_when_the_server_has_accepted, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__open_waits_for_an_accept_at_most_a_tenth_of_a_second, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__open_refused_port_is_false, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__open_non_loopback_host_is_a_runtime_error, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__reopen_and_close, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__close_all_wait_returns_after_the_peer_closed, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__close_all_wait_is_bounded, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__bad_arguments_are_runtime_errors, setup, teardown),
      cmocka_unit_test_setup_teardown(test_socket__no_table_is_a_runtime_error, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
