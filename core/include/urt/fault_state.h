/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/fault_state.h — the types of a fault scenario and of the fault state that
 * urt_data_t carries (last in it). Fixed size, no pointers: a scenario and a urt_data_t with
 * faults installed still copy with memcpy. The API is in urt/faults.h.
 */
#ifndef URT_FAULT_STATE_H
#define URT_FAULT_STATE_H

#include <stdint.h>

#include "urt/drivers/friction.h"
#include "urt/drivers/harmonic_drive.h"
#include "urt/drivers/motor.h"
#include "urt/drivers/pi_cascade.h"
#include "urt/drivers/sensors.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_MAX_FAULTS 16

/* Fault classes (../shared/docs/faults.md §1). The number is the class's index in
 * urt_fault_class_name(); scenario files name classes by that name. New classes are appended. */
enum {
  URT_FAULT_GEAR_STIFFNESS = 0, /* mesh stiffness loss: K_m ×(1 − s), c_m ×√(1 − s)   [1]  */
  URT_FAULT_LUBRICANT,          /* LuGre levels f_c, f_v, σ1 ×(1 + s)                  [1]  */
  URT_FAULT_WINDING_SHORT,      /* shorted fraction μ: R, L, k_t = k_e ×(1 − μ/3)      [1]  */
  URT_FAULT_DEMAGNETISATION,    /* k_t = k_e ×(1 − s)                                  [1]  */
  URT_FAULT_ENCODER_BIAS,       /* joint: + s on the measured angle [rad]; motor: on the
                                 * measured motor speed [rad/s]                              */
  URT_FAULT_ENCODER_DRIFT,      /* a bias growing at rate s: joint [rad/s], motor [rad/s²]   */
  URT_FAULT_ENCODER_NOISE,      /* white noise of σ = s per physics step: joint [rad],
                                 * motor [rad/s]                                             */
  URT_FAULT_ENCODER_STUCK,      /* the measurement holds its value from when it stuck [1]   */
  URT_FAULT_CURRENT_OFFSET,     /* i_meas = i + s                                      [A]  */
  URT_FAULT_CURRENT_GAIN,       /* i_meas = (1 + s) i                                  [1]  */
  URT_FAULT_SUPPLY_SAG,         /* the bus (PWM saturation) at V_net − s               [V]  */
  URT_FAULT_BRAKE_DRAG,         /* a Coulomb torque s added to the joint's friction    [N m] */
  URT_FAULT_COLLISION,          /* a force s at the TCP along `direction` (base frame) [N]  */
  URT_FAULT_CRACK,              /* flexspline crack of depth s: K_m ×(1 − s cos²(q_WG)), a dip
                                 * each time one of the WG's two lobes passes it            [1]  */
  URT_FAULT_PAYLOAD,            /* an unexpected point mass s at `offset` (flange frame): the
                                 * physics carries it, the controller does not know it [kg] */
  URT_FAULT_BACKLASH,           /* a dead zone of width s in the gear's output torsional spring
                                 * (T_CS = 0 while |q_CS − q| < s/2): lost motion s at every
                                 * torque reversal, output side                       [rad] */
  URT_FAULT_WG_BEARING,         /* a spall in the WG bearing: a torque pulse of peak s on the WG
                                 * each time a ball passes it, at BPFO, BPFI or BSF of the
                                 * relative race speed (`location`, `balls`, `ball_ratio`) [N m] */
  URT_FAULT_TRANSMISSION_ERROR, /* kinematic error growth: the output lags the CS by
                                 * s·sin(2 q_WG), the 2·f_WG harmonic                 [rad] */
  URT_FAULT_ENCODER_MISSED,     /* each count the encoder should register is lost with
                                 * probability s (seeded): the joint encoder's reading falls
                                 * behind by the lost counts, the motor encoder's speed reading
                                 * dips one count per step for each                    [1]  */
  URT_FAULT_NCLASSES
};

/* Which sensor an encoder fault hits (ignored by the other classes). */
enum { URT_FAULT_ENC_JOINT = 0, URT_FAULT_ENC_MOTOR = 1 };

/* Where a WG-bearing spall sits: on the outer race (in the fixed flexspline; impacts at BPFO),
 * the inner race (on the WG cam; BPFI) or a ball (BSF). */
enum { URT_FAULT_BEARING_OUTER = 0, URT_FAULT_BEARING_INNER = 1, URT_FAULT_BEARING_BALL = 2 };

/* How a fault's severity evolves from its onset (s(t) for a spec of severity v):
 *   STEP          v from onset on
 *   LINEAR        v·min(1, (t − onset)/ramp)
 *   EXP           v·(e^{u/τ} − 1)/(e^{ramp/τ} − 1), u = min(t − onset, ramp): accelerating growth
 *   INTERMITTENT  v in the windows [onset + k(on + off), onset + k(on + off) + on), else 0
 *   RANDOM_WALK   v at onset, then + σ√h N(0, 1) per physics step h (seeded), kept in the
 *                 class's range */
