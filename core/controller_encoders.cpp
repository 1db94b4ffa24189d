// SPDX-License-Identifier: Apache-2.0
// core/controller_encoders.cpp — the controller's motor/joint encoder check. Each UR joint has
// two encoders, one on the motor shaft and one on the output; the controller compares them and
// a disagreement trips a protective stop (../shared/docs/faults.md, class 9, source [18]: UR's
// service manual and a repairer's guide: "If deviation exceeds tolerance: Position Disagree
// fault", "Protective Stops"). Here that is what a stuck, biased or drifting joint encoder, or
// a stuck or biased motor encoder, does to a running arm: before the loop, closed on the bad
// reading, carries the arm away.
//
// The motor side is the motor angle plus the angle error its encoder's faults have added up.
// The model's motor-encoder faults act on the speed reading (urt/faults.h), so that error is the
// reading's deviation (a bias, or a stuck value against the true filtered speed) integrated over
// each period; its noise and lost counts are left out, as a count error does not accumulate
// into the angle a real drive counts (the check then sees only what persists). The joint side
// is the joint encoder's reading (urt__measured_q, its faults included). Their difference is
// the gear's deflection, which changes with the load; it is taken as the reference whenever the
// arm does not run (powered off, braked, stopped), so only what changes while running counts,
// against URT_ENCODER_TOLERANCE (controller.h: above every mechanical fault's own). No
// allocation. Context: RT.
#include <cmath>

#include "controller_internal.hpp"
#include "joint.hpp"
#include "step_internal.h"

namespace urt::core {

int tick_encoder_check(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d,
                       bool run) noexcept {
  int tripped = -1;
  for (int j = 0; j < URT_NJ; j++) {
    const double* x = d->x[j];
    const urt_fault_joint_t* fj = joint_fault(d, j);
    if (fj) {
      const double healthy = x[URT_X_W] + d->eps_w[j];
      const double deviation =
          fj->qdm_stuck ? fj->qdm_hold - healthy : fj->qdm_bias;  // noise, lost counts: above
      c->enc_motor_err[j] += deviation * c->period;
    }
    const double ratio = (fj ? fj->gear : m->gear[j]).ratio;
    const double disagreement =
        (x[URT_X_QM] + c->enc_motor_err[j]) / ratio - urt__measured_q(d, j);
    if (!run) {
      c->enc_anchor[j] = disagreement;
      continue;
    }
    if (tripped < 0 && std::fabs(disagreement - c->enc_anchor[j]) > URT_ENCODER_TOLERANCE) {
      tripped = j;  // the others' motor errors still advance this period
    }
  }
  return tripped;
}

}  // namespace urt::core
