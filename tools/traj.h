/* SPDX-License-Identifier: Apache-2.0
 * tools/traj.h — joint-space test trajectories for the offline runner, the tests and the
 * benchmark (model.md §6.2). Every trajectory is a fixed-size, caller-owned struct with no
 * pointers (it can be copied with memcpy) and is evaluated analytically at any time t:
 * position q [rad], speed q̇ [rad/s] and acceleration q̈ [rad/s²] per joint.
 *
 * Three kinds:
 *   hold        q(t) = q0, at rest.
 *   excitation  Swevers et al. (1997) finite Fourier series, per joint i, ω = 2π f_f:
 *                 q_i(t) = q0_i + Σ_{l=1..N} [ a_il/(ωl) sin(ωlt) − b_il/(ωl) (cos(ωlt) − 1) ]
 *                 q̇_i(t) = Σ_l [ a_il cos(ωlt) + b_il sin(ωlt) ]
 *                 q̈_i(t) = Σ_l ωl [ −a_il sin(ωlt) + b_il cos(ωlt) ]
 *               The "− 1" removes the constant of the cosine terms so that q(0) = q0 exactly.
 *               Σ_l a_il = 0 gives q̇(0) = 0 and Σ_l l·b_il = 0 gives q̈(0) = 0; the series is
 *               periodic, so it also ends at rest at q0 after every whole period.
 *   pickplace   a sequence of movej moves: synchronised joint-space trapezoids. The joint with
 *               the largest |Δq| (the lead) follows a trapezoid with (v, a, d); every other
 *               joint j follows the same normalised profile scaled by Δq_j/|Δq_lead|, so all
 *               joints start and stop together. When the distance is too short to reach v the
 *               profile is triangular with peak √(2 D a d / (a + d)). After each move the arm
 *               rests at the target for the move's dwell time. No blending.
 *
 * Before t = 0 a trajectory holds its start, after its duration it holds its end, at rest.
 * Nothing here clips: generators stay inside the bounds they are given, and urt_traj_check()
 * refuses a trajectory that a model's command limits would refuse.
 */
#ifndef URT_TRAJ_H
#define URT_TRAJ_H

#include <stddef.h>
#include <stdint.h>

#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

#define URT_TRAJ_FOURIER_NMAX 8     /* largest number of harmonics */
#define URT_TRAJ_PICKPLACE_NMAX 32  /* largest number of moves in a sequence */

typedef enum urt_traj_kind {
  URT_TRAJ_HOLD = 0,
  URT_TRAJ_FOURIER = 1,
  URT_TRAJ_PICKPLACE = 2
} urt_traj_kind_t;

//---- excitation: finite Fourier series ----

typedef struct urt_traj_fourier {
  double q0[URT_NJ];                        /* start and end position      [rad]   */
  double f_f;                               /* base frequency              [Hz]    */
  int n;                                    /* harmonics, 1..URT_TRAJ_FOURIER_NMAX */
  int periods;                              /* duration in whole periods 1/f_f     */
  double a[URT_NJ][URT_TRAJ_FOURIER_NMAX];  /* cosine speed coefficients   [rad/s] */
  double b[URT_NJ][URT_TRAJ_FOURIER_NMAX];  /* sine speed coefficients     [rad/s] */
} urt_traj_fourier_t;

/* Bounds for the random generator, per joint. */
typedef struct urt_traj_fourier_opts {
  double f_f;                /* base frequency                 [Hz]     default 0.1  */
  int n;                     /* harmonics                               default 5    */
  int periods;               /* periods to play                         default 1    */
  double amp_max[URT_NJ];    /* bound on |q − q0|              [rad]    0.8 (j 1–4), 1.2 (j 5–6) */
  double qd_max[URT_NJ];     /* bound on |q̇|                   [rad/s]  default 1.0  */
  double qdd_max[URT_NJ];    /* bound on |q̈|                   [rad/s²] default 3.0  */
} urt_traj_fourier_opts_t;

/* Fill o with the defaults listed above. Context: any. */
void urt_traj_fourier_opts_default(urt_traj_fourier_opts_t *o);

