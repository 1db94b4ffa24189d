/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urp_compile.c — a PolyScope program's node tree (urp_doc.h) to URScript (urp.h).
 *
 * The schema was learned from real files (URCL's tests/resources/dockerursim/programs, and
 * programs published by tools that write .urp for PolyScope 3.x and 5.x): every node is an
 * element, its sub-nodes sit in a <children> element, expressions are sequences of
 * <ExpressionChar character=…>, <ExpressionToken token=…> and <ExpressionVariable> (holding a
 * variable element, often an XStream `reference` to where it was first declared). Where
 * PolyScope versions differ (Set's outputBit/outputValue attributes against pin/digitalValue
 * children, a Popup's message attribute against a <message> child, waypoints' <JointAngles>
 * child against a `joints` attribute) both forms are read.
 *
 * The URScript is what PolyScope generates, without its `$ n "…"` line markers: a def named
 * after the program, BeforeStart first, the main body in `while (True):` unless the program
 * runs only once, numbers written back as stored (shortest text that reads back to the same
 * double). A node outside the subset is a compile error naming it, never skipped.
 */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "urp_doc.h"
#include "urp_text.h"
#include "urt/net/urp.h"

#define SCRIPT_FILE_MAX (1u << 20)  /* a Script node's file [bytes] */

struct urt_urp_program {
  char name[64];
  char *tmpl;
  size_t len;
  int external;
};

typedef struct gen {
  urp_text out;
  char why[256];
  int loops;        /* Loop_<k> counters handed out */
  int external;     /* External Control nodes seen */
  const urt_urp_options_t *opt;
} gen;

static int fail(gen *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail(gen *g, const char *fmt, ...) {
  if (!g->why[0]) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(g->why, sizeof g->why, fmt, ap);
    va_end(ap);
  }
  return -1;
}

static int is_tag(const urp_el *e, const char *tag) { return e && strcmp(e->tag, tag) == 0; }

static int eq_nocase(const char *a, const char *b) {
  if (!a || !b) {
    return 0;
  }
  while (*a && *b && tolower((unsigned char)*a) == tolower((unsigned char)*b)) {
    a++, b++;
  }
  return *a == *b;
}

/* An element's text, or the attribute of that name, whichever exists (child first). */
static const char *param(const urp_el *node, const char *name) {
  const urp_el *c = urp_child(node, name);
  return c ? c->text : urp_attr(node, name);
}

//---- values ----

/* Parse a stored number: blanks around it allowed, nothing else. */
static int parse_num(const char *s, double *x) {
  if (!s) {
    return -1;
  }
  while (isspace((unsigned char)*s)) s++;
  char *end = NULL;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || errno == ERANGE || !isfinite(v)) {
    return -1;
  }
  while (isspace((unsigned char)*end)) end++;
  if (*end) {
    return -1;
  }
  *x = v;
  return 0;
}

/* The shortest text that reads back as x. */
static void put_num(urp_text *t, double x) {
  char buf[40];
  for (int prec = 1; prec <= 17; prec++) {
    snprintf(buf, sizeof buf, "%.*g", prec, x);
    if (strtod(buf, NULL) == x) {
      break;
    }
  }
  // "1" stays an integer only where PolyScope writes one; a float literal keeps its type
  if (!strpbrk(buf, ".eEn")) {
    strcat(buf, ".0");
  }
  urp_text_puts(t, buf);
}

static int num_param(gen *g, const urp_el *node, const char *name, double *x) {
  const char *s = param(node, name);
  if (parse_num(s, x) != 0) {
    return fail(g, "%s: %s '%s' is not a number", node->tag, name, s ? s : "(missing)");
  }
  return 0;
}

/* "a, b, c, d, e, f" → six numbers. */
static int parse_six(const char *s, double v[6]) {
  if (!s) {
    return -1;
  }
  for (int k = 0; k < 6; k++) {
    char *end = NULL;
    errno = 0;
    v[k] = strtod(s, &end);
    if (end == s || errno == ERANGE || !isfinite(v[k])) {
      return -1;
    }
    s = end;
    while (isspace((unsigned char)*s)) s++;
    if (k < 5) {
      if (*s != ',') {
        return -1;
      }
      s++;
    }
  }
  return *s ? -1 : 0;
}

static void put_six(urp_text *t, const char *prefix, const double v[6]) {
  urp_text_puts(t, prefix);
  for (int k = 0; k < 6; k++) {
    if (k) urp_text_puts(t, ", ");
    put_num(t, v[k]);
  }
  urp_text_puts(t, "]");
}

/* "1"/"0", "true"/"false", "high"/"low" → 1/0; -1 otherwise. */
static int parse_bool(const char *s) {
  if (!s) return -1;
  while (isspace((unsigned char)*s)) s++;
  char w[8] = {0};
  size_t n = 0;
  while (s[n] && !isspace((unsigned char)s[n]) && n < sizeof w - 1) {
    w[n] = s[n];
    n++;
  }
  if (eq_nocase(w, "1") || eq_nocase(w, "true") || eq_nocase(w, "high")) return 1;
  if (eq_nocase(w, "0") || eq_nocase(w, "false") || eq_nocase(w, "low")) return 0;
  return -1;
}

