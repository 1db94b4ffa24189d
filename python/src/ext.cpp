// SPDX-License-Identifier: Apache-2.0
// python/src/ext.cpp — urtwin._urtwin, the nanobind module behind `import urtwin`: the model
// (urt_model_load_overlays), trajectories (tools/traj.h, samples, RTDE record.py CSV through
// tools/replay_csv.h) and the run (run.hpp) with the GIL released while it steps. The Python
// layer (python/urtwin/__init__.py) shapes the arguments and names the columns.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "replay_csv.h"
#include "run.hpp"
#include "traj.h"
#include "urt/core.h"
#include "urt/faults.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

using Array = nb::ndarray<nb::numpy, double>;
using InArray = nb::ndarray<const double, nb::c_contig, nb::device::cpu>;

// An owned buffer handed to numpy without a copy.
Array to_numpy(std::vector<double> &&v, std::vector<size_t> shape) {
  auto *owned = new std::vector<double>(std::move(v));
  nb::capsule owner(owned, [](void *p) noexcept { delete (std::vector<double> *)p; });
  return Array(owned->data(), shape.size(), shape.data(), owner);
}

Array joints_to_numpy(const std::vector<Joints> &rows) {
  std::vector<double> v;
  v.reserve(rows.size() * URT_NJ);
  for (const Joints &r : rows) {
    v.insert(v.end(), r.begin(), r.end());
  }
  return to_numpy(std::move(v), {rows.size(), (size_t)URT_NJ});
}

class Model {
 public:
  Model(const std::string &config, const std::vector<std::string> &overlays,
        const std::vector<std::string> &overrides) {
    std::vector<const char *> ov, os;
    for (const std::string &s : overlays) ov.push_back(s.c_str());
    ov.push_back(nullptr);
    for (const std::string &s : overrides) os.push_back(s.c_str());
    os.push_back(nullptr);
    char err[1024] = "";
    urt_model_t *m = nullptr;
    int rc = urt_model_load_overlays(config.c_str(), ov.data(), os.data(), &m, err, sizeof err);
    if (rc != 0) {
      throw std::invalid_argument(err[0] ? err : urt_strerror(rc));
    }
    m_.reset(m);
  }

  const urt_model_t *get() const { return m_.get(); }

  std::string print(bool json) const {
    char *buf = nullptr;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f) {
      throw std::runtime_error("open_memstream failed");
    }
    urt_model_print(m_.get(), f, json ? 1 : 0);
    std::fclose(f);
    std::string s(buf, len);
    std::free(buf);
    return s;
  }

  std::vector<double> vec6(const double *v) const { return std::vector<double>(v, v + URT_NJ); }

  std::vector<std::string> joint_names() const {
    std::vector<std::string> n;
    for (int j = 0; j < URT_NJ; j++) n.emplace_back(m_->joint[j].name);
    return n;
  }

 private:
  struct Free {
    void operator()(urt_model_t *m) const { urt_model_free(m); }
  };
  std::unique_ptr<urt_model_t, Free> m_;
};

void check_built(const Model &model, const urtpy::Trajectory &tr) {
  char err[512] = "";
  if (urt_traj_check(&tr.builtin, model.get(), err, sizeof err) != 0) {
    throw std::invalid_argument(std::string(err) +
                                " (the model would refuse this trajectory; raise the limit "
                                "with an override joints.<index>.<limit>=VALUE)");
  }
}

urtpy::Trajectory make_excitation(const Model &model, uint64_t seed) {
  urtpy::Trajectory tr;
  if (urt_traj_make_excitation(&tr.builtin, model.get()->q0, nullptr, seed) != 0) {
    throw std::invalid_argument("cannot build the excitation trajectory from the model's q0");
  }
  check_built(model, tr);
  return tr;
}

urtpy::Trajectory make_pickplace(const Model &model) {
  urtpy::Trajectory tr;
  if (urt_traj_make_pickplace(&tr.builtin, model.get()->q0) != 0) {
    throw std::invalid_argument("cannot build the pickplace trajectory from the model's q0");
  }
  check_built(model, tr);
  return tr;
}

urtpy::Trajectory make_hold(const Model &model, double duration) {
  if (!std::isfinite(duration) || duration <= 0.0) {
    throw std::invalid_argument("hold: duration: expected seconds > 0");
  }
  urtpy::Trajectory tr;
  urt_traj_make_hold(&tr.builtin, model.get()->q0, duration);
  return tr;
}

