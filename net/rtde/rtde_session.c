/* SPDX-License-Identifier: Apache-2.0
 * net/rtde/rtde_session.c — the per-connection RTDE state machine (protocols.md §2.2, clients.md
 * §1): framing of client bytes, one reply per setup/control request, input recipes with ids
 * 1..N per connection and ownership across connections, and decimated data packages.
 *
 * Decisions where UR's documents are silent (all unconfirmed against a real controller):
 *  - an O with a frequency ≤ 0, NaN or above the controller rate gets the normal type list but
 *    recipe id 0 (invalid recipe, nothing streams, S is then refused with 0);
 *  - a U with an unknown recipe id or a size that does not match its recipe is dropped and
 *    counted; no text message is sent, because ur_rtde reads exactly one package after each
 *    request and an unsolicited M would be taken as that reply;
 *  - a package of an unknown type is skipped (framing is intact); only a size < 3 or larger
 *    than URT_RTDE_MAX_PACKAGE loses the framing and closes the connection.
 */
#include <math.h>
#include <string.h>

#include "rtde_internal.h"
#include "urt/errors.h"

/* the largest reply one request can produce: an O/I reply listing URT_RTDE_MAX_FIELDS types */
#define REPLY_WORST (4 + URT_RTDE_MAX_FIELDS * 14)
_Static_assert(REPLY_WORST <= URT_RTDE_REPLY_CAP, "one worst-case reply fits the queue");

//---- registry ----

void urt_rtde_registry_init(urt_rtde_registry_t *g) { memset(g, 0, sizeof *g); }

//---- inputs ----

void urt_rtde_inputs_merge(urt_rtde_inputs_t *dst, const urt_rtde_inputs_t *src) {
  if (src->set & URT_RTDE_IN_SPEED_SLIDER) {
    dst->speed_slider_fraction = src->speed_slider_fraction;
  }
  if (src->set & URT_RTDE_IN_EXT_FT) {
    memcpy(dst->external_force_torque, src->external_force_torque,
           sizeof dst->external_force_torque);
  }
  dst->set |= src->set;

  // digital outputs: newer bits win where the newer mask is set
  dst->std_do = (uint8_t)((dst->std_do & ~src->std_do_mask) | (src->std_do & src->std_do_mask));
  dst->std_do_mask |= src->std_do_mask;
  dst->conf_do =
      (uint8_t)((dst->conf_do & ~src->conf_do_mask) | (src->conf_do & src->conf_do_mask));
  dst->conf_do_mask |= src->conf_do_mask;
  dst->tool_do =
      (uint8_t)((dst->tool_do & ~src->tool_do_mask) | (src->tool_do & src->tool_do_mask));
  dst->tool_do_mask |= src->tool_do_mask;

  // analog outputs
  for (int i = 0; i < 2; i++) {
    if (src->ao_mask & (1u << i)) {
      dst->ao[i] = src->ao[i];
      dst->ao_type = (uint8_t)((dst->ao_type & ~(1u << i)) | (src->ao_type & (1u << i)));
    }
  }
  dst->ao_mask |= src->ao_mask;

  // registers
  for (int i = 0; i < URT_RTDE_NREG; i++) {
    if (src->int_set >> i & 1) {
      dst->int_reg[i] = src->int_reg[i];
    }
    if (src->double_set >> i & 1) {
      dst->double_reg[i] = src->double_reg[i];
    }
  }
  dst->int_set |= src->int_set;
  dst->double_set |= src->double_set;
  for (int k = 0; k < 2; k++) {
    dst->bit_val[k] = (dst->bit_val[k] & ~src->bit_set[k]) | (src->bit_val[k] & src->bit_set[k]);
    dst->bit_set[k] |= src->bit_set[k];
  }
}

void urt_rtde_inputs_apply_registers(const urt_rtde_inputs_t *in, urt_rtde_registers_t *r) {
  for (int i = 0; i < URT_RTDE_NREG; i++) {
    if (in->int_set >> i & 1) {
      r->in_int[i] = in->int_reg[i];
      r->in_int_writes[i]++;
    }
    if (in->double_set >> i & 1) {
      r->in_double[i] = in->double_reg[i];
      r->in_double_writes[i]++;
    }
  }
  for (int i = 0; i < URT_RTDE_NBITREG; i++) {
    if (in->bit_set[i / 64] >> (i % 64) & 1) {
      r->in_bit[i] = (uint8_t)(in->bit_val[i / 64] >> (i % 64) & 1);
    }
  }
}