static int is_ident(const char *s) {
  if (!s || !(isalpha((unsigned char)*s) || *s == '_')) {
    return 0;
  }
  size_t n = 0;
  for (; *s; s++, n++) {
    if (!(isalnum((unsigned char)*s) || *s == '_')) {
      return 0;
    }
  }
  return n < 64;
}

/* A string literal's contents: URScript has no escapes, so a double quote becomes a single
 * one and control characters blanks (PolyScope's own editor allows neither). */
static void put_string(urp_text *t, const char *s) {
  urp_text_puts(t, "\"");
  for (; s && *s; s++) {
    char c = *s;
    if (c == '"') c = '\'';
    if ((unsigned char)c < 0x20) c = ' ';
    urp_text_put(t, &c, 1);
  }
  urp_text_puts(t, "\"");
}

//---- expressions ----

/* The name of a variable element (after following its reference). */
static const char *var_name(gen *g, const urp_el *v, const char *where) {
  const urp_el *d = urp_deref(v);
  const char *name = d ? urp_attr(d, "name") : NULL;
  if (!d) {
    fail(g, "%s: the variable reference '%s' does not resolve", where, urp_attr(v, "reference"));
    return NULL;
  }
  if (!is_ident(name)) {
    fail(g, "%s: '%s' is not a variable name", where, name ? name : "(missing)");
    return NULL;
  }
  return name;
}

/* The text of an <expression>: one line, no control characters. */
static int expr_text(gen *g, const urp_el *expr, const char *where, urp_text *t) {
  if (!expr) {
    return fail(g, "%s: no expression", where);
  }
  size_t start = t->len;
  if (!expr->first) {
    urp_text_put(t, expr->text, expr->text_len);  // a plain-text expression
  }
  for (const urp_el *c = expr->first; c; c = c->next) {
    if (is_tag(c, "ExpressionChar")) {
      urp_text_puts(t, urp_attr(c, "character") ? urp_attr(c, "character") : "");
    } else if (is_tag(c, "ExpressionToken")) {
      urp_text_puts(t, urp_attr(c, "token") ? urp_attr(c, "token") : "");
    } else if (is_tag(c, "ExpressionVariable")) {
      const urp_el *v = c->first ? c->first : c;
      const char *name = var_name(g, v, where);
      if (!name) {
        return -1;
      }
      urp_text_puts(t, name);
    } else {
      return fail(g, "%s: unsupported expression element '%s'", where, c->tag);
    }
  }
  if (t->oom) {
    return fail(g, "out of memory");
  }
  for (size_t k = start; k < t->len; k++) {
    if ((unsigned char)t->p[k] < 0x20 && t->p[k] != '\t') {
      return fail(g, "%s: the expression holds a line break or control character", where);
    }
  }
  size_t k = start;
  while (k < t->len && isspace((unsigned char)t->p[k])) k++;
  if (k == t->len) {
    return fail(g, "%s: empty expression", where);
  }
  return 0;
}

/* "(<expression>)" into out. */
static int put_cond(gen *g, const urp_el *node, urp_text *out) {
  urp_text_puts(out, "(");
  if (expr_text(g, urp_child(node, "expression"), node->tag, out) != 0) {
    return -1;
  }
  urp_text_puts(out, ")");
  return 0;
}

//---- I/O pins ----

typedef struct pin_kind {
  const char *prefix;    /* referencedName up to '[' */
  const char *fn;        /* URScript function       */
  int max;               /* highest index           */
} pin_kind;

static const pin_kind kDigitalIn[] = {
    {"digital_in", "get_standard_digital_in", 7},
    {"config_in", "get_configurable_digital_in", 7},
    {"tool_in", "get_tool_digital_in", 1},
    {"GP_bool_in", "read_input_boolean_register", 127},
    {NULL, NULL, 0}};
static const pin_kind kDigitalOut[] = {
    {"digital_out", "set_standard_digital_out", 7},
    {"config_out", "set_configurable_digital_out", 7},
    {"tool_out", "set_tool_digital_out", 1},
    {"GP_bool_out", "write_output_boolean_register", 127},
    {NULL, NULL, 0}};
static const pin_kind kAnalogOut[] = {
    {"analog_out", "set_standard_analog_out", 1},
    {NULL, NULL, 0}};

