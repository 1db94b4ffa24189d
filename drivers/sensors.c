/* SPDX-License-Identifier: Apache-2.0
 * drivers/sensors.c — held measurement errors (noise + quantisation) and the seeded RNG.
 * The sensor filters themselves are continuous states integrated with the drive; their
 * equations are in the header. */
#include "urt/drivers/sensors.h"
#include "urt/drivers/sensors_inline.h"

#include <math.h>

urt_sensors_state_t urt_sensors_deriv(const urt_sensors_params_t *p,
                                      const urt_sensors_state_t *s, double i, double qd_m,
                                      double q) {
  return urt_sensors_deriv_inline(p, s, i, qd_m, q);
}

double urt_sensors_quantise(double x, double lsb) {
  if (!(lsb > 0.0)) {
    return x;
  }
  return lsb * nearbyint(x / lsb);
}

double urt_sensors_held_error(double y, double sigma, double n, double lsb, int noise,
                              int quantise) {
  double meas = y + (noise ? sigma * n : 0.0);
  if (quantise) {
    meas = urt_sensors_quantise(meas, lsb);
  }
  return meas - y;
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

// splitmix64 spreads any seed (even 0) over the four xoshiro words
static uint64_t splitmix64(uint64_t *s) {
  uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

void urt_rng_seed(urt_rng_t *r, uint64_t seed) {
  for (int k = 0; k < 4; k++) {
    r->s[k] = splitmix64(&seed);
  }
  r->spare = 0.0;
  r->has_spare = 0;
}

// xoshiro256** (Blackman and Vigna)
uint64_t urt_rng_next(urt_rng_t *r) {
  uint64_t *s = r->s;
  uint64_t result = rotl(s[1] * 5, 7) * 9;
  uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return result;
}

// uniform in (0, 1): 53 random bits, never exactly 0 so the logarithm below stays finite
static double uniform(urt_rng_t *r) { return ((urt_rng_next(r) >> 11) + 0.5) * 0x1.0p-53; }

double urt_rng_normal(urt_rng_t *r) {
  if (r->has_spare) {
    r->has_spare = 0;
    return r->spare;
  }

  // Box–Muller: two uniforms give two independent normals; keep one for the next call
  double u1 = uniform(r), u2 = uniform(r);
  double rad = sqrt(-2.0 * log(u1));
  double ang = 6.283185307179586 * u2;
  r->spare = rad * sin(ang);
  r->has_spare = 1;
  return rad * cos(ang);
}
