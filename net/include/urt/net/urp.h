/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/urp.h — PolyScope programs (.urp: gzip-compressed XML) compiled to
 * URScript text, and the External Control URCap's program fetch (external_control.md §1.1).
 *
 *   .urp bytes ──urt_urp_compile()──▶ program (a URScript template)
 *   program ──urt_urp_render(header, body)──▶ URScript text for the runner
 *
 * The template is final unless the program holds External Control nodes: then, when it is
 * played, the text fetched from the remote PC (urt_urcap_fetch) is split at
 * `# HEADER_BEGIN`/`# HEADER_END` (urt_urcap_split) and rendered in: the header once at the
 * top of the program, the rest at every External Control node.
 *
 * Node subset: MainProgram (runOnlyOnce), BeforeStart, Move (MoveJ/MoveL/MoveP) with Fixed or
 * Variable Waypoints, Wait (Sleep, DigitalInput, Condition), Set (DigitalOutput,
 * AnalogOutput), Script (Line, File), Assignment, Loop (forever, n times, while), If/ElseIf/
 * Else, Folder, Comment, Popup, Halt and the External Control node. Anything else fails the
 * compile with the node's name. Context: non-RT; everything allocates.
 */
#ifndef URT_NET_URP_H
#define URT_NET_URP_H

#include <stddef.h>
#ifndef __cplusplus
#include <stdatomic.h>
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_urp_program urt_urp_program_t;

/* Largest .urp file read from disk [bytes] (the decompressed XML is bounded separately). */
#define URT_URP_MAX_FILE (4u << 20)

typedef struct urt_urp_options {
  /* Directory that a Script node's `file` may name (resolved with realpath inside it) when the
   * node carries no cachedContents. NULL: such a node fails. Nullable. */
  const char *script_root;
  /* The def name if the program's own name is not a valid identifier. NULL: "Program". */
  const char *fallback_name;
} urt_urp_options_t;

/* Compile the bytes of a .urp file. Returns 0 and *out, or -1 with why filled (one line, e.g.
 * "bad gzip data (truncated)", "bad XML at line 3: …", "unsupported program node 'Timer'").
 * Nullable: opt. */
int urt_urp_compile(const void *data, size_t len, const urt_urp_options_t *opt,
                    urt_urp_program_t **out, char *why, size_t why_sz);

/* Read (at most URT_URP_MAX_FILE bytes) and compile one file. Same returns. */
int urt_urp_compile_file(const char *path, const urt_urp_options_t *opt, urt_urp_program_t **out,
                         char *why, size_t why_sz);

void urt_urp_free(urt_urp_program_t *p);  /* Nullable: p */

/* The def's name, e.g. "external_control". */
const char *urt_urp_name(const urt_urp_program_t *p);

/* How many External Control nodes the program holds (0: render needs no fetch). */
int urt_urp_external_nodes(const urt_urp_program_t *p);

/* The template, for a copy that outlives p (render it with urt_urp_render_template). */
const char *urt_urp_template(const urt_urp_program_t *p, size_t *len);

/* Fill the template: header (once, at the top of the program) and body (at every External
 * Control node), each line indented to where it goes. Either may be NULL (nothing). Returns 0
 * and a NUL-terminated *text (free with free()) of *len bytes, or -1 (out of memory). */
int urt_urp_render(const urt_urp_program_t *p, const char *header, const char *body, char **text,
                   size_t *len);
int urt_urp_render_template(const char *tmpl, size_t tmpl_len, const char *header,
                            const char *body, char **text, size_t *len);

//---- the External Control URCap's side: request_program on the remote PC ----

typedef struct urt_urcap_config {
  const char *host;          /* IPv4 literal or "localhost"; loopback only (127.0.0.0/8) */
  int port;                  /* 50002 by default                                          */
  int connect_timeout_ms;    /* <= 0: 5000 (the URCap's)                                 */
  int read_timeout_ms;       /* <= 0: 500 (the URCap's socket timeout)                   */
  int total_timeout_ms;      /* <= 0: 10000: the whole exchange, however slowly it trickles */
#ifndef __cplusplus
  const _Atomic int *cancel; /* nonzero: give up at the next 50 ms step. Nullable.       */
#else
  const void *cancel;        /* (C only: an _Atomic int)                                 */
#endif
} urt_urcap_config_t;

/* Is host an IPv4 literal in 127.0.0.0/8, or "localhost"? */
int urt_urcap_host_is_loopback(const char *host);

/* Connect, write "request_program\n", read reply lines until the server is quiet for
 * read_timeout_ms (or closes), as the URCap does. Returns 0 with the text in *text (free with
 * free()). On failure returns -1 and *text is what the URCap runs instead: a blocking popup
 * ("The connection to the remote PC at HOST:PORT could not be established. Reason: …" or
 * "Timeout while reading requested program from HOST:PORT") followed by sync(). A host that is
 * not loopback is never dialled (the popup names the reason). *text is NULL only when out of
 * memory. */
int urt_urcap_fetch(const urt_urcap_config_t *cfg, char **text, size_t *len);

/* Split fetched text as the URCap does: the lines from `# HEADER_BEGIN` to `# HEADER_END`
 * (both kept) are the header, the lines after it the body; without both markers the whole
 * text is the body. Returns 0 with *header and *body (free both), or -1 (out of memory). */
int urt_urcap_split(const char *text, size_t len, char **header, char **body);

#ifdef __cplusplus
}
#endif
#endif
