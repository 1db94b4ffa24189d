/* SPDX-License-Identifier: Apache-2.0
 * net/codec/primary.c — primary/secondary interface messages (protocols.md §4). */
#include "urt/net/primary.h"

#include <string.h>

#include "urt/controller.h"
#include "urt/errors.h"
#include "urt/net/be_codec.h"

//---- layout generations ----

/* MasterboardData's last reserved byte: URCL 2.14 parses the 5.x layout (70 bytes) for every
 * version and throws on a shorter package ("Could not parse received package"), and its CI
 * runs that parser in strict mode against URSim 3.14.3, so CB3 3.14+ sends the byte too
 * (protocols.md §4.3 had 69 for every CB3 from UMD, which predates 3.14). */
static int masterboard_has_last_reserved(const urt_version_t *v) {
  return v->major >= 5 || (v->major == 3 && v->minor >= 14);
}

/* The sub-package layouts change at these versions (protocols.md §4.3). */
typedef enum layout {
  LAYOUT_CB3_30,  /* 3.0–3.1 */
  LAYOUT_CB3_32,  /* 3.2–3.4 */
  LAYOUT_CB3_35,  /* 3.5+    */
  LAYOUT_E        /* 5.x     */
} layout_t;

static layout_t layout_of(const urt_version_t *v) {
  if (v->major >= 5) {
    return LAYOUT_E;
  }
  if (v->minor <= 1) {
    return LAYOUT_CB3_30;
  }
  return v->minor <= 4 ? LAYOUT_CB3_32 : LAYOUT_CB3_35;
}

/* Sub-packages in sending order (URSim 5.8 order, SAFETY_DATA left out). */
static const int kOrder[] = {
    URT_PRIMARY_ROBOT_MODE_DATA,    URT_PRIMARY_JOINT_DATA,         URT_PRIMARY_CARTESIAN_INFO,
    URT_PRIMARY_KINEMATICS_INFO,    URT_PRIMARY_CALIBRATION_DATA,   URT_PRIMARY_MASTERBOARD_DATA,
    URT_PRIMARY_TOOL_DATA,          URT_PRIMARY_CONFIGURATION_DATA, URT_PRIMARY_FORCE_MODE_DATA,
    URT_PRIMARY_ADDITIONAL_INFO,    URT_PRIMARY_TOOL_COMM_INFO,     URT_PRIMARY_TOOL_MODE_INFO};

int urt_primary_subpackage_size(const urt_version_t *v, int sub_type) {
  layout_t l = layout_of(v);
  int e = (l == LAYOUT_E);
  switch (sub_type) {
    case URT_PRIMARY_ROBOT_MODE_DATA:
      return 5 + (l == LAYOUT_CB3_30 ? 33 : l == LAYOUT_CB3_32 ? 41 : 42);
    case URT_PRIMARY_JOINT_DATA:
      return 5 + 246;
    case URT_PRIMARY_TOOL_DATA:
      return 5 + 32;
    case URT_PRIMARY_MASTERBOARD_DATA:
      return 5 + (l == LAYOUT_CB3_30 ? 67 : masterboard_has_last_reserved(v) ? 70 : 69);
    case URT_PRIMARY_CARTESIAN_INFO:
      return 5 + (l == LAYOUT_CB3_30 ? 48 : 96);
    case URT_PRIMARY_KINEMATICS_INFO:
      return 5 + 220;
    case URT_PRIMARY_CONFIGURATION_DATA:
      return 5 + 440;
    case URT_PRIMARY_FORCE_MODE_DATA:
      return 5 + 56;
    case URT_PRIMARY_ADDITIONAL_INFO:
      return 5 + (e ? 4 : 3);
    case URT_PRIMARY_CALIBRATION_DATA:
      return 5 + 48;
    case URT_PRIMARY_TOOL_COMM_INFO:
      return e ? 5 + 21 : 0;
    case URT_PRIMARY_TOOL_MODE_INFO:
      return e ? 5 + 3 : 0;
    default:
      return 0;
  }
}

//---- robot description ----

static uint32_t fnv1a(uint32_t h, const uint8_t *p, size_t n) {
  for (size_t i = 0; i < n; i++) {
    h ^= p[i];
    h *= 16777619u;
  }
  return h;
}

