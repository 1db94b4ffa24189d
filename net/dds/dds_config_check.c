/* SPDX-License-Identifier: Apache-2.0
 * net/dds/dds_config_check.c — a small XML well-formedness check (see dds_config_check.h):
 * a stack of open element names; comments, processing instructions and CDATA skipped. */
#include "urt/net/dds_config_check.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "urt/errors.h"

#define MAX_DEPTH 32
#define MAX_NAME 64

static int line_of(const char *xml, const char *p) {
  int line = 1;
  for (const char *c = xml; c < p; c++) {
    line += *c == '\n';
  }
  return line;
}

static int bad(char *err, size_t err_sz, const char *xml, const char *p, const char *why) {
  if (err != NULL && err_sz > 0) {
    snprintf(err, err_sz, "line %d: %s", line_of(xml, p), why);
  }
  return URT_ECONFIG;
}

static int name_char(char c) {
  return isalnum((unsigned char)c) || c == '_' || c == '-' || c == '.' || c == ':';
}

int urt_dds_config_check(const char *xml, char *err, size_t err_sz) {
  char stack[MAX_DEPTH][MAX_NAME];
  int depth = 0, roots = 0;
  const char *p = xml;
  while (*p != '\0') {
    if (*p != '<') {
      if (depth == 0 && !isspace((unsigned char)*p)) {
        return bad(err, err_sz, xml, p, "text outside the root element");
      }
      p++;
      continue;
    }
    const char *skip_end = NULL;
    if (strncmp(p, "<!--", 4) == 0) {
      skip_end = "-->";
    } else if (strncmp(p, "<?", 2) == 0) {
      skip_end = "?>";
    } else if (strncmp(p, "<![CDATA[", 9) == 0) {
      skip_end = "]]>";
    } else if (strncmp(p, "<!", 2) == 0) {
      skip_end = ">";
    }
    if (skip_end != NULL) {
      const char *e = strstr(p + 2, skip_end);
      if (e == NULL) {
        return bad(err, err_sz, xml, p, "unterminated comment or declaration");
      }
      p = e + strlen(skip_end);
      continue;
    }
    int closing = p[1] == '/';
    const char *n = p + 1 + closing;
    size_t len = 0;
    while (name_char(n[len])) {
      len++;
    }
    if (len == 0 || len >= MAX_NAME) {
      return bad(err, err_sz, xml, p, "bad element name");
    }
    // attributes (name="value" or name='value') up to > or />
    const char *q = n + len;
    int empty = 0;
    for (;;) {
      while (isspace((unsigned char)*q)) {
        q++;
      }
      if (*q == '>') {
        break;
      }
      if (!closing && q[0] == '/' && q[1] == '>') {
        empty = 1;
        q++;
        break;
      }
      if (closing || !name_char(*q)) {
        return bad(err, err_sz, xml, q, *q ? "malformed tag" : "tag not closed");
      }
      while (name_char(*q)) {
        q++;
      }
      while (isspace((unsigned char)*q)) {
        q++;
      }
      if (*q != '=') {
        return bad(err, err_sz, xml, q, "attribute without a value");
      }
      q++;
      while (isspace((unsigned char)*q)) {
        q++;
      }
      char quote = *q;
      if (quote != '"' && quote != '\'') {
        return bad(err, err_sz, xml, q, "attribute value not quoted");
      }
      const char *e = strchr(q + 1, quote);
      if (e == NULL) {
        return bad(err, err_sz, xml, q, "attribute value not closed");
      }
      q = e + 1;
    }
    if (closing) {
      if (depth == 0 || strlen(stack[depth - 1]) != len ||
          strncmp(stack[depth - 1], n, len) != 0) {
        return bad(err, err_sz, xml, p, "closing tag does not match the open element");
      }
      depth--;
    } else {
      if (depth == 0) {
        if (roots++ > 0) {
          return bad(err, err_sz, xml, p, "more than one root element");
        }
        if (len != 10 || strncmp(n, "CycloneDDS", 10) != 0) {
          return bad(err, err_sz, xml, p, "the root element is not <CycloneDDS>");
        }
      }
      if (!empty) {
        if (depth == MAX_DEPTH) {
          return bad(err, err_sz, xml, p, "elements nested too deep");
        }
        memcpy(stack[depth], n, len);
        stack[depth][len] = '\0';
        depth++;
      }
    }
    p = q + 1;
  }
  if (depth > 0) {
    char why[MAX_NAME + 40];
    snprintf(why, sizeof why, "<%s> is never closed (file cut short?)", stack[depth - 1]);
    return bad(err, err_sz, xml, p, why);
  }
  if (roots == 0) {
    return bad(err, err_sz, xml, p, "no <CycloneDDS> element");
  }
  return 0;
}
