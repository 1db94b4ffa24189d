/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/drivers/pi_cascade.h — the joint controller of paper §2.1, Table 1,
 * as continuous-time states (model.md §1.2, §5.3b: sampled, the current loops go unstable).
 *
 *   q̇_M,ref = P_pos (q_set − q_FB) + τ q̇_set                  [rad/s motor]  (speed feed-forward)
 *   e_v     = q̇_M,ref − q̇_M,FB
 *   i_ref   = sat_{±i_max}( P_vel e_v + I_vel ξ_v + i_ff )      [A]   i_ff = T_ff/(k_t τ)
 *   ξ̇_v     = e_v, held at zero while i_ref is saturated and e_v pushes further into it
 *   e_c     = i_ref − i_FB
 *   V_sup   = sat_{±V_net}( P_cur e_c + I_cur ξ_c )            [V]   averaged PWM, §1.3
 *   ξ̇_c     = e_c, held likewise while V_sup is saturated
 *
 * Torque mode (in.torque = 1): i_ref = sat_{±i_max}(i_ff) and ξ̇_v = 0 — the position and speed
 * loops are off, the current loop makes the commanded torque; ξ_v keeps its value for the return
 * to position control.
 *
 * P_pos [1/s] maps the joint-side position error to a motor-speed reference: τ is not applied
 * a second time (model.md §0.2). States: (ξ_v, ξ_c).
 */
#ifndef URT_DRIVERS_PI_CASCADE_H
#define URT_DRIVERS_PI_CASCADE_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_pi_cascade_params {
  double p_pos;  /* position gain                      [rad_motor/s per rad_joint] */
  double p_vel;  /* speed-loop proportional gain       [A s/rad]  */
  double i_vel;  /* speed-loop integral gain           [A/rad]    */
  double p_cur;  /* current-loop proportional gain     [V/A]      */
  double i_cur;  /* current-loop integral gain         [V/(A s)]  */
  double i_max;  /* current-reference limit            [A]        */
  double v_net;  /* supply voltage (PWM saturation)    [V]        */
} urt_pi_cascade_params_t;

/* The two integrators. */
typedef struct urt_pi_cascade_state {
  double xi_v;    /* speed-loop integrator ∫e_v dt     [rad]   */
  double xi_c;    /* current-loop integrator ∫e_c dt   [A s]   */
} urt_pi_cascade_state_t;

/* Measured signals and set-points the cascade reads. */
typedef struct urt_pi_cascade_in {
  double q_set;   /* joint position set-point          [rad]   */
  double qd_set;  /* joint velocity feed-forward       [rad/s] */
  double i_ff;    /* current feed-forward              [A]     */
  double q_fb;    /* joint encoder measurement          [rad]   */
  double qdm_fb;  /* motor speed measurement            [rad/s] */
  double i_fb;    /* current measurement                [A]     */
  int torque;     /* 1: torque mode (position and speed loops off)  */
} urt_pi_cascade_in_t;

typedef struct urt_pi_cascade_out {
  double qdm_ref;  /* motor speed reference            [rad/s] */
  double i_ref;    /* current reference (saturated)     [A]     */
  double v_sup;    /* supply voltage (saturated)        [V]     */
  urt_pi_cascade_state_t d;  /* dξ_v/dt, dξ_c/dt (0 while clamped)   */
  int i_sat;       /* 1 while i_ref is saturated                */
  int v_sat;       /* 1 while V_sup is saturated                */
} urt_pi_cascade_out_t;

/* Evaluate the cascade: references, saturated outputs and the integrators' rates. ratio is
 * the gear ratio τ. Context: RT. Pure. */
urt_pi_cascade_out_t urt_pi_cascade_eval(const urt_pi_cascade_params_t *p, double ratio,
                                         const urt_pi_cascade_state_t *s,
                                         const urt_pi_cascade_in_t *in);

#ifdef __cplusplus
}
#endif
#endif
