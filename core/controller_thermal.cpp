// SPDX-License-Identifier: Apache-2.0
// core/controller_thermal.cpp — the motors' thermal model, stepped once per controller period:
// a first-order winding temperature per joint, c_th dT/dt = R i² − (T − t_amb)/r_th, with the
// copper loss of the current the physics ran (config/README.md, `thermal`). Its temperatures are
// the joint temperatures of ports 30003/RTDE. No allocation. Context: RT.
#include <cmath>

#include "controller_internal.hpp"

namespace urt::core {

void tick_thermal(const urt_model_t* m, urt_ctrl_t* c, const urt_data_t* d) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    const urt_thermal_params_t& th = m->thermal[j];
    if (th.c_th <= 0.0 || th.r_th <= 0.0) {
      c->temperature[j] = th.t_amb;
      continue;
    }
    double i = d->x[j][URT_X_I];
    double p_loss = m->motor[j].r * i * i;
    // exact for constant loss over the period (stable at any rate)
    double t_ss = th.t_amb + p_loss * th.r_th;
    double k = std::exp(-c->period / (th.r_th * th.c_th));
    c->temperature[j] = t_ss + (c->temperature[j] - t_ss) * k;
  }
}

}  // namespace urt::core
