/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_builtins_io.c — the URScript builtins for the controller's I/O: digital
 * and analog outputs (set through the command queue), the input and output bits as the last
 * snapshot shows them, and the RTDE general-purpose registers that the host keeps.
 */
#include <string.h>

#include "script_vm.h"

//---- digital and analog I/O ----

int urt__us_set_io(vm *V, const us_node *at, int index, bool value) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_DIGITAL_OUT, .index = index, .value = value ? 1 : 0};
  return urt__us_submit(V, at, &c);
}

/* set_*_digital_out(n, b): base is the bit of output 0, count the number of outputs */
static int digital_out(vm *V, const us_node *n, sv *a, int base, int count) {
  int64_t k;
  bool b;
  if (urt__us_arg_int(V, n, a, 0, &k) != X_OK || urt__us_arg_bool(V, n, a, 1,
                                                                  &b) != X_OK) return X_ERR;
  if (k < 0 || k >= count) return urt__us_fail(V, n, "Index out of bounds: digital output %lld", (long long)k);
  return urt__us_set_io(V, n, base + (int)k, b);
}

static int b_set_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 0, 18); }
static int b_set_standard_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 0, 8); }
static int b_set_configurable_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 8, 8); }
static int b_set_tool_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return digital_out(V, n, a, 16, 2); }

static int b_set_analog_out(vm *V, const us_node *n, sv *a, sv *out) {
  int64_t k;
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_SET_ANALOG_OUT};
  if (urt__us_arg_int(V, n, a, 0, &k) != X_OK || urt__us_arg_num(V, n, a, 1, 0,
                                                                 &c.value) != X_OK) return X_ERR;
  if (k < 0 || k > 1) return urt__us_fail(V, n, "Index out of bounds: analog output %lld",
                                          (long long)k);
  if (c.value < 0 || c.value > 1) return urt__us_fail(V, n, "Analog output value %g outside [0, 1]", c.value);
  c.index = (int32_t)k;
  return urt__us_submit(V, n, &c);
}

static int get_bit(vm *V, const us_node *n, sv *a, sv *out, bool input, int base, int count) {
  int64_t k;
  if (urt__us_arg_int(V, n, a, 0, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= count) return urt__us_fail(V, n, "Index out of bounds: %lld", (long long)k);
  uint32_t bits = input ? urt__us_snap(V)->digital_in : urt__us_snap(V)->digital_out;
  *out = mk_bool((bits >> (base + k)) & 1u);
  return X_OK;
}

static int b_get_standard_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 0, 8); }
static int b_get_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 0, 18); }
static int b_get_configurable_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 8, 8); }
static int b_get_tool_digital_out(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, false, 16, 2); }
static int b_get_standard_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 0, 8); }
static int b_get_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 0, 18); }
static int b_get_configurable_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 8, 8); }
static int b_get_tool_digital_in(vm *V, const us_node *n, sv *a, sv *out) { return get_bit(V, n, a, out, true, 16, 2); }

/* get_*_analog_in(n) [V]: inputs 0–1 of the control box, then 0–1 of the tool (get_analog_in's
 * 2–3), as the last snapshot shows them */
