// SPDX-License-Identifier: Apache-2.0
// core/fault_load.cpp — urt_faults_load / urt_faults_parse: a fault scenario file (YAML, format
// in urt/faults.h) validated key by key with the config's machinery (config_field.hpp), so its
// errors read like the config's: "file:line: faults[2].severity: must be in [0, 0.3] (got 0.5)".
// The class, target and range rules are urt_fault_spec_invalid's (fault_eval.cpp); this file
// only adds where in the file a rule was broken. Context: non-RT.
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <new>
#include <sstream>
#include <string>

#include "config_field.hpp"
#include "urt/core.h"
#include "urt/faults.h"

namespace urt::core {
namespace {

using namespace config;

bool is_encoder(int c) {
  return c == URT_FAULT_ENCODER_BIAS || c == URT_FAULT_ENCODER_DRIFT ||
         c == URT_FAULT_ENCODER_NOISE || c == URT_FAULT_ENCODER_STUCK ||
         c == URT_FAULT_ENCODER_MISSED;
}

[[noreturn]] void fail_at(const Field& item, const char* key, const std::string& reason) {
  item.origin().fail(join_key(item.path(), key), item.line(), reason);
}

int parse_class(const Field& f) {
  if (!f.node().IsScalar()) {
    f.fail("must be a fault class name (got " + describe_node(f.node()) + ")");
  }
  const std::string name = f.node().Scalar();
  std::string all;
  for (int c = 0; c < urt_fault_class_count(); c++) {
    if (name == urt_fault_class_name(c)) {
      return c;
    }
    all += (c ? ", " : "") + std::string(urt_fault_class_name(c));
  }
  f.fail("unknown fault class '" + name + "' (known: " + all + ")");
}

void parse_profile(const Field& pf, urt_fault_spec_t* s) {
  Map p = pf.map({"kind", "onset"}, {"ramp", "tau", "on", "off", "sigma", "seed"});
  std::string kind = p["kind"].choice({"step", "linear", "exp", "intermittent", "random_walk"});
  s->onset = p["onset"].number(ge(0.0));
  // the keys each kind takes; any other is refused, a missing one named
  const char* need[3] = {nullptr, nullptr, nullptr};
  if (kind == "step") {
    s->profile = URT_FAULT_STEP;
  } else if (kind == "linear") {
    s->profile = URT_FAULT_LINEAR;
    need[0] = "ramp";
  } else if (kind == "exp") {
    s->profile = URT_FAULT_EXP;
    need[0] = "ramp";
    need[1] = "tau";
  } else if (kind == "intermittent") {
    s->profile = URT_FAULT_INTERMITTENT;
    need[0] = "on";
    need[1] = "off";
  } else {
    s->profile = URT_FAULT_RANDOM_WALK;
    need[0] = "sigma";
    need[1] = "seed";
  }
  for (const char* key : {"ramp", "tau", "on", "off", "sigma", "seed"}) {
    bool wanted = false;
    for (const char* n : need) {
      wanted = wanted || (n && std::strcmp(n, key) == 0);
    }
    const Field* v = p.get(key);
    if (!wanted && v) {
      v->fail("not a key of a " + kind + " profile");
    }
    if (wanted && !v) {
      fail_at(pf, key, "missing key (a " + kind + " profile needs it)");
    }
  }
  if (const Field* v = p.get("ramp")) {
    s->ramp = v->number(ge(0.0));
  }
  if (const Field* v = p.get("tau")) {
    s->tau = v->number(gt(0.0));
  }
  if (const Field* v = p.get("on")) {
    s->on = v->number(gt(0.0));
  }
  if (const Field* v = p.get("off")) {
    s->off = v->number(ge(0.0));
  }
  if (const Field* v = p.get("sigma")) {
    s->sigma = v->number(ge(0.0));
  }
  if (const Field* v = p.get("seed")) {
    s->seed = v->integer(0, UINT64_MAX);
  }
}

void parse_fault(const urt_model_t* m, const Field& item, urt_fault_spec_t* s) {
  Map f = item.map({"class", "severity", "unit", "profile"},
                   {"joint", "component", "direction", "offset", "seed", "location", "balls",
                    "ball_ratio"});
  std::memset(s, 0, sizeof *s);
  s->cls = parse_class(f["class"]);
  const char* cname = urt_fault_class_name(s->cls);
  const bool enc = is_encoder(s->cls), coll = s->cls == URT_FAULT_COLLISION;
  const bool load = s->cls == URT_FAULT_PAYLOAD;

  // the target: a joint (not for a collision, which acts at the TCP), an encoder's component
  if (coll || load) {
    if (const Field* v = f.get("joint")) {
      v->fail(std::string("a ") + cname + " acts at the flange, not on a joint");
    }
  } else if (const Field* v = f.get("joint")) {
    s->joint = (int32_t)v->integer(0, URT_NJ - 1);
  } else {
    fail_at(item, "joint", "missing key (a " + std::string(cname) + " fault needs its joint)");
  }
  if (enc) {
    if (const Field* v = f.get("component")) {
      s->component = v->choice({"joint", "motor"}) == std::string("motor") ? URT_FAULT_ENC_MOTOR
                                                                            : URT_FAULT_ENC_JOINT;
    } else {
      fail_at(item, "component", "missing key (an encoder fault names motor or joint)");
    }
  } else if (const Field* v = f.get("component")) {
    v->fail("only encoder faults have a component");
  }
  if (coll) {
    if (const Field* v = f.get("direction")) {
      double u[3];
      v->numbers(u, 3, any_finite());
      double n = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
      if (!(n > 0.0)) {
        v->fail("must not be the zero vector");
      }
      for (int i = 0; i < 3; i++) {
        s->direction[i] = u[i] / n;
      }
    } else {
      fail_at(item, "direction", "missing key (a collision's force direction, base frame)");
    }
  } else if (const Field* v = f.get("direction")) {
    v->fail("only a collision has a direction");
  }
  if (load) {
    if (const Field* v = f.get("offset")) {
      v->numbers(s->offset, 3, in(-URT_PAYLOAD_COG_MAX, URT_PAYLOAD_COG_MAX));
    } else {
      fail_at(item, "offset", "missing key (where the mass sits in the flange frame, m)");
    }
  } else if (const Field* v = f.get("offset")) {
    v->fail("only a payload fault has an offset");
  }
  if (s->cls == URT_FAULT_WG_BEARING) {
    // the bearing's geometry: where the spall is, and what sets its impact rate
    const char* keys[] = {"location", "balls", "ball_ratio"};
    for (const char* key : keys) {
      if (!f.get(key)) {
        fail_at(item, key, "missing key (a wg_bearing fault needs location, balls, ball_ratio)");
      }
    }
    const std::string loc = f["location"].choice({"outer", "inner", "ball"});
    s->location = loc == "outer"   ? URT_FAULT_BEARING_OUTER
                  : loc == "inner" ? URT_FAULT_BEARING_INNER
                                   : URT_FAULT_BEARING_BALL;
    s->balls = (int32_t)f["balls"].integer(6, 60);
    s->ball_ratio = f["ball_ratio"].number(in(0.05, 0.5));
  } else {
    for (const char* key : {"location", "balls", "ball_ratio"}) {
      if (const Field* v = f.get(key)) {
        v->fail("only a wg_bearing fault has a location, balls and ball_ratio");
      }
    }
  }
  if (const Field* v = f.get("seed")) {
    if (s->cls != URT_FAULT_ENCODER_NOISE && s->cls != URT_FAULT_ENCODER_MISSED) {
      v->fail("only encoder_noise and encoder_missed draw with a seed of their own (a "
              "random_walk profile takes one)");
    }
    s->seed = v->integer(0, UINT64_MAX);
  }

  // the unit first (a severity in the wrong unit is the likely cause of a range error)
  const char* unit = urt_fault_class_unit(s->cls, s->component);
  const Field& uf = f["unit"];
  if (!uf.node().IsScalar() || uf.node().Scalar() != unit) {
    uf.fail(std::string("must be \"") + unit + "\" for " + cname +
            (enc ? (s->component == URT_FAULT_ENC_MOTOR ? " (motor encoder)" : " (joint encoder)")
                 : "") +
            " (got " + describe_node(uf.node()) + ")");
  }
  double lo, hi;
  urt_fault_severity_range(m, s, &lo, &hi);
  s->severity = f["severity"].number(in(lo, hi));
  parse_profile(f["profile"], s);

  // whatever else the setter refuses (it should be nothing by now)
  if (const char* why = urt_fault_spec_invalid(m, s)) {
    item.fail(why);
  }
}

urt_fault_scenario_t parse_doc(const urt_model_t* m, const std::string& name,
                               const std::string& text) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw LoadError{URT_ECONFIG,
                    name + ":" + std::to_string(e.mark.line + 1) + ": syntax error: " + e.msg};
  }
  Origin origin(name);
  Field top(&origin, root, "", 1);
  Map doc = top.map({"faults"});
  std::vector<Field> items = doc["faults"].list_up_to(URT_MAX_FAULTS);
  urt_fault_scenario_t sc;
  std::memset(&sc, 0, sizeof sc);
  sc.n = (int32_t)items.size();
  for (size_t k = 0; k < items.size(); k++) {
    parse_fault(m, items[k], &sc.f[k]);
  }
  return sc;
}