/* pin referencedName "digital_out[3]" → kind and index. */
static const pin_kind *find_pin(gen *g, const urp_el *node, const pin_kind *kinds, int *index) {
  const urp_el *pin = urp_child(node, "pin");
  const urp_el *d = pin ? urp_deref(pin) : NULL;
  const char *ref = d ? urp_attr(d, "referencedName") : NULL;
  if (!ref) {
    fail(g, "%s: no pin", node->tag);
    return NULL;
  }
  const char *br = strchr(ref, '[');
  for (const pin_kind *k = kinds; br && k->prefix; k++) {
    size_t n = strlen(k->prefix);
    if ((size_t)(br - ref) != n || strncmp(ref, k->prefix, n) != 0) {
      continue;
    }
    char *end = NULL;
    long i = strtol(br + 1, &end, 10);
    if (end == br + 1 || *end != ']' || end[1] || i < 0 || i > k->max) {
      break;
    }
    *index = (int)i;
    return k;
  }
  fail(g, "%s: unsupported pin '%s'", node->tag, ref);
  return NULL;
}

//---- nodes ----

enum { STOP_NONE = 0, STOP_WAYPOINT, STOP_BRANCH };
static const urp_el *emit_list(gen *g, const urp_el *c, int ind, int stop, int *rc);
static int emit_children(gen *g, const urp_el *node, int ind);

static void line(gen *g, int ind, const char *s) {
  urp_text_indent(&g->out, ind);
  urp_text_puts(&g->out, s);
  urp_text_puts(&g->out, "\n");
}

/* the line "<indent><text>\n" where text was built in t */
static void line_t(gen *g, int ind, urp_text *t) {
  urp_text_indent(&g->out, ind);
  urp_text_put(&g->out, t->p ? t->p : "", t->len);
  urp_text_puts(&g->out, "\n");
  if (t->oom) g->out.oom = true;
  urp_text_free(t);
}

typedef struct move_ctx {
  const char *fn;          /* movej / movel / movep */
  int joint_space;         /* MoveJ: joint speed and acceleration */
  double v, a, r;          /* shared parameters */
} move_ctx;

static int emit_waypoint(gen *g, const urp_el *wp, const move_ctx *m, int ind) {
  const char *name = urp_attr(wp, "name") ? urp_attr(wp, "name") : "(unnamed)";
  const char *type = urp_attr(wp, "type") ? urp_attr(wp, "type") : "Fixed";
  urp_text t = {0};
  urp_text_printf(&t, "%s(", m->fn);

  if (eq_nocase(type, "Fixed")) {
    // joint angles are what PolyScope stores as the truth of a fixed waypoint (the pose is
    // recomputed from them); movel/movep take them as "pose as joint positions"
    const urp_el *pos = urp_child(wp, "position");
    const urp_el *ja = pos ? urp_child(pos, "JointAngles") : NULL;
    const char *angles = ja ? urp_attr(ja, "angles") : pos ? urp_attr(pos, "joints") : NULL;
    const char *pose = pos ? urp_attr(pos, "pose") : NULL;
    double v[6];
    if (angles) {
      if (parse_six(angles, v) != 0) {
        urp_text_free(&t);
        return fail(g, "Waypoint '%s': joint angles '%s' are not six numbers", name, angles);
      }
      put_six(&t, "[", v);
    } else if (pose) {
      if (parse_six(pose, v) != 0) {
        urp_text_free(&t);
        return fail(g, "Waypoint '%s': pose '%s' is not six numbers", name, pose);
      }
      put_six(&t, "p[", v);
    } else {
      urp_text_free(&t);
      return fail(g, "Waypoint '%s': no position", name);
    }
  } else if (eq_nocase(type, "Variable")) {
    const urp_el *var = urp_child(wp, "variable");
    const char *vn = var ? var_name(g, var, "Waypoint") : NULL;
    if (!vn) {
      urp_text_free(&t);
      return var ? -1 : fail(g, "Waypoint '%s': no variable", name);
    }
    urp_text_puts(&t, vn);
  } else {
    urp_text_free(&t);
    return fail(g, "unsupported program node 'Waypoint' (%s waypoint '%s')", type, name);
  }

  // the waypoint's own parameters, where it has them, else the Move's
  double v = m->v, a = m->a, r = m->r;
  const urp_el *mp = urp_child(wp, "motionParameters");
  const char *vs = mp ? urp_attr(mp, m->joint_space ? "jointSpeed" : "cartesianSpeed") : NULL;
  const char *as = mp ? urp_attr(mp, m->joint_space ? "jointAcceleration"
                                                   : "cartesianAcceleration") : NULL;
  const char *rs = mp ? urp_attr(mp, "blendRadius") : NULL;
  if ((vs && parse_num(vs, &v) != 0) || (as && parse_num(as, &a) != 0) ||
      (rs && parse_num(rs, &r) != 0) || v <= 0 || a <= 0 || r < 0) {
    urp_text_free(&t);
    return fail(g, "Waypoint '%s': bad speed, acceleration or blend radius", name);
  }
  urp_text_puts(&t, ", a=");
  put_num(&t, a);
  urp_text_puts(&t, ", v=");
  put_num(&t, v);
  if (r > 0) {
    urp_text_puts(&t, ", r=");
    put_num(&t, r);
  }
  urp_text_puts(&t, ")");
  line_t(g, ind, &t);
  return 0;
}

