// SPDX-License-Identifier: Apache-2.0
// core/model_load.cpp — urt_model_load(): read a robot parameter file (config/ur5.yaml),
// apply command-line overrides to the YAML tree, validate every key (unknown, missing, type,
// range, list length, cross-field rules), fill urt_model_t in SI units and hand it to
// urt_model_prepare() for the derived values.
//
// Errors read "file:line: key.path: reason". The line is the 1-based line of the offending
// key (of the list element for list items, of the parent map for a missing key); a value that
// came from an override reports "override" instead of a line. Key paths are written with
// 0-based list indices in brackets: joints[1].motor.kt (joints[0] is the base, paper joint 1).
//
// Context: non-RT. C++ exceptions are used internally and all of them stop at urt_model_load.

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <new>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "config_field.hpp"
#include "model_units.hpp"
#include "urt/core.h"

namespace urt::core {
namespace {  // file-local: nothing here is visible to the linker

using namespace config;  // Field, Map, Range, Origin, LoadError (config_field.hpp)

//---- overrides: "dotted.key=value" applied to the tree before validation ----

struct PathPart {
  bool is_index;
  std::string key;
  size_t index;
};

// "joints.1.motor.kt" or "joints[1].motor.kt" → parts; false if malformed.
bool parse_key_path(const std::string &s, std::vector<PathPart> *parts) {
  size_t i = 0;
  bool want_name = true;  // a name must start the path and follow every '.'
  while (i < s.size()) {
    if (s[i] == '[') {
      size_t close = s.find(']', i);
      if (want_name || close == std::string::npos || close == i + 1) {
        return false;
      }
      std::string digits = s.substr(i + 1, close - i - 1);
      if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 6) {
        return false;
      }
      parts->push_back({true, "", std::stoul(digits)});
      i = close + 1;
      if (i < s.size() && s[i] != '.' && s[i] != '[') {
        return false;
      }
    } else if (s[i] == '.') {
      if (want_name) {
        return false;
      }
      want_name = true;
      i++;
    } else {
      size_t end = s.find_first_of(".[", i);
      if (end == std::string::npos) {
        end = s.size();
      }
      std::string name = s.substr(i, end - i);
      if (!want_name) {
        return false;
      }
      // a purely numeric component is a list index (joints.1.motor)
      if (name.find_first_not_of("0123456789") == std::string::npos && name.size() <= 6) {
        parts->push_back({true, "", std::stoul(name)});
      } else {
        parts->push_back({false, name, 0});
      }
      want_name = false;
      i = end;
    }
  }
  return !parts->empty() && !want_name;
}

std::string canonical_path(const std::vector<PathPart> &parts) {
  std::string out;
  for (const PathPart &p : parts) {
    out = p.is_index ? join_index(out, p.index) : join_key(out, p.key);
  }
  return out;
}

std::string trim(const std::string &s) {
  size_t b = s.find_first_not_of(" \t");
  size_t e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// Set the value at a parsed key path in the tree. fail(at, reason) reports a path that does
// not exist; mark(path) records where a replaced or created value came from.
void set_path(YAML::Node root, const std::vector<PathPart> &parts, const YAML::Node &v,
              const std::function<void(const std::string &, const std::string &)> &fail,
              const std::function<void(const std::string &)> &mark) {
  // walk to the parent; reset() rebinds the handle (operator= would overwrite the node)
  YAML::Node cur;
  cur.reset(root);
  std::string path;
  for (size_t k = 0; k < parts.size(); k++) {
    const PathPart &p = parts[k];
    bool last = k + 1 == parts.size();
    if (p.is_index) {
      std::string at = join_index(path, p.index);
      if (!cur.IsSequence()) {
        fail(at, path.empty() ? "the document is not a list" : path + " is not a list");
      }
      if (p.index >= cur.size()) {
        fail(at, "index out of range (list has " + std::to_string(cur.size()) + " elements)");
      }
      path = at;
      if (last) {
        cur[p.index] = v;
      } else {
        YAML::Node next = cur[p.index];
        cur.reset(next);
      }
    } else {
      std::string at = join_key(path, p.key);
      if (!cur.IsMap()) {
        fail(at, (path.empty() ? std::string("the document") : path) + " is not a map");
      }
      path = at;
      if (last) {
        cur[p.key] = v;
      } else {
        // a missing intermediate map is created; validation then names what is wrong with it
        if (!cur[p.key]) {
          cur[p.key] = YAML::Node(YAML::NodeType::Map);
          mark(path);
        }
        YAML::Node next = cur[p.key];
        cur.reset(next);
      }
    }
  }
  mark(canonical_path(parts));
}

void apply_override(Origin *origin, YAML::Node root, const std::string &text) {
  size_t eq = text.find('=');
  if (eq == std::string::npos) {
    origin->fail_override(text, "expected key=value");
  }
  std::string key = trim(text.substr(0, eq));
  std::string value = trim(text.substr(eq + 1));
  std::vector<PathPart> parts;
  if (!parse_key_path(key, &parts)) {
    origin->fail_override(key.empty() ? text : key,
                          "malformed key (write a.b.c, list elements as a.1.b or a[1].b)");
  }
  std::string canonical = canonical_path(parts);

  // the value is YAML itself, so lists ([0, 0, -9.81]) and maps can be overridden too
  YAML::Node v;
  try {
    v = YAML::Load(value);
  } catch (const YAML::Exception &e) {
    origin->fail_override(canonical, "invalid YAML value: " + e.msg);
  }
  set_path(
      root, parts, v,
      [origin](const std::string &at, const std::string &why) { origin->fail_override(at, why); },
      [origin](const std::string &at) { origin->add_override_path(at); });
}

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

// The whole file, or URT_EIO with the system's reason.
std::string read_file(const char *path) {
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    int e = errno;
    throw LoadError{URT_EIO, std::string(path) + ": cannot open: " +
                                 (e ? std::strerror(e) : "unknown error")};
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) {
    throw LoadError{URT_EIO, std::string(path) + ": cannot read"};
  }
  return ss.str();
}

//---- overlays and includes ----
//
// An overlay (urt_model_load_overlays, `--overlay FILE`) is YAML with three top-level keys:
//   overlay: {name: ..., base: ..., note: ...}   free-form provenance, not read
//   include: PATH | [PATH, ...]                  overlays applied first, relative to this file
//   set:                                         keys exactly as --set takes them
//     joints.1.friction.f_c: {value: 7.2, unit: "N m", from: [a.csv], residual: 0.12}
//     payload.mass: 0.3                          a bare value is allowed too
// Each entry goes through the same tree walk as an override, so an unknown key or a value out
// of range is refused by validation, named "overlayfile:line: key: reason". `unit`, when given,
// must be the key's unit (model_units.cpp); `from` and `residual` are provenance, checked for
// type and otherwise ignored.
//
// A config file may start from others: `include: PATH | [PATH, ...]` (relative to it). Each
// included config is deep-merged over the ones before it (maps merge key by key; a scalar or a
// list replaces), an included overlay is applied where it stands, and the file's own keys go
// on top. Values keep the file and line they came from for error messages.

constexpr int kMaxIncludeDepth = 16;

int line_of(const YAML::Node &n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 1; }

[[noreturn]] void fail_at(const std::string &file, int line, const std::string &key,
                          const std::string &reason) {
  throw LoadError{URT_ECONFIG, file + ":" + std::to_string(line) + ": " + key + ": " + reason};
}

// A path in an include: relative to the including file's directory unless absolute.
std::string resolve_relative(const std::string &from_file, const std::string &p) {
  if (!p.empty() && p[0] == '/') {
    return p;
  }
  size_t slash = from_file.rfind('/');
  return slash == std::string::npos ? p : from_file.substr(0, slash + 1) + p;
}

YAML::Node parse_file(const std::string &path) {
  std::string text = read_file(path.c_str());
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException &e) {
    throw LoadError{URT_ECONFIG,
                    path + ":" + std::to_string(e.mark.line + 1) + ": syntax error: " + e.msg};
  }
}

