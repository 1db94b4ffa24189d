/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_parse.c — URScript recursive-descent parser and name check (the lexer is
 * script_lex.c).
 *
 * Grammar (indentation and newlines are not significant; blocks close with `end`):
 *   unit     := item*
 *   item     := def | stmt
 *   def      := ('def' | 'sec') NAME '(' [param (',' param)*] ')' ':' stmt* 'end'
 *   param    := NAME ['=' expr]
 *   stmt     := def | 'global' NAME ['=' expr] | 'local' NAME ['=' expr]
 *             | 'if' expr (':'|'then') stmt* ('elif' expr (':'|'then') stmt*)* ['else' [':'] stmt*] 'end'
 *             | 'while' expr (':'|'do') stmt* 'end'
 *             | 'return' [expr on the same line] | 'halt' | 'break' | 'continue'
 *             | postfix '=' expr | expr
 *   expr     := or ; or := and ('or' and)* ; and := not ('and' not)* ; not := 'not' not | cmp
 *   cmp      := sum [('=='|'!='|'<'|'<='|'>'|'>=') sum] ; sum := prod (('+'|'-') prod)*
 *   prod     := unary (('*'|'/'|'%') unary)* ; unary := '-' unary | '+' unary | postfix
 *   postfix  := primary ('[' expr ']' | '(' args ')')*
 *   primary  := INT | FLOAT | STRING | 'True' | 'False' | NAME | '[' list ']' | 'p[' list ']'
 *             | '(' expr ')' | '(' expr ',' … ')'  (a tuple, as python-urx's set_payload sends)
 * `#` starts a comment and `$ …` (PolyScope line markers) is skipped to the end of the line.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "script.h"
#include "script_lex.h"
#include "urt/errors.h"

//---- arena ----

struct us_block {
  struct us_block *next;
  size_t used, cap;
  _Alignas(16) unsigned char mem[];
};

void *urt__us_alloc(us_arena *a, size_t n) {
  n = (n + 15u) & ~(size_t)15u;
  if (n == 0) {
    n = 16;
  }
  if (a->cap_total && a->used_total + n > a->cap_total) {
    return NULL;
  }
  struct us_block *b = a->head;
  if (!b || b->cap - b->used < n) {
    size_t cap = n > 65536 ? n : 65536;
    b = malloc(sizeof *b + cap);
    if (!b) {
      return NULL;
    }
    b->used = 0;
    b->cap = cap;
    b->next = a->head;
    a->head = b;
  }
  void *p = b->mem + b->used;
  b->used += n;
  a->used_total += n;
  memset(p, 0, n);
  return p;
}

void urt__us_arena_free(us_arena *a) {
  struct us_block *b = a->head;
  while (b) {
    struct us_block *next = b->next;
    free(b);
    b = next;
  }
  a->head = NULL;
  a->used_total = 0;
}

//---- parser state ----

typedef struct parser {
  lexer L;
  tok t;             /* current token */
  us_prog *prog;
  us_err *err;
  int depth;
  bool failed;
  /* interned names: open addressing */
  us_name **tab;
  int tab_cap, n_names;
  /* every def, for call resolution */
  us_node **defs;
  int n_defs, cap_defs;
} parser;

static void *palloc(parser *P, size_t n) {
  void *p = urt__us_alloc(&P->prog->arena, n);
  if (!p && !P->failed) {
    P->failed = true;
    P->err->kind = US_ERR_SYNTAX;
    snprintf(P->err->text, sizeof P->err->text, "program too large");
  }
  return p;
}

/* syntax_error_on_line:<line>:<text of that line>: (the format a real controller sends; see
 * the report for where it was observed) */
static void syntax_error(parser *P, const tok *t) {
  if (P->failed) {
    return;
  }
  P->failed = true;
  us_err *e = P->err;
  e->kind = US_ERR_SYNTAX;
  e->line = t->line;
  e->column = t->col;
  const char *ls = t->s - (t->col - 1);
  const char *le = ls;
  while (le < P->L.end && *le != '\n' && *le != '\r') {
    le++;
  }
  int n = (int)(le - ls);
  if (n > 900) {
    n = 900;
  }
  snprintf(e->text, sizeof e->text, "syntax_error_on_line:%u:%.*s:", t->line, n, ls);
}

static void advance(parser *P) {
  P->t = urt__us_lex_next(&P->L);
  if (P->t.kind == T_ERR) {
    syntax_error(P, &P->t);
  }
}

static bool accept(parser *P, int kind) {
  if (P->t.kind == kind) {
    advance(P);
    return true;
  }
  return false;
}

static bool expect(parser *P, int kind) {
  if (accept(P, kind)) {
    return true;
  }
  syntax_error(P, &P->t);
  return false;
}

static tok peek(parser *P) {
  lexer copy = P->L;
  return urt__us_lex_next(&copy);
}

static const us_name *intern(parser *P, const char *s, int len) {
  if (P->n_names * 2 >= P->tab_cap) {
    int cap = P->tab_cap ? P->tab_cap * 2 : 256;
    us_name **tab = calloc((size_t)cap, sizeof *tab);
    if (!tab) {
      syntax_error(P, &P->t);
      return NULL;
    }
    for (int k = 0; k < P->tab_cap; k++) {
      if (P->tab[k]) {
        uint32_t h = 2166136261u;
        for (int j = 0; j < P->tab[k]->len; j++) {
          h = (h ^ (unsigned char)P->tab[k]->s[j]) * 16777619u;
        }
        int at = (int)(h & (uint32_t)(cap - 1));
        while (tab[at]) {
          at = (at + 1) & (cap - 1);
        }
        tab[at] = P->tab[k];
      }
    }
    free(P->tab);
    P->tab = tab;
    P->tab_cap = cap;
  }
  uint32_t h = 2166136261u;
  for (int j = 0; j < len; j++) {
    h = (h ^ (unsigned char)s[j]) * 16777619u;
  }
  int at = (int)(h & (uint32_t)(P->tab_cap - 1));
  while (P->tab[at]) {
    if (P->tab[at]->len == len && memcmp(P->tab[at]->s, s, len) == 0) {
      return P->tab[at];
    }
    at = (at + 1) & (P->tab_cap - 1);
  }
  us_name *n = palloc(P, sizeof *n + (size_t)len + 1);
  if (!n) {
    return NULL;
  }
  char *copy = (char *)(n + 1);
  memcpy(copy, s, len);
  n->s = copy;
  n->len = len;
  n->id = P->n_names++;
  P->tab[at] = n;
  return n;
}

static us_node *new_node(parser *P, int kind, const tok *at) {
  us_node *n = palloc(P, sizeof *n);
  if (n) {
    n->kind = (uint8_t)kind;
    n->line = at->line;
    n->col = at->col;
    n->builtin = -1;
  }
  return n;
}

/* a growable list of nodes during parsing, copied into the arena when done */
typedef struct nlist {
  us_node **v;
  const us_name **names;
  int n, cap;
} nlist;

static bool nlist_push(parser *P, nlist *l, us_node *x, const us_name *name) {
  if (l->n == l->cap) {
    int cap = l->cap ? l->cap * 2 : 8;
    us_node **v = realloc(l->v, (size_t)cap * sizeof *v);
    if (!v) {
      syntax_error(P, &P->t);
      return false;
    }
    l->v = v;
    const us_name **nm = realloc(l->names, (size_t)cap * sizeof *nm);
    if (!nm) {
      syntax_error(P, &P->t);
      return false;
    }
    l->names = nm;
    l->cap = cap;
  }
  l->v[l->n] = x;
  l->names[l->n] = name;
  l->n++;
  return true;
}

static void nlist_finish(parser *P, nlist *l, us_node *into, bool with_names) {
  into->n = l->n;
  if (l->n && !P->failed) {
    into->kids = palloc(P, (size_t)l->n * sizeof *into->kids);
    if (into->kids) {
      memcpy(into->kids, l->v, (size_t)l->n * sizeof *into->kids);
    }
    if (with_names) {
      into->argn = palloc(P, (size_t)l->n * sizeof *into->argn);
      if (into->argn) {
        memcpy(into->argn, l->names, (size_t)l->n * sizeof *into->argn);
      }
    }
    if (!into->kids || (with_names && !into->argn)) {
      into->n = 0;
    }
  } else {
    into->n = 0;
  }
  free(l->v);
  free(l->names);
  memset(l, 0, sizeof *l);
}

static bool enter(parser *P) {
  if (++P->depth > URT_SCRIPT_MAX_DEPTH) {
    syntax_error(P, &P->t);
    return false;
  }
  return true;
}

//---- expressions ----

static us_node *parse_expr(parser *P);

/* one element of a list literal or an argument list (name: the argument's, or NULL); false
 * if it failed or the list is full */
static bool parse_item(parser *P, nlist *l, const us_name *name) {
  us_node *e = parse_expr(P);
  if (P->failed) {
    return false;
  }
  if (l->n >= URT_SCRIPT_MAX_LIST) {
    syntax_error(P, &P->t);
    return false;
  }
  nlist_push(P, l, e, name);
  return true;
}

static us_node *parse_list_tail(parser *P, us_node *n, int close) {
  nlist l = {0};
  if (P->t.kind != close) {
    do {
      if (!parse_item(P, &l, NULL)) {
        break;
      }
    } while (!P->failed && accept(P, T_COMMA));
  }
  if (!P->failed) {
    expect(P, close);
  }
  nlist_finish(P, &l, n, false);
  return n;
}

static char *unescape(parser *P, const tok *t, int *out_len) {
  char *s = palloc(P, (size_t)t->len);
  if (!s) {
    return NULL;
  }
  int n = 0;
  for (int k = 1; k < t->len - 1; k++) {
    char c = t->s[k];
    if (c == '\\' && k + 1 < t->len - 1) {
      char e = t->s[++k];
      c = e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e;
    }
    s[n++] = c;
  }
  s[n] = 0;
  *out_len = n;
  return s;
}

static us_node *parse_primary(parser *P) {
  tok t = P->t;
  us_node *n = NULL;
  switch (t.kind) {
    case T_INT:
      n = new_node(P, N_INT, &t);
      if (n) n->i = t.i;
      advance(P);
      return n;
    case T_FLOAT:
      n = new_node(P, N_FLOAT, &t);
      if (n) n->f = t.f;
      advance(P);
      return n;
    case T_TRUE:
    case T_FALSE:
      n = new_node(P, N_BOOL, &t);
      if (n) n->i = t.kind == T_TRUE;
      advance(P);
      return n;
    case T_STR:
      n = new_node(P, N_STR, &t);
      if (n) n->s = unescape(P, &t, &n->slen);
      advance(P);
      return n;
    case T_NAME:
      n = new_node(P, N_NAME, &t);
      if (n) n->name = intern(P, t.s, t.len);
      advance(P);
      return n;
    case T_RUN:
      // `run name()`: starts a thread, the value is its handle
      advance(P);
      if (P->t.kind != T_NAME) {
        syntax_error(P, &P->t);
        return NULL;
      }
      n = new_node(P, N_RUN, &t);
      if (n) n->name = intern(P, P->t.s, P->t.len);
      advance(P);
      expect(P, T_LP);
      expect(P, T_RP);
      return n;
    case T_LB:
      advance(P);
      n = new_node(P, N_LIST, &t);
      return n ? parse_list_tail(P, n, T_RB) : NULL;
    case T_POSE:
      advance(P);
      n = new_node(P, N_POSE, &t);
      if (n) parse_list_tail(P, n, T_RB);
      if (n && !P->failed && n->n == 1) {
        // `p[i]`: an element of a variable named p (a pose literal has six), as in ur_rtde's
        // `def scale_pose(p, factor): p[0] = p[0] * factor`
        us_node *base = new_node(P, N_NAME, &t);
        if (!base) return NULL;
        base->name = intern(P, "p", 1);
        us_node *ix = n->kids[0];
        n->kind = N_INDEX;
        n->a = base;
        n->b = ix;
        n->n = 0;
        n->kids = NULL;
      }
      return n;
    case T_LP: {
      advance(P);
      us_node *e = parse_expr(P);
      if (P->failed) {
        return NULL;
      }
      if (P->t.kind == T_COMMA) {
        // a tuple such as set_payload(1.5, (0, 0, 0.05)): a list
        nlist l = {0};
        nlist_push(P, &l, e, NULL);
        while (!P->failed && accept(P, T_COMMA)) {
          if (l.n >= URT_SCRIPT_MAX_LIST) {
            syntax_error(P, &P->t);
            break;
          }
          nlist_push(P, &l, parse_expr(P), NULL);
        }
        n = new_node(P, N_LIST, &t);
        if (n) {
          nlist_finish(P, &l, n, false);
        } else {
          free(l.v);
          free(l.names);
        }
        expect(P, T_RP);
        return n;
      }
      expect(P, T_RP);
      return e;
    }
    default:
      syntax_error(P, &t);
      return NULL;
  }
}

static us_node *parse_postfix(parser *P) {
  us_node *e = parse_primary(P);
  while (!P->failed && (P->t.kind == T_LB || P->t.kind == T_LP)) {
    tok t = P->t;
    if (!enter(P)) {
      return NULL;
    }
    if (t.kind == T_LB) {
      advance(P);
      us_node *ix = new_node(P, N_INDEX, &t);
      if (!ix) {
        return NULL;
      }
      ix->a = e;
      ix->b = parse_expr(P);
      if (!P->failed && accept(P, T_COMMA)) {
        // m[i, j]: a matrix element; the column index is the one kid
        nlist l = {0};
        nlist_push(P, &l, parse_expr(P), NULL);
        nlist_finish(P, &l, ix, false);
      }
      expect(P, T_RB);
      e = ix;
    } else {
      // calls only on plain names
      if (!e || e->kind != N_NAME) {
        syntax_error(P, &t);
        return NULL;
      }
      advance(P);
      us_node *c = new_node(P, N_CALL, &(tok){.line = e->line, .col = e->col});
      if (!c) {
        return NULL;
      }
      c->name = e->name;
      nlist l = {0};
      if (P->t.kind != T_RP) {
        do {
          const us_name *argname = NULL;
          if (P->t.kind == T_NAME && peek(P).kind == T_ASSIGN) {
            argname = intern(P, P->t.s, P->t.len);
            advance(P);
            advance(P);
          } else if (l.n && l.names[l.n - 1]) {
            syntax_error(P, &P->t);  // positional after named
            break;
          }
          if (!parse_item(P, &l, argname)) {
            break;
          }
        } while (!P->failed && accept(P, T_COMMA));
      }
      nlist_finish(P, &l, c, true);
      expect(P, T_RP);
      e = c;
    }
    P->depth--;
  }
  return e;
}

static us_node *parse_unary(parser *P) {
  if (P->t.kind == T_MINUS || P->t.kind == T_PLUS) {
    tok t = P->t;
    advance(P);
    if (!enter(P)) {
      return NULL;
    }
    us_node *n = new_node(P, N_UNARY, &t);
    if (n) {
      n->op = (uint8_t)t.kind;
      n->a = parse_unary(P);
    }
    P->depth--;
    return n;
  }
  return parse_postfix(P);
}

static us_node *binary(parser *P, const tok *t, us_node *l, us_node *r) {
  us_node *n = new_node(P, N_BINARY, t);
  if (n) {
    n->op = (uint8_t)t->kind;
    n->a = l;
    n->b = r;
  }
  return n;
}

static us_node *parse_prod(parser *P) {
  us_node *e = parse_unary(P);
  while (!P->failed && (P->t.kind == T_STAR || P->t.kind == T_SLASH || P->t.kind == T_PERCENT)) {
    tok t = P->t;
    advance(P);
    e = binary(P, &t, e, parse_unary(P));
  }
  return e;
}

static us_node *parse_sum(parser *P) {
  us_node *e = parse_prod(P);
  while (!P->failed && (P->t.kind == T_PLUS || P->t.kind == T_MINUS)) {
    tok t = P->t;
    advance(P);
    e = binary(P, &t, e, parse_prod(P));
  }
  return e;
}

static us_node *parse_cmp(parser *P) {
  us_node *e = parse_sum(P);
  int k = P->t.kind;
  if (!P->failed && (k == T_EQ || k == T_NE || k == T_LT || k == T_LE || k == T_GT || k == T_GE)) {
    tok t = P->t;
    advance(P);
    e = binary(P, &t, e, parse_sum(P));
  }
  return e;
}

static us_node *parse_not(parser *P) {
  if (P->t.kind == T_NOT) {
    tok t = P->t;
    advance(P);
    if (!enter(P)) {
      return NULL;
    }
    us_node *n = new_node(P, N_UNARY, &t);
    if (n) {
      n->op = T_NOT;
      n->a = parse_not(P);
    }
    P->depth--;
    return n;
  }
  return parse_cmp(P);
}

static us_node *parse_and(parser *P) {
  us_node *e = parse_not(P);
  while (!P->failed && P->t.kind == T_AND) {
    tok t = P->t;
    advance(P);
    e = binary(P, &t, e, parse_not(P));
  }
  return e;
}

static us_node *parse_expr(parser *P) {
  if (!enter(P)) {
    return NULL;
  }
  us_node *e = parse_and(P);
  while (!P->failed && (P->t.kind == T_OR || P->t.kind == T_XOR)) {
    tok t = P->t;
    advance(P);
    e = binary(P, &t, e, parse_and(P));
  }
  P->depth--;
  return P->failed ? NULL : e;
}

//---- statements ----

static bool name_is(const us_name *nm, const char *s) {
  return (int)strlen(s) == nm->len && memcmp(s, nm->s, (size_t)nm->len) == 0;
}

static us_node *parse_stmt(parser *P);

/* statements until one of the stop tokens (not consumed) */
static us_node *parse_block(parser *P, const tok *at, int stop1, int stop2, int stop3) {
  us_node *b = new_node(P, N_BLOCK, at);
  nlist l = {0};
  if (!enter(P)) {
    return NULL;
  }
  while (!P->failed && P->t.kind != stop1 && P->t.kind != stop2 && P->t.kind != stop3) {
    if (P->t.kind == T_EOF) {
      syntax_error(P, &P->t);
      break;
    }
    us_node *s = parse_stmt(P);
    if (P->failed) {
      break;
    }
    nlist_push(P, &l, s, NULL);
  }
  P->depth--;
  if (b) {
    nlist_finish(P, &l, b, false);
  } else {
    free(l.v);
    free(l.names);
  }
  return b;
}

static us_node *parse_def(parser *P) {
  tok t = P->t;
  int flag = t.kind == T_SEC ? US_DEF_SEC : t.kind == T_THREAD ? US_DEF_THREAD : US_DEF_FUNC;
  advance(P);
  if (P->t.kind != T_NAME) {
    syntax_error(P, &P->t);
    return NULL;
  }
  us_node *d = new_node(P, N_DEF, &t);
  if (!d) {
    return NULL;
  }
  d->flag = (uint8_t)flag;
  d->name = intern(P, P->t.s, P->t.len);
  advance(P);
  expect(P, T_LP);
  nlist l = {0};
  if (!P->failed && P->t.kind != T_RP) {
    do {
      if (P->t.kind != T_NAME) {
        syntax_error(P, &P->t);
        break;
      }
      const us_name *pn = intern(P, P->t.s, P->t.len);
      advance(P);
      us_node *def = NULL;
      if (accept(P, T_ASSIGN)) {
        def = parse_expr(P);
      }
      if (l.n >= URT_SCRIPT_MAX_LIST) {
        syntax_error(P, &P->t);
      }
      if (P->failed) {
        break;
      }
      nlist_push(P, &l, def, pn);
    } while (!P->failed && accept(P, T_COMMA));
  }
  nlist_finish(P, &l, d, true);
  if (flag == US_DEF_THREAD && d->n > 0 && !P->failed) {
    syntax_error(P, &P->t);  // a thread takes no parameters
  }
  expect(P, T_RP);
  expect(P, T_COLON);
  if (P->failed) {
    return NULL;
  }
  d->a = parse_block(P, &t, T_END, T_END, T_END);
  expect(P, T_END);
  if (!P->failed) {
    if (P->n_defs == P->cap_defs) {
      int cap = P->cap_defs ? P->cap_defs * 2 : 16;
      us_node **v = realloc(P->defs, (size_t)cap * sizeof *v);
      if (!v) {
        syntax_error(P, &t);
        return NULL;
      }
      P->defs = v;
      P->cap_defs = cap;
    }
    P->defs[P->n_defs++] = d;
  }
  return d;
}

static us_node *parse_stmt(parser *P) {
  tok t = P->t;
  us_node *n = NULL;
  switch (t.kind) {
    case T_DEF:
    case T_SEC:
    case T_THREAD:
      return parse_def(P);
    case T_JOIN:
    case T_KILL:
      advance(P);
      n = new_node(P, t.kind == T_JOIN ? N_JOIN : N_KILL, &t);
      if (n) n->a = parse_expr(P);
      return n;
    case T_GLOBAL:
    case T_LOCAL:
      advance(P);
      if (P->t.kind != T_NAME) {
        syntax_error(P, &P->t);
        return NULL;
      }
      n = new_node(P, t.kind == T_GLOBAL ? N_GLOBAL : N_LOCAL, &t);
      if (!n) {
        return NULL;
      }
      n->name = intern(P, P->t.s, P->t.len);
      advance(P);
      if (accept(P, T_ASSIGN)) {
        n->a = parse_expr(P);
      }
      return n;
    case T_IF: {
      n = new_node(P, N_IF, &t);
      nlist l = {0};
      advance(P);
      for (;;) {
        us_node *cond = parse_expr(P);
        if (!P->failed && !accept(P, T_COLON) && !accept(P, T_THEN)) {
          syntax_error(P, &P->t);
        }
        if (P->failed) {
          break;
        }
        us_node *body = parse_block(P, &t, T_ELIF, T_ELSE, T_END);
        if (P->failed) {
          break;
        }
        nlist_push(P, &l, cond, NULL);
        nlist_push(P, &l, body, NULL);
        if (!accept(P, T_ELIF)) {
          break;
        }
      }
      if (!P->failed && accept(P, T_ELSE)) {
        accept(P, T_COLON);
        us_node *body = parse_block(P, &t, T_END, T_END, T_END);
        if (!P->failed) {
          nlist_push(P, &l, body, NULL);
          if (n) n->flag = 1;
        }
      }
      if (n) {
        nlist_finish(P, &l, n, false);
      } else {
        free(l.v);
        free(l.names);
      }
      expect(P, T_END);
      return n;
    }
    case T_WHILE:
      advance(P);
      n = new_node(P, N_WHILE, &t);
      if (!n) {
        return NULL;
      }
      n->a = parse_expr(P);
      if (!P->failed && !accept(P, T_COLON) && !accept(P, T_DO)) {
        syntax_error(P, &P->t);
      }
      if (P->failed) {
        return NULL;
      }
      n->b = parse_block(P, &t, T_END, T_END, T_END);
      expect(P, T_END);
      return n;
    case T_RETURN:
      advance(P);
      n = new_node(P, N_RETURN, &t);
      // a value only on the same line: statements are not separated otherwise
      if (n && P->t.line == t.line && P->t.kind != T_END && P->t.kind != T_EOF &&
          P->t.kind != T_ELSE && P->t.kind != T_ELIF) {
        n->a = parse_expr(P);
      }
      return n;
    case T_HALT:
    case T_BREAK:
    case T_CONTINUE:
      advance(P);
      return new_node(P, t.kind == T_HALT ? N_HALT : t.kind == T_BREAK ? N_BREAK : N_CONTINUE, &t);
    case T_FOR:
      // not part of the subset: a compile error, never a silent success
      if (!P->failed) {
        P->failed = true;
        P->err->kind = US_ERR_COMPILE;
        P->err->line = t.line;
        P->err->column = t.col;
        snprintf(P->err->text, sizeof P->err->text, "compile_error_unsupported:%.*s:", t.len, t.s);
      }
      return NULL;
    default: {
      us_node *lhs = parse_expr(P);
      if (P->failed) {
        return NULL;
      }
      if (P->t.kind == T_ASSIGN) {
        tok at = P->t;
        // targets: name or name[index] (digital_out[2]=True is python-urx's CB2 syntax)
        if (!(lhs->kind == N_NAME ||
              (lhs->kind == N_INDEX && lhs->n == 0 && lhs->a && lhs->a->kind == N_NAME))) {
          syntax_error(P, &at);
          return NULL;
        }
        advance(P);
        n = new_node(P, N_ASSIGN, &(tok){.line = lhs->line, .col = lhs->col});
        if (!n) {
          return NULL;
        }
        n->name = lhs->kind == N_NAME ? lhs->name : lhs->a->name;
        n->a = lhs->kind == N_INDEX ? lhs->b : NULL;
        n->b = parse_expr(P);
        return n;
      }
      // enter_critical / exit_critical are statements without parentheses
      if (lhs->kind == N_NAME && (name_is(lhs->name, "enter_critical") ||
                                  name_is(lhs->name, "exit_critical"))) {
        n = new_node(P, N_CRITICAL, &(tok){.line = lhs->line, .col = lhs->col});
        if (n) n->flag = name_is(lhs->name, "enter_critical");
        return n;
      }
      n = new_node(P, N_EXPR, &(tok){.line = lhs->line, .col = lhs->col});
      if (n) {
        n->a = lhs;
      }
      return n;
    }
  }
}

//---- name check ----

/* the names a program binds anywhere (assignments, params, global/local, defs) */
typedef struct check {
  parser *P;
  unsigned char *bound;  /* by name id */
  bool secondary;
} check;

static void collect(check *C, const us_node *n) {
  if (!n) {
    return;
  }
  switch (n->kind) {
    case N_ASSIGN:
    case N_GLOBAL:
    case N_LOCAL:
      if (n->name) C->bound[n->name->id] = 1;
      break;
    case N_DEF:
      for (int k = 0; k < n->n; k++) {
        if (n->argn && n->argn[k]) C->bound[n->argn[k]->id] = 1;
      }
      break;
    default:
      break;
  }
  collect(C, n->a);
  collect(C, n->b);
  for (int k = 0; k < n->n; k++) {
    collect(C, n->kids[k]);
  }
}

static const char *const kConstants[] = {"pi", "digital_out", "digital_in"};

static bool is_constant(const us_name *nm) {
  for (size_t k = 0; k < sizeof kConstants / sizeof kConstants[0]; k++) {
    if ((int)strlen(kConstants[k]) == nm->len && memcmp(kConstants[k], nm->s, nm->len) == 0) {
      return true;
    }
  }
  return false;
}

static void name_error(check *C, const us_node *n, const char *fmt) {
  parser *P = C->P;
  if (P->failed) {
    return;
  }
  P->failed = true;
  P->err->kind = US_ERR_COMPILE;
  P->err->line = n->line;
  P->err->column = n->col;
  snprintf(P->err->text, sizeof P->err->text, fmt, n->name->len, n->name->s);
}

static void resolve(check *C, us_node *n) {
  if (!n || C->P->failed) {
    return;
  }
  parser *P = C->P;
  if (n->kind == N_NAME) {
    if (!C->bound[n->name->id] && !is_constant(n->name)) {
      name_error(C, n, "compile_error_name_not_found:%.*s:");
      return;
    }
  } else if (n->kind == N_RUN) {
    n->def = NULL;
    for (int k = 0; k < P->n_defs; k++) {
      if (P->defs[k]->name == n->name && P->defs[k]->flag == US_DEF_THREAD) {
        n->def = P->defs[k];
        break;
      }
    }
    if (!n->def) {
      name_error(C, n, "compile_error_name_not_found:%.*s:");
      return;
    }
  } else if (n->kind == N_CALL) {
    n->def = NULL;
    for (int k = 0; k < P->n_defs; k++) {
      if (P->defs[k]->name == n->name && P->defs[k]->flag != US_DEF_THREAD) {
        n->def = P->defs[k];
        break;
      }
    }
    if (!n->def) {
      n->builtin = urt__us_builtin_find(n->name->s, n->name->len);
      if (n->builtin < 0) {
        name_error(C, n, "compile_error_name_not_found:%.*s:");
        return;
      }
      // A function the controller has and urtwin does not compiles and is a runtime error
      // naming it when reached (never a no-op). Not a compile error: URCL's and ur_rtde's
      // scripts call such functions in branches picked at run time by the client's command,
      // and refusing the whole script would take every other command away with them.
    }
  } else if (n->kind == N_ASSIGN && n->a && !C->bound[n->name->id] && !is_constant(n->name)) {
    name_error(C, n, "compile_error_name_not_found:%.*s:");
    return;
  }
  resolve(C, n->a);
  resolve(C, n->b);
  for (int k = 0; k < n->n; k++) {
    resolve(C, n->kids[k]);
  }
}

//---- entry ----

int urt__us_parse(const char *text, size_t len, us_prog **out, us_err *err) {
  memset(err, 0, sizeof *err);
  if (len > URT_SCRIPT_MAX_TEXT) {
    err->kind = US_ERR_SYNTAX;
    err->line = 1;
    err->column = 1;
    snprintf(err->text, sizeof err->text, "program too large (%zu bytes > %u)", len,
             URT_SCRIPT_MAX_TEXT);
    return -1;
  }
  us_prog *prog = calloc(1, sizeof *prog);
  if (!prog) {
    err->kind = US_ERR_SYNTAX;
    snprintf(err->text, sizeof err->text, "out of memory");
    return -1;
  }
  prog->arena.cap_total = 64u * len + (1u << 20);
  parser P = {0};
  P.prog = prog;
  P.err = err;
  P.L.src = P.L.p = P.L.line_start = text;
  P.L.end = text + len;
  P.L.line = 1;
  advance(&P);

  // the unit: items until EOF
  tok first = P.t;
  nlist items = {0};
  int n_stmts = 0, n_top_defs = 0;
  us_node *first_def = NULL;
  while (!P.failed && P.t.kind != T_EOF) {
    us_node *s = parse_stmt(&P);
    if (P.failed) {
      break;
    }
    if (s->kind == N_DEF) {
      n_top_defs++;
      if (!first_def) {
        first_def = s;
      }
    } else {
      n_stmts++;
    }
    nlist_push(&P, &items, s, NULL);
  }
  if (!P.failed && items.n == 0) {
    syntax_error(&P, &P.t);
  }

  // the program: the def itself, or a synthetic function holding the statements
  us_node *main = NULL;
  if (!P.failed) {
    if (n_stmts == 0) {
      main = first_def;
      free(items.v);
      free(items.names);
      memset(&items, 0, sizeof items);
    } else {
      main = new_node(&P, N_DEF, &first);
      if (main) {
        main->a = new_node(&P, N_BLOCK, &first);
        if (main->a) {
          nlist_finish(&P, &items, main->a, false);
        }
      }
    }
  }
  free(items.v);
  free(items.names);

  // every name used must be bound somewhere or be a builtin
  if (!P.failed && main) {
    check C = {.P = &P};
    C.bound = calloc((size_t)P.n_names + 1, 1);
    if (!C.bound) {
      syntax_error(&P, &first);
    } else {
      collect(&C, main);
      for (int k = 0; k < P.n_defs; k++) {
        collect(&C, P.defs[k]);
      }
      resolve(&C, main);
      for (int k = 0; k < P.n_defs && !P.failed; k++) {
        resolve(&C, P.defs[k]);
      }
      free(C.bound);
    }
  }
  free(P.tab);

  if (P.failed || !main) {
    free(P.defs);
    urt__us_prog_free(prog);
    if (err->kind == US_ERR_NONE) {
      err->kind = US_ERR_SYNTAX;
    }
    return -1;
  }
  prog->main = main;
  prog->secondary = main->name && main->flag == US_DEF_SEC;
  if (main->name) {
    snprintf(prog->name, sizeof prog->name, "%.*s", main->name->len, main->name->s);
  } else {
    snprintf(prog->name, sizeof prog->name, "%s", "statement");
  }
  prog->n_names = P.n_names;
  prog->n_defs = P.n_defs;
  if (P.n_defs) {
    prog->defs = urt__us_alloc(&prog->arena, (size_t)P.n_defs * sizeof *prog->defs);
    if (prog->defs) {
      memcpy(prog->defs, P.defs, (size_t)P.n_defs * sizeof *prog->defs);
    } else {
      prog->n_defs = 0;
    }
  }
  free(P.defs);
  *out = prog;
  return 0;
}

void urt__us_prog_free(us_prog *p) {
  if (p) {
    urt__us_arena_free(&p->arena);
    free(p);
  }
}

void urt__us_err_msg(const us_err *e, bool secondary, urt_script_msg_t *msg) {
  memset(msg, 0, sizeof *msg);
  if (secondary) {
    msg->kind = URT_SCRIPT_MSG_KEY;
    snprintf(msg->title, sizeof msg->title, "%s", "SECONDARY_PROGRAM_EXCEPTION_XXX");
  } else {
    msg->kind = URT_SCRIPT_MSG_RUNTIME_EXCEPTION;
  }
  msg->line = e->line;
  msg->column = e->column;
  snprintf(msg->text, sizeof msg->text, "%s", e->text);
}

int urt_script_check(const char *text, size_t len, urt_script_msg_t *msg) {
  if (!text) {
    return URT_EINVAL;
  }
  us_prog *p = NULL;
  us_err err;
  if (urt__us_parse(text, len, &p, &err) != 0) {
    if (msg) {
      urt__us_err_msg(&err, false, msg);
    }
    return URT_EINVAL;
  }
  urt__us_prog_free(p);
  return 0;
}
