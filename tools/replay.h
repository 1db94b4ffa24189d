// SPDX-License-Identifier: Apache-2.0
// tools/replay.h — plays a recording's set-point (tools/replay_csv.h) through the twin as the
// controller's target and compares the twin's motor currents with the measured ones.
#ifndef URT_TOOLS_REPLAY_H
#define URT_TOOLS_REPLAY_H

#include <string>
#include <vector>

#include "replay_csv.h"
#include "urt/core.h"

struct ReplayJointStats {
  double range = 0.0;          // max − min of target_q [rad]
  bool moves = false;          // range > 0.05 rad
  double rms_meas = 0.0;       // RMS(actual_current) [A]
  double rms_err_twin = 0.0;   // RMS(twin − actual) [A]
  double rms_err_ur = 0.0;     // RMS(target_current − actual) [A] (NaN without target_current)
  double ratio_twin = 0.0, ratio_ur = 0.0;  // the errors over rms_meas
  double corr_twin = 0.0, corr_ur = 0.0;    // Pearson correlation with actual_current
};

struct ReplayResult {
  double period = 0.0;         // controller period the set-point is fed at [s]
  long ticks = 0;              // controller periods run
  long gaps = 0;               // sample intervals longer than 1.5 periods (filled)
  double max_gap = 0.0;        // longest sample interval [s]
  double max_time_offset = 0;  // largest distance of a sample interval from whole periods [s]
  long dropped = 0;            // samples on a tick another sample already took
  double wall = 0.0;           // wall time of the simulation [s]
  double cpu = 0.0;            // its CPU time (the simulating thread's) [s]
  long steps = 0, refined = 0; // physics steps, and those redone as fine steps (urt_step)
  std::vector<Joints> twin_q, twin_qd, twin_current;  // the twin at each recorded sample
  ReplayJointStats joint[URT_NJ];
};

// "joints.J.qd_max=V" / "joints.J.qdd_max=V" for every joint whose recorded target_qd or
// target_qdd exceeds the model's limit (V: 2 % above the recorded maximum).
void replay_limit_overrides(const urt_model_t *m, const ReplayRecording &rec,
                            std::vector<std::string> *out);

// Run the replay: the twin starts at the first recorded target_q at rest; every controller
// period (the recording's sample interval, its 10th percentile, a whole number of physics steps) the
// controller takes the recorded set-point at the period's end (samples missing in a gap are
// interpolated: q by cubic Hermite on q and q̇, q̇ and q̈ linearly; each sample is placed the
// nearest whole number of periods after the previous one, as the controller produced it) and the drives follow its
// interpolation. Returns 0, or 1 with a message in *err (a refused set-point, a failed step).
int replay_run(const urt_model_t *m, const ReplayRecording &rec, ReplayResult *res,
               std::string *err);

// Write the recording's set-point and measurements beside the twin's signals, space-separated
// with one header line (record.py style). Returns false with a message on a write error.
bool replay_write_trace(const std::string &path, const ReplayRecording &rec,
                        const ReplayResult &res, std::string *err);

// The summary as JSON (keys joints[j].rms_meas, rms_err_twin, rms_err_ur, ratio_twin,
// ratio_ur, corr_twin, corr_ur, name, range, moves; rms_err_ur etc. null without
// target_current).
bool replay_write_json(const std::string &path, const urt_model_t *m, const ReplayRecording &rec,
                       const ReplayResult &res, std::string *err);

// The table on f.
void replay_print(FILE *f, const urt_model_t *m, const ReplayRecording &rec,
                  const ReplayResult &res);

#endif
