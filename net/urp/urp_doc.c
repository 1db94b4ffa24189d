/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urp_doc.c — gunzip and XML parse of a .urp file into an element tree (urp_doc.h).
 *
 * Everything is bounded because the bytes come from a file a client names: the decompressed
 * size (a gzip bomb stops at URP_MAX_XML), the nesting depth and the element count. A DOCTYPE
 * is refused outright: PolyScope never writes one, and without it no entity can expand.
 */
#include "urp_doc.h"

#include <expat.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static void say(char *why, size_t why_sz, const char *fmt, ...) {
  if (!why || why_sz == 0) {
    return;
  }
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, why_sz, fmt, ap);
  va_end(ap);
}

//---- gzip ----

int urp_gunzip(const void *data, size_t len, char **xml, size_t *xml_len, char *why,
               size_t why_sz) {
  const unsigned char *in = data;
  if (len < 18 || in[0] != 0x1f || in[1] != 0x8b) {
    say(why, why_sz, "not a gzip file");
    return -1;
  }
  if (len > UINT_MAX) {
    say(why, why_sz, "file too large");
    return -1;
  }
  z_stream z;
  memset(&z, 0, sizeof z);
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) {  // 16: gzip wrapper only
    say(why, why_sz, "zlib could not start");
    return -1;
  }
  size_t cap = 64 * 1024, n = 0;
  char *out = malloc(cap + 1);
  if (!out) {
    inflateEnd(&z);
    say(why, why_sz, "out of memory");
    return -1;
  }
  z.next_in = (unsigned char *)in;
  z.avail_in = (unsigned)len;
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    if (n == cap) {
      if (cap >= URP_MAX_XML) {
        inflateEnd(&z);
        free(out);
        say(why, why_sz, "program larger than %u bytes when decompressed", URP_MAX_XML);
        return -1;
      }
      size_t ncap = cap * 2 > URP_MAX_XML ? URP_MAX_XML : cap * 2;
      char *grown = realloc(out, ncap + 1);
      if (!grown) {
        inflateEnd(&z);
        free(out);
        say(why, why_sz, "out of memory");
        return -1;
      }
      out = grown;
      cap = ncap;
    }
    z.next_out = (unsigned char *)out + n;
    z.avail_out = (unsigned)(cap - n);
    rc = inflate(&z, Z_NO_FLUSH);
    n = cap - z.avail_out;
    if (rc == Z_STREAM_END) {
      break;
    }
    if (rc != Z_OK || (z.avail_in == 0 && z.avail_out != 0)) {
      // a corrupt stream, or one that ends before its end marker
      inflateEnd(&z);
      free(out);
      say(why, why_sz, "bad gzip data (%s)", rc == Z_OK || rc == Z_BUF_ERROR ? "truncated"
                                                : z.msg ? z.msg : "corrupt");
      return -1;
    }
  }
  inflateEnd(&z);
  out[n] = '\0';
  *xml = out;
  *xml_len = n;
  return 0;
}

//---- XML ----

typedef struct builder {
  XML_Parser p;
  urp_el *root, *cur;
  int depth;
  long count;
  char why[160];
} builder;

static void fail(builder *b, const char *fmt, ...) {
  if (!b->why[0]) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(b->why, sizeof b->why, fmt, ap);
    va_end(ap);
  }
  XML_StopParser(b->p, XML_FALSE);
}

static void XMLCALL on_start(void *ud, const XML_Char *tag, const XML_Char **attrs) {
  builder *b = ud;
  if (b->why[0]) {
    return;
  }
  if (++b->depth > URP_MAX_DEPTH) {
    fail(b, "XML nested deeper than %d elements", URP_MAX_DEPTH);
    return;
  }
  if (++b->count > URP_MAX_ELEMENTS) {
    fail(b, "more than %d XML elements", URP_MAX_ELEMENTS);
    return;
  }
  urp_el *e = calloc(1, sizeof *e);
  int na = 0;
  while (attrs[na]) {
    na++;
  }
  if (e) {
    e->tag = strdup(tag);
    e->attr = calloc((size_t)na + 1, sizeof *e->attr);
    e->text = calloc(1, 1);
  }
  if (!e || !e->tag || !e->attr || !e->text) {
    if (e) {
      free(e->tag);
      free(e->attr);
      free(e->text);
      free(e);
    }
    fail(b, "out of memory");
    return;
  }
  // link first, so that a failure below still frees e with the tree
  e->parent = b->cur;
  if (b->cur) {
    if (b->cur->last) {
      b->cur->last->next = e;
    } else {
      b->cur->first = e;
    }
    b->cur->last = e;
  } else {
    b->root = e;
  }
  b->cur = e;
  for (int k = 0; k < na; k++) {
    e->attr[k] = strdup(attrs[k]);
    if (!e->attr[k]) {
      fail(b, "out of memory");
      return;
    }
  }
}

static void XMLCALL on_end(void *ud, const XML_Char *tag) {
  (void)tag;
  builder *b = ud;
  if (b->why[0]) {
    return;
  }
  b->depth--;
  b->cur = b->cur ? b->cur->parent : NULL;
}

