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
      return "payload inertia elements must be within ±1 kg m²";
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
  return URT_OK;
}