void urt_primary_kinematics_checksum(urt_primary_robot_info_t *info) {
  for (int j = 0; j < URT_NJ; j++) {
    uint8_t b[32];
    urt_wbuf_t w = urt_wbuf_make(b, sizeof b);
    urt_be_put_f64(&w, info->dh_theta[j]);
    urt_be_put_f64(&w, info->dh_a[j]);
    urt_be_put_f64(&w, info->dh_d[j]);
    urt_be_put_f64(&w, info->dh_alpha[j]);
    info->checksum[j] = fnv1a(2166136261u, b, sizeof b);
  }
}

void urt_primary_robot_info_from_model(const urt_version_t *v, const urt_model_t *m,
                                       urt_primary_robot_info_t *info) {
  memset(info, 0, sizeof *info);

  // DH and limits of the loaded model
  for (int j = 0; j < URT_NJ; j++) {
    const urt_link_params_t *l = &m->arm.link[j];
    info->dh_a[j] = l->a;
    info->dh_d[j] = l->d;
    info->dh_alpha[j] = l->alpha;
    info->dh_theta[j] = l->theta;
    info->q_min[j] = m->joint[j].q_min;
    info->q_max[j] = m->joint[j].q_max;
    info->qd_max[j] = m->joint[j].qd_max;
    info->qdd_max[j] = m->joint[j].qdd_max;
  }

  // PolyScope defaults (URSim 5.8 CONFIGURATION_DATA)
  info->v_joint_default = 1.0471975511965976;
  info->a_joint_default = 1.3962634015954636;
  info->v_tool_default = 0.25;
  info->a_tool_default = 1.2;
  info->eq_radius = 0.25;

  // identity: UR5 on the version's controller generation
  info->robot_type = 1;
  if (urt_version_is_eseries(v)) {
    info->masterboard_version = 6;
    info->controller_box_type = 4;
    info->robot_sub_type = 3;
  } else {
    info->masterboard_version = 3;
    info->controller_box_type = 3;
    info->robot_sub_type = 0;
  }
  info->calibration_status = 0;
  urt_primary_kinematics_checksum(info);
}

//---- sub-packages ----

/* Begin a size-prefixed package; returns where its size goes. */
static uint8_t *begin(urt_wbuf_t *w, uint8_t type) {
  uint8_t *at = w->p;
  urt_be_put_u32(w, 0);
  urt_be_put_u8(w, type);
  return at;
}

/* Patch the size of the package begun at `at` (its length includes the header). */
static void finish(urt_wbuf_t *w, uint8_t *at) {
  if (!w->err) {
    urt_be_store_u32(at, (uint32_t)(w->p - at));
  }
}

static void put_robot_mode(urt_wbuf_t *w, layout_t l, const urt_snapshot_t *s) {
  int connected = s->robot_mode > URT_ROBOT_MODE_DISCONNECTED;
  int power_on = s->robot_mode >= URT_ROBOT_MODE_POWER_ON && s->robot_mode <= URT_ROBOT_MODE_RUNNING;
  int estop = s->safety_mode == 6 || s->safety_mode == 7;
  // controller time in µs; NaN, negative or absurd times become 0 (the cast would be UB)
  double t_us = s->time * 1e6 + 0.5;
  if (!(t_us >= 0.0 && t_us < 1.8e19)) {
    t_us = 0.0;
  }

  urt_be_put_u64(w, (uint64_t)t_us);
  urt_be_put_bool(w, connected);
  urt_be_put_bool(w, connected);  /* real robot enabled: no simulation switch in the snapshot */
  urt_be_put_bool(w, power_on);
  urt_be_put_bool(w, estop);
  urt_be_put_bool(w, s->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP);
  urt_be_put_bool(w, s->program_state == URT_PROGRAM_PLAYING);
  urt_be_put_bool(w, s->program_state == URT_PROGRAM_PAUSED);
  urt_be_put_i8(w, (int8_t)s->robot_mode);
  urt_be_put_u8(w, (uint8_t)s->control_mode);
  urt_be_put_f64(w, s->speed_slider);
  urt_be_put_f64(w, s->speed_scaling);
  if (l != LAYOUT_CB3_30) {
    urt_be_put_f64(w, 1.0);  /* target speed fraction limit */
  }
  if (l == LAYOUT_CB3_35 || l == LAYOUT_E) {
    urt_be_put_u8(w, 0);  /* reserved */
  }
}

static void put_joint_data(urt_wbuf_t *w, const urt_snapshot_t *s) {
  for (int j = 0; j < URT_NJ; j++) {
    urt_be_put_f64(w, s->q[j]);
    urt_be_put_f64(w, s->q_target[j]);
    urt_be_put_f64(w, s->qd[j]);
    urt_be_put_f32(w, (float)s->i_actual[j]);
    urt_be_put_f32(w, (float)s->v_actual[j]);
    urt_be_put_f32(w, (float)s->temperature[j]);
    urt_be_put_f32(w, 0.0f);  /* T_micro, deprecated */
    urt_be_put_u8(w, (uint8_t)s->joint_mode[j]);
  }
}

