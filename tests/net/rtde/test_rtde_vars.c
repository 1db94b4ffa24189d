/* SPDX-License-Identifier: Apache-2.0
 * tests/net/rtde/test_rtde_vars.c — the variable tables: names, types, version gates. */
#include <stdbool.h>
#include <string.h>

#include "rtde_test_util.h"
#include "test_support.h"
#include "urt/errors.h"

static int out_type(const char *name, urt_version_t v) {
  urt_rtde_field_t f;
  return urt_rtde_output_lookup(name, strlen(name), &v, &f) == 0 ? f.type : -1;
}

static int in_type(const char *name, urt_version_t v) {
  urt_rtde_field_t f;
  return urt_rtde_input_lookup(name, strlen(name), &v, &f) == 0 ? f.type : -1;
}

static void test_rtde_vars__type_tokens_and_sizes(void **state) {
  static const char *const names[] = {"BOOL", "UINT8", "UINT32", "UINT64", "INT32",
                                      "DOUBLE", "VECTOR3D", "VECTOR6D", "VECTOR6INT32",
                                      "VECTOR6UINT32"};
  static const size_t sizes[] = {1, 1, 4, 8, 4, 8, 24, 48, 24, 24};
  for (int t = 0; t < URT_RTDE_NTYPES; t++) {
    assert_string_equal(urt_rtde_type_name((urt_rtde_type_t)t), names[t]);
    assert_int_equal(urt_rtde_type_size((urt_rtde_type_t)t), sizes[t]);
  }
}

static void test_rtde_vars__every_client_default_output_exists_with_its_type(void **state) {
  /* ur_rtde receive defaults + version extras, ROS 2 driver recipe (protocols.md §2.7) */
  static const struct {
    const char *name;
    int type;
  } want[] = {
      {"timestamp", URT_RTDE_DOUBLE}, {"target_q", URT_RTDE_VECTOR6D},
      {"target_qd", URT_RTDE_VECTOR6D}, {"target_qdd", URT_RTDE_VECTOR6D},
      {"target_current", URT_RTDE_VECTOR6D}, {"target_moment", URT_RTDE_VECTOR6D},
      {"actual_q", URT_RTDE_VECTOR6D}, {"actual_qd", URT_RTDE_VECTOR6D},
      {"actual_current", URT_RTDE_VECTOR6D}, {"joint_control_output", URT_RTDE_VECTOR6D},
      {"actual_TCP_pose", URT_RTDE_VECTOR6D}, {"actual_TCP_speed", URT_RTDE_VECTOR6D},
      {"actual_TCP_force", URT_RTDE_VECTOR6D}, {"target_TCP_pose", URT_RTDE_VECTOR6D},
      {"target_TCP_speed", URT_RTDE_VECTOR6D}, {"actual_digital_input_bits", URT_RTDE_UINT64},
      {"joint_temperatures", URT_RTDE_VECTOR6D}, {"actual_execution_time", URT_RTDE_DOUBLE},
      {"robot_mode", URT_RTDE_INT32}, {"joint_mode", URT_RTDE_VECTOR6INT32},
      {"safety_mode", URT_RTDE_INT32}, {"safety_status", URT_RTDE_INT32},
      {"actual_tool_accelerometer", URT_RTDE_VECTOR3D}, {"speed_scaling", URT_RTDE_DOUBLE},
      {"target_speed_fraction", URT_RTDE_DOUBLE}, {"actual_momentum", URT_RTDE_DOUBLE},
      {"actual_main_voltage", URT_RTDE_DOUBLE}, {"actual_robot_voltage", URT_RTDE_DOUBLE},
      {"actual_robot_current", URT_RTDE_DOUBLE}, {"actual_joint_voltage", URT_RTDE_VECTOR6D},
      {"actual_digital_output_bits", URT_RTDE_UINT64}, {"runtime_state", URT_RTDE_UINT32},
      {"standard_analog_input0", URT_RTDE_DOUBLE}, {"standard_analog_input1", URT_RTDE_DOUBLE},
      {"standard_analog_output0", URT_RTDE_DOUBLE}, {"standard_analog_output1", URT_RTDE_DOUBLE},
      {"robot_status_bits", URT_RTDE_UINT32}, {"safety_status_bits", URT_RTDE_UINT32},
      {"analog_io_types", URT_RTDE_UINT32}, {"tool_mode", URT_RTDE_UINT32},
      {"tool_analog_input_types", URT_RTDE_UINT32}, {"tool_analog_input0", URT_RTDE_DOUBLE},
      {"tool_analog_input1", URT_RTDE_DOUBLE}, {"tool_output_voltage", URT_RTDE_INT32},
      {"tool_output_current", URT_RTDE_DOUBLE}, {"tool_temperature", URT_RTDE_DOUBLE},
      {"tcp_offset", URT_RTDE_VECTOR6D}, {"payload", URT_RTDE_DOUBLE},
      {"payload_cog", URT_RTDE_VECTOR3D}, {"payload_inertia", URT_RTDE_VECTOR6D},
      {"ft_raw_wrench", URT_RTDE_VECTOR6D}, {"actual_current_as_torque", URT_RTDE_VECTOR6D},
      {"elbow_position", URT_RTDE_VECTOR3D}, {"tool_output_mode", URT_RTDE_UINT8},
      {"output_int_register_0", URT_RTDE_INT32}, {"output_int_register_47", URT_RTDE_INT32},
      {"output_double_register_19", URT_RTDE_DOUBLE}, {"output_double_register_47", URT_RTDE_DOUBLE},
      {"output_bit_register_64", URT_RTDE_BOOL}, {"output_bit_register_127", URT_RTDE_BOOL},
      {"output_bit_registers0_to_31", URT_RTDE_UINT32},
      {"output_bit_registers32_to_63", URT_RTDE_UINT32},
      {"input_int_register_47", URT_RTDE_INT32}, {"input_double_register_0", URT_RTDE_DOUBLE},
      {"input_bit_register_100", URT_RTDE_BOOL}, {"input_bit_registers0_to_31", URT_RTDE_UINT32},
  };
  urt_version_t v = rt_version(5, 23, 0, 0);
  for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
    int t = out_type(want[i].name, v);
    if (t != want[i].type) {
      fail_msg("%s: type %d, want %d", want[i].name, t, want[i].type);
    }
  }
}

