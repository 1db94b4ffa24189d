/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/version.h — the one controller version urtwin emulates, used
 * consistently by every interface (protocols.md §6): dashboard PolyscopeVersion, RTDE `v`,
 * the primary VERSION message, the 30003 packet size and the sub-package layouts.
 */
#ifndef URT_NET_VERSION_H
#define URT_NET_VERSION_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_version {
  int major, minor, bugfix, build;
  char date[32];              /* build date text, e.g. "Oct 23 2024" */
} urt_version_t;

/* Parse "5.19.0.1210631", "5.19" or "3.15.8" (missing parts become defaults of that line:
 * e-Series 5.19.0.1210631 "Oct 23 2024", CB3 3.15.8.106339 "Sep 14 2023"). Only 3.x and 5.x are
 * accepted. Returns 0 or URT_EINVAL. */
int urt_version_parse(const char *text, urt_version_t *v);

/* e-Series (5.x): 500 Hz; CB3 (3.x): 125 Hz. */
int urt_version_is_eseries(const urt_version_t *v);
double urt_version_period(const urt_version_t *v);      /* 0.002 or 0.008 [s] */

/* Size of a 30003 packet for this version (protocols.md §1.3): 1044/1060/1108/1116. */
size_t urt_version_rt_packet_size(const urt_version_t *v);

/* "URSoftware 5.19.0.1210631 (Oct 23 2024)" */
void urt_version_polyscope(const urt_version_t *v, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
