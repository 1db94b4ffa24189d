/* SPDX-License-Identifier: Apache-2.0
 * drivers/friction.c — LuGre friction, paper eq. (7). Equations in the header. */
#include "urt/drivers/friction.h"
#include "urt/drivers/friction_inline.h"

#include <math.h>

double urt_friction_g(const urt_friction_params_t *p, double qd) {
  double g, v_dg;
  urt__friction_g_and_vdg(p, urt__friction_fc(p, qd), fabs(qd), &g, &v_dg);
  return g;
}

double urt_friction_dg(const urt_friction_params_t *p, double qd) {
  double v = fabs(qd);
  if (v == 0.0) {
    return 0.0;
  }
  double g, v_dg;
  urt__friction_g_and_vdg(p, urt__friction_fc(p, qd), v, &g, &v_dg);
  return (qd > 0.0 ? 1.0 : -1.0) * v_dg / v;
}

urt_friction_out_t urt_friction_eval(const urt_friction_params_t *p,
                                     const urt_friction_state_t *s, double qd) {
  return urt_friction_eval_inline(p, s, qd);
}
