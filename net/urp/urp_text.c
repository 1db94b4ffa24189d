/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urp_text.c — the growing text buffer (urp_text.h).
 */
#include "urp_text.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool reserve(urp_text *t, size_t more) {
  if (t->oom) {
    return false;
  }
  if (t->len + more + 1 <= t->cap) {
    return true;
  }
  size_t cap = t->cap ? t->cap : 256;
  while (cap < t->len + more + 1) {
    cap *= 2;
  }
  char *p = realloc(t->p, cap);
  if (!p) {
    t->oom = true;
    return false;
  }
  t->p = p;
  t->cap = cap;
  return true;
}

void urp_text_put(urp_text *t, const char *s, size_t n) {
  if (!reserve(t, n)) {
    return;
  }
  memcpy(t->p + t->len, s, n);
  t->len += n;
  t->p[t->len] = '\0';
}

void urp_text_puts(urp_text *t, const char *s) { urp_text_put(t, s, strlen(s)); }

void urp_text_printf(urp_text *t, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0 || !reserve(t, (size_t)n)) {
    t->oom = true;
    return;
  }
  va_start(ap, fmt);
  vsnprintf(t->p + t->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  t->len += (size_t)n;
}

void urp_text_indent(urp_text *t, int level) {
  for (int k = 0; k < level; k++) {
    urp_text_put(t, "  ", 2);
  }
}

void urp_text_lines(urp_text *t, const char *s, size_t n, int level) {
  size_t i = 0;
  while (i < n) {
    size_t j = i;
    while (j < n && s[j] != '\n') {
      j++;
    }
    urp_text_indent(t, level);
    for (size_t k = i; k < j; k++) {
      char c = s[k];
      if (c == '\r') {
        continue;
      }
      urp_text_put(t, c == URP_SLOT ? "?" : &c, 1);
    }
    urp_text_put(t, "\n", 1);
    i = j + 1;
  }
}

void urp_text_free(urp_text *t) {
  free(t->p);
  t->p = NULL;
  t->len = t->cap = 0;
}
