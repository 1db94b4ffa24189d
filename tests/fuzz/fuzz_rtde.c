/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_rtde.c — arbitrary client bytes, in arbitrary chunks, into two RTDE sessions
 * sharing one registry; a data tick after every chunk. Invariants checked on every step:
 *   - the server's byte stream (replies and data, in send order) is well framed: replies are
 *     V/S/P of 4 bytes, v of 19, O/I of at least 3; data packages only between an accepted S
 *     reply and the next P reply;
 *   - buffers stay within their bounds; a closed session stays closed;
 *   - the registry only names live sessions, and closing a session frees all it owned.
 * Input layout: byte 0 picks the versions; then records [ctl][len][len bytes]: ctl bit 0 picks
 * the session, bits 1–3 how many reply bytes to drain (0 = all), bit 4 closes and reopens it. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "urt/net/rtde.h"

#define CHECK(c)                                                        \
  do {                                                                  \
    if (!(c)) {                                                         \
      fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #c); \
      abort();                                                          \
    }                                                                   \
  } while (0)

typedef struct peer {
  urt_rtde_session_t s;
  int started;        /* as seen by the client from the stream          */
  int protocol_seen;  /* last accepted V request is not visible: unused  */
  uint8_t partial[URT_RTDE_REPLY_CAP + 16];  /* reply bytes of a package not yet complete */
  size_t plen;
} peer_t;

static urt_rtde_registry_t g_reg;
static peer_t g_peer[2];
static urt_rtde_registers_t g_regs;
static urt_snapshot_t g_snap;

/* account server→client bytes and check their framing */
static void client_sees(peer_t *c, const uint8_t *b, size_t n) {
  while (n > 0) {
    size_t k = n;
    if (c->plen + k > sizeof c->partial) {
      k = sizeof c->partial - c->plen;
    }
    memcpy(c->partial + c->plen, b, k);
    c->plen += k;
    b += k;
    n -= k;
    for (;;) {
      if (c->plen < 3) {
        break;
      }
      size_t size = (size_t)c->partial[0] << 8 | c->partial[1];
      CHECK(size >= 3);
      if (c->plen < size) {
        CHECK(size <= URT_RTDE_REPLY_CAP);
        break;
      }
      uint8_t type = c->partial[2];
      switch (type) {
        case 'V':
          CHECK(size == 4);
          break;
        case 'v':
          CHECK(size == 19);
          break;
        case 'S':
          CHECK(size == 4);
          if (c->partial[3] == 1) {
            c->started = 1;
          }
          break;
        case 'P':
          CHECK(size == 4);
          CHECK(c->partial[3] == 1);
          c->started = 0;
          break;
        case 'O':
        case 'I':
          break;
        case 'U':
          CHECK(c->started);
          break;
        default:
          CHECK(0 && "unexpected package type from the server");
      }
      memmove(c->partial, c->partial + size, c->plen - size);
      c->plen -= size;
    }
  }
}

static void open_peer(int i, const urt_version_t *v) {
  memset(&g_peer[i], 0, sizeof g_peer[i]);
  urt_rtde_session_init(&g_peer[i].s, &g_reg, v);
}

static void close_peer(int i) {
  uint32_t id = g_peer[i].s.id;
  urt_rtde_session_fini(&g_peer[i].s);
  for (int k = 0; k < urt_rtde_input_count(); k++) {
    CHECK(g_reg.owner[k] != id);
  }
}

static void drain(peer_t *c, size_t max) {
  const uint8_t *p;
  size_t n = urt_rtde_session_output(&c->s, &p);
  CHECK(n <= URT_RTDE_REPLY_CAP);
  if (max && n > max) {
    n = max;
  }
  client_sees(c, p, n);
  urt_rtde_session_consume(&c->s, n);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) {
    return 0;
  }
  urt_version_t v[2];
  memset(v, 0, sizeof v);
  v[0].major = (data[0] & 1) ? 3 : 5;
  v[0].minor = (data[0] >> 1) & 31;
  v[0].bugfix = 1;
  v[0].build = 1234;
  v[1] = v[0];
  v[1].major = (data[0] & 0x80) ? 3 : 5;
  urt_rtde_registry_init(&g_reg);
  open_peer(0, &v[0]);
  open_peer(1, &v[1]);

  static uint8_t out[1 << 17];
  size_t pos = 1;
  while (pos + 2 <= size) {
    uint8_t ctl = data[pos];
    size_t len = data[pos + 1];
    pos += 2;
    if (len > size - pos) {
      len = size - pos;
    }
    int who = ctl & 1;
    peer_t *c = &g_peer[who];

    // client bytes in; what is not consumed is retried after a drain
    const uint8_t *b = data + pos;
    size_t left = len;
    int spins = 0;
    while (left > 0 && !urt_rtde_session_closed(&c->s)) {
      long used = urt_rtde_session_feed(&c->s, b, left);
      if (used < 0) {
        CHECK(urt_rtde_session_closed(&c->s));
        break;
      }
      CHECK((size_t)used <= left);
      b += used;
      left -= (size_t)used;
      CHECK(c->s.in_len <= URT_RTDE_MAX_PACKAGE);
      CHECK(c->s.out_len <= URT_RTDE_REPLY_CAP && c->s.out_head <= c->s.out_len);
      if (left > 0) {
        drain(c, 0);
        CHECK(++spins < 100000);
      }
    }
    pos += len;
    if (urt_rtde_session_closed(&c->s)) {
      CHECK(urt_rtde_session_feed(&c->s, data, 0) < 0);
    }

    // the server drains some of its replies, then runs one tick for both sessions
    drain(c, (ctl >> 1) & 7 ? ((ctl >> 1) & 7) * 3 : 0);
    g_snap.tick++;
    g_snap.time += 0.002;
    for (int i = 0; i < 2; i++) {
      int n = urt_rtde_session_encode_data(&g_peer[i].s, &g_snap, &g_regs, out,
                                           (ctl & 0x40) ? 40 : sizeof out);
      CHECK(n >= 0 || n == -3 /* URT_ENOSPC */);
      if (n > 0) {
        CHECK((size_t)n == ((size_t)out[0] << 8 | out[1]));
        CHECK(out[2] == 'U');
        client_sees(&g_peer[i], out, (size_t)n);
      }
      urt_rtde_inputs_t in;
      if (urt_rtde_session_take_inputs(&g_peer[i].s, &in)) {
        urt_rtde_inputs_apply_registers(&in, &g_regs);
      }
    }

    // registry: every owner is a live session
    for (int k = 0; k < urt_rtde_input_count(); k++) {
      uint32_t o = g_reg.owner[k];
      CHECK(o == 0 || o == g_peer[0].s.id || o == g_peer[1].s.id);
    }

    // reconnect
    if (ctl & 0x10) {
      close_peer(who);
      open_peer(who, &v[who]);
    }
  }
  close_peer(0);
  close_peer(1);
  CHECK(g_reg.nsessions == 0);
  return 0;
}