std::vector<double> take(const InArray &a, const char *name, size_t rows, int cols) {
  bool ok = cols == 0 ? (a.ndim() == 1 && a.shape(0) == rows)
                      : (a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == (size_t)cols);
  if (!ok) {
    std::string shape = "(";
    for (size_t i = 0; i < a.ndim(); i++) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    shape += a.ndim() == 1 ? ",)" : ")";
    throw std::invalid_argument(std::string(name) + ": expected shape (" + std::to_string(rows) +
                                (cols ? ", " + std::to_string(cols) : std::string(",")) +
                                "), got " + shape);
  }
  std::vector<double> v(a.data(), a.data() + a.size());
  for (size_t i = 0; i < v.size(); i++) {
    if (!std::isfinite(v[i])) {
      throw std::invalid_argument(std::string(name) + ": non-finite value at sample " +
                                  std::to_string(cols ? i / cols : i));
    }
  }
  return v;
}

urtpy::Trajectory make_samples(const InArray &t, const InArray &q, const InArray &qd,
                               const InArray &qdd) {
  if (t.ndim() != 1 || t.shape(0) < 2) {
    throw std::invalid_argument("t: expected a 1-D array of at least two times");
  }
  const size_t n = t.shape(0);
  urtpy::Trajectory tr;
  tr.sampled = true;
  tr.samples.t = take(t, "t", n, 0);
  tr.samples.q = take(q, "q", n, URT_NJ);
  tr.samples.qd = take(qd, "qd", n, URT_NJ);
  tr.samples.qdd = take(qdd, "qdd", n, URT_NJ);
  const double t0 = tr.samples.t[0];
  for (size_t i = 0; i < n; i++) {
    if (i > 0 && !(tr.samples.t[i] > tr.samples.t[i - 1])) {
      throw std::invalid_argument("t: not strictly increasing at sample " + std::to_string(i));
    }
  }
  for (double &x : tr.samples.t) x -= t0;  // the run starts at the first sample
  return tr;
}

nb::dict read_record_csv(const std::string &path) {
  ReplayRecording rec;
  std::string err;
  if (replay_csv_read(path, &rec, &err) != 0) {
    throw std::invalid_argument(err);
  }
  nb::dict out;
  out["timestamp"] = to_numpy(std::vector<double>(rec.t), {rec.t.size()});
  out["target_q"] = joints_to_numpy(rec.target_q);
  out["target_qd"] = joints_to_numpy(rec.target_qd);
  out["actual_current"] = joints_to_numpy(rec.actual_current);
  if (rec.has_target_qdd) out["target_qdd"] = joints_to_numpy(rec.target_qdd);
  if (rec.has_target_current) out["target_current"] = joints_to_numpy(rec.target_current);
  if (rec.has_actual_q) out["actual_q"] = joints_to_numpy(rec.actual_q);
  if (rec.has_actual_qd) out["actual_qd"] = joints_to_numpy(rec.actual_qd);
  return out;
}

// A fault scenario from a file (urt_faults_load) or from YAML text (urt_faults_parse, with
// name standing for the file in messages); a bad one raises ValueError "name:line: key: reason".
void load_faults(const Model &model, nb::object file, nb::object yaml, const std::string &name,
                 urt_fault_scenario_t *out) {
  std::memset(out, 0, sizeof *out);
  char err[512] = "";
  int rc = 0;
  if (!file.is_none()) {
    rc = urt_faults_load(model.get(), nb::cast<std::string>(file).c_str(), out, err, sizeof err);
  } else if (!yaml.is_none()) {
    rc = urt_faults_parse(model.get(), nb::cast<std::string>(yaml).c_str(), name.c_str(), out,
                          err, sizeof err);
  }
  if (rc != 0) {
    throw std::invalid_argument(err[0] ? std::string(err) : std::string(urt_strerror(rc)));
  }
}

