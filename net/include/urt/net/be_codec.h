/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/be_codec.h — a bounded big-endian writer. Every wire encoder writes
 * through it: a put that does not fit sets w->err and writes nothing (then or later), so an
 * encoder can write unconditionally and check the flag once at the end.
 * Context: any (pure, no allocation).
 */
#ifndef URT_NET_BE_CODEC_H
#define URT_NET_BE_CODEC_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_wbuf {
  uint8_t *start; /* first byte of the buffer          */
  uint8_t *p;     /* next byte to write                */
  uint8_t *end;   /* one past the last writable byte   */
  int err;        /* set once a put did not fit        */
} urt_wbuf_t;

/* A writer over buf[0..cap). Nullable: buf (only with cap 0). */
static inline urt_wbuf_t urt_wbuf_make(uint8_t *buf, size_t cap) {
  urt_wbuf_t w = {buf, buf, buf ? buf + cap : buf, 0};
  return w;
}

/* Bytes written so far. */
static inline size_t urt_wbuf_len(const urt_wbuf_t *w) { return (size_t)(w->p - w->start); }

/* Reserve n bytes; NULL (and err set) if they do not fit. */
static inline uint8_t *urt_wbuf_take(urt_wbuf_t *w, size_t n) {
  if (w->err || (size_t)(w->end - w->p) < n) {
    w->err = 1;
    return NULL;
  }
  uint8_t *q = w->p;
  w->p += n;
  return q;
}

static inline void urt_be_store_u32(uint8_t *q, uint32_t x) {
  q[0] = (uint8_t)(x >> 24);
  q[1] = (uint8_t)(x >> 16);
  q[2] = (uint8_t)(x >> 8);
  q[3] = (uint8_t)x;
}

static inline void urt_be_store_u64(uint8_t *q, uint64_t x) {
  urt_be_store_u32(q, (uint32_t)(x >> 32));
  urt_be_store_u32(q + 4, (uint32_t)x);
}

static inline void urt_be_put_u8(urt_wbuf_t *w, uint8_t x) {
  uint8_t *q = urt_wbuf_take(w, 1);
  if (q) {
    q[0] = x;
  }
}

static inline void urt_be_put_i8(urt_wbuf_t *w, int8_t x) { urt_be_put_u8(w, (uint8_t)x); }

static inline void urt_be_put_bool(urt_wbuf_t *w, int b) { urt_be_put_u8(w, b ? 1 : 0); }

static inline void urt_be_put_u16(urt_wbuf_t *w, uint16_t x) {
  uint8_t *q = urt_wbuf_take(w, 2);
  if (q) {
    q[0] = (uint8_t)(x >> 8);
    q[1] = (uint8_t)x;
  }
}

static inline void urt_be_put_u32(urt_wbuf_t *w, uint32_t x) {
  uint8_t *q = urt_wbuf_take(w, 4);
  if (q) {
    urt_be_store_u32(q, x);
  }
}

static inline void urt_be_put_i32(urt_wbuf_t *w, int32_t x) { urt_be_put_u32(w, (uint32_t)x); }

static inline void urt_be_put_u64(urt_wbuf_t *w, uint64_t x) {
  uint8_t *q = urt_wbuf_take(w, 8);
  if (q) {
    urt_be_store_u64(q, x);
  }
}

static inline void urt_be_put_f32(urt_wbuf_t *w, float x) {
  uint32_t u;
  memcpy(&u, &x, sizeof u);
  urt_be_put_u32(w, u);
}

static inline void urt_be_put_f64(urt_wbuf_t *w, double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  urt_be_put_u64(w, u);
}

/* n doubles in a row. */
static inline void urt_be_put_f64v(urt_wbuf_t *w, const double *x, int n) {
  for (int i = 0; i < n; i++) {
    urt_be_put_f64(w, x[i]);
  }
}

static inline void urt_be_put_bytes(urt_wbuf_t *w, const void *src, size_t n) {
  uint8_t *q = urt_wbuf_take(w, n);
  if (q && n) {
    memcpy(q, src, n);
  }
}

static inline void urt_be_put_zeros(urt_wbuf_t *w, size_t n) {
  uint8_t *q = urt_wbuf_take(w, n);
  if (q && n) {
    memset(q, 0, n);
  }
}

#ifdef __cplusplus
}
#endif
#endif