static void put_tool_data(urt_wbuf_t *w, const urt_snapshot_t *s) {
  // tool analog inputs in voltage mode (range 1), at the levels set from outside (SET_INPUTS)
  urt_be_put_i8(w, 1);
  urt_be_put_i8(w, 1);
  urt_be_put_f64(w, s->tool_analog_in[0]);
  urt_be_put_f64(w, s->tool_analog_in[1]);
  urt_be_put_f32(w, 0.0f);  /* tool voltage 48 V */
  urt_be_put_u8(w, (uint8_t)s->tool_voltage);  /* tool output voltage (set_tool_voltage) */
  urt_be_put_f32(w, 0.0f);  /* tool current */
  urt_be_put_f32(w, 0.0f);  /* tool temperature */
  urt_be_put_u8(w, (uint8_t)s->joint_mode[URT_NJ - 1]);  /* tool mode follows wrist 3 */
}

static void put_masterboard(urt_wbuf_t *w, layout_t l, int last_reserved,
                            const urt_snapshot_t *s) {
  urt_be_put_u32(w, s->digital_in);
  urt_be_put_u32(w, s->digital_out);
  urt_be_put_u8(w, 1);  /* analog input ranges: voltage, as URSim's */
  urt_be_put_u8(w, 1);
  urt_be_put_f64(w, s->analog_in[0]);
  urt_be_put_f64(w, s->analog_in[1]);
  urt_be_put_i8(w, 0);  /* analog output domains */
  urt_be_put_i8(w, 0);
  urt_be_put_f64(w, s->analog_out[0]);
  urt_be_put_f64(w, s->analog_out[1]);
  urt_be_put_f32(w, 24.0f);  /* masterboard temperature: not modelled (URSim value) */
  urt_be_put_f32(w, (float)s->v_robot);
  urt_be_put_f32(w, (float)s->i_robot);
  urt_be_put_f32(w, 0.0f);   /* master I/O current */
  urt_be_put_u8(w, (uint8_t)s->safety_mode);
  urt_be_put_u8(w, s->safety_mode == URT_SAFETY_MODE_REDUCED);
  urt_be_put_bool(w, 0);     /* euromap67 not installed */
  urt_be_put_u32(w, 0);      /* reserved */
  if (l != LAYOUT_CB3_30) {
    urt_be_put_u8(w, 1);     /* operational mode selector input (URSim value) */
    urt_be_put_u8(w, 1);     /* three-position enabling device input (URSim value) */
  }
  if (last_reserved) {
    urt_be_put_u8(w, 1);     /* reserved (URSim value) */
  }
}

static void put_cartesian(urt_wbuf_t *w, layout_t l, const urt_snapshot_t *s) {
  urt_be_put_f64v(w, s->tcp_pose, 6);
  if (l != LAYOUT_CB3_30) {
    urt_be_put_f64v(w, s->tcp_offset, 6);
  }
}

static void put_kinematics(urt_wbuf_t *w, const urt_primary_robot_info_t *ri) {
  for (int j = 0; j < URT_NJ; j++) {
    urt_be_put_u32(w, ri->checksum[j]);
  }
  urt_be_put_f64v(w, ri->dh_theta, URT_NJ);
  urt_be_put_f64v(w, ri->dh_a, URT_NJ);
  urt_be_put_f64v(w, ri->dh_d, URT_NJ);
  urt_be_put_f64v(w, ri->dh_alpha, URT_NJ);
  urt_be_put_u32(w, ri->calibration_status);
}

static void put_configuration(urt_wbuf_t *w, const urt_primary_robot_info_t *ri) {
  for (int j = 0; j < URT_NJ; j++) {
    urt_be_put_f64(w, ri->q_min[j]);
    urt_be_put_f64(w, ri->q_max[j]);
  }
  for (int j = 0; j < URT_NJ; j++) {
    urt_be_put_f64(w, ri->qd_max[j]);
    urt_be_put_f64(w, ri->qdd_max[j]);
  }
  urt_be_put_f64(w, ri->v_joint_default);
  urt_be_put_f64(w, ri->a_joint_default);
  urt_be_put_f64(w, ri->v_tool_default);
  urt_be_put_f64(w, ri->a_tool_default);
  urt_be_put_f64(w, ri->eq_radius);
  urt_be_put_f64v(w, ri->dh_a, URT_NJ);
  urt_be_put_f64v(w, ri->dh_d, URT_NJ);
  urt_be_put_f64v(w, ri->dh_alpha, URT_NJ);
  urt_be_put_f64v(w, ri->dh_theta, URT_NJ);
  urt_be_put_i32(w, ri->masterboard_version);
  urt_be_put_i32(w, ri->controller_box_type);
  urt_be_put_i32(w, ri->robot_type);
  urt_be_put_i32(w, ri->robot_sub_type);
}

