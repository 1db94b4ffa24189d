// SPDX-License-Identifier: Apache-2.0
// core/reference.cpp — the whole 126-state model integrated by SUNDIALS CVODE (BDF, dense
// direct solver, difference-quotient Jacobian, tight tolerances), stopping at every step
// boundary where the set-point and the held sensor errors change. It judges urt_step; it is
// minutes per simulated second and never runs in the emulator.
#include "urt/reference.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

#include "step_internal.h"

struct urt_reference {
  SUNContext ctx = nullptr;
  void* cvode = nullptr;
  N_Vector y = nullptr, atol = nullptr;
  SUNMatrix jac = nullptr;
  SUNLinearSolver ls = nullptr;
  const urt_model_t* m = nullptr;
  const urt_data_t* d = nullptr;  // command and held errors of the step being integrated
  double t_step = 0.0;           // CVODE time at which that step began
};

namespace {

constexpr int kN = URT_NJ * URT_NXJ;

int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
  auto* r = static_cast<urt_reference*>(user);
  urt_rhs(r->m, r->d, t - r->t_step, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  return 0;
}

// Absolute tolerance per state, model.md §5.1 at rtol 1e-11, scaled with rtol.
double atol_for(int i, double scale) {
  switch (i) {
    case URT_X_QM:
    case URT_X_QWG:
    case URT_X_QCS:
    case URT_X_Q:
    case URT_X_P:
    case URT_X_Z:
    case URT_X_XI_V:
      return 1e-13 * scale;
    case URT_X_XFS:
    case URT_X_YFS:
      return 1e-16 * scale;
    default:
      return 1e-10 * scale;
  }
}

}  // namespace

#define CHECK(call)          \
  do {                       \
    if ((call) != 0) {       \
      urt_reference_free(r); \
      return URT_ESOLVER;    \
    }                        \
  } while (0)

extern "C" int urt_reference_create(const urt_model_t* m, const urt_data_t* d, double rtol,
                                    urt_reference_t** out) {
  auto* r = new (std::nothrow) urt_reference;
  if (!r) {
    return URT_ENOMEM;
  }
  r->m = m;
  r->d = d;
  r->t_step = d->t;
  CHECK(SUNContext_Create(nullptr, &r->ctx));
  r->y = N_VNew_Serial(kN, r->ctx);
  r->atol = N_VNew_Serial(kN, r->ctx);
  if (!r->y || !r->atol) {
    urt_reference_free(r);
    return URT_ENOMEM;
  }
  std::memcpy(N_VGetArrayPointer(r->y), d->x, sizeof d->x);
  double* at = N_VGetArrayPointer(r->atol);
  for (int k = 0; k < kN; k++) {
    at[k] = atol_for(k % URT_NXJ, rtol / 1e-11);
  }

  // BDF up to order 5 with a dense direct solver; the step never skips a set-point corner
  r->cvode = CVodeCreate(CV_BDF, r->ctx);
  if (!r->cvode) {
    urt_reference_free(r);
    return URT_ENOMEM;
  }
  CHECK(CVodeInit(r->cvode, rhs, d->t, r->y));
  CHECK(CVodeSVtolerances(r->cvode, rtol, r->atol));
  CHECK(CVodeSetUserData(r->cvode, r));
  r->jac = SUNDenseMatrix(kN, kN, r->ctx);
  r->ls = SUNLinSol_Dense(r->y, r->jac, r->ctx);
  if (!r->jac || !r->ls) {
    urt_reference_free(r);
    return URT_ENOMEM;
  }
  CHECK(CVodeSetLinearSolver(r->cvode, r->ls, r->jac));
  CHECK(CVodeSetMaxStep(r->cvode, std::fmin(1e-4, m->dt)));
  CHECK(CVodeSetMaxNumSteps(r->cvode, 1000000));
  *out = r;
  return URT_OK;
}

extern "C" int urt_reference_step(urt_reference_t* r, const urt_model_t* m, urt_data_t* d) {
  urt__command_check(m, d);

  // integrate exactly to the step boundary with this step's command and held errors
  double x0[URT_NJ][URT_NXJ];
  std::memcpy(x0, d->x, sizeof x0);
  r->d = d;
  r->t_step = d->t;
  double t_end = d->t + m->dt;
  if (CVodeSetStopTime(r->cvode, t_end) != 0) {
    return URT_ESOLVER;
  }
  sunrealtype t_ret = d->t;
  int rc = CVode(r->cvode, t_end, r->y, &t_ret, CV_NORMAL);
  if (rc < 0) {
    return URT_ESOLVER;
  }
  std::memcpy(d->x, N_VGetArrayPointer(r->y), sizeof d->x);
  urt__step_finish(m, d, x0);
  return URT_OK;
}

extern "C" long urt_reference_nsteps(const urt_reference_t* r) {
  long n = 0;
  CVodeGetNumSteps(r->cvode, &n);
  return n;
}

extern "C" void urt_reference_free(urt_reference_t* r) {
  if (!r) {
    return;
  }
  if (r->cvode) {
    CVodeFree(&r->cvode);
  }
  if (r->ls) {
    SUNLinSolFree(r->ls);
  }
  if (r->jac) {
    SUNMatDestroy(r->jac);
  }
  if (r->y) {
    N_VDestroy(r->y);
  }
  if (r->atol) {
    N_VDestroy(r->atol);
  }
  if (r->ctx) {
    SUNContext_Free(&r->ctx);
  }
  delete r;
}
