// SPDX-License-Identifier: Apache-2.0
// core/config_tree.cpp — reads a robot parameter file into a YAML tree (config_tree.hpp):
// includes, overlays and "dotted.key=value" overrides, each value's origin recorded. Moved
// unchanged out of model_load.cpp, which validates the tree and fills the model. Tested through
// urt_model_load: tests/core/test_model_load.c (overrides), tests/python/test_config_overlay.py
// (overlays, includes, units).
//
// Context: non-RT. C++ exceptions are used internally and all of them stop at urt_model_load.

#include "config_tree.hpp"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "model_units.hpp"
#include "urt/core.h"

namespace urt::core::config {

[[noreturn]] void fail_at(const std::string &file, int line, const std::string &key,
                          const std::string &reason) {
  throw LoadError{URT_ECONFIG, file + ":" + std::to_string(line) + ": " + key + ": " + reason};
}

namespace {  // file-local: nothing here is visible to the linker

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
  std::vector<PendingUnit> pending_units;  // config_tree.hpp
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

}  // namespace

YAML::Node read_tree(Origin *origin, const char *path, const char *const *overlays,
                     const char *const *overrides, std::vector<PendingUnit> *pending) {
  LoadContext cx{origin, false, {}};
  YAML::Node root;
  root.reset(resolve_includes(&cx, path, parse_file(path), 0));

  for (const char *const *o = overlays; o && *o; o++) {
    YAML::Node doc = parse_file(*o);
    apply_overlay_doc(&cx, root, doc, *o, 0);
  }
  for (const char *const *o = overrides; o && *o; o++) {
    apply_override(origin, root, *o);
  }
  *pending = std::move(cx.pending_units);
  return root;
}

const char *key_unit(const char *key) {
  std::vector<PathPart> parts;
  if (!key || !parse_key_path(key, &parts)) {
    return nullptr;
  }
  return config_unit(generic_path(parts));
}

}  // namespace urt::core::config
