// SPDX-License-Identifier: Apache-2.0
// core/model_load.cpp — urt_model_load(): read a robot parameter file (config/ur5.yaml) with
// its includes, overlays and command-line overrides (config_tree.cpp), validate every key
// (unknown, missing, type, range, list length, cross-field rules), fill urt_model_t in SI units
// and hand it to urt_model_prepare() for the derived values.
//
// Errors read "file:line: key.path: reason". The line is the 1-based line of the offending
// key (of the list element for list items, of the parent map for a missing key); a value that
// came from an override reports "override" instead of a line. Key paths are written with
// 0-based list indices in brackets: joints[1].motor.kt (joints[0] is the base, paper joint 1).
//
// Context: non-RT. C++ exceptions are used internally and all of them stop at urt_model_load.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "config_field.hpp"
#include "config_tree.hpp"
#include "urt/core.h"

namespace urt::core {
namespace {  // file-local: nothing here is visible to the linker

using namespace config;  // Field, Map, Range, Origin, LoadError (config_field.hpp)

//---- the model: one function per section of the file ----

void load_simulation(const Field &f, urt_model_t *m) {
  Map s = f.map({"dt", "seed", "drives_engaged", "substep_h_max", "substep_ratio"},
                {"refine_every"});
  m->dt = s["dt"].number(in_lo_open(0.0, 1e-3));
  m->seed = s["seed"].integer(0, std::numeric_limits<uint64_t>::max());
  m->drives_engaged = s["drives_engaged"].boolean() ? 1 : 0;
  m->substep_h_max = s["substep_h_max"].number(in_lo_open(0.0, 1e-3));
  m->substep_ratio = s["substep_ratio"].number(gt(0.0));
  const Field *refine = s.get("refine_every");
  m->refine_every = refine ? (uint32_t)refine->integer(0, UINT32_MAX) : 0u;
}

// Inertia about the CoM: a physical rigid body has a positive-definite tensor whose diagonal
// obeys the triangle inequality. The size bound (mass · 1 m²) catches Table 5's link-1 typo.
void check_inertia(const Field &f, const double I[6], double mass) {
  double xx = I[0], yy = I[1], zz = I[2], xy = I[3], xz = I[4], yz = I[5];
  double m2 = xx * yy - xy * xy;
  double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  if (!(xx > 0.0 && m2 > 0.0 && det > 0.0)) {
    f.fail("must be positive definite");
  }
  if (xx + yy < zz || yy + zz < xx || zz + xx < yy) {
    f.fail("diagonal must satisfy the triangle inequality (Ixx + Iyy >= Izz, ...)");
  }
  if (xx > mass || yy > mass || zz > mass) {
    f.fail("moments must be <= mass * 1 m^2 (" + fmt_g(mass) +
           " kg m^2): a value not in kg m^2, or a missing 1e-4?");
  }
}

void load_arm(const Field &f, urt_arm_params_t *arm) {
  Map a = f.map({"gravity", "tcp", "links"});
  a["gravity"].numbers(arm->gravity, 3, in(-100.0, 100.0));
  std::vector<Field> tcp = a["tcp"].list(6);
  for (size_t i = 0; i < 6; i++) {
    arm->tcp[i] = tcp[i].number(i < 3 ? in(-2.0, 2.0) : angle());
  }
  // the rotation vector's angle is its norm, in [0, pi]
  if (std::hypot(arm->tcp[3], arm->tcp[4], arm->tcp[5]) > kPi) {
    a["tcp"].fail("rotation vector (elements 3..5) must have norm <= pi");
  }

  std::vector<Field> links = a["links"].list(URT_NJ);
  for (size_t i = 0; i < URT_NJ; i++) {
    Map l = links[i].map({"a", "alpha", "beta", "d", "theta", "mass", "com", "inertia"});
    urt_link_params_t *p = &arm->link[i];
    p->a = l["a"].number(in(-2.0, 2.0));
    p->alpha = l["alpha"].number(angle());
    p->beta = l["beta"].number(angle());
    p->d = l["d"].number(in(-2.0, 2.0));
    p->theta = l["theta"].number(angle());
    p->mass = l["mass"].number(in_lo_open(0.0, 1000.0));
    l["com"].numbers(p->com, 3, in(-2.0, 2.0));
    l["inertia"].numbers(p->inertia, 6, any_finite());
    check_inertia(l["inertia"], p->inertia, p->mass);
  }
}

// The payload mounted at start: what urt_payload_invalid() accepts, each bound at its own key
// first (so the error names the key), then the tensor as a whole.
void load_payload(const Field &f, urt_payload_t *p) {
  Map s = f.map({"mass", "cog", "inertia"});
  p->mass = s["mass"].number(in(0.0, URT_PAYLOAD_MASS_MAX));
  s["cog"].numbers(p->cog, 3, in(-URT_PAYLOAD_COG_MAX, URT_PAYLOAD_COG_MAX));
  s["inertia"].numbers(p->inertia, 6, in(-URT_PAYLOAD_INERTIA_MAX, URT_PAYLOAD_INERTIA_MAX));
  if (const char *why = urt_payload_invalid(p)) {
    s["inertia"].fail(why);
  }
}

void load_gear(const Field &f, urt_harmonic_drive_params_t *g) {
  Map s = f.map({"z_fs", "z_cs", "r_g", "alpha_t", "k_wg", "k_b", "k_fs", "k_m", "k_cs", "j_wg",
                 "j_fs", "j_cs", "zeta"});
  g->z_fs = static_cast<double>(s["z_fs"].integer(1, 100000));
  g->z_cs = static_cast<double>(s["z_cs"].integer(1, 100000));
  // the CS has more teeth than the FS, or the ratio Z_CS/(Z_CS − Z_FS) is not a reduction
  if (g->z_cs <= g->z_fs) {
    s["z_cs"].fail("must be > z_fs (" + fmt_g(g->z_fs) + ")");
  }
  g->r_g = s["r_g"].number(in_lo_open(0.0, 1.0));
  g->alpha_t = s["alpha_t"].number(in_open(0.0, kPi / 2, "in (0, pi/2) rad"));
  g->k_wg = s["k_wg"].number(gt(0.0));
  g->k_b = s["k_b"].number(gt(0.0));
  g->k_fs = s["k_fs"].number(gt(0.0));
  g->k_m = s["k_m"].number(gt(0.0));
  g->k_cs = s["k_cs"].number(gt(0.0));
  g->j_wg = s["j_wg"].number(gt(0.0));
  g->j_fs = s["j_fs"].number(gt(0.0));
  g->j_cs = s["j_cs"].number(gt(0.0));
  g->zeta = s["zeta"].number(in(0.0, 10.0));
}

// The bristle part is common to all joints; the levels and the Stribeck dip are per joint.
void load_friction_common(const Field &f, urt_friction_params_t *fr) {
  Map s = f.map({"enabled", "sigma0", "sigma1"});
  fr->enabled = s["enabled"].boolean() ? 1 : 0;
  fr->sigma0 = s["sigma0"].number(gt(0.0));
  fr->sigma1 = s["sigma1"].number(ge(0.0));
}

// The sensor section as written; per-joint quanta follow from i_max and dt.
struct SensorConfig {
  urt_sensors_params_t common;  // everything but lsb_i
  double adc_range;             // full scale ±adc_range·i_max   [-]
  uint64_t adc_bits;            // ADC resolution                [bit]
};

void load_sensors(const Field &f, double dt, SensorConfig *sc) {
  Map s = f.map({"noise", "quantise", "current", "motor_encoder", "joint_encoder"});
  urt_sensors_params_t *p = &sc->common;
  p->noise = s["noise"].boolean() ? 1 : 0;
  p->quantise = s["quantise"].boolean() ? 1 : 0;

  Map c = s["current"].map({"f", "sigma", "adc_bits", "adc_range"});
  p->f_i = c["f"].number(gt(0.0));
  p->sigma_i = c["sigma"].number(ge(0.0));
  sc->adc_bits = c["adc_bits"].integer(1, 32);
  sc->adc_range = c["adc_range"].number(in(1.0, 100.0));

  // one encoder count per step is the smallest speed a position difference can show
  Map w = s["motor_encoder"].map({"f", "zeta", "sigma", "counts_per_rev"});
  p->f_w = w["f"].number(gt(0.0));
  p->zeta_w = w["zeta"].number(in_lo_open(0.0, 10.0));
  p->sigma_w = w["sigma"].number(ge(0.0));
  p->lsb_w = 2.0 * kPi / static_cast<double>(w["counts_per_rev"].integer(2, 1ULL << 40)) / dt;

  Map q = s["joint_encoder"].map({"f", "zeta", "sigma", "counts_per_rev"});
  p->f_q = q["f"].number(gt(0.0));
  p->zeta_q = q["zeta"].number(in_lo_open(0.0, 10.0));
  p->sigma_q = q["sigma"].number(ge(0.0));
  p->lsb_q = 2.0 * kPi / static_cast<double>(q["counts_per_rev"].integer(2, 1ULL << 40));
}

void load_joints(const Field &f, const urt_harmonic_drive_params_t gear[2],
                 const urt_friction_params_t &fric, const SensorConfig &sc, double v_net,
                 urt_model_t *m) {
  std::vector<Field> joints = f.list(URT_NJ);
  for (size_t j = 0; j < URT_NJ; j++) {
    Map s = joints[j].map({"name", "size", "q_min", "q_max", "qd_max", "qdd_max", "torque_max",
                           "q0", "current_offset", "control", "motor", "friction"});
    urt_joint_params_t *jp = &m->joint[j];

    // identity and drive size
    std::string name = s["name"].name(sizeof jp->name - 1);
    std::snprintf(jp->name, sizeof jp->name, "%s", name.c_str());
    std::string size = s["size"].choice({"A", "B"});
    jp->size = size[0];
    m->gear[j] = gear[size == "A" ? 0 : 1];

    // limits and the initial pose inside them
    Range q_range{-4 * kPi, 4 * kPi, false, false, "in [-4 pi, 4 pi] rad"};
    jp->q_min = s["q_min"].number(q_range);
    jp->q_max = s["q_max"].number(q_range);
    if (jp->q_max <= jp->q_min) {
      s["q_max"].fail("must be > q_min (" + fmt_g(jp->q_min) + ")");
    }
    jp->qd_max = s["qd_max"].number(in_lo_open(0.0, 100.0));
    jp->qdd_max = s["qdd_max"].number(in_lo_open(0.0, 10000.0));
    jp->torque_max = s["torque_max"].number(gt(0.0));
    m->q0[j] = s["q0"].number(any_finite());
    if (m->q0[j] < jp->q_min || m->q0[j] > jp->q_max) {
      s["q0"].fail("must be in [q_min, q_max] = [" + fmt_g(jp->q_min) + ", " +
                   fmt_g(jp->q_max) + "]");
    }

    // controller gains (all > 0: urt_data_init divides by the integral gains)
    Map c = s["control"].map({"p_pos", "p_vel", "i_vel", "p_cur", "i_cur"});
    urt_pi_cascade_params_t *cp = &m->control[j];
    cp->p_pos = c["p_pos"].number(gt(0.0));
    cp->p_vel = c["p_vel"].number(gt(0.0));
    cp->i_vel = c["i_vel"].number(gt(0.0));
    cp->p_cur = c["p_cur"].number(gt(0.0));
    cp->i_cur = c["i_cur"].number(gt(0.0));

    Map mo = s["motor"].map({"j", "r", "l", "kt"});
    urt_motor_params_t *mp = &m->motor[j];
    mp->j = mo["j"].number(gt(0.0));
    mp->r = mo["r"].number(gt(0.0));
    mp->l = mo["l"].number(gt(0.0));
    mp->kt = mo["kt"].number(gt(0.0));
    mp->ke = mp->kt;  // k_e = k_t [paper §2.2]

    // the simple derived limits: supply voltage and i_max = T_max/(k_t τ) [model.md §1.2]
    double ratio = m->gear[j].z_cs / (m->gear[j].z_cs - m->gear[j].z_fs);
    cp->v_net = v_net;
    cp->i_max = jp->torque_max / (mp->kt * ratio);

    // a current-measurement zero offset beyond a fifth of full current is a broken sensor,
    // not a calibration
    jp->i_offset = s["current_offset"].number(any_finite());
    if (std::fabs(jp->i_offset) > 0.2 * cp->i_max) {
      s["current_offset"].fail("must be in [-0.2 i_max, 0.2 i_max] = [" +
                               fmt_g(-0.2 * cp->i_max) + ", " + fmt_g(0.2 * cp->i_max) +
                               "] A (got " + fmt_g(jp->i_offset) + ")");
    }

    // friction: the common LuGre part plus this joint's levels and Stribeck dip;
    // g(0) = f_c (1 ± a)(1 + K_s) > 0 needs f_c > 0 and |a| < 1
    Map fr = s["friction"].map({"f_c", "f_v", "k_q", "k_static", "qd_s", "asym", "relax"});
    urt_friction_params_t *fp = &m->friction[j];
    *fp = fric;
    fp->f_c = fr["f_c"].number(gt(0.0));
    fp->f_v = fr["f_v"].number(ge(0.0));
    fp->k_q = fr["k_q"].number(ge(0.0));
    fp->k_static = fr["k_static"].number(in(0.0, 10.0));
    fp->qd_s = fr["qd_s"].number(in_lo_open(0.0, 100.0));
    fp->asym = fr["asym"].number(in_open(-1.0, 1.0, "in (-1, 1)"));
    fp->relax = fr["relax"].number(in(0.0, 1000.0));

    // sensors: common settings, ADC quantum from this joint's i_max
    m->sensors[j] = sc.common;
    m->sensors[j].lsb_i =
        2.0 * sc.adc_range * cp->i_max / std::ldexp(1.0, static_cast<int>(sc.adc_bits));
  }
}

// The thermal section: ambient, and r_th, c_th per drive size (A, B).
void load_thermal(const Field &f, urt_thermal_params_t th[2]) {
  Map s = f.map({"t_amb", "A", "B"});
  double t_amb = s["t_amb"].number(in(-50.0, 100.0));
  const char *sizes[2] = {"A", "B"};
  for (int k = 0; k < 2; k++) {
    Map z = s[sizes[k]].map({"r_th", "c_th"});
    th[k].t_amb = t_amb;
    th[k].r_th = z["r_th"].number(in_lo_open(0.0, 1000.0));
    th[k].c_th = z["c_th"].number(in_lo_open(0.0, 1.0e6));
  }
}

void load_model(const Origin &origin, const YAML::Node &root, urt_model_t *m) {
  int root_line = root.Mark().line >= 0 ? root.Mark().line + 1 : 1;
  Field doc(&origin, root, "", root_line);
  Map top = doc.map({"name", "simulation", "supply", "arm", "payload", "gear_sizes",
                     "friction_common", "sensors", "thermal", "joints"});

  std::string name = top["name"].name(sizeof m->name - 1);
  std::snprintf(m->name, sizeof m->name, "%s", name.c_str());
  load_simulation(top["simulation"], m);

  Map supply = top["supply"].map({"v_net"});
  double v_net = supply["v_net"].number(in_lo_open(0.0, 1000.0));

  load_arm(top["arm"], &m->arm);
  load_payload(top["payload"], &m->payload);

  Map sizes = top["gear_sizes"].map({"A", "B"});
  urt_harmonic_drive_params_t gear[2] = {};
  load_gear(sizes["A"], &gear[0]);
  load_gear(sizes["B"], &gear[1]);

  urt_friction_params_t fric = {};
  load_friction_common(top["friction_common"], &fric);

  SensorConfig sc = {};
  load_sensors(top["sensors"], m->dt, &sc);

  urt_thermal_params_t thermal[2] = {};
  load_thermal(top["thermal"], thermal);

  load_joints(top["joints"], gear, fric, sc, v_net, m);
  for (int j = 0; j < URT_NJ; j++) {
    m->thermal[j] = thermal[m->joint[j].size == 'A' ? 0 : 1];
  }
}

// Read (config_tree.cpp), validate and fill. Returns the filled (not yet prepared) model.
urt_model_t *load(const char *path, const char *const *overlays, const char *const *overrides) {
  Origin origin(path);
  std::vector<PendingUnit> pending;
  YAML::Node root = read_tree(&origin, path, overlays, overrides, &pending);

  // calloc, not new: urt_model_free (C) releases it with free()
  urt_model_t *m = static_cast<urt_model_t *>(std::calloc(1, sizeof *m));
  if (!m) {
    throw std::bad_alloc();
  }
  try {
    load_model(origin, root, m);
    if (!pending.empty()) {
      const PendingUnit &p = pending.front();
      fail_at(p.file, p.line, p.key, "a unit is given, but the loader knows none for this key");
    }
  } catch (...) {
    std::free(m);
    throw;
  }
  std::snprintf(m->source, sizeof m->source, "%s", path);
  return m;
}

void set_err(char *err, size_t err_sz, const std::string &msg) {
  if (err && err_sz > 0) {
    std::snprintf(err, err_sz, "%s", msg.c_str());
  }
}

}  // namespace
}  // namespace urt::core

