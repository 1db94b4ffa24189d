/* SPDX-License-Identifier: Apache-2.0
 * tests/support/test_support.c — shared fixtures for the CMocka tests. */
#include "test_support.h"

#include <stdio.h>
#include <unistd.h>

#include <stdio.h>
#include <stdlib.h>

const char *urt_test_path(const char *rel) {
  static char buf[1024];
  snprintf(buf, sizeof buf, "%s/%s", URT_SOURCE_DIR, rel);
  return buf;
}

#ifdef URT_WRAP_MALLOC
static int armed;
static long count;

void *__real_malloc(size_t n);
void *__real_calloc(size_t k, size_t n);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);

// the wrappers only count: the test decides what a count means
void *__wrap_malloc(size_t n) {
  if (armed) {
    count++;
  }
  return __real_malloc(n);
}
void *__wrap_calloc(size_t k, size_t n) {
  if (armed) {
    count++;
  }
  return __real_calloc(k, n);
}
void *__wrap_realloc(void *p, size_t n) {
  if (armed) {
    count++;
  }
  return __real_realloc(p, n);
}
void __wrap_free(void *p) {
  if (armed) {
    count++;
  }
  __real_free(p);
}
// C++ operator new/delete go to libstdc++, which calls malloc from inside the shared library
// where --wrap cannot see it, so the C++ entry points are wrapped as well
void *__real__Znwm(size_t n);
void *__real__Znam(size_t n);
void *__wrap__Znwm(size_t n) {
  if (armed) {
    count++;
  }
  return __real__Znwm(n);
}
void *__wrap__Znam(size_t n) {
  if (armed) {
    count++;
  }
  return __real__Znam(n);
}
void urt_test_malloc_arm(int on) { armed = on; }
long urt_test_malloc_count(void) { return count; }
#else
void urt_test_malloc_arm(int on) { (void)on; }
long urt_test_malloc_count(void) { return -1; }
#endif

const char *urt_test_host(int block, int k) {
  static char host[8][32];
  static int next;
  char *h = host[next++ % 8];
  snprintf(h, sizeof host[0], "127.%d.%d.%d", block, (int)(getpid() % 250), k);
  return h;
}
