/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_lex.c — the URScript lexer: keywords, names, numbers, strings and
 * operators, with their line and column for error messages. */
#include "script_lex.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "script.h"

static const struct {
  const char *s;
  int kind;
} kKeywords[] = {
    {"def", T_DEF},       {"sec", T_SEC},       {"thread", T_THREAD}, {"end", T_END},
    {"if", T_IF},         {"elif", T_ELIF},     {"else", T_ELSE},     {"then", T_THEN},
    {"while", T_WHILE},   {"do", T_DO},         {"return", T_RETURN}, {"global", T_GLOBAL},
    {"local", T_LOCAL},   {"True", T_TRUE},     {"False", T_FALSE},   {"and", T_AND},
    {"or", T_OR},         {"not", T_NOT},       {"xor", T_XOR},       {"halt", T_HALT},
    {"break", T_BREAK},   {"continue", T_CONTINUE}, {"run", T_RUN},   {"join", T_JOIN},
    {"kill", T_KILL},     {"for", T_FOR},
};

static bool is_alpha(int c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
static bool is_digit(int c) { return c >= '0' && c <= '9'; }

/* skip blanks, newlines, `#` comments and `$ …` PolyScope marker lines */
static void lex_skip(lexer *L) {
  while (L->p < L->end) {
    char c = *L->p;
    if (c == '\n') {
      L->p++;
      L->line++;
      L->line_start = L->p;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      L->p++;
    } else if (c == '#' || c == '$') {
      while (L->p < L->end && *L->p != '\n') {
        L->p++;
      }
    } else {
      return;
    }
  }
}

tok urt__us_lex_next(lexer *L) {
  lex_skip(L);
  tok t = {0};
  t.s = L->p;
  t.line = L->line;
  t.col = (uint32_t)(L->p - L->line_start) + 1;
  if (L->p >= L->end) {
    t.kind = T_EOF;
    return t;
  }
  const char *p = L->p;
  char c = *p;

  // names and keywords; `p[` opens a pose literal
  if (is_alpha((unsigned char)c)) {
    while (p < L->end && (is_alpha((unsigned char)*p) || is_digit((unsigned char)*p))) {
      p++;
    }
    t.len = (int)(p - L->p);
    t.kind = T_NAME;
    if (t.len == 1 && c == 'p' && p < L->end && *p == '[') {
      t.kind = T_POSE;
      p++;
      t.len = 2;
    } else {
      for (size_t k = 0; k < sizeof kKeywords / sizeof kKeywords[0]; k++) {
        if ((int)strlen(kKeywords[k].s) == t.len && memcmp(kKeywords[k].s, t.s, t.len) == 0) {
          t.kind = kKeywords[k].kind;
          break;
        }
      }
    }
    L->p = p;
    return t;
  }

  // numbers: 12, 1.5, .5, 1e-3, 2.5E+2
  if (is_digit((unsigned char)c) || (c == '.' && p + 1 < L->end && is_digit((unsigned char)p[1]))) {
    bool is_float = false;
    while (p < L->end && is_digit((unsigned char)*p)) {
      p++;
    }
    if (p < L->end && *p == '.') {
      is_float = true;
      p++;
      while (p < L->end && is_digit((unsigned char)*p)) {
        p++;
      }
    }
    if (p < L->end && (*p == 'e' || *p == 'E')) {
      const char *q = p + 1;
      if (q < L->end && (*q == '+' || *q == '-')) {
        q++;
      }
      if (q < L->end && is_digit((unsigned char)*q)) {
        is_float = true;
        p = q;
        while (p < L->end && is_digit((unsigned char)*p)) {
          p++;
        }
      }
    }
    t.len = (int)(p - L->p);
    char buf[64];
    int n = t.len < 63 ? t.len : 63;
    memcpy(buf, t.s, n);
    buf[n] = 0;
    if (!is_float) {
      errno = 0;
      long long v = strtoll(buf, NULL, 10);
      if (errno == ERANGE || t.len > 62) {
        is_float = true;  // too big for an int: keep it as a float
      } else {
        t.kind = T_INT;
        t.i = v;
      }
    }
    if (is_float) {
      t.kind = T_FLOAT;
      t.f = t.len > 62 ? HUGE_VAL : strtod(buf, NULL);
    }
    L->p = p;
    return t;
  }

  // strings: "…" or '…' on one line; escapes are unescaped by the parser
  if (c == '"' || c == '\'') {
    p++;
    while (p < L->end && *p != c && *p != '\n') {
      if (*p == '\\' && p + 1 < L->end && p[1] != '\n') {
        p++;
      }
      p++;
    }
    if (p >= L->end || *p != c) {
      t.kind = T_ERR;
      t.len = (int)(p - L->p);
      L->p = p;
      return t;
    }
    p++;
    t.kind = T_STR;
    t.len = (int)(p - L->p);
    L->p = p;
    return t;
  }

  // operators and punctuation
  char d = p + 1 < L->end ? p[1] : 0;
  t.len = 1;
  switch (c) {
    case '(': t.kind = T_LP; break;
    case ')': t.kind = T_RP; break;
    case '[': t.kind = T_LB; break;
    case ']': t.kind = T_RB; break;
    case ',': t.kind = T_COMMA; break;
    case ':': t.kind = T_COLON; break;
    case '+': t.kind = T_PLUS; break;
    case '-': t.kind = T_MINUS; break;
    case '*': t.kind = T_STAR; break;
    case '/': t.kind = T_SLASH; break;
    case '%': t.kind = T_PERCENT; break;
    case '=':
      if (d == '=') { t.kind = T_EQ; t.len = 2; } else { t.kind = T_ASSIGN; }
      break;
    case '!':
      if (d == '=') { t.kind = T_NE; t.len = 2; } else { t.kind = T_ERR; }
      break;
    case '<':
      if (d == '=') { t.kind = T_LE; t.len = 2; } else { t.kind = T_LT; }
      break;
    case '>':
      if (d == '=') { t.kind = T_GE; t.len = 2; } else { t.kind = T_GT; }
      break;
    default: t.kind = T_ERR; break;
  }
  L->p += t.len;
  return t;
}

