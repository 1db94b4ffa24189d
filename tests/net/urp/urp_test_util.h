/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urp/urp_test_util.h — build .urp bytes (gzip-compressed XML) in a test. */
#ifndef URT_TESTS_URP_TEST_UTIL_H
#define URT_TESTS_URP_TEST_UTIL_H

#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* gzip xml into a malloc'd buffer (as PolyScope writes a .urp). */
static inline unsigned char *urp_test_gzip(const char *xml, size_t *len) {
  z_stream z;
  memset(&z, 0, sizeof z);
  if (deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    return NULL;
  }
  size_t cap = deflateBound(&z, strlen(xml)) + 64;
  unsigned char *out = malloc(cap);
  z.next_in = (unsigned char *)xml;
  z.avail_in = (unsigned)strlen(xml);
  z.next_out = out;
  z.avail_out = (unsigned)cap;
  deflate(&z, Z_FINISH);
  *len = cap - z.avail_out;
  deflateEnd(&z);
  return out;
}

/* A whole program around a MainProgram body (and an optional BeforeStart body). */
static inline char *urp_test_program(const char *name, const char *run_once, const char *before,
                                     const char *body) {
  const char *fmt =
      "<URProgram name=\"%s\" installation=\"default\" directory=\"/programs\">\n"
      "  <kinematics status=\"NOT_INITIALIZED\" validChecksum=\"false\">\n"
      "    <deltaTheta value=\"0.0, 0.0, 0.0, 0.0, 0.0, 0.0\"/>\n"
      "  </kinematics>\n"
      "  <children>\n"
      "    <InitVariablesNode/>\n"
      "%s%s%s"
      "    <MainProgram runOnlyOnce=\"%s\" InitVariablesNode=\"true\">\n"
      "      <children>\n%s\n      </children>\n"
      "    </MainProgram>\n"
      "  </children>\n"
      "</URProgram>\n";
  const char *b0 = before ? "    <SpecialSequence type=\"BeforeStart\"><children>\n" : "";
  const char *b1 = before ? before : "";
  const char *b2 = before ? "\n    </children></SpecialSequence>\n" : "";
  size_t n = strlen(fmt) + strlen(name) + strlen(b0) + strlen(b1) + strlen(b2) +
             strlen(run_once) + strlen(body) + 1;
  char *s = malloc(n);
  snprintf(s, n, fmt, name, b0, b1, b2, run_once, body);
  return s;
}

#endif
