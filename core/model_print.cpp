// SPDX-License-Identifier: Apache-2.0
// core/model_print.cpp — urt_model_print(): the fully resolved model, every given and derived
// parameter in SI units, as YAML (units and "derived" in comments) or JSON (the same tree, plus
// top-level "units" and "derived" tables keyed by generic paths such as "joints[].motor.kt").
//
// The layout is the model's, not the config file's: each joint carries its own gear, control,
// friction and sensor blocks with the struct field names of urt/model.h and urt/drivers/*.h.
// Numbers use the shortest text that reads back to the same double (at most %.17g), so the
// output is exact; the Pinocchio cross-check reads "arm" from the JSON.
//
// Context: non-RT.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "integrator.hpp"
#include "urt/core.h"

namespace urt::core {
namespace {  // file-local: nothing here is visible to the linker

// Shortest %g text (at least 6 significant digits, so 7400 is not written 7.4e+03) that parses
// back to exactly v. YAML 1.1 readers (PyYAML) take "5e-05" for a string, so an exponent form
// always gets a decimal point: "5.0e-05".
std::string format_number(double v, bool json) {
  if (std::isnan(v)) {
    return json ? "null" : ".nan";
  }
  if (std::isinf(v)) {
    return json ? "null" : (v > 0 ? ".inf" : "-.inf");
  }
  char buf[40];
  for (int prec = 6; prec <= 17; prec++) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) {
      break;
    }
  }
  std::string s = buf;
  size_t e = s.find('e');
  if (e != std::string::npos && s.find('.') == std::string::npos) {
    s.insert(e, ".0");
  }
  return s;
}

// A JSON string literal; also a valid YAML double-quoted scalar.
std::string quote(const char *s) {
  std::string out = "\"";
  for (const unsigned char *p = reinterpret_cast<const unsigned char *>(s); *p; p++) {
    switch (*p) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (*p < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", *p);
          out += buf;
        } else {
          out += static_cast<char>(*p);
        }
    }
  }
  return out + "\"";
}

//---- a small two-format tree writer ----

class Emitter {
 public:
  Emitter(FILE *f, bool json) : f_(f), json_(json) {}

  void begin_doc(const char *source) {
    if (json_) {
      std::fputs("{", f_);
    } else {
      std::fprintf(f_, "# urtwin resolved model of %s\n", source);
      std::fputs("# [unit] after each value; derived: computed at load, not read from the file\n",
                 f_);
    }
    stack_.push_back({false, true, ""});
  }

  void end_doc() {
    if (json_) {
      // the unit and derived tables, keyed by generic path
      begin_map("units");
      for (const auto &u : units_) {
        str(u.first.c_str(), u.second.c_str(), nullptr, false, false);
      }
      end_map();
      separator();
      std::fputs("\"derived\": [", f_);
      for (size_t i = 0; i < derived_.size(); i++) {
        std::fprintf(f_, "%s%s", i ? ", " : "", quote(derived_[i].c_str()).c_str());
      }
      std::fputs("]\n}\n", f_);
    }
    stack_.pop_back();
  }

  // key is NULL for a map that is a list element
  void begin_map(const char *key) {
    if (json_) {
      separator();
      std::fprintf(f_, "%s{", key ? (quote(key) + ": ").c_str() : "");
    } else if (key) {
      line_start(key);
      std::fputs(":\n", f_);
    } else {
      dash_pending_ = true;
    }
    push(key, false);
  }

  void end_map() { pop('}'); }

  void begin_list(const char *key) {
    if (json_) {
      separator();
      std::fprintf(f_, "%s: [", quote(key).c_str());
    } else {
      line_start(key);
      std::fputs(":\n", f_);
    }
    push(key, true);
  }

  void end_list() { pop(']'); }

  void num(const char *key, double v, const char *unit, bool derived = false) {
    scalar(key, format_number(v, json_), unit, derived);
  }

  void nums(const char *key, const double *v, int n, const char *unit, bool derived = false) {
    std::string s = "[";
    for (int i = 0; i < n; i++) {
      s += (i ? ", " : "") + format_number(v[i], json_);
    }
    scalar(key, s + "]", unit, derived);
  }