static int emit_move(gen *g, const urp_el *n, int ind) {
  const char *mt = urp_attr(n, "motionType") ? urp_attr(n, "motionType") : "MoveJ";
  move_ctx m = {0};
  if (strcmp(mt, "MoveJ") == 0) {
    m = (move_ctx){"movej", 1, 1.0471975511965976, 1.3962634015954636, 0.0};
  } else if (strcmp(mt, "MoveL") == 0) {
    m = (move_ctx){"movel", 0, 0.25, 1.2, 0.0};
  } else if (strcmp(mt, "MoveP") == 0) {
    m = (move_ctx){"movep", 0, 0.25, 1.2, 0.0};
  } else {
    return fail(g, "unsupported program node 'Move' (%s)", mt);
  }
  const char *s;
  if (((s = urp_attr(n, "speed")) && parse_num(s, &m.v) != 0) ||
      ((s = urp_attr(n, "acceleration")) && parse_num(s, &m.a) != 0) ||
      ((s = urp_attr(n, "blendRadius")) && parse_num(s, &m.r) != 0)) {
    return fail(g, "%s: bad speed, acceleration or blend radius", mt);
  }
  const urp_el *kids = urp_child(n, "children");
  const urp_el *c = kids ? kids->first : NULL;
  while (c) {
    if (is_tag(c, "Waypoint")) {
      if (emit_waypoint(g, c, &m, ind) != 0) {
        return -1;
      }
      c = c->next;
    } else {
      // PolyScope lets any node sit between the waypoints of a Move
      int rc = 0;
      c = emit_list(g, c, ind, STOP_WAYPOINT, &rc);
      if (rc != 0) {
        return -1;
      }
    }
  }
  return 0;
}

static int emit_wait(gen *g, const urp_el *n, int ind) {
  const char *type = urp_attr(n, "type") ? urp_attr(n, "type") : "Sleep";
  if (strcmp(type, "Sleep") == 0) {
    double t;
    if (num_param(g, n, "waitTime", &t) != 0) return -1;
    if (t < 0) return fail(g, "Wait: negative time");
    urp_text s = {0};
    urp_text_puts(&s, "sleep(");
    put_num(&s, t);
    urp_text_puts(&s, ")");
    line_t(g, ind, &s);
    return 0;
  }
  urp_text s = {0};
  if (strcmp(type, "DigitalInput") == 0) {
    int index;
    const pin_kind *k = find_pin(g, n, kDigitalIn, &index);
    if (!k) return -1;
    int b = parse_bool(param(n, "digitalValue"));
    if (b < 0) return fail(g, "Wait: digitalValue is not 0/1");
    urp_text_printf(&s, "while (not(%s(%d) == %s)):", k->fn, index, b ? "True" : "False");
  } else if (strcmp(type, "Condition") == 0) {
    urp_text_puts(&s, "while (not");
    if (put_cond(g, n, &s) != 0) {
      urp_text_free(&s);
      return -1;
    }
    urp_text_puts(&s, "):");
  } else {
    return fail(g, "unsupported program node 'Wait' (%s)", type);
  }
  line_t(g, ind, &s);
  line(g, ind + 1, "sync()");
  line(g, ind, "end");
  return 0;
}

static int emit_set(gen *g, const urp_el *n, int ind) {
  for (const urp_el *c = n->first; c; c = c->next) {
    if (!is_tag(c, "pin") && !is_tag(c, "digitalValue") && !is_tag(c, "analogValue")) {
      return fail(g, "unsupported program node 'Set' (with %s)", c->tag);
    }
  }
  urp_text s = {0};
  const char *bit = urp_attr(n, "outputBit");
  const char *type = urp_attr(n, "type") ? urp_attr(n, "type") : "DigitalOutput";
  if (bit) {
    // the older form: <Set type="DigitalOutput" outputBit="2" outputValue="true"/>
    char *end = NULL;
    long i = strtol(bit, &end, 10);
    int b = parse_bool(urp_attr(n, "outputValue"));
    if (end == bit || *end || i < 0 || i > 7 || b < 0) {
      return fail(g, "Set: bad outputBit/outputValue");
    }
    urp_text_printf(&s, "set_standard_digital_out(%ld, %s)", i, b ? "True" : "False");
  } else if (strcmp(type, "DigitalOutput") == 0) {
    int index;
    const pin_kind *k = find_pin(g, n, kDigitalOut, &index);
    if (!k) return -1;
    int b = parse_bool(param(n, "digitalValue"));
    if (b < 0) return fail(g, "Set: digitalValue is not 0/1");
    urp_text_printf(&s, "%s(%d, %s)", k->fn, index, b ? "True" : "False");
  } else if (strcmp(type, "AnalogOutput") == 0) {
    int index;
    const pin_kind *k = find_pin(g, n, kAnalogOut, &index);
    double v;
    if (!k || num_param(g, n, "analogValue", &v) != 0) return -1;
    urp_text_printf(&s, "%s(%d, ", k->fn, index);
    put_num(&s, v);
    urp_text_puts(&s, ")");
  } else {
    return fail(g, "unsupported program node 'Set' (%s)", type);
  }
  line_t(g, ind, &s);
  return 0;
}