//---- C API ----

extern "C" int urt_model_load(const char *path, const char *const *overrides, urt_model_t **out,
                              char *err, size_t err_sz) {
  return urt_model_load_overlays(path, nullptr, overrides, out, err, err_sz);
}

extern "C" const char *urt_config_key_unit(const char *key) {
  return urt::core::config::key_unit(key);
}

extern "C" int urt_model_load_overlays(const char *path, const char *const *overlays,
                                       const char *const *overrides, urt_model_t **out,
                                       char *err, size_t err_sz) {
  using urt::core::LoadError;
  using urt::core::set_err;

  if (!path || !out) {
    set_err(err, err_sz, "urt_model_load: path and out must not be NULL");
    return URT_EINVAL;
  }
  urt_model_t *m = nullptr;
  try {
    m = urt::core::load(path, overlays, overrides);
  } catch (const LoadError &e) {
    set_err(err, err_sz, e.msg);
    return e.code;
  } catch (const std::bad_alloc &) {
    set_err(err, err_sz, std::string(path) + ": out of memory");
    return URT_ENOMEM;
  } catch (const std::exception &e) {
    set_err(err, err_sz, std::string(path) + ": " + e.what());
    return URT_ECONFIG;
  } catch (...) {
    set_err(err, err_sz, std::string(path) + ": unexpected error");
    return URT_ECONFIG;
  }

  // derived values and integrator tables (core/model_prepare.cpp)
  int rc = urt_model_prepare(m);
  if (rc != 0) {
    set_err(err, err_sz, std::string(path) + ": model preparation failed: " + urt_strerror(rc));
    urt_model_free(m);
    return rc;
  }
  *out = m;
  return 0;
}
