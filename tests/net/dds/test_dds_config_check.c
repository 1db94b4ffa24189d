/* SPDX-License-Identifier: Apache-2.0
 * tests/net/dds/test_dds_config_check.c — the shipped loopback configuration passes; files cut
 * short, with mismatched tags, unquoted attributes or another root are refused with a line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/dds_config_check.h"

static void test_check__shipped_loopback_config_passes(void **state) {
  FILE *f = fopen(urt_test_path("config/cyclonedds-lo.xml"), "rb");
  assert_non_null(f);
  static char buf[65536];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = '\0';
  char err[160] = "";
  assert_int_equal(urt_dds_config_check(buf, err, sizeof err), 0);
}

static void test_check__refuses_malformed(void **state) {
  const char *bad[] = {
      "<CycloneDDS><Domain><General>",                             // cut short
      "<CycloneDDS><Domain></General></CycloneDDS>",               // mismatched
      "<CycloneDDS><Domain Id=any/></CycloneDDS>",                 // unquoted
      "<Other/>",                                                  // not Cyclone's
      "<CycloneDDS/><CycloneDDS/>",                                // two roots
      "<CycloneDDS><!-- never closed </CycloneDDS>",               // comment
      "<CycloneDDS/> trailing",                                    // text after
      "",                                                          // empty
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char err[160] = "";
    assert_int_equal(urt_dds_config_check(bad[i], err, sizeof err), URT_ECONFIG);
    assert_non_null(strstr(err, "line "));
  }
}

static void test_check__accepts_declarations_comments_and_empty_tags(void **state) {
  const char *ok =
      "<?xml version=\"1.0\"?>\n<!-- c -->\n<CycloneDDS xmlns='https://cdds.io/config'>\n"
      "  <Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\" />"
      "</Interfaces></General></Domain>\n</CycloneDDS>\n<!-- end -->\n";
  assert_int_equal(urt_dds_config_check(ok, NULL, 0), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_check__shipped_loopback_config_passes),
      cmocka_unit_test(test_check__refuses_malformed),
      cmocka_unit_test(test_check__accepts_declarations_comments_and_empty_tags),
  };
  return cmocka_run_group_tests_name("net/dds/config_check", tests, NULL, NULL);
}