/* A Script node's file when it carries no cached copy: looked up inside script_root. */
static int read_script_file(gen *g, const char *file, urp_text *t) {
  if (!g->opt || !g->opt->script_root) {
    return fail(g, "Script: '%s' has no cached contents and no programs folder to read it from",
                file);
  }
  char root[PATH_MAX], cand[PATH_MAX], real[PATH_MAX];
  while (isspace((unsigned char)*file)) file++;
  const char *rel = file[0] == '/' ? strrchr(file, '/') + 1 : file;  // robot paths: by name
  size_t rl = strlen(rel);
  while (rl > 0 && isspace((unsigned char)rel[rl - 1])) rl--;
  if (!realpath(g->opt->script_root, root) ||
      snprintf(cand, sizeof cand, "%s/%.*s", root, (int)rl, rel) >= (int)sizeof cand ||
      !realpath(cand, real) || strncmp(real, root, strlen(root)) != 0 ||
      real[strlen(root)] != '/') {
    return fail(g, "Script: file '%s' not found", file);
  }
  FILE *f = fopen(real, "rb");
  struct stat st;
  if (!f || fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode) ||
      st.st_size > (off_t)SCRIPT_FILE_MAX) {
    if (f) fclose(f);
    return fail(g, "Script: file '%s' cannot be read", file);
  }
  char buf[4096];
  size_t got;
  while ((got = fread(buf, 1, sizeof buf, f)) > 0) {
    urp_text_put(t, buf, got);
  }
  fclose(f);
  return 0;
}

static int emit_script(gen *g, const urp_el *n, int ind) {
  const char *type = urp_attr(n, "type") ? urp_attr(n, "type") : "Line";
  if (strcmp(type, "Line") == 0) {
    urp_text s = {0};
    if (expr_text(g, urp_child(n, "expression"), "Script", &s) != 0) {
      urp_text_free(&s);
      return -1;
    }
    line_t(g, ind, &s);
    return 0;
  }
  if (strcmp(type, "File") == 0) {
    const urp_el *cached = urp_child(n, "cachedContents");
    if (cached) {
      urp_text_lines(&g->out, cached->text, cached->text_len, ind);
      return 0;
    }
    const urp_el *file = urp_child(n, "file");
    if (!file) return fail(g, "Script: neither cached contents nor a file");
    urp_text body = {0};
    if (read_script_file(g, file->text, &body) != 0) {
      urp_text_free(&body);
      return -1;
    }
    urp_text_lines(&g->out, body.p ? body.p : "", body.len, ind);
    urp_text_free(&body);
    return 0;
  }
  return fail(g, "unsupported program node 'Script' (%s)", type);
}

static int emit_assignment(gen *g, const urp_el *n, int ind) {
  const char *src = urp_attr(n, "valueSource");
  if (src && strcmp(src, "Expression") != 0) {
    return fail(g, "unsupported program node 'Assignment' (value from %s)", src);
  }
  const urp_el *var = urp_child(n, "variable");
  const char *name = var ? var_name(g, var, "Assignment") : NULL;
  if (!name) {
    return var ? -1 : fail(g, "Assignment: no variable");
  }
  urp_text s = {0};
  urp_text_printf(&s, "global %s = ", name);
  if (expr_text(g, urp_child(n, "expression"), "Assignment", &s) != 0) {
    urp_text_free(&s);
    return -1;
  }
  line_t(g, ind, &s);
  return 0;
}

static int emit_loop(gen *g, const urp_el *n, int ind) {
  const char *cc = urp_attr(n, "checkContinuously");
  if (cc && eq_nocase(cc, "true")) {
    return fail(g, "unsupported program node 'Loop' (checking the expression continuously)");
  }
  const char *type = urp_attr(n, "type");
  const char *count = NULL;
  static const char *const kCount[] = {"loopNum", "loopCount", "count", "times", NULL};
  for (int k = 0; kCount[k] && !count; k++) {
    count = param(n, kCount[k]);
  }
  enum { FOREVER, TIMES, WHILE } kind;
  if (type && (eq_nocase(type, "Forever") || eq_nocase(type, "Always"))) {
    kind = FOREVER;
  } else if (type && (eq_nocase(type, "While") || eq_nocase(type, "Expression"))) {
    kind = WHILE;
  } else if (type && !eq_nocase(type, "Counting") && !eq_nocase(type, "XTimes") &&
             !eq_nocase(type, "Times")) {
    return fail(g, "unsupported program node 'Loop' (%s)", type);
  } else if (type || count) {
    kind = TIMES;
  } else {
    kind = urp_child(n, "expression") ? WHILE : FOREVER;
  }

  urp_text s = {0};
  if (kind == FOREVER) {
    line(g, ind, "while (True):");
  } else if (kind == WHILE) {
    urp_text_puts(&s, "while ");
    if (put_cond(g, n, &s) != 0) {
      urp_text_free(&s);
      return -1;
    }
    urp_text_puts(&s, ":");
    line_t(g, ind, &s);
  } else {
    char *end = NULL;
    long times = count ? strtol(count, &end, 10) : -1;
    while (end && isspace((unsigned char)*end)) end++;
    if (!count || end == count || *end || times < 0 || times > INT_MAX) {
      return fail(g, "Loop: '%s' is not a number of times", count ? count : "(missing)");
    }
    int k = ++g->loops;
    urp_text_indent(&g->out, ind);
    urp_text_printf(&g->out, "Loop_%d = 0\n", k);
    urp_text_indent(&g->out, ind);
    urp_text_printf(&g->out, "while (Loop_%d < %ld):\n", k, times);
    if (emit_children(g, n, ind + 1) != 0) return -1;
    urp_text_indent(&g->out, ind + 1);
    urp_text_printf(&g->out, "Loop_%d = Loop_%d + 1\n", k, k);
    line(g, ind, "end");
    return 0;
  }
  if (emit_children(g, n, ind + 1) != 0) return -1;
  line(g, ind, "end");
  return 0;
}

