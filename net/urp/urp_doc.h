/* SPDX-License-Identifier: Apache-2.0
 * net/urp/urp_doc.h — a .urp file as a small element tree: gunzip (zlib) and parse the XML
 * (expat) into elements with their attributes and text, all bounded (size, depth, count), and
 * resolve PolyScope's XStream-style `reference="../../Assignment[2]/variable"` attributes.
 * Private to net/urp.
 */
#ifndef URT_NET_URP_DOC_H
#define URT_NET_URP_DOC_H

#include <stddef.h>

#define URP_MAX_XML (16u << 20)  /* largest decompressed program [bytes]          */
#define URP_MAX_DEPTH 200        /* deepest element nesting                        */
#define URP_MAX_ELEMENTS 200000  /* elements in one program                        */

typedef struct urp_el urp_el;
struct urp_el {
  char *tag;
  char **attr;            /* name, value, name, value, …, then NULL */
  char *text;             /* character data directly inside, concatenated ("" if none) */
  size_t text_len;
  urp_el *parent, *first, *last, *next;
};

/* Decompress a gzip stream (the .urp file) into a NUL-terminated buffer. Returns 0 and
 * xml and xml_len (free xml with free()), or -1 with why filled. */
int urp_gunzip(const void *data, size_t len, char **xml, size_t *xml_len, char *why, size_t why_sz);

/* Parse XML into a tree. A DOCTYPE (and so any entity declaration) is refused. Returns the
 * root element or NULL with why filled. */
urp_el *urp_parse_xml(const char *xml, size_t len, char *why, size_t why_sz);

void urp_free(urp_el *root);

/* The attribute's value, or NULL. */
const char *urp_attr(const urp_el *e, const char *name);

/* The first child element with this tag, or NULL. */
urp_el *urp_child(const urp_el *e, const char *tag);

/* Follow e's `reference` attribute, if any, to the element it names (relative path of
 * "..", "Tag" and "Tag[n]" steps, n from 1). Returns e itself when it has no reference, NULL
 * when the reference does not resolve. */
const urp_el *urp_deref(const urp_el *e);

#endif
