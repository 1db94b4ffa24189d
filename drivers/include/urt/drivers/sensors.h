/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/drivers/sensors.h — joint-drive sensors (paper §2.5; numbers proposed in
 * model.md §1.7).
 *
 *   current sensor    τ_i di_f/dt = i − i_f                         τ_i = 1/(2π f_i)
 *   motor encoder     ẅ + 2ζ_w ω_w ẇ + ω_w² w = ω_w² q̇_M             ω_w = 2π f_w
 *   joint encoder     p̈ + 2ζ_q ω_q ṗ + ω_q² p = ω_q² q               ω_q = 2π f_q
 *
 * The filters are continuous states. Sample-and-hold, Gaussian noise and mid-tread quantisation
 * enter as a held error (model.md §5.3c), sampled once per physics step t_k:
 *
 *   ε_k = Q(y_f(t_k) + n_k) − y_f(t_k),   y_FB(t) = y_f(t) + ε_k  on [t_k, t_k+1)
 *
 * so noise and quantisation have the right statistics without adding a loop delay.
 */
#ifndef URT_DRIVERS_SENSORS_H
#define URT_DRIVERS_SENSORS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_sensors_params {
  double f_i;                  /* current-sensor bandwidth              [Hz]     */
  double f_w, zeta_w;          /* motor-encoder speed filter            [Hz], [-] */
  double f_q, zeta_q;          /* joint-encoder position filter         [Hz], [-] */
  double sigma_i;              /* current noise std                     [A]      */
  double sigma_w;              /* motor-speed noise std                 [rad/s]  */
  double sigma_q;              /* joint-position noise std              [rad]    */
  double lsb_i;                /* current quantum                       [A]      */
  double lsb_w;                /* motor-speed quantum                   [rad/s]  */
  double lsb_q;                /* joint-position quantum                [rad]    */
  int noise;                   /* 0: no noise                                    */
  int quantise;                /* 0: no quantisation                             */
} urt_sensors_params_t;

/* The three filters' states. */
typedef struct urt_sensors_state {
  double i_f;      /* current-sensor output             [A]      */
  double w, wd;    /* motor-speed filter output, rate   [rad/s, rad/s²] */
  double p, pd;    /* joint-position filter output, rate [rad, rad/s]   */
} urt_sensors_state_t;

/* Rates of the filter states for true current i [A], motor speed qd_m [rad/s] and joint
 * angle q [rad]. Context: RT. Pure. */
urt_sensors_state_t urt_sensors_deriv(const urt_sensors_params_t *p,
                                      const urt_sensors_state_t *s, double i, double qd_m,
                                      double q);

/* Mid-tread quantiser: lsb · round(x / lsb); lsb <= 0 passes x through. Context: RT. Pure. */
double urt_sensors_quantise(double x, double lsb);

/* Held measurement error ε = Q(y + σ n) − y for a standard-normal draw n. Context: RT. Pure. */
double urt_sensors_held_error(double y, double sigma, double n, double lsb, int noise,
                              int quantise);

/* Seeded xoshiro256** generator and a ziggurat standard normal (drivers/ziggurat_table.h).
 * Context: RT. */
typedef struct urt_rng {
  uint64_t s[4];
} urt_rng_t;
void urt_rng_seed(urt_rng_t *r, uint64_t seed);
uint64_t urt_rng_next(urt_rng_t *r);
double urt_rng_normal(urt_rng_t *r);

#ifdef __cplusplus
}
#endif
#endif