nb::tuple run(const Model &model, const urtpy::Trajectory &tr, double duration, long decimate,
              nb::object seed, nb::object faults_file, nb::object faults_yaml,
              const std::string &faults_name) {
  urtpy::RunSpec spec;
  load_faults(model, faults_file, faults_yaml, faults_name, &spec.faults);
  spec.duration = duration;
  spec.decimate = decimate;
  if (!seed.is_none()) {
    spec.has_seed = true;
    spec.seed = nb::cast<uint64_t>(seed);
  }
  urtpy::RunOutput out;
  int rc;
  {
    nb::gil_scoped_release unlocked;  // the loop touches no Python object
    rc = urtpy::run(model.get(), tr, spec, &out);
  }
  if (rc == 2) {
    throw std::invalid_argument(out.error);
  }
  if (rc != 0) {
    throw std::runtime_error(out.error);
  }
  nb::list chans;
  for (const urtpy::Channel &c : out.channels) {
    chans.append(nb::make_tuple(c.name, c.offset, c.width, c.unit, c.what));
  }
  nb::dict info;
  info["steps"] = out.steps;
  info["wall_s"] = out.wall_s;
  info["cpu_s"] = out.cpu_s;
  info["dt"] = model.get()->dt;
  size_t rows = out.rows, w = (size_t)out.row_width;
  return nb::make_tuple(to_numpy(std::move(out.data), {rows, w}), chans, info);
}

}  // namespace

NB_MODULE(_urtwin, mod) {
  mod.doc() = "urtwin's C core: model, trajectories, offline run (see the urtwin package)";
  mod.attr("NJ") = URT_NJ;

  nb::class_<Model>(mod, "Model")
      .def(nb::init<const std::string &, const std::vector<std::string> &,
                    const std::vector<std::string> &>(),
           "config"_a, "overlays"_a, "overrides"_a)
      .def("print", &Model::print, "json"_a = false)
      .def_prop_ro("dt", [](const Model &m) { return m.get()->dt; })
      .def_prop_ro("seed", [](const Model &m) { return m.get()->seed; })
      .def_prop_ro("name", [](const Model &m) { return std::string(m.get()->name); })
      .def_prop_ro("source", [](const Model &m) { return std::string(m.get()->source); })
      .def_prop_ro("q0", [](const Model &m) { return m.vec6(m.get()->q0); })
      .def_prop_ro("joint_names", &Model::joint_names)
      .def_prop_ro("q_min", [](const Model &m) {
        double v[URT_NJ];
        for (int j = 0; j < URT_NJ; j++) v[j] = m.get()->joint[j].q_min;
        return m.vec6(v);
      })
      .def_prop_ro("q_max", [](const Model &m) {
        double v[URT_NJ];
        for (int j = 0; j < URT_NJ; j++) v[j] = m.get()->joint[j].q_max;
        return m.vec6(v);
      })
      .def_prop_ro("payload_mass", [](const Model &m) { return m.get()->payload.mass; });

  nb::class_<urtpy::Trajectory>(mod, "Trajectory")
      .def_prop_ro("duration", &urtpy::Trajectory::duration)
      .def_prop_ro("kind", [](const urtpy::Trajectory &t) { return std::string(t.kind()); });

  mod.def("excitation", &make_excitation, "model"_a, "seed"_a);
  mod.def("pickplace", &make_pickplace, "model"_a);
  mod.def("hold", &make_hold, "model"_a, "duration"_a);
  mod.def("samples", &make_samples, "t"_a, "q"_a, "qd"_a, "qdd"_a);
  mod.def("read_record_csv", &read_record_csv, "path"_a);
  mod.def("config_key_unit", [](const std::string &key) -> nb::object {
    const char *u = urt_config_key_unit(key.c_str());
    return u ? nb::object(nb::str(u)) : nb::none();
  });
  mod.def("channels", [] {
    nb::list chans;
    for (const urtpy::Channel &c : urtpy::channels()) {
      chans.append(nb::make_tuple(c.name, c.offset, c.width, c.unit, c.what));
    }
    return chans;
  });
  mod.def("run", &run, "model"_a, "trajectory"_a, "duration"_a, "decimate"_a, "seed"_a.none(),
          "faults_file"_a.none() = nb::none(), "faults_yaml"_a.none() = nb::none(),
          "faults_name"_a = "faults");
  mod.def("faults_check", [](const Model &m, nb::object file, nb::object yaml,
                            const std::string &name) {
    urt_fault_scenario_t sc;
    load_faults(m, file, yaml, name, &sc);
    return (int)sc.n;
  }, "model"_a, "file"_a.none(), "yaml"_a.none(), "name"_a);
  mod.def("fault_classes", [] {
    nb::list out;
    for (int c = 0; c < urt_fault_class_count(); c++) out.append(urt_fault_class_name(c));
    return out;
  });
}
