/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/test_version.c — the emulated version (net/codec/version.c). */
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/version.h"

static void test_version_parse__full_text(void **state) {
  urt_version_t v;
  assert_int_equal(urt_version_parse("5.19.0.1210631", &v), 0);
  assert_int_equal(v.major, 5);
  assert_int_equal(v.minor, 19);
  assert_int_equal(v.bugfix, 0);
  assert_int_equal(v.build, 1210631);
  assert_string_equal(v.date, "Oct 23 2024");
}

static void test_version_parse__missing_parts_take_the_line_defaults(void **state) {
  urt_version_t v;
  assert_int_equal(urt_version_parse("3", &v), 0);
  assert_int_equal(v.minor, 15);
  assert_int_equal(v.bugfix, 8);
  assert_int_equal(v.build, 106339);
  assert_string_equal(v.date, "Sep 14 2023");
  assert_int_equal(urt_version_parse("3.3", &v), 0);
  assert_int_equal(v.minor, 3);
  assert_int_equal(v.bugfix, 0);
  assert_int_equal(v.build, 106339);
  assert_int_equal(urt_version_parse("5.8", &v), 0);
  assert_int_equal(v.minor, 8);
  assert_int_equal(v.build, 1210631);
  assert_int_equal(urt_version_parse("5.19", &v), 0);
  assert_int_equal(v.bugfix, 0);
}

static void test_version_parse__rejects_other_lines_and_junk(void **state) {
  urt_version_t v = {7, 7, 7, 7, "keep"};
  const char *bad[] = {"", "4.1", "10.7", "1.8", "5.", ".5", "5..1", "5.19.0.1.2", "5.19a",
                       "5.19 ", "-5", "5.99999999999", NULL};
  for (int i = 0; bad[i]; i++) {
    assert_int_equal(urt_version_parse(bad[i], &v), URT_EINVAL);
  }
  assert_int_equal(v.major, 7);  /* untouched on error */
  assert_int_equal(urt_version_parse(NULL, &v), URT_EINVAL);
}

static void test_version_rt_packet_size__per_generation(void **state) {
  static const struct {
    const char *v;
    size_t size;
  } cases[] = {{"3.0", 1044},  {"3.1", 1044},  {"3.2", 1060},  {"3.4", 1060},
               {"3.5", 1108},  {"3.9", 1108},  {"3.10", 1116}, {"3.15", 1116},
               {"5.0", 1108},  {"5.3", 1108},  {"5.4", 1116},  {"5.19", 1116}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    urt_version_t v;
    assert_int_equal(urt_version_parse(cases[i].v, &v), 0);
    assert_int_equal(urt_version_rt_packet_size(&v), cases[i].size);
  }
}

static void test_version__period_and_polyscope_text(void **state) {
  urt_version_t e, cb3;
  urt_version_parse("5.19", &e);
  urt_version_parse("3.15", &cb3);
  assert_true(urt_version_is_eseries(&e));
  assert_false(urt_version_is_eseries(&cb3));
  assert_true(urt_version_period(&e) == 0.002);
  assert_true(urt_version_period(&cb3) == 0.008);
  char buf[64];
  urt_version_polyscope(&e, buf, sizeof buf);
  assert_string_equal(buf, "URSoftware 5.19.0.1210631 (Oct 23 2024)");
  urt_version_polyscope(&cb3, buf, 11);
  assert_string_equal(buf, "URSoftware");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_version_parse__full_text),
      cmocka_unit_test(test_version_parse__missing_parts_take_the_line_defaults),
      cmocka_unit_test(test_version_parse__rejects_other_lines_and_junk),
      cmocka_unit_test(test_version_rt_packet_size__per_generation),
      cmocka_unit_test(test_version__period_and_polyscope_text),
  };
  return cmocka_run_group_tests_name("net/codec/version", tests, NULL, NULL);
}
