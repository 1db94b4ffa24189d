/* SPDX-License-Identifier: Apache-2.0
 * tests/net/rtde/test_rtde_session.c — the RTDE state machine without sockets: byte-exact
 * handshakes (protocols.md §2.7a), recipe ids, ownership, decimation, inputs, every malformed
 * package path and arbitrary chunking. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtde_test_util.h"
#include "test_support.h"
#include "urt/errors.h"

static urt_rtde_registry_t g_reg;
static urt_rtde_registers_t g_regs;
static urt_snapshot_t g_snap;

static urt_rtde_session_t *new_session(int major, int minor, int bugfix) {
  urt_rtde_session_t *s = malloc(sizeof *s);
  assert_non_null(s);
  urt_version_t v = rt_version(major, minor, bugfix, major >= 5 ? 1210631 : 106339);
  urt_rtde_session_init(s, &g_reg, &v);
  return s;
}

static void free_session(urt_rtde_session_t *s) {
  urt_rtde_session_fini(s);
  free(s);
}

static int setup(void **state) {
  urt_rtde_registry_init(&g_reg);
  memset(&g_regs, 0, sizeof g_regs);
  memset(&g_snap, 0, sizeof g_snap);
  return 0;
}

static void expect_bytes(const uint8_t *got, size_t n, const uint8_t *want, size_t wn) {
  assert_int_equal(n, wn);
  assert_memory_equal(got, want, wn);
}

/* the §2.7a exchange, as one client byte stream and the server bytes it must produce */
static size_t example_client_stream(uint8_t *b) {
  size_t n = 0;
  n += rt_pkg(b + n, 'V', "\x00\x02", 2);
  n += rt_pkg(b + n, 'v', NULL, 0);
  n += rt_pkg_outputs(b + n, 500.0, "timestamp,actual_q");
  n += rt_pkg_names(b + n, 'I', "speed_slider_mask,speed_slider_fraction");
  n += rt_pkg(b + n, 'S', NULL, 0);
  return n;
}

static const uint8_t k_example_replies[] = {
    0x00, 0x04, 0x56, 0x01,                                                  /* V ok   */
    0x00, 0x13, 0x76, 0, 0, 0, 5, 0, 0, 0, 0x13, 0, 0, 0, 0, 0x00, 0x12, 0x79, 0x07, /* v */
    0x00, 0x13, 0x4F, 0x01, 'D', 'O', 'U', 'B', 'L', 'E', ',', 'V', 'E', 'C', 'T', 'O', 'R',
    '6', 'D',                                                                /* O      */
    0x00, 0x11, 0x49, 0x01, 'U', 'I', 'N', 'T', '3', '2', ',', 'D', 'O', 'U', 'B', 'L', 'E', /* I */
    0x00, 0x04, 0x53, 0x01};                                                 /* S ok   */

//---- handshakes ----

static void test_rtde_session__v2_handshake_matches_the_worked_example(void **state) {
  uint8_t in[256], out[512];
  size_t n = example_client_stream(in);

  // the request bytes themselves are the ones of §2.7a
  static const uint8_t o_hdr[] = {0x00, 0x1D, 0x4F, 0x40, 0x7F, 0x40, 0, 0, 0, 0, 0};
  assert_memory_equal(in + 5 + 3, o_hdr, sizeof o_hdr);
  static const uint8_t i_hdr[] = {0x00, 0x2A, 0x49};
  assert_memory_equal(in + 5 + 3 + 29, i_hdr, sizeof i_hdr);

  urt_rtde_session_t *s = new_session(5, 19, 0);
  size_t k = rt_exchange(s, in, n, out, sizeof out);
  expect_bytes(out, k, k_example_replies, sizeof k_example_replies);
  assert_int_equal(s->protocol, 2);
  assert_true(s->started);

  // step 11: a 60-byte data package with recipe id 1, timestamp and actual_q
  g_snap.time = 42.5;
  for (int j = 0; j < 6; j++) {
    g_snap.q[j] = 0.1 * j;
  }
  k = (size_t)urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out);
  assert_int_equal(k, 60);
  static const uint8_t head[] = {0x00, 0x3C, 0x55, 0x01, 0x40, 0x45, 0x40, 0, 0, 0, 0, 0};
  assert_memory_equal(out, head, sizeof head);
  uint8_t q1[8];
  double x = 0.1;
  uint64_t u;
  memcpy(&u, &x, 8);
  for (int i = 0; i < 8; i++) {
    q1[i] = (uint8_t)(u >> (56 - 8 * i));
  }
  assert_memory_equal(out + 12 + 8, q1, 8);

  // step 12: U for input recipe 1 — mask 1, fraction 0.5 — is decoded, not answered
  static const uint8_t u_pkg[] = {0x00, 0x10, 0x55, 0x01, 0, 0, 0, 1, 0x3F, 0xE0, 0, 0, 0, 0, 0, 0};
  k = rt_exchange(s, u_pkg, sizeof u_pkg, out, sizeof out);
  assert_int_equal(k, 0);
  urt_rtde_inputs_t in_fx;
  assert_true(urt_rtde_session_take_inputs(s, &in_fx));
  assert_true(in_fx.set & URT_RTDE_IN_SPEED_SLIDER);
  assert_true(in_fx.speed_slider_fraction == 0.5);
  assert_false(urt_rtde_session_take_inputs(s, &in_fx));

  // step 13: P / accepted; data stops
  uint8_t p_pkg[3];
  rt_pkg(p_pkg, 'P', NULL, 0);
  k = rt_exchange(s, p_pkg, 3, out, sizeof out);
  static const uint8_t p_rep[] = {0x00, 0x04, 0x50, 0x01};
  expect_bytes(out, k, p_rep, sizeof p_rep);
  g_snap.tick = 1000;
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);
  free_session(s);
}

