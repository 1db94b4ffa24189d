/* SPDX-License-Identifier: Apache-2.0
 * net/rtde/rtde_vars.c — the RTDE variable tables: name → type lookup gated by the emulated
 * version (resolved once per recipe), and the per-field copier used every data package.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rtde_internal.h"
#include "urt/errors.h"

//---- types ----

static const char *const k_type_name[URT_RTDE_NTYPES] = {
    "BOOL", "UINT8", "UINT32", "UINT64", "INT32", "DOUBLE",
    "VECTOR3D", "VECTOR6D", "VECTOR6INT32", "VECTOR6UINT32"};
static const uint8_t k_type_size[URT_RTDE_NTYPES] = {1, 1, 4, 8, 4, 8, 24, 48, 24, 24};

const char *urt_rtde_type_name(urt_rtde_type_t t) {
  return (unsigned)t < URT_RTDE_NTYPES ? k_type_name[t] : "NOT_FOUND";
}

size_t urt_rtde_type_size(urt_rtde_type_t t) {
  return (unsigned)t < URT_RTDE_NTYPES ? k_type_size[t] : 0;
}

//---- versions ----

int urt__rtde_version_code(const urt_version_t *v) {
  int mi = v->minor < 0 ? 0 : (v->minor > 99 ? 99 : v->minor);
  int bu = v->bugfix < 0 ? 0 : (v->bugfix > 99 ? 99 : v->bugfix);
  return URT_RTDE_VER(v->major, mi, bu);
}

int urt__rtde_is_eseries(const urt_version_t *v) { return v->major >= 5; }

double urt__rtde_controller_hz(const urt_version_t *v) {
  return urt__rtde_is_eseries(v) ? 500.0 : 125.0;
}

static int available(const urt_version_t *v, int since_cb3, int since_e) {
  int since = urt__rtde_is_eseries(v) ? since_e : since_cb3;
  return since != URT_RTDE_NEVER && urt__rtde_version_code(v) >= since;
}

//---- tables ----

typedef struct var_entry {
  const char *name;
  uint8_t type;
  int since_cb3, since_e;
} var_entry_t;

static const var_entry_t k_outputs[] = {
#define X(name, type, cb3, e, value) {#name, URT_RTDE_##type, cb3, e},
#include "rtde_outputs.def"
#undef X
};
static const var_entry_t k_inputs[] = {
#define X(name, type, cb3, e) {#name, URT_RTDE_##type, cb3, e},
#include "rtde_inputs.def"
#undef X
};
#define NOUT ((int)(sizeof k_outputs / sizeof k_outputs[0]))
#define NIN ((int)(sizeof k_inputs / sizeof k_inputs[0]))

_Static_assert(NOUT == URT__RTDE_OUT_NFIXED, "output table and kinds agree");
_Static_assert(NIN == URT__RTDE_IN_NFIXED, "input table and ids agree");
_Static_assert(URT__RTDE_IN_COUNT <= 512, "registry owner[] holds every input id");
_Static_assert(URT__RTDE_OUT_NKINDS <= 0xffff, "kinds fit the field");

static const char *entry_name(const var_entry_t *t, int n, int i, urt_rtde_type_t *type,
                              int *since_cb3, int *since_e) {
  if (i < 0 || i >= n) {
    return NULL;
  }
  if (type) {
    *type = (urt_rtde_type_t)t[i].type;
  }
  if (since_cb3) {
    *since_cb3 = t[i].since_cb3;
  }
  if (since_e) {
    *since_e = t[i].since_e;
  }
  return t[i].name;
}

const char *urt_rtde_output_name(int i, urt_rtde_type_t *type, int *since_cb3, int *since_e) {
  return entry_name(k_outputs, NOUT, i, type, since_cb3, since_e);
}

const char *urt_rtde_input_name(int i, urt_rtde_type_t *type, int *since_cb3, int *since_e) {
  return entry_name(k_inputs, NIN, i, type, since_cb3, since_e);
}

int urt_rtde_input_count(void) { return URT__RTDE_IN_COUNT; }

//---- name resolution ----

static int name_eq(const char *name, size_t len, const char *lit) {
  return strlen(lit) == len && memcmp(name, lit, len) == 0;
}

/* "prefix" followed by a decimal number without leading zeros; returns the number or -1 */
static int suffix_number(const char *name, size_t len, const char *prefix) {
  size_t pl = strlen(prefix);
  if (len <= pl || len > pl + 3 || memcmp(name, prefix, pl) != 0) {
    return -1;
  }
  if (name[pl] == '0' && len > pl + 1) {
    return -1;
  }
  int n = 0;
  for (size_t i = pl; i < len; i++) {
    if (name[i] < '0' || name[i] > '9') {
      return -1;
    }
    n = n * 10 + (name[i] - '0');
  }
  return n;
}

