// SPDX-License-Identifier: Apache-2.0
// tools/bench_mujoco.cpp — MuJoCo's mj_step through dlopen, on the loaded UR5. Contract in
// bench_mujoco.h.
#include "bench_mujoco.h"

#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace urt::tools {
namespace {

template <typename F>
bool sym(void *handle, const char *name, F *f, std::string *err) {
  void *p = dlsym(handle, name);
  if (p == nullptr) {
    *err = std::string("dlsym ") + name + ": not found";
    return false;
  }
  *f = reinterpret_cast<F>(p);
  return true;
}

// mj_loadXML wants a file: write the MJCF to a private temp file and remove it right away
void *mj_load_string(const MjApi &mj, const std::string &xml, std::string *err) {
  const char *tmp = getenv("TMPDIR");
  std::string path = std::string(tmp && *tmp ? tmp : "/tmp") + "/urt_bench_XXXXXX.xml";
  std::vector<char> buf(path.begin(), path.end());
  buf.push_back('\0');
  int fd = mkstemps(buf.data(), 4);
  if (fd < 0) {
    *err = std::string("mkstemps: ") + strerror(errno);
    return nullptr;
  }
  bool wrote = write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size());
  close(fd);
  char e[1000] = "";
  void *model = wrote ? mj.load_xml(buf.data(), nullptr, e, sizeof e) : nullptr;
  unlink(buf.data());
  if (model == nullptr) {
    *err = wrote ? std::string("mj_loadXML: ") + e : "cannot write the temporary MJCF";
  }
  return model;
}

}  // namespace

bool MjApi::open(const std::string &path, std::string *err) {
  handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char *e = dlerror();
    *err = std::string("dlopen: ") + (e ? e : "failed");
    return false;
  }
  bool ok = sym(handle, "mj_loadXML", &load_xml, err) &&
            sym(handle, "mj_makeData", &make_data, err) && sym(handle, "mj_step", &step, err) &&
            sym(handle, "mj_deleteData", &delete_data, err) &&
            sym(handle, "mj_deleteModel", &delete_model, err) &&
            sym(handle, "mj_setState", &set_state, err) &&
            sym(handle, "mj_getState", &get_state, err) &&
            sym(handle, "mj_stateSize", &state_size, err);
  if (!ok) {
    return false;
  }
  // optional: only for the report
  auto version_string =
      reinterpret_cast<const char *(*)(void)>(dlsym(handle, "mj_versionString"));
  version = version_string ? version_string() : "unknown";
  return true;
}

MjApi::~MjApi() {
  if (handle != nullptr) {
    dlclose(handle);
  }
}

const MjVariant kMjVariants[3] = {
    {"euler", "Euler", false},
    {"rk4", "RK4", false},
    {"euler_frictionloss", "Euler", true},
};