static void test_rtde_session__v1_handshake_has_no_output_recipe_id(void **state) {
  uint8_t in[256], out[512];
  urt_rtde_session_t *s = new_session(3, 15, 8);
  size_t n = 0;
  n += rt_pkg(in + n, 'V', "\x00\x01", 2);
  n += rt_pkg_names(in + n, 'O', "timestamp,actual_q");
  n += rt_pkg_names(in + n, 'I', "input_int_register_0");
  n += rt_pkg(in + n, 'S', NULL, 0);
  size_t k = rt_exchange(s, in, n, out, sizeof out);
  static const uint8_t want[] = {
      0x00, 0x04, 0x56, 0x01,
      0x00, 0x12, 0x4F, 'D', 'O', 'U', 'B', 'L', 'E', ',', 'V', 'E', 'C', 'T', 'O', 'R', '6', 'D',
      0x00, 0x09, 0x49, 0x01, 'I', 'N', 'T', '3', '2',
      0x00, 0x04, 0x53, 0x01};
  expect_bytes(out, k, want, sizeof want);
  assert_int_equal(s->protocol, 1);
  assert_int_equal(s->decimation, 1);  /* v1 streams at the controller rate (125 Hz) */

  // data packages carry no recipe id in v1: 3 + 8 + 48
  int len = urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out);
  assert_int_equal(len, 59);
  assert_int_equal(out[2], 'U');
  free_session(s);
}

static void test_rtde_session__protocol_version_other_than_1_or_2_is_refused(void **state) {
  uint8_t in[16], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  static const uint8_t no[] = {0x00, 0x04, 0x56, 0x00};
  static const uint16_t bad[] = {0, 3, 0x0200, 0xffff};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    uint8_t v[2] = {(uint8_t)(bad[i] >> 8), (uint8_t)bad[i]};
    size_t k = rt_exchange(s, in, rt_pkg(in, 'V', v, 2), out, sizeof out);
    expect_bytes(out, k, no, sizeof no);
    assert_int_equal(s->protocol, 1);
  }
  // a V without its uint16 is refused too
  size_t k = rt_exchange(s, in, rt_pkg(in, 'V', "\x02", 1), out, sizeof out);
  expect_bytes(out, k, no, sizeof no);
  free_session(s);
}

static void test_rtde_session__v_reply_is_16_bytes_every_time(void **state) {
  uint8_t in[16], out[64];
  urt_rtde_session_t *s = new_session(5, 23, 0);
  for (int i = 0; i < 2; i++) {  /* ur_rtde asks twice */
    size_t k = rt_exchange(s, in, rt_pkg(in, 'v', NULL, 0), out, sizeof out);
    assert_int_equal(k, 19);
    assert_int_equal(out[1], 19);
    assert_int_equal(out[2], 'v');
    assert_int_equal(out[3 + 7], 23);
  }
  free_session(s);
}

