/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/model.h — the robot's constant parameters, loaded once from a config file
 * validated, then frozen (const everywhere after urt_model_load). SI units throughout.
 */
#ifndef URT_MODEL_H
#define URT_MODEL_H

#include <stdint.h>

#include "urt/drivers/friction.h"
#include "urt/drivers/harmonic_drive.h"
#include "urt/drivers/motor.h"
#include "urt/drivers/pi_cascade.h"
#include "urt/drivers/sensors.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_NJ 6      /* joints of a UR arm */
#define URT_NXJ 21    /* continuous states per joint (model.md §1.9) */
#define URT_NXD 18    /* drive-block states per joint (all but q, q̇, z) */

/* One link of the Hayati-modified DH chain (paper eq. 8, Table 4):
 *   ^{i−1}A_i = Transl(z, d) · Rot(z, θ + q_i) · Transl(x, a) · Rot(x, α) · Rot(y, β)
 * and its rigid-body data (Table 5) in DH frame i: CoM, inertia about the CoM with axes
 * parallel to frame i. */
typedef struct urt_link_params {
  double a;          /* [m]   */
  double alpha;      /* [rad] */
  double beta;       /* [rad] */
  double d;          /* [m]   */
  double theta;      /* joint offset added to q_i [rad] */
  double mass;       /* [kg]  */
  double com[3];     /* CoM in frame i [m] */
  double inertia[6]; /* Ixx, Iyy, Izz, Ixy, Ixz, Iyz about the CoM [kg m²] */
} urt_link_params_t;

/* A payload on the flange, as UR's set_target_payload gives it: mass, centre of gravity in the
 * tool flange frame (DH frame 6 here, the frame the TCP offset is given in), inertia about the
 * CoG with axes parallel to the flange's. It is added to link 6's rigid body. All zero: none. */
typedef struct urt_payload {
  double mass;       /* [kg]  */
  double cog[3];     /* CoG in the flange frame [m] */
  double inertia[6]; /* Ixx, Iyy, Izz, Ixy, Ixz, Iyz about the CoG [kg m²] */
} urt_payload_t;

#define URT_PAYLOAD_MASS_MAX 5.0  /* UR5 rated payload [kg] */
#define URT_PAYLOAD_COG_MAX 1.0   /* |CoG component| bound: within a metre of the flange [m] */
#define URT_PAYLOAD_INERTIA_MAX 133.0 /* |inertia element| bound: URScript's [kg m²] */

/* Why a payload is refused, or NULL when it is taken: finite, 0 ≤ mass ≤ URT_PAYLOAD_MASS_MAX,
 * |cog_i| ≤ URT_PAYLOAD_COG_MAX, |I_ij| ≤ URT_PAYLOAD_INERTIA_MAX and Ixx, Iyy, Izz ≥ 0 (UR's
 * rule; a controller takes a tensor no body has). The loader, the controller and URScript share
 * it. Context: RT. */
const char *urt_payload_invalid(const urt_payload_t *p);

/* The nearest positive semi-definite inertia tensor to in (Frobenius norm: the principal axes
 * kept, negative principal moments raised to 0), [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]; a PSD tensor
 * is returned unchanged. What the physics carries for a declared tensor. Context: RT. */
void urt_payload_physical(const double in[6], double out[6]);

typedef struct urt_arm_params {
  urt_link_params_t link[URT_NJ];
  double gravity[3];       /* gravity in base frame 0 [m/s²] */
  double tcp[6];           /* TCP offset from the flange: x y z [m], rx ry rz axis-angle [rad] */
  /* derived by urt_arm_prepare(): the constant part of each link transform,
   * Transl(x, a) · Rot(x, α) · Rot(y, β), row-major 3×4, and cos/sin of θ */
  double fixed[URT_NJ][12];
  double cos_theta[URT_NJ], sin_theta[URT_NJ];
  double tcp_fixed[12];    /* flange → TCP, row-major 3×4 */
} urt_arm_params_t;

/* Fill the derived fields of an arm. Context: non-RT. */
void urt_arm_prepare(urt_arm_params_t *a);

/* Per-joint limits and identity. */
typedef struct urt_joint_params {
  char name[16];           /* "base", "shoulder", ...                 */
  char size;               /* drive size 'A' or 'B'                   */
  double q_min, q_max;     /* position limits                 [rad]   */
  double qd_max;           /* speed limit                     [rad/s] */
  double qdd_max;          /* acceleration-command limit      [rad/s²] */
  double torque_max;       /* peak output torque, sets i_max  [N m]   */
  /* zero offset of the drive's current measurement: the current loop and the reported
   * current see i + i_offset, the motor carries i (core/joint.cpp)       [A]     */
  double i_offset;
} urt_joint_params_t;

/* First-order thermal model of one joint's motor winding, integrated by the controller
 * (core/controller.cpp): C dT/dt = R i² − (T − T_amb)/R_th. */
typedef struct urt_thermal_params {
  double t_amb;            /* ambient temperature              [°C]    */
  double r_th;             /* winding-to-ambient resistance    [K/W]   */
  double c_th;             /* winding and housing heat capacity [J/K]  */
} urt_thermal_params_t;

typedef struct urt_model {
  /* sizes and timing */
  char name[32];           /* robot model, e.g. "UR5"                  */
  double dt;               /* physics step                      [s]    */
  double substep_h_max;    /* largest sub-step for stiff-friction joints [s] */
  double substep_ratio;    /* sub-step a joint when dt·|g'_min|/J_out exceeds this [-] */
  uint64_t seed;           /* sensor-noise RNG seed                     */
  int drives_engaged;      /* 0: joints free (drive torque T_CS = 0)     */
  uint32_t refine_every;   /* redo every N-th step as fine steps whatever its plausibility
                              (0: only implausible ones): a knob for measuring the cost of
                              the refined path, which healthy runs rarely take          */

  /* arm */
  urt_arm_params_t arm;
  urt_joint_params_t joint[URT_NJ];

  /* drives, one per joint */
  urt_pi_cascade_params_t control[URT_NJ];
  urt_motor_params_t motor[URT_NJ];
  urt_harmonic_drive_params_t gear[URT_NJ];
  urt_friction_params_t friction[URT_NJ];
  urt_sensors_params_t sensors[URT_NJ];
  urt_thermal_params_t thermal[URT_NJ];

  /* initial state */
  double q0[URT_NJ];       /* initial joint positions           [rad]  */
  urt_payload_t payload;   /* payload mounted at start (urt_data_init copies it into
                            * urt_data_t.live, where the run changes it)          */

  /* derived at load: integrator tables (precomputed W_d^-1 per active set), see integrator.h */
  struct urt_integrator_tables *tables;  /* owned; NULL until urt_model_prepare() */
  char source[256];        /* file the model came from (for messages)   */
} urt_model_t;

#ifdef __cplusplus
}
#endif
#endif
