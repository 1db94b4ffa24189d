/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/test_script_parse.c — lexer, parser and name check: good programs parse,
 * every error carries the controller's text, line and column. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "script.h"
#include "test_support.h"
#include "urt/errors.h"

static us_prog *parse_ok(const char *text) {
  us_prog *p = NULL;
  us_err e;
  int rc = urt__us_parse(text, strlen(text), &p, &e);
  if (rc != 0) {
    fail_msg("parse failed: %u:%u %s", e.line, e.column, e.text);
  }
  return p;
}

static void expect_error(const char *text, uint32_t line, uint32_t col, const char *msg) {
  urt_script_msg_t m;
  int rc = urt_script_check(text, strlen(text), &m);
  assert_int_equal(rc, URT_EINVAL);
  assert_int_equal(m.kind, URT_SCRIPT_MSG_RUNTIME_EXCEPTION);
  assert_string_equal(m.text, msg);
  assert_int_equal(m.line, line);
  assert_int_equal(m.column, col);
}

static void test_parse__program_with_every_construct(void **state) {
  const char *text =
      "def prog():\n"
      "  $ 1 \"Robot Program\"\n"
      "  # a comment\n"
      "  global count = 0\n"
      "  local x = 1.5e-1\n"
      "  while count < 3 do\n"
      "    count = count + 1\n"
      "  end\n"
      "  if count == 3 then\n"
      "    textmsg(\"three\")\n"
      "  elif count > 3:\n"
      "    halt\n"
      "  else:\n"
      "    textmsg('other', 2)\n"
      "  end\n"
      "  def twice(v, k=2):\n"
      "    return v * k\n"
      "  end\n"
      "  y = twice(x, k=3)\n"
      "  l = [1, 2, 3]\n"
      "  l[0] = -l[2]\n"
      "  q = p[0.1, 0.2, 0.3, 0, 3.14, 0]\n"
      "  ok = not (x > 1 and True) or False\n"
      "end\n";
  us_prog *p = parse_ok(text);
  assert_string_equal(p->name, "prog");
  assert_false(p->secondary);
  assert_int_equal(p->main->kind, N_DEF);
  assert_int_equal(p->n_defs, 2);
  urt__us_prog_free(p);
}

static void test_parse__python_urx_one_liners(void **state) {
  const char *lines[] = {
      "movej([0.1, -1.5, 1.2, -1.0, -1.5, 0.0], a=0.1, v=0.05, r=0)\n",
      "digital_out[2]=True\n",
      "set_tcp(p[0.0, 0.0, 0.1, 0, 0, 0])\n",
      "set_payload(1.5, (0, 0, 0.05))\n",
      "textmsg(\"hello\")\n",
      "movel(p[0.1, 0.2, 0.3, 0.0, 3.14, 0.0], a=0.1, v=0.05, r=0)\n",
      "servoj([0.1, -1.5, 1.2, -1.0, -1.5, 0.0], a=0.1, v=0.05, t=0.008, lookahead_time=0.1, gain=300)\n",
      "stopj(1.5)\n",
      "speedj([0.1, 0, 0, 0, 0, 0], 0.5, 0.1)\n",
      "set_digital_out(2,True)\n",
  };
  for (size_t k = 0; k < sizeof lines / sizeof lines[0]; k++) {
    us_prog *p = parse_ok(lines[k]);
    assert_string_equal(p->name, "statement");
    urt__us_prog_free(p);
  }
}

static void test_parse__sec_program_is_secondary(void **state) {
  us_prog *p = parse_ok("sec setup():\n set_payload(1.0, [0, 0, 0.1])\nend\n");
  assert_true(p->secondary);
  assert_string_equal(p->name, "setup");
  urt__us_prog_free(p);
}

static void test_parse__numbers(void **state) {
  us_prog *p = parse_ok("x = [1, 2.5, .5, 1e3, 2.5E-2, 99999999999999999999]\n");
  const us_node *list = p->main->a->kids[0]->b;
  assert_int_equal(list->kind, N_LIST);
  assert_int_equal(list->kids[0]->kind, N_INT);
  assert_int_equal(list->kids[0]->i, 1);
  assert_int_equal(list->kids[1]->kind, N_FLOAT);
  assert_true(list->kids[2]->f == 0.5);
  assert_true(list->kids[3]->f == 1000.0);
  assert_true(list->kids[4]->f == 0.025);
  assert_int_equal(list->kids[5]->kind, N_FLOAT);  // too big for an int
  urt__us_prog_free(p);
}

static void test_parse__unknown_function_is_a_compile_error_at_its_position(void **state) {
  // the exact case of URCL's test_program_execution_reports_exception
  expect_error("def illegal_fun():\n  calldoesntexist()\nend", 2, 3,
               "compile_error_name_not_found:calldoesntexist:");
}

static void test_parse__unsupported_function_compiles_for_a_runtime_error(void **state) {
  // a controller function urtwin does not run compiles (client scripts hold such calls in
  // branches their commands pick); reaching it is a runtime error naming it (script_interp)
  us_prog *p = parse_ok("def f():\n  if False:\n    movec([0,0,0,0,0,0], [0,0,0,0,0,0])\n  end\nend\n");
  urt__us_prog_free(p);
}