static void put_force_mode(urt_wbuf_t *w, const urt_snapshot_t *s) {
  urt_be_put_f64v(w, s->tcp_force, 6);
  urt_be_put_f64(w, 0.0);  /* robot dexterity: not computed */
}

static void put_additional_info(urt_wbuf_t *w, layout_t l) {
  // freedrive button pressed / enabled, I/O-enabled freedrive (+ reserved on e-Series)
  urt_be_put_u8(w, 0);
  urt_be_put_bool(w, 0);
  urt_be_put_bool(w, 0);
  if (l == LAYOUT_E) {
    urt_be_put_u8(w, 0);
  }
}

static void put_tool_comm_info(urt_wbuf_t *w) {
  // tool communication disabled, URSim 5.8 settings
  urt_be_put_bool(w, 0);
  urt_be_put_i32(w, 115200);
  urt_be_put_i32(w, 0);
  urt_be_put_i32(w, 1);
  urt_be_put_f32(w, 1.5f);
  urt_be_put_f32(w, 3.5f);
}

static void put_tool_mode_info(urt_wbuf_t *w) {
  urt_be_put_u8(w, 0);  /* output mode */
  urt_be_put_u8(w, 1);  /* digital output mode 0 (URSim value) */
  urt_be_put_u8(w, 1);  /* digital output mode 1 */
}

//---- ROBOT_STATE ----

int urt_primary_encode_robot_state(const urt_version_t *v, const urt_primary_robot_info_t *info,
                                   const urt_snapshot_t *s, uint8_t *buf, size_t cap) {
  layout_t l = layout_of(v);
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *msg = begin(&w, URT_PRIMARY_ROBOT_STATE);

  // each sub-package in order, skipping the ones this version does not send
  for (size_t k = 0; k < sizeof kOrder / sizeof kOrder[0]; k++) {
    int type = kOrder[k];
    if (urt_primary_subpackage_size(v, type) == 0) {
      continue;
    }
    uint8_t *sub = begin(&w, (uint8_t)type);
    switch (type) {
      case URT_PRIMARY_ROBOT_MODE_DATA:
        put_robot_mode(&w, l, s);
        break;
      case URT_PRIMARY_JOINT_DATA:
        put_joint_data(&w, s);
        break;
      case URT_PRIMARY_CARTESIAN_INFO:
        put_cartesian(&w, l, s);
        break;
      case URT_PRIMARY_KINEMATICS_INFO:
        put_kinematics(&w, info);
        break;
      case URT_PRIMARY_CALIBRATION_DATA:
        urt_be_put_zeros(&w, 6 * 8);
        break;
      case URT_PRIMARY_MASTERBOARD_DATA:
        put_masterboard(&w, l, masterboard_has_last_reserved(v), s);
        break;
      case URT_PRIMARY_TOOL_DATA:
        put_tool_data(&w, s);
        break;
      case URT_PRIMARY_CONFIGURATION_DATA:
        put_configuration(&w, info);
        break;
      case URT_PRIMARY_FORCE_MODE_DATA:
        put_force_mode(&w, s);
        break;
      case URT_PRIMARY_ADDITIONAL_INFO:
        put_additional_info(&w, l);
        break;
      case URT_PRIMARY_TOOL_COMM_INFO:
        put_tool_comm_info(&w);
        break;
      case URT_PRIMARY_TOOL_MODE_INFO:
        put_tool_mode_info(&w);
        break;
    }
    finish(&w, sub);
  }
  finish(&w, msg);
  return w.err ? URT_ENOSPC : (int)urt_wbuf_len(&w);
}

//---- ROBOT_MESSAGE ----

/* Header of a robot message: size placeholder, type 20, timestamp, source, message type. */
static uint8_t *begin_message(urt_wbuf_t *w, uint64_t ts, int source, int msg_type) {
  uint8_t *at = begin(w, URT_PRIMARY_ROBOT_MESSAGE);
  urt_be_put_u64(w, ts);
  urt_be_put_i8(w, (int8_t)source);
  urt_be_put_u8(w, (uint8_t)msg_type);
  return at;
}

