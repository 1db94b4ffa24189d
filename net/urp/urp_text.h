/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urp_text.h — a growing text buffer for the .urp compiler and the URCap fetch.
 * Private to net/urp.
 */
#ifndef URT_NET_URP_TEXT_H
#define URT_NET_URP_TEXT_H

#include <stdbool.h>
#include <stddef.h>

typedef struct urp_text {
  char *p;
  size_t len, cap;
  bool oom;       /* an append failed: the text is incomplete */
} urp_text;

void urp_text_put(urp_text *t, const char *s, size_t n);
void urp_text_puts(urp_text *t, const char *s);
void urp_text_printf(urp_text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void urp_text_indent(urp_text *t, int level);  /* two spaces per level, as PolyScope writes */
void urp_text_free(urp_text *t);

/* Append text line by line, each line indented to level (its own leading blanks kept); "\r"
 * dropped, the compiler's slot byte (0x01) written as '?' so that no input can forge a slot. */
void urp_text_lines(urp_text *t, const char *s, size_t n, int level);

#define URP_SLOT '\x01'  /* a template line "<indent>\x01H" or "<indent>\x01B" is a slot */

#endif
