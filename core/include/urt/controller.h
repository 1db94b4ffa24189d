/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/controller.h — the UR controller's motion layer, run on the physics thread
 * at the controller rate (500 Hz e-Series, 125 Hz CB3).
 *
 *   urt_ctrl_cmd_t (values, through a ring) ──urt_ctrl_apply()──▶ urt_ctrl_t
 *   every controller period:  urt_ctrl_tick()  plans the set-point at the end of the period
 *   every physics step:       urt_ctrl_setpoint(s)  interpolates it (cubic Hermite in time)
 *                             into the urt_command_t the drives follow.
 *
 * Robot mode, safety mode and program state follow a real controller (protocols.md §2.8):
 * POWER_OFF → (power on) IDLE → (brake release) RUNNING; NORMAL ↔ PROTECTIVE_STOP.
 * Motion is accepted only in RUNNING + NORMAL; anything else refuses the command and reports it.
 */
#ifndef URT_CONTROLLER_H
#define URT_CONTROLLER_H

#include <stdint.h>

#include "urt/controller_motion_state.h"
#include "urt/data.h"
#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Robot mode (protocols.md §2.8.1). */
enum {
  URT_ROBOT_MODE_NO_CONTROLLER = -1,
  URT_ROBOT_MODE_DISCONNECTED = 0,
  URT_ROBOT_MODE_CONFIRM_SAFETY = 1,
  URT_ROBOT_MODE_BOOTING = 2,
  URT_ROBOT_MODE_POWER_OFF = 3,
  URT_ROBOT_MODE_POWER_ON = 4,
  URT_ROBOT_MODE_IDLE = 5,
  URT_ROBOT_MODE_BACKDRIVE = 6,
  URT_ROBOT_MODE_RUNNING = 7
};

/* Safety mode / safety status (protocols.md §2.8.2–3). */
enum {
  URT_SAFETY_MODE_NORMAL = 1,
  URT_SAFETY_MODE_REDUCED = 2,
  URT_SAFETY_MODE_PROTECTIVE_STOP = 3,
  URT_SAFETY_MODE_RECOVERY = 4,
  URT_SAFETY_MODE_SAFEGUARD_STOP = 5,
  URT_SAFETY_MODE_FAULT = 9
};

/* Program (runtime) state (protocols.md §2.8.4). */
enum {
  URT_PROGRAM_STOPPING = 0,
  URT_PROGRAM_STOPPED = 1,
  URT_PROGRAM_PLAYING = 2,
  URT_PROGRAM_PAUSING = 3,
  URT_PROGRAM_PAUSED = 4,
  URT_PROGRAM_RESUMING = 5
};

/* Joint mode (protocols.md §2.8.5). */
enum {
  URT_JOINT_MODE_BACKDRIVE = 238,
  URT_JOINT_MODE_POWER_OFF = 239,
  URT_JOINT_MODE_FAULT = 252,    /* the joint whose drive faulted (URT_CTRL_FAULT_JOINT)     */
  URT_JOINT_MODE_RUNNING = 253,
  URT_JOINT_MODE_IDLE = 255
};

/* What the motion generator is doing. */
typedef enum urt_ctrl_motion {
  URT_MOTION_IDLE = 0,   /* holding the last set-point                          */
  URT_MOTION_MOVEJ,      /* joint-space trapezoid                               */
  URT_MOTION_MOVEL,      /* Cartesian straight line, IK every tick              */
  URT_MOTION_SERVOJ,     /* online servo toward a streamed joint target          */
  URT_MOTION_SPEEDJ,     /* joint velocity ramp                                  */
  URT_MOTION_SPEEDL,     /* tool velocity ramp, resolved through the Jacobian    */
  URT_MOTION_STOP,       /* decelerating to rest (stopj/stopl, end of servo/speed) */
  URT_MOTION_DIRECT,     /* external joint set-points (LCM command channel)      */
  URT_MOTION_SERVOL,     /* online servo toward a streamed TCP pose               */
  URT_MOTION_SERVOC,     /* circular-blend servo toward a TCP pose at tool speed v */
  URT_MOTION_TORQUE,     /* direct joint-torque control of the drives             */
  URT_MOTION_FREEDRIVE,  /* teach mode: gravity-compensated, back-drivable arm    */
  URT_MOTION_FORCE,      /* force mode: compliant along selected task-frame axes  */
  URT_MOTION_PATH        /* a planned path of segments: blended movej/movel (r > 0), movep,
                            movec, optimovel (core/motion_path.cpp)                     */
} urt_ctrl_motion_t;

