/* SPDX-License-Identifier: Apache-2.0
 * net/server/input_latch.c — the RTDE input registers as the controller latched them, tick by
 * tick (emulator_internal.h, in_hist). A controller latches its inputs once per cycle: a
 * client's package that arrives during cycle L is seen from cycle L + 1 on, by the program and
 * by the data packages alike. urtwin's program runs on the runner thread, which may process a
 * tick late and then several back to back; reading the live bank there, a late slice of tick k
 * would see inputs that arrived since, and the same inputs would give a different per-tick
 * command stream depending on the runner's lateness. Under reg_lock, I/O and runner threads.
 */
#include <string.h>

#include "emulator_internal.h"

void urt__inputs_latch(urt_emulator_t *e, uint64_t newest_tick) {
  // and never for a tick whose slice has read its inputs already: a runner thread ahead of this
  // one (this thread streams late) has run slice newest_tick + 1 with what it found
  const uint64_t from = (newest_tick > e->in_read_tick ? newest_tick : e->in_read_tick) + 1;
  struct urt__in_regs *h = &e->in_hist[e->in_newest];
  if (h->from != from) {
    // several packages in one cycle: the last one wins, as in a controller's latch
    if (h->from != 0) {
      e->in_newest = (e->in_newest + 1) % URT__IN_HISTORY;
      h = &e->in_hist[e->in_newest];
    }
    h->from = from;
  }
  memcpy(h->in_int, e->regs.in_int, sizeof h->in_int);
  memcpy(h->in_double, e->regs.in_double, sizeof h->in_double);
  memcpy(h->in_bit, e->regs.in_bit, sizeof h->in_bit);
}

void urt__inputs_read(urt_emulator_t *e, uint64_t tick, urt_rtde_registers_t *r) {
  if (tick > e->in_read_tick) {
    e->in_read_tick = tick;
  }
  urt__inputs_at(e, tick, r);
}

void urt__inputs_at(const urt_emulator_t *e, uint64_t tick, urt_rtde_registers_t *r) {
  const struct urt__in_regs *found = NULL;
  for (uint32_t n = 0; n < URT__IN_HISTORY; n++) {
    const struct urt__in_regs *h =
        &e->in_hist[(e->in_newest + URT__IN_HISTORY - n) % URT__IN_HISTORY];
    if (h->from == 0) {
      break;  // no older entry
    }
    found = h;
    if (h->from <= tick) {
      break;
    }
  }
  // every tick has an entry (the bank as it started holds from tick 1, emulator.c) unless the
  // reader is more than URT__IN_HISTORY written ticks behind: it then gets the oldest kept
  if (found) {
    memcpy(r->in_int, found->in_int, sizeof r->in_int);
    memcpy(r->in_double, found->in_double, sizeof r->in_double);
    memcpy(r->in_bit, found->in_bit, sizeof r->in_bit);
  }
}
