/* SPDX-License-Identifier: Apache-2.0
 * net/server/port_rtde.c — port 30004 (RTDE): one urt_rtde_session_t per connection; client
 * inputs reach the controller (speed slider, digital and analog outputs, external wrench) and
 * the register bank every tick, and data packages leave at each recipe's frequency. */
#include <stdlib.h>
#include <string.h>

#include "emulator_internal.h"

#define DATA_MAX 8192  /* largest data package an output recipe can make [bytes] */

// Queue the session's pending replies on the connection; false when they do not fit (a
// client that does not read its replies is broken: the caller closes it).
static bool send_replies(urt__client_t *c) {
  urt_rtde_session_t *s = c->proto;
  const uint8_t *p;
  size_t n = urt_rtde_session_output(s, &p);
  if (n == 0) {
    return true;
  }
  if (!urt_tcp_send(c->conn, p, n)) {
    return false;
  }
  urt_rtde_session_consume(s, n);
  return true;
}

static bool rtde_open(urt_emulator_t *e, urt__client_t *c) {
  urt_rtde_session_t *s = malloc(sizeof *s);  // ~45 kB: per connection, not on the stack
  if (!s) {
    return false;
  }
  urt_rtde_session_init(s, &e->rtde_registry, &e->cfg.version);
  c->proto = s;
  return true;
}

static bool rtde_input(urt_emulator_t *e, urt__client_t *c, const uint8_t *data, size_t n) {
  urt_rtde_session_t *s = c->proto;
  atomic_fetch_add(&e->rtde_packages, 1);
  while (n > 0) {
    long used = urt_rtde_session_feed(s, data, n);
    if (used < 0 || urt_rtde_session_closed(s)) {
      return false;  // unrecoverable framing: the real controller drops the connection too
    }
    data += used;
    n -= (size_t)used;
    if (!send_replies(c)) {
      return false;
    }
    if (used == 0 && n > 0 && urt_rtde_session_output(s, &(const uint8_t *){NULL}) > 0) {
      return false;  // replies are stuck: the client is not reading them
    }
  }
  // the first inputs of a period go to the controller now, not at the next tick (one period
  // less of latency); later ones in the same period wait in the session, merged newest-wins,
  // for the tick (a controller reads its inputs once a cycle): a client sending at 10 kHz
  // costs the ring one set of commands per period, not twenty
  if (urt_loop_latest_tick(e->loop) > e->rtde_applied_tick) {
    urt__rtde_apply_inputs(e);
  }
  return true;
}

static void apply(urt_emulator_t *e, const urt_rtde_inputs_t *all);

static void rtde_close(urt_emulator_t *e, urt__client_t *c) {
  if (c->proto) {
    // inputs it sent after the period's first wait in the session for the next tick, which
    // would no longer see them (close_client has taken the client off the list); the bytes
    // arrived before its FIN and a controller acts on them, so they are applied here
    urt_rtde_inputs_t last;
    if (urt_rtde_session_take_inputs(c->proto, &last)) {
      apply(e, &last);
    }
    urt_rtde_session_fini(c->proto);
    free(c->proto);
    c->proto = NULL;
  }
}

const urt__port_ops_t urt__port_rtde_ops = {.open = rtde_open, .input = rtde_input,
                                            .close = rtde_close};

//---- per tick ----

// Set digital outputs first..first+7 from a mask and values.
static void submit_outputs(urt_emulator_t *e, int first, uint8_t mask, uint8_t values) {
  for (int b = 0; b < 8; b++) {
    if (mask >> b & 1) {
      urt_ctrl_cmd_t cmd = {.kind = URT_CTRL_SET_DIGITAL_OUT, .index = first + b,
                            .value = (double)(values >> b & 1)};
      urt__submit(e, URT__RING_RTDE, &cmd);
    }
  }
}

void urt__rtde_apply_inputs(urt_emulator_t *e) {
  urt_rtde_inputs_t all, one;
  bool any = false;
  for (urt__client_t *c = e->clients; c; c = c->next) {
    if (c->conn->port_kind != PORT_RTDE || !c->proto) {
      continue;
    }
    // inputs apply without S: ur_rtde's IO interface never starts a stream
    if (urt_rtde_session_take_inputs(c->proto, &one)) {
      if (!any) {
        all = one;
        any = true;
      } else {
        urt_rtde_inputs_merge(&all, &one);
      }
    }
  }
  if (any) {
    apply(e, &all);
  }
}

