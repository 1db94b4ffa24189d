/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/data.h — the mutable state of one simulated robot. Caller-owned, fixed
 * size, no pointers: it can be copied with memcpy.
 */
#ifndef URT_DATA_H
#define URT_DATA_H

#include <stdint.h>

#include "urt/drivers/sensors.h"
#include "urt/fault_state.h"
#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Index of each continuous state within a joint's 21 (model.md §1.9, reordered so that the
 * 18 drive-block states come first and the arm interface (q, q̇, z) last). */
enum {
  URT_X_I = 0,     /* motor current i                         [A]     */
  URT_X_XI_C,      /* current-loop integrator ξ_c             [A s]   */
  URT_X_I_F,       /* current-sensor filter output            [A]     */
  URT_X_QM,        /* motor angle q_M                         [rad]   */
  URT_X_QDM,       /* motor speed q̇_M                         [rad/s] */
  URT_X_QWG,       /* wave-generator angle                    [rad]   */
  URT_X_QDWG,      /* wave-generator speed                    [rad/s] */
  URT_X_XFS,       /* flexspline x                            [m]     */
  URT_X_XDFS,      /*                                         [m/s]   */
  URT_X_YFS,       /* flexspline y                            [m]     */
  URT_X_YDFS,      /*                                         [m/s]   */
  URT_X_QCS,       /* circular-spline angle                   [rad]   */
  URT_X_QDCS,      /* circular-spline speed                   [rad/s] */
  URT_X_XI_V,      /* speed-loop integrator ξ_v               [rad]   */
  URT_X_W,         /* motor-speed filter output               [rad/s] */
  URT_X_WD,        /* its rate                                [rad/s²] */
  URT_X_P,         /* joint-position filter output            [rad]   */
  URT_X_PD,        /* its rate                                [rad/s] */
  URT_X_Q,         /* joint angle q (arm DoF)                 [rad]   */
  URT_X_QD,        /* joint speed q̇                           [rad/s] */
  URT_X_Z          /* LuGre bristle deflection z              [rad]   */
};

/* Protective-stop causes (bit mask in urt_data_t.pstop). */
enum {
  URT_PSTOP_NONFINITE_CMD = 1u << 0,   /* NaN/Inf in a command            */
  URT_PSTOP_POS_LIMIT = 1u << 1,       /* set-point outside joint limits  */
  URT_PSTOP_SPEED_LIMIT = 1u << 2,     /* speed set-point above qd_max    */
  URT_PSTOP_ACC_LIMIT = 1u << 3,       /* acceleration above qdd_max      */
  URT_PSTOP_TORQUE_LIMIT = 1u << 4,    /* torque feed-forward too large   */
  URT_PSTOP_NONFINITE_STATE = 1u << 5, /* the integrator produced NaN/Inf or an implausible state */
  URT_PSTOP_ENCODER = 1u << 6          /* a joint's motor and joint encoders disagree (the
                                        * controller's check, core/controller_encoders.cpp) */
};

/* One joint command, valid from the current step on. Within a step the set-point follows
 * q(t) = q + q̇ s + q̈ s²/2 (s = time since the step began), which the integrator differentiates.
 * A joint whose bit is set in torque_mask is torque-controlled: its drive's position and speed
 * loops are off (ξ_v held), the current reference is tau_ff/(k_t τ) clamped to ±i_max, and
 * q, q̇ only pass the command checks (q̈ stays the other joints' estimate of its acceleration).
 * Zero the whole struct before filling it. */
typedef struct urt_command {
  double q[URT_NJ];        /* position set-point            [rad]    */
  double qd[URT_NJ];       /* velocity feed-forward         [rad/s]  */
  double qdd[URT_NJ];      /* acceleration                  [rad/s²] */
  double tau_ff[URT_NJ];   /* output-torque feed-forward    [N m]    */
  uint32_t torque_mask;    /* bit j: joint j in torque mode (0: all position-controlled) */
} urt_command_t;

/* Model parameters that change while the robot runs: the physics reads them from here, not from
 * the const model. urt_data_init copies them from the model; a change is a value the
 * controller installs between two controller ticks (urt_data_set_*), so the physics steps of
 * one period all see the same parameters and the next period the new ones. */
typedef struct urt_live_params {
  urt_payload_t payload;             /* what link 6 carries (set_payload, set_target_payload) */
  /* the inertia tensor as declared (the loader, set_target_payload): what the controller
   * reports (get_target_payload_inertia, RTDE payload_inertia). payload.inertia is its nearest
   * PSD tensor (urt_payload_physical), which the physics carries */
  double payload_inertia_declared[6];
  /* a transition in progress (set_target_payload's transition_time): payload moves linearly
   * to payload_target, reaching it when payload_time_left [s] runs out (0: none) */
  urt_payload_t payload_target;
  double payload_time_left;
} urt_live_params_t;

typedef struct urt_data {
  /* state — advanced by the integrator */
  double t;                          /* simulation time                [s]    */
  uint64_t steps;                    /* steps taken                            */
  double x[URT_NJ][URT_NXJ];         /* continuous states, URT_X_* order       */

  /* inputs — written by urt_command_set() between steps */
  urt_command_t cmd;                 /* the command the step uses               */
  double wrench_ext[6];              /* external force/torque at the TCP, base frame [N, N m] */

  /* discrete states — held measurement errors and the RNG */
  double eps_i[URT_NJ], eps_w[URT_NJ], eps_q[URT_NJ];
  urt_rng_t rng;

  /* derived — qdd by every step; the rest by urt_data_update_outputs(), which the reader
   * calls at its own sampling rate (a 500 Hz controller needs them 40× less often) */
  double qdd[URT_NJ];                /* mean joint acceleration over the last step [rad/s²] */
  double i_fb[URT_NJ];               /* measured current               [A]      */
  double qdm_fb[URT_NJ];             /* measured motor speed           [rad/s]  */
  double q_fb[URT_NJ];               /* measured joint position        [rad]    */
  double i_ref[URT_NJ];              /* current reference              [A]      */
  double v_sup[URT_NJ];              /* motor voltage                  [V]      */
  double t_in[URT_NJ];               /* wave-generator input torque    [N m]    */
  double t_cs[URT_NJ];               /* gear output torque T_CS        [N m]    */
  double t_f[URT_NJ];                /* friction torque                [N m]    */
  double tcp_pose[6];                /* x y z [m], rx ry rz [rad] in base frame */

  /* status */
  uint32_t pstop;                    /* URT_PSTOP_* bits; 0 when running        */
  uint32_t isat_count, vsat_count;   /* steps that began with a saturated loop (a torque-mode
                                      * joint counts in isat_count: i_ref is held)  */
  uint32_t refined_count;            /* steps redone as sub-steps (urt_step); one
                                      * redone again as fine steps counts twice */

  /* parameters — the model's values that a run may change (last: the layout before them is
   * the one the recorded controller hashes fold) */
  urt_live_params_t live;

  /* faults — the installed scenario and what it does at the current step (urt/faults.h); all
   * zero: none. After live, so that a run without faults keeps the recorded hashes. */
  urt_fault_state_t faults;
} urt_data_t;

#ifdef __cplusplus
}
#endif
#endif
