/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/controller_motion_state.h — the state each motion of the controller keeps
 * between periods (urt_ctrl_t.motion_state). Plain data, fixed size, so that urt_ctrl_t stays a
 * caller-owned value; one member per motion, the running motion's (urt_ctrl_t.motion) is the
 * live one. What the motions do with it is private to core/ (core/motion_*.cpp). */
#ifndef URT_CONTROLLER_MOTION_STATE_H
#define URT_CONTROLLER_MOTION_STATE_H

#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Trapezoidal speed profile over a distance D: accelerate at ap for ta, cruise at vp, brake. */
typedef struct urt_trap {
  double D, T, ta, vp, ap;
} urt_trap_t;

typedef struct urt_movej_state {
  urt_trap_t tr;
  double q_start[URT_NJ], dq[URT_NJ];
} urt_movej_state_t;

typedef struct urt_movel_state {
  urt_trap_t tr;
  double p_start[3], dp[3];      /* line: p = p_start + dp · s/D                             */
  double r_start[3];             /* start orientation (rotation vector)                      */
  double axis[3], theta;         /* R(s) = R_start · Rot(axis, θ s/D), axis in the start frame */
} urt_movel_state_t;

typedef struct urt_stop_state {
  double a[URT_NJ];              /* per-joint deceleration, all joints reach 0 together      */
} urt_stop_state_t;

typedef struct urt_speedj_state {
  double qd_goal[URT_NJ], a[URT_NJ];  /* goal speed and ramp rate, in motion time            */
  double qd_s[URT_NJ];           /* speed in motion time (the set-point's is qd_s · scale)  */
  double tau;                    /* motion time since the start [s]: scale per second       */
} urt_speedj_state_t;

typedef struct urt_speedl_state {
  double xd_goal[6], xd[6];      /* goal and current tool twist (v; ω), base frame           */
} urt_speedl_state_t;

typedef struct urt_servoj_state {  /* servoj, and servol on its IK */
  double target[URT_NJ];
  double since;                  /* time since the last servoj [s]                           */
} urt_servoj_state_t;

typedef struct urt_torque_state {
  double tau[URT_NJ];            /* commanded joint torques [N m]                            */
  double friction;               /* 1: add the friction model at the actual speed            */
  double since;                  /* time since the last TORQUE [s]                           */
} urt_torque_state_t;

typedef struct urt_freedrive_state {
  double free[6];                /* feature-frame axes x y z rx ry rz: 1 free, 0 held         */
  double feature[6];             /* the feature frame (pose in the base frame)               */
  double p_hold[3], r_hold[3];   /* TCP pose when freedrive began (base frame)               */
} urt_freedrive_state_t;

typedef struct urt_servoc_state {
  double target[6];              /* pose goal                                                */
  double xd[6];                  /* current tool twist (v; ω), base frame                    */
} urt_servoc_state_t;

typedef struct urt_force_state {
  double xd[6];                  /* current tool twist (v; ω), base frame                    */
  double xd_goal[6];             /* twist of the speedl running inside force mode, base frame */
} urt_force_state_t;

typedef union urt_ctrl_motion_state {
  urt_movej_state_t movej;
  urt_movel_state_t movel;
  urt_stop_state_t stop;
  urt_speedj_state_t speedj;
  urt_speedl_state_t speedl;
  urt_servoj_state_t servoj;
  urt_torque_state_t torque;
  urt_freedrive_state_t freedrive;
  urt_servoc_state_t servoc;
  urt_force_state_t force;
} urt_ctrl_motion_state_t;

#ifdef __cplusplus
}
#endif
#endif