// Body j+1 sits on body j at T_j = Transl(z, d)·Rot(z, θ)·Transl(x, a)·Rot(x, α)·Rot(y, β) (the
// q-independent part of eq. 8; body j turns about its own z by q_j), and link j's inertia,
// given in DH frame j, is carried into body j by the same T_j.
std::string mjcf_from_model(const urt_model_t *m, double dt, const MjVariant &v) {
  // PD servo gains per drive size: a controlled arm, stiff enough to track the set-point
  static const double kp[6] = {20000, 20000, 10000, 2000, 2000, 2000};
  static const double kv[6] = {400, 400, 200, 20, 20, 20};

  std::string x;
  char b[768];
  snprintf(b, sizeof b,
           "<mujoco model=\"ur5_like\">\n"
           "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
           "  <option timestep=\"%.12g\" integrator=\"%s\" gravity=\"%.12g %.12g %.12g\"/>\n"
           "  <worldbody>\n",
           dt, v.integrator, m->arm.gravity[0], m->arm.gravity[1], m->arm.gravity[2]);
  x += b;
  double T_R[URT_NJ][3][3], T_p[URT_NJ][3];
  for (int j = 0; j < URT_NJ; ++j) {
    const urt_arm_params_t &a = m->arm;
    const double *F = a.fixed[j];  // row-major 3×4
    double c = a.cos_theta[j], s = a.sin_theta[j];
    double Rz[3][3] = {{c, -s, 0}, {s, c, 0}, {0, 0, 1}};
    for (int r = 0; r < 3; ++r) {
      T_p[j][r] = r == 2 ? a.link[j].d : 0.0;
      for (int k = 0; k < 3; ++k) {
        T_p[j][r] += Rz[r][k] * F[4 * k + 3];
      }
      for (int col = 0; col < 3; ++col) {
        T_R[j][r][col] = 0.0;
        for (int k = 0; k < 3; ++k) {
          T_R[j][r][col] += Rz[r][k] * F[4 * k + col];
        }
      }
    }
  }
  for (int j = 0; j < URT_NJ; ++j) {
    std::string ind(4 + 2 * j, ' ');
    if (j == 0) {
      x += ind + "<body name=\"link1\">\n";
    } else {
      const double(*R)[3] = T_R[j - 1];
      snprintf(b, sizeof b,
               "%s<body name=\"link%d\" pos=\"%.12g %.12g %.12g\" "
               "xyaxes=\"%.12g %.12g %.12g %.12g %.12g %.12g\">\n",
               ind.c_str(), j + 1, T_p[j - 1][0], T_p[j - 1][1], T_p[j - 1][2], R[0][0], R[1][0],
               R[2][0], R[0][1], R[1][1], R[2][1]);
      x += b;
    }

    // link j's inertial in body j: p = T_p + T_R c, I_b = T_R I T_Rᵀ
    const urt_link_params_t &l = m->arm.link[j];
    const double *in = l.inertia;
    double I[3][3] = {{in[0], in[3], in[4]}, {in[3], in[1], in[5]}, {in[4], in[5], in[2]}};
    double p[3], Ib[3][3] = {};
    for (int r = 0; r < 3; ++r) {
      p[r] = T_p[j][r];
      for (int c = 0; c < 3; ++c) {
        p[r] += T_R[j][r][c] * l.com[c];
        for (int k = 0; k < 3; ++k) {
          for (int n = 0; n < 3; ++n) {
            Ib[r][c] += T_R[j][r][k] * I[k][n] * T_R[j][c][n];
          }
        }
      }
    }
    double armature = m->gear[j].ratio * m->gear[j].ratio * m->motor[j].j;
    snprintf(b, sizeof b,
             "%s  <joint name=\"j%d\" axis=\"0 0 1\" range=\"%.12g %.12g\" armature=\"%.12g\" "
             "damping=\"%.12g\" frictionloss=\"%.12g\"/>\n"
             "%s  <inertial pos=\"%.12g %.12g %.12g\" mass=\"%.12g\" "
             "fullinertia=\"%.12g %.12g %.12g %.12g %.12g %.12g\"/>\n"
             "%s  <geom type=\"capsule\" fromto=\"0 0 0 %.12g %.12g %.12g\" size=\"0.04\" "
             "contype=\"0\" conaffinity=\"0\"/>\n",
             ind.c_str(), j + 1, m->joint[j].q_min, m->joint[j].q_max, armature,
             m->friction[j].f_v, v.frictionloss ? m->friction[j].f_c : 0.0, ind.c_str(), p[0],
             p[1], p[2], l.mass, Ib[0][0], Ib[1][1], Ib[2][2], Ib[0][1], Ib[0][2], Ib[1][2],
             ind.c_str(), T_p[j][0], T_p[j][1], T_p[j][2]);
    x += b;
  }
  for (int j = URT_NJ - 1; j >= 0; --j) {
    x += std::string(4 + 2 * j, ' ') + "</body>\n";
  }
  x += "  </worldbody>\n  <actuator>\n";
  for (int j = 0; j < URT_NJ; ++j) {
    double t = m->joint[j].torque_max;
    snprintf(b, sizeof b,
             "    <position joint=\"j%d\" kp=\"%g\" kv=\"%g\" forcelimited=\"true\" "
             "forcerange=\"%.12g %.12g\"/>\n",
             j + 1, kp[j], kv[j], -t, t);
    x += b;
  }
  x += "  </actuator>\n</mujoco>\n";
  return x;
}

MjCase::MjCase(const MjApi &mj, const urt_model_t *m, const MjVariant &v, double dt, const Setpoint &sp,
       long steps)
    : mj_(mj), sp_(sp) {
  r.variant = &v;
  r.dt = dt;
  model_ = mj_load_string(mj, mjcf_from_model(m, dt, v), &r.error);
  if (model_ == nullptr) {
    r.status = "error";
    return;
  }
  data_ = mj.make_data(model_);
  if (data_ == nullptr) {
    r.status = "error";
    r.error = "mj_makeData failed";
    return;
  }
  if (mj.state_size(model_, MjApi::kStateQpos) != URT_NJ ||
      mj.state_size(model_, MjApi::kStateCtrl) != URT_NJ) {
    r.status = "error";
    r.error = "unexpected nq/nu in the generated model";
    return;
  }

  // start at the same q0 as urt, servo set-point there
  mj.set_state(model_, data_, sp.q0, MjApi::kStateQpos);
  mj.set_state(model_, data_, sp.q0, MjApi::kStateCtrl);
  samples_.assign(static_cast<size_t>(steps), 0);
}

MjCase::~MjCase() {
  if (data_ != nullptr) {
    mj_.delete_data(data_);
  }
  if (model_ != nullptr) {
    mj_.delete_model(model_);
  }
}

void MjCase::run(long n, bool timed) {
  double q[URT_NJ], qd[URT_NJ], qdd[URT_NJ], qpos[URT_NJ];
  for (long k = 0; k < n; ++k) {
    sp_.at(static_cast<double>(steps_++) * r.dt, q, qd, qdd);
    mj_.set_state(model_, data_, q, MjApi::kStateCtrl);
    int64_t t0 = now_ns();
    mj_.step(model_, data_);
    int64_t t1 = now_ns();
    if (!timed || done_ >= samples_.size()) {
      continue;
    }
    samples_[done_++] = t1 - t0;
    mj_.get_state(model_, data_, qpos, MjApi::kStateQpos);
    for (int j = 0; j < URT_NJ; ++j) {
      r.max_track_err = std::max(r.max_track_err, std::fabs(q[j] - qpos[j]));
    }
  }
}

void MjCase::finish() {
  if (!ok()) {
    return;
  }
  if (!std::isfinite(r.max_track_err)) {
    r.status = "error";
    r.error = "state became non-finite";
  }
  samples_.resize(done_);
  r.stats = summarise(std::move(samples_));
}

}  // namespace urt::tools