//---- session lifetime ----

void urt_rtde_session_init(urt_rtde_session_t *s, urt_rtde_registry_t *g,
                           const urt_version_t *v) {
  memset(s, 0, sizeof *s);
  s->registry = g;
  s->version = *v;
  s->protocol = 1;
  s->decimation = 1;

  // an id no attached session uses: 0 means "free" in owner[]
  do {
    g->next_id++;
  } while (g->next_id == 0);
  s->id = g->next_id;
  g->nsessions++;
}

void urt_rtde_session_fini(urt_rtde_session_t *s) {
  urt_rtde_registry_t *g = s->registry;
  if (!g) {
    return;
  }
  for (int i = 0; i < URT__RTDE_IN_COUNT; i++) {
    if (g->owner[i] == s->id) {
      g->owner[i] = 0;
    }
  }
  g->nsessions--;
  s->registry = NULL;
  s->started = false;
}

bool urt_rtde_session_closed(const urt_rtde_session_t *s) { return s->closed; }

static void close_with(urt_rtde_session_t *s, int err) {
  s->closed = true;
  s->error = err;
  s->started = false;
}

//---- reply queue ----

static size_t reply_free(const urt_rtde_session_t *s) { return URT_RTDE_REPLY_CAP - s->out_len; }

/* a writer over the free tail of the reply queue (compacted first) */
static urt__rtde_w_t reply_begin(urt_rtde_session_t *s) {
  if (s->out_head > 0) {
    memmove(s->outbuf, s->outbuf + s->out_head, s->out_len - s->out_head);
    s->out_len -= s->out_head;
    s->out_head = 0;
  }
  return (urt__rtde_w_t){s->outbuf + s->out_len, s->outbuf + URT_RTDE_REPLY_CAP, 0};
}

/* patch the size of the package that starts at the queue's old end and keep it */
static void reply_end(urt_rtde_session_t *s, urt__rtde_w_t *w) {
  uint8_t *start = s->outbuf + s->out_len;
  size_t len = (size_t)(w->p - start);
  if (w->err || len < 3) {
    return;  /* cannot happen: REPLY_WORST is reserved before handling */
  }
  start[0] = (uint8_t)(len >> 8);
  start[1] = (uint8_t)len;
  s->out_len += len;
}

static void reply_u8(urt_rtde_session_t *s, uint8_t type, uint8_t value) {
  urt__rtde_w_t w = reply_begin(s);
  be_put_u16(&w, 0);
  be_put_u8(&w, type);
  be_put_u8(&w, value);
  reply_end(s, &w);
}

size_t urt_rtde_session_output(const urt_rtde_session_t *s, const uint8_t **p) {
  *p = s->outbuf + s->out_head;
  return s->out_len - s->out_head;
}

//---- name lists ----

/* Split "a,b,c" (a single trailing comma is ignored, as ur_rtde sends one after every name).
 * Calls back once per token; returns the token count. */
typedef void (*token_fn)(void *ctx, int k, const char *name, size_t len);
static int split_names(const uint8_t *p, size_t n, token_fn fn, void *ctx) {
  if (n > 0 && p[n - 1] == ',') {
    n--;
  }
  if (n == 0) {
    return 0;
  }
  int k = 0;
  size_t start = 0;
  for (size_t i = 0; i <= n; i++) {
    if (i == n || p[i] == ',') {
      if (k < URT_RTDE_MAX_FIELDS && fn) {
        fn(ctx, k, (const char *)p + start, i - start);
      }
      k++;
      start = i + 1;
    }
  }
  return k;
}

static int count_names(const uint8_t *p, size_t n) { return split_names(p, n, NULL, NULL); }