/* availability of register number i of a family: 0–23 since 3.4/5.0, 24–47 and bits 64–127
 * since 3.9/5.3 */
static int reg_available(const urt_version_t *v, int upper) {
  return upper ? available(v, URT_RTDE_VER(3, 9, 0), URT_RTDE_VER(5, 3, 0))
               : available(v, URT_RTDE_VER(3, 4, 0), URT_RTDE_VER(5, 0, 0));
}

/* Register names shared by outputs (read-back) and inputs. Sets *family to 0 int, 1 double,
 * 2 single bit, 3 bits 0–31, 4 bits 32–63 and *index; returns 0 or -1. */
static int register_name(const char *name, size_t len, const char *dir, const urt_version_t *v,
                         int *family, int *index) {
  char prefix[40];
  int i;
  snprintf(prefix, sizeof prefix, "%s_int_register_", dir);
  if ((i = suffix_number(name, len, prefix)) >= 0 && i < URT_RTDE_NREG) {
    *family = 0;
    *index = i;
    return reg_available(v, i >= 24) ? 0 : -1;
  }
  snprintf(prefix, sizeof prefix, "%s_double_register_", dir);
  if ((i = suffix_number(name, len, prefix)) >= 0 && i < URT_RTDE_NREG) {
    *family = 1;
    *index = i;
    return reg_available(v, i >= 24) ? 0 : -1;
  }
  snprintf(prefix, sizeof prefix, "%s_bit_register_", dir);
  if ((i = suffix_number(name, len, prefix)) >= 64 && i < URT_RTDE_NBITREG) {
    *family = 2;
    *index = i;
    return reg_available(v, 1) ? 0 : -1;
  }
  snprintf(prefix, sizeof prefix, "%s_bit_registers0_to_31", dir);
  if (name_eq(name, len, prefix)) {
    *family = 3;
    *index = 0;
    return reg_available(v, 0) ? 0 : -1;
  }
  snprintf(prefix, sizeof prefix, "%s_bit_registers32_to_63", dir);
  if (name_eq(name, len, prefix)) {
    *family = 4;
    *index = 0;
    return reg_available(v, 0) ? 0 : -1;
  }
  return -1;
}

static const uint8_t k_family_type[5] = {URT_RTDE_INT32, URT_RTDE_DOUBLE, URT_RTDE_BOOL,
                                         URT_RTDE_UINT32, URT_RTDE_UINT32};

/* Outputs UR documents that urtwin has no model for and would have to send as a stand-in zero:
 * refused at setup as an unknown name is (NOT_FOUND), so that a client never takes a zero for
 * a value. None is in the default recipes of ur_rtde 1.6.5, URCL 2.14.0, the ROS 2 driver or
 * UR's RTDE examples (URCL lists them only in its exhaustive recipe, whose test ignores unknown
 * names); net/rtde/README.md lists them, and those still sent as zero because such a recipe
 * asks for them. */
static const char *const k_unmodelled[] = {
    "io_current", "script_control_line", "actual_current_window", "collision_detection_ratio",
    "actual_TCP_acceleration", "target_TCP_acceleration", "actual_robot_energy_consumed",
    "actual_robot_braking_energy_dissipated", "time_scale_source", "target_base_acceleration",
    "target_base_wrench"};

int urt_rtde_output_unmodelled(const char *name, size_t len) {
  for (size_t k = 0; k < sizeof k_unmodelled / sizeof k_unmodelled[0]; k++) {
    if (name_eq(name, len, k_unmodelled[k])) {
      return 1;
    }
  }
  return 0;
}