/* One command into the controller: a value, never a pointer. */
typedef enum urt_ctrl_cmd_kind {
  URT_CTRL_NONE = 0,
  /* motion (each carries id: the program waits until snapshot.motion_done_id >= id) */
  URT_CTRL_MOVEJ,        /* q[6], a, v, t (t > 0 overrides a and v), r (0: stop at target;
                            > 0: blend into the next planned motion, core/motion_path.cpp) */
  URT_CTRL_MOVEL,        /* pose[6], a, v, t, r                                  */
  URT_CTRL_SERVOJ,       /* q[6], t, lookahead_time, gain                          */
  URT_CTRL_SPEEDJ,       /* qd[6], a, t (t <= 0: until replaced)                   */
  URT_CTRL_SPEEDL,       /* xd[6], a, a_rot, t                                     */
  URT_CTRL_STOPJ,        /* a                                                      */
  URT_CTRL_STOPL,        /* a (tool deceleration, converted to joints)             */
  URT_CTRL_DIRECT,       /* q[6], qd[6], tau[6]: external set-point (LCM)          */
  /* I/O and settings */
  URT_CTRL_SET_DIGITAL_OUT,   /* index 0..17 (standard 0–7, configurable 8–15, tool 16–17), value */
  URT_CTRL_SET_ANALOG_OUT,    /* index 0..1, value [0..1]                                   */
  URT_CTRL_SET_SPEED_SLIDER,  /* value [0..1]                                               */
  URT_CTRL_SET_TCP,           /* pose[6]                                                    */
  URT_CTRL_SET_PAYLOAD,       /* value = mass [kg], pose[0..2] = CoG [m] (flange frame),
                                 tau[0..5] = inertia about the CoG, Ixx Iyy Izz Ixy Ixz Iyz
                                 [kg m²]; t = transition time [s] (0: at once): mounted on link 6
                                 from this tick (urt_data_set_payload_target)                */
  /* robot state machine */
  URT_CTRL_POWER_ON,
  URT_CTRL_POWER_OFF,
  URT_CTRL_BRAKE_RELEASE,
  URT_CTRL_UNLOCK_PSTOP,
  URT_CTRL_PROGRAM_STATE,     /* index = URT_PROGRAM_* (set by the program runner)          */
  URT_CTRL_HALT,              /* stop motion now at a (program stopped): like stopj         */
  /* added for the RTDE/dashboard and ur_rtde control issues */
  URT_CTRL_PAUSE,             /* program paused: planned motion decelerates along its path  */
  URT_CTRL_RESUME,            /* continue after PAUSE                                       */
  URT_CTRL_SET_WRENCH,        /* pose[6] = external wrench at the TCP, base frame [N, N m]   */
  URT_CTRL_SET_GRAVITY,       /* pose[0..2] = gravity vector in the base frame [m/s²], as the
                                 model's (floor: 0 0 −9.81; URScript set_gravity(d) gives the
                                 opposite, away from the earth: negate it). The controller's
                                 model only (feed-forward, freedrive), not the world's         */
  URT_CTRL_SERVOL,            /* pose[6], t, lookahead_time, gain (servoj in tool space)      */
  URT_CTRL_SERVOC,            /* pose[6], a, v, r (r treated as 0)                          */
  URT_CTRL_TORQUE,            /* tau[6] joint torques [N m] besides gravity (the controller
                                 adds its g(q)); index 0: no friction compensation, 1: the
                                 whole friction model, 2: q[6] its viscous and qd[6] its
                                 Coulomb part scaled (0..1 each, direct_torque's scales)     */
  URT_CTRL_FREEDRIVE,         /* index 1: enter teach mode; q[6] = free axes x y z rx ry rz
                                 (1 free, 0 held) of the feature frame pose[6] (base frame;
                                 zeros: the base); index 0: end and hold where the arm is    */
  URT_CTRL_FORCE_MODE,        /* pose = task frame, q = selection (0/1), tau = wrench,
                                 index = type (1..3), qd = limits (speeds [m/s, rad/s] of the
                                 compliant axes / deviations [m, rad] of the others); not a
                                 motion: a following SPEEDL runs inside it                    */
  URT_CTRL_FORCE_MODE_END,    /* leave force mode                                           */
  URT_CTRL_SET_TOOL_VOLTAGE,  /* value = 0, 12 or 24: the tool connector's supply [V]        */
  URT_CTRL_PROTECTIVE_STOP,   /* URScript protective_stop(): a protective stop now (RUNNING
                                 only), fault URT_CTRL_FAULT_SCRIPT_PSTOP (C209A0 on 30001)   */
  /* added by the motions issue (core/motion_*.cpp) */
  URT_CTRL_OPTIMOVEJ,         /* q[6], a, v: fractions in (0, 1] of every joint's maximum
                                 acceleration and speed (qdd_max, qd_max; the planner keeps
                                 its margins 0.9, 0.98); r as movej. A motion: done on arrival */
  /* added by the replay (urt_sim --replay) */
  URT_CTRL_SETPOINT,          /* q[6], qd[6], pose[0..5] = q̈[6], tau[6]: a complete joint
                                 set-point at the end of the period, as a recorded controller's
                                 target_q/qd/qdd; otherwise as DIRECT (done in its period) */
  /* added by the hardening issue: what the world wires to the control box's inputs */
  URT_CTRL_SET_INPUTS,        /* index = mask of the digital inputs to change (bits 0–7
                                 standard, 8–15 configurable, 16–17 tool), value = their new
                                 levels (the same bits, an integer); a = mask of the analog
                                 inputs to change (bit 0–1 standard 0–1, bit 2–3 tool 0–1),
                                 q[0..3] = their values [V], in [0, 10]                     */
  URT_CTRL_ZERO_FTSENSOR,     /* pose[6] = the raw TCP wrench (snapshot tcp_force_raw) that
                                 reads zero from now on: zero_ftsensor()                     */
  /* added by the blends and process moves (core/motion_path.cpp) */
  URT_CTRL_MOVEP,             /* pose[6], a, v, r: the tool at constant speed v on lines,
                                 circular blends of radius r between them                   */
  URT_CTRL_MOVEC,             /* pose[6] = pose_to, q[6] = pose_via (position used), a, v, r,
                                 index = mode (0: orientation interpolated to pose_to, 1: fixed
                                 relative to the arc's tangent)                             */
  URT_CTRL_OPTIMOVEL,         /* pose[6], a, v: fractions in (0, 1] of the tool acceleration and
                                 speed the joints allow along the line (qdd_max, qd_max with the
                                 planner's margins 0.9, 0.98), r as movel                    */
  /* added by the fault issue: live injection (URTWIN_FAULT on LCM) */
  URT_CTRL_FAULT,             /* inject (index 1) or clear (index 0) a fault in the physics;
                                 fields as urt_fault_cmd_pack (urt/faults.h) writes them. An
                                 onset before the tick's time starts the profile at the tick.
                                 Invalid or with URT_MAX_FAULTS installed: refused
                                 (URT_CTRL_FAULT_BAD_ARGUMENT), counted in faults_refused    */
  /* added by the fault issue: the way out of a joint fault */
  URT_CTRL_RESTART_SAFETY     /* dashboard `restart safety`: a FAULT safety mode (a joint
                                 fault) clears to NORMAL with the arm powered off; the
                                 dashboard sends POWER_OFF first                            */
} urt_ctrl_cmd_kind_t;

