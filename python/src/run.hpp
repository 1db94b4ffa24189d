// SPDX-License-Identifier: Apache-2.0
// python/src/run.hpp — the offline run behind urtwin.run(): a trajectory (one of tools/traj.h's
// or sampled arrays) played through urt_step exactly as urt_sim plays it (same command, same
// sampling instants, so the same seed gives the same bits), recording every signal urt_sim
// writes plus the drive's internal channels into one row-major buffer. Pure C++: no Python, so
// the caller can run it with the GIL released.
#ifndef URT_PYTHON_RUN_HPP
#define URT_PYTHON_RUN_HPP

#include <cstdint>
#include <string>
#include <vector>

#include "traj.h"
#include "urt/core.h"
#include "urt/faults.h"

namespace urtpy {

// A set-point given as samples: t strictly increasing from 0 [s], q, qd, qdd row-major n×6.
// Between samples q is a cubic Hermite on (q, q̇) at both ends and q̇, q̈ are linear; after the
// last sample the last q is held at rest.
struct SampledTraj {
  std::vector<double> t, q, qd, qdd;
  size_t n() const { return t.size(); }
  double duration() const { return t.empty() ? 0.0 : t.back(); }
  void eval(double t, double q[URT_NJ], double qd[URT_NJ], double qdd[URT_NJ]) const;
};

// Either a tools/traj.h trajectory or samples.
struct Trajectory {
  bool sampled = false;
  urt_traj_t builtin{};
  SampledTraj samples;
  double duration() const { return sampled ? samples.duration() : urt_traj_duration(&builtin); }
  const char *kind() const { return sampled ? "samples" : urt_traj_kind_name(builtin.kind); }
  void eval(double t, double q[URT_NJ], double qd[URT_NJ], double qdd[URT_NJ]) const;
};

struct RunSpec {
  double duration = -1.0;   // < 0: the trajectory's own
  long decimate = 1;        // record every decimate-th step (and the last)
  bool has_seed = false;    // reseed the sensor noise (as simulation.seed = seed would)
  uint64_t seed = 0;
  // The fault scenario (core/include/urt/faults.h; n = 0: none), installed after urt_data_init
  // and the reseed, as urt_sim --faults does; its truth is recorded per sample (channels()).
  urt_fault_scenario_t faults{};
};

// One recorded channel: columns [offset, offset + width) of each row.
struct Channel {
  const char *name;
  int offset, width;
  const char *unit;
  const char *what;
};

struct RunOutput {
  std::vector<Channel> channels;
  int row_width = 0;
  size_t rows = 0;
  std::vector<double> data;  // rows × row_width, row-major
  uint64_t steps = 0;
  double wall_s = 0.0;       // wall time of the stepping loop
  double cpu_s = 0.0;        // its CPU time (this thread's: a busy machine's measure)
  std::string error;         // set when run() returns non-zero
};

// The channels, in row order (the same for every run).
const std::vector<Channel> &channels();

// Play tr through m. Returns 0, or 1 with out->error (a refused command, a failed step, the
// trajectory outside the model's limits), 2 for bad arguments.
int run(const urt_model_t *m, const Trajectory &tr, const RunSpec &spec, RunOutput *out);

}  // namespace urtpy

#endif
