// SPDX-License-Identifier: Apache-2.0
// core/config_field.hpp — the machinery that validates a YAML file key by key: where a value
// came from (Origin), allowed ranges (Range), strict scalar parsing, and Field/Map, which fail
// with "file:line: key.path: reason" (unknown, duplicate or missing key, type, range). The
// robot parameter file (model_load.cpp) and the fault scenario file (fault_load.cpp) share it.
// Moved unchanged out of model_load.cpp. Internal to the core. Context: non-RT; failures are
// thrown as LoadError and stop at the loader's C entry point.
#ifndef URT_CORE_CONFIG_FIELD_HPP
#define URT_CORE_CONFIG_FIELD_HPP

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "urt/core.h"

namespace urt::core::config {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// A load failure: the URT_E* code and the full "file:line: key: reason" text.
struct LoadError {
  int code;
  std::string msg;
};

// %g for bounds in messages: short, and exact enough to see which bound was hit.
inline std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Key path of a map entry or a list element: "arm.links[2].mass".
inline std::string join_key(const std::string &path, const std::string &key) {
  return path.empty() ? key : path + "." + key;
}
inline std::string join_index(const std::string &path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

//---- where values came from: the file, an included file, an overlay, or an override ----

class Origin {
 public:
  explicit Origin(std::string file) : file_(std::move(file)), base_(file_) {}

  // The file given on the command line (named by --set errors).
  const std::string &file() const { return file_; }
  // The file the tree's own lines belong to: the innermost config an include chain starts at.
  void set_base_file(const std::string &f) { base_ = f; }

  // Remember a key path an override replaced or created; everything at or below it is
  // reported as "override" rather than with a file line.
  void add_override_path(const std::string &path) { sources_.push_back({path, file_, 0}); }
  // Everything at or below path came from file, at line (an overlay entry, an included file's
  // key): errors there name that file and line. The latest source of a path wins.
  void add_source(const std::string &path, const std::string &file, int line) {
    sources_.push_back({path, file, line > 0 ? line : 1});
  }

  [[noreturn]] void fail(const std::string &path, int line, const std::string &reason) const {
    std::string where = base_ + ":" + std::to_string(line > 0 ? line : 1);
    if (const Source *s = source_of(path)) {
      where = s->file + ":" + (s->line > 0 ? std::to_string(s->line) : std::string("override"));
    }
    throw LoadError{URT_ECONFIG,
                    where + ": " + (path.empty() ? "(document)" : path) + ": " + reason};
  }

  [[noreturn]] void fail_override(const std::string &key, const std::string &reason) const {
    throw LoadError{URT_ECONFIG, file_ + ":override: " + key + ": " + reason};
  }

 private:
  struct Source {
    std::string path, file;
    int line;  // 0: an override
  };

  const Source *source_of(const std::string &path) const {
    for (auto it = sources_.rbegin(); it != sources_.rend(); ++it) {
      const std::string &o = it->path;
      if (o.empty() || (path.compare(0, o.size(), o) == 0 &&
                        (path.size() == o.size() || path[o.size()] == '.' ||
                         path[o.size()] == '['))) {
        return &*it;
      }
    }
    return nullptr;
  }

  std::string file_, base_;
  std::vector<Source> sources_;
};

//---- allowed ranges of numbers ----

struct Range {
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;
  const char *text = nullptr;  // replaces the generated wording, e.g. "in [-pi, pi] rad"

  bool contains(double v) const {
    bool lo_ok = lo_open ? v > lo : v >= lo;
    bool hi_ok = hi_open ? v < hi : v <= hi;
    return lo_ok && hi_ok;
  }

  std::string describe() const {
    if (text) {
      return text;
    }
    bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    if (has_lo && has_hi) {
      return std::string("in ") + (lo_open ? "(" : "[") + fmt_g(lo) + ", " + fmt_g(hi) +
             (hi_open ? ")" : "]");
    }
    if (has_lo) {
      return (lo_open ? "> " : ">= ") + fmt_g(lo);
    }
    if (has_hi) {
      return (hi_open ? "< " : "<= ") + fmt_g(hi);
    }
    return "finite";
  }
};

inline Range any_finite() { return Range{}; }
inline Range gt(double lo) { return Range{lo, kInf, true, false, nullptr}; }
inline Range ge(double lo) { return Range{lo, kInf, false, false, nullptr}; }
inline Range in(double lo, double hi) { return Range{lo, hi, false, false, nullptr}; }
inline Range in_lo_open(double lo, double hi) { return Range{lo, hi, true, false, nullptr}; }
inline Range in_open(double lo, double hi, const char *text) { return Range{lo, hi, true, true, text}; }
// angles are checked against ±π, which also catches a value left in degrees
inline Range angle() { return Range{-kPi, kPi, false, false, "in [-pi, pi] rad"}; }

//---- scalar parsing (strict: YAML core-schema numbers and booleans only) ----

// A plain (unquoted) decimal number, or one of YAML's .inf/.nan spellings.
inline bool parse_double(const std::string &s, double *out) {
  static const char *const pos_inf[] = {".inf", ".Inf", ".INF", "+.inf", "+.Inf", "+.INF"};
  static const char *const neg_inf[] = {"-.inf", "-.Inf", "-.INF"};
  static const char *const nan[] = {".nan", ".NaN", ".NAN"};
  for (const char *t : pos_inf) {
    if (s == t) {
      *out = kInf;
      return true;
    }
  }
  for (const char *t : neg_inf) {
    if (s == t) {
      *out = -kInf;
      return true;
    }
  }
  for (const char *t : nan) {
    if (s == t) {
      *out = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
  }

  // only digits, sign, point and exponent: from_chars would also take "inf", "nan" and hex
  if (s.empty() || s.find_first_not_of("0123456789+-.eE") != std::string::npos) {
    return false;
  }
  const char *b = s.data(), *e = s.data() + s.size();
  if (*b == '+') {
    b++;
  }
  auto [p, ec] = std::from_chars(b, e, *out, std::chars_format::general);
  if (ec == std::errc::result_out_of_range) {
    *out = (*b == '-') ? -kInf : kInf;
    return p == e;
  }
  return ec == std::errc() && p == e;
}

// How a node looks, for "(got ...)" in messages.
inline std::string describe_node(const YAML::Node &n) {
  switch (n.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return n.Tag() == "!" ? "\"" + n.Scalar() + "\"" : "'" + n.Scalar() + "'";
    default:
      return "nothing";
  }
}

//---- a value in the tree with its key path and line ----

class Map;

class Field {
 public:
  Field(const Origin *origin, YAML::Node node, std::string path, int line)
      : origin_(origin), node_(std::move(node)), path_(std::move(path)), line_(line) {}

  const std::string &path() const { return path_; }
  int line() const { return line_; }
  const Origin &origin() const { return *origin_; }
  const YAML::Node &node() const { return node_; }

  [[noreturn]] void fail(const std::string &reason) const { origin_->fail(path_, line_, reason); }

  double number(const Range &r) const {
    const std::string &s = scalar_for("must be a number");
    double v = 0.0;
    if (!parse_double(s, &v)) {
      fail("must be a number (got " + describe_node(node_) + ")");
    }
    if (!std::isfinite(v)) {
      fail("must be finite (got " + s + ")");
    }
    if (!r.contains(v)) {
      fail("must be " + r.describe() + " (got " + s + ")");
    }
    return v;
  }

  uint64_t integer(uint64_t lo, uint64_t hi) const {
    std::string what = "must be an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]";
    const std::string &s = scalar_for(what);
    const char *b = s.data(), *e = s.data() + s.size();
    if (b != e && *b == '+') {
      b++;
    }
    uint64_t v = 0;
    auto [p, ec] = std::from_chars(b, e, v, 10);
    if (b == e || ec != std::errc() || p != e || v < lo || v > hi) {
      fail(what + " (got " + describe_node(node_) + ")");
    }
    return v;
  }

  bool boolean() const {
    const std::string &s = scalar_for("must be true or false");
    if (s == "true" || s == "True" || s == "TRUE") {
      return true;
    }
    if (s == "false" || s == "False" || s == "FALSE") {
      return false;
    }
    fail("must be true or false (got " + describe_node(node_) + ")");
  }

  // An identifier: 1..max_len characters of [A-Za-z0-9_.+-] (safe to print in YAML and JSON).
  std::string name(size_t max_len) const {
    if (!node_.IsScalar()) {
      fail("must be a name (got " + describe_node(node_) + ")");
    }
    const std::string &s = node_.Scalar();
    if (s.empty() || s.size() > max_len ||
        s.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.+-") !=
            std::string::npos) {
      fail("must be 1 to " + std::to_string(max_len) +
           " characters of A-Z a-z 0-9 _ . + - (got " + describe_node(node_) + ")");
    }
    return s;
  }

  // One of a few fixed words, e.g. the drive size A or B.
  std::string choice(std::initializer_list<const char *> words) const {
    std::vector<const char *> list(words);
    std::string what = "must be ";
    for (size_t i = 0; i < list.size(); i++) {
      what += i == 0 ? "" : (i + 1 == list.size() ? " or " : ", ");
      what += list[i];
    }
    if (node_.IsScalar()) {
      for (const char *w : words) {
        if (node_.Scalar() == w) {
          return w;
        }
      }
    }
    fail(what + " (got " + describe_node(node_) + ")");
  }

  Map map(std::initializer_list<const char *> keys) const;
  // A map with required keys and optional ones (Map::get tells which are there).
  Map map(std::initializer_list<const char *> keys,
          std::initializer_list<const char *> optional) const;

  // A list of 1 to max elements, each with its own path and line.
  std::vector<Field> list_up_to(size_t max) const {
    std::string what = "must be a list of 1 to " + std::to_string(max);
    if (!node_.IsSequence()) {
      fail(what + " (got " + describe_node(node_) + ")");
    }
    if (node_.size() < 1 || node_.size() > max) {
      fail(what + " (got " + std::to_string(node_.size()) + ")");
    }
    return list(node_.size());
  }

  // A list of exactly n elements, each with its own path and line.
  std::vector<Field> list(size_t n) const {
    std::string what = "must be a list of " + std::to_string(n);
    if (!node_.IsSequence()) {
      fail(what + " (got " + describe_node(node_) + ")");
    }
    if (node_.size() != n) {
      fail(what + " (got " + std::to_string(node_.size()) + ")");
    }
    std::vector<Field> out;
    for (size_t i = 0; i < n; i++) {
      YAML::Node e = node_[i];
      int line = e.Mark().line >= 0 ? e.Mark().line + 1 : line_;
      out.emplace_back(origin_, e, join_index(path_, i), line);
    }
    return out;
  }

  // A list of exactly n numbers, each in r.
  void numbers(double *out, size_t n, const Range &r) const {
    std::vector<Field> items = list(n);
    for (size_t i = 0; i < n; i++) {
      out[i] = items[i].number(r);
    }
  }

 private:
  // The scalar text of a number/boolean; quoted strings are strings, not numbers.
  const std::string &scalar_for(const std::string &what) const {
    if (!node_.IsScalar()) {
      fail(what + " (got " + describe_node(node_) + ")");
    }
    if (node_.Tag() == "!") {
      fail(what + ", not a quoted string (got " + describe_node(node_) + ")");
    }
    return node_.Scalar();
  }

  const Origin *origin_;
  YAML::Node node_;
  std::string path_;
  int line_;
};

// A map whose keys were checked: no unknown key, no duplicate, none of the listed keys missing.
class Map {
 public:
  Map(const Field &self, const YAML::Node &node, std::initializer_list<const char *> keys,
      std::initializer_list<const char *> optional = {}) {
    if (!node.IsMap()) {
      self.fail("must be a map (got " + describe_node(node) + ")");
    }

    // unknown and duplicate keys first: a misspelt key is the likely cause of a missing one
    for (auto it = node.begin(); it != node.end(); ++it) {
      // copies: it-> returns a proxy that dies with the full expression
      YAML::Node k = it->first;
      YAML::Node v = it->second;
      int line = k.Mark().line >= 0 ? k.Mark().line + 1 : self.line();
      if (!k.IsScalar()) {
        self.origin().fail(self.path(), line,
                           "keys must be strings (got " + describe_node(k) + ")");
      }
      std::string key = k.Scalar();
      std::string path = join_key(self.path(), key);
      bool known = false;
      for (const char *allowed : keys) {
        known = known || key == allowed;
      }
      for (const char *allowed : optional) {
        known = known || key == allowed;
      }
      if (!known) {
        self.origin().fail(path, line, "unknown key");
      }
      for (const auto &e : entries_) {
        if (e.first == key) {
          self.origin().fail(path, line,
                             "duplicate key (first at line " + std::to_string(e.second.line()) +
                                 ")");
        }
      }
      // the key's line, not the value's: a null or block value has its mark elsewhere
      entries_.emplace_back(key, Field(&self.origin(), v, path, line));
    }

    // then missing keys, reported at the parent map's line
    for (const char *allowed : keys) {
      if (!find(allowed)) {
        self.origin().fail(join_key(self.path(), allowed), self.line(), "missing key");
      }
    }
  }

  // only keys passed to the constructor: they are all present
  const Field &operator[](const char *key) const { return *find(key); }
  // a key passed as optional, or nullptr when the file does not have it
  const Field *get(const char *key) const { return find(key); }

 private:
  const Field *find(const char *key) const {
    for (const auto &e : entries_) {
      if (e.first == key) {
        return &e.second;
      }
    }
    return nullptr;
  }

  std::vector<std::pair<std::string, Field>> entries_;
};

inline Map Field::map(std::initializer_list<const char *> keys) const { return Map(*this, node_, keys); }
inline Map Field::map(std::initializer_list<const char *> keys,
                      std::initializer_list<const char *> optional) const {
  return Map(*this, node_, keys, optional);
}

}  // namespace urt::core::config

#endif
