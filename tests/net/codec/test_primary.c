/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/test_primary.c — primary/secondary messages (net/codec/primary.c). */
#include <math.h>
#include <string.h>

#include "codec_fixture.h"
#include "test_model.h"
#include "test_support.h"
#include "urt/errors.h"
#include "urt/net/primary.h"

static urt_model_t *g_model;

static int setup(void **state) {
  g_model = urt_test_model(NULL);
  return 0;
}

static int teardown(void **state) {
  urt_model_free(g_model);
  return 0;
}

static urt_version_t ver(const char *text) {
  urt_version_t v;
  assert_int_equal(urt_version_parse(text, &v), 0);
  return v;
}

typedef struct sub {
  int type;
  int size;
  const uint8_t *payload;  /* after the 5-byte header */
} sub_t;

/* Split a ROBOT_STATE into its sub-packages; fails the test if the framing is off. */
static int split(const uint8_t *b, int n, sub_t *out, int max) {
  assert_true(n >= 5);
  assert_int_equal(rd_i32(b), n);
  assert_int_equal(b[4], URT_PRIMARY_ROBOT_STATE);
  int k = 0;
  for (int off = 5; off < n;) {
    assert_true(off + 5 <= n);
    int size = (int)rd_u32(b + off);
    assert_true(size >= 5 && off + size <= n);
    assert_true(k < max);
    out[k].type = b[off + 4];
    out[k].size = size;
    out[k].payload = b + off + 5;
    k++;
    off += size;
  }
  return k;
}

static const sub_t *find(const sub_t *subs, int n, int type) {
  for (int i = 0; i < n; i++) {
    if (subs[i].type == type) {
      return &subs[i];
    }
  }
  fail_msg("sub-package %d missing", type);
  return NULL;
}

static int encode_state(const char *version, const urt_snapshot_t *s, uint8_t *buf, size_t cap,
                        urt_primary_robot_info_t *info) {
  urt_version_t v = ver(version);
  urt_primary_robot_info_from_model(&v, g_model, info);
  return urt_primary_encode_robot_state(&v, info, s, buf, cap);
}

//---- ROBOT_STATE ----

static void test_primary_robot_state__subpackage_sizes_per_version(void **state) {
  static const struct {
    const char *v;
    int n;
    int type[12], size[12];
  } cases[] = {
      {"3.0", 10, {0, 1, 4, 5, 9, 3, 2, 6, 7, 8}, {38, 251, 53, 225, 53, 72, 37, 445, 61, 8}},
      {"3.3", 10, {0, 1, 4, 5, 9, 3, 2, 6, 7, 8}, {46, 251, 101, 225, 53, 74, 37, 445, 61, 8}},
      {"3.13", 10, {0, 1, 4, 5, 9, 3, 2, 6, 7, 8}, {47, 251, 101, 225, 53, 74, 37, 445, 61, 8}},
      // 3.14+: MasterboardData at URCL's 70 bytes (its strict parser, CI on URSim 3.14.3)
      {"3.14", 10, {0, 1, 4, 5, 9, 3, 2, 6, 7, 8}, {47, 251, 101, 225, 53, 75, 37, 445, 61, 8}},
      {"3.15", 10, {0, 1, 4, 5, 9, 3, 2, 6, 7, 8}, {47, 251, 101, 225, 53, 75, 37, 445, 61, 8}},
      {"5.8",
       12,
       {0, 1, 4, 5, 9, 3, 2, 6, 7, 8, 11, 12},
       {47, 251, 101, 225, 53, 75, 37, 445, 61, 9, 26, 8}},
  };
  urt_snapshot_t s;
  fixture_snapshot(&s);
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    uint8_t b[4096];
    urt_primary_robot_info_t info;
    int n = encode_state(cases[c].v, &s, b, sizeof b, &info);
    assert_true(n > 0 && n <= URT_PRIMARY_MAX_MESSAGE);
    sub_t subs[16];
    int k = split(b, n, subs, 16);
    assert_int_equal(k, cases[c].n);
    urt_version_t v = ver(cases[c].v);
    for (int i = 0; i < k; i++) {
      assert_int_equal(subs[i].type, cases[c].type[i]);
      assert_int_equal(subs[i].size, cases[c].size[i]);
      assert_int_equal(urt_primary_subpackage_size(&v, subs[i].type), subs[i].size);
    }
  }
}