typedef struct urt_ctrl_cmd {
  int32_t kind;          /* urt_ctrl_cmd_kind_t                        */
  int32_t index;         /* I/O index or program state                 */
  uint64_t id;           /* motion id, increasing per producer; 0 for non-motion */
  double q[URT_NJ];      /* joint target [rad], or joint speeds [rad/s] for speedj */
  double pose[6];        /* pose p[x y z rx ry rz] or tool speed [m/s, rad/s]       */
  double tau[URT_NJ];    /* torque feed-forward [N m] (DIRECT)         */
  double qd[URT_NJ];     /* velocity feed-forward [rad/s] (DIRECT)     */
  double a, v, t, r;     /* acceleration, speed, time, blend radius    */
  double a_rot;          /* rotational acceleration (speedl, stopl)    */
  double lookahead_time; /* servoj                                     */
  double gain;           /* servoj                                     */
  double value;          /* digital/analog value, slider, payload mass */
  uint64_t tick;         /* a program's command: the controller tick whose slice issued it
                            (urt_ctrl_t.tick when it was issued); applied on time at that tick's
                            end, later when the program's thread ran late. 0: not stamped */
} urt_ctrl_cmd_t;

/* Why the controller refused or aborted something (bits in urt_ctrl_t.fault, copied to the
 * snapshot so the program runner can report it as a runtime error / protective stop). */