int urt_rtde_output_lookup(const char *name, size_t len, const urt_version_t *v,
                           urt_rtde_field_t *f) {
  if (urt_rtde_output_unmodelled(name, len)) {
    return URT_EINVAL;
  }
  // fixed names
  for (int i = 0; i < NOUT; i++) {
    if (name_eq(name, len, k_outputs[i].name)) {
      if (!available(v, k_outputs[i].since_cb3, k_outputs[i].since_e)) {
        return URT_EINVAL;
      }
      *f = (urt_rtde_field_t){(uint16_t)i, 0, k_outputs[i].type};
      return 0;
    }
  }

  // output registers, then the read-back of the input registers
  int family, index;
  if (register_name(name, len, "output", v, &family, &index) == 0) {
    *f = (urt_rtde_field_t){(uint16_t)(URT__RTDE_OUT_INT_REG + family), (uint8_t)index,
                            k_family_type[family]};
    return 0;
  }
  if (register_name(name, len, "input", v, &family, &index) == 0) {
    *f = (urt_rtde_field_t){(uint16_t)(URT__RTDE_IN_INT_REG + family), (uint8_t)index,
                            k_family_type[family]};
    return 0;
  }
  return URT_EINVAL;
}

int urt_rtde_input_lookup(const char *name, size_t len, const urt_version_t *v,
                          urt_rtde_field_t *f) {
  for (int i = 0; i < NIN; i++) {
    if (name_eq(name, len, k_inputs[i].name)) {
      if (!available(v, k_inputs[i].since_cb3, k_inputs[i].since_e)) {
        return URT_EINVAL;
      }
      *f = (urt_rtde_field_t){(uint16_t)i, 0, k_inputs[i].type};
      return 0;
    }
  }
  int family, index;
  if (register_name(name, len, "input", v, &family, &index) != 0) {
    return URT_EINVAL;
  }
  static const uint16_t base[5] = {URT__RTDE_IN_INT_BASE, URT__RTDE_IN_DOUBLE_BASE,
                                   URT__RTDE_IN_BIT_BASE - 64, URT__RTDE_IN_BITS_LO_ID,
                                   URT__RTDE_IN_BITS_HI_ID};
  uint16_t id = (uint16_t)(base[family] + (family <= 2 ? index : 0));
  *f = (urt_rtde_field_t){id, (uint8_t)index, k_family_type[family]};
  return 0;
}

//---- values the snapshot does not carry directly ----

static const double k_zero6[6] = {0};
#define MISSING_D 0.0
#define MISSING_U 0u
#define MISSING_I 0
#define MISSING_U8 0u
#define MISSING_V6 k_zero6

/* robot_status_bits (protocols.md §2.8.6): power on, program running; the teach and power
 * buttons are never pressed in the emulator */
static uint32_t robot_status_bits(const urt_snapshot_t *s) {
  uint32_t b = 0;
  if (s->robot_mode >= 4 && s->robot_mode <= 7) {
    b |= 1u << 0;
  }
  if (s->program_state == 2) {
    b |= 1u << 1;
  }
  return b;
}

/* safety_status_bits (protocols.md §2.8.7) from the safety mode */
static uint32_t safety_status_bits(const urt_snapshot_t *s) {
  switch (s->safety_mode) {
    case 1: return 1u << 0;                                     /* normal              */
    case 2: return 1u << 1;                                     /* reduced             */
    case 3: return (1u << 2) | (1u << 10);                      /* protective stop     */
    case 4: return 1u << 3;                                     /* recovery            */
    case 5: return (1u << 4) | (1u << 10);                      /* safeguard stop      */
    case 6: return (1u << 5) | (1u << 7) | (1u << 10);          /* system e-stop       */
    case 7: return (1u << 6) | (1u << 7) | (1u << 10);          /* robot e-stop        */
    case 8: return (1u << 8) | (1u << 10);                      /* violation           */
    case 9: return (1u << 9) | (1u << 10);                      /* fault               */
    default: return 0;
  }
}

