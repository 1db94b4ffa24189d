// SPDX-License-Identifier: Apache-2.0
// core/payload.cpp — what a physical payload is (urt_payload_invalid: the loader, the controller
// and URScript refuse the same payloads with the same reason) and how a run mounts one
// (urt_data_set_payload: a value written into urt_data_t.live between two controller ticks).
#include <cmath>

#include "urt/core.h"

namespace {

bool finite_all(const double* x, int n) {
  for (int i = 0; i < n; i++) {
    if (!std::isfinite(x[i])) {
      return false;
    }
  }
  return true;
}

}  // namespace

extern "C" const char* urt_payload_invalid(const urt_payload_t* p) {
  if (!std::isfinite(p->mass) || !finite_all(p->cog, 3) || !finite_all(p->inertia, 6)) {
    return "payload values must be finite";
  }
  if (!(p->mass >= 0.0 && p->mass <= URT_PAYLOAD_MASS_MAX)) {
    return "payload mass must be within [0, 5] kg (the UR5's rated payload)";
  }
  for (int i = 0; i < 3; i++) {
    if (std::fabs(p->cog[i]) > URT_PAYLOAD_COG_MAX) {
      return "payload centre of gravity must be within 1 m of the flange on each axis";
    }
  }
  for (int i = 0; i < 6; i++) {
    if (std::fabs(p->inertia[i]) > URT_PAYLOAD_INERTIA_MAX) {
      return "payload inertia elements must be within ±133 kg m² (URScript's bound)";
    }
  }

  // an inertia tensor is positive semi-definite: every principal minor ≥ 0 (a relative slack
  // of 1e-12 lets rounded values of a point mass or a thin rod through)
  const double* J = p->inertia;
  const double xx = J[0], yy = J[1], zz = J[2], xy = J[3], xz = J[4], yz = J[5];
  const double scale = std::fmax(std::fabs(xx) + std::fabs(yy) + std::fabs(zz), 1e-300);
  const double tol1 = 1e-12 * scale, tol2 = tol1 * scale, tol3 = tol2 * scale;
  const double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  if (xx < -tol1 || yy < -tol1 || zz < -tol1 || xx * yy - xy * xy < -tol2 ||
      xx * zz - xz * xz < -tol2 || yy * zz - yz * yz < -tol2 || det < -tol3) {
    return "payload inertia must be positive semi-definite (a real body's)";
  }
  return nullptr;
}

extern "C" int urt_data_set_payload(const urt_model_t* m, urt_data_t* d, const urt_payload_t* p) {
  (void)m;  // the bounds are the UR5's; a model with its own would read them here
  if (urt_payload_invalid(p)) {
    return URT_EINVAL;
  }
  d->live.payload = *p;
  d->live.payload_time_left = 0.0;  // a change at once ends a transition in progress
  return URT_OK;
}

extern "C" int urt_data_set_payload_target(const urt_model_t* m, urt_data_t* d,
                                           const urt_payload_t* p, double transition_time) {
  if (!(transition_time >= 0.0 && transition_time <= 1000.0)) {
    return URT_EINVAL;
  }
  if (transition_time == 0.0) {
    return urt_data_set_payload(m, d, p);
  }
  if (urt_payload_invalid(p)) {
    return URT_EINVAL;
  }
  d->live.payload_target = *p;
  d->live.payload_time_left = transition_time;
  return URT_OK;
}

extern "C" void urt_data_live_advance(const urt_model_t* m, urt_data_t* d, double h) {
  (void)m;
  urt_live_params_t& l = d->live;
  if (l.payload_time_left <= 0.0) {
    return;
  }
  // the straight line from here to the target, the fraction h of the time left; every point on
  // it is a valid payload (bounds are boxes, PSD matrices a convex cone)
  if (h >= l.payload_time_left) {
    l.payload = l.payload_target;
    l.payload_time_left = 0.0;
    return;
  }
  const double f = h / l.payload_time_left;
  urt_payload_t& p = l.payload;
  const urt_payload_t& t = l.payload_target;
  p.mass += f * (t.mass - p.mass);
  for (int i = 0; i < 3; i++) {
    p.cog[i] += f * (t.cog[i] - p.cog[i]);
  }
  for (int i = 0; i < 6; i++) {
    p.inertia[i] += f * (t.inertia[i] - p.inertia[i]);
  }
  l.payload_time_left -= h;
}
