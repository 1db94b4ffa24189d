/* SPDX-License-Identifier: Apache-2.0
 * drivers/motor.c — DC-equivalent PMSM, paper eq. (1). Equations in the header. */
#include "urt/drivers/motor.h"
#include "urt/drivers/motor_inline.h"

urt_motor_deriv_t urt_motor_deriv(const urt_motor_params_t *p, const urt_motor_state_t *s,
                                  double v_sup, double t_in) {
  return urt_motor_deriv_inline(p, s, v_sup, t_in);
}