static int if_branch(const urp_el *e) {
  if (!is_tag(e, "If")) return 0;
  const char *t = urp_attr(e, "type");
  return t && (strcmp(t, "ElseIf") == 0 || strcmp(t, "Else") == 0);
}

/* One branch head ("if"/"elif"/"else") and its body (its children, except trailing branches
 * that some PolyScope versions nest inside the If: those are returned in *nested). */
static int emit_branch(gen *g, const urp_el *n, const char *head, int ind, int *seen_else) {
  const char *cc = urp_attr(n, "checkContinuously");
  if (cc && eq_nocase(cc, "true")) {
    return fail(g, "unsupported program node 'If' (checking the expression continuously)");
  }
  if (*seen_else) {
    return fail(g, "If: a branch after Else");
  }
  urp_text s = {0};
  if (strcmp(head, "else") == 0) {
    *seen_else = 1;
    line(g, ind, "else:");
  } else {
    urp_text_printf(&s, "%s ", head);
    if (put_cond(g, n, &s) != 0) {
      urp_text_free(&s);
      return -1;
    }
    urp_text_puts(&s, ":");
    line_t(g, ind, &s);
  }
  // the body: children up to the first nested ElseIf/Else
  const urp_el *kids = urp_child(n, "children");
  int rc = 0;
  const urp_el *rest = emit_list(g, kids ? kids->first : NULL, ind + 1, STOP_BRANCH, &rc);
  if (rc != 0) return -1;
  // nested branches
  for (const urp_el *c = rest; c; c = c->next) {
    if (!if_branch(c)) {
      return fail(g, "If: '%s' after an %s branch inside the If", c->tag, urp_attr(rest, "type"));
    }
    const char *t = urp_attr(c, "type");
    if (emit_branch(g, c, strcmp(t, "Else") == 0 ? "else" : "elif", ind, seen_else) != 0) {
      return -1;
    }
  }
  return 0;
}

/* An If and the ElseIf/Else siblings after it; returns the first sibling not consumed. */
static const urp_el *emit_if(gen *g, const urp_el *n, int ind, int *rc) {
  int seen_else = 0;
  *rc = emit_branch(g, n, "if", ind, &seen_else);
  const urp_el *c = n->next;
  for (; *rc == 0 && if_branch(c); c = c->next) {
    const char *t = urp_attr(c, "type");
    *rc = emit_branch(g, c, strcmp(t, "Else") == 0 ? "else" : "elif", ind, &seen_else);
  }
  if (*rc == 0) line(g, ind, "end");
  return c;
}

static int emit_popup(gen *g, const urp_el *n, int ind) {
  const char *type = urp_attr(n, "type");
  int warning = eq_nocase(urp_attr(n, "warning"), "true") || eq_nocase(type, "Warning");
  int error = eq_nocase(urp_attr(n, "error"), "true") || eq_nocase(type, "Error");
  if (type && !eq_nocase(type, "Message") && !warning && !error) {
    return fail(g, "unsupported program node 'Popup' (%s)", type);
  }
  const char *msg = param(n, "message");
  urp_text s = {0};
  urp_text_puts(&s, "popup(");
  put_string(&s, msg ? msg : "");
  urp_text_puts(&s, ", ");
  put_string(&s, error ? "Error" : warning ? "Warning" : "Message");
  urp_text_printf(&s, ", %s, %s, blocking=True)", warning ? "True" : "False",
                  error ? "True" : "False");
  line_t(g, ind, &s);
  if (eq_nocase(urp_attr(n, "haltProgram"), "true")) {
    line(g, ind, "halt");
  }
  return 0;
}