typedef struct resolve_ctx {
  urt_rtde_session_t *s;
  int input;                              /* 0 outputs, 1 inputs           */
  urt_rtde_field_t f[URT_RTDE_MAX_FIELDS];
  int8_t status[URT_RTDE_MAX_FIELDS];     /* 0 ok, 1 NOT_FOUND, 2 IN_USE   */
} resolve_ctx_t;

static void resolve_one(void *vctx, int k, const char *name, size_t len) {
  resolve_ctx_t *c = vctx;
  urt_rtde_session_t *s = c->s;
  int rc = c->input ? urt_rtde_input_lookup(name, len, &s->version, &c->f[k])
                    : urt_rtde_output_lookup(name, len, &s->version, &c->f[k]);
  c->status[k] = rc == 0 ? 0 : 1;
  if (rc == 0 && c->input) {
    uint32_t owner = s->registry ? s->registry->owner[c->f[k].var] : 0;
    if (owner != 0 && owner != s->id) {
      c->status[k] = 2;
    }
  }
}

static void put_types(urt__rtde_w_t *w, const resolve_ctx_t *c, int n) {
  for (int k = 0; k < n; k++) {
    const char *t = c->status[k] == 1   ? "NOT_FOUND"
                    : c->status[k] == 2 ? "IN_USE"
                                        : urt_rtde_type_name((urt_rtde_type_t)c->f[k].type);
    if (k > 0) {
      be_put_u8(w, ',');
    }
    be_put_bytes(w, t, strlen(t));
  }
}

/* Resolve the comma-separated names p[0..n) into c (outputs, or inputs with their owners).
 * Returns how many, 0 for an empty or too long list; *ok = 0 if the list is refused or a name
 * is not found or in use; *size = the bytes of their values. */
static int resolve_names(resolve_ctx_t *c, urt_rtde_session_t *s, int input, const uint8_t *p,
                         size_t n, int *ok, size_t *size) {
  int count = count_names(p, n);
  if (count == 0 || count > URT_RTDE_MAX_FIELDS) {
    *ok = 0;
    count = count > URT_RTDE_MAX_FIELDS ? 0 : count;
    n = 0;
  }
  c->s = s;
  c->input = input;
  split_names(p, n, resolve_one, c);
  *size = 0;
  for (int k = 0; k < count; k++) {
    if (c->status[k]) {
      *ok = 0;
    }
    *size += urt_rtde_type_size((urt_rtde_type_t)c->f[k].type);
  }
  return count;
}

/* The O or I reply: the id byte (id < 0: none), then the types. */
static void reply_setup(urt_rtde_session_t *s, uint8_t type, int id, const resolve_ctx_t *c,
                        int count) {
  urt__rtde_w_t w = reply_begin(s);
  be_put_u16(&w, 0);
  be_put_u8(&w, type);
  if (id >= 0) {
    be_put_u8(&w, (uint8_t)id);
  }
  put_types(&w, c, count);
  reply_end(s, &w);
}

//---- O: setup outputs ----

static void handle_setup_outputs(urt_rtde_session_t *s, const uint8_t *p, size_t n) {
  resolve_ctx_t c;  /* 2.5 kB of stack, setup only */
  double hz = urt__rtde_controller_hz(&s->version);
  double freq = hz;
  int ok = 1;

  // v2 carries the frequency first
  if (s->protocol == 2) {
    if (n < 8) {
      ok = 0;
      n = 0;
    } else {
      freq = be_get_f64(p);
      p += 8;
      n -= 8;
      if (!(freq > 0.0 && freq <= hz)) {
        ok = 0;
      }
    }
  }

  // resolve every name once, into kinds and types
  size_t size;
  int count = resolve_names(&c, s, 0, p, n, &ok, &size);

  // install the recipe (one per connection: it replaces the previous one)
  s->out_configured = true;
  s->out_valid = ok;
  s->out_count = ok ? (uint16_t)count : 0;
  s->out_size = ok ? (uint16_t)size : 0;
  s->out_sent_any = false;
  if (ok) {
    memcpy(s->out, c.f, (size_t)count * sizeof c.f[0]);
    double d = floor(hz / freq + 1e-9);
    s->decimation = d < 1.0 ? 1u : (d > 4e9 ? 4000000000u : (uint32_t)d);
  }

  // reply: v2 recipe id (1, or 0 if invalid), then the types
  reply_setup(s, URT_RTDE_SETUP_OUTPUTS, s->protocol == 2 ? (ok ? 1 : 0) : -1, &c, count);
}