static double tcp_force_scalar(const urt_snapshot_t *s) {
  return sqrt(s->tcp_force[0] * s->tcp_force[0] + s->tcp_force[1] * s->tcp_force[1] +
              s->tcp_force[2] * s->tcp_force[2]);
}

//---- per-type writers ----

#define PUT_BOOL(w, x) be_put_u8(w, (x) ? 1 : 0)
#define PUT_UINT8(w, x) be_put_u8(w, (uint8_t)(x))
#define PUT_UINT32(w, x) be_put_u32(w, (uint32_t)(x))
#define PUT_UINT64(w, x) be_put_u64(w, (uint64_t)(x))
#define PUT_INT32(w, x) be_put_u32(w, (uint32_t)(int32_t)(x))
#define PUT_DOUBLE(w, x) be_put_f64(w, (double)(x))
#define PUT_VECTOR3D(w, a) put_vd(w, a, 3)
#define PUT_VECTOR6D(w, a) put_vd(w, a, 6)
#define PUT_VECTOR6INT32(w, a) put_vi(w, a, 6)

static void put_vd(urt__rtde_w_t *w, const double *a, int n) {
  for (int i = 0; i < n; i++) {
    be_put_f64(w, a[i]);
  }
}
static void put_vi(urt__rtde_w_t *w, const int32_t *a, int n) {
  for (int i = 0; i < n; i++) {
    be_put_u32(w, (uint32_t)a[i]);
  }
}

static uint32_t bits_word(const uint8_t *bits) {
  uint32_t x = 0;
  for (int i = 0; i < 32; i++) {
    x |= (uint32_t)(bits[i] ? 1u : 0u) << i;
  }
  return x;
}

static void put_field(urt__rtde_w_t *w, urt_rtde_field_t f, const urt_snapshot_t *s,
                      const urt_rtde_registers_t *r) {
  int i = f.index;
  switch (f.var) {
#define X(name, type, cb3, e, value) \
  case URT__RTDE_OUT_##name:         \
    PUT_##type(w, value);            \
    break;
#include "rtde_outputs.def"
#undef X
    case URT__RTDE_OUT_INT_REG: PUT_INT32(w, r->out_int[i]); break;
    case URT__RTDE_OUT_DOUBLE_REG: PUT_DOUBLE(w, r->out_double[i]); break;
    case URT__RTDE_OUT_BIT_REG: PUT_BOOL(w, r->out_bit[i]); break;
    case URT__RTDE_OUT_BITS_LO: PUT_UINT32(w, bits_word(r->out_bit)); break;
    case URT__RTDE_OUT_BITS_HI: PUT_UINT32(w, bits_word(r->out_bit + 32)); break;
    case URT__RTDE_IN_INT_REG: PUT_INT32(w, r->in_int[i]); break;
    case URT__RTDE_IN_DOUBLE_REG: PUT_DOUBLE(w, r->in_double[i]); break;
    case URT__RTDE_IN_BIT_REG: PUT_BOOL(w, r->in_bit[i]); break;
    case URT__RTDE_IN_BITS_LO: PUT_UINT32(w, bits_word(r->in_bit)); break;
    case URT__RTDE_IN_BITS_HI: PUT_UINT32(w, bits_word(r->in_bit + 32)); break;
    default: w->err = 1; break;   /* not a resolved field: refuse rather than misframe */
  }
}

int urt_rtde_encode_fields(const urt_rtde_field_t *f, int n, int recipe_id,
                           const urt_snapshot_t *snap, const urt_rtde_registers_t *r,
                           uint8_t *out, size_t cap) {
  urt__rtde_w_t w = {out, out + cap, 0};

  // header; the size is patched once the fields are written
  be_put_u16(&w, 0);
  be_put_u8(&w, URT_RTDE_DATA_PACKAGE);
  if (recipe_id >= 0) {
    be_put_u8(&w, (uint8_t)recipe_id);
  }
  for (int k = 0; k < n && !w.err; k++) {
    put_field(&w, f[k], snap, r);
  }
  size_t len = (size_t)(w.p - out);
  if (w.err || len > 0xffff) {
    return URT_ENOSPC;
  }
  out[0] = (uint8_t)(len >> 8);
  out[1] = (uint8_t)len;
  return (int)len;
}
