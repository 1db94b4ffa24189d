/* SPDX-License-Identifier: Apache-2.0
 * net/codec/script_framer.c — URScript / controller-command framing for 30001–30003
 * (protocols.md §4.6). One pass, one byte at a time, so chunking cannot change the result. */
#include "urt/net/script_framer.h"

#include <stdlib.h>
#include <string.h>

#include "urt/errors.h"

//---- internal codes ----

enum { MODE_IDLE = 0, MODE_PROGRAM, MODE_SECONDARY, MODE_BLOCK, MODE_SKIP };

/* What the first token of a line is. */
enum { KW_NONE = 0, KW_DEF, KW_SEC, KW_OPEN, KW_OTHER };

//---- controller commands ----

static const struct {
  const char *text;
  urt_script_cmd_t cmd;
} kCommands[] = {
    {"power on", URT_SCRIPT_CMD_POWER_ON},
    {"power off", URT_SCRIPT_CMD_POWER_OFF},
    {"set robotmode run", URT_SCRIPT_CMD_BRAKE_RELEASE},
    {"set unlock protective stop", URT_SCRIPT_CMD_UNLOCK_PSTOP},
    {"stop program", URT_SCRIPT_CMD_STOP_PROGRAM},
    {"set sim", URT_SCRIPT_CMD_SET_SIM},
    {"set real", URT_SCRIPT_CMD_SET_REAL},
};

/* First words of lines that are controller commands even when the rest is unknown. */
static const char *const kCommandWords[] = {"power", "set", "stop", "brake", "unlock"};

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

