// SPDX-License-Identifier: Apache-2.0
// tools/bench_timing.h — what every timed case of urt_bench shares: a monotonic clock, order
// statistics of per-step samples, and the moving set-point both engines follow.
#ifndef URT_TOOLS_BENCH_TIMING_H
#define URT_TOOLS_BENCH_TIMING_H

#include <time.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "urt/model.h"

namespace urt::tools {

inline int64_t now_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

struct Stats {
  long n = 0;
  double min_us = 0, median_us = 0, mean_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
};

// Order statistics of per-step samples [ns], reported in µs.
Stats summarise(std::vector<int64_t> samples_ns);

// Median cost of an empty timed region: what every sample carries on top of the work (reported,
// not subtracted — it is ~20 ns on a vDSO clock, well below the noise of a shared machine).
double clock_overhead_ns();

// Per joint j: q = q0 + A·(1 − cos ωt), so the arm starts at rest at q0 and reverses at every
// half period (friction passes through stick–slip), with consistent q, q̇, q̈. Frequencies
// differ per joint so the configuration — and M(q) — keeps changing.
struct Setpoint {
  double q0[URT_NJ], amp[URT_NJ], omega[URT_NJ];

  void at(double t, double q[URT_NJ], double qd[URT_NJ], double qdd[URT_NJ]) const {
    for (int j = 0; j < URT_NJ; ++j) {
      double c = std::cos(omega[j] * t), s = std::sin(omega[j] * t);
      q[j] = q0[j] + amp[j] * (1.0 - c);
      qd[j] = amp[j] * omega[j] * s;
      qdd[j] = amp[j] * omega[j] * omega[j] * c;
    }
  }
};

// The set-point for a model: from its q0, inside its limits, peak speed `speed` [rad/s].
Setpoint make_setpoint(const urt_model_t *m, double speed);

}  // namespace urt::tools

#endif
