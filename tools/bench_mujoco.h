// SPDX-License-Identifier: Apache-2.0
// tools/bench_mujoco.h — MuJoCo's mj_step on a UR5-like model built from the same loaded
// urtwin model, for urt_bench's side-by-side timing. MuJoCo is dlopen'ed (the pip wheel ships
// libmujoco.so), so nothing here needs MuJoCo's headers or stops urtwin from building without it.
#ifndef URT_TOOLS_BENCH_MUJOCO_H
#define URT_TOOLS_BENCH_MUJOCO_H

#include <string>
#include <vector>

#include "bench_timing.h"

namespace urt::tools {

// The few C API entry points we need, typed by hand. mjModel*/mjData* are opaque here; the pip
// wheel is a double (mjtNum = double) build.
struct MjApi {
  void *handle = nullptr;
  void *(*load_xml)(const char *, const void *, char *, int) = nullptr;
  void *(*make_data)(const void *) = nullptr;
  void (*step)(const void *, void *) = nullptr;
  void (*delete_data)(void *) = nullptr;
  void (*delete_model)(void *) = nullptr;
  void (*set_state)(const void *, void *, const double *, int) = nullptr;
  void (*get_state)(const void *, const void *, double *, int) = nullptr;
  int (*state_size)(const void *, int) = nullptr;
  std::string version;

  // mjtState bits (mujoco/mjtype.h), stable since MuJoCo 3.0
  static constexpr int kStateQpos = 1 << 1;
  static constexpr int kStateCtrl = 1 << 6;

  // Load the library at path. Returns false with *err set when it or a symbol is missing.
  bool open(const std::string &path, std::string *err);
  ~MjApi();
};

struct MjVariant {
  const char *name;
  const char *integrator;   // MJCF option/@integrator
  bool frictionloss;        // joint dry friction → constraint solver every step
};

// "euler" is MuJoCo's default and the primary comparison; rk4 is the 4-stage explicit scheme
// (urt_step is a 2-stage implicit one plus sub-steps); frictionloss adds the constraint solver,
// the nearest MuJoCo gets to a friction model.
extern const MjVariant kMjVariants[3];

// MJCF of m's arm (its Hayati-DH chain and link inertias) as a rigid 6-joint MuJoCo model:
// armature τ²J_M, viscous damping f_v and (variant) dry friction f_c of the loaded drives,
// position servos limited to each joint's torque_max, no contacts, timestep dt.
std::string mjcf_from_model(const urt_model_t *m, double dt, const MjVariant &v);

struct MjRun {
  const MjVariant *variant = nullptr;
  double dt = 0;
  std::string status = "ok";
  std::string error;
  Stats stats;
  double max_track_err = 0;
};

// One mj_step workload (variant, dt), stepped in chunks like urt_bench's urt_step cases.
class MjCase {
 public:
  MjRun r;

  MjCase(const MjApi &mj, const urt_model_t *m, const MjVariant &v, double dt, const Setpoint &sp,
         long steps);
  MjCase(const MjCase &) = delete;
  MjCase &operator=(const MjCase &) = delete;
  ~MjCase();

  bool ok() const { return r.status == "ok"; }

  // Advance n steps. Only mj_step is timed, as for urt_step; ctrl is written between steps.
  void run(long n, bool timed);
  void finish();

 private:
  const MjApi &mj_;
  Setpoint sp_;
  void *model_ = nullptr;
  void *data_ = nullptr;
  std::vector<int64_t> samples_;
  size_t done_ = 0;
  long steps_ = 0;
};

}  // namespace urt::tools

#endif