static void test_primary_robot_state__under_2000_bytes_for_every_version(void **state) {
  const char *versions[] = {"3.0", "3.1", "3.2", "3.4", "3.5", "3.9", "3.10", "3.15",
                            "5.0", "5.3", "5.4", "5.8", "5.19", "5.23"};
  urt_snapshot_t s;
  fixture_snapshot(&s);
  for (size_t i = 0; i < sizeof versions / sizeof versions[0]; i++) {
    uint8_t b[4096];
    urt_primary_robot_info_t info;
    int n = encode_state(versions[i], &s, b, sizeof b, &info);
    assert_true(n > 0 && n <= URT_PRIMARY_MAX_MESSAGE);
  }
}

static void test_primary_robot_state__robot_mode_fields(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  uint8_t b[4096];
  urt_primary_robot_info_t info;
  sub_t subs[16];
  int k = split(b, encode_state("3.3", &s, b, sizeof b, &info), subs, 16);
  const uint8_t *p = find(subs, k, 0)->payload;
  assert_int_equal(rd_u64(p), 12500000);  /* 12.5 s in µs */
  const uint8_t expect_bools[7] = {1, 1, 1, 0, 0, 1, 0};
  assert_memory_equal(p + 8, expect_bools, 7);
  assert_int_equal((int8_t)p[15], 7);
  assert_int_equal(p[16], 0);
  assert_true(rd_f64(p + 17) == 0.9);
  assert_true(rd_f64(p + 25) == 0.8);
  assert_true(rd_f64(p + 33) == 1.0);

  // power off, protective stop, paused
  s.robot_mode = URT_ROBOT_MODE_POWER_OFF;
  s.safety_mode = URT_SAFETY_MODE_PROTECTIVE_STOP;
  s.program_state = URT_PROGRAM_PAUSED;
  k = split(b, encode_state("5.19", &s, b, sizeof b, &info), subs, 16);
  p = find(subs, k, 0)->payload;
  const uint8_t expect2[7] = {1, 1, 0, 0, 1, 0, 1};
  assert_memory_equal(p + 8, expect2, 7);
  assert_int_equal((int8_t)p[15], 3);
  assert_int_equal(p[41], 0);  /* reserved byte of 3.5+/5.x */
}

static void test_primary_robot_state__joint_cartesian_masterboard_fields(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  uint8_t b[4096];
  urt_primary_robot_info_t info;
  sub_t subs[16];
  int k = split(b, encode_state("5.19", &s, b, sizeof b, &info), subs, 16);

  // joint data: 6 × (q, q_target, qd, I, V, T, T_micro, mode)
  const uint8_t *p = find(subs, k, 1)->payload;
  for (int j = 0; j < 6; j++, p += 41) {
    assert_true(rd_f64(p) == s.q[j]);
    assert_true(rd_f64(p + 8) == s.q_target[j]);
    assert_true(rd_f64(p + 16) == s.qd[j]);
    assert_true(rd_f32(p + 24) == (float)s.i_actual[j]);
    assert_true(rd_f32(p + 28) == (float)s.v_actual[j]);
    assert_true(rd_f32(p + 32) == (float)s.temperature[j]);
    assert_true(rd_f32(p + 36) == 0.0f);
    assert_int_equal(p[40], 253);
  }

  // cartesian info: pose then TCP offset
  p = find(subs, k, 4)->payload;
  for (int i = 0; i < 6; i++) {
    assert_true(rd_f64(p + 8 * i) == s.tcp_pose[i]);
    assert_true(rd_f64(p + 48 + 8 * i) == s.tcp_offset[i]);
  }

  // masterboard: bits, analog outputs, voltage, safety mode
  p = find(subs, k, 3)->payload;
  assert_int_equal(rd_u32(p), 5);
  assert_int_equal(rd_u32(p + 4), 0x30002);
  assert_true(rd_f64(p + 28) == 0.25);
  assert_true(rd_f64(p + 36) == 0.75);
  assert_true(rd_f32(p + 48) == 48.25f);
  assert_true(rd_f32(p + 52) == 1.75f);
  assert_int_equal(p[60], 1);  /* safety mode */

  // force mode: the TCP wrench
  p = find(subs, k, 7)->payload;
  for (int i = 0; i < 6; i++) {
    assert_true(rd_f64(p + 8 * i) == s.tcp_force[i]);
  }
}