enum {
  URT_CTRL_FAULT_NOT_RUNNING = 1u << 0,    /* motion while not RUNNING+NORMAL            */
  URT_CTRL_FAULT_BAD_TARGET = 1u << 1,     /* NaN/Inf or out-of-limit target → pstop     */
  URT_CTRL_FAULT_IK = 1u << 2,             /* no inverse-kinematics solution             */
  URT_CTRL_FAULT_BAD_ARGUMENT = 1u << 3,   /* a, v, t, gain… outside the allowed range   */
  URT_CTRL_FAULT_PSTOP = 1u << 4,          /* the physics entered a protective stop      */
  URT_CTRL_FAULT_SCRIPT_PSTOP = 1u << 5,   /* a program asked for it (protective_stop())  */
  URT_CTRL_FAULT_JUMP = 1u << 6,           /* an external set-point (DIRECT) further from the
                                              set-point than its joint moves in one period at
                                              qd_max → pstop (C204A0 on 30001)            */
  URT_CTRL_FAULT_ENCODER = 1u << 7,        /* a joint's motor and joint encoders disagree by
                                              more than URT_ENCODER_TOLERANCE → pstop    */
  URT_CTRL_FAULT_JOINT = 1u << 8           /* a joint's drive asked for its current limit for
                                              URT_OVERCURRENT_TIME (over-current): the joint
                                              faults, safety mode FAULT, arm powered off */
};

#define URT_SERVOJ_REPLAY 32  /* periods a late servoj can be run from its issuing tick */
/* [rad] how far a joint's motor encoder (over the gear ratio) and joint encoder may disagree,
 * beyond where they stood when the arm last was not running, before the controller stops the
 * arm (core/controller_encoders.cpp). [P]: UR documents the check, not its threshold. Above the
 * largest the model's joints show without a sensor fault: 0.04 rad, the shoulder with its gear
 * stiffness at the catalogue's 4 % under the excitation trajectory (healthy: 8e-4). */
#define URT_ENCODER_TOLERANCE 0.05
/* [s] how long a running joint's drive may ask for its whole current (|i_ref| at i_max, the
 * drive's limit) before the controller takes it for an over-current and faults the joint
 * (core/controller_overcurrent.cpp). [P]: UR's joint firmware has the protection, its
 * threshold is not public. A planned motion's feed-forward stays within torque_max (the
 * physics protective-stops it otherwise), so a healthy arm saturates only in tracking
 * transients of a few milliseconds; a drive held at its limit this long carries a load it
 * cannot (a collision, a dragging brake, a motor that lost its torque constant). */
#define URT_OVERCURRENT_TIME 0.25