bool is_overlay(const YAML::Node &doc) { return doc.IsMap() && (doc["set"] || doc["overlay"]); }

// "joints.1.friction.f_c" → "joints[].friction.f_c", the key of the unit table
std::string generic_path(const std::vector<PathPart> &parts) {
  std::string out;
  for (const PathPart &p : parts) {
    out = p.is_index ? out + "[]" : join_key(out, p.key);
  }
  return out;
}

// A stated unit equals the key's, or the key's before its "; " remark ("kg m^2; Ixx ...").
bool unit_matches(const std::string &given, const char *unit) {
  std::string u = unit;
  return given == u || given == u.substr(0, u.find("; "));
}

// The paths of an include: a path or a list of paths (strings).
std::vector<std::pair<std::string, int>> include_paths(const std::string &file,
                                                       const YAML::Node &inc, int key_line) {
  std::vector<std::pair<std::string, int>> out;
  auto one = [&](const YAML::Node &n) {
    if (!n.IsScalar() || n.Scalar().empty()) {
      fail_at(file, line_of(n), "include", "must be a path or a list of paths");
    }
    out.emplace_back(resolve_relative(file, n.Scalar()), line_of(n));
  };
  if (inc.IsSequence()) {
    for (size_t i = 0; i < inc.size(); i++) {
      one(inc[i]);
    }
  } else if (inc.IsScalar()) {
    one(inc);
  } else {
    fail_at(file, key_line, "include", "must be a path or a list of paths");
  }
  return out;
}