/* Draw random coefficients that satisfy the rest conditions and the bounds of o, starting
 * from q0. Each joint's a and b are drawn uniformly in [−1, 1] from a splitmix64 stream seeded
 * with seed, projected onto Σ a_l = 0 and Σ l·b_l = 0, then scaled so that the tightest of the
 * three bounds is just met (the bounds are certified on a dense grid with an analytic margin
 * for the extremes between grid points, see urt_traj_fourier_bounds). The same seed and
 * options give the same bits. Context: non-RT (a few 10⁵ sin/cos).
 * Nullable: o (defaults). Returns 0, or URT_EINVAL when an option is out of range
 * (f_f ≤ 0, n outside 1..URT_TRAJ_FOURIER_NMAX, periods < 1, a bound ≤ 0 or non-finite, q0
 * non-finite); f is untouched then. */
int urt_traj_fourier_random(urt_traj_fourier_t *f, const double q0[URT_NJ],
                            const urt_traj_fourier_opts_t *o, uint64_t seed);

/* Evaluate the series at t [s] (held at rest at q0 outside [0, duration]).
 * Context: RT (no allocation; 2·n sin/cos). Nullable: q, qd, qdd (skipped). */
void urt_traj_fourier_eval(const urt_traj_fourier_t *f, double t, double q[URT_NJ],
                           double qd[URT_NJ], double qdd[URT_NJ]);

/* Certified upper bounds on max |q − q0|, max |q̇| and max |q̈| over a period, per joint:
 * the maximum over 4096 samples per period plus h²/8 times a bound on the quantity's second
 * derivative (h the sample spacing), so the true maxima never exceed them; the margin is of
 * order 10⁻⁴ relative or less for n ≤ 8. Context: non-RT. Nullable: any output. */
void urt_traj_fourier_bounds(const urt_traj_fourier_t *f, double amp[URT_NJ], double qd[URT_NJ],
                             double qdd[URT_NJ]);

//---- pick-and-place: movej sequence ----

/* One movej move; the fields after dwell are derived by urt_traj_pickplace_add(). */
typedef struct urt_traj_move {
  double q[URT_NJ];        /* target                                  [rad]    */
  double v;                /* lead-joint speed                        [rad/s]  */
  double a;                /* lead-joint acceleration                 [rad/s²] */
  double d;                /* lead-joint deceleration                 [rad/s²] */
  double dwell;            /* rest at the target after arrival        [s]      */
  /* derived */
  double t0;               /* start time                              [s]      */
  double t_acc, t_cruise, t_dec;  /* phase durations                  [s]      */
  double t_stop;           /* arrival, (t0 + t_acc + t_cruise) + t_dec [s]     */
  double dist;             /* lead-joint distance D = max_j |Δq_j|    [rad]    */
  double v_peak;           /* lead-joint peak speed (< v if triangular) [rad/s] */
  double q_from[URT_NJ];   /* start of the move                       [rad]    */
  double ratio[URT_NJ];    /* Δq_j / D, in [−1, 1]; ±1 for the lead    [-]      */
  int lead;                /* index of the lead joint, −1 for a pure dwell      */
} urt_traj_move_t;

typedef struct urt_traj_pickplace {
  double q0[URT_NJ];       /* start                                   [rad]    */
  int n;                   /* moves in use                                     */
  double duration;         /* end of the last move's dwell            [s]      */
  urt_traj_move_t move[URT_TRAJ_PICKPLACE_NMAX];
} urt_traj_pickplace_t;

/* UR's movej defaults and the paper's wrist-2 stress event (model.md §6.2). */
#define URT_TRAJ_MOVEJ_A 1.4                        /* [rad/s²] */
#define URT_TRAJ_MOVEJ_V 1.05                       /* [rad/s]  */
#define URT_TRAJ_STRESS_V 3.14159265358979323846    /* 180°/s   [rad/s]  */
#define URT_TRAJ_STRESS_A (2500.0 * 3.14159265358979323846 / 180.0) /* 2500°/s² [rad/s²] */

/* Start an empty sequence at q0 (duration 0). Context: any. */
void urt_traj_pickplace_init(urt_traj_pickplace_t *p, const double q0[URT_NJ]);

/* Append a move from the end of the sequence to q with lead-joint speed v, acceleration a and
 * deceleration d (d = 0: same as a), then a rest of dwell seconds. A move to the current
 * position is a pure dwell. Context: any.
 * Returns 0, URT_ENOSPC when the sequence already holds URT_TRAJ_PICKPLACE_NMAX moves, or
 * URT_EINVAL when q is non-finite, v ≤ 0, a ≤ 0, d < 0 or dwell < 0 (p untouched). */