static int is_word_char(unsigned char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

int urt_script_command_of(const char *line, size_t len) {
  // normalise: trim, collapse blank runs to one space, accept lowercase words only
  char norm[64];
  size_t n = 0;
  int pending_space = 0;
  for (size_t i = 0; i < len; i++) {
    char c = line[i];
    if (is_blank(c)) {
      pending_space = (n > 0);
      continue;
    }
    if (!(c >= 'a' && c <= 'z')) {
      return -1;
    }
    if (n + 2 >= sizeof norm) {
      return -1;
    }
    if (pending_space) {
      norm[n++] = ' ';
      pending_space = 0;
    }
    norm[n++] = c;
  }
  norm[n] = '\0';

  // a known command
  for (size_t k = 0; k < sizeof kCommands / sizeof kCommands[0]; k++) {
    if (strcmp(norm, kCommands[k].text) == 0) {
      return (int)kCommands[k].cmd;
    }
  }

  // an unknown one: two or more words, the first a command word
  const char *space = strchr(norm, ' ');
  if (!space) {
    return -1;
  }
  size_t w = (size_t)(space - norm);
  for (size_t k = 0; k < sizeof kCommandWords / sizeof kCommandWords[0]; k++) {
    if (strlen(kCommandWords[k]) == w && strncmp(norm, kCommandWords[k], w) == 0) {
      return URT_SCRIPT_CMD_UNKNOWN;
    }
  }
  return -1;
}

//---- unit buffer ----

/* Clear the unit being collected and the lexer (not the line counter or statistics). */
static void clear_unit(urt_script_framer_t *f) {
  f->len = 0;
  f->depth = 0;
  f->quote = 0;
  f->escape = 0;
  f->comment = 0;
  f->word_len = 0;
  f->word_digit = 0;
  f->line_code = 0;
  f->first_kw = KW_NONE;
  f->mode = MODE_IDLE;
}

/* Make room for one more byte plus the terminating NUL. 0 or URT_ENOSPC / URT_ENOMEM. */
static int reserve_one(urt_script_framer_t *f) {
  if (f->len + 1 > f->max_unit) {
    return URT_ENOSPC;
  }
  if (f->len + 2 <= f->cap) {
    return 0;
  }
  size_t cap = f->cap ? f->cap : 256;
  while (cap < f->len + 2) {
    cap *= 2;
  }
  if (cap > f->max_unit + 1) {
    cap = f->max_unit + 1;
  }
  char *p = realloc(f->buf, cap);
  if (!p) {
    return URT_ENOMEM;
  }
  f->buf = p;
  f->cap = cap;
  return 0;
}

//---- emitting ----

static void emit(urt_script_framer_t *f, urt_script_unit_t *u) {
  f->units++;
  if (u->kind == URT_SCRIPT_UNIT_ERROR) {
    f->errors++;
  }
  if (f->on_unit) {
    f->on_unit(f->user, u);
  }
}

/* Emit an ERROR with an excerpt of what was collected, then skip the rest of the unit. */
static void fail_unit(urt_script_framer_t *f, urt_script_error_t err, int *count) {
  char excerpt[URT_SCRIPT_ERROR_EXCERPT + 1];
  size_t n = f->len < URT_SCRIPT_ERROR_EXCERPT ? f->len : URT_SCRIPT_ERROR_EXCERPT;
  if (n) {
    memcpy(excerpt, f->buf, n);
  }
  excerpt[n] = '\0';
  static const char *const kText[] = {"", "unit larger than the size limit",
                                      "block still open at the end of the stream",
                                      "out of memory"};
  urt_script_unit_t u = {URT_SCRIPT_UNIT_ERROR, URT_SCRIPT_CMD_UNKNOWN, err, kText[err],
                         excerpt, n, NULL, 0, f->unit_line};
  emit(f, &u);
  (*count)++;
  f->len = 0;
  f->mode = MODE_SKIP;
}

/* Emit the collected bytes as one unit of the given kind. */
static void emit_text(urt_script_framer_t *f, urt_script_unit_kind_t kind, int *count) {
  f->buf[f->len] = '\0';
  urt_script_unit_t u = {kind, URT_SCRIPT_CMD_UNKNOWN, URT_SCRIPT_ERR_NONE, NULL, f->buf,
                         f->len, NULL, 0, f->unit_line};

  // a program's name: the word after def/sec
  if (kind == URT_SCRIPT_UNIT_PROGRAM || kind == URT_SCRIPT_UNIT_SECONDARY) {
    size_t i = 0;
    while (i < f->len && is_blank(f->buf[i])) {
      i++;
    }
    i = (i + 3 < f->len) ? i + 3 : f->len;
    while (i < f->len && is_blank(f->buf[i])) {
      i++;
    }
    size_t s = i;
    while (i < f->len && is_word_char((unsigned char)f->buf[i])) {
      i++;
    }
    u.name = f->buf + s;
    u.name_len = i - s;
  }

  // a statement may be a controller command
  if (kind == URT_SCRIPT_UNIT_STATEMENT) {
    int cmd = urt_script_command_of(f->buf, f->len);
    if (cmd >= 0) {
      u.kind = URT_SCRIPT_UNIT_COMMAND;
      u.command = (urt_script_cmd_t)cmd;
    }
  }
  emit(f, &u);
  (*count)++;
  f->len = 0;
}

//---- lexer ----

/* The current word is complete: count blocks and note the line's first token. */
static void end_word(urt_script_framer_t *f) {
  if (f->word_len == 0) {
    return;
  }
  int kw = KW_OTHER;
  if (!f->word_digit && f->word_len <= 6) {
    char w[8];
    memcpy(w, f->word, (size_t)f->word_len);
    w[f->word_len] = '\0';
    if (strcmp(w, "def") == 0) {
      kw = KW_DEF;
    } else if (strcmp(w, "sec") == 0) {
      kw = KW_SEC;
    } else if (strcmp(w, "thread") == 0 || strcmp(w, "if") == 0 || strcmp(w, "while") == 0 ||
               strcmp(w, "for") == 0) {
      kw = KW_OPEN;
    } else if (strcmp(w, "end") == 0) {
      if (f->depth > 0) {
        f->depth--;
      }
    }
  }
  if (kw != KW_OTHER) {
    f->depth++;
  }
  if (f->first_kw == KW_NONE) {
    f->first_kw = kw;
  }
  f->word_len = 0;
}

/* Lex one stored byte (not a newline). */
static void lex(urt_script_framer_t *f, unsigned char c) {
  if (f->comment) {
    return;
  }
  if (f->quote) {
    if (f->escape) {
      f->escape = 0;
    } else if (c == '\\') {
      f->escape = 1;
    } else if (c == (unsigned char)f->quote) {
      f->quote = 0;
    }
    return;
  }
  if (is_word_char(c)) {
    if (f->word_len == 0) {
      f->word_digit = (c >= '0' && c <= '9');
    }
    if (f->word_len < (int)sizeof f->word) {
      f->word[f->word_len] = (char)c;
    }
    if (f->word_len < 1000) {
      f->word_len++;
    }
    f->line_code = 1;
    return;
  }
  end_word(f);
  if (is_blank((char)c)) {
    return;
  }
  if (c == '#') {
    f->comment = 1;
    return;
  }
  if (c == '"' || c == '\'') {
    f->quote = (char)c;
  }
  f->line_code = 1;
  if (f->first_kw == KW_NONE) {
    f->first_kw = KW_OTHER;
  }
}

/* A newline arrived (or the stream ended): finish the line. */
static void end_line(urt_script_framer_t *f, int *count) {
  end_word(f);
  f->quote = 0;
  f->escape = 0;
  f->comment = 0;
  f->line_no++;
  int code = f->line_code;
  int first = f->first_kw;
  f->line_code = 0;
  f->first_kw = KW_NONE;

  switch (f->mode) {
    case MODE_SKIP:
      // resume framing once the skipped unit's blocks are closed
      if (f->depth == 0) {
        f->mode = MODE_IDLE;
      }
      return;

    case MODE_IDLE:
      if (!code) {
        f->len = 0;  // blank or comment-only line between units
        f->depth = 0;
        return;
      }
      f->unit_line = f->line_no;
      if (f->depth == 0) {
        emit_text(f, first == KW_DEF   ? URT_SCRIPT_UNIT_PROGRAM
                     : first == KW_SEC ? URT_SCRIPT_UNIT_SECONDARY
                                       : URT_SCRIPT_UNIT_STATEMENT,
                  count);
        return;
      }
      f->mode = first == KW_DEF ? MODE_PROGRAM : first == KW_SEC ? MODE_SECONDARY : MODE_BLOCK;
      break;

    default:
      if (f->depth == 0) {
        emit_text(f, f->mode == MODE_PROGRAM     ? URT_SCRIPT_UNIT_PROGRAM
                     : f->mode == MODE_SECONDARY ? URT_SCRIPT_UNIT_SECONDARY
                                                 : URT_SCRIPT_UNIT_STATEMENT,
                  count);
        f->mode = MODE_IDLE;
        return;
      }
      break;
  }

  // the unit continues on the next line
  int rc = reserve_one(f);
  if (rc != 0) {
    fail_unit(f, rc == URT_ENOSPC ? URT_SCRIPT_ERR_OVERSIZE : URT_SCRIPT_ERR_NOMEM, count);
    return;
  }
  f->buf[f->len++] = '\n';
}

//---- public API ----

void urt_script_framer_init_max(urt_script_framer_t *f, size_t max_unit) {
  memset(f, 0, sizeof *f);
  f->max_unit = max_unit ? max_unit : URT_SCRIPT_MAX_UNIT_DEFAULT;
  clear_unit(f);
}

void urt_script_framer_init(urt_script_framer_t *f) { urt_script_framer_init_max(f, 0); }

void urt_script_framer_free(urt_script_framer_t *f) {
  free(f->buf);
  f->buf = NULL;
  f->cap = 0;
  f->len = 0;
}

void urt_script_framer_reset(urt_script_framer_t *f) { clear_unit(f); }

int urt_script_framer_feed(urt_script_framer_t *f, const void *data, size_t n,
                           urt_script_unit_fn on_unit, void *user) {
  const unsigned char *p = data;
  int count = 0;
  f->on_unit = on_unit;
  f->user = user;
  for (size_t i = 0; i < n; i++) {
    unsigned char c = p[i];

    // line ends; CR and NUL never reach a unit (CR still separates words)
    if (c == '\n') {
      end_line(f, &count);
      continue;
    }
    if (c == '\r' || c == '\0') {
      f->dropped_bytes++;
      if (c == '\r') {
        end_word(f);
      }
      continue;
    }

    // while skipping a failed unit only its block structure matters
    if (f->mode == MODE_SKIP) {
      lex(f, c);
      continue;
    }

    // skip leading blanks of a line outside a unit (they never start one)
    if (f->mode == MODE_IDLE && f->len == 0 && is_blank((char)c)) {
      continue;
    }

    // store, then lex
    int rc = reserve_one(f);
    if (rc != 0) {
      if (f->mode == MODE_IDLE) {
        f->unit_line = f->line_no + 1;
      }
      fail_unit(f, rc == URT_ENOSPC ? URT_SCRIPT_ERR_OVERSIZE : URT_SCRIPT_ERR_NOMEM, &count);
      lex(f, c);
      continue;
    }
    f->buf[f->len++] = (char)c;
    lex(f, c);
  }
  return count;
}

int urt_script_framer_finish(urt_script_framer_t *f, urt_script_unit_fn on_unit, void *user) {
  int count = 0;
  f->on_unit = on_unit;
  f->user = user;

  // a last line without its newline
  if (f->mode != MODE_SKIP && f->len > 0 && f->buf[f->len - 1] != '\n') {
    end_line(f, &count);
  }

  // a block still open
  if (f->mode == MODE_PROGRAM || f->mode == MODE_SECONDARY || f->mode == MODE_BLOCK) {
    while (f->len > 0 && f->buf[f->len - 1] == '\n') {
      f->len--;
    }
    fail_unit(f, URT_SCRIPT_ERR_INCOMPLETE, &count);
  }
  clear_unit(f);
  return count;
}
