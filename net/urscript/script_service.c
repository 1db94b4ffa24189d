/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_service.c — what the controller does for a running program every tick,
 * whatever its threads do: it records the TCP force (for tool_contact) and checks the RTDE watchdog set by
 * rtde_set_watchdog. The scheduler calls urt__us_service_tick once per tick, before the threads
 * run; the builtins that read the record live here too.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "script_vm.h"

#define CONTACT_FORCE 10.0  /* [N] resisting force along the direction that is a contact */
#define CONTACT_ONSET 2.5   /* [N] below this the contact had not started yet            */

int urt__us_service_tick(us_service *sv, const us_hooks *h, uint64_t tick, us_err *err) {
  const urt_script_host_t *host = h->host;
  // the tick's own snapshot, as the slices read (urt__us_snap): a late runner's service ticks,
  // run back to back, recorded the newest force each, the same sample several times over
  urt_snapshot_t s;
  urt__us_snap_at(host, tick, &s);
  uint64_t k = sv->n++ % US_HIST;
  memcpy(sv->f[k], s.tcp_force, sizeof sv->f[k]);  // already less zero_ftsensor's offset

  // rtde_set_watchdog: a refresh within 1 / f (one tick of slack). A paused program's watchdog
  // waits: it is armed again from the tick the program plays.
  if (sv->wd_on && host->read_registers) {
    urt_rtde_registers_t r;
    host->read_registers(host->ctx, tick, &r);
    uint32_t n = sv->wd_double ? r.in_double_writes[sv->wd_reg] : r.in_int_writes[sv->wd_reg];
    if (s.program_state == URT_PROGRAM_PAUSED) {
      sv->wd_last = -1;
    } else if (n != sv->wd_count || sv->wd_last < 0) {
      sv->wd_count = n;
      sv->wd_last = s.time;
    } else if (s.time - sv->wd_last > sv->wd_period + s.period + 1e-9) {
      if (sv->wd_pause) {
        // "pause": the program pauses (and is frozen, script_sched.c) until `play`; a command
        // ring that is full is asked again at the next tick
        urt_ctrl_cmd_t c = {.kind = URT_CTRL_PAUSE, .tick = tick};
        if (host->submit(host->ctx, &c)) {
          sv->wd_last = -1;
        }
        return X_OK;
      }
      if (err->kind == US_ERR_NONE) {
        err->kind = US_ERR_RUNTIME;
        snprintf(err->text, sizeof err->text,
                 "RTDE watchdog: %s was not updated for %.3f s (minimum frequency %g Hz); "
                 "program stopped",
                 sv->wd_name, s.time - sv->wd_last, 1.0 / sv->wd_period);
      }
      return X_ERR;
    }
  }
  return X_OK;
}

//---- builtins ----

/* tool_contact(direction): ticks back to just before a contact along the direction's translation
 * started, or 0 without one. A contact is a resisting force (opposite to the direction) above
 * CONTACT_FORCE in the TCP force zeroed by zero_ftsensor; an all-zero direction counts contacts
 * from every direction (the force's size). */
static int b_tool_contact(vm *V, const us_node *n, sv *a, sv *out) {
  double dir[6];
  if (urt__us_arg_vec6(V, n, a, 0, dir, NULL) != X_OK) return X_ERR;
  us_service *sv = urt__us_service(V);
  double norm = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  uint64_t avail = sv->n < US_HIST ? sv->n : US_HIST;
  int steps = 0;
  for (uint64_t k = 0; k < avail; k++) {
    const double *f = sv->f[(sv->n - 1 - k) % US_HIST];
    double resist = norm < 1e-12 ? sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                                 : -(f[0] * dir[0] + f[1] * dir[1] + f[2] * dir[2]) / norm;
    if (k == 0 && resist <= CONTACT_FORCE) break;
    if (resist <= CONTACT_ONSET) break;
    steps = (int)k + 1;
  }
  *out = mk_int(steps);
  return X_OK;
}

/* zero_ftsensor(): the controller subtracts the wrench it reads now from every later reading
 * (get_tcp_force, RTDE actual_TCP_force, 30003, tool_contact) */
static int b_zero_ftsensor(vm *V, const us_node *n, sv *a, sv *out) {
  urt_ctrl_cmd_t c = {.kind = URT_CTRL_ZERO_FTSENSOR};
  memcpy(c.pose, urt__us_snap(V)->tcp_force_raw, sizeof c.pose);
  return urt__us_submit(V, n, &c);
}

/* rtde_set_watchdog(variable_name, min_frequency, action="pause"): when the input register is
 * not written within 1 / min_frequency, "pause" (UR's default) pauses the program until
 * dashboard `play`, "stop" stops it; "ignore" (or f = 0) turns it off. */
static int b_rtde_set_watchdog(vm *V, const us_node *n, sv *a, sv *out) {
  double f;
  if (a[0].t != V_STR) return urt__us_fail(V, n, "Type error: rtde_set_watchdog: variable_name must be a string");
  if (urt__us_arg_num(V, n, a, 1, 0, &f) != X_OK) return X_ERR;
  const char *action = "pause";
  int alen = 5;
  if (a[2].t == V_STR) {
    action = a[2].u.s;
    alen = a[2].n;
  } else if (a[2].t != V_NONE) {
    return urt__us_fail(V, n, "Type error: rtde_set_watchdog: action must be a string");
  }
  us_service *sv = urt__us_service(V);
  char name[64];
  snprintf(name, sizeof name, "%.*s", a[0].n, a[0].u.s);
  int reg = -1;
  bool dbl = false;
  if (sscanf(name, "input_int_register_%d", &reg) == 1) {
    dbl = false;
  } else if (sscanf(name, "input_double_register_%d", &reg) == 1) {
    dbl = true;
  } else {
    return urt__us_fail(V, n, "rtde_set_watchdog: %s is not an RTDE input register urtwin watches "
                              "(input_int_register_N, input_double_register_N)", name);
  }
  if (reg < 0 || reg >= URT_RTDE_NREG) return urt__us_fail(V, n, "rtde_set_watchdog: register %d out of range", reg);
  if (alen == 6 && memcmp(action, "ignore", 6) == 0) {
    sv->wd_on = false;
    return X_OK;
  }
  bool pause = alen == 5 && memcmp(action, "pause", 5) == 0;
  if (!pause && !(alen == 4 && memcmp(action, "stop", 4) == 0)) {
    return urt__us_fail(V, n, "rtde_set_watchdog: unknown action \"%.*s\" (\"pause\", \"stop\" or "
                              "\"ignore\")", alen, action);
  }
  if (!(f >= 0)) return urt__us_fail(V, n, "rtde_set_watchdog: negative frequency %g", f);
  sv->wd_on = f > 0;
  sv->wd_pause = pause;
  sv->wd_double = dbl;
  sv->wd_reg = reg;
  sv->wd_period = f > 0 ? 1.0 / f : 0;
  sv->wd_last = -1;  // armed at the next tick
  snprintf(sv->wd_name, sizeof sv->wd_name, "%s", name);
  return X_OK;
}

#define P(...) {__VA_ARGS__}
const us_builtin urt__us_builtins_service[] = {
    {"tool_contact", b_tool_contact, 1, P("direction")},
    {"zero_ftsensor", b_zero_ftsensor, 0, P(NULL)},
    {"rtde_set_watchdog", b_rtde_set_watchdog, 2, P("variable_name", "min_frequency", "action")},
};
#undef P

const int urt__us_n_builtins_service =
    (int)(sizeof urt__us_builtins_service / sizeof urt__us_builtins_service[0]);