static void test_parse__unknown_variable_is_a_compile_error(void **state) {
  expect_error("def f():\n  x = 1\n  y = x + zz\nend\n", 3, 11, "compile_error_name_not_found:zz:");
}

static void test_parse__syntax_error_names_the_line(void **state) {
  // unbalanced parenthesis: the error shows at the next token, `end` on line 3
  expect_error("def unbalanced_parens():\n    textmsg(\"log \", get_actual_tcp_pose()\nend\n", 3, 1,
               "syntax_error_on_line:3:end:");
  expect_error("def f():\n    movej([0.5, -1, -2, 0, 0, -0], a=0.25, v=1.0))\nend\n", 2, 50,
               "syntax_error_on_line:2:    movej([0.5, -1, -2, 0, 0, -0], a=0.25, v=1.0)):");
}

static void test_parse__missing_end(void **state) {
  expect_error("def f():\n  x = 1\n", 3, 1, "syntax_error_on_line:3::");
}

static void test_parse__unterminated_string(void **state) {
  expect_error("textmsg(\"abc)\n", 1, 9, "syntax_error_on_line:1:textmsg(\"abc):");
}

static void test_parse__bad_character(void **state) {
  expect_error("x = 1 @ 2\n", 1, 7, "syntax_error_on_line:1:x = 1 @ 2:");
}

static void test_parse__threads_parse(void **state) {
  us_prog *p = parse_ok("def f():\n  thread t():\n    enter_critical\n    sync()\n    exit_critical\n"
                        "  end\n  h = run t()\n  join h\n  kill h\nend\n");
  urt__us_prog_free(p);
}

static void test_parse__thread_errors(void **state) {
  // run names a thread, not a function; a thread takes no parameters; `for` is not URScript
  expect_error("def f():\n  def g():\n  end\n  h = run g()\nend\n", 4, 7,
               "compile_error_name_not_found:g:");
  expect_error("def f():\n  thread t():\n  end\n  t()\nend\n", 4, 3,
               "compile_error_name_not_found:t:");
  urt_script_msg_t m;
  const char *params = "def f():\n  thread t(x):\n  end\nend\n";
  assert_int_equal(urt_script_check(params, strlen(params), &m), URT_EINVAL);
  assert_non_null(strstr(m.text, "syntax_error_on_line:2:"));
  expect_error("def f():\n  for x in y:\n  end\nend\n", 2, 3, "compile_error_unsupported:for:");
}

static void test_parse__nesting_deeper_than_64_is_refused(void **state) {
  char text[1024] = "x = ";
  for (int k = 0; k < 70; k++) strcat(text, "(");
  strcat(text, "1");
  for (int k = 0; k < 70; k++) strcat(text, ")");
  urt_script_msg_t m;
  assert_int_equal(urt_script_check(text, strlen(text), &m), URT_EINVAL);
  assert_non_null(strstr(m.text, "syntax_error_on_line:1:"));
}

static void test_parse__list_longer_than_1024_is_refused(void **state) {
  static char text[8192];
  strcpy(text, "x = [");
  for (int k = 0; k < 1100; k++) strcat(text, k ? ",1" : "1");
  strcat(text, "]\n");
  assert_int_equal(urt_script_check(text, strlen(text), NULL), URT_EINVAL);
}

static void test_parse__empty_and_oversized_units_are_refused(void **state) {
  assert_int_equal(urt_script_check("  # only a comment\n", 19, NULL), URT_EINVAL);
  assert_int_equal(urt_script_check("x=1", URT_SCRIPT_MAX_TEXT + 1, NULL), URT_EINVAL);
}

static void test_parse__assignment_to_call_is_a_syntax_error(void **state) {
  expect_error("f() = 1\n", 1, 5, "syntax_error_on_line:1:f() = 1:");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_parse__program_with_every_construct),
      cmocka_unit_test(test_parse__python_urx_one_liners),
      cmocka_unit_test(test_parse__sec_program_is_secondary),
      cmocka_unit_test(test_parse__numbers),
      cmocka_unit_test(test_parse__unknown_function_is_a_compile_error_at_its_position),
      cmocka_unit_test(test_parse__unsupported_function_compiles_for_a_runtime_error),
      cmocka_unit_test(test_parse__unknown_variable_is_a_compile_error),
      cmocka_unit_test(test_parse__syntax_error_names_the_line),
      cmocka_unit_test(test_parse__missing_end),
      cmocka_unit_test(test_parse__unterminated_string),
      cmocka_unit_test(test_parse__bad_character),
      cmocka_unit_test(test_parse__threads_parse),
      cmocka_unit_test(test_parse__thread_errors),
      cmocka_unit_test(test_parse__nesting_deeper_than_64_is_refused),
      cmocka_unit_test(test_parse__list_longer_than_1024_is_refused),
      cmocka_unit_test(test_parse__empty_and_oversized_units_are_refused),
      cmocka_unit_test(test_parse__assignment_to_call_is_a_syntax_error),
  };
  return cmocka_run_group_tests_name("net/urscript/script_parse", tests, NULL, NULL);
}
