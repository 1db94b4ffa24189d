/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/drivers/motor.h — DC-equivalent PMSM, paper eq. (1).
 *
 *   L di/dt      = V_sup − R i − k_e q̇_M          (k_e = k_t)
 *   J_M q̈_M      = k_t i − T_in                    (T_in: torque taken by the wave generator)
 *
 * Symbols: i [A], V [V], q_M [rad], q̇_M [rad/s], R [Ω], L [H], J_M [kg m²], k_t [N m/A].
 * States: (i, q_M, q̇_M). Inputs: V_sup, T_in.
 */
#ifndef URT_DRIVERS_MOTOR_H
#define URT_DRIVERS_MOTOR_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_motor_params {
  double j;  /* rotor inertia J_M                        [kg m²] */
  double r;  /* winding resistance R                     [Ω]     */
  double l;  /* winding inductance L                     [H]     */
  double kt; /* torque constant k_t                      [N m/A] */
  double ke; /* back-EMF constant k_e (= k_t)            [V s/rad] */
} urt_motor_params_t;

typedef struct urt_motor_state {
  double i;     /* winding current       [A]     */
  double q_m;   /* rotor angle           [rad]   */
  double qd_m;  /* rotor speed           [rad/s] */
} urt_motor_state_t;

/* Time derivative of urt_motor_state_t, field by field. */
typedef struct urt_motor_deriv {
  double di;   /* di/dt      [A/s]    */
  double dq;   /* dq_M/dt    [rad/s]  */
  double dqd;  /* d²q_M/dt²  [rad/s²] */
} urt_motor_deriv_t;

/* Time derivatives of the motor states for supply voltage v_sup [V] and load torque t_in
 * [N m]. Context: RT. Pure. */
urt_motor_deriv_t urt_motor_deriv(const urt_motor_params_t *p, const urt_motor_state_t *s,
                                  double v_sup, double t_in);

#ifdef __cplusplus
}
#endif
#endif