static int get_analog(vm *V, const us_node *n, sv *a, sv *out, int first, int count) {
  int64_t k;
  if (urt__us_arg_int(V, n, a, 0, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= count) return urt__us_fail(V, n, "Index out of bounds: analog input %lld", (long long)k);
  const urt_snapshot_t *s = urt__us_snap(V);
  int i = first + (int)k;
  *out = mk_float(i < 2 ? s->analog_in[i] : s->tool_analog_in[i - 2]);
  return X_OK;
}

static int b_get_standard_analog_in(vm *V, const us_node *n, sv *a, sv *out) { return get_analog(V, n, a, out, 0, 2); }
static int b_get_tool_analog_in(vm *V, const us_node *n, sv *a, sv *out) { return get_analog(V, n, a, out, 2, 2); }
static int b_get_analog_in(vm *V, const us_node *n, sv *a, sv *out) { return get_analog(V, n, a, out, 0, 4); }

//---- RTDE registers (protocols.md §2.5–2.6) ----

/* the register number argument 0, checked against the bank's size */
static int reg_index(vm *V, const us_node *n, sv *a, int count, int *out) {
  int64_t k;
  if (urt__us_arg_int(V, n, a, 0, &k) != X_OK) return X_ERR;
  if (k < 0 || k >= count) {
    return urt__us_fail(V, n, "%.*s: register %lld out of range 0..%d", n->name->len, n->name->s,
                        (long long)k, count - 1);
  }
  *out = (int)k;
  return X_OK;
}

static int reg_write(vm *V, const us_node *n, sv *a, int kind, int count) {
  const urt_script_host_t *h = V->h->host;
  int k = 0;
  double x;
  if (!h->write_output_register) return urt__us_fail(V, n, "RTDE registers are not available");
  if (reg_index(V, n, a, count, &k) != X_OK) return X_ERR;
  if (kind == URT_SCRIPT_REG_INT) {
    int64_t i;
    if (urt__us_arg_int(V, n, a, 1, &i) != X_OK) return X_ERR;
    if (i < INT32_MIN || i > INT32_MAX) return urt__us_fail(V, n, "%.*s: %lld does not fit 32 bits", n->name->len, n->name->s, (long long)i);
    x = (double)i;
  } else if (kind == URT_SCRIPT_REG_BIT) {
    bool b;
    if (urt__us_arg_bool(V, n, a, 1, &b) != X_OK) return X_ERR;
    x = b ? 1 : 0;
  } else if (urt__us_arg_num(V, n, a, 1, 0, &x) != X_OK) {
    return X_ERR;
  }
  h->write_output_register(h->ctx, kind, k, x);
  return X_OK;
}

static int reg_read(vm *V, const us_node *n, sv *a, sv *out, int kind, bool input) {
  const urt_script_host_t *h = V->h->host;
  int k = 0;
  if (!h->read_registers) return urt__us_fail(V, n, "RTDE registers are not available");
  if (reg_index(V, n, a, kind == URT_SCRIPT_REG_BIT ? URT_RTDE_NBITREG : URT_RTDE_NREG, &k) != X_OK) return X_ERR;
  urt_rtde_registers_t r;
  h->read_registers(h->ctx, V->tick, &r);  // the inputs as this tick held them
  if (kind == URT_SCRIPT_REG_INT) *out = mk_int(input ? r.in_int[k] : r.out_int[k]);
  else if (kind == URT_SCRIPT_REG_DOUBLE) *out = mk_float(input ? r.in_double[k] : r.out_double[k]);
  else *out = mk_bool((input ? r.in_bit[k] : r.out_bit[k]) != 0);
  return X_OK;
}

static int b_write_output_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_INT, URT_RTDE_NREG); }
static int b_write_output_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_DOUBLE, URT_RTDE_NREG); }
static int b_write_output_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_write(V, n, a, URT_SCRIPT_REG_BIT, URT_RTDE_NBITREG); }
static int b_read_input_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_INT, true); }
static int b_read_input_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_DOUBLE, true); }
static int b_read_input_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_BIT, true); }
static int b_read_output_integer_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_INT, false); }
static int b_read_output_float_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_DOUBLE, false); }
static int b_read_output_boolean_register(vm *V, const us_node *n, sv *a, sv *out) { return reg_read(V, n, a, out, URT_SCRIPT_REG_BIT, false); }

//---- table ----

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_io[] = {
    // I/O
    {"set_digital_out", b_set_digital_out, 2, P("n", "b")},
    {"set_standard_digital_out", b_set_standard_digital_out, 2, P("n", "b")},
    {"set_configurable_digital_out", b_set_configurable_digital_out, 2, P("n", "b")},
    {"set_tool_digital_out", b_set_tool_digital_out, 2, P("n", "b")},
    {"set_analog_out", b_set_analog_out, 2, P("n", "f")},
    {"set_standard_analog_out", b_set_analog_out, 2, P("n", "f")},
    {"get_standard_digital_out", b_get_standard_digital_out, 1, P("n")},
    {"get_digital_out", b_get_digital_out, 1, P("n")},
    {"get_configurable_digital_out", b_get_configurable_digital_out, 1, P("n")},
    {"get_tool_digital_out", b_get_tool_digital_out, 1, P("n")},
    {"get_standard_digital_in", b_get_standard_digital_in, 1, P("n")},
    {"get_digital_in", b_get_digital_in, 1, P("n")},
    {"get_configurable_digital_in", b_get_configurable_digital_in, 1, P("n")},
    {"get_tool_digital_in", b_get_tool_digital_in, 1, P("n")},
    {"get_standard_analog_in", b_get_standard_analog_in, 1, P("n")},
    {"get_tool_analog_in", b_get_tool_analog_in, 1, P("n")},
    {"get_analog_in", b_get_analog_in, 1, P("n")},
    // RTDE registers
    {"write_output_integer_register", b_write_output_integer_register, 2, P("address", "value")},
    {"write_output_float_register", b_write_output_float_register, 2, P("address", "value")},
    {"write_output_boolean_register", b_write_output_boolean_register, 2, P("address", "value")},
    {"read_input_integer_register", b_read_input_integer_register, 1, P("address")},
    {"read_input_float_register", b_read_input_float_register, 1, P("address")},
    {"read_input_boolean_register", b_read_input_boolean_register, 1, P("address")},
    {"read_output_integer_register", b_read_output_integer_register, 1, P("address")},
    {"read_output_float_register", b_read_output_float_register, 1, P("address")},
    {"read_output_boolean_register", b_read_output_boolean_register, 1, P("address")},
};
#undef P

const int urt__us_n_builtins_io =
    (int)(sizeof urt__us_builtins_io / sizeof urt__us_builtins_io[0]);