//---- I: setup inputs ----

static void handle_setup_inputs(urt_rtde_session_t *s, const uint8_t *p, size_t n) {
  resolve_ctx_t c;
  int ok = 1;
  size_t size;
  int count = resolve_names(&c, s, 1, p, n, &ok, &size);
  size += 1;  // the recipe id that leads a U package

  // room for one more recipe whose U package fits the input buffer
  if (s->n_in >= URT_RTDE_MAX_INPUT_RECIPES || s->pool_used + count > URT_RTDE_INPUT_POOL ||
      size + 3 > URT_RTDE_MAX_PACKAGE || !s->registry) {
    ok = 0;
  }

  // install it with the next id and claim its variables (overlap within a connection is fine)
  int id = 0;
  if (ok) {
    urt_rtde_recipe_t *r = &s->in[s->n_in];
    r->first = s->pool_used;
    r->count = (uint16_t)count;
    r->size = (uint16_t)(size - 1);
    memcpy(s->pool + s->pool_used, c.f, (size_t)count * sizeof c.f[0]);
    s->pool_used = (uint16_t)(s->pool_used + count);
    id = ++s->n_in;
    for (int k = 0; k < count; k++) {
      s->registry->owner[c.f[k].var] = s->id;
    }
  }

  // reply (both protocol versions): recipe id, then the types
  reply_setup(s, URT_RTDE_SETUP_INPUTS, id, &c, count);
}

//---- U: client data ----