static void test_primary_robot_state__kinematics_and_configuration_from_the_model(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  uint8_t b[4096];
  urt_primary_robot_info_t info;
  sub_t subs[16];
  int k = split(b, encode_state("5.19", &s, b, sizeof b, &info), subs, 16);

  // kinematics: checksums, θ, a, d, α, status
  const uint8_t *p = find(subs, k, 5)->payload;
  for (int j = 0; j < 6; j++) {
    const urt_link_params_t *l = &g_model->arm.link[j];
    assert_int_equal(rd_u32(p + 4 * j), info.checksum[j]);
    assert_true(rd_f64(p + 24 + 8 * j) == l->theta);
    assert_true(rd_f64(p + 72 + 8 * j) == l->a);
    assert_true(rd_f64(p + 120 + 8 * j) == l->d);
    assert_true(rd_f64(p + 168 + 8 * j) == l->alpha);
  }
  assert_int_equal(rd_u32(p + 216), 0);

  // configuration: limits, defaults, DH (a, d, α, θ), identity
  p = find(subs, k, 6)->payload;
  for (int j = 0; j < 6; j++) {
    assert_true(rd_f64(p + 16 * j) == g_model->joint[j].q_min);
    assert_true(rd_f64(p + 16 * j + 8) == g_model->joint[j].q_max);
    assert_true(rd_f64(p + 96 + 16 * j) == g_model->joint[j].qd_max);
    assert_true(rd_f64(p + 96 + 16 * j + 8) == g_model->joint[j].qdd_max);
    assert_true(rd_f64(p + 232 + 8 * j) == g_model->arm.link[j].a);
    assert_true(rd_f64(p + 280 + 8 * j) == g_model->arm.link[j].d);
    assert_true(rd_f64(p + 328 + 8 * j) == g_model->arm.link[j].alpha);
    assert_true(rd_f64(p + 376 + 8 * j) == g_model->arm.link[j].theta);
  }
  assert_near(rd_f64(p + 192), 1.0471975511965976, 0);
  assert_true(rd_f64(p + 224) == 0.25);
  assert_int_equal(rd_i32(p + 424), 6);
  assert_int_equal(rd_i32(p + 428), 4);
  assert_int_equal(rd_i32(p + 432), 1);  /* UR5 */
  assert_int_equal(rd_i32(p + 436), 3);
}

static void test_primary_kinematics_checksum__follows_the_dh_values(void **state) {
  urt_version_t v = ver("5.19");
  urt_primary_robot_info_t a, b;
  urt_primary_robot_info_from_model(&v, g_model, &a);
  urt_primary_robot_info_from_model(&v, g_model, &b);
  assert_memory_equal(a.checksum, b.checksum, sizeof a.checksum);
  b.dh_d[2] += 1e-6;
  urt_primary_kinematics_checksum(&b);
  for (int j = 0; j < 6; j++) {
    if (j == 2) {
      assert_int_not_equal(a.checksum[j], b.checksum[j]);
    } else {
      assert_int_equal(a.checksum[j], b.checksum[j]);
    }
  }
}