static void put_text(urt_wbuf_t *w, const char *text) {
  if (text) {
    urt_be_put_bytes(w, text, strlen(text));
  }
}

static int end_message(urt_wbuf_t *w, uint8_t *at) {
  finish(w, at);
  return w->err ? URT_ENOSPC : (int)urt_wbuf_len(w);
}

int urt_primary_encode_version(const urt_version_t *v, uint64_t timestamp_us, uint8_t *buf,
                               size_t cap) {
  static const char kProject[] = "URControl";
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, URT_PRIMARY_SOURCE_ROBOT_INTERFACE,
                              URT_PRIMARY_MSG_VERSION);
  urt_be_put_i8(&w, (int8_t)(sizeof kProject - 1));
  urt_be_put_bytes(&w, kProject, sizeof kProject - 1);
  urt_be_put_u8(&w, (uint8_t)v->major);
  urt_be_put_u8(&w, (uint8_t)v->minor);
  urt_be_put_i32(&w, v->bugfix);
  urt_be_put_i32(&w, v->build);
  urt_be_put_bytes(&w, v->date, strnlen(v->date, sizeof v->date));
  return end_message(&w, at);
}

int urt_primary_encode_text(uint64_t timestamp_us, int source, const char *text, uint8_t *buf,
                            size_t cap) {
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_TEXT);
  put_text(&w, text);
  return end_message(&w, at);
}

int urt_primary_encode_key(uint64_t timestamp_us, int source, int32_t code, int32_t argument,
                           const char *title, const char *text, uint8_t *buf, size_t cap) {
  size_t title_len = title ? strlen(title) : 0;
  if (title_len > 255) {
    return URT_EINVAL;
  }
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_KEY);
  urt_be_put_i32(&w, code);
  urt_be_put_i32(&w, argument);
  urt_be_put_u8(&w, (uint8_t)title_len);
  put_text(&w, title);
  put_text(&w, text);
  return end_message(&w, at);
}

int urt_primary_encode_popup(uint64_t timestamp_us, int source, uint32_t request_id,
                             uint32_t requested_type, bool warning, bool error, bool blocking,
                             const char *title, const char *text, uint8_t *buf, size_t cap) {
  size_t title_len = title ? strlen(title) : 0;
  if (title_len > 255) {
    return URT_EINVAL;
  }
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_POPUP);
  urt_be_put_u32(&w, request_id);
  urt_be_put_u32(&w, requested_type);
  urt_be_put_u8(&w, warning ? 1 : 0);
  urt_be_put_u8(&w, error ? 1 : 0);
  urt_be_put_u8(&w, blocking ? 1 : 0);
  urt_be_put_u8(&w, (uint8_t)title_len);
  put_text(&w, title);
  put_text(&w, text);
  return end_message(&w, at);
}

int urt_primary_encode_runtime_exception(uint64_t timestamp_us, int source, uint32_t line,
                                         uint32_t column, const char *text, uint8_t *buf,
                                         size_t cap) {
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_RUNTIME_EXCEPTION);
  urt_be_put_u32(&w, line);
  urt_be_put_u32(&w, column);
  put_text(&w, text);
  return end_message(&w, at);
}

int urt_primary_encode_error_code(uint64_t timestamp_us, int source, int32_t code,
                                  int32_t argument, int32_t report_level, uint32_t data_type,
                                  uint32_t data, const char *text, uint8_t *buf, size_t cap) {
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_ERROR_CODE);
  urt_be_put_i32(&w, code);
  urt_be_put_i32(&w, argument);
  urt_be_put_i32(&w, report_level);
  urt_be_put_u32(&w, data_type);
  urt_be_put_u32(&w, data);
  put_text(&w, text);
  return end_message(&w, at);
}

int urt_primary_encode_safety_mode(uint64_t timestamp_us, int source, int32_t code,
                                   int32_t argument, int safety_mode, uint32_t data_type,
                                   uint32_t data, uint8_t *buf, size_t cap) {
  urt_wbuf_t w = urt_wbuf_make(buf, cap);
  uint8_t *at = begin_message(&w, timestamp_us, source, URT_PRIMARY_MSG_SAFETY_MODE);
  urt_be_put_i32(&w, code);
  urt_be_put_i32(&w, argument);
  urt_be_put_u8(&w, (uint8_t)safety_mode);
  urt_be_put_u32(&w, data_type);
  urt_be_put_u32(&w, data);
  return end_message(&w, at);
}
