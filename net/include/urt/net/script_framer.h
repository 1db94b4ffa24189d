/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/script_framer.h — splits the text a client writes to 30001–30003 into
 * units the controller acts on (protocols.md §4.6):
 *
 *   COMMAND    a whole line that is a controller command, not URScript
 *              ("power on", "set robotmode run", "stop program", "set sim", …)
 *   PROGRAM    a complete top-level `def name(…): … end`
 *   SECONDARY  a complete top-level `sec name(…): … end`
 *   STATEMENT  one top-level line (or a top-level `if/while/for/thread … end` block)
 *   ERROR      a unit that could not be framed (over the size limit, incomplete at the end
 *              of the stream, out of memory)
 *
 * Blocks are counted by words: `def sec thread if while for` open, `end` closes, `elif` and
 * `else` are neutral; words inside `#` comments and "…"/'…' strings do not count, and strings
 * and comments end at the end of a line. A unit ends at the newline of the line on which its
 * block count returns to zero. `\r` and NUL bytes are dropped; blank and comment-only lines
 * between units are skipped. Feeding the same bytes in any chunking gives the same units.
 *
 * Memory is bounded: the unit buffer grows to at most max_unit + 1 bytes. A unit that would
 * exceed max_unit is reported at once as an ERROR unit; its remaining bytes are skipped up to
 * the end of the line on which its block count is back to zero (for a single line: the next
 * line), where framing resumes.
 */
#ifndef URT_NET_SCRIPT_FRAMER_H
#define URT_NET_SCRIPT_FRAMER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define URT_SCRIPT_MAX_UNIT_DEFAULT (1u << 20)  /* 1 MiB */
#define URT_SCRIPT_ERROR_EXCERPT 64             /* bytes of a failed unit shown in its ERROR */

typedef enum urt_script_unit_kind {
  URT_SCRIPT_UNIT_COMMAND = 1,
  URT_SCRIPT_UNIT_PROGRAM,
  URT_SCRIPT_UNIT_SECONDARY,
  URT_SCRIPT_UNIT_STATEMENT,
  URT_SCRIPT_UNIT_ERROR
} urt_script_unit_kind_t;

/* Controller commands (protocols.md §4.6). */
typedef enum urt_script_cmd {
  URT_SCRIPT_CMD_UNKNOWN = 0,   /* looks like a command ("set foo bar") but is not known */
  URT_SCRIPT_CMD_POWER_ON,      /* "power on"                   */
  URT_SCRIPT_CMD_POWER_OFF,     /* "power off"                  */
  URT_SCRIPT_CMD_BRAKE_RELEASE, /* "set robotmode run"          */
  URT_SCRIPT_CMD_UNLOCK_PSTOP,  /* "set unlock protective stop" */
  URT_SCRIPT_CMD_STOP_PROGRAM,  /* "stop program"               */
  URT_SCRIPT_CMD_SET_SIM,       /* "set sim"                    */
  URT_SCRIPT_CMD_SET_REAL       /* "set real"                   */
} urt_script_cmd_t;

typedef enum urt_script_error {
  URT_SCRIPT_ERR_NONE = 0,
  URT_SCRIPT_ERR_OVERSIZE,      /* unit longer than max_unit                    */
  URT_SCRIPT_ERR_INCOMPLETE,    /* block still open at urt_script_framer_flush() */
  URT_SCRIPT_ERR_NOMEM          /* the buffer could not grow                    */
} urt_script_error_t;

typedef struct urt_script_unit {
  urt_script_unit_kind_t kind;
  urt_script_cmd_t command;     /* COMMAND only                                         */
  urt_script_error_t error_code;/* ERROR only, else URT_SCRIPT_ERR_NONE                 */
  const char *error;            /* ERROR only: what went wrong (static text); else NULL */
  const char *text;             /* the unit's lines joined by '\n', no final newline,
                                   NUL-terminated; ERROR: the first ≤ 64 bytes kept.
                                   Valid only during the callback.                      */
  size_t len;                   /* bytes in text (without the NUL)                      */
  const char *name;             /* PROGRAM/SECONDARY: the name after def/sec (in text) */
  size_t name_len;              /* 0 when there is none                                 */
  uint64_t line;                /* 1-based stream line number of the unit's first line  */
} urt_script_unit_t;

/* Called once per unit, in stream order. It must not call back into the same framer. */
typedef void (*urt_script_unit_fn)(void *user, const urt_script_unit_t *unit);

typedef struct urt_script_framer {
  /* configuration */
  size_t max_unit;         /* largest unit [bytes], set by init / init_max */

  /* the callback of the feed or finish call in progress */
  urt_script_unit_fn on_unit;
  void *user;

  /* unit buffer (grows to at most max_unit + 1) */
  char *buf;
  size_t len, cap;

  /* lexer */
  int depth;               /* open blocks                                   */
  char quote;              /* inside a string delimited by this, or 0        */
  int escape;              /* previous byte was a backslash inside a string  */
  int comment;             /* inside a # comment                              */
  char word[8];            /* current word (first 7 bytes)                   */
  int word_len;            /* its full length, 0 when not in a word          */
  int word_digit;          /* current word starts with a digit (a number)    */

  /* current line and unit */
  int line_code;           /* the line has something other than blanks/comments */
  int first_kw;            /* what the line's first token is (internal code)  */
  int mode;                /* idle, program, secondary, block, skip (internal) */
  uint64_t line_no;        /* lines completed so far                          */
  uint64_t unit_line;      /* first line of the unit being collected          */

  /* statistics */
  uint64_t units, errors, dropped_bytes;
} urt_script_framer_t;

/* Set up a framer with the default unit limit (URT_SCRIPT_MAX_UNIT_DEFAULT). No allocation
 * until bytes arrive. Context: any. */
void urt_script_framer_init(urt_script_framer_t *f);

/* The same with a unit limit of max_unit bytes (0: the default). */
void urt_script_framer_init_max(urt_script_framer_t *f, size_t max_unit);

/* Free the buffer. The framer may be initialised again afterwards. */
void urt_script_framer_free(urt_script_framer_t *f);

/* Forget any partial unit (e.g. the client reconnected); statistics are kept. */
void urt_script_framer_reset(urt_script_framer_t *f);

/* Consume n bytes (any content, any chunking) and call on_unit for every unit they complete,
 * in order. on_unit must not call back into this framer. Returns the number of units emitted
 * (ERROR units included). Nullable: data when n is 0, on_unit (units are then only counted),
 * user. Context: non-RT (may grow the buffer). */
int urt_script_framer_feed(urt_script_framer_t *f, const void *data, size_t n,
                           urt_script_unit_fn on_unit, void *user);

/* End of stream: a final line without newline is framed as if the newline had arrived (a
 * statement sent without its newline still runs); a block still open becomes an ERROR
 * (URT_SCRIPT_ERR_INCOMPLETE). The framer is then empty. Returns the number of units. */
int urt_script_framer_finish(urt_script_framer_t *f, urt_script_unit_fn on_unit, void *user);

/* "power on" → URT_SCRIPT_CMD_POWER_ON …; -1 if line is not a controller command (blanks
 * around and between words are ignored). */
int urt_script_command_of(const char *line, size_t len);

#ifdef __cplusplus
}
#endif
#endif
