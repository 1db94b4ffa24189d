/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/drivers/harmonic_drive.h — the 4-DoF translational strain-wave gear of
 * paper eqs. (2)–(6), model.md §1.5. Input: wave generator (WG); output: circular spline (CS);
 * the flexspline (FS) is fixed to the housing and reduced to an equivalent mass on the pitch
 * radius r_g.
 *
 *   τ   = Z_CS/(Z_CS − Z_FS)                       (= 101)
 *   α_n = atan(1/(τ tan α_t))                      equivalent cam angle, eq. (3)
 *   m_FS = J_FS / r_g²
 *   x_WG = r_g tan α_n q_WG        y_CS = r_g q_CS   (kinematic rows of eq. 6)
 *
 *   T_in = K_WG (q_M − q_WG) + c_WG (q̇_M − q̇_WG)                                   [N m]
 *   F_b  = K_b (x_WG − x_FS) + c_b (ẋ_WG − ẋ_FS)                                    [N]
 *   F_m  = K_m [x_FS s_t − (y_CS + y_FS) c_t] + c_m [ẋ_FS s_t − (ẏ_CS + ẏ_FS) c_t]   [N]
 *   F_t  = (K_FS y_FS + c_FS ẏ_FS)/r_g²                                             [N]
 *   T_CS = K_CS (q_CS − q) + c_CS (q̇_CS − q̇)                                       [N m]
 *
 *   J_WG q̈_WG = T_in − F_b r_g s_n c_n        m_FS ẍ_FS = F_b − F_m s_t
 *   m_FS ÿ_FS = F_m c_t − F_t                  J_CS q̈_CS = F_m r_g c_t − T_CS
 *
 * s_n c_n is kept as printed (static ratio τ/cos²α_n = 101.03; model.md §1.5).
 * Damping: c = 2 ζ √(K m_red) with the reduced inertias of model.md §2.2.
 */
#ifndef URT_DRIVERS_HARMONIC_DRIVE_H
#define URT_DRIVERS_HARMONIC_DRIVE_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_harmonic_drive_params {
  /* given (paper Table 3) */
  double z_fs, z_cs;   /* teeth of flexspline and circular spline        [-]        */
  double r_g;          /* pitch radius                                   [m]        */
  double alpha_t;      /* tooth pressure angle                           [rad]      */
  double k_wg;         /* WG torsional stiffness                         [N m/rad]  */
  double k_b;          /* WG bearing radial stiffness                    [N/m]      */
  double k_fs;         /* FS torsional stiffness                         [N m/rad]  */
  double k_m;          /* mesh stiffness                                 [N/m]      */
  double k_cs;         /* CS / output torsional stiffness                [N m/rad]  */
  double j_wg, j_fs, j_cs; /* inertias                                   [kg m²]    */
  double zeta;         /* damping ratio of every spring                  [-]        */
  /* derived by urt_harmonic_drive_derive() */
  double ratio;        /* τ                                              [-]        */
  double alpha_n;      /* equivalent cam angle                           [rad]      */
  double m_fs;         /* equivalent FS mass                             [kg]       */
  double c_wg, c_b, c_m, c_fs, c_cs; /* dampings           [N m s/rad] or [N s/m]   */
  double sin_n, cos_n, tan_n, sin_t, cos_t; /* of α_n and α_t, so the step calls no trig   */
} urt_harmonic_drive_params_t;

/* Positions and rates of the gear's own bodies. */
typedef struct urt_harmonic_drive_state {
  double q_wg, qd_wg;   /* wave generator   [rad, rad/s] */
  double x_fs, xd_fs;   /* flexspline x     [m, m/s]     */
  double y_fs, yd_fs;   /* flexspline y     [m, m/s]     */
  double q_cs, qd_cs;   /* circular spline  [rad, rad/s] */
} urt_harmonic_drive_state_t;

/* The motor (input) and joint (output) ends the gear is connected to. */
typedef struct urt_harmonic_drive_ends {
  double q_m, qd_m;     /* motor            [rad, rad/s] */
  double q, qd;         /* joint output     [rad, rad/s] */
} urt_harmonic_drive_ends_t;

typedef struct urt_harmonic_drive_out {
  double t_in;                     /* torque the WG takes from the motor  [N m] */
  double t_cs;                     /* torque the CS gives the joint       [N m] */
  urt_harmonic_drive_state_t d;    /* time derivative of the state              */
} urt_harmonic_drive_out_t;

/* Fill the derived fields from the given ones, motor inertia j_m for the WG reduced inertia.
 * Context: non-RT. */
void urt_harmonic_drive_derive(urt_harmonic_drive_params_t *p, double j_m);

/* Torques and the state's rates of eq. (5). Context: RT. Pure. */
urt_harmonic_drive_out_t urt_harmonic_drive_eval(const urt_harmonic_drive_params_t *p,
                                                 const urt_harmonic_drive_state_t *s,
                                                 const urt_harmonic_drive_ends_t *e);

/* Static equilibrium of eq. (6), augmented (model.md §1.5): given the joint angle q0 and the
 * output torque t0 the gear must carry, solve for (q_M, q_WG, x_FS, y_FS, q_CS) with all rates
 * zero. Writes u[5] = {q_m, q_wg, x_fs, y_fs, q_cs} and the input torque *t_in.
 * Context: non-RT. Returns 0, or URT_ESOLVER if the 7×7 system is singular. */
int urt_harmonic_drive_equilibrium(const urt_harmonic_drive_params_t *p, double q0, double t0,
                                   double u[5], double *t_in);

#ifdef __cplusplus
}
#endif
#endif