struct LoadContext {
  Origin *origin;
  bool base_set = false;
  // a unit stated for a path the table does not know: decided after validation, which names
  // an unknown key first
  struct PendingUnit {
    std::string file, key;
    int line;
  };
  std::vector<PendingUnit> pending_units;
};

void apply_overlay_doc(LoadContext *cx, YAML::Node root, const YAML::Node &doc,
                       const std::string &file, int depth);

void apply_overlay_entry(LoadContext *cx, YAML::Node root, const std::string &file,
                         const YAML::Node &k, const YAML::Node &entry) {
  int line = line_of(k);
  if (!k.IsScalar()) {
    fail_at(file, line, "set", "keys must be strings");
  }
  const std::string key = k.Scalar();
  std::vector<PathPart> parts;
  if (!parse_key_path(key, &parts)) {
    fail_at(file, line, key, "malformed key (write a.b.c, list elements as a.1.b or a[1].b)");
  }
  std::string canonical = canonical_path(parts);

  // {value: v, unit: u, from: [...], residual: r}, or the bare value
  YAML::Node value;
  value.reset(entry);
  std::string unit;
  bool has_unit = false;
  if (entry.IsMap() && entry["value"]) {
    for (auto it = entry.begin(); it != entry.end(); ++it) {
      YAML::Node ek = it->first;
      YAML::Node ev = it->second;
      std::string name = ek.IsScalar() ? ek.Scalar() : std::string();
      std::string at = canonical + "." + name;
      if (name == "value") {
        value.reset(ev);  // rebind: operator= would overwrite the entry map
      } else if (name == "unit") {
        if (!ev.IsScalar()) {
          fail_at(file, line_of(ek), at, "must be a unit, e.g. \"N m\"");
        }
        unit = ev.Scalar();
        has_unit = true;
      } else if (name == "from") {
        bool ok = ev.IsScalar() || ev.IsSequence();
        for (size_t i = 0; ev.IsSequence() && i < ev.size(); i++) {
          ok = ok && ev[i].IsScalar();
        }
        if (!ok) {
          fail_at(file, line_of(ek), at, "must be a file name or a list of file names");
        }
      } else if (name == "residual") {
        double r = 0.0;
        if (!ev.IsScalar() || !parse_double(ev.Scalar(), &r) || !std::isfinite(r) || r < 0.0) {
          fail_at(file, line_of(ek), at, "must be a finite number >= 0");
        }
      } else {
        fail_at(file, line_of(ek), at, "unknown key (an entry has value, unit, from, residual)");
      }
    }
  }

  if (has_unit) {
    const char *u = config_unit(generic_path(parts));
    if (!u) {
      cx->pending_units.push_back({file, canonical, line});
    } else if (!unit_matches(unit, u)) {
      fail_at(file, line, canonical,
              "unit \"" + unit + "\" does not match the key's unit \"" + u + "\"");
    }
  }

  Origin *origin = cx->origin;
  set_path(
      root, parts, value,
      [&](const std::string &at, const std::string &why) { fail_at(file, line, at, why); },
      [&](const std::string &at) { origin->add_source(at, file, line); });
}