static void test_primary_robot_state__returns_enospc_when_cap_is_short(void **state) {
  urt_snapshot_t s;
  fixture_snapshot(&s);
  uint8_t b[2100];
  urt_primary_robot_info_t info;
  int full = encode_state("5.19", &s, b, sizeof b, &info);
  assert_true(full > 0);
  urt_version_t v = ver("5.19");
  for (int cap = 0; cap < full; cap++) {
    memset(b, 0xCD, sizeof b);
    assert_int_equal(urt_primary_encode_robot_state(&v, &info, &s, b, (size_t)cap), URT_ENOSPC);
    for (size_t i = (size_t)cap; i < sizeof b; i++) {
      if (b[i] != 0xCD) {
        fail_msg("cap %d: byte %zu written", cap, i);
      }
    }
  }
}

//---- ROBOT_MESSAGE ----

static void test_primary_encode_version__golden_bytes(void **state) {
  urt_version_t v = ver("5.19");
  uint8_t b[128];
  static const uint8_t expect[] = {
      0x00, 0x00, 0x00, 46, 20,                          /* size, ROBOT_MESSAGE        */
      0, 0, 0, 0, 0, 0, 0x30, 0x39,                      /* timestamp 12345 µs         */
      0xFE, 3,                                           /* source −2, VERSION         */
      9, 'U', 'R', 'C', 'o', 'n', 't', 'r', 'o', 'l',    /* project name               */
      5, 19,                                             /* major, minor               */
      0, 0, 0, 0,                                        /* bugfix                     */
      0x00, 0x12, 0x79, 0x07,                            /* build 1210631              */
      'O', 'c', 't', ' ', '2', '3', ' ', '2', '0', '2', '4'};
  assert_int_equal(urt_primary_encode_version(&v, 12345, b, sizeof b), sizeof expect);
  assert_memory_equal(b, expect, sizeof expect);
  for (size_t cap = 0; cap < sizeof expect; cap++) {
    assert_int_equal(urt_primary_encode_version(&v, 12345, b, cap), URT_ENOSPC);
  }
}

static void test_primary_encode_key__title_and_text(void **state) {
  uint8_t b[256];
  int n = urt_primary_encode_key(7, URT_PRIMARY_SOURCE_ROBOT_INTERFACE, 0, 0,
                                 "PROGRAM_XXX_STARTED", "script_1", b, sizeof b);
  assert_int_equal(n, 5 + 10 + 4 + 4 + 1 + 19 + 8);
  assert_int_equal(rd_i32(b), n);
  assert_int_equal(b[4], 20);
  assert_int_equal(rd_u64(b + 5), 7);
  assert_int_equal((int8_t)b[13], -2);
  assert_int_equal(b[14], URT_PRIMARY_MSG_KEY);
  assert_int_equal(rd_i32(b + 15), 0);
  assert_int_equal(rd_i32(b + 19), 0);
  assert_int_equal(b[23], 19);
  assert_memory_equal(b + 24, "PROGRAM_XXX_STARTED", 19);
  assert_memory_equal(b + 43, "script_1", 8);

  char long_title[300];
  memset(long_title, 'A', sizeof long_title - 1);
  long_title[sizeof long_title - 1] = '\0';
  assert_int_equal(urt_primary_encode_key(0, -2, 0, 0, long_title, "", b, sizeof b), URT_EINVAL);
  assert_int_equal(urt_primary_encode_key(0, -2, 0, 0, "T", "x", b, 20), URT_ENOSPC);
}

static void test_primary_encode_popup__flags_title_text(void **state) {
  uint8_t b[256];
  int n = urt_primary_encode_popup(5, URT_PRIMARY_SOURCE_ROBOT_INTERFACE, 0, 0, false, true, true,
                                   "Error connecting", "check the PC", b, sizeof b);
  assert_int_equal(n, 15 + 4 + 4 + 3 + 1 + 16 + 12);
  assert_int_equal(rd_i32(b), n);
  assert_int_equal(b[4], 20);
  assert_int_equal(b[14], 2);
  assert_int_equal(rd_u32(b + 15), 0);
  assert_int_equal(rd_u32(b + 19), 0);
  assert_int_equal(b[23], 0);  // warning
  assert_int_equal(b[24], 1);  // error
  assert_int_equal(b[25], 1);  // blocking
  assert_int_equal(b[26], 16);
  assert_memory_equal(b + 27, "Error connecting", 16);
  assert_memory_equal(b + 43, "check the PC", 12);
  char long_title[300];
  memset(long_title, 'A', sizeof long_title - 1);
  long_title[sizeof long_title - 1] = '\0';
  assert_int_equal(urt_primary_encode_popup(0, -2, 0, 0, 0, 0, 0, long_title, "", b, sizeof b), URT_EINVAL);
  assert_int_equal(urt_primary_encode_popup(0, -2, 0, 0, 0, 0, 0, "T", "x", b, 20), URT_ENOSPC);
}