  void uint(const char *key, uint64_t v, const char *unit) {
    scalar(key, std::to_string(v), unit, false);
  }

  void boolean(const char *key, bool v, const char *unit) {
    scalar(key, v ? "true" : "false", unit, false);
  }

  void str(const char *key, const char *v, const char *unit, bool derived = false,
           bool record = true) {
    scalar(key, quote(v), unit, derived, record);
  }

 private:
  struct Level {
    bool is_list;
    bool first;
    std::string generic;  // "joints[].motor": list elements collapse to "[]"
  };

  void push(const char *key, bool is_list) {
    const std::string &up = stack_.back().generic;
    std::string g = key ? (up.empty() ? key : up + "." + key) : up + "[]";
    stack_.push_back({is_list, true, g});
  }

  void pop(char close) {
    bool empty = stack_.back().first;
    stack_.pop_back();
    if (json_) {
      if (!empty) {
        std::fputc('\n', f_);
        indent(depth() + 1);
      }
      std::fputc(close, f_);
    }
  }

  // nesting below the document: 0 for its top-level keys
  int depth() const { return static_cast<int>(stack_.size()) - 1; }

  void indent(int n) {
    for (int i = 0; i < n; i++) {
      std::fputs("  ", f_);
    }
  }

  // JSON: comma between siblings, newline and indentation before each
  void separator() {
    Level &l = stack_.back();
    std::fputs(l.first ? "\n" : ",\n", f_);
    l.first = false;
    indent(depth() + 1);
  }

  // YAML: indentation, or "- " for the first key of a list element
  void line_start(const char *key) {
    stack_.back().first = false;
    int col = 2 * depth();
    if (dash_pending_) {
      indent(depth() - 1);
      std::fputs("- ", f_);
      dash_pending_ = false;
    } else {
      indent(depth());
    }
    std::fputs(key, f_);
    col_ = col + static_cast<int>(std::strlen(key));
  }

  void scalar(const char *key, const std::string &text, const char *unit, bool derived,
              bool record = true) {
    std::string g = stack_.back().generic;
    g = g.empty() ? key : g + "." + key;
    if (record && unit && find_unit(g) < 0) {
      units_.emplace_back(g, unit);
    }
    if (record && derived && find_derived(g) < 0) {
      derived_.push_back(g);
    }

    if (json_) {
      separator();
      std::fprintf(f_, "%s: %s", quote(key).c_str(), text.c_str());
      return;
    }
    line_start(key);
    std::fprintf(f_, ": %s", text.c_str());
    col_ += 2 + static_cast<int>(text.size());
    if (unit || derived) {
      // comments line up at column 40 where the value leaves room
      std::fprintf(f_, "%*s#", col_ < 40 ? 40 - col_ : 2, "");
      if (unit) {
        std::fprintf(f_, " [%s]", unit);
      }
      if (derived) {
        std::fputs(" derived", f_);
      }
    }
    std::fputc('\n', f_);
  }

  int find_unit(const std::string &g) const {
    for (size_t i = 0; i < units_.size(); i++) {
      if (units_[i].first == g) {
        return static_cast<int>(i);
      }
    }
    return -1;
  }

  int find_derived(const std::string &g) const {
    for (size_t i = 0; i < derived_.size(); i++) {
      if (derived_[i] == g) {
        return static_cast<int>(i);
      }
    }
    return -1;
  }

  FILE *f_;
  bool json_;
  bool dash_pending_ = false;
  int col_ = 0;
  std::vector<Level> stack_;
  std::vector<std::pair<std::string, std::string>> units_;
  std::vector<std::string> derived_;
};

//---- the model, section by section ----

void print_simulation(Emitter &e, const urt_model_t *m) {
  e.begin_map("simulation");
  e.num("dt", m->dt, "s");
  e.uint("seed", m->seed, "-");
  e.boolean("drives_engaged", m->drives_engaged != 0, "-");
  e.num("substep_h_max", m->substep_h_max, "s");
  e.num("substep_ratio", m->substep_ratio, "-");
  e.uint("refine_every", m->refine_every, "steps");
  e.end_map();
}

