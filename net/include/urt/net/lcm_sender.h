/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/lcm_sender.h — the LCM messages of urtwin as pure functions: fill a status
 * or drive message from what the loop published, decode and check a command. Nothing here
 * touches a socket, a clock or a thread (Drake's iiwa_status_sender: "does not actually send
 * the message"); net/lcm/lcm_bridge.c does the sending.
 *
 *   urt_snapshot_t      ──urt_lcm_status_fill()──▶  lcmt_urtwin_status   (one per controller tick)
 *   urt_drive_sample_t  ──urt_lcm_drive_fill()───▶  lcmt_urtwin_drive
 *   lcmt_urtwin_command ──urt_lcm_command_to_ctrl()──▶ urt_ctrl_cmd_t (URT_CTRL_DIRECT)
 *
 * The message types are generated at build time by lcm-gen from the files in net/lcm/types/.
 */
#ifndef URT_NET_LCM_SENDER_H
#define URT_NET_LCM_SENDER_H

#include <stddef.h>
#include <stdint.h>

#include "urt/controller.h"
#include "urt/faults.h"
#include "urt/loop.h"
#include "urt/snapshot.h"
#include "urtwin_lcmt_urtwin_command.h"
#include "urtwin_lcmt_urtwin_drive.h"
#include "urtwin_lcmt_urtwin_fault.h"
#include "urtwin_lcmt_urtwin_fault_truth.h"
#include "urtwin_lcmt_urtwin_io.h"
#include "urtwin_lcmt_urtwin_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fill a status message from the snapshot of one controller tick. utime is the controller time
 * in microseconds (rounded), as Drake's simulated iiwa does; publish_utime [us since the epoch]
 * and ticks_lost are the publisher's, passed in so the function stays pure.
 * Context: any; no allocation (the message has only fixed-size arrays). */
void urt_lcm_status_fill(const urt_snapshot_t *s, int64_t publish_utime, int64_t ticks_lost,
                         urtwin_lcmt_urtwin_status *msg);

/* Fill a drive message from one drive sample; samples_lost as for ticks_lost.
 * Context: any; no allocation. */
void urt_lcm_drive_fill(const urt_drive_sample_t *d, int64_t samples_lost,
                        urtwin_lcmt_urtwin_drive *msg);

/* Check a decoded command and turn it into a URT_CTRL_DIRECT controller command with the given
 * motion id (q = joint_position, qd = joint_velocity or 0, tau = joint_torque or 0).
 * Returns 0, URT_EPROTO (num_joints != 6, num_velocities or num_torques not 0 or 6, or a NULL
 * array where the count says 6) or URT_ERANGE (a NaN or infinite value). On failure *out is
 * untouched. Context: any; no allocation. */
int urt_lcm_command_to_ctrl(const urtwin_lcmt_urtwin_command *msg, uint64_t id,
                            urt_ctrl_cmd_t *out);

/* Decode an encoded lcmt_urtwin_command (as received on the command channel) and check it as
 * urt_lcm_command_to_ctrl does. Returns 0, URT_EPROTO (not a well-formed lcmt_urtwin_command:
 * wrong fingerprint, truncated, trailing bytes, bad counts) or URT_ERANGE (NaN or infinite).
 * On failure *out is untouched. Context: non-RT (the generated decoder allocates the arrays). */
int urt_lcm_command_decode(const void *buf, size_t len, uint64_t id, urt_ctrl_cmd_t *out);

/* Decode an encoded lcmt_urtwin_io (as received on the I/O channel) into a URT_CTRL_SET_INPUTS
 * command. Returns 0, URT_EPROTO (not a well-formed lcmt_urtwin_io) or URT_ERANGE (a mask
 * outside the 18 digital pins or 4 analog inputs, levels outside the mask, an analog value
 * named by the mask not finite or outside [0, 10] V). On failure *out is untouched.
 * Context: any; no allocation (the type has no variable-length arrays). */
int urt_lcm_io_decode(const void *buf, size_t len, urt_ctrl_cmd_t *out);

/* Decode an encoded lcmt_urtwin_fault (as received on the fault channel) into a URT_CTRL_FAULT
 * command (urt_fault_cmd_pack). An injection is checked as a scenario file's entry would be
 * (urt_fault_spec_invalid against m; with m NULL only what needs no model: class, profile and
 * location names); a collision's direction is normalised. Returns 0, URT_EPROTO (not a
 * well-formed lcmt_urtwin_fault) or URT_ERANGE (unknown class, profile or location, a target,
 * severity or profile the class refuses, a seed outside [0, 2^53)). On failure *out is
 * untouched. Context: non-RT (the generated decoder allocates the strings). Nullable: m. */
int urt_lcm_fault_decode(const void *buf, size_t len, const urt_model_t *m, urt_ctrl_cmd_t *out);

/* A fault-truth message with its arrays: urt_lcm_fault_truth_fill points msg's arrays into this
 * struct (class names at the static urt_fault_class_name strings), so filling allocates
 * nothing. Not copyable by assignment (msg points into it). */
typedef struct urt_lcm_fault_truth_buf {
  urtwin_lcmt_urtwin_fault_truth msg;
  char *fault_class[URT_MAX_FAULTS];
  int32_t joint[URT_MAX_FAULTS], component[URT_MAX_FAULTS];
  int8_t active[URT_MAX_FAULTS];
  double severity[URT_MAX_FAULTS], onset[URT_MAX_FAULTS];
} urt_lcm_fault_truth_buf_t;

/* Fill b->msg from the snapshot of one tick (its fault_truth). utime as the status's.
 * Context: any; no allocation. */
void urt_lcm_fault_truth_fill(const urt_snapshot_t *s, urt_lcm_fault_truth_buf_t *b);

#ifdef __cplusplus
}
#endif
#endif
