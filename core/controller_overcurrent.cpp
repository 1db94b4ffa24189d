// SPDX-License-Identifier: Apache-2.0
// core/controller_overcurrent.cpp — the controller's over-current check. A UR joint's drive
// protects its motor and electronics: a joint that cannot carry its load faults, its brake
// engages and the arm powers off ("C281A3: Robot State Machine: Shoulder joint entered the
// Fault State ... the brakes are activated and the robot needs to be manually activated
// again. The whole program stopped", a UR5e user, forum.universal-robots.com t/11925). The
// model's drive limits its current reference at ±i_max (model.md §1.2: i_max = T_max/(k_t τ)),
// so an over-current shows as a drive that keeps asking for that limit: its load needs more
// torque than the joint has. A running joint that does so for URT_OVERCURRENT_TIME without a
// break faults (controller.h: [P], the firmware's threshold is not public). The cause can be
// outside (a collision wrench, a payload heavier than the joint can lift) or in the joint (a
// dragging brake, a weakened motor, a seized gear).
//
// The current reference is the drive's output d->i_ref at the end of the last period (the
// state the tick starts from): the loop's snapshot (urt_snapshot_fill) and the replay's
// sampling refresh the outputs at every period's end (urt_ctrl_tick's contract), so it is not
// evaluated twice. A torque-mode joint's reference is its command, which the controller keeps
// within torque_max: one commanded at its very limit for that long counts as well.
// No allocation. Context: RT.
#include <cmath>

#include "controller_internal.hpp"
#include "joint.hpp"

namespace urt::core {

int tick_overcurrent_check(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                           bool run) noexcept {
  int tripped = -1;
  for (int j = 0; j < URT_NJ; j++) {
    if (!run) {
      c->oc_time[j] = 0.0;
      continue;
    }
    // the reference is clamped to exactly ±i_max when saturated (a fault's drive parameters,
    // where the joint has one); a millionth below it is not a limit a loop reaches by chance
    const urt_fault_joint_t* fj = joint_fault(d, j);
    const double i_max = (fj ? fj->control : m->control[j]).i_max;
    const bool at_limit = std::fabs(d->i_ref[j]) >= i_max * (1.0 - 1e-6);
    c->oc_time[j] = at_limit ? c->oc_time[j] + c->period : 0.0;
    // a millionth of a period below: whole periods summed in floating point
    if (tripped < 0 && c->oc_time[j] >= URT_OVERCURRENT_TIME - 1e-6 * c->period) {
      tripped = j;
    }
  }
  return tripped;
}

}  // namespace urt::core
