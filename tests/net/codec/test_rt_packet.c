/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/test_rt_packet.c — the port 30003 packet (net/codec/rt_packet.c). */
#include <string.h>

#include "codec_fixture.h"
#include "test_support.h"
#include "urt/net/rt_packet.h"

static urt_version_t ver(const char *text) {
  urt_version_t v;
  assert_int_equal(urt_version_parse(text, &v), 0);
  return v;
}

/* Assert n doubles at off equal x. */
static void assert_f64s(const uint8_t *b, size_t off, const double *x, int n) {
  for (int j = 0; j < n; j++) {
    if (rd_f64(b + off + 8 * j) != x[j]) {
      fail_msg("offset %zu + 8·%d: %.17g != %.17g", off, j, rd_f64(b + off + 8 * j), x[j]);
    }
  }
}

static void test_rt_packet_encode__size_per_version(void **state) {
  static const struct {
    const char *v;
    size_t size;
  } cases[] = {{"3.0", 1044}, {"3.1", 1044}, {"3.2", 1060}, {"3.4", 1060}, {"3.5", 1108},
               {"3.9", 1108}, {"5.0", 1108}, {"5.3", 1108}, {"3.10", 1116}, {"5.4", 1116},
               {"5.19", 1116}};
  urt_snapshot_t s;
  fixture_snapshot(&s);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    urt_version_t v = ver(cases[i].v);
    uint8_t buf[URT_RT_PACKET_MAX + 16];
    assert_int_equal(urt_rt_packet_encode(&v, &s, buf, sizeof buf), cases[i].size);
    assert_int_equal(rd_i32(buf), (int32_t)cases[i].size);
  }
}

static void test_rt_packet_encode__every_field_at_its_offset(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  urt_version_t v = ver("5.19");
  uint8_t b[URT_RT_PACKET_MAX];
  assert_int_equal(urt_rt_packet_encode(&v, &s, b, sizeof b), 1116);

  assert_true(rd_f64(b + URT_RT_OFF_TIME) == 12.5);
  assert_f64s(b, 12, s.q_target, 6);
  assert_f64s(b, 60, s.qd_target, 6);
  assert_f64s(b, 108, s.qdd_target, 6);
  assert_f64s(b, 156, s.i_target, 6);
  assert_f64s(b, 204, s.m_target, 6);
  assert_f64s(b, 252, s.q, 6);
  assert_f64s(b, 300, s.qd, 6);
  assert_f64s(b, 348, s.i_actual, 6);
  assert_f64s(b, 396, s.i_control, 6);
  assert_f64s(b, 444, s.tcp_pose, 6);
  assert_f64s(b, 492, s.tcp_speed, 6);
  assert_f64s(b, 540, s.tcp_force, 6);
  assert_f64s(b, 588, s.tcp_pose_target, 6);
  assert_f64s(b, 636, s.tcp_speed_target, 6);
  assert_true(rd_f64(b + 684) == 5.0);  /* digital inputs as the bit mask's value */
  assert_f64s(b, 692, s.temperature, 6);
  assert_true(rd_f64(b + 740) == s.exec_time);
  assert_true(rd_f64(b + 748) == 0.0);
  assert_true(rd_f64(b + 756) == 7.0);
  for (int j = 0; j < 6; j++) {
    assert_true(rd_f64(b + 764 + 8 * j) == 253.0);
  }
  assert_true(rd_f64(b + 812) == 1.0);
  for (size_t off = 820; off < 868; off += 8) {
    assert_true(rd_f64(b + off) == 0.0);
  }
  assert_f64s(b, 868, s.tool_accel, 3);
  for (size_t off = 892; off < 940; off += 8) {
    assert_true(rd_f64(b + off) == 0.0);
  }
  assert_true(rd_f64(b + 940) == 0.8);
  assert_true(rd_f64(b + 948) == 0.0);
  assert_true(rd_f64(b + 956) == 0.0 && rd_f64(b + 964) == 0.0);
  assert_true(rd_f64(b + 972) == 48.5);
  assert_true(rd_f64(b + 980) == 48.25);
  assert_true(rd_f64(b + 988) == 1.75);
  assert_f64s(b, 996, s.v_actual, 6);
  assert_true(rd_f64(b + 1044) == (double)0x30002);
  assert_true(rd_f64(b + 1052) == 2.0);
  assert_f64s(b, 1060, s.elbow_pos, 3);
  assert_f64s(b, 1084, s.elbow_vel, 3);
  assert_true(rd_f64(b + 1108) == 1.0);
}

static void test_rt_packet_encode__older_layouts_are_prefixes(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  urt_version_t newest = ver("5.19");
  uint8_t full[URT_RT_PACKET_MAX];
  urt_rt_packet_encode(&newest, &s, full, sizeof full);
  const char *older[] = {"3.0", "3.3", "3.7", "5.2"};
  for (int i = 0; i < 4; i++) {
    urt_version_t v = ver(older[i]);
    uint8_t b[URT_RT_PACKET_MAX];
    size_t n = urt_rt_packet_encode(&v, &s, b, sizeof b);
    assert_int_equal(n, urt_version_rt_packet_size(&v));
    assert_memory_equal(b + 4, full + 4, n - 4);
  }
}

static void test_rt_packet_encode__returns_zero_when_cap_is_short(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  urt_version_t v = ver("3.3");
  uint8_t b[1200];
  memset(b, 0xAB, sizeof b);
  assert_int_equal(urt_rt_packet_encode(&v, &s, b, 1059), 0);
  for (size_t i = 0; i < sizeof b; i++) {
    assert_int_equal(b[i], 0xAB);
  }
  assert_int_equal(urt_rt_packet_encode(&v, &s, NULL, 0), 0);
  assert_int_equal(urt_rt_packet_encode(&v, &s, b, 1060), 1060);
  assert_int_equal(b[1060], 0xAB);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rt_packet_encode__size_per_version),
      cmocka_unit_test(test_rt_packet_encode__every_field_at_its_offset),
      cmocka_unit_test(test_rt_packet_encode__older_layouts_are_prefixes),
      cmocka_unit_test(test_rt_packet_encode__returns_zero_when_cap_is_short),
  };
  return cmocka_run_group_tests_name("net/codec/rt_packet", tests, NULL, NULL);
}