static void test_primary_encode_runtime_exception__line_column_text(void **state) {
  uint8_t b[128];
  const char *text = "compile_error_name_not_found:foo:";
  int n = urt_primary_encode_runtime_exception(9, URT_PRIMARY_SOURCE_RT_MACHINE, 12, 3, text, b,
                                               sizeof b);
  assert_int_equal(n, 15 + 8 + (int)strlen(text));
  assert_int_equal((int8_t)b[13], -3);
  assert_int_equal(b[14], 10);
  assert_int_equal(rd_u32(b + 15), 12);
  assert_int_equal(rd_u32(b + 19), 3);
  assert_memory_equal(b + 23, text, strlen(text));
}

static void test_primary_encode_error_code_and_safety_mode(void **state) {
  uint8_t b[128];
  int n = urt_primary_encode_error_code(1, URT_PRIMARY_SOURCE_CONTROLLER, 210, 0,
                                        URT_PRIMARY_REPORT_VIOLATION, 0, 0, "read-only", b,
                                        sizeof b);
  assert_int_equal(n, 15 + 20 + 9);
  assert_int_equal(b[14], 6);
  assert_int_equal(rd_i32(b + 15), 210);
  assert_int_equal(rd_i32(b + 23), 3);
  assert_memory_equal(b + 35, "read-only", 9);

  n = urt_primary_encode_safety_mode(1, URT_PRIMARY_SOURCE_RT_MACHINE, 209, 2,
                                     URT_SAFETY_MODE_PROTECTIVE_STOP, 1, 42, b, sizeof b);
  assert_int_equal(n, 15 + 4 + 4 + 1 + 4 + 4);
  assert_int_equal(b[14], 5);
  assert_int_equal(rd_i32(b + 15), 209);
  assert_int_equal(rd_i32(b + 19), 2);
  assert_int_equal(b[23], 3);
  assert_int_equal(rd_u32(b + 24), 1);
  assert_int_equal(rd_u32(b + 28), 42);

  n = urt_primary_encode_text(1, URT_PRIMARY_SOURCE_CONTROLLER, "hello", b, sizeof b);
  assert_int_equal(n, 20);
  assert_int_equal(b[14], 0);
  assert_memory_equal(b + 15, "hello", 5);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_primary_robot_state__subpackage_sizes_per_version),
      cmocka_unit_test(test_primary_robot_state__under_2000_bytes_for_every_version),
      cmocka_unit_test(test_primary_robot_state__robot_mode_fields),
      cmocka_unit_test(test_primary_robot_state__joint_cartesian_masterboard_fields),
      cmocka_unit_test(test_primary_robot_state__kinematics_and_configuration_from_the_model),
      cmocka_unit_test(test_primary_kinematics_checksum__follows_the_dh_values),
      cmocka_unit_test(test_primary_robot_state__returns_enospc_when_cap_is_short),
      cmocka_unit_test(test_primary_encode_version__golden_bytes),
      cmocka_unit_test(test_primary_encode_key__title_and_text),
      cmocka_unit_test(test_primary_encode_popup__flags_title_text),
      cmocka_unit_test(test_primary_encode_runtime_exception__line_column_text),
      cmocka_unit_test(test_primary_encode_error_code_and_safety_mode),
  };
  return cmocka_run_group_tests_name("net/codec/primary", tests, setup, teardown);
}