static void test_rtde_vars__unofficial_and_malformed_names_are_not_found(void **state) {
  urt_version_t v = rt_version(5, 25, 0, 0);
  static const char *const bad[] = {
      "actual_qdd", "actual_moment", "", "timestamp ", "Timestamp", "output_int_register_48",
      "output_int_register_", "output_int_register_01", "output_int_register_-1",
      "output_int_register_1000", "output_bit_register_63", "output_bit_register_0",
      "input_bit_register_128", "output_int_register_0x", "speed_slider_mask" /* input only */};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    if (out_type(bad[i], v) != -1) {
      fail_msg("output '%s' should be NOT_FOUND", bad[i]);
    }
  }
  static const char *const bad_in[] = {"timestamp", "output_int_register_0",
                                       "input_bit_register_63", "input_int_register_48",
                                       "payload"};
  for (size_t i = 0; i < sizeof bad_in / sizeof bad_in[0]; i++) {
    if (in_type(bad_in[i], v) != -1) {
      fail_msg("input '%s' should be NOT_FOUND", bad_in[i]);
    }
  }
}

static void test_rtde_vars__versions_gate_names(void **state) {
  // upper register ranges from 3.9 / 5.3
  assert_int_equal(out_type("output_int_register_24", rt_version(5, 2, 0, 0)), -1);
  assert_int_equal(out_type("output_int_register_24", rt_version(5, 3, 0, 0)), URT_RTDE_INT32);
  assert_int_equal(in_type("input_double_register_47", rt_version(3, 8, 0, 0)), -1);
  assert_int_equal(in_type("input_double_register_47", rt_version(3, 9, 0, 0)), URT_RTDE_DOUBLE);
  assert_int_equal(in_type("input_bit_register_64", rt_version(5, 2, 9, 0)), -1);
  assert_int_equal(in_type("input_int_register_23", rt_version(3, 4, 0, 0)), URT_RTDE_INT32);
  assert_int_equal(in_type("input_int_register_23", rt_version(3, 3, 0, 0)), -1);

  // outputs added over time
  assert_int_equal(out_type("payload", rt_version(5, 5, 0, 0)), -1);
  assert_int_equal(out_type("payload", rt_version(5, 5, 1, 0)), URT_RTDE_DOUBLE);
  assert_int_equal(out_type("payload_inertia", rt_version(5, 10, 0, 0)), -1);
  assert_int_equal(out_type("payload_inertia", rt_version(5, 11, 0, 0)), URT_RTDE_VECTOR6D);
  assert_int_equal(out_type("payload_inertia", rt_version(3, 15, 0, 0)), URT_RTDE_VECTOR6D);
  assert_int_equal(out_type("ft_raw_wrench", rt_version(5, 8, 0, 0)), -1);
  assert_int_equal(out_type("ft_raw_wrench", rt_version(5, 9, 0, 0)), URT_RTDE_VECTOR6D);
  assert_int_equal(out_type("ft_raw_wrench", rt_version(3, 15, 8, 0)), -1);
  assert_int_equal(out_type("actual_current_as_torque", rt_version(5, 22, 0, 0)), -1);
  assert_int_equal(out_type("actual_current_as_torque", rt_version(5, 23, 0, 0)),
                   URT_RTDE_VECTOR6D);
  assert_int_equal(out_type("safety_status", rt_version(3, 9, 0, 0)), -1);
  assert_int_equal(out_type("safety_status", rt_version(3, 10, 0, 0)), URT_RTDE_INT32);
  assert_int_equal(out_type("tool_output_mode", rt_version(3, 15, 8, 0)), -1);
  assert_int_equal(out_type("elbow_position", rt_version(3, 4, 0, 0)), -1);
  assert_int_equal(out_type("tcp_offset", rt_version(5, 5, 0, 0)), -1);
  // documented by UR, no model in urtwin: NOT_FOUND rather than a stand-in zero
  assert_int_equal(out_type("actual_TCP_acceleration", rt_version(5, 99, 0, 0)), -1);
  assert_int_equal(out_type("io_current", rt_version(5, 19, 0, 0)), -1);
  assert_int_equal(out_type("target_base_wrench", rt_version(5, 99, 0, 0)), -1);
  assert_int_equal(out_type("target_gravity", rt_version(5, 24, 0, 0)), URT_RTDE_VECTOR3D);
}