typedef struct urt_ctrl {
  double period;              /* controller period [s] (0.002 or 0.008)          */
  int n_sub;                  /* physics steps per period (period / m->dt)       */
  uint64_t tick;              /* controller ticks since start                     */

  /* robot state machine */
  int32_t robot_mode, safety_mode, program_state;
  uint32_t fault;             /* URT_CTRL_FAULT_* of the most recent refusal (sticky until next motion) */

  /* I/O and settings */
  uint32_t digital_out;       /* bits 0–7 standard, 8–15 configurable, 16–17 tool */
  double analog_out[2];
  double speed_slider;        /* [0..1] target speed fraction                     */
  double speed_scaling;       /* actual scaling applied by the trajectory         */
  double tcp_offset[6];
  double payload_mass, payload_cog[3];

  /* motion generator */
  urt_ctrl_motion_t motion;
  uint64_t motion_id;         /* id of the motion being executed (0 none)          */
  uint64_t motion_done_id;    /* highest id finished (or aborted)                  */
  double seg_time;            /* time into the current motion [s]                  */
  urt_ctrl_cmd_t active;      /* the command being executed                        */
  urt_ctrl_motion_state_t motion_state; /* the running motion's own state (its member)  */

  /* set-points: at the start (0) and end (1) of the current period; the physics steps
   * interpolate between them */
  double q0[URT_NJ], qd0[URT_NJ], qdd0[URT_NJ];
  double q1[URT_NJ], qd1[URT_NJ], qdd1[URT_NJ];
  double tau_ff[URT_NJ];      /* external torque feed-forward (DIRECT)             */

  /* added by core/controller.cpp (not in the first contract) */
  double tau_model0[URT_NJ], tau_model1[URT_NJ]; /* model feed-forward at the period's ends:
                              * inverse dynamics + friction of the set-point − tau_bias [N m] */
  double tau_bias[URT_NJ];    /* gravity at the initial pose, which urt_data_init's integrators
                               * already carry                              [N m]  */
  double traj_time;           /* time along a planned motion, advanced at speed_scaling [s] */
  urt_ctrl_cmd_t pending;     /* movej/movel waiting for the arm to stop (has_pending)  */
  int has_pending;
  double temperature[URT_NJ]; /* motor winding temperature (thermal model)  [°C]  */

  /* added for pause, gravity, torque control, freedrive and force mode (core/controller.cpp) */
  int32_t paused;             /* 1 from PAUSE to RESUME (or PROGRAM_STATE STOPPED)        */
  double pause_scale;         /* [0..1] the pause's factor on planned-motion time, slewed  */
  uint32_t torque_mask;       /* joints whose drives run in torque mode (bit j)           */
  uint32_t torque_mask_last;  /* the mask the last period's set-points carried            */
  double gravity[3];          /* the controller's gravity (SET_GRAVITY), base  [m/s²]     */
  int32_t force_mode;         /* 1 while force mode is on                                 */
  urt_ctrl_cmd_t force;       /* its parameters: the last FORCE_MODE                      */
  int32_t tool_voltage;       /* the tool connector's supply (SET_TOOL_VOLTAGE)  [V]      */

  /* added by the hardening issue: the inputs (SET_INPUTS), first of the fields the recorded
   * controller hashes leave out (tests/core/test_controller_hash.c) */
  uint32_t digital_in;        /* bits 0–7 standard, 8–15 configurable, 16–17 tool */
  double analog_in[2];        /* standard analog inputs [V]                       */
  double tool_analog_in[2];   /* tool analog inputs [V]                           */
  double ft_bias[6];          /* subtracted from the TCP wrench (ZERO_FTSENSOR) [N, N m] */

  /* added by the fault issue: live fault commands (URT_CTRL_FAULT) applied and refused */
  uint32_t faults_applied, faults_refused;

  /* a speedj stream's debt (core/motion_speedj.cpp): the speed (motion time) still behind the
   * on-time stream after a program's speedj came late, the speed a speedj last ran at, and the
   * tick whose period that was (the next speedj inherits the debt when it follows at once) */
  double speedj_owed[URT_NJ], speedj_w[URT_NJ];
  uint64_t speedj_tick;

  /* a servoj stream's last periods (core/motion_servoj.cpp), so that a program's servoj that
   * reaches the controller late runs from the tick after the one that issued it: each slot, by
   * tick % URT_SERVOJ_REPLAY, the set-point at the start of that tick (a re-run goes toward the
   * late command's target); and the tick at which servoj's timeout began the stop that runs now
   * (0: none) */
  struct urt_servoj_replay {
    uint64_t tick[URT_SERVOJ_REPLAY];
    double q[URT_SERVOJ_REPLAY][URT_NJ], qd[URT_SERVOJ_REPLAY][URT_NJ];
    uint64_t timeout_tick;
  } servoj_replay;

  /* the newest controller tick whose slice the running program's thread has delivered (its
   * commands are in the rings; 0: no program runs), set by the loop before each period. A
   * program's command is due at the period after its tick: while this is behind that, the
   * program's thread runs late (descheduled) and its next command is still to come
   * (core/motion_speedj.cpp). */
  uint64_t program_slice;

  /* the motor/joint encoder check (core/controller_encoders.cpp): per joint, the motor-side
   * angle error the motor encoder's faults have accumulated [rad, motor side], the
   * disagreement (motor side / ratio − joint encoder) when the arm last was not running
   * [rad], and the joint whose check stopped the arm (−1: none) */
  double enc_motor_err[URT_NJ], enc_anchor[URT_NJ];
  int32_t enc_joint;

  /* the over-current check (core/controller_overcurrent.cpp): per joint, how long its drive
   * has asked for its current limit without a break [s], and the joint that faulted (−1:
   * none; set with safety mode FAULT) */
  double oc_time[URT_NJ];
  int32_t fault_joint;
} urt_ctrl_t;