static void test_rtde_session__text_message_from_client_gets_no_reply(void **state) {
  uint8_t in[64], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  static const uint8_t m[] = {5, 'h', 'e', 'l', 'l', 'o', 3, 'c', 'l', 'i', 2};
  assert_int_equal(rt_exchange(s, in, rt_pkg(in, 'M', m, sizeof m), out, sizeof out), 0);
  assert_int_equal(s->stats.text_messages, 1);
  free_session(s);
}

//---- output recipes ----

static void negotiate_v2(urt_rtde_session_t *s) {
  uint8_t in[8], out[8];
  rt_exchange(s, in, rt_pkg(in, 'V', "\x00\x02", 2), out, sizeof out);
}

static void test_rtde_session__unknown_output_is_not_found_and_start_is_refused(void **state) {
  uint8_t in[256], out[256];
  char types[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  size_t k = rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp,actual_qdd,actual_moment"),
                         out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "DOUBLE,NOT_FOUND,NOT_FOUND");
  k = rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  static const uint8_t no[] = {0x00, 0x04, 0x53, 0x00};
  expect_bytes(out, k, no, sizeof no);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);

  // a corrected recipe replaces it and starts
  k = rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp,"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  assert_string_equal(types, "DOUBLE");
  k = rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  assert_int_equal(out[3], 1);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 12);
  free_session(s);
}

static void test_rtde_session__trailing_comma_is_ignored(void **state) {
  uint8_t in[256], out[256];
  char types[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  size_t k = rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp,actual_q,"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  assert_string_equal(types, "DOUBLE,VECTOR6D");
  k = rt_exchange(s, in, rt_pkg_names(in, 'I', "input_int_register_0,input_double_register_0,"),
                  out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  assert_string_equal(types, "INT32,DOUBLE");

  // but an empty name inside the list is unknown
  k = rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp,,actual_q"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "DOUBLE,NOT_FOUND,VECTOR6D");
  free_session(s);
}

static void test_rtde_session__illegal_frequency_gives_recipe_id_0(void **state) {
  uint8_t in[256], out[256];
  char types[256];
  const double bad[] = {0.0, -1.0, 500.5, 1000.0, NAN, INFINITY};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    urt_rtde_session_t *s = new_session(5, 19, 0);
    negotiate_v2(s);
    size_t k = rt_exchange(s, in, rt_pkg_outputs(in, bad[i], "timestamp"), out, sizeof out);
    assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
    assert_string_equal(types, "DOUBLE");
    k = rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
    assert_int_equal(out[3], 0);
    free_session(s);
  }
  // CB3 caps at 125 Hz
  urt_rtde_session_t *s = new_session(3, 15, 8);
  negotiate_v2(s);
  size_t k = rt_exchange(s, in, rt_pkg_outputs(in, 126, "timestamp"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  k = rt_exchange(s, in, rt_pkg_outputs(in, 125, "timestamp"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  free_session(s);
}

static int count_packages(urt_rtde_session_t *s, uint64_t ticks) {
  uint8_t out[256];
  int n = 0;
  for (uint64_t t = 0; t < ticks; t++) {
    g_snap.tick = t;
    n += urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out) > 0;
  }
  return n;
}

static void test_rtde_session__frequency_decimates_the_controller_rate(void **state) {
  struct {
    int major;
    double f;
    int want;  /* packages in 1000 ticks */
  } cases[] = {{5, 500, 1000}, {5, 250, 500}, {5, 125, 250}, {5, 100, 200}, {5, 10, 20},
               {5, 300, 1000} /* floor(500/300) = 1 */, {5, 1, 2}, {3, 125, 1000}, {3, 10, 84}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    uint8_t in[256], out[256];
    urt_rtde_session_t *s = new_session(cases[i].major, cases[i].major == 5 ? 19 : 15, 0);
    negotiate_v2(s);
    rt_exchange(s, in, rt_pkg_outputs(in, cases[i].f, "timestamp"), out, sizeof out);
    rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
    assert_int_equal(out[3], 1);
    int got = count_packages(s, 1000);
    if (got != cases[i].want) {
      fail_msg("%d.x at %g Hz: %d packages in 1000 ticks, want %d", cases[i].major, cases[i].f,
               got, cases[i].want);
    }
    free_session(s);
  }
}

static void test_rtde_session__no_data_before_the_start_reply_is_drained(void **state) {
  uint8_t in[256], out[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp"), out, sizeof out);

  // before S: nothing
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);

  // S handled but its reply still queued: still nothing
  assert_int_equal(urt_rtde_session_feed(s, in, rt_pkg(in, 'S', NULL, 0)), 3);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);
  const uint8_t *p;
  assert_int_equal(urt_rtde_session_output(s, &p), 4);
  urt_rtde_session_consume(s, 2);  /* a partial send is not enough either */
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);
  urt_rtde_session_consume(s, 2);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 12);

  // the same tick is never sent twice
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out), 0);
  free_session(s);
}