// Hand merged inputs to the controller: the registers (latched for the tick), then commands.
static void apply(urt_emulator_t *e, const urt_rtde_inputs_t *in) {
  e->rtde_applied_tick = urt_loop_latest_tick(e->loop);
  pthread_mutex_lock(&e->reg_lock);
  urt_rtde_inputs_apply_registers(in, &e->regs);
  urt__inputs_latch(e, e->rtde_applied_tick);
  pthread_mutex_unlock(&e->reg_lock);
  if (in->set & URT_RTDE_IN_SPEED_SLIDER) {
    urt_ctrl_cmd_t cmd = {.kind = URT_CTRL_SET_SPEED_SLIDER, .value = in->speed_slider_fraction};
    urt__submit(e, URT__RING_RTDE, &cmd);
  }
  if (in->set & URT_RTDE_IN_EXT_FT) {
    // the virtual world pushes the tool with this wrench (it is what the physics feels)
    urt_ctrl_cmd_t cmd = {.kind = URT_CTRL_SET_WRENCH};
    memcpy(cmd.pose, in->external_force_torque, sizeof cmd.pose);
    urt__submit(e, URT__RING_RTDE, &cmd);
  }
  submit_outputs(e, 0, in->std_do_mask, in->std_do);
  submit_outputs(e, 8, in->conf_do_mask, in->conf_do);
  submit_outputs(e, 16, in->tool_do_mask & 3, in->tool_do);
  for (int i = 0; i < 2; i++) {
    if (in->ao_mask >> i & 1) {
      urt_ctrl_cmd_t cmd = {.kind = URT_CTRL_SET_ANALOG_OUT, .index = i, .value = in->ao[i]};
      urt__submit(e, URT__RING_RTDE, &cmd);
    }
  }
}

void urt__rtde_stream_tick(urt_emulator_t *e, const urt_snapshot_t *s) {
  static _Thread_local urt_rtde_registers_t regs;
  static _Thread_local uint8_t buf[DATA_MAX];
  bool have_regs = false;
  for (urt__client_t *c = e->clients; c; c = c->next) {
    if (c->conn->port_kind != PORT_RTDE || !c->proto) {
      continue;
    }
    urt_rtde_session_t *ses = c->proto;
    if (!ses->started) {
      continue;
    }
    if (!have_regs) {
      pthread_mutex_lock(&e->reg_lock);
      regs = e->regs;
      urt__inputs_at(e, s->tick, &regs);  // the inputs as this tick held them
      // a running program's outputs as its slice of the previous tick left them: the slice
      // whose commands this tick executed (on a controller both come from one cycle; the
      // program may have run further by the time this thread streams the tick)
      // (also for the ticks a late I/O thread streams after the program has ended)
      const struct urt__out_regs *h = &e->out_hist[(s->tick - 1) % URT_LOOP_HISTORY];
      bool kept = s->tick > 0 && h->slice == s->tick;
      if (!kept && e->out_running && e->out_done > 0 && e->out_done < s->tick) {
        // that slice has not ended yet (the runner is late): the newest slice that has, never
        // the live bank, which may hold part of the running slice's writes
        h = &e->out_hist[(e->out_done - 1) % URT_LOOP_HISTORY];
        kept = true;
      }
      if (kept) {
        memcpy(regs.out_int, h->out_int, sizeof regs.out_int);
        memcpy(regs.out_double, h->out_double, sizeof regs.out_double);
        memcpy(regs.out_bit, h->out_bit, sizeof regs.out_bit);
      }
      pthread_mutex_unlock(&e->reg_lock);
      have_regs = true;
    }
    send_replies(c);
    int n = urt_rtde_session_encode_data(ses, s, &regs, buf, sizeof buf);
    if (n > 0 && !urt_tcp_send(c->conn, buf, (size_t)n)) {
      atomic_fetch_add(&e->rtde_dropped, 1);
    }
  }
}