void set_err(char* err, size_t err_sz, const std::string& msg) {
  if (err && err_sz > 0) {
    std::snprintf(err, err_sz, "%s", msg.c_str());
  }
}

int parse_guarded(const urt_model_t* m, const std::string& name, const std::string* text,
                  urt_fault_scenario_t* out, char* err, size_t err_sz) {
  try {
    std::string body;
    if (!text) {
      errno = 0;
      std::ifstream in(name, std::ios::binary);
      if (!in) {
        int e = errno;
        throw LoadError{URT_EIO,
                        name + ": cannot open: " + (e ? std::strerror(e) : "unknown error")};
      }
      std::ostringstream ss;
      ss << in.rdbuf();
      if (in.bad()) {
        throw LoadError{URT_EIO, name + ": cannot read"};
      }
      body = ss.str();
      text = &body;
    }
    *out = parse_doc(m, name, *text);
    return URT_OK;
  } catch (const LoadError& e) {
    set_err(err, err_sz, e.msg);
    return e.code;
  } catch (const std::bad_alloc&) {
    set_err(err, err_sz, name + ": out of memory");
    return URT_ENOMEM;
  } catch (const std::exception& e) {
    set_err(err, err_sz, name + ": " + e.what());
    return URT_ECONFIG;
  }
}

}  // namespace
}  // namespace urt::core

extern "C" int urt_faults_load(const urt_model_t* m, const char* path, urt_fault_scenario_t* out,
                               char* err, size_t err_sz) {
  return urt::core::parse_guarded(m, path ? path : "(null)", nullptr, out, err, err_sz);
}

extern "C" int urt_faults_parse(const urt_model_t* m, const char* yaml_text,
                                const char* name_for_errors, urt_fault_scenario_t* out, char* err,
                                size_t err_sz) {
  const std::string text = yaml_text ? yaml_text : "";
  return urt::core::parse_guarded(m, name_for_errors ? name_for_errors : "(text)", &text, out,
                                  err, err_sz);
}