static void test_rtde_session__setup_is_accepted_after_pause(void **state) {
  uint8_t in[512], out[512];
  char types[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp"), out, sizeof out);
  rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  assert_int_equal(count_packages(s, 10), 10);
  rt_exchange(s, in, rt_pkg(in, 'P', NULL, 0), out, sizeof out);
  assert_int_equal(count_packages(s, 10), 0);
  size_t k = rt_exchange(s, in, rt_pkg_names(in, 'I', "speed_slider_mask,speed_slider_fraction"),
                         out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  assert_int_equal(out[3], 1);
  assert_int_equal(count_packages(s, 10), 10);
  free_session(s);
}

static void test_rtde_session__encode_returns_enospc_when_cap_is_short(void **state) {
  uint8_t in[256], out[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  rt_exchange(s, in, rt_pkg_outputs(in, 500, "timestamp,actual_q"), out, sizeof out);
  rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, 59), URT_ENOSPC);
  assert_int_equal(urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, 60), 60);
  free_session(s);
}

//---- registers ----

static void test_rtde_session__registers_are_read_from_the_bank(void **state) {
  uint8_t in[512], out[512];
  char types[256];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  size_t k = rt_exchange(s, in,
                         rt_pkg_outputs(in, 500,
                                        "output_int_register_2,output_double_register_47,"
                                        "output_bit_register_64,output_bit_registers0_to_31,"
                                        "input_int_register_24,input_bit_registers32_to_63"),
                         out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  assert_string_equal(types, "INT32,DOUBLE,BOOL,UINT32,INT32,UINT32");
  rt_exchange(s, in, rt_pkg(in, 'S', NULL, 0), out, sizeof out);
  g_regs.out_int[2] = -2;
  g_regs.out_double[47] = 1.5;
  g_regs.out_bit[64] = 1;
  g_regs.out_bit[0] = 1;
  g_regs.out_bit[31] = 1;
  g_regs.in_int[24] = 7;
  g_regs.in_bit[33] = 1;
  int len = urt_rtde_session_encode_data(s, &g_snap, &g_regs, out, sizeof out);
  static const uint8_t want[] = {0, 29, 'U', 1, 0xff, 0xff, 0xff, 0xfe, 0x3f, 0xf8, 0, 0, 0, 0,
                                 0,  0, 1, 0x80, 0, 0, 1, 0, 0, 0, 7, 0, 0, 0, 2};
  expect_bytes(out, (size_t)len, want, sizeof want);
  free_session(s);
}

//---- input recipes and ownership ----

static void test_rtde_session__input_recipe_ids_count_from_1_per_connection(void **state) {
  uint8_t in[1024], out[1024];
  char types[1024];
  urt_rtde_session_t *a = new_session(5, 19, 0);
  urt_rtde_session_t *b = new_session(5, 19, 0);
  negotiate_v2(a);
  rt_exchange(a, in, rt_pkg_outputs(in, 500, "timestamp"), out, sizeof out);  /* output id 1 */

  // 23 overlapping recipes, as ur_rtde's control interface registers them
  for (int id = 1; id <= 23; id++) {
    char names[512];
    int n = snprintf(names, sizeof names, "input_int_register_0,");
    for (int d = 0; d < id % 18; d++) {
      n += snprintf(names + n, sizeof names - n, "input_double_register_%d,", d);
    }
    if (id == 23) {
      snprintf(names + n, sizeof names - n, "external_force_torque,");
    }
    size_t k = rt_exchange(a, in, rt_pkg_names(in, 'I', names), out, sizeof out);
    assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), id);
  }

  // a second connection's recipes also start at 1 (on inputs nobody owns)
  size_t k = rt_exchange(b, in, rt_pkg_names(in, 'I', "input_int_register_23,"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  free_session(a);
  free_session(b);
}

static void test_rtde_session__claimed_input_is_in_use_for_other_connections(void **state) {
  uint8_t in[512], out[512];
  char types[256];
  urt_rtde_session_t *a = new_session(5, 19, 0);
  urt_rtde_session_t *b = new_session(5, 19, 0);
  size_t k = rt_exchange(a, in,
                         rt_pkg_names(in, 'I', "speed_slider_mask,speed_slider_fraction"), out,
                         sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);

  // the other connection gets IN_USE (id 0) for the held names only
  k = rt_exchange(b, in, rt_pkg_names(in, 'I', "speed_slider_fraction,input_int_register_1"), out,
                  sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "IN_USE,INT32");
  // nothing was claimed by the failed recipe, and its id was not used up
  k = rt_exchange(b, in, rt_pkg_names(in, 'I', "input_int_register_1,bogus"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "INT32,NOT_FOUND");
  k = rt_exchange(b, in, rt_pkg_names(in, 'I', "input_int_register_1"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);

  // the owner can reuse its own inputs in another recipe
  k = rt_exchange(a, in, rt_pkg_names(in, 'I', "speed_slider_mask,speed_slider_fraction"), out,
                  sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 2);

  // closing the owner releases its claims
  free_session(a);
  k = rt_exchange(b, in, rt_pkg_names(in, 'I', "speed_slider_fraction"), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 2);
  assert_string_equal(types, "DOUBLE");
  free_session(b);
  assert_int_equal(g_reg.nsessions, 0);
}

static void test_rtde_session__inputs_are_decoded_with_masks(void **state) {
  uint8_t in[512], out[512];
  char types[512];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  size_t k = rt_exchange(
      s, in,
      rt_pkg_names(in, 'I',
                   "standard_digital_output_mask,standard_digital_output,"
                   "standard_analog_output_mask,standard_analog_output_type,"
                   "standard_analog_output_0,standard_analog_output_1,input_int_register_5,"
                   "input_double_register_30,input_bit_registers32_to_63,input_bit_register_127,"
                   "external_force_torque"),
      out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 1);
  assert_string_equal(types,
                      "UINT8,UINT8,UINT8,UINT8,DOUBLE,DOUBLE,INT32,DOUBLE,UINT32,BOOL,VECTOR6D");

  // DO 3 on (mask 8 value 8, plus DO 0 in the value but not in the mask), AO 1 at 0.25 V
  uint8_t p[256];
  size_t n = 0;
  p[n++] = 1;
  p[n++] = 8;
  p[n++] = 9;
  p[n++] = 2;
  p[n++] = 2;
  const double d[] = {0.75, 0.25};
  for (int i = 0; i < 2; i++) {
    uint64_t u;
    memcpy(&u, &d[i], 8);
    for (int j = 0; j < 8; j++) {
      p[n++] = (uint8_t)(u >> (56 - 8 * j));
    }
  }
  p[n++] = 0xff; p[n++] = 0xff; p[n++] = 0xff; p[n++] = 0xfb;  /* -5 */
  memset(p + n, 0, 8); p[n] = 0x40; n += 8;                    /* 2.0 */
  p[n++] = 0x80; p[n++] = 0; p[n++] = 0; p[n++] = 1;           /* bits 32 and 63 */
  p[n++] = 1;                                                  /* bit 127 */
  memset(p + n, 0, 48); p[n] = 0x3f; p[n + 1] = 0xf0; n += 48; /* fx = 1.0 */
  k = rt_exchange(s, in, rt_pkg(in, 'U', p, n), out, sizeof out);
  assert_int_equal(k, 0);
  assert_int_equal(s->stats.inputs, 1);

  urt_rtde_inputs_t e;
  assert_true(urt_rtde_session_take_inputs(s, &e));
  assert_int_equal(e.std_do_mask, 8);
  assert_int_equal(e.std_do, 8);
  assert_int_equal(e.ao_mask, 2);
  assert_int_equal(e.ao_type, 2);
  assert_true(e.ao[1] == 0.25);
  assert_true(e.int_set == 1ull << 5 && e.int_reg[5] == -5);
  assert_true(e.double_set == 1ull << 30 && e.double_reg[30] == 2.0);
  assert_true(e.bit_set[0] == 0xffffffff00000000ull);
  assert_true(e.bit_val[0] == ((1ull << 32) | (1ull << 63)));
  assert_true(e.bit_set[1] == 1ull << 63 && e.bit_val[1] == 1ull << 63);
  assert_true((e.set & URT_RTDE_IN_EXT_FT) && e.external_force_torque[0] == 1.0);
  assert_false(e.set & URT_RTDE_IN_SPEED_SLIDER);

  // the register part lands in the bank, where the outputs read it back
  urt_rtde_inputs_apply_registers(&e, &g_regs);
  assert_int_equal(g_regs.in_int[5], -5);
  assert_true(g_regs.in_double[30] == 2.0);
  assert_int_equal(g_regs.in_bit[32], 1);
  assert_int_equal(g_regs.in_bit[33], 0);
  assert_int_equal(g_regs.in_bit[63], 1);
  assert_int_equal(g_regs.in_bit[127], 1);
  free_session(s);
}

static void test_rtde_session__inputs_merge_in_order(void **state) {
  urt_rtde_inputs_t a, b;
  memset(&a, 0, sizeof a);
  memset(&b, 0, sizeof b);
  a.std_do_mask = 0x0f;
  a.std_do = 0x05;
  a.int_set = 1;
  a.int_reg[0] = 1;
  b.std_do_mask = 0x03;
  b.std_do = 0x02;
  b.int_set = 3;
  b.int_reg[0] = 2;
  b.int_reg[1] = 3;
  b.set = URT_RTDE_IN_SPEED_SLIDER;
  b.speed_slider_fraction = 0.3;
  urt_rtde_inputs_merge(&a, &b);
  assert_int_equal(a.std_do_mask, 0x0f);
  assert_int_equal(a.std_do, 0x06);
  assert_int_equal(a.int_reg[0], 2);
  assert_int_equal(a.int_reg[1], 3);
  assert_true(a.set & URT_RTDE_IN_SPEED_SLIDER);
}

static void test_rtde_session__bad_input_packages_are_dropped_and_counted(void **state) {
  uint8_t in[64], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  rt_exchange(s, in, rt_pkg_names(in, 'I', "input_int_register_0"), out, sizeof out);
  static const uint8_t bad[][6] = {
      {0},                        /* no recipe id             */
      {0, 0, 0, 0, 1},            /* id 0                     */
      {2, 0, 0, 0, 1},            /* id never handed out      */
      {1, 0, 0, 1},               /* too short                */
      {1, 0, 0, 0, 1, 9},         /* too long                 */
  };
  static const size_t len[] = {0, 5, 5, 4, 6};
  for (int i = 0; i < 5; i++) {
    assert_int_equal(rt_exchange(s, in, rt_pkg(in, 'U', bad[i], len[i]), out, sizeof out), 0);
  }
  assert_int_equal(s->stats.bad_input, 5);
  urt_rtde_inputs_t e;
  assert_false(urt_rtde_session_take_inputs(s, &e));
  assert_false(urt_rtde_session_closed(s));
  free_session(s);
}

static void test_rtde_session__inputs_apply_without_start(void **state) {
  /* ur_rtde's IO interface never sends S */
  uint8_t in[64], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  rt_exchange(s, in, rt_pkg_names(in, 'I', "input_int_register_23,speed_slider_mask,"
                                           "speed_slider_fraction"), out, sizeof out);
  static const uint8_t u[] = {1, 0, 0, 0, 22, 0, 0, 0, 1, 0x3f, 0xe0, 0, 0, 0, 0, 0, 0};
  rt_exchange(s, in, rt_pkg(in, 'U', u, sizeof u), out, sizeof out);
  urt_rtde_inputs_t e;
  assert_true(urt_rtde_session_take_inputs(s, &e));
  assert_true(e.set & URT_RTDE_IN_SPEED_SLIDER);
  assert_int_equal(e.int_reg[23], 22);
  free_session(s);
}

//---- malformed packages ----

static void test_rtde_session__size_below_3_closes(void **state) {
  for (int size = 0; size < 3; size++) {
    urt_rtde_session_t *s = new_session(5, 19, 0);
    uint8_t b[3] = {0, (uint8_t)size, 'V'};
    assert_int_equal(urt_rtde_session_feed(s, b, 3), URT_EPROTO);
    assert_true(urt_rtde_session_closed(s));
    assert_int_equal(s->error, URT_EPROTO);
    assert_int_equal(urt_rtde_session_feed(s, b, 3), URT_EPROTO);
    free_session(s);
  }
}

static void test_rtde_session__oversize_package_closes(void **state) {
  urt_rtde_session_t *s = new_session(5, 19, 0);
  uint8_t b[3] = {(URT_RTDE_MAX_PACKAGE + 1) >> 8, (URT_RTDE_MAX_PACKAGE + 1) & 0xff, 'O'};
  assert_int_equal(urt_rtde_session_feed(s, b, 3), URT_EPROTO);
  assert_true(urt_rtde_session_closed(s));
  free_session(s);
}

static void test_rtde_session__unknown_type_is_skipped(void **state) {
  uint8_t in[64], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  size_t n = rt_pkg(in, 'x', "abc", 3);
  n += rt_pkg(in + n, 0, NULL, 0);
  n += rt_pkg(in + n, 'v', NULL, 0);
  size_t k = rt_exchange(s, in, n, out, sizeof out);
  assert_int_equal(k, 19);  /* only the v reply */
  assert_int_equal(s->stats.unknown_type, 2);
  assert_false(urt_rtde_session_closed(s));
  free_session(s);
}

static void test_rtde_session__truncated_package_waits_for_the_rest(void **state) {
  uint8_t in[64], out[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  size_t n = rt_pkg(in, 'V', "\x00\x02", 2);
  assert_int_equal(rt_exchange(s, in, n - 1, out, sizeof out), 0);
  assert_int_equal(rt_exchange(s, in + n - 1, 1, out, sizeof out), 4);
  free_session(s);
}

static void test_rtde_session__short_or_empty_setup_is_refused(void **state) {
  uint8_t in[64], out[64];
  char types[64];
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  static const uint8_t short_freq[] = {0x40, 0x7f, 0x40};
  size_t k = rt_exchange(s, in, rt_pkg(in, 'O', short_freq, 3), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "");
  k = rt_exchange(s, in, rt_pkg_outputs(in, 500, ""), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  k = rt_exchange(s, in, rt_pkg_names(in, 'I', ","), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "");
  free_session(s);
}

static void test_rtde_session__too_many_fields_are_refused(void **state) {
  static uint8_t in[URT_RTDE_MAX_PACKAGE], out[64];
  char names[URT_RTDE_MAX_PACKAGE];
  char types[64];
  size_t n = 0;
  for (int i = 0; i <= URT_RTDE_MAX_FIELDS; i++) {
    n += (size_t)snprintf(names + n, sizeof names - n, "payload,");
  }
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  size_t k = rt_exchange(s, in, rt_pkg_outputs(in, 500, names), out, sizeof out);
  assert_int_equal(rt_reply_types(out, k, 1, types, sizeof types), 0);
  assert_string_equal(types, "");
  free_session(s);
}

static void test_rtde_session__full_reply_queue_applies_back_pressure(void **state) {
  /* a client that sends many setups and never reads: the session stops taking bytes */
  static uint8_t in[1 << 16];
  char names[2048];
  size_t nn = 0;
  for (int i = 0; i < 100; i++) {
    nn += (size_t)snprintf(names + nn, sizeof names - nn, "target_q,");
  }
  size_t n = 0;
  for (int i = 0; i < 20; i++) {
    n += rt_pkg_names(in + n, 'I', "input_int_register_0,");
    n += rt_pkg_outputs(in + n, 500, names);
  }
  urt_rtde_session_t *s = new_session(5, 19, 0);
  negotiate_v2(s);
  long used = urt_rtde_session_feed(s, in, n);
  assert_true(used > 0 && (size_t)used < n);
  const uint8_t *p;
  assert_true(urt_rtde_session_output(s, &p) <= URT_RTDE_REPLY_CAP);

  // draining lets it go on, and in the end every request is answered once
  size_t off = (size_t)used;
  int replies = 0;
  while (off < n || urt_rtde_session_output(s, &p) > 0) {
    size_t k = urt_rtde_session_output(s, &p);
    for (size_t i = 0; i < k; i += (size_t)(p[i] << 8 | p[i + 1])) {
      replies++;
    }
    urt_rtde_session_consume(s, k);
    long u = urt_rtde_session_feed(s, in + off, n - off);
    assert_true(u >= 0);
    off += (size_t)u;
  }
  assert_int_equal(replies, 40);
  assert_int_equal(s->n_in, 20);
  free_session(s);
}

//---- chunking ----

static void test_rtde_session__any_chunking_gives_the_same_replies(void **state) {
  uint8_t in[512], out[512];
  size_t n = example_client_stream(in);
  static const uint8_t u_pkg[] = {0x00, 0x10, 0x55, 0x01, 0, 0, 0, 1, 0x3F, 0xE0, 0, 0, 0, 0, 0, 0};
  memcpy(in + n, u_pkg, sizeof u_pkg);
  n += sizeof u_pkg;

  // split in two at every byte boundary
  for (size_t cut = 0; cut <= n; cut++) {
    urt_rtde_registry_init(&g_reg);
    urt_rtde_session_t *s = new_session(5, 19, 0);
    size_t k = rt_exchange(s, in, cut, out, sizeof out);
    k += rt_exchange(s, in + cut, n - cut, out + k, sizeof out - k);
    expect_bytes(out, k, k_example_replies, sizeof k_example_replies);
    urt_rtde_inputs_t e;
    assert_true(urt_rtde_session_take_inputs(s, &e));
    assert_true(e.speed_slider_fraction == 0.5);
    free_session(s);
  }

  // one byte at a time, and random chunks
  for (int rep = 0; rep < 200; rep++) {
    urt_rtde_registry_init(&g_reg);
    urt_rtde_session_t *s = new_session(5, 19, 0);
    size_t k = 0, off = 0;
    srand((unsigned)rep);
    while (off < n) {
      size_t c = rep == 0 ? 1 : 1 + (size_t)rand() % 17;
      c = c > n - off ? n - off : c;
      k += rt_exchange(s, in + off, c, out + k, sizeof out - k);
      off += c;
    }
    expect_bytes(out, k, k_example_replies, sizeof k_example_replies);
    free_session(s);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_rtde_session__v2_handshake_matches_the_worked_example, setup),
      cmocka_unit_test_setup(test_rtde_session__v1_handshake_has_no_output_recipe_id, setup),
      cmocka_unit_test_setup(test_rtde_session__protocol_version_other_than_1_or_2_is_refused, setup),
      cmocka_unit_test_setup(test_rtde_session__v_reply_is_16_bytes_every_time, setup),
      cmocka_unit_test_setup(test_rtde_session__text_message_from_client_gets_no_reply, setup),
      cmocka_unit_test_setup(test_rtde_session__unknown_output_is_not_found_and_start_is_refused, setup),
      cmocka_unit_test_setup(test_rtde_session__trailing_comma_is_ignored, setup),
      cmocka_unit_test_setup(test_rtde_session__illegal_frequency_gives_recipe_id_0, setup),
      cmocka_unit_test_setup(test_rtde_session__frequency_decimates_the_controller_rate, setup),
      cmocka_unit_test_setup(test_rtde_session__no_data_before_the_start_reply_is_drained, setup),
      cmocka_unit_test_setup(test_rtde_session__setup_is_accepted_after_pause, setup),
      cmocka_unit_test_setup(test_rtde_session__encode_returns_enospc_when_cap_is_short, setup),
      cmocka_unit_test_setup(test_rtde_session__registers_are_read_from_the_bank, setup),
      cmocka_unit_test_setup(test_rtde_session__input_recipe_ids_count_from_1_per_connection, setup),
      cmocka_unit_test_setup(test_rtde_session__claimed_input_is_in_use_for_other_connections, setup),
      cmocka_unit_test_setup(test_rtde_session__inputs_are_decoded_with_masks, setup),
      cmocka_unit_test_setup(test_rtde_session__inputs_merge_in_order, setup),
      cmocka_unit_test_setup(test_rtde_session__bad_input_packages_are_dropped_and_counted, setup),
      cmocka_unit_test_setup(test_rtde_session__inputs_apply_without_start, setup),
      cmocka_unit_test_setup(test_rtde_session__size_below_3_closes, setup),
      cmocka_unit_test_setup(test_rtde_session__oversize_package_closes, setup),
      cmocka_unit_test_setup(test_rtde_session__unknown_type_is_skipped, setup),
      cmocka_unit_test_setup(test_rtde_session__truncated_package_waits_for_the_rest, setup),
      cmocka_unit_test_setup(test_rtde_session__short_or_empty_setup_is_refused, setup),
      cmocka_unit_test_setup(test_rtde_session__too_many_fields_are_refused, setup),
      cmocka_unit_test_setup(test_rtde_session__full_reply_queue_applies_back_pressure, setup),
      cmocka_unit_test_setup(test_rtde_session__any_chunking_gives_the_same_replies, setup),
  };
  return cmocka_run_group_tests_name("net/rtde/rtde_session", tests, NULL, NULL);
}
