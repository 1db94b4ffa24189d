// SPDX-License-Identifier: Apache-2.0
// core/payload.cpp — what a physical payload is (urt_payload_invalid: the loader, the controller
// and URScript refuse the same payloads with the same reason) and how a run mounts one
// (urt_data_set_payload: a value written into urt_data_t.live between two controller ticks).
#include <cmath>
#include <cstring>

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
  // UR's rule (script manual, set_target_payload): each element within ±133 kg m², Ixx, Iyy,
  // Izz not negative. Nothing more: a controller takes a tensor no real body has (URCL's
  // set_target_payload test sends one with a negative determinant); the physics then carries the
  // nearest one a body can have (urt_payload_physical)
  for (int i = 0; i < 6; i++) {
    if (std::fabs(p->inertia[i]) > URT_PAYLOAD_INERTIA_MAX) {
      return "payload inertia elements must be within ±133 kg m² (URScript's bound)";
    }
  }
  for (int i = 0; i < 3; i++) {
    if (p->inertia[i] < 0.0) {
      return "payload inertia Ixx, Iyy and Izz must not be negative";
    }
  }
  return nullptr;
}

namespace {

// the eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations (converges
// quadratically; 50 sweeps are far more than a 3×3 needs), in place: a becomes diagonal (the
// eigenvalues), v holds the eigenvectors as columns. Bounded and allocation-free (RT).
void jacobi3(double a[3][3], double v[3][3]) {
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) {
      v[i][j] = i == j ? 1.0 : 0.0;
    }
  }
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = std::fabs(a[0][1]) + std::fabs(a[0][2]) + std::fabs(a[1][2]);
    if (off == 0.0) {
      return;
    }
    for (int p = 0; p < 2; p++) {
      for (int q = p + 1; q < 3; q++) {
        if (a[p][q] == 0.0) {
          continue;
        }
        double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        double t = std::copysign(1.0, theta) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; k++) {  // a ← Jᵀ a J, the rotation in the (p, q) plane
          double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; k++) {
          double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        a[p][q] = a[q][p] = 0.0;
        for (int k = 0; k < 3; k++) {
          double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
}

}  // namespace

// The nearest positive semi-definite tensor (Frobenius norm): the same principal axes, negative
// principal moments raised to 0. A tensor that already is PSD comes back unchanged (bit for bit:
// it is not decomposed), so a real body's payload moves no physics value.
extern "C" void urt_payload_physical(const double in[6], double out[6]) {
  const double xx = in[0], yy = in[1], zz = in[2], xy = in[3], xz = in[4], yz = in[5];
  const double scale = std::fmax(std::fabs(xx) + std::fabs(yy) + std::fabs(zz), 1e-300);
  const double tol1 = 1e-12 * scale, tol2 = tol1 * scale, tol3 = tol2 * scale;
  const double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  if (xx >= -tol1 && yy >= -tol1 && zz >= -tol1 && xx * yy - xy * xy >= -tol2 &&
      xx * zz - xz * xz >= -tol2 && yy * zz - yz * yz >= -tol2 && det >= -tol3) {
    for (int i = 0; i < 6; i++) {
      out[i] = in[i];
    }
    return;
  }
  double a[3][3] = {{xx, xy, xz}, {xy, yy, yz}, {xz, yz, zz}}, v[3][3];
  jacobi3(a, v);
  double lam[3];
  for (int k = 0; k < 3; k++) {
    lam[k] = std::fmax(a[k][k], 0.0);
  }
  double r[3][3];
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) {
      r[i][j] = v[i][0] * lam[0] * v[j][0] + v[i][1] * lam[1] * v[j][1] + v[i][2] * lam[2] * v[j][2];
    }
  }
  out[0] = r[0][0];
  out[1] = r[1][1];
  out[2] = r[2][2];
  out[3] = 0.5 * (r[0][1] + r[1][0]);
  out[4] = 0.5 * (r[0][2] + r[2][0]);
  out[5] = 0.5 * (r[1][2] + r[2][1]);
}

extern "C" int urt_data_set_payload(const urt_model_t* m, urt_data_t* d, const urt_payload_t* p) {
  (void)m;  // the bounds are the UR5's; a model with its own would read them here
  if (urt_payload_invalid(p)) {
    return URT_EINVAL;
  }
  // the controller keeps the tensor as declared (get_target_payload_inertia); the physics
  // carries the nearest one a body can have
  std::memcpy(d->live.payload_inertia_declared, p->inertia, sizeof d->live.payload_inertia_declared);
  d->live.payload = *p;
  urt_payload_physical(p->inertia, d->live.payload.inertia);
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
  std::memcpy(d->live.payload_inertia_declared, p->inertia, sizeof d->live.payload_inertia_declared);
  d->live.payload_target = *p;
  urt_payload_physical(p->inertia, d->live.payload_target.inertia);
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
  // it is a valid payload (bounds are boxes, PSD matrices a convex cone: both ends are PSD)
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