int urt_traj_pickplace_add(urt_traj_pickplace_t *p, const double q[URT_NJ], double v, double a,
                           double d, double dwell);

/* The default pick-and-place (about 15 s, tool pointing down, bare flange): from q0 to a pick
 * site and a place site on either side of the base at UR movej defaults (a = 1.4 rad/s²,
 * v = 1.05 rad/s), slower approach and retreat moves (a = 1.0 rad/s², v = 0.5 rad/s) with
 * dwells for gripping, and the stress event at the place site: wrist 2 (index 4) turns 1.6 rad
 * at 180°/s with 2500°/s² acceleration and deceleration, the stop ending at about 8.5 s as in
 * the paper's Fig. 11, then returns at the defaults. Waypoints are absolute; with q0 =
 * [0, −π/2, π/2, −π/2, −π/2, 0] the first move starts after a 0.5 s rest.
 * Context: any. Returns 0 or URT_EINVAL (non-finite q0). */
int urt_traj_pickplace_default(urt_traj_pickplace_t *p, const double q0[URT_NJ]);

/* Evaluate the sequence at t [s]. Piecewise analytic; at a phase boundary the later phase
 * applies (q̈ is right-continuous). Context: RT. Nullable: q, qd, qdd. */
void urt_traj_pickplace_eval(const urt_traj_pickplace_t *p, double t, double q[URT_NJ],
                             double qd[URT_NJ], double qdd[URT_NJ]);

//---- any trajectory ----

typedef struct urt_traj {
  urt_traj_kind_t kind;
  double hold_q[URT_NJ];          /* URT_TRAJ_HOLD: the position  [rad] */
  double hold_duration;           /* URT_TRAJ_HOLD: the duration  [s]   */
  union {
    urt_traj_fourier_t fourier;   /* URT_TRAJ_FOURIER   */
    urt_traj_pickplace_t pp;      /* URT_TRAJ_PICKPLACE */
  } u;
} urt_traj_t;

/* Make tr a hold at q for duration seconds. Context: any. */
void urt_traj_make_hold(urt_traj_t *tr, const double q[URT_NJ], double duration);

/* Make tr a random excitation from q0 (see urt_traj_fourier_random). Context: non-RT.
 * Nullable: o. Returns 0 or URT_EINVAL. */
int urt_traj_make_excitation(urt_traj_t *tr, const double q0[URT_NJ],
                             const urt_traj_fourier_opts_t *o, uint64_t seed);

/* Make tr the default pick-and-place from q0 (see urt_traj_pickplace_default). Context: any.
 * Returns 0 or URT_EINVAL. */
int urt_traj_make_pickplace(urt_traj_t *tr, const double q0[URT_NJ]);

/* Evaluate any trajectory at t [s]. Context: RT. Nullable: q, qd, qdd. */
void urt_traj_eval(const urt_traj_t *tr, double t, double q[URT_NJ], double qd[URT_NJ],
                   double qdd[URT_NJ]);

/* Duration [s]: periods/f_f, the end of the last dwell, or the hold time. Context: any. */
double urt_traj_duration(const urt_traj_t *tr);

/* Position range and peak |q̇|, |q̈| per joint: exact for hold and pick-and-place, certified
 * upper bounds (urt_traj_fourier_bounds) for the excitation. Context: non-RT.
 * Nullable: any output. */
void urt_traj_peaks(const urt_traj_t *tr, double q_lo[URT_NJ], double q_hi[URT_NJ],
                    double qd_peak[URT_NJ], double qdd_peak[URT_NJ]);

/* Check tr against m's command limits: q_min ≤ q ≤ q_max, |q̇| ≤ qd_max and |q̈| ≤ qdd_max
 * for every joint (the limits urt_command_set enforces), so that no command of tr is refused.
 * Context: non-RT. Nullable: err.
 * Returns 0, or URT_ERANGE with the first violation in err ("joint 5 (wrist2): peak speed
 * 3.1416 rad/s > qd_max 3 rad/s"). */
int urt_traj_check(const urt_traj_t *tr, const urt_model_t *m, char *err, size_t err_sz);

/* "hold", "excitation", "pickplace". Context: any. Never returns NULL. */
const char *urt_traj_kind_name(urt_traj_kind_t kind);

#ifdef __cplusplus
}
#endif
#endif
