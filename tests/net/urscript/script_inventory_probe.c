/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/script_inventory_probe.c — every function a URScript text calls, and what
 * urtwin has for it, as JSON on stdout (tests/python/test_script_inventory.py).
 *
 * The text is lexed, not parsed, so that a script using what the parser does not take yet
 * (threads) still gives its full inventory. URCL's template syntax is read as its renderer
 * would leave it: `{{ NAME }}` becomes a number and `{% … %}` lines go, keeping every version
 * branch (the inventory is their union). A call is NAME followed by `(`; `def NAME(`, `sec
 * NAME(` and `thread NAME(` define NAME. Each called name is "defined" (by the script),
 * "builtin" (urtwin runs it), "unsupported" (urtwin knows it and refuses it) or "missing". */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "script.h"
#include "script_lex.h"
#include "script_vm.h"

#define MAX_NAMES 1024

typedef struct entry {
  char name[128];
  int calls;
  int first_line;
  bool defined;
} entry;

static entry names[MAX_NAMES];
static int n_names;

static entry *get(const char *s, int len) {
  for (int k = 0; k < n_names; k++) {
    if ((int)strlen(names[k].name) == len && memcmp(names[k].name, s, (size_t)len) == 0) {
      return &names[k];
    }
  }
  if (n_names == MAX_NAMES || len >= (int)sizeof names[0].name) return NULL;
  entry *e = &names[n_names++];
  memcpy(e->name, s, (size_t)len);
  e->name[len] = 0;
  return e;
}

/* URCL's template syntax out: {{ X }} → 0, lines holding {% … %} → empty */
static size_t render(char *t, size_t n) {
  size_t w = 0;
  for (size_t r = 0; r < n;) {
    if (t[r] == '{' && r + 1 < n && t[r + 1] == '%') {
      while (r < n && t[r] != '\n') r++;
      continue;
    }
    if (t[r] == '{' && r + 1 < n && t[r + 1] == '{') {
      char *end = strstr(t + r, "}}");
      if (end) {
        t[w++] = '0';
        r = (size_t)(end - t) + 2;
        continue;
      }
    }
    t[w++] = t[r++];
  }
  t[w] = 0;
  return w;
}

int main(void) {
  size_t cap = URT_SCRIPT_MAX_TEXT * 2, n = 0;
  char *text = malloc(cap + 1);
  if (!text) return 2;
  for (size_t k; (k = fread(text + n, 1, cap - n, stdin)) > 0;) n += k;
  n = render(text, n);

  lexer L = {.src = text, .p = text, .end = text + n, .line = 1, .line_start = text};
  tok prev = {.kind = T_EOF}, t = urt__us_lex_next(&L);
  int errors = 0;
  while (t.kind != T_EOF) {
    tok next = urt__us_lex_next(&L);
    if (t.kind == T_ERR) {
      errors++;
    } else if (t.kind == T_NAME && next.kind == T_LP) {
      entry *e = get(t.s, t.len);
      if (e) {
        if (prev.kind == T_DEF || prev.kind == T_SEC || prev.kind == T_THREAD) {
          e->defined = true;
        } else {
          if (!e->calls) e->first_line = (int)t.line;
          e->calls++;
        }
      }
    }
    prev = t;
    t = next;
  }

  printf("{\"lex_errors\": %d, \"calls\": [", errors);
  int out = 0;
  for (int k = 0; k < n_names; k++) {
    const entry *e = &names[k];
    if (!e->calls) continue;
    const char *status = "missing";
    int b = urt__us_builtin_find(e->name, (int)strlen(e->name));
    if (e->defined) status = "defined";
    else if (b >= 0) status = urt__us_builtin_get(b)->fn ? "builtin" : "unsupported";
    printf("%s{\"name\": \"%s\", \"calls\": %d, \"line\": %d, \"status\": \"%s\"}",
           out++ ? ", " : "", e->name, e->calls, e->first_line, status);
  }
  printf("]}\n");
  free(text);
  return 0;
}