static int emit_comment(gen *g, const urp_el *n, int ind) {
  const char *c = param(n, "comment");
  urp_text s = {0};
  urp_text_puts(&s, "# ");
  for (; c && *c; c++) {
    char ch = (unsigned char)*c < 0x20 ? ' ' : *c;
    urp_text_put(&s, &ch, 1);
  }
  line_t(g, ind, &s);
  return 0;
}

static const char kExternalControl[] = "com.fzi.externalcontrol.ExternalControlNode";

static int emit_contributed(gen *g, const urp_el *n, int ind) {
  const char *cls = urp_attr(n, "strategyClass");
  if (cls && strcmp(cls, kExternalControl) == 0) {
    g->external++;
    urp_text_indent(&g->out, ind);
    urp_text_puts(&g->out, "\x01" "B\n");
    return 0;
  }
  const char *what = urp_attr(n, "strategyProgramNodeType");
  return fail(g, "unsupported program node 'Contributed' (%s)",
              what ? what : cls ? cls : "unknown URCap");
}

/* The nodes from c on, in order, until the end or a node that `stop` names; returns that
 * node (NULL at the end). *rc: 0, or -1 with g->why. */
static const urp_el *emit_list(gen *g, const urp_el *c, int ind, int stop, int *rc_out) {
  *rc_out = 0;
  while (c) {
    if ((stop == STOP_WAYPOINT && is_tag(c, "Waypoint")) || (stop == STOP_BRANCH && if_branch(c))) {
      return c;
    }
    int rc = 0;
    const urp_el *next = c->next;
    const char *tag = c->tag;
    if (strcmp(tag, "Move") == 0) {
      rc = emit_move(g, c, ind);
    } else if (strcmp(tag, "Waypoint") == 0) {
      rc = fail(g, "a Waypoint outside a Move");
    } else if (strcmp(tag, "Wait") == 0) {
      rc = emit_wait(g, c, ind);
    } else if (strcmp(tag, "Set") == 0) {
      rc = emit_set(g, c, ind);
    } else if (strcmp(tag, "Script") == 0) {
      rc = emit_script(g, c, ind);
    } else if (strcmp(tag, "Assignment") == 0) {
      rc = emit_assignment(g, c, ind);
    } else if (strcmp(tag, "Loop") == 0) {
      rc = emit_loop(g, c, ind);
    } else if (strcmp(tag, "If") == 0) {
      if (if_branch(c)) {
        rc = fail(g, "If: %s without an If before it", urp_attr(c, "type"));
      } else {
        next = emit_if(g, c, ind, &rc);
      }
    } else if (strcmp(tag, "Folder") == 0) {
      rc = emit_children(g, c, ind);
    } else if (strcmp(tag, "Comment") == 0) {
      rc = emit_comment(g, c, ind);
    } else if (strcmp(tag, "Popup") == 0) {
      rc = emit_popup(g, c, ind);
    } else if (strcmp(tag, "Halt") == 0) {
      line(g, ind, "halt");
    } else if (strcmp(tag, "Contributed") == 0) {
      rc = emit_contributed(g, c, ind);
    } else if (strcmp(tag, "Placeholder") == 0) {
      // an empty line of the program tree: nothing to run
    } else {
      rc = fail(g, "unsupported program node '%s'", tag);
    }
    if (rc == 0 && g->out.oom) {
      rc = fail(g, "out of memory");
    }
    if (rc != 0) {
      *rc_out = -1;
      return NULL;
    }
    c = next;
  }
  return NULL;
}

/* Every node of n's <children>, in order. */
static int emit_children(gen *g, const urp_el *n, int ind) {
  const urp_el *kids = urp_child(n, "children");
  int rc = 0;
  emit_list(g, kids ? kids->first : NULL, ind, STOP_NONE, &rc);
  return rc;
}


//---- the program ----

static void def_name(const char *name, const urt_urp_options_t *opt, char out[64]) {
  size_t n = 0;
  for (const char *s = name; s && *s && n < 62; s++) {
    out[n++] = (isalnum((unsigned char)*s) || *s == '_') ? *s : '_';
  }
  out[n] = '\0';
  if (n > 0 && isdigit((unsigned char)out[0])) {
    memmove(out + 1, out, n + 1);
    out[0] = 'P';
  }
  if (n == 0) {
    snprintf(out, 64, "%s", opt && is_ident(opt->fallback_name) ? opt->fallback_name : "Program");
  }
}

