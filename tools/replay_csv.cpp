// SPDX-License-Identifier: Apache-2.0
// tools/replay_csv.cpp — reads an RTDE record.py recording (tools/replay_csv.h). The known
// names are RTDE's outputs (net/rtde/rtde_outputs.def, vector types expanded to _0 … _n) and
// the output register families, so a misspelt column is an error rather than ignored data.
#include "replay_csv.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace {

// how many columns an RTDE output type takes in record.py's layout
constexpr int kDOUBLE = 1, kUINT64 = 1, kUINT32 = 1, kINT32 = 1, kUINT8 = 1, kBOOL = 1;
constexpr int kVECTOR3D = 3, kVECTOR6D = 6, kVECTOR6INT32 = 6, kVECTOR6UINT32 = 6;

struct OutputField {
  const char *name;
  int width;
};

#define URT_RTDE_VER(a, b, c) 0
#define URT_RTDE_NEVER 0
#define X(name, type, ...) {#name, k##type},
const OutputField kOutputs[] = {
#include "rtde_outputs.def"
};
#undef X
#undef URT_RTDE_VER
#undef URT_RTDE_NEVER

bool all_digits(const std::string &s) {
  return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
}

// An RTDE output name as record.py writes it: a scalar field, a vector element, a register.
bool known_column(const std::string &c) {
  for (const OutputField &f : kOutputs) {
    size_t n = std::strlen(f.name);
    if (f.width == 1 && c == f.name) {
      return true;
    }
    if (f.width > 1 && c.size() > n + 1 && c.compare(0, n, f.name) == 0 && c[n] == '_') {
      std::string idx = c.substr(n + 1);
      if (all_digits(idx) && idx.size() == 1 && idx[0] - '0' < f.width) {
        return true;
      }
    }
  }
  for (const char *fam : {"output_int_register_", "output_double_register_",
                          "output_bit_register_", "input_int_register_",
                          "input_double_register_", "input_bit_register_"}) {
    size_t n = std::strlen(fam);
    if (c.compare(0, n, fam) == 0 && all_digits(c.substr(n))) {
      return true;
    }
  }
  return c == "output_bit_registers0_to_31" || c == "output_bit_registers32_to_63";
}

std::vector<std::string> split(const std::string &line) {
  std::vector<std::string> out;
  std::istringstream ss(line);
  std::string w;
  while (ss >> w) {
    out.push_back(w);
  }
  return out;
}

bool parse_cell(const std::string &s, double *v) {
  char *end = nullptr;
  errno = 0;
  *v = std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0' && errno != ERANGE && std::isfinite(*v);
}

std::string where(const std::string &path, int line) {
  return path + ":" + std::to_string(line) + ": ";
}

}  // namespace

int replay_csv_read(const std::string &path, ReplayRecording *r, std::string *err) {
  *r = ReplayRecording{};
  r->path = path;
  std::ifstream in(path);
  if (!in) {
    *err = path + ": cannot open: " + std::strerror(errno ? errno : ENOENT);
    return 2;
  }

  std::string text;
  int lineno = 0;
  // the header: the first line
  if (!std::getline(in, text)) {
    *err = where(path, 1) + "empty file: expected a header line of column names";
    return 2;
  }
  lineno = 1;
  r->columns = split(text);
  if (r->columns.empty()) {
    *err = where(path, 1) + "empty header: expected column names";
    return 2;
  }
  for (size_t i = 0; i < r->columns.size(); i++) {
    const std::string &c = r->columns[i];
    if (!known_column(c)) {
      *err = where(path, 1) + "unknown column '" + c + "' (not an RTDE output name)";
      return 2;
    }
    for (size_t k = 0; k < i; k++) {
      if (r->columns[k] == c) {
        *err = where(path, 1) + "duplicate column '" + c + "'";
        return 2;
      }
    }
  }

  // where each field's columns are (-1: absent); a vector field is all there or missing
  auto find = [&](const std::string &name) -> int {
    for (size_t i = 0; i < r->columns.size(); i++) {
      if (r->columns[i] == name) {
        return (int)i;
      }
    }
    return -1;
  };
  struct Vec {
    const char *name;
    bool required;
    std::vector<Joints> *dst;
    bool *present;
    int col[URT_NJ];
  };
  bool yes = true;
  Vec vecs[] = {
      {"target_q", true, &r->target_q, &yes, {}},
      {"target_qd", true, &r->target_qd, &yes, {}},
      {"actual_current", true, &r->actual_current, &yes, {}},
      {"target_qdd", false, &r->target_qdd, &r->has_target_qdd, {}},
      {"target_current", false, &r->target_current, &r->has_target_current, {}},
      {"actual_q", false, &r->actual_q, &r->has_actual_q, {}},
      {"actual_qd", false, &r->actual_qd, &r->has_actual_qd, {}},
  };
  int col_t = find("timestamp");
  if (col_t < 0) {
    *err = where(path, 1) + "missing column 'timestamp'";
    return 2;
  }
  for (Vec &v : vecs) {
    int found = 0;
    for (int j = 0; j < URT_NJ; j++) {
      v.col[j] = find(std::string(v.name) + "_" + std::to_string(j));
      found += v.col[j] >= 0;
    }
    if (found == 0 && !v.required) {
      continue;
    }
    for (int j = 0; j < URT_NJ; j++) {
      if (v.col[j] < 0) {
        *err = where(path, 1) + "missing column '" + v.name + "_" + std::to_string(j) + "'" +
               (v.required ? " (required)" : " (the other joints' are there)");
        return 2;
      }
    }
    if (!v.required) {
      *v.present = true;
    }
  }

  // the samples
  std::vector<double> row;
  while (std::getline(in, text)) {
    lineno++;
    std::vector<std::string> cells = split(text);
    if (cells.empty()) {
      continue;  // a blank line (e.g. at the end)
    }
    if (cells.size() != r->columns.size()) {
      *err = where(path, lineno) + "expected " + std::to_string(r->columns.size()) +
             " cells, got " + std::to_string(cells.size());
      return 2;
    }
    row.resize(cells.size());
    for (size_t i = 0; i < cells.size(); i++) {
      if (!parse_cell(cells[i], &row[i])) {
        *err = where(path, lineno) + "column '" + r->columns[i] + "': not a finite number: '" +
               cells[i] + "'";
        return 2;
      }
    }
    double t = row[(size_t)col_t];
    if (!r->t.empty() && !(t > r->t.back())) {
      *err = where(path, lineno) + "timestamp " + cells[(size_t)col_t] +
             " is not after the previous sample's (line " + std::to_string(r->line.back()) +
             ")";
      return 2;
    }
    r->t.push_back(t);
    r->line.push_back(lineno);
    for (Vec &v : vecs) {
      if (v.col[0] < 0) {
        continue;
      }
      Joints a;
      for (int j = 0; j < URT_NJ; j++) {
        a[(size_t)j] = row[(size_t)v.col[j]];
      }
      v.dst->push_back(a);
    }
  }
  if (in.bad()) {
    *err = path + ": read error";
    return 2;
  }
  if (r->t.size() < 2) {
    *err = where(path, lineno) + "at least two samples are needed, the file has " +
           std::to_string(r->t.size());
    return 2;
  }
  return 0;
}
