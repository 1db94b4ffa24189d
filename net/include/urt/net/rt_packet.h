/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/rt_packet.h — the port 30003 (and 30013) real-time packet
 * (protocols.md §1): int32 size, then big-endian doubles in a fixed order that each software
 * generation extends at the end (1044 / 1060 / 1108 / 1116 bytes).
 */
#ifndef URT_NET_RT_PACKET_H
#define URT_NET_RT_PACKET_H

#include <stddef.h>
#include <stdint.h>

#include "urt/net/version.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Byte offsets of the fields (from the first byte of the packet, size field at 0). */
enum {
  URT_RT_OFF_TIME = 4,
  URT_RT_OFF_Q_TARGET = 12,
  URT_RT_OFF_QD_TARGET = 60,
  URT_RT_OFF_QDD_TARGET = 108,
  URT_RT_OFF_I_TARGET = 156,
  URT_RT_OFF_M_TARGET = 204,
  URT_RT_OFF_Q_ACTUAL = 252,
  URT_RT_OFF_QD_ACTUAL = 300,
  URT_RT_OFF_I_ACTUAL = 348,
  URT_RT_OFF_I_CONTROL = 396,
  URT_RT_OFF_TOOL_VECTOR_ACTUAL = 444,
  URT_RT_OFF_TCP_SPEED_ACTUAL = 492,
  URT_RT_OFF_TCP_FORCE = 540,
  URT_RT_OFF_TOOL_VECTOR_TARGET = 588,
  URT_RT_OFF_TCP_SPEED_TARGET = 636,
  URT_RT_OFF_DIGITAL_INPUTS = 684,
  URT_RT_OFF_MOTOR_TEMPERATURES = 692,
  URT_RT_OFF_CONTROLLER_TIMER = 740,
  URT_RT_OFF_TEST_VALUE = 748,
  URT_RT_OFF_ROBOT_MODE = 756,
  URT_RT_OFF_JOINT_MODES = 764,
  URT_RT_OFF_SAFETY_MODE = 812,
  URT_RT_OFF_TOOL_ACCELEROMETER = 868,
  URT_RT_OFF_SPEED_SCALING = 940,
  URT_RT_OFF_LINEAR_MOMENTUM_NORM = 948,
  URT_RT_OFF_V_MAIN = 972,
  URT_RT_OFF_V_ROBOT = 980,
  URT_RT_OFF_I_ROBOT = 988,
  URT_RT_OFF_V_ACTUAL = 996,
  URT_RT_OFF_DIGITAL_OUTPUTS = 1044,  /* 3.2+ */
  URT_RT_OFF_PROGRAM_STATE = 1052,    /* 3.2+ */
  URT_RT_OFF_ELBOW_POSITION = 1060,   /* 3.5+ / 5.0+ */
  URT_RT_OFF_ELBOW_VELOCITY = 1084,   /* 3.5+ / 5.0+ */
  URT_RT_OFF_SAFETY_STATUS = 1108     /* 3.10+ / 5.4+ */
};

#define URT_RT_PACKET_MAX 1116  /* largest packet this encoder writes [bytes] */

/* Encode the real-time packet of version v from snapshot s into buf: exactly
 * urt_version_rt_packet_size(v) bytes, every field of protocols.md §1.2 that the version has.
 * Digital bits are sent as doubles whose value is the bit mask; "controller timer" is
 * s->exec_time; reserved fields and the test value are 0; the linear momentum norm is the
 * arm's (s->momentum).
 * Context: any (pure; no allocation).
 * Returns the number of bytes written, or 0 if cap is smaller than the packet (buf untouched
 * beyond cap). */
size_t urt_rt_packet_encode(const urt_version_t *v, const urt_snapshot_t *s, uint8_t *buf,
                            size_t cap);

#ifdef __cplusplus
}
#endif
#endif