// What urt_model_prepare decided from the parameters: which joints are sub-stepped and why.
void print_integrator(Emitter &e, const urt_model_t *m) {
  const urt_integrator_tables *t = m->tables;
  if (!t) {
    return;
  }
  double sub[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    sub[j] = t->substepped[j];
  }
  e.begin_map("integrator");
  e.num("n_sub", t->n_sub, "-", true);
  e.num("h_sub", t->h[kSub], "s", true);
  e.num("h_fine", t->h[kFine], "s", true);
  e.nums("substepped", sub, URT_NJ, "1 = sub-stepped joint", true);
  e.nums("substep_below", t->v_sub, URT_NJ, "rad/s: only while |qd| is below", true);
  e.nums("friction_slope_min", t->g_slope_min, URT_NJ, "N m s/rad", true);
  e.nums("output_inertia_min", t->j_out, URT_NJ, "kg m^2", true);
  e.end_map();
}

void print_arm(Emitter &e, const urt_arm_params_t *a) {
  e.begin_map("arm");
  e.nums("gravity", a->gravity, 3, "m/s^2");
  e.nums("tcp", a->tcp, 6, "m, m, m, rad, rad, rad");
  e.nums("tcp_fixed", a->tcp_fixed, 12, "3x4 row-major [R | p], p in m", true);
  e.begin_list("links");
  for (int i = 0; i < URT_NJ; i++) {
    const urt_link_params_t *l = &a->link[i];
    e.begin_map(nullptr);
    e.num("a", l->a, "m");
    e.num("alpha", l->alpha, "rad");
    e.num("beta", l->beta, "rad");
    e.num("d", l->d, "m");
    e.num("theta", l->theta, "rad");
    e.num("mass", l->mass, "kg");
    e.nums("com", l->com, 3, "m");
    e.nums("inertia", l->inertia, 6, "kg m^2; Ixx Iyy Izz Ixy Ixz Iyz");
    e.nums("fixed", a->fixed[i], 12, "3x4 row-major [R | p], p in m", true);
    e.num("cos_theta", a->cos_theta[i], "-", true);
    e.num("sin_theta", a->sin_theta[i], "-", true);
    e.end_map();
  }
  e.end_list();
  e.end_map();
}

void print_payload(Emitter &e, const urt_payload_t *p) {
  e.begin_map("payload");
  e.num("mass", p->mass, "kg");
  e.nums("cog", p->cog, 3, "m, flange frame");
  e.nums("inertia", p->inertia, 6, "kg m^2 about the CoG; Ixx Iyy Izz Ixy Ixz Iyz");
  e.end_map();
}

