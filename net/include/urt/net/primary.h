/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/primary.h — messages of the primary (30001) and secondary (30002)
 * client interfaces (protocols.md §4): int32 size (incl. the 5-byte header), uint8 type, body.
 *
 *   VERSION (ROBOT_MESSAGE 20 / 3)  first message on both ports
 *   ROBOT_STATE (16)                10 Hz, sub-packages of the emulated version (§4.3)
 *   ROBOT_MESSAGE (20)              TEXT, KEY, RUNTIME_EXCEPTION, ERROR_CODE, SAFETY_MODE
 *
 * All encoders are pure: they return the bytes written or URT_ENOSPC (cap too small; buf may
 * hold a partial message) / URT_EINVAL, and never touch a socket, clock or global.
 * Timestamps are controller time in microseconds (the URSim 5.8 fixture's robot-mode
 * timestamp is a whole number of 2 ms ticks only when read as µs).
 */
#ifndef URT_NET_PRIMARY_H
#define URT_NET_PRIMARY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/model.h"
#include "urt/net/version.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

/* python-urx 0.11.0 drops any message above this size on 30002. */
#define URT_PRIMARY_MAX_MESSAGE 2000

/* Message types (protocols.md §4.1). */
enum {
  URT_PRIMARY_ROBOT_STATE = 16,
  URT_PRIMARY_ROBOT_MESSAGE = 20
};

/* ROBOT_STATE sub-package types (protocols.md §4.3). */
enum {
  URT_PRIMARY_ROBOT_MODE_DATA = 0,
  URT_PRIMARY_JOINT_DATA = 1,
  URT_PRIMARY_TOOL_DATA = 2,
  URT_PRIMARY_MASTERBOARD_DATA = 3,
  URT_PRIMARY_CARTESIAN_INFO = 4,
  URT_PRIMARY_KINEMATICS_INFO = 5,
  URT_PRIMARY_CONFIGURATION_DATA = 6,
  URT_PRIMARY_FORCE_MODE_DATA = 7,
  URT_PRIMARY_ADDITIONAL_INFO = 8,
  URT_PRIMARY_CALIBRATION_DATA = 9,
  URT_PRIMARY_SAFETY_DATA = 10,
  URT_PRIMARY_TOOL_COMM_INFO = 11,
  URT_PRIMARY_TOOL_MODE_INFO = 12,
  URT_PRIMARY_NSUB = 13
};

/* ROBOT_MESSAGE types (protocols.md §4.5) and sources. */
enum {
  URT_PRIMARY_MSG_TEXT = 0,
  URT_PRIMARY_MSG_POPUP = 2,
  URT_PRIMARY_MSG_VERSION = 3,
  URT_PRIMARY_MSG_SAFETY_MODE = 5,
  URT_PRIMARY_MSG_ERROR_CODE = 6,
  URT_PRIMARY_MSG_KEY = 7,
  URT_PRIMARY_MSG_RUNTIME_EXCEPTION = 10
};
enum {
  URT_PRIMARY_SOURCE_ROBOT_INTERFACE = -2,  /* version, key messages            */
  URT_PRIMARY_SOURCE_RT_MACHINE = -3,       /* runtime exception, safety mode   */
  URT_PRIMARY_SOURCE_CONTROLLER = 7
};

/* ERROR_CODE report levels. */
enum {
  URT_PRIMARY_REPORT_DEBUG = 0,
  URT_PRIMARY_REPORT_INFO = 1,
  URT_PRIMARY_REPORT_WARNING = 2,
  URT_PRIMARY_REPORT_VIOLATION = 3,
  URT_PRIMARY_REPORT_FAULT = 4,
  URT_PRIMARY_REPORT_CRITICAL_FAULT = 5
};

/* The constant robot description that KINEMATICS_INFO and CONFIGURATION_DATA carry.
 * Filled once by urt_primary_robot_info_from_model(); the caller may override any field. */
typedef struct urt_primary_robot_info {
  double dh_a[URT_NJ], dh_d[URT_NJ];           /* [m]   */
  double dh_alpha[URT_NJ], dh_theta[URT_NJ];   /* [rad] */
  double q_min[URT_NJ], q_max[URT_NJ];         /* joint position limits       [rad]    */
  double qd_max[URT_NJ], qdd_max[URT_NJ];      /* joint speed/accel limits    [rad/s, rad/s²] */
  double v_joint_default, a_joint_default;     /* [rad/s, rad/s²] */
  double v_tool_default, a_tool_default;       /* [m/s, m/s²]     */
  double eq_radius;                            /* [m]             */
  int32_t masterboard_version, controller_box_type, robot_type, robot_sub_type;
  uint32_t checksum[URT_NJ];                   /* KINEMATICS_INFO checksum per joint */
  uint32_t calibration_status;
} urt_primary_robot_info_t;

