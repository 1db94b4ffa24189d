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
  double late;                   /* periods this speedj came late (or the one it superseded)  */
  double fresh;                  /* 1 until its first period: superseded then, it never ramped */
  double limit;                  /* the trajectory limiter's fraction of the commanded speed  */
  uint64_t expired;              /* a program's speedj: the tick its t ran out (0: running)    */
  double held;                   /* time it has run on past t, its program's thread late [s]  */
} urt_speedj_state_t;

typedef struct urt_speedl_state {
  double xd_goal[6], xd[6];      /* goal and current tool twist (v; ω), base frame           */
} urt_speedl_state_t;

typedef struct urt_servoj_state {  /* servoj, and servol on its IK */
  double target[URT_NJ];
  double since;                  /* time since the last servoj [s]                           */
} urt_servoj_state_t;

typedef struct urt_torque_state {
  double tau[URT_NJ];            /* commanded joint torques [N m], gravity not included      */
  double viscous[URT_NJ];        /* share of the friction model's viscous part added, 0..1   */
  double coulomb[URT_NJ];        /* share of its Coulomb (and Stribeck) part added, 0..1     */
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

/* A planned path (core/motion_path.cpp): up to URT_PATH_SEGS pieces, the head one running.
 * A piece's geometry is evaluated at σ = s0 + s for s in [0, len]: LINE p = p0 + u σ; ARC
 * p = p0 + ρ (cos(σ/ρ) e1 + sin(σ/ρ) e2); JOINT q = q0 + dq σ/L; HERMITE a joint-space cubic
 * from (q0, qd0) to (q0 + dq, qd1) over its duration T. Orientation (LINE, ARC): orient 0
 * R = Rot(r0) · Rot(axis, θ σ/L) (axis in the start frame), orient 1 R = Rot(n, σ/ρ) · Rot(r0)
 * (n = e1 × e2: fixed relative to the arc's tangent). */
enum { URT_SEG_JOINT = 1, URT_SEG_LINE = 2, URT_SEG_ARC = 3, URT_SEG_HERMITE = 4 };
#define URT_PATH_SEGS 4

typedef struct urt_path_seg {
  int32_t kind;                  /* URT_SEG_*                                                */
  int32_t move;                  /* the move it belongs to (index into urt_path_state_t.move) */
  int32_t orient;                /* 0 interpolated, 1 fixed relative to the arc's tangent, 2 a
                                    tool blend's: a cubic rotation vector whose rates at the ends
                                    (body, per unit path) are qd0[0..2] and qd1[0..2]         */
  int32_t pad_;
  double s0, len, L;             /* offset into the geometry, length run, geometry's length  */
  double v_max;                  /* path speed limit on it [m/s or rad/s]                     */
  double T;                      /* HERMITE: duration [s] (set when it starts)               */
  double p0[3], u[3], e1[3], e2[3], rho;
  double r0[3], axis[3], theta;
  double q0[URT_NJ], dq[URT_NJ], qd0[URT_NJ], qd1[URT_NJ];
} urt_path_seg_t;

typedef struct urt_path_move {
  uint64_t id;
  int32_t kind;                  /* URT_CTRL_* of its command                                 */
  int32_t joint;                 /* 1: joint space (movej, optimovej)                         */
  int32_t done;                  /* 1: its id is marked done (blend look-ahead or the end)    */
  int32_t pad_;
  double r;                      /* blend radius asked for [m]                                */
  double a, v;                   /* path acceleration and speed [m/s², m/s or rad/s², rad/s]  */
  double fa, fv;                 /* optimovel: the fractions (0 otherwise)                    */
  double chord;                  /* TCP distance from its start to its target [m]             */
  double zone;                   /* path length from its end at which the blend zone begins  */
  double end_p[3];               /* TCP position of its target                                */
  double opt_v, opt_a;           /* optimovel: the tool speed and acceleration the joints allow
                                    where it runs now (where it will begin, while queued)     */
} urt_path_move_t;

typedef struct urt_path_state {
  urt_path_seg_t seg[URT_PATH_SEGS];
  urt_path_move_t move[2];       /* the running move and the one queued behind it             */
  int32_t nseg, nmove;
  int32_t queued_stop;           /* 1: the queued move starts from rest at this one's target  */
  int32_t pad_;
  double s, sd;                  /* along the head piece, path speed                          */
} urt_path_state_t;

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
  urt_path_state_t path;
} urt_ctrl_motion_state_t;

#ifdef __cplusplus
}
#endif
#endif
