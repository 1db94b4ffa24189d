// SPDX-License-Identifier: Apache-2.0
// tools/replay_csv.h — a recording in the layout of UR's RTDE record.py: one header line of
// space-separated names (vector fields as name_0 … name_5), then one row of numbers per sample.
// Any subset and order of RTDE's output names is accepted; urt_sim --replay needs timestamp,
// target_q_*, target_qd_* and actual_current_*, and uses target_qdd_*, target_current_*,
// actual_q_* and actual_qd_* when present.
#ifndef URT_TOOLS_REPLAY_CSV_H
#define URT_TOOLS_REPLAY_CSV_H

#include <array>
#include <string>
#include <vector>

#include "urt/model.h"

using Joints = std::array<double, URT_NJ>;

struct ReplayRecording {
  std::string path;
  std::vector<std::string> columns;  // the header, as read
  std::vector<int> line;             // the file line of each sample (1-based)
  std::vector<double> t;             // timestamp [s]
  std::vector<Joints> target_q, target_qd, target_qdd, target_current;
  std::vector<Joints> actual_q, actual_qd, actual_current;
  bool has_target_qdd = false, has_target_current = false;
  bool has_actual_q = false, has_actual_qd = false;
};

// Read and check a recording. Returns 0, or 2 with "file:line: reason" in *err: an unreadable
// file, an unknown, duplicate or missing required column, a row of the wrong length, a cell
// that is not a finite number, a timestamp not after the previous one, no samples.
int replay_csv_read(const std::string &path, ReplayRecording *r, std::string *err);

#endif