static void test_rtde_vars__table_iteration_covers_every_name(void **state) {
  urt_version_t newest = rt_version(5, 99, 99, 0);
  int n = 0;
  urt_rtde_type_t t;
  int cb3, e;
  const char *name;
  int refused = 0;
  while ((name = urt_rtde_output_name(n, &t, &cb3, &e)) != NULL) {
    // an output urtwin has no model for is refused as an unknown one
    bool unmodelled = urt_rtde_output_unmodelled(name, strlen(name));
    refused += unmodelled;
    assert_int_equal(out_type(name, newest), unmodelled ? -1 : (int)t);
    n++;
  }
  assert_int_equal(refused, 11);
  assert_true(n >= 80);
  int ni = 0;
  while ((name = urt_rtde_input_name(ni, &t, &cb3, &e)) != NULL) {
    assert_int_equal(in_type(name, newest), (int)t);
    ni++;
  }
  assert_int_equal(ni, 13);
  assert_true(urt_rtde_input_count() <= 512);
}

static void test_rtde_vars__derived_status_bits(void **state) {
  urt_snapshot_t s;
  urt_rtde_registers_t r;
  memset(&s, 0, sizeof s);
  memset(&r, 0, sizeof r);
  urt_version_t v = rt_version(5, 19, 0, 0);
  urt_rtde_field_t f[3];
  assert_int_equal(urt_rtde_output_lookup("robot_status_bits", 17, &v, &f[0]), 0);
  assert_int_equal(urt_rtde_output_lookup("safety_status_bits", 18, &v, &f[1]), 0);
  assert_int_equal(urt_rtde_output_lookup("tcp_force_scalar", 16, &v, &f[2]), 0);
  s.robot_mode = 7;
  s.program_state = 2;
  s.safety_mode = 3;
  s.tcp_force[0] = 3;
  s.tcp_force[1] = 4;
  uint8_t out[64];
  int n = urt_rtde_encode_fields(f, 3, -1, &s, &r, out, sizeof out);
  assert_int_equal(n, 3 + 4 + 4 + 8);
  static const uint8_t want[] = {0, 19, 'U', 0, 0, 0, 3, 0, 0, 0x04, 0x04,
                                 0x40, 0x14, 0, 0, 0, 0, 0, 0};
  assert_memory_equal(out, want, sizeof want);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rtde_vars__type_tokens_and_sizes),
      cmocka_unit_test(test_rtde_vars__every_client_default_output_exists_with_its_type),
      cmocka_unit_test(test_rtde_vars__unofficial_and_malformed_names_are_not_found),
      cmocka_unit_test(test_rtde_vars__versions_gate_names),
      cmocka_unit_test(test_rtde_vars__table_iteration_covers_every_name),
      cmocka_unit_test(test_rtde_vars__derived_status_bits),
  };
  return cmocka_run_group_tests_name("net/rtde/rtde_vars", tests, NULL, NULL);
}
