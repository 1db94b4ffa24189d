/* SPDX-License-Identifier: Apache-2.0 */
#include "rtde_test_util.h"

#include <string.h>

#include "test_support.h"

urt_version_t rt_version(int major, int minor, int bugfix, int build) {
  urt_version_t v;
  memset(&v, 0, sizeof v);
  v.major = major;
  v.minor = minor;
  v.bugfix = bugfix;
  v.build = build;
  return v;
}

size_t rt_pkg(uint8_t *out, uint8_t type, const void *payload, size_t n) {
  size_t len = 3 + n;
  out[0] = (uint8_t)(len >> 8);
  out[1] = (uint8_t)len;
  out[2] = type;
  if (n) {
    memcpy(out + 3, payload, n);
  }
  return len;
}

size_t rt_pkg_outputs(uint8_t *out, double freq, const char *names) {
  static uint8_t p[URT_RTDE_MAX_PACKAGE + 64];
  uint64_t u;
  memcpy(&u, &freq, 8);
  for (int i = 0; i < 8; i++) {
    p[i] = (uint8_t)(u >> (56 - 8 * i));
  }
  size_t n = strlen(names);
  memcpy(p + 8, names, n);
  return rt_pkg(out, 'O', p, 8 + n);
}

size_t rt_pkg_names(uint8_t *out, uint8_t type, const char *names) {
  return rt_pkg(out, type, names, strlen(names));
}

size_t rt_exchange(urt_rtde_session_t *s, const uint8_t *in, size_t n, uint8_t *out, size_t cap) {
  long used = urt_rtde_session_feed(s, in, n);
  assert_int_equal(used, (long)n);
  const uint8_t *p;
  size_t k = urt_rtde_session_output(s, &p);
  assert_true(k <= cap);
  memcpy(out, p, k);
  urt_rtde_session_consume(s, k);
  return k;
}

int rt_reply_types(const uint8_t *r, size_t n, int has_id, char *types, size_t cap) {
  size_t size = (size_t)r[0] << 8 | r[1];
  assert_int_equal(size, n);
  size_t off = 3 + (has_id ? 1 : 0);
  size_t len = size - off;
  assert_true(len < cap);
  memcpy(types, r + off, len);
  types[len] = 0;
  return has_id ? r[3] : -1;
}
