/* SPDX-License-Identifier: Apache-2.0
 * drivers/sensors.c — held measurement errors (noise + quantisation) and the seeded RNG.
 * The sensor filters themselves are continuous states integrated with the drive; their
 * equations are in the header. */
#include "urt/drivers/sensors.h"
#include "urt/drivers/sensors_inline.h"
#include "ziggurat_table.h"

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

// the top 53 bits of a draw as a point in (0, 1), never exactly 0 so a logarithm of it stays
// finite
static double unit_open(uint64_t u) { return ((double)(u >> 11) + 0.5) * 0x1.0p-53; }

static double uniform(urt_rng_t *r) { return unit_open(urt_rng_next(r)); }

// The ziggurat (Marsaglia and Tsang 2000; layers in ziggurat_table.h): one 64-bit draw picks a
// layer (bits 0-7), a sign (bit 8) and a point along the layer (bits 11-63, independent of the
// other two); about 99 % of draws end at the first comparison, the rest in the layer's wedge
// (an exp) or the tail beyond R (two logs, Marsaglia 1964). Exact in distribution, as
// Box–Muller was (which took a log, a sqrt, a sin and a cos per two draws: 12 % of urt_step
// with noise on), but a seed's sequence is not Box–Muller's.
double urt_rng_normal(urt_rng_t *r) {
  for (;;) {
    const uint64_t u = urt_rng_next(r);
    const int i = (int)(u & 0xff);
    const double sign = (u & 0x100) ? -1.0 : 1.0;
    const double z = unit_open(u) * urt_zig_x[i];
    if (z < urt_zig_x[i + 1]) {
      return sign * z;  // inside the layer's rectangle that lies under f everywhere
    }
    if (i == 0) {
      // the tail beyond R: a = -ln(u1)/R, b = -ln(u2), accepted when 2b >= a^2
      double a, b;
      do {
        a = -log(uniform(r)) / URT_ZIG_R;
        b = -log(uniform(r));
      } while (b + b < a * a);
      return sign * (URT_ZIG_R + a);
    }
    // the wedge between x[i+1] and x[i]: a uniform height in the layer, under f(z) or not
    const double y = urt_zig_f[i] + uniform(r) * (urt_zig_f[i + 1] - urt_zig_f[i]);
    if (y < exp(-0.5 * z * z)) {
      return sign * z;
    }
  }
}