static int compile_tree(gen *g, const urp_el *root, urt_urp_program_t *p) {
  if (!is_tag(root, "URProgram")) {
    return fail(g, "not a PolyScope program (root element '%s')", root->tag);
  }
  const urp_el *top = urp_child(root, "children");
  const urp_el *main = NULL, *before = NULL;
  for (const urp_el *c = top ? top->first : NULL; c; c = c->next) {
    if (is_tag(c, "MainProgram") && !main) {
      main = c;
    } else if (is_tag(c, "SpecialSequence") && !before &&
               strcmp(urp_attr(c, "type") ? urp_attr(c, "type") : "", "BeforeStart") == 0) {
      before = c;
    } else if (is_tag(c, "InitVariablesNode")) {
      // PolyScope's variable initialisation: the Assignments carry the values
    } else if (is_tag(c, "SpecialSequence")) {
      return fail(g, "unsupported program node 'SpecialSequence' (%s)",
                  urp_attr(c, "type") ? urp_attr(c, "type") : "no type");
    } else {
      return fail(g, "unsupported program node '%s'", c->tag);
    }
  }
  if (!main) {
    return fail(g, "no MainProgram");
  }
  def_name(urp_attr(root, "name"), g->opt, p->name);
  urp_text_printf(&g->out, "def %s():\n", p->name);
  urp_text_puts(&g->out, "  \x01H\n");  // the External Control header, if any
  if (before && emit_children(g, before, 1) != 0) {
    return -1;
  }
  const char *once = urp_attr(main, "runOnlyOnce");
  int loops = once && eq_nocase(once, "false");
  if (loops) {
    line(g, 1, "while (True):");
  }
  if (emit_children(g, main, loops ? 2 : 1) != 0) {
    return -1;
  }
  if (loops) {
    line(g, 1, "end");
  }
  urp_text_puts(&g->out, "end\n");
  if (g->out.oom) {
    return fail(g, "out of memory");
  }
  return 0;
}

int urt_urp_compile(const void *data, size_t len, const urt_urp_options_t *opt,
                    urt_urp_program_t **out, char *why, size_t why_sz) {
  char *xml = NULL;
  size_t xml_len = 0;
  if (why && why_sz) why[0] = '\0';
  if (urp_gunzip(data, len, &xml, &xml_len, why, why_sz) != 0) {
    return -1;
  }
  urp_el *root = urp_parse_xml(xml, xml_len, why, why_sz);
  free(xml);
  if (!root) {
    return -1;
  }
  gen g;
  memset(&g, 0, sizeof g);
  g.opt = opt;
  urt_urp_program_t *p = calloc(1, sizeof *p);
  int rc = p ? compile_tree(&g, root, p) : fail(&g, "out of memory");
  urp_free(root);
  if (rc != 0) {
    if (why && why_sz) snprintf(why, why_sz, "%s", g.why);
    urp_text_free(&g.out);
    free(p);
    return -1;
  }
  p->tmpl = g.out.p;
  p->len = g.out.len;
  p->external = g.external;
  *out = p;
  return 0;
}

int urt_urp_compile_file(const char *path, const urt_urp_options_t *opt, urt_urp_program_t **out,
                         char *why, size_t why_sz) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    snprintf(why, why_sz, "cannot open the file (%s)", strerror(errno));
    return -1;
  }
  struct stat st;
  if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (off_t)URT_URP_MAX_FILE) {
    fclose(f);
    snprintf(why, why_sz, "not a regular file of at most %u bytes", URT_URP_MAX_FILE);
    return -1;
  }
  char *buf = malloc((size_t)st.st_size + 1);
  size_t got = buf ? fread(buf, 1, (size_t)st.st_size, f) : 0;
  fclose(f);
  if (!buf || got != (size_t)st.st_size) {
    free(buf);
    snprintf(why, why_sz, "cannot read the file");
    return -1;
  }
  int rc = urt_urp_compile(buf, got, opt, out, why, why_sz);
  free(buf);
  return rc;
}

void urt_urp_free(urt_urp_program_t *p) {
  if (p) {
    free(p->tmpl);
    free(p);
  }
}

const char *urt_urp_name(const urt_urp_program_t *p) { return p->name; }
int urt_urp_external_nodes(const urt_urp_program_t *p) { return p->external; }

const char *urt_urp_template(const urt_urp_program_t *p, size_t *len) {
  *len = p->len;
  return p->tmpl;
}

//---- rendering ----

int urt_urp_render_template(const char *tmpl, size_t tmpl_len, const char *header,
                            const char *body, char **text, size_t *len) {
  urp_text t = {0};
  size_t i = 0;
  while (i < tmpl_len) {
    size_t j = i;
    while (j < tmpl_len && tmpl[j] != '\n') j++;
    size_t k = i;
    while (k < j && tmpl[k] == ' ') k++;
    if (j - k == 2 && tmpl[k] == URP_SLOT) {
      // a slot line: the fetched text, indented to the slot's level
      const char *fill = tmpl[k + 1] == 'H' ? header : body;
      if (fill) {
        urp_text_lines(&t, fill, strlen(fill), (int)((k - i) / 2));
      }
    } else {
      urp_text_put(&t, tmpl + i, j - i);
      urp_text_put(&t, "\n", 1);
    }
    i = j + 1;
  }
  if (t.oom || !t.p) {
    urp_text_free(&t);
    return -1;
  }
  *text = t.p;
  *len = t.len;
  return 0;
}

int urt_urp_render(const urt_urp_program_t *p, const char *header, const char *body, char **text,
                   size_t *len) {
  return urt_urp_render_template(p->tmpl, p->len, header, body, text, len);
}