/* Start at rest at the data's joint positions, in RUNNING + NORMAL (powered = 1) or
 * POWER_OFF (powered = 0), program STOPPED. period must be a whole number of m->dt.
 * Context: init. Returns 0 or URT_EINVAL. */
int urt_ctrl_init(const urt_model_t *m, urt_ctrl_t *c, const urt_data_t *d, double period,
                  int powered);

/* Apply one command (called for every command drained from the rings, before the tick).
 * Invalid commands set c->fault and, for bad targets, a protective stop. Context: RT. */
void urt_ctrl_apply(const urt_model_t *m, urt_ctrl_t *c, urt_data_t *d, const urt_ctrl_cmd_t *cmd);

/* Plan the next period: advance the motion generator by c->period, producing q1/qd1/qdd1.
 * Follows the physics' protective stop (d->pstop) into PROTECTIVE_STOP. d's outputs must be
 * those of its state (urt_data_update_outputs after the last period's steps, as the loop's
 * snapshot does): the over-current check reads the drives' i_ref there. Context: RT. */
void urt_ctrl_tick(const urt_model_t *m, urt_ctrl_t *c, urt_data_t *d);

/* The drive command at physics step k (0..n_sub-1) of the current period. Context: RT. */
void urt_ctrl_setpoint(const urt_model_t *m, const urt_ctrl_t *c, int k, urt_command_t *out);

/* Inverse kinematics of the calibrated model: joint positions q reaching TCP pose (base frame,
 * axis-angle) closest to qnear. Context: RT (bounded iterations, no allocation).
 * Returns 0, or URT_ERANGE when no solution within 1e-10 m / 1e-10 rad exists. */
int urt_ctrl_inverse_kinematics(const urt_model_t *m, const double pose[6],
                                const double qnear[URT_NJ], double q[URT_NJ]);

/* As urt_ctrl_inverse_kinematics, with the TCP at flange · tcp (x y z rx ry rz) instead of the
 * model's fixed TCP (the controller's runtime set_tcp). Context: RT. */
int urt_ctrl_inverse_kinematics_tcp(const urt_model_t *m, const double tcp[6],
                                    const double pose[6], const double qnear[URT_NJ],
                                    double q[URT_NJ]);

/* TCP pose (base frame, axis-angle) at q with the TCP at flange · tcp. Context: RT. */
void urt_ctrl_forward_kinematics_tcp(const urt_model_t *m, const double tcp[6],
                                     const double q[URT_NJ], double pose[6]);

#ifdef __cplusplus
}
#endif
#endif
