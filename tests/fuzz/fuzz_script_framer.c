/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_script_framer.c — libFuzzer target for net/codec/script_framer.c.
 *
 * Input: byte 0 picks the unit limit, byte 1 the chunking, the rest is what a client sends.
 * The bytes are framed twice — in one feed and in chunks of varying size — and must give the
 * same units. Every unit must respect the documented invariants (bounded, NUL-terminated,
 * no CR/NUL inside, ERROR ⇔ error text, name inside the text, buffer within the limit). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "urt/net/script_framer.h"

#define CHECK(c)     \
  do {               \
    if (!(c)) {      \
      __builtin_trap(); \
    }                \
  } while (0)

typedef struct digest {
  uint64_t h;
  size_t units;
  size_t max_unit;
} digest_t;

static uint64_t mix(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) {
    h = (h ^ b[i]) * 1099511628211ull;
  }
  return h;
}

static void on_unit(void *user, const urt_script_unit_t *u) {
  digest_t *d = user;

  // the documented invariants of one unit
  CHECK(u->kind >= URT_SCRIPT_UNIT_COMMAND && u->kind <= URT_SCRIPT_UNIT_ERROR);
  CHECK(u->text != NULL);
  CHECK(u->len <= d->max_unit);
  CHECK(u->text[u->len] == '\0');
  CHECK(memchr(u->text, '\0', u->len) == NULL);
  CHECK(memchr(u->text, '\r', u->len) == NULL);
  CHECK((u->kind == URT_SCRIPT_UNIT_ERROR) == (u->error != NULL));
  CHECK((u->kind == URT_SCRIPT_UNIT_ERROR) == (u->error_code != URT_SCRIPT_ERR_NONE));
  if (u->kind == URT_SCRIPT_UNIT_ERROR) {
    CHECK(u->len <= URT_SCRIPT_ERROR_EXCERPT);
  } else {
    CHECK(u->len > 0);
    CHECK(u->text[u->len - 1] != '\n');
  }
  if (u->kind == URT_SCRIPT_UNIT_PROGRAM || u->kind == URT_SCRIPT_UNIT_SECONDARY) {
    CHECK(u->name >= u->text && u->name + u->name_len <= u->text + u->len);
  } else {
    CHECK(u->name_len == 0);
  }
  if (u->kind == URT_SCRIPT_UNIT_COMMAND) {
    CHECK(urt_script_command_of(u->text, u->len) == (int)u->command);
  }
  CHECK(u->line >= 1);

  // fold it into the digest
  int v[4] = {(int)u->kind, (int)u->command, (int)u->error_code, (int)u->name_len};
  d->h = mix(d->h, v, sizeof v);
  d->h = mix(d->h, &u->line, sizeof u->line);
  d->h = mix(d->h, &u->len, sizeof u->len);
  d->h = mix(d->h, u->text, u->len);
  d->units++;
}

/* Frame data in chunks taken from the chunk pattern (0 = all at once). */
static digest_t run(const uint8_t *data, size_t n, size_t max_unit, uint8_t pattern) {
  urt_script_framer_t f;
  urt_script_framer_init_max(&f, max_unit);
  digest_t d = {1469598103934665603ull, 0, f.max_unit};
  size_t counted = 0;
  size_t off = 0;
  unsigned step = 0;
  while (off < n) {
    size_t k = pattern ? 1 + ((pattern * (step + 7u)) % 97u) : n;
    if (k > n - off) {
      k = n - off;
    }
    int got = urt_script_framer_feed(&f, data + off, k, on_unit, &d);
    CHECK(got >= 0);
    counted += (size_t)got;
    CHECK(f.cap <= f.max_unit + 1);
    off += k;
    step++;
  }
  counted += (size_t)urt_script_framer_finish(&f, on_unit, &d);
  CHECK(counted == d.units);
  CHECK(f.len == 0 && f.depth == 0);
  urt_script_framer_free(&f);
  return d;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 2) {
    return 0;
  }
  size_t max_unit = 16 + (size_t)data[0] * 16;  /* 16 … 4096 bytes */
  uint8_t pattern = data[1] ? data[1] : 1;
  data += 2;
  size -= 2;

  digest_t whole = run(data, size, max_unit, 0);
  digest_t chunked = run(data, size, max_unit, pattern);
  digest_t bytewise = run(data, size, max_unit, 97);  /* one byte at a time */
  CHECK(whole.units == chunked.units && whole.h == chunked.h);
  CHECK(whole.units == bytewise.units && whole.h == bytewise.h);
  return 0;
}
