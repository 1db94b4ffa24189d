// SPDX-License-Identifier: Apache-2.0
// tools/io_script.h — `urtwin --io FILE`: a timed script of input levels (what a test rig or
// a PLC would put on the control box's inputs), played in controller time on its own thread.
//
//   # t: controller time since start [s], non-decreasing; each entry changes only what it names
//   - t: 0.5
//     standard_digital_in: {0: true, 3: true}     # pins 0–7
//   - t: 1.0
//     configurable_digital_in: {2: true}          # pins 0–7 (bits 8–15)
//     tool_digital_in: {0: true}                  # pins 0–1 (bits 16–17)
//     standard_analog_in: {0: 4.2}                # inputs 0–1 [V], 0–10
//     tool_analog_in: {1: 0.5}                    # inputs 0–1 [V], 0–10
//
// Each entry becomes one URT_CTRL_SET_INPUTS submitted when the loop's newest tick reaches t,
// so it takes effect at the first tick at or after t (lockstep pacing: when the ticks get
// there). Errors name the file, line and key, as the config's do.
#pragma once

#include <string>
#include <vector>

#include "urt/controller.h"
#include "urt/loop.h"

struct IoEvent {
  double t;            // controller time [s]
  urt_ctrl_cmd_t cmd;  // URT_CTRL_SET_INPUTS
  int line;            // where it came from, for messages
};

// Parse FILE. Returns false with "file:line: key: reason" in *err.
bool io_script_load(const std::string &path, std::vector<IoEvent> *out, std::string *err);

// A thread that plays the events into the loop (its own command ring, "io").
class IoPlayer {
 public:
  IoPlayer(urt_loop_t *loop, std::vector<IoEvent> events);
  ~IoPlayer();
  bool start(std::string *err);  // claims the ring and starts the thread
  void stop();                   // bounded: the thread looks at its stop flag every 50 ms
  size_t played() const;         // events submitted so far
  size_t dropped() const;        // events the ring could not take (counted, not retried)

 private:
  struct Impl;
  Impl *impl_;
};
