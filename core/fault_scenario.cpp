// SPDX-License-Identifier: Apache-2.0
// core/fault_scenario.cpp — a fault scenario's lifecycle in urt_data_t (urt/faults.h): set a
// whole scenario, add one fault, clear the matching ones (each fault keeps its own state and
// random generator when others come and go), and a fault as a controller command (pack/unpack)
// so that a server thread can hand it to the physics thread through a ring. What the faults do
// each step is fault_eval.cpp. Context: RT; nothing here allocates, locks or prints.
#include <cmath>
#include <cstring>

#include "urt/core.h"
#include "joint.hpp"
#include "urt/controller.h"
#include "urt/faults.h"

namespace {

// one fault's state from the start, as urt_data_set_faults gives it
void fault_state_init(urt_fault_state_t& fs, int k) {
  const urt_fault_spec_t& f = fs.s.f[k];
  fs.severity[k] = 0.0;
  fs.onset_time[k] = -1.0;
  fs.acc[k] = f.profile == URT_FAULT_RANDOM_WALK ? f.severity : 0.0;
  fs.active[k] = 0;
  fs.stuck_latched[k] = 0;
  fs.last_count[k] = 0.0;
  fs.missed[k] = 0.0;
  // one generator per fault, so adding a fault does not change another's draws
  urt_rng_seed(&fs.rng[k], f.seed ^ (0x9e3779b97f4a7c15ull * (uint64_t)(k + 1)));
}

// move fault `from` to slot `to` with all its state
void fault_move(urt_fault_state_t& fs, int to, int from) {
  fs.s.f[to] = fs.s.f[from];
  fs.severity[to] = fs.severity[from];
  fs.onset_time[to] = fs.onset_time[from];
  fs.acc[to] = fs.acc[from];
  fs.active[to] = fs.active[from];
  fs.stuck_latched[to] = fs.stuck_latched[from];
  fs.rng[to] = fs.rng[from];
  fs.last_count[to] = fs.last_count[from];
  fs.missed[to] = fs.missed[from];
}

bool whole(double v) { return std::isfinite(v) && v == std::floor(v); }

}  // namespace

extern "C" int urt_data_set_faults(const urt_model_t* m, urt_data_t* d,
                                   const urt_fault_scenario_t* s) {
  if (s && (s->n < 0 || s->n > URT_MAX_FAULTS)) {
    return URT_EINVAL;
  }
  const int n = s ? s->n : 0;
  for (int k = 0; k < n; k++) {
    if (urt_fault_spec_invalid(m, &s->f[k])) {
      return URT_EINVAL;
    }
  }
  urt_fault_state_t& fs = d->faults;
  std::memset(&fs, 0, sizeof fs);
  if (n == 0) {
    return URT_OK;
  }
  fs.s = *s;
  for (int k = 0; k < n; k++) {
    fault_state_init(fs, k);
  }
  urt_faults_advance(m, d);
  return URT_OK;
}

extern "C" int urt_data_add_fault(const urt_model_t* m, urt_data_t* d, const urt_fault_spec_t* f) {
  if (urt_fault_spec_invalid(m, f)) {
    return URT_EINVAL;
  }
  urt_fault_state_t& fs = d->faults;
  if (fs.s.n >= URT_MAX_FAULTS) {
    return URT_ENOSPC;
  }
  const int k = fs.s.n;
  fs.s.f[k] = *f;
  fault_state_init(fs, k);
  fs.s.n = k + 1;
  return URT_OK;
}

extern "C" int urt_data_clear_faults(const urt_model_t* m, urt_data_t* d, int cls, int joint,
                                     int component) {
  urt_fault_state_t& fs = d->faults;
  int kept = 0;
  for (int k = 0; k < fs.s.n; k++) {
    const urt_fault_spec_t& f = fs.s.f[k];
    const bool match = (cls < 0 || f.cls == cls) && (joint < 0 || f.joint == joint) &&
                       (component < 0 || f.component == component);
    if (!match) {
      if (kept != k) {
        fault_move(fs, kept, k);
      }
      kept++;
    }
  }
  const int removed = fs.s.n - kept;
  fs.s.n = kept;
  if (kept == 0 && removed > 0) {
    // nothing left: no joint reads fault parameters any more (urt_step stops advancing them);
    // where that lowers a joint's friction level its bristles slip to the model's
    double fc_before[URT_NJ];
    for (int j = 0; j < URT_NJ; j++) {
      fc_before[j] = urt::core::friction_now(m, d, j).f_c;
    }
    std::memset(&fs, 0, sizeof fs);
    for (int j = 0; j < URT_NJ; j++) {
      if (m->friction[j].f_c < fc_before[j]) {
        urt::core::bristles_to_level(m->friction[j], d->x[j]);
      }
    }
  }
  return removed;
}

extern "C" void urt_fault_cmd_pack(const urt_fault_spec_t* f, int inject, urt_ctrl_cmd_t* out) {
  std::memset(out, 0, sizeof *out);
  out->kind = URT_CTRL_FAULT;
  out->index = inject ? 1 : 0;
  out->q[0] = f->cls;
  out->q[1] = f->joint;
  out->q[2] = f->component;
  out->q[3] = f->profile;
  out->value = f->severity;
  out->t = f->onset;
  out->r = f->ramp;
  out->a = f->tau;
  out->v = f->on;
  out->a_rot = f->off;
  out->gain = f->sigma;
  out->tau[0] = (double)f->seed;
  for (int i = 0; i < 3; i++) {
    out->pose[i] = f->direction[i];
    out->pose[3 + i] = f->offset[i];
  }
  out->tau[1] = f->location;
  out->tau[2] = f->balls;
  out->tau[3] = f->ball_ratio;
}

extern "C" int urt_fault_cmd_unpack(const urt_ctrl_cmd_t* c, urt_fault_spec_t* f) {
  if (c->kind != URT_CTRL_FAULT || (c->index != 0 && c->index != 1)) {
    return URT_EINVAL;
  }
  for (int i = 0; i < 4; i++) {
    if (!whole(c->q[i]) || std::fabs(c->q[i]) > 1e6) {
      return URT_EINVAL;
    }
  }
  if (!whole(c->tau[0]) || c->tau[0] < 0.0 || c->tau[0] >= 9007199254740992.0 ||
      !whole(c->tau[1]) || !whole(c->tau[2]) || std::fabs(c->tau[1]) > 1e6 ||
      std::fabs(c->tau[2]) > 1e6) {
    return URT_EINVAL;
  }
  std::memset(f, 0, sizeof *f);
  f->cls = (int32_t)c->q[0];
  f->joint = (int32_t)c->q[1];
  f->component = (int32_t)c->q[2];
  if (c->index == 0) {
    return 0;
  }
  f->profile = (int32_t)c->q[3];
  f->severity = c->value;
  f->onset = c->t;
  f->ramp = c->r;
  f->tau = c->a;
  f->on = c->v;
  f->off = c->a_rot;
  f->sigma = c->gain;
  f->seed = (uint64_t)c->tau[0];
  for (int i = 0; i < 3; i++) {
    f->direction[i] = c->pose[i];
    f->offset[i] = c->pose[3 + i];
  }
  f->location = (int32_t)c->tau[1];
  f->balls = (int32_t)c->tau[2];
  f->ball_ratio = c->tau[3];
  return 1;
}

