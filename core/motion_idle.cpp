// SPDX-License-Identifier: Apache-2.0
// core/motion_idle.cpp — no motion: the set-point holds where the last motion left it, at rest.
// Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

uint32_t tick(const MotionEnv& e) {
  std::memset(e.c->qd1, 0, sizeof e.c->qd1);
  std::memset(e.c->qdd1, 0, sizeof e.c->qdd1);
  return 0;
}

void start(const MotionEnv&, const urt_ctrl_cmd_t&, const MotionStart&) {}

}  // namespace

const Motion kIdleMotion = {URT_MOTION_IDLE, false, false, false, no_bad_argument,
                            no_bad_target,   start, tick,  stop_on_path, nullptr};

}  // namespace urt::core
