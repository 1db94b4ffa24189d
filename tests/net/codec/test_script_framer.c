/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/test_script_framer.c — URScript framing (net/codec/script_framer.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/script_framer.h"

//---- a recorder of units ----

#define MAX_UNITS 256

typedef struct rec {
  int n;
  int kind[MAX_UNITS], command[MAX_UNITS], error[MAX_UNITS];
  char *text[MAX_UNITS];
  size_t len[MAX_UNITS];
  char name[MAX_UNITS][64];
  uint64_t line[MAX_UNITS];
} rec_t;

static void on_unit(void *user, const urt_script_unit_t *u) {
  rec_t *r = user;
  assert_true(r->n < MAX_UNITS);
  assert_int_equal(u->text[u->len], '\0');
  assert_null(memchr(u->text, '\r', u->len));
  int i = r->n++;
  r->kind[i] = u->kind;
  r->command[i] = u->command;
  r->error[i] = u->error_code;
  assert_true((u->kind == URT_SCRIPT_UNIT_ERROR) == (u->error != NULL));
  r->text[i] = malloc(u->len + 1);
  memcpy(r->text[i], u->text, u->len + 1);
  r->len[i] = u->len;
  size_t nl = u->name_len < 63 ? u->name_len : 63;
  if (nl) {
    memcpy(r->name[i], u->name, nl);
  }
  r->name[i][nl] = '\0';
  r->line[i] = u->line;
}

static void rec_free(rec_t *r) {
  for (int i = 0; i < r->n; i++) {
    free(r->text[i]);
  }
  r->n = 0;
}

/* Frame text fed in chunks of `chunk` bytes (0: all at once), then flush. */
static void frame(rec_t *r, const char *text, size_t n, size_t chunk, size_t max_unit) {
  urt_script_framer_t f;
  memset(r, 0, sizeof *r);
  urt_script_framer_init_max(&f, max_unit);
  if (chunk == 0) {
    chunk = n ? n : 1;
  }
  int total = 0;
  for (size_t off = 0; off < n; off += chunk) {
    size_t k = n - off < chunk ? n - off : chunk;
    total += urt_script_framer_feed(&f, text + off, k, on_unit, r);
  }
  total += urt_script_framer_finish(&f, on_unit, r);
  assert_int_equal(total, r->n);
  urt_script_framer_free(&f);
}

static void assert_same_units(const rec_t *a, const rec_t *b) {
  assert_int_equal(a->n, b->n);
  for (int i = 0; i < a->n; i++) {
    assert_int_equal(a->kind[i], b->kind[i]);
    assert_int_equal(a->command[i], b->command[i]);
    assert_int_equal(a->error[i], b->error[i]);
    assert_int_equal(a->len[i], b->len[i]);
    assert_memory_equal(a->text[i], b->text[i], a->len[i]);
    assert_string_equal(a->name[i], b->name[i]);
    assert_int_equal(a->line[i], b->line[i]);
  }
}

//---- cases ----

static const char kMixed[] =
    "power on\r\n"
    "set robotmode run\n"
    "  # a comment line\n"
    "\n"
    "stop program\n"
    "def externalControl():\n"
    "  global x = 1  # def if while: not counted here\n"
    "  textmsg(\"end if def \\\" end\")\n"
    "  thread t():\n"
    "    while True:\n"
    "      if x > 1:\n"
    "        x = 0\n"
    "      elif x < 0:\n"
    "        x = 1\n"
    "      else:\n"
    "        end_force_mode()\n"
    "      end\n"
    "      sync()\n"
    "    end\n"
    "  end\n"
    "  def inner(a):\n"
    "    for i in range(3):\n"
    "      a = a + i\n"
    "    end\n"
    "    return a\n"
    "  end\n"
    "$ 1 \"Robot Program\"\n"
    "  thr = run t()\n"
    "end\n"
    "sec setup():\n"
    "  set_payload(1.0, [0, 0, 0.1])\n"
    "end\n"
    "movej([0, -1.57, 0, -1.57, 0, 0], a=1.4, v=1.05)\n"
    "set_digital_out(2, True)\n"
    "set sim\n"
    "set real\n"
    "set unlock protective stop\n"
    "power off\n"
    "set foo bar\n"
    "while True:\n"
    "  sync()\n"
    "end\n"
    "textmsg(\"no newline\")";

static void test_script_framer__splits_commands_programs_and_statements(void **state) {
  rec_t r;
  frame(&r, kMixed, sizeof kMixed - 1, 0, 0);
  static const int kinds[] = {
      URT_SCRIPT_UNIT_COMMAND,   URT_SCRIPT_UNIT_COMMAND,   URT_SCRIPT_UNIT_COMMAND,
      URT_SCRIPT_UNIT_PROGRAM,   URT_SCRIPT_UNIT_SECONDARY, URT_SCRIPT_UNIT_STATEMENT,
      URT_SCRIPT_UNIT_STATEMENT, URT_SCRIPT_UNIT_COMMAND,   URT_SCRIPT_UNIT_COMMAND,
      URT_SCRIPT_UNIT_COMMAND,   URT_SCRIPT_UNIT_COMMAND,   URT_SCRIPT_UNIT_COMMAND,
      URT_SCRIPT_UNIT_STATEMENT, URT_SCRIPT_UNIT_STATEMENT};
  assert_int_equal(r.n, sizeof kinds / sizeof kinds[0]);
  for (int i = 0; i < r.n; i++) {
    if (r.kind[i] != kinds[i]) {
      fail_msg("unit %d: kind %d, expected %d: '%s'", i, r.kind[i], kinds[i], r.text[i]);
    }
  }
  assert_int_equal(r.command[0], URT_SCRIPT_CMD_POWER_ON);
  assert_string_equal(r.text[0], "power on");
  assert_int_equal(r.command[1], URT_SCRIPT_CMD_BRAKE_RELEASE);
  assert_int_equal(r.command[2], URT_SCRIPT_CMD_STOP_PROGRAM);
  assert_int_equal(r.line[2], 5);
  assert_string_equal(r.name[3], "externalControl");
  assert_int_equal(r.line[3], 6);
  assert_true(strncmp(r.text[3], "def externalControl():\n", 23) == 0);
  assert_true(strcmp(r.text[3] + r.len[3] - 4, "\nend") == 0);
  assert_string_equal(r.name[4], "setup");
  assert_string_equal(r.text[5], "movej([0, -1.57, 0, -1.57, 0, 0], a=1.4, v=1.05)");
  assert_int_equal(r.command[7], URT_SCRIPT_CMD_SET_SIM);
  assert_int_equal(r.command[8], URT_SCRIPT_CMD_SET_REAL);
  assert_int_equal(r.command[9], URT_SCRIPT_CMD_UNLOCK_PSTOP);
  assert_int_equal(r.command[10], URT_SCRIPT_CMD_POWER_OFF);
  assert_int_equal(r.command[11], URT_SCRIPT_CMD_UNKNOWN);
  assert_string_equal(r.text[12], "while True:\n  sync()\nend");
  assert_string_equal(r.text[13], "textmsg(\"no newline\")");
  rec_free(&r);
}

static void test_script_framer__every_chunking_gives_the_same_units(void **state) {
  rec_t whole, part;
  frame(&whole, kMixed, sizeof kMixed - 1, 0, 0);
  for (size_t chunk = 1; chunk <= 17; chunk++) {
    frame(&part, kMixed, sizeof kMixed - 1, chunk, 0);
    assert_same_units(&whole, &part);
    rec_free(&part);
  }

  // every single split point
  for (size_t cut = 0; cut <= sizeof kMixed - 1; cut++) {
    urt_script_framer_t f;
    memset(&part, 0, sizeof part);
    urt_script_framer_init(&f);
    urt_script_framer_feed(&f, kMixed, cut, on_unit, &part);
    urt_script_framer_feed(&f, kMixed + cut, sizeof kMixed - 1 - cut, on_unit, &part);
    urt_script_framer_finish(&f, on_unit, &part);
    urt_script_framer_free(&f);
    assert_same_units(&whole, &part);
    rec_free(&part);
  }
  rec_free(&whole);
}

static void test_script_framer__end_inside_strings_and_comments_does_not_close(void **state) {
  const char text[] =
      "def f():\n"
      "  textmsg(\"end\")  # end end end\n"
      "  s = 'end'\n"
      "  # end\n"
      "  x = \"unterminated end\n"
      "  y = 2\n"
      "end\n"
      "textmsg(1)\n";
  rec_t r;
  frame(&r, text, sizeof text - 1, 0, 0);
  assert_int_equal(r.n, 2);
  assert_int_equal(r.kind[0], URT_SCRIPT_UNIT_PROGRAM);
  assert_int_equal(r.kind[1], URT_SCRIPT_UNIT_STATEMENT);
  assert_int_equal(r.line[1], 8);
  rec_free(&r);
}

static void test_script_framer__program_waits_for_its_end(void **state) {
  urt_script_framer_t f;
  rec_t r;
  memset(&r, 0, sizeof r);
  urt_script_framer_init(&f);
  assert_int_equal(urt_script_framer_feed(&f, "def p():\n  if True:\n", 20, on_unit, &r), 0);
  assert_int_equal(urt_script_framer_feed(&f, "  end\n", 6, on_unit, &r), 0);
  assert_int_equal(urt_script_framer_feed(&f, "end", 3, on_unit, &r), 0);  /* needs "\n" */
  assert_int_equal(urt_script_framer_feed(&f, "\n", 1, on_unit, &r), 1);
  assert_int_equal(r.kind[0], URT_SCRIPT_UNIT_PROGRAM);

  // an open block at the end of the stream is an error
  assert_int_equal(urt_script_framer_feed(&f, "def q():\n  x = 1\n", 17, on_unit, &r), 0);
  assert_int_equal(urt_script_framer_finish(&f, on_unit, &r), 1);
  assert_int_equal(r.kind[1], URT_SCRIPT_UNIT_ERROR);
  assert_int_equal(r.error[1], URT_SCRIPT_ERR_INCOMPLETE);
  assert_string_equal(r.text[1], "def q():\n  x = 1");
  urt_script_framer_free(&f);
  rec_free(&r);
}

static void test_script_framer__oversize_unit_is_an_error_then_framing_resumes(void **state) {
  // a long single line, then a long program, each followed by a good statement
  char text[4096];
  size_t n = 0;
  n += (size_t)sprintf(text + n, "textmsg(\"");
  for (int i = 0; i < 300; i++) {
    text[n++] = 'x';
  }
  n += (size_t)sprintf(text + n, "\")\nset_digital_out(1, True)\ndef big():\n");
  for (int i = 0; i < 40; i++) {
    n += (size_t)sprintf(text + n, "  if x:\n    movej([0,0,0,0,0,%d])\n  end\n", i);
  }
  n += (size_t)sprintf(text + n, "end\ntextmsg(\"after\")\npower on\n");

  rec_t r;
  frame(&r, text, n, 0, 256);
  assert_int_equal(r.n, 5);
  assert_int_equal(r.kind[0], URT_SCRIPT_UNIT_ERROR);
  assert_int_equal(r.error[0], URT_SCRIPT_ERR_OVERSIZE);
  assert_int_equal(r.len[0], URT_SCRIPT_ERROR_EXCERPT);
  assert_int_equal(r.line[0], 1);
  assert_string_equal(r.text[1], "set_digital_out(1, True)");
  assert_int_equal(r.kind[2], URT_SCRIPT_UNIT_ERROR);
  assert_int_equal(r.line[2], 3);
  assert_true(strncmp(r.text[2], "def big():", 10) == 0);
  assert_string_equal(r.text[3], "textmsg(\"after\")");  /* no fragment of big() leaked */
  assert_int_equal(r.command[4], URT_SCRIPT_CMD_POWER_ON);

  // the same at every chunking
  for (size_t chunk = 1; chunk < 40; chunk += 3) {
    rec_t p;
    frame(&p, text, n, chunk, 256);
    assert_same_units(&r, &p);
    rec_free(&p);
  }
  rec_free(&r);
}

static void test_script_framer__garbage_and_nul_bytes_do_not_crash(void **state) {
  unsigned char junk[8192];
  uint32_t x = 12345;
  for (size_t i = 0; i < sizeof junk; i++) {
    x = x * 1103515245u + 12345u;
    junk[i] = (unsigned char)(x >> 16);
  }
  junk[100] = '\0';
  junk[200] = '\n';
  rec_t r;
  frame(&r, (const char *)junk, sizeof junk, 7, 512);
  for (int i = 0; i < r.n; i++) {
    assert_true(r.len[i] <= 512);
    assert_null(memchr(r.text[i], '\0', r.len[i]));
  }
  rec_free(&r);

  // NUL inside a statement is dropped
  const char text[] = "text\0msg(1)\n";
  frame(&r, text, sizeof text - 1, 0, 0);
  assert_int_equal(r.n, 1);
  assert_string_equal(r.text[0], "textmsg(1)");
  rec_free(&r);
}

static void test_script_framer__commands_and_a_missing_callback(void **state) {
  urt_script_framer_t f;
  urt_script_framer_init(&f);
  assert_int_equal(f.max_unit, URT_SCRIPT_MAX_UNIT_DEFAULT);
  assert_int_equal(urt_script_framer_feed(&f, "power on\nx = 1\n", 15, NULL, NULL), 2);
  urt_script_framer_free(&f);
  assert_int_equal(urt_script_command_of("  power   on ", 13), URT_SCRIPT_CMD_POWER_ON);
  assert_int_equal(urt_script_command_of("power on()", 10), -1);
  assert_int_equal(urt_script_command_of("halt", 4), -1);
  assert_int_equal(urt_script_command_of("movej x", 7), -1);
}

/* ur_rtde 1.6.5's control script (tests/net/codec/data, or the installed wheel's text). */
static void test_script_framer__large_nested_program_is_one_unit(void **state) {
  // build a 60 kB program with nested defs, threads, loops and ifs
  size_t cap = 1 << 17, n = 0;
  char *text = malloc(cap);
  n += (size_t)snprintf(text + n, cap - n, "stop program\ndef rtde_control():\n");
  for (int d = 0; d < 200; d++) {
    n += (size_t)snprintf(text + n, cap - n,
                          "  def f%d(a):\n"
                          "    # if while for thread end\n"
                          "    while a > 0:\n"
                          "      if a == 3:\n"
                          "        textmsg(\"end of %d\")\n"
                          "      elif a == 2:\n"
                          "        a = a - 1\n"
                          "      else:\n"
                          "        end_freedrive_mode()\n"
                          "      end\n"
                          "      a = a - 1\n"
                          "    end\n"
                          "    return a\n"
                          "  end\n"
                          "  thread t%d():\n"
                          "    for i in range(2):\n"
                          "      sync()\n"
                          "    end\n"
                          "  end\n",
                          d, d, d);
  }
  n += (size_t)snprintf(text + n, cap - n, "  f0(3)\nend\nset_digital_out(0, True)\n");
  assert_true(n > 50000 && n < cap);

  rec_t r;
  for (size_t chunk = 0; chunk < 5000; chunk = chunk ? chunk * 3 : 1) {
    frame(&r, text, n, chunk, 0);
    assert_int_equal(r.n, 3);
    assert_int_equal(r.kind[0], URT_SCRIPT_UNIT_COMMAND);
    assert_int_equal(r.kind[1], URT_SCRIPT_UNIT_PROGRAM);
    assert_string_equal(r.name[1], "rtde_control");
    assert_int_equal(r.len[1], n - strlen("stop program\n") - strlen("\nset_digital_out(0, True)\n"));
    assert_int_equal(r.kind[2], URT_SCRIPT_UNIT_STATEMENT);
    rec_free(&r);
  }
  free(text);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_script_framer__splits_commands_programs_and_statements),
      cmocka_unit_test(test_script_framer__every_chunking_gives_the_same_units),
      cmocka_unit_test(test_script_framer__end_inside_strings_and_comments_does_not_close),
      cmocka_unit_test(test_script_framer__program_waits_for_its_end),
      cmocka_unit_test(test_script_framer__oversize_unit_is_an_error_then_framing_resumes),
      cmocka_unit_test(test_script_framer__garbage_and_nul_bytes_do_not_crash),
      cmocka_unit_test(test_script_framer__commands_and_a_missing_callback),
      cmocka_unit_test(test_script_framer__large_nested_program_is_one_unit),
  };
  return cmocka_run_group_tests_name("net/codec/script_framer", tests, NULL, NULL);
}
