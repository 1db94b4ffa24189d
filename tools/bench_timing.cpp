// SPDX-License-Identifier: Apache-2.0
// tools/bench_timing.cpp — clock, statistics and set-point shared by urt_bench's cases.
#include "bench_timing.h"

#include <algorithm>

namespace urt::tools {
namespace {

// nearest-rank percentile of sorted data, p in (0, 1]
double percentile(const std::vector<int64_t> &sorted, double p) {
  size_t n = sorted.size();
  size_t k = static_cast<size_t>(std::ceil(p * static_cast<double>(n)));
  k = std::min(std::max<size_t>(k, 1), n);
  return static_cast<double>(sorted[k - 1]);
}

}  // namespace

Stats summarise(std::vector<int64_t> samples_ns) {
  Stats s;
  if (samples_ns.empty()) {
    return s;
  }
  std::sort(samples_ns.begin(), samples_ns.end());
  size_t n = samples_ns.size();
  double sum = 0;
  for (int64_t x : samples_ns) {
    sum += static_cast<double>(x);
  }
  s.n = static_cast<long>(n);
  s.min_us = samples_ns.front() * 1e-3;
  s.max_us = samples_ns.back() * 1e-3;
  s.mean_us = sum / static_cast<double>(n) * 1e-3;
  s.median_us = (n % 2 ? static_cast<double>(samples_ns[n / 2])
                       : 0.5 * static_cast<double>(samples_ns[n / 2 - 1] + samples_ns[n / 2])) *
                1e-3;
  s.p99_us = percentile(samples_ns, 0.99) * 1e-3;
  s.p999_us = percentile(samples_ns, 0.999) * 1e-3;
  return s;
}

double clock_overhead_ns() {
  std::vector<int64_t> v(20000);
  for (auto &x : v) {
    int64_t t0 = now_ns();
    int64_t t1 = now_ns();
    x = t1 - t0;
  }
  std::sort(v.begin(), v.end());
  return static_cast<double>(v[v.size() / 2]);
}

// amp carries the direction (sign) that keeps q0 + 2A inside the limits with a margin.
Setpoint make_setpoint(const urt_model_t *m, double speed) {
  const double kMargin = 0.05;  // rad kept from each limit
  Setpoint sp;
  for (int j = 0; j < URT_NJ; ++j) {
    double w = 2.0 * M_PI * (0.25 + 0.05 * j);
    // a limit of 0 (not set in the file) means "no limit", not "do not move"
    double v = m->joint[j].qd_max > 0 ? std::min(speed, 0.9 * m->joint[j].qd_max) : speed;
    double a = v / w;
    if (m->joint[j].qdd_max > 0) {
      a = std::min(a, 0.9 * m->joint[j].qdd_max / (w * w));
    }
    double room_up = (m->joint[j].q_max - kMargin - m->q0[j]) / 2.0;
    double room_down = (m->q0[j] - m->joint[j].q_min - kMargin) / 2.0;
    if (a <= room_up) {
      sp.amp[j] = a;
    } else if (a <= room_down) {
      sp.amp[j] = -a;
    } else {
      sp.amp[j] = room_up >= room_down ? std::max(room_up, 0.0) : -std::max(room_down, 0.0);
    }
    sp.q0[j] = m->q0[j];
    sp.omega[j] = w;
  }
  return sp;
}

}  // namespace urt::tools