enum {
  URT_FAULT_STEP = 0,
  URT_FAULT_LINEAR,
  URT_FAULT_EXP,
  URT_FAULT_INTERMITTENT,
  URT_FAULT_RANDOM_WALK
};

typedef struct urt_fault_spec {
  int32_t cls;          /* URT_FAULT_* class                                  */
  int32_t joint;        /* 0..5 (ignored by COLLISION)                        */
  int32_t component;    /* URT_FAULT_ENC_* for encoder classes, else 0        */
  int32_t profile;      /* URT_FAULT_STEP ...                                 */
  double severity;      /* in the class's unit (urt_fault_class_unit)         */
  double onset;         /* simulation time the fault starts          [s]     */
  double ramp;          /* LINEAR, EXP: time to full severity        [s]     */
  double tau;           /* EXP: growth time constant                 [s]     */
  double on, off;       /* INTERMITTENT: window lengths              [s]     */
  double sigma;         /* RANDOM_WALK: severity units per √s                */
  uint64_t seed;        /* RANDOM_WALK and ENCODER_NOISE draws               */
  double direction[3];  /* COLLISION: unit vector of the force, base frame    */
  double offset[3];     /* PAYLOAD: where the mass sits, flange frame   [m]   */
  int32_t location;     /* WG_BEARING: URT_FAULT_BEARING_*                    */
  int32_t balls;        /* WG_BEARING: number of rolling elements             */
  double ball_ratio;    /* WG_BEARING: d cos φ / D (ball over pitch diameter) */
} urt_fault_spec_t;

typedef struct urt_fault_scenario {
  int32_t n;                           /* faults in use, 0..URT_MAX_FAULTS */
  int32_t reserved;
  urt_fault_spec_t f[URT_MAX_FAULTS];
} urt_fault_scenario_t;

/* One joint's parameters as its faults have made them, at the current step (the physics reads
 * these instead of the model's when the joint's bit is set in urt_fault_state_t.joint_mask). */
typedef struct urt_fault_joint {
  urt_motor_params_t motor;
  urt_pi_cascade_params_t control;
  urt_harmonic_drive_params_t gear;
  urt_friction_params_t friction;
  double i_gain, i_bias;       /* current measurement: i_gain·(i_f + ε) + i_bias      */
  double q_bias, qdm_bias;     /* added to the measured joint angle [rad], motor speed [rad/s] */
  double q_noise, qdm_noise;   /* this step's encoder noise draws                     */
  int32_t q_stuck, qdm_stuck;  /* 1: the measurement holds q_hold / qdm_hold           */
  double q_hold, qdm_hold;
  double crack;                /* crack depth: K_m dips by this fraction under a lobe  */
  double backlash;             /* dead-zone width of the output spring            [rad] */
  double te_amp;               /* kinematic error s·sin(2 q_WG) at the output     [rad] */
  double wg_pulse;             /* WG-bearing pulse peak                           [N m] */
  double wg_pulse_rate;        /* impacts per WG radian (relative to the FS)      [1/rad] */
  double qdm_missed;           /* this step's lost motor counts as a speed error [rad/s] */
  double z_max;                /* LuGre's bound on |z| with these friction levels [rad] */
} urt_fault_joint_t;

typedef struct urt_fault_state {
  urt_fault_scenario_t s;              /* the installed scenario                      */
  double severity[URT_MAX_FAULTS];     /* s(t) at the current step                    */
  double onset_time[URT_MAX_FAULTS];   /* when it first became active, −1: not yet    */
  double acc[URT_MAX_FAULTS];          /* DRIFT: the bias accumulated; RANDOM_WALK: the walk */
  int32_t active[URT_MAX_FAULTS];      /* the profile is on at the current step       */
  int32_t stuck_latched[URT_MAX_FAULTS];
  double last_count[URT_MAX_FAULTS];   /* ENCODER_MISSED: the count the sensor last passed */
  double missed[URT_MAX_FAULTS];       /* ENCODER_MISSED: joint counts lost so far [rad] */
  urt_rng_t rng[URT_MAX_FAULTS];
  uint32_t joint_mask;                 /* bit j: joint[j] below is in use             */
  uint32_t reserved;
  urt_fault_joint_t joint[6];
  double wrench[6];                    /* collision force/torque at the TCP, base frame */
  double payload_mass;                 /* PAYLOAD faults: their masses summed [kg]      */
  double payload_moment[3];            /* Σ m·offset, flange frame [kg m]               */
} urt_fault_state_t;

#ifdef __cplusplus
}
#endif
#endif