void apply_overlay_doc(LoadContext *cx, YAML::Node root, const YAML::Node &doc,
                       const std::string &file, int depth) {
  if (!doc.IsMap()) {
    fail_at(file, line_of(doc), "(document)",
            "an overlay must be a map of overlay, include and set");
  }
  // includes first, then this file's own set, whatever their order in the file
  YAML::Node set;
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    YAML::Node k = it->first;
    YAML::Node v = it->second;
    std::string name = k.IsScalar() ? k.Scalar() : std::string();
    if (name == "overlay") {
      if (!v.IsMap()) {
        fail_at(file, line_of(k), name, "must be a map (free-form: name, base, tool, note)");
      }
    } else if (name == "include") {
      if (depth >= kMaxIncludeDepth) {
        fail_at(file, line_of(k), name,
                "includes nested deeper than " + std::to_string(kMaxIncludeDepth) +
                    " (a cycle?)");
      }
      for (const auto &[path, pline] : include_paths(file, v, line_of(k))) {
        YAML::Node sub = parse_file(path);
        if (!is_overlay(sub)) {
          fail_at(file, pline, name, path + " is not an overlay (no set: or overlay: key)");
        }
        apply_overlay_doc(cx, root, sub, path, depth + 1);
      }
    } else if (name == "set") {
      if (!v.IsMap()) {
        fail_at(file, line_of(k), name, "must be a map of key: value");
      }
      set.reset(v);
    } else {
      fail_at(file, line_of(k), name.empty() ? "(key)" : name,
              "unknown key (an overlay has overlay, include and set)");
    }
  }
  if (set) {
    for (auto it = set.begin(); it != set.end(); ++it) {
      apply_overlay_entry(cx, root, file, it->first, it->second);
    }
  }
}

// src over dst: maps merge key by key, anything else replaces; every replaced value remembers
// its file and line.
void deep_merge(LoadContext *cx, YAML::Node dst, const YAML::Node &src, const std::string &path,
                const std::string &file) {
  for (auto it = src.begin(); it != src.end(); ++it) {
    YAML::Node k = it->first;
    YAML::Node v = it->second;
    if (!k.IsScalar()) {
      fail_at(file, line_of(k), path.empty() ? "(document)" : path, "keys must be strings");
    }
    std::string key = k.Scalar();
    std::string at = join_key(path, key);
    if (dst[key] && dst[key].IsMap() && v.IsMap()) {
      deep_merge(cx, dst[key], v, at, file);
    } else {
      dst[key] = v;
      cx->origin->add_source(at, file, line_of(k));
    }
  }
}

// A config document with its includes resolved.
YAML::Node resolve_includes(LoadContext *cx, const std::string &file, YAML::Node doc, int depth) {
  if (!doc.IsMap() || !doc["include"]) {
    return doc;
  }
  int key_line = 1;
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == "include") {
      key_line = line_of(it->first);
    }
  }
  if (depth >= kMaxIncludeDepth) {
    fail_at(file, key_line, "include",
            "includes nested deeper than " + std::to_string(kMaxIncludeDepth) + " (a cycle?)");
  }
  YAML::Node tree;
  bool have = false;
  for (const auto &[path, pline] : include_paths(file, doc["include"], key_line)) {
    YAML::Node sub = parse_file(path);
    if (is_overlay(sub)) {
      if (!have) {
        fail_at(file, pline, "include", path + " is an overlay: include a config before it");
      }
      apply_overlay_doc(cx, tree, sub, path, depth + 1);
      continue;
    }
    YAML::Node resolved = resolve_includes(cx, path, sub, depth + 1);
    sub.reset(resolved);
    if (!sub.IsMap()) {
      fail_at(path, line_of(sub), "(document)", "must be a map");
    }
    if (!have) {
      tree.reset(sub);
      have = true;
      if (!cx->base_set) {
        cx->origin->set_base_file(path);  // the innermost config: its lines are the tree's own
        cx->base_set = true;
      }
    } else {
      deep_merge(cx, tree, sub, "", path);
    }
  }
  doc.remove("include");
  deep_merge(cx, tree, doc, "", file);
  return tree;
}

// Parse, include, overlay, override, validate and fill. Returns the filled (not yet prepared)
// model.
urt_model_t *load(const char *path, const char *const *overlays, const char *const *overrides) {
  Origin origin(path);
  LoadContext cx{&origin, false, {}};
  YAML::Node root;
  root.reset(resolve_includes(&cx, path, parse_file(path), 0));

  for (const char *const *o = overlays; o && *o; o++) {
    YAML::Node doc = parse_file(*o);
    apply_overlay_doc(&cx, root, doc, *o, 0);
  }
  for (const char *const *o = overrides; o && *o; o++) {
    apply_override(&origin, root, *o);
  }

  // calloc, not new: urt_model_free (C) releases it with free()
  urt_model_t *m = static_cast<urt_model_t *>(std::calloc(1, sizeof *m));
  if (!m) {
    throw std::bad_alloc();
  }
  try {
    load_model(origin, root, m);
    if (!cx.pending_units.empty()) {
      const auto &p = cx.pending_units.front();
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
  std::vector<urt::core::PathPart> parts;
  if (!key || !urt::core::parse_key_path(key, &parts)) {
    return nullptr;
  }
  return urt::core::config_unit(urt::core::generic_path(parts));
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
