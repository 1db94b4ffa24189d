/* SPDX-License-Identifier: Apache-2.0
 * drivers/pi_cascade.c — position P, speed PI, current PI with clamping anti-windup and the
 * averaged 48 V PWM stage. Equations in the header. */
#include "urt/drivers/pi_cascade.h"
#include "urt/drivers/pi_cascade_inline.h"

urt_pi_cascade_out_t urt_pi_cascade_eval(const urt_pi_cascade_params_t *p, double ratio,
                                         const urt_pi_cascade_state_t *s,
                                         const urt_pi_cascade_in_t *in) {
  return urt_pi_cascade_eval_inline(p, ratio, s, in);
}
