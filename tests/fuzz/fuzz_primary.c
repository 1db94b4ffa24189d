/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_primary.c — libFuzzer target for net/codec/primary.c, the 30001/30002 encoders.
 *
 * The primary codec has no parser of client bytes: what a hostile or broken world controls is
 * the state it encodes (any snapshot, NaN and out-of-range modes included), the texts of robot
 * messages (a script's textmsg, popup and exception texts of any length) and the room left in a
 * client's buffer. So the input is: byte 0 picks the version and the encoder, bytes 1–2 the
 * capacity, then a snapshot's and a robot description's raw bytes, then text. Every encoder is
 * run into a buffer of exactly that capacity (ASan catches a write past it) and judged:
 *   - it returns the size written, or URT_ENOSPC / URT_EINVAL, never more than the capacity;
 *   - a message starts with its own big-endian int32 size and its type (16 or 20);
 *   - ROBOT_STATE is a chain of sub-packages whose sizes are the version's documented ones and
 *     add up to the message, which is at most URT_PRIMARY_MAX_MESSAGE bytes;
 *   - a robot message ends with its text as given (TEXT, KEY, RUNTIME_EXCEPTION, ERROR_CODE);
 *   - encoding is a pure function: the same input into a roomier buffer gives the same bytes,
 *     and a capacity below the size is always URT_ENOSPC. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "urt/errors.h"
#include "urt/net/primary.h"
#include "urt/net/version.h"

#define CHECK(c)        \
  do {                  \
    if (!(c)) {         \
      __builtin_trap(); \
    }                   \
  } while (0)

#define ROOMY 65536

static uint32_t be32(const uint8_t *p) {
  return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

typedef struct input {
  urt_version_t v;
  int encoder;
  size_t cap;
  urt_snapshot_t s;
  urt_primary_robot_info_t info;
  char text[4096];
  char title[512];
  int32_t a, b, c;
} input_t;

// Run the chosen encoder into buf[cap].
static int encode(const input_t *in, uint8_t *buf, size_t cap) {
  uint64_t ts = (uint64_t)(uint32_t)in->a * 2000u;
  switch (in->encoder) {
    case 0: return urt_primary_encode_robot_state(&in->v, &in->info, &in->s, buf, cap);
    case 1: return urt_primary_encode_version(&in->v, ts, buf, cap);
    case 2: return urt_primary_encode_text(ts, in->b, in->text, buf, cap);
    case 3: return urt_primary_encode_key(ts, in->b, in->c, in->a, in->title, in->text, buf, cap);
    case 4:
      return urt_primary_encode_popup(ts, in->b, (uint32_t)in->c, (uint32_t)in->a, in->b & 1,
                                      in->b & 2, in->b & 4, in->title, in->text, buf, cap);
    case 5:
      return urt_primary_encode_runtime_exception(ts, in->b, (uint32_t)in->c, (uint32_t)in->a,
                                                  in->text, buf, cap);
    case 6:
      return urt_primary_encode_error_code(ts, in->b, in->c, in->a, in->b % 6, (uint32_t)in->c,
                                           (uint32_t)in->a, in->text, buf, cap);
    default:
      return urt_primary_encode_safety_mode(ts, in->b, in->c, in->a, in->b % 12, (uint32_t)in->c,
                                            (uint32_t)in->a, buf, cap);
  }
}

// Take n bytes (zeros once the input is used up).
static void take(const uint8_t **p, size_t *left, void *out, size_t n) {
  size_t k = n < *left ? n : *left;
  memset(out, 0, n);
  memcpy(out, *p, k);
  *p += k;
  *left -= k;
}

static void check_robot_state(const urt_version_t *v, const uint8_t *m, int n) {
  CHECK(m[4] == URT_PRIMARY_ROBOT_STATE);
  CHECK(n <= URT_PRIMARY_MAX_MESSAGE);
  int off = 5;
  while (off < n) {
    CHECK(n - off >= 5);
    int size = (int)be32(m + off);
    int type = m[off + 4];
    CHECK(type < URT_PRIMARY_NSUB);
    CHECK(size == urt_primary_subpackage_size(v, type));
    CHECK(size >= 5 && size <= n - off);
    off += size;
  }
  CHECK(off == n);
}

static void check_ends_with(const uint8_t *m, int n, const char *text) {
  size_t len = strlen(text);
  CHECK((size_t)n >= len + 5);
  CHECK(memcmp(m + n - len, text, len) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static input_t in;
  static uint8_t roomy[ROOMY];
  if (size < 3) {
    return 0;
  }
  memset(&in, 0, sizeof in);
  CHECK(urt_version_parse(data[0] & 1 ? "5.19" : "3.15", &in.v) == URT_OK);
  in.encoder = (data[0] >> 1) % 8;
  in.cap = ((size_t)data[1] << 8 | data[2]) % 4096;
  const uint8_t *p = data + 3;
  size_t left = size - 3;
  take(&p, &left, &in.s, sizeof in.s);
  take(&p, &left, &in.info, sizeof in.info);
  take(&p, &left, &in.a, sizeof in.a);
  take(&p, &left, &in.b, sizeof in.b);
  take(&p, &left, &in.c, sizeof in.c);
  // the title: up to the first NUL (or 300 bytes: longer than the 255 the wire can hold)
  size_t tl = 0;
  while (tl < 300 && tl < left && p[tl]) {
    tl++;
  }
  memcpy(in.title, p, tl);
  p += tl < left ? tl + 1 : tl;
  left -= tl < left ? tl + 1 : tl;
  size_t xl = left < sizeof in.text - 1 ? left : sizeof in.text - 1;
  memcpy(in.text, p, xl);  // a NUL inside ends the text, as a C string does

  uint8_t *buf = malloc(in.cap ? in.cap : 1);  // exactly cap bytes: ASan sees a write past it
  int n = encode(&in, buf, in.cap);
  int full = encode(&in, roomy, sizeof roomy);
  CHECK(full == URT_EINVAL || full > 0);
  CHECK(n == full || n == URT_ENOSPC);
  CHECK(n <= (int)in.cap);
  if (full > 0) {
    CHECK((size_t)full < sizeof roomy);
    CHECK(be32(roomy) == (uint32_t)full);
    CHECK((n == URT_ENOSPC) == ((size_t)full > in.cap));
    if (n > 0) {
      CHECK(memcmp(buf, roomy, (size_t)n) == 0);  // pure: the same bytes whatever the room
    }
    if (in.encoder == 0) {
      check_robot_state(&in.v, roomy, full);
    } else {
      CHECK(roomy[4] == URT_PRIMARY_ROBOT_MESSAGE);
      if (in.encoder == 2 || in.encoder == 3 || in.encoder == 5 || in.encoder == 6) {
        check_ends_with(roomy, full, in.text);
      }
    }
  } else {
    CHECK(n == URT_EINVAL || n == URT_ENOSPC);
    CHECK(in.encoder == 3 || in.encoder == 4);  // only the titled messages refuse input
    CHECK(strlen(in.title) > 255);
  }
  free(buf);
  return 0;
}