/* Fill info from the loaded model: DH a/d/α/θ of the model's links (β is not on the wire),
 * limits of its joints, UR defaults for speeds (1.0472 rad/s, 1.3963 rad/s², 0.25 m/s,
 * 1.2 m/s², eq radius 0.25 m), robot_type 1 (UR5), board/box/sub-type of the version's line
 * (e-Series: URSim 5.8's 6/4/3; CB3: 3/3/0, unconfirmed), and the checksum of our
 * calibration (urt_primary_kinematics_checksum). Context: non-RT or RT (pure). */
void urt_primary_robot_info_from_model(const urt_version_t *v, const urt_model_t *m,
                                       urt_primary_robot_info_t *info);

/* Fill info->checksum from info's DH values: per joint, FNV-1a 32 of the big-endian bytes of
 * θ, a, d, α. Identical DH gives identical checksums; any change alters them. */
void urt_primary_kinematics_checksum(urt_primary_robot_info_t *info);

/* Total size (incl. its 5-byte header) of a sub-package in version v's ROBOT_STATE, or 0 if
 * the version does not send it. */
int urt_primary_subpackage_size(const urt_version_t *v, int sub_type);

/* ROBOT_STATE (type 16) of version v: sub-packages in URSim 5.8 order
 * 0, 1, 4, 5, 9, 3, 2, 6, 7, 8 (+ 11, 12 on e-Series); SAFETY_DATA (10) is UR-internal and not
 * sent. Robot-mode booleans follow s: connected/enabled ⇔ robot_mode > DISCONNECTED,
 * power on ⇔ POWER_ON … RUNNING, program running ⇔ program_state == PLAYING, paused ⇔ PAUSED,
 * protective stopped ⇔ safety_mode == PROTECTIVE_STOP, e-stopped ⇔ safety_mode 6/7.
 * The whole message is at most URT_PRIMARY_MAX_MESSAGE bytes for every version.
 * Returns the size or URT_ENOSPC. */
int urt_primary_encode_robot_state(const urt_version_t *v, const urt_primary_robot_info_t *info,
                                   const urt_snapshot_t *s, uint8_t *buf, size_t cap);

/* VERSION message: project "URControl", v's major/minor/bugfix/build, v->date as build date,
 * source −2. Returns the size or URT_ENOSPC. */
int urt_primary_encode_version(const urt_version_t *v, uint64_t timestamp_us, uint8_t *buf,
                               size_t cap);

/* TEXT message (type 0). Returns the size or URT_ENOSPC. */
int urt_primary_encode_text(uint64_t timestamp_us, int source, const char *text, uint8_t *buf,
                            size_t cap);

/* KEY message (type 7), e.g. title "PROGRAM_XXX_STARTED", text = program name.
 * Returns the size, URT_EINVAL (title longer than 255 bytes) or URT_ENOSPC. */
int urt_primary_encode_key(uint64_t timestamp_us, int source, int32_t code, int32_t argument,
                           const char *title, const char *text, uint8_t *buf, size_t cap);

/* POPUP (type 2), what URScript's popup() shows on the pendant: request id and requested type
 * (0, 0 for a script popup), the warning / error / blocking flags, title and text.
 * Returns the size, URT_EINVAL (title longer than 255 bytes) or URT_ENOSPC. */
int urt_primary_encode_popup(uint64_t timestamp_us, int source, uint32_t request_id,
                             uint32_t requested_type, bool warning, bool error, bool blocking,
                             const char *title, const char *text, uint8_t *buf, size_t cap);

/* RUNTIME_EXCEPTION (type 10): script line and column, text such as
 * "compile_error_name_not_found:foo:". Returns the size or URT_ENOSPC. */
int urt_primary_encode_runtime_exception(uint64_t timestamp_us, int source, uint32_t line,
                                         uint32_t column, const char *text, uint8_t *buf,
                                         size_t cap);

/* ERROR_CODE (type 6): code C<code>A<argument>, URT_PRIMARY_REPORT_* level, data type/value
 * and text. Returns the size or URT_ENOSPC. */
int urt_primary_encode_error_code(uint64_t timestamp_us, int source, int32_t code,
                                  int32_t argument, int32_t report_level, uint32_t data_type,
                                  uint32_t data, const char *text, uint8_t *buf, size_t cap);

/* SAFETY_MODE (type 5): code, argument, safety mode (protocols.md §2.8.2), report data type
 * and value. Returns the size or URT_ENOSPC. */
int urt_primary_encode_safety_mode(uint64_t timestamp_us, int source, int32_t code,
                                   int32_t argument, int safety_mode, uint32_t data_type,
                                   uint32_t data, uint8_t *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
