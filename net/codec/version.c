/* SPDX-License-Identifier: Apache-2.0
 * net/codec/version.c — the emulated controller version (protocols.md §1.3, §6). */
#include "urt/net/version.h"

#include <stdio.h>
#include <string.h>

#include "urt/errors.h"

//---- defaults of each line ----

static const urt_version_t kDefaultE = {5, 19, 0, 1210631, "Oct 23 2024"};
static const urt_version_t kDefaultCb3 = {3, 15, 8, 106339, "Sep 14 2023"};

/* Parse one decimal part into *out (0 .. 999999999). Returns the end or NULL. */
static const char *parse_part(const char *p, int *out) {
  long x = 0;
  int n = 0;
  while (*p >= '0' && *p <= '9') {
    if (++n > 9) {
      return NULL;
    }
    x = x * 10 + (*p - '0');
    p++;
  }
  if (n == 0) {
    return NULL;
  }
  *out = (int)x;
  return p;
}

//---- public API ----

int urt_version_parse(const char *text, urt_version_t *v) {
  if (!text || !v) {
    return URT_EINVAL;
  }

  // split "major[.minor[.bugfix[.build]]]"
  int part[4] = {0, 0, 0, 0};
  int n = 0;
  const char *p = text;
  while (n < 4) {
    p = parse_part(p, &part[n]);
    if (!p) {
      return URT_EINVAL;
    }
    n++;
    if (*p == '.') {
      p++;
      continue;
    }
    break;
  }
  if (*p != '\0') {
    return URT_EINVAL;
  }

  // only the CB3 and e-Series lines
  const urt_version_t *def;
  if (part[0] == 5) {
    def = &kDefaultE;
  } else if (part[0] == 3) {
    def = &kDefaultCb3;
  } else {
    return URT_EINVAL;
  }

  // missing parts come from the line's default (bugfix only when the minor matches)
  urt_version_t r = *def;
  if (n >= 2) {
    r.minor = part[1];
    r.bugfix = (part[1] == def->minor) ? def->bugfix : 0;
  }
  if (n >= 3) {
    r.bugfix = part[2];
  }
  if (n >= 4) {
    r.build = part[3];
  }
  *v = r;
  return 0;
}

int urt_version_is_eseries(const urt_version_t *v) { return v->major >= 5; }

double urt_version_period(const urt_version_t *v) {
  return urt_version_is_eseries(v) ? 0.002 : 0.008;
}

size_t urt_version_rt_packet_size(const urt_version_t *v) {
  if (v->major == 3) {
    if (v->minor <= 1) {
      return 1044;
    }
    if (v->minor <= 4) {
      return 1060;
    }
    if (v->minor <= 9) {
      return 1108;
    }
    return 1116;
  }
  return v->minor <= 3 ? 1108 : 1116;
}

void urt_version_polyscope(const urt_version_t *v, char *buf, size_t cap) {
  if (!buf || cap == 0) {
    return;
  }
  snprintf(buf, cap, "URSoftware %d.%d.%d.%d (%s)", v->major, v->minor, v->bugfix, v->build,
           v->date);
}
