/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_lex.h — the URScript lexer's tokens (private to net/urscript). */
#ifndef URT_SCRIPT_LEX_H
#define URT_SCRIPT_LEX_H

#include <stdint.h>

typedef struct tok {
  int kind;
  const char *s;  /* start in the source */
  int len;
  uint32_t line, col;
  int64_t i;
  double f;
} tok;

typedef struct lexer {
  const char *src, *p, *end;
  uint32_t line;
  const char *line_start;
} lexer;

/* The next token at L->p (kinds T_* of script.h; T_EOF at the end, T_ERR for a character no
 * token starts with); skips blanks, newlines, `#` comments and `$ …` PolyScope marker lines. */
tok urt__us_lex_next(lexer *L);

#endif
