/* SPDX-License-Identifier: Apache-2.0
 * tests/support/test_support.h — shared fixtures for the CMocka tests. */
#ifndef URT_TEST_SUPPORT_H
#define URT_TEST_SUPPORT_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

/* Path of a file in the source tree, e.g. urt_test_path("config/ur5.yaml"). Static buffer. */
const char *urt_test_path(const char *rel);

/* A loopback address of this test binary and process, "127.<block>.<pid % 250>.<k>" (block:
 * a number of the test's own, 1..254; k: 1..254), for an emulator on UR's own ports with no
 * offset. Ports stay below the ephemeral range (32768+: any client's local port), and two test
 * processes never share an address, so parallel runs (ctest -j, two trees) cannot collide. */
const char *urt_test_host(int block, int k);

/* Heap-call counting for tests linked with WRAP_MALLOC: urt_test_malloc_arm(1) starts
 * counting, urt_test_malloc_count() tells how many malloc/calloc/realloc/free happened. */
void urt_test_malloc_arm(int on);
long urt_test_malloc_count(void);

/* Assert |a − b| <= tol with a readable message. */
#define assert_near(a, b, tol)                                                          \
  do {                                                                                  \
    double a_ = (a), b_ = (b), t_ = (tol);                                              \
    if (!(fabs(a_ - b_) <= t_)) {                                                       \
      fail_msg("%s = %.12g, %s = %.12g, |diff| = %.3g > %.3g", #a, a_, #b, b_,          \
               fabs(a_ - b_), t_);                                                      \
    }                                                                                   \
  } while (0)

#endif