static void XMLCALL on_text(void *ud, const XML_Char *s, int len) {
  builder *b = ud;
  if (b->why[0] || !b->cur || len <= 0) {
    return;
  }
  urp_el *e = b->cur;
  char *grown = realloc(e->text, e->text_len + (size_t)len + 1);
  if (!grown) {
    fail(b, "out of memory");
    return;
  }
  memcpy(grown + e->text_len, s, (size_t)len);
  e->text_len += (size_t)len;
  grown[e->text_len] = '\0';
  e->text = grown;
}

static void XMLCALL on_doctype(void *ud, const XML_Char *name, const XML_Char *sysid,
                               const XML_Char *pubid, int has_internal_subset) {
  (void)name, (void)sysid, (void)pubid, (void)has_internal_subset;
  fail(ud, "a DOCTYPE is not allowed in a program");
}

static void XMLCALL on_entity(void *ud, const XML_Char *name, int is_param, const XML_Char *value,
                              int value_len, const XML_Char *base, const XML_Char *sysid,
                              const XML_Char *pubid, const XML_Char *notation) {
  (void)name, (void)is_param, (void)value, (void)value_len, (void)base, (void)sysid;
  (void)pubid, (void)notation;
  fail(ud, "entity declarations are not allowed in a program");
}

urp_el *urp_parse_xml(const char *xml, size_t len, char *why, size_t why_sz) {
  if (len > URP_MAX_XML) {
    say(why, why_sz, "program larger than %u bytes", URP_MAX_XML);
    return NULL;
  }
  builder b;
  memset(&b, 0, sizeof b);
  b.p = XML_ParserCreate("UTF-8");
  if (!b.p) {
    say(why, why_sz, "out of memory");
    return NULL;
  }
  XML_SetUserData(b.p, &b);
  XML_SetElementHandler(b.p, on_start, on_end);
  XML_SetCharacterDataHandler(b.p, on_text);
  XML_SetStartDoctypeDeclHandler(b.p, on_doctype);
  XML_SetEntityDeclHandler(b.p, on_entity);
  enum XML_Status st = XML_Parse(b.p, xml, (int)len, XML_TRUE);
  if (st != XML_STATUS_OK && !b.why[0]) {
    snprintf(b.why, sizeof b.why, "bad XML at line %lu: %s",
             (unsigned long)XML_GetCurrentLineNumber(b.p), XML_ErrorString(XML_GetErrorCode(b.p)));
  }
  XML_ParserFree(b.p);
  if (b.why[0] || !b.root) {
    say(why, why_sz, "%s", b.why[0] ? b.why : "no XML element");
    urp_free(b.root);
    return NULL;
  }
  return b.root;
}

void urp_free(urp_el *e) {
  while (e) {
    urp_el *next = e->next;
    urp_free(e->first);  // recursion bounded by URP_MAX_DEPTH
    for (char **a = e->attr; a && *a; a++) {
      free(*a);
    }
    free(e->attr);
    free(e->tag);
    free(e->text);
    free(e);
    e = next;
  }
}

//---- queries ----

const char *urp_attr(const urp_el *e, const char *name) {
  if (!e || !e->attr) {
    return NULL;
  }
  for (char **a = e->attr; a[0] && a[1]; a += 2) {
    if (strcmp(a[0], name) == 0) {
      return a[1];
    }
  }
  return NULL;
}

urp_el *urp_child(const urp_el *e, const char *tag) {
  for (urp_el *c = e ? e->first : NULL; c; c = c->next) {
    if (strcmp(c->tag, tag) == 0) {
      return c;
    }
  }
  return NULL;
}

const urp_el *urp_deref(const urp_el *e) {
  const char *ref = urp_attr(e, "reference");
  if (!ref) {
    return e;
  }
  const urp_el *at = e;
  const char *p = ref;
  for (int steps = 0; *p; steps++) {
    if (steps > 4 * URP_MAX_DEPTH) {
      return NULL;
    }
    const char *slash = strchr(p, '/');
    size_t n = slash ? (size_t)(slash - p) : strlen(p);
    if (n == 2 && p[0] == '.' && p[1] == '.') {
      at = at->parent;
    } else if (n == 1 && p[0] == '.') {
      // stays
    } else if (n > 0) {
      // "Tag" or "Tag[k]": the k-th child element with that tag (1-based)
      const char *br = memchr(p, '[', n);
      size_t tag_len = br ? (size_t)(br - p) : n;
      long k = 1;
      if (br) {
        char *end = NULL;
        k = strtol(br + 1, &end, 10);
        if (end != p + n - 1 || *end != ']' || k < 1) {
          return NULL;
        }
      }
      const urp_el *found = NULL;
      for (const urp_el *c = at->first; c; c = c->next) {
        if (strlen(c->tag) == tag_len && memcmp(c->tag, p, tag_len) == 0 && --k == 0) {
          found = c;
          break;
        }
      }
      at = found;
    }
    if (!at) {
      return NULL;
    }
    if (!slash) {
      break;
    }
    p = slash + 1;
  }
  // a reference to an element that itself refers on is followed once more, no further
  return urp_attr(at, "reference") ? NULL : at;
}
