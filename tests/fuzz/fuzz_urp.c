/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_urp.c — arbitrary bytes through the .urp loader (net/urp): gunzip, the XML
 * parser, the node compiler and the template render, and the URCap's header/body split.
 *
 * Input layout: byte 0 even: the rest is the file as it is (mostly gzip errors); odd: the rest
 * is XML, gzip'd here first, so that the parser and the compiler see structured input.
 * Invariants: compile returns 0 or -1 with a reason; a compiled program renders, its text has
 * no slot byte (0x01) left and ends with "end\n"; no crash, leak or out-of-bounds access.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "urt/net/urp.h"

static unsigned char *gzip_bytes(const uint8_t *data, size_t n, size_t *len) {
  z_stream z;
  memset(&z, 0, sizeof z);
  if (deflateInit2(&z, 1, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    abort();
  }
  size_t cap = deflateBound(&z, n) + 64;
  unsigned char *out = malloc(cap);
  z.next_in = (unsigned char *)data;
  z.avail_in = (unsigned)n;
  z.next_out = out;
  z.avail_out = (unsigned)cap;
  if (deflate(&z, Z_FINISH) != Z_STREAM_END) {
    abort();
  }
  *len = cap - z.avail_out;
  deflateEnd(&z);
  return out;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1 || size > (1u << 20)) {
    return 0;
  }
  size_t len = size - 1;
  unsigned char *gz = NULL;
  const void *file = data + 1;
  if (data[0] & 1) {
    gz = gzip_bytes(data + 1, len, &len);
    file = gz;
  }

  urt_urp_program_t *p = NULL;
  char why[256];
  why[0] = 'x';
  why[sizeof why - 1] = 'x';
  if (urt_urp_compile(file, len, NULL, &p, why, sizeof why) == 0) {
    char *text = NULL;
    size_t tl = 0;
    if (urt_urp_render(p, "# HEADER_BEGIN\nx = 1\n# HEADER_END\n", "y = 2\n", &text, &tl) != 0 ||
        memchr(text, '\x01', tl) || tl < 4 || memcmp(text + tl - 4, "end\n", 4) != 0 ||
        strlen(text) != tl) {
      abort();
    }
    free(text);
    urt_urp_free(p);
  } else if (!memchr(why, '\0', sizeof why) || why[0] == '\0') {
    abort();  // a failure always says why, NUL-terminated
  }
  free(gz);

  // the URCap's split of fetched text: header + body hold every line of a marked text
  char *header = NULL, *body = NULL;
  if (urt_urcap_split((const char *)data + 1, size - 1, &header, &body) == 0) {
    if (strlen(header) + strlen(body) > 2 * size + 2) {
      abort();
    }
    free(header);
    free(body);
  }
  return 0;
}