void print_joint(Emitter &e, const urt_model_t *m, int j) {
  const urt_joint_params_t *jp = &m->joint[j];
  char size[2] = {jp->size, '\0'};
  e.begin_map(nullptr);
  e.str("name", jp->name, nullptr);
  e.str("size", size, nullptr);
  e.num("q_min", jp->q_min, "rad");
  e.num("q_max", jp->q_max, "rad");
  e.num("qd_max", jp->qd_max, "rad/s");
  e.num("qdd_max", jp->qdd_max, "rad/s^2");
  e.num("torque_max", jp->torque_max, "N m");
  e.num("q0", m->q0[j], "rad");
  e.num("current_offset", jp->i_offset, "A");

  const urt_motor_params_t *mo = &m->motor[j];
  e.begin_map("motor");
  e.num("j", mo->j, "kg m^2");
  e.num("r", mo->r, "Ohm");
  e.num("l", mo->l, "H");
  e.num("kt", mo->kt, "N m/A");
  e.num("ke", mo->ke, "V s/rad", true);
  e.end_map();

  const urt_harmonic_drive_params_t *g = &m->gear[j];
  e.begin_map("gear");
  e.num("z_fs", g->z_fs, "-");
  e.num("z_cs", g->z_cs, "-");
  e.num("r_g", g->r_g, "m");
  e.num("alpha_t", g->alpha_t, "rad");
  e.num("k_wg", g->k_wg, "N m/rad");
  e.num("k_b", g->k_b, "N/m");
  e.num("k_fs", g->k_fs, "N m/rad");
  e.num("k_m", g->k_m, "N/m");
  e.num("k_cs", g->k_cs, "N m/rad");
  e.num("j_wg", g->j_wg, "kg m^2");
  e.num("j_fs", g->j_fs, "kg m^2");
  e.num("j_cs", g->j_cs, "kg m^2");
  e.num("zeta", g->zeta, "-");
  e.num("ratio", g->ratio, "-", true);
  e.num("alpha_n", g->alpha_n, "rad", true);
  e.num("m_fs", g->m_fs, "kg", true);
  e.num("c_wg", g->c_wg, "N m s/rad", true);
  e.num("c_b", g->c_b, "N s/m", true);
  e.num("c_m", g->c_m, "N s/m", true);
  e.num("c_fs", g->c_fs, "N m s/rad", true);
  e.num("c_cs", g->c_cs, "N m s/rad", true);
  e.end_map();

  const urt_pi_cascade_params_t *c = &m->control[j];
  e.begin_map("control");
  e.num("p_pos", c->p_pos, "rad_motor/s per rad_joint");
  e.num("p_vel", c->p_vel, "A s/rad");
  e.num("i_vel", c->i_vel, "A/rad");
  e.num("p_cur", c->p_cur, "V/A");
  e.num("i_cur", c->i_cur, "V/(A s)");
  e.num("i_max", c->i_max, "A", true);
  e.num("v_net", c->v_net, "V");
  e.end_map();

  const urt_friction_params_t *f = &m->friction[j];
  e.begin_map("friction");
  e.boolean("enabled", f->enabled != 0, "-");
  e.num("sigma0", f->sigma0, "N m/rad");
  e.num("sigma1", f->sigma1, "N m s/rad");
  e.num("qd_s", f->qd_s, "rad/s");
  e.num("k_static", f->k_static, "-");
  e.num("f_c", f->f_c, "N m");
  e.num("f_v", f->f_v, "N m (s/rad)^(2/3)");
  e.num("k_q", f->k_q, "-");
  e.num("asym", f->asym, "-");
  e.num("relax", f->relax, "1/s");
  e.end_map();

  const urt_sensors_params_t *s = &m->sensors[j];
  e.begin_map("sensors");
  e.num("f_i", s->f_i, "Hz");
  e.num("f_w", s->f_w, "Hz");
  e.num("zeta_w", s->zeta_w, "-");
  e.num("f_q", s->f_q, "Hz");
  e.num("zeta_q", s->zeta_q, "-");
  e.num("sigma_i", s->sigma_i, "A");
  e.num("sigma_w", s->sigma_w, "rad/s");
  e.num("sigma_q", s->sigma_q, "rad");
  e.num("lsb_i", s->lsb_i, "A", true);
  e.num("lsb_w", s->lsb_w, "rad/s", true);
  e.num("lsb_q", s->lsb_q, "rad", true);
  e.boolean("noise", s->noise != 0, "-");
  e.boolean("quantise", s->quantise != 0, "-");
  e.end_map();

  const urt_thermal_params_t *th = &m->thermal[j];
  e.begin_map("thermal");
  e.num("t_amb", th->t_amb, "degC");
  e.num("r_th", th->r_th, "K/W");
  e.num("c_th", th->c_th, "J/K");
  e.num("tau", th->r_th * th->c_th, "s", true);
  e.end_map();

  e.end_map();
}

}  // namespace
}  // namespace urt::core

//---- C API ----

extern "C" void urt_model_print(const urt_model_t *m, FILE *f, int json) {
  using urt::core::Emitter;
  if (!m || !f) {
    return;
  }
  // nothing here allocates more than a few small strings; a failure must not escape into C
  try {
    Emitter e(f, json != 0);
    e.begin_doc(m->source);
    e.str("name", m->name, nullptr);
    e.str("source", m->source, nullptr);
    urt::core::print_simulation(e, m);
    urt::core::print_integrator(e, m);
    urt::core::print_arm(e, &m->arm);
    urt::core::print_payload(e, &m->payload);
    e.begin_list("joints");
    for (int j = 0; j < URT_NJ; j++) {
      urt::core::print_joint(e, m, j);
    }
    e.end_list();
    e.end_doc();
  } catch (...) {
    std::fputs("\n# urt_model_print: out of memory\n", f);
  }
}
