/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/snapshot.h — everything the outside world may know about the robot at one
 * controller tick: a POD copied out of the physics thread through a seqlock history
 * (urt/loop.h). Every protocol encoder (30001–30003, RTDE, LCM, DDS) reads only this.
 * SI units; joint order base → wrist 3; poses x y z [m], rx ry rz axis-angle [rad].
 */
#ifndef URT_SNAPSHOT_H
#define URT_SNAPSHOT_H

#include <stdint.h>

#include "urt/controller.h"
#include "urt/data.h"
#include "urt/faults.h"
#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_snapshot {
  /* time */
  uint64_t tick;              /* controller ticks since start                         */
  double time;                /* controller time = tick · period            [s]       */
  double period;              /* controller period                          [s]       */
  double sim_time;            /* physics time (= time)                      [s]       */

  /* joints: target (the motion generator) */
  double q_target[URT_NJ], qd_target[URT_NJ], qdd_target[URT_NJ];
  double i_target[URT_NJ];    /* motor current the target motion needs: τ_id/(k_t·N) [A] */
  double m_target[URT_NJ];    /* target joint torque, inverse dynamics of the target [N m] */
  /* joints: actual (the physics) */
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  double i_actual[URT_NJ];    /* measured motor current                     [A]       */
  double i_control[URT_NJ];   /* current reference of the PI cascade        [A]       */
  double tau[URT_NJ];         /* joint output torque T_CS                   [N m]     */
  double tau_from_current[URT_NJ]; /* the measured current as joint torque, i·k_t·N [N m] */
  double gravity_target[3];   /* the controller's gravity (set_gravity), base [m/s²]   */
  double v_actual[URT_NJ];    /* motor voltage                              [V]       */
  double temperature[URT_NJ]; /* motor winding temperature                  [°C]      */
  int32_t joint_mode[URT_NJ]; /* URT_JOINT_MODE_*                                      */

  /* tool */
  double tcp_pose[6], tcp_speed[6];               /* actual                       */
  double tcp_pose_target[6], tcp_speed_target[6];
  double tcp_force[6];        /* wrench at the TCP estimated from the joint-torque residual,
                               * less what zero_ftsensor zeroed (ctrl ft_bias)     [N, N m] */
  double tcp_force_raw[6];    /* the same before that offset                       [N, N m] */
  double tcp_offset[6];       /* active TCP offset from the flange                         */
  double tool_accel[3];       /* tool accelerometer, tool frame             [m/s²]    */
  double elbow_pos[3], elbow_vel[3];  /* elbow joint: origin of DH frame 2 (on the axis of
                                       * joint 3, the elbow), base frame [m, m/s] */
  double payload_mass, payload_cog[3];  /* the mounted payload: flange frame [kg, m] */
  double payload_inertia[6];  /* its inertia about the CoG, Ixx Iyy Izz Ixy Ixz Iyz [kg m²] */
  double momentum;            /* norm of the arm's linear momentum Σ m v_CoM [kg m/s]  */

  /* power */
  double v_main, v_robot, i_robot;  /* 48 V supply, robot current           [V, A]   */

  /* I/O */
  uint32_t digital_in, digital_out; /* bits 0–7 standard, 8–15 configurable, 16–17 tool */
  double analog_out[2];
  double analog_in[2], tool_analog_in[2];  /* inputs in voltage mode (SET_INPUTS)  [V]      */

  /* modes */
  int32_t robot_mode, safety_mode, safety_status, program_state, control_mode;
  uint32_t pstop;             /* physics protective-stop causes (URT_PSTOP_*)          */
  uint32_t ctrl_fault;        /* URT_CTRL_FAULT_* of the last refusal                  */
  double speed_slider, speed_scaling;
  double motion_rate;  /* the rate of motion time (slider × pause, without speedj's limiter):
                          speedj's t and the VM's waits for it count in it */

  /* motion bookkeeping (the program runner waits on these) */
  int32_t motion;             /* urt_ctrl_motion_t                                     */
  uint64_t motion_id, motion_done_id;

  /* drive internals (LCM drive message, PHM research) */
  double motor_angle[URT_NJ], motor_speed[URT_NJ];  /* q_M, q̇_M              [rad, rad/s] */
  double gear_in_torque[URT_NJ];                      /* wave-generator input T_in [N m] */
  double friction_torque[URT_NJ];                     /* LuGre T_f            [N m]     */
  double flex_x[URT_NJ], flex_y[URT_NJ];              /* flexspline deflection [m]      */
  double bristle_z[URT_NJ];                           /* LuGre z              [rad]     */

  /* loop diagnostics */
  double exec_time;           /* physics time spent in the last period      [s]       */
  uint64_t overruns;          /* periods that finished late                           */
  uint64_t missed_periods;    /* whole periods skipped to catch up                    */
  uint64_t cmd_dropped;       /* commands refused because a ring was full             */
  int32_t tool_voltage;       /* tool connector supply (set_tool_voltage)   [V]       */
  int64_t published_wall_ns;  /* CLOCK_REALTIME when the loop published this tick [ns]
                               * (DDS source timestamps: tick → subscriber latency)   */

  /* fault ground truth at the tick (urt_faults_truth; LCM URTWIN_FAULT_TRUTH) */
  urt_fault_truth_t fault_truth;
  uint32_t faults_applied, faults_refused;  /* live fault commands (URT_CTRL_FAULT)   */
  int32_t enc_joint;          /* the joint whose encoders disagreed (URT_PSTOP_ENCODER), −1 */
  int32_t fault_joint;        /* the joint in its fault state (URT_CTRL_FAULT_JOINT), −1   */
} urt_snapshot_t;

/* Fill a snapshot from the physics and the controller (calls urt_data_update_outputs).
 * Context: RT (no allocation). */
void urt_snapshot_fill(const urt_model_t *m, const urt_ctrl_t *c, urt_data_t *d,
                       urt_snapshot_t *s);

#ifdef __cplusplus
}
#endif
#endif
