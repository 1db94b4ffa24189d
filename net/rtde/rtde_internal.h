/* SPDX-License-Identifier: Apache-2.0
 * net/rtde/rtde_internal.h — private to net/rtde: the output kinds and input variable ids
 * generated from the .def tables, and a bounds-checked big-endian writer/reader.
 */
#ifndef URT_NET_RTDE_INTERNAL_H
#define URT_NET_RTDE_INTERNAL_H

#include <stdint.h>
#include <string.h>

#include "urt/net/rtde.h"

/* output kinds: the fixed names, then the register families */
enum {
#define X(name, type, cb3, e, value) URT__RTDE_OUT_##name,
#include "rtde_outputs.def"
#undef X
  URT__RTDE_OUT_NFIXED,
  URT__RTDE_OUT_INT_REG = URT__RTDE_OUT_NFIXED,
  URT__RTDE_OUT_DOUBLE_REG,
  URT__RTDE_OUT_BIT_REG,
  URT__RTDE_OUT_BITS_LO,
  URT__RTDE_OUT_BITS_HI,
  URT__RTDE_IN_INT_REG,        /* read-back of the inputs */
  URT__RTDE_IN_DOUBLE_REG,
  URT__RTDE_IN_BIT_REG,
  URT__RTDE_IN_BITS_LO,
  URT__RTDE_IN_BITS_HI,
  URT__RTDE_OUT_NKINDS
};

/* input variable ids: the fixed names, then one id per register (the unit of ownership) */
enum {
#define X(name, type, cb3, e) URT__RTDE_IN_##name,
#include "rtde_inputs.def"
#undef X
  URT__RTDE_IN_NFIXED,
  URT__RTDE_IN_INT_BASE = URT__RTDE_IN_NFIXED,
  URT__RTDE_IN_DOUBLE_BASE = URT__RTDE_IN_INT_BASE + URT_RTDE_NREG,
  URT__RTDE_IN_BITS_LO_ID = URT__RTDE_IN_DOUBLE_BASE + URT_RTDE_NREG,
  URT__RTDE_IN_BITS_HI_ID,
  URT__RTDE_IN_BIT_BASE,       /* input_bit_register_64 … 127 */
  URT__RTDE_IN_COUNT = URT__RTDE_IN_BIT_BASE + 64
};

//---- big-endian writer that refuses to run past its end ----

typedef struct urt__rtde_w {
  uint8_t *p, *end;
  int err;
} urt__rtde_w_t;

static inline void be_put_u8(urt__rtde_w_t *w, uint8_t x) {
  if (w->end - w->p < 1) {
    w->err = 1;
    return;
  }
  *w->p++ = x;
}
static inline void be_put_u16(urt__rtde_w_t *w, uint16_t x) {
  if (w->end - w->p < 2) {
    w->err = 1;
    return;
  }
  w->p[0] = (uint8_t)(x >> 8);
  w->p[1] = (uint8_t)x;
  w->p += 2;
}
static inline void be_put_u32(urt__rtde_w_t *w, uint32_t x) {
  if (w->end - w->p < 4) {
    w->err = 1;
    return;
  }
  for (int i = 0; i < 4; i++) {
    w->p[i] = (uint8_t)(x >> (24 - 8 * i));
  }
  w->p += 4;
}
static inline void be_put_u64(urt__rtde_w_t *w, uint64_t x) {
  if (w->end - w->p < 8) {
    w->err = 1;
    return;
  }
  for (int i = 0; i < 8; i++) {
    w->p[i] = (uint8_t)(x >> (56 - 8 * i));
  }
  w->p += 8;
}
static inline void be_put_f64(urt__rtde_w_t *w, double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  be_put_u64(w, u);
}
static inline void be_put_bytes(urt__rtde_w_t *w, const void *b, size_t n) {
  if ((size_t)(w->end - w->p) < n) {
    w->err = 1;
    return;
  }
  if (n) {
    memcpy(w->p, b, n);
  }
  w->p += n;
}

static inline uint16_t be_get_u16(const uint8_t *p) { return (uint16_t)((p[0] << 8) | p[1]); }
static inline uint32_t be_get_u32(const uint8_t *p) {
  return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}
static inline uint64_t be_get_u64(const uint8_t *p) {
  return ((uint64_t)be_get_u32(p) << 32) | be_get_u32(p + 4);
}
static inline double be_get_f64(const uint8_t *p) {
  uint64_t u = be_get_u64(p);
  double x;
  memcpy(&x, &u, sizeof x);
  return x;
}

/* Version code of v (URT_RTDE_VER) and whether it is e-Series (major ≥ 5). */
int urt__rtde_version_code(const urt_version_t *v);
int urt__rtde_is_eseries(const urt_version_t *v);
/* Controller rate of v [Hz]: 500 e-Series, 125 CB3. */
double urt__rtde_controller_hz(const urt_version_t *v);

#endif