static void handle_data(urt_rtde_session_t *s, const uint8_t *p, size_t n) {
  if (n < 1 || p[0] == 0 || p[0] > s->n_in) {
    s->stats.bad_input++;
    return;
  }
  const urt_rtde_recipe_t *r = &s->in[p[0] - 1];
  if (n - 1 != r->size) {
    s->stats.bad_input++;
    return;
  }

  // decode into the retained values and this package's effects
  urt_rtde_inputs_t e;
  memset(&e, 0, sizeof e);
  urt_rtde_inputs_t *v = &s->retained;
  int slider = 0, sdo = 0, cdo = 0, tdo = 0, ao = 0;
  const uint8_t *q = p + 1;
  for (int k = 0; k < r->count; k++) {
    urt_rtde_field_t f = s->pool[r->first + k];
    int i = f.index;
    switch (f.var) {
      case URT__RTDE_IN_speed_slider_mask: s->retained_slider_mask = be_get_u32(q); slider = 1; break;
      case URT__RTDE_IN_speed_slider_fraction: v->speed_slider_fraction = be_get_f64(q); slider = 1; break;
      case URT__RTDE_IN_standard_digital_output_mask: s->retained_std_do_mask = q[0]; sdo = 1; break;
      case URT__RTDE_IN_standard_digital_output: v->std_do = q[0]; sdo = 1; break;
      case URT__RTDE_IN_configurable_digital_output_mask: s->retained_conf_do_mask = q[0]; cdo = 1; break;
      case URT__RTDE_IN_configurable_digital_output: v->conf_do = q[0]; cdo = 1; break;
      case URT__RTDE_IN_tool_digital_output_mask: s->retained_tool_do_mask = q[0] & 3u; tdo = 1; break;
      case URT__RTDE_IN_tool_digital_output: v->tool_do = q[0] & 3u; tdo = 1; break;
      case URT__RTDE_IN_standard_analog_output_mask: s->retained_ao_mask = q[0] & 3u; ao = 1; break;
      case URT__RTDE_IN_standard_analog_output_type: v->ao_type = q[0] & 3u; ao = 1; break;
      case URT__RTDE_IN_standard_analog_output_0: v->ao[0] = be_get_f64(q); ao = 1; break;
      case URT__RTDE_IN_standard_analog_output_1: v->ao[1] = be_get_f64(q); ao = 1; break;
      case URT__RTDE_IN_external_force_torque:
        for (int j = 0; j < 6; j++) {
          e.external_force_torque[j] = be_get_f64(q + 8 * j);
        }
        e.set |= URT_RTDE_IN_EXT_FT;
        break;
      case URT__RTDE_IN_BITS_LO_ID:
      case URT__RTDE_IN_BITS_HI_ID: {
        uint64_t word = be_get_u32(q);
        int shift = f.var == URT__RTDE_IN_BITS_HI_ID ? 32 : 0;
        e.bit_set[0] |= 0xffffffffull << shift;
        e.bit_val[0] = (e.bit_val[0] & ~(0xffffffffull << shift)) | (word << shift);
        break;
      }
      default:
        if (f.var >= URT__RTDE_IN_INT_BASE && f.var < URT__RTDE_IN_DOUBLE_BASE) {
          e.int_reg[i] = (int32_t)be_get_u32(q);
          e.int_set |= 1ull << i;
        } else if (f.var >= URT__RTDE_IN_DOUBLE_BASE && f.var < URT__RTDE_IN_BITS_LO_ID) {
          e.double_reg[i] = be_get_f64(q);
          e.double_set |= 1ull << i;
        } else if (f.var >= URT__RTDE_IN_BIT_BASE && f.var < URT__RTDE_IN_COUNT) {
          e.bit_set[1] |= 1ull << (i - 64);
          e.bit_val[1] = (e.bit_val[1] & ~(1ull << (i - 64))) | ((uint64_t)(q[0] != 0) << (i - 64));
        }
        break;
    }
    q += urt_rtde_type_size((urt_rtde_type_t)f.type);
  }

  // masked outputs act on the retained mask and value of their group
  if (slider && (s->retained_slider_mask & 1u)) {
    e.set |= URT_RTDE_IN_SPEED_SLIDER;
    e.speed_slider_fraction = v->speed_slider_fraction;
  }
  if (sdo) {
    e.std_do_mask = s->retained_std_do_mask;
    e.std_do = v->std_do & e.std_do_mask;
  }
  if (cdo) {
    e.conf_do_mask = s->retained_conf_do_mask;
    e.conf_do = v->conf_do & e.conf_do_mask;
  }
  if (tdo) {
    e.tool_do_mask = s->retained_tool_do_mask;
    e.tool_do = v->tool_do & e.tool_do_mask;
  }
  if (ao) {
    e.ao_mask = s->retained_ao_mask;
    e.ao_type = v->ao_type & e.ao_mask;
    e.ao[0] = v->ao[0];
    e.ao[1] = v->ao[1];
  }
  urt_rtde_inputs_merge(&s->pending, &e);
  s->have_pending = true;
  s->stats.inputs++;
}

bool urt_rtde_session_take_inputs(urt_rtde_session_t *s, urt_rtde_inputs_t *out) {
  if (!s->have_pending) {
    return false;
  }
  *out = s->pending;
  memset(&s->pending, 0, sizeof s->pending);
  s->have_pending = false;
  return true;
}

//---- one package ----

static void handle_package(urt_rtde_session_t *s, uint8_t type, const uint8_t *p, size_t n) {
  s->stats.packages++;
  switch (type) {
    case URT_RTDE_REQUEST_PROTOCOL_VERSION: {
      uint16_t want = n >= 2 ? be_get_u16(p) : 0;
      int ok = want == 1 || want == 2;
      if (ok) {
        s->protocol = (uint8_t)want;
      }
      reply_u8(s, URT_RTDE_REQUEST_PROTOCOL_VERSION, (uint8_t)ok);
      break;
    }
    case URT_RTDE_GET_URCONTROL_VERSION: {
      urt__rtde_w_t w = reply_begin(s);
      be_put_u16(&w, 0);
      be_put_u8(&w, URT_RTDE_GET_URCONTROL_VERSION);
      be_put_u32(&w, (uint32_t)s->version.major);
      be_put_u32(&w, (uint32_t)s->version.minor);
      be_put_u32(&w, (uint32_t)s->version.bugfix);
      be_put_u32(&w, (uint32_t)s->version.build);
      reply_end(s, &w);
      break;
    }
    case URT_RTDE_TEXT_MESSAGE:
      s->stats.text_messages++;  /* accepted, never answered */
      break;
    case URT_RTDE_SETUP_OUTPUTS:
      handle_setup_outputs(s, p, n);
      break;
    case URT_RTDE_SETUP_INPUTS:
      handle_setup_inputs(s, p, n);
      break;
    case URT_RTDE_START: {
      // refused only when the output recipe was rejected; the reply precedes any data
      int ok = !(s->out_configured && !s->out_valid);
      if (ok && !s->started) {
        s->started = true;
        s->out_sent_any = false;
      }
      reply_u8(s, URT_RTDE_START, (uint8_t)ok);
      break;
    }
    case URT_RTDE_PAUSE:
      s->started = false;
      reply_u8(s, URT_RTDE_PAUSE, 1);
      break;
    case URT_RTDE_DATA_PACKAGE:
      handle_data(s, p, n);
      break;
    default:
      s->stats.unknown_type++;
      break;
  }
}

