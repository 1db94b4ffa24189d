/* SPDX-License-Identifier: Apache-2.0
 * tests/net/rtde/rtde_test_util.h — versions filled directly (urt_version_parse lives on another
 * branch) and small helpers to build RTDE packages and drain a session. */
#ifndef URT_TEST_RTDE_UTIL_H
#define URT_TEST_RTDE_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "urt/net/rtde.h"

urt_version_t rt_version(int major, int minor, int bugfix, int build);

/* package with a header: type + payload */
size_t rt_pkg(uint8_t *out, uint8_t type, const void *payload, size_t n);
/* O v2: frequency + names */
size_t rt_pkg_outputs(uint8_t *out, double freq, const char *names);
/* O v1 / I: names only */
size_t rt_pkg_names(uint8_t *out, uint8_t type, const char *names);

/* feed everything (failing the test if it is not all consumed), then move the replies to out */
size_t rt_exchange(urt_rtde_session_t *s, const uint8_t *in, size_t n, uint8_t *out, size_t cap);

/* parse the reply of an I or O request: recipe id (or -1 if has_id == 0) and types text */
int rt_reply_types(const uint8_t *r, size_t n, int has_id, char *types, size_t cap);

#endif