//---- framing ----

/* handle every complete package in inbuf while the reply queue has room for the worst reply */
static void process(urt_rtde_session_t *s) {
  size_t pos = 0;
  while (!s->closed && s->in_len - pos >= 3) {
    const uint8_t *h = s->inbuf + pos;
    size_t size = be_get_u16(h);
    if (size < 3 || size > URT_RTDE_MAX_PACKAGE) {
      close_with(s, URT_EPROTO);
      break;
    }
    if (s->in_len - pos < size) {
      break;
    }
    if (reply_free(s) + s->out_head < REPLY_WORST) {
      break;  /* back-pressure: wait until the caller drains the replies */
    }
    handle_package(s, h[2], h + 3, size - 3);
    pos += size;
  }
  if (pos > 0) {
    memmove(s->inbuf, s->inbuf + pos, s->in_len - pos);
    s->in_len -= pos;
  }
}

uint8_t *urt_rtde_session_recv_buf(urt_rtde_session_t *s, size_t *space) {
  *space = s->closed ? 0 : URT_RTDE_MAX_PACKAGE - s->in_len;
  return s->inbuf + s->in_len;
}

int urt_rtde_session_commit(urt_rtde_session_t *s, size_t n) {
  if (s->closed) {
    return URT_EPROTO;
  }
  if (n > URT_RTDE_MAX_PACKAGE - s->in_len) {
    n = URT_RTDE_MAX_PACKAGE - s->in_len;
  }
  s->in_len += n;
  process(s);
  return s->closed ? URT_EPROTO : 0;
}

long urt_rtde_session_feed(urt_rtde_session_t *s, const uint8_t *in, size_t n) {
  size_t used = 0;
  if (s->closed) {
    return URT_EPROTO;
  }
  process(s);
  while (used < n && !s->closed) {
    size_t space;
    uint8_t *dst = urt_rtde_session_recv_buf(s, &space);
    if (space == 0) {
      break;  /* stalled on the reply queue */
    }
    size_t k = n - used < space ? n - used : space;
    memcpy(dst, in + used, k);
    used += k;
    urt_rtde_session_commit(s, k);
  }
  return s->closed ? URT_EPROTO : (long)used;
}

void urt_rtde_session_consume(urt_rtde_session_t *s, size_t n) {
  size_t pending = s->out_len - s->out_head;
  s->out_head += n < pending ? n : pending;
  if (s->out_head == s->out_len) {
    s->out_head = s->out_len = 0;
  }
  process(s);
}

//---- data packages ----

int urt_rtde_session_encode_data(urt_rtde_session_t *s, const urt_snapshot_t *snap,
                                 const urt_rtde_registers_t *r, uint8_t *out, size_t cap) {
  if (s->closed || !s->started || !s->out_valid || s->out_count == 0 ||
      s->out_len != s->out_head) {
    return 0;
  }
  if (s->out_sent_any && snap->tick < s->next_tick) {
    return 0;
  }
  int rc = urt_rtde_encode_fields(s->out, s->out_count, s->protocol == 2 ? 1 : -1, snap, r, out,
                                  cap);
  if (rc < 0) {
    return rc;
  }
  s->out_sent_any = true;
  s->next_tick = snap->tick + s->decimation;
  s->stats.data_sent++;
  return rc;
}
