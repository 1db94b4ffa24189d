// SPDX-License-Identifier: Apache-2.0
// tools/urt_bench.cpp — cost of one urt_step, side by side with MuJoCo's mj_step on a UR5-like
// model, measured in one run (model.md §5.6 target, style.md point 24).
//
//   urt_bench [--config config/ur5.yaml] [--set key=value]... [--steps N] [--warmup N]
//             [--dt 5e-5,1e-4] [--mujoco-lib /path/libmujoco.so.X] [--json out.json]
//
// For every dt it loads the model with "<dt-key>=<dt>" added to the overrides, starts at rest,
// drives a moving sine set-point on all joints and times each urt_step with CLOCK_MONOTONIC
// into a preallocated array. A standing case at every dt holds the arm at q0 (set-point at rest):
// at low joint speed the drives' friction refines the step (stick-slip), so it is timed too and
// reported beside the moving one, with its ratio to mj_step (JSON "standing_runs" and
// "standing_ratios"; never asserted). All cases (urt at each dt, MuJoCo variants) are timed round robin
// in chunks (--chunk), so load changes on the machine hit them alike. MuJoCo (bench_mujoco.h)
// is dlopen'ed, so the benchmark builds and runs without it; if it cannot be loaded the JSON and
// the table say "unavailable". Only medians, percentiles and ratios are reported — never a pass/fail on time:
// the machine is shared and noisy. Pinocchio's ABA is timed by tools/bench.py, which merges.
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "bench_mujoco.h"
#include "bench_timing.h"
#include "urt/core.h"

namespace urt::tools {
namespace {

// set when the robot parameter file does not load: the tools exit 2 on that
bool g_config_error = false;

//---- options ----

struct Options {
  std::string config = "config/ur5.yaml";
  std::vector<std::string> sets;            // user overrides, "key.path=value"
  std::string dt_key = "simulation.dt";     // the override key the loader reads dt from
  std::vector<double> dts = {5e-5, 1e-4};   // 20 kHz and 10 kHz
  long steps = 20000;
  long warmup = 2000;
  long chunk = 500;                          // steps per case per round-robin turn
  double speed = 0.9;                        // peak joint speed of the set-point [rad/s]
  std::string mujoco_lib;
  std::string json;
  std::string mjcf_out;
  int cpu = -1;
  bool dma_latency = false;
  bool skip_urt = false;
  bool skip_mujoco = false;
  bool quiet = false;
};

void usage(FILE *f) {
  fprintf(f,
          "usage: urt_bench [options]\n"
          "  --config FILE        robot parameter file (default config/ur5.yaml)\n"
          "  --set KEY=VALUE      override passed to urt_model_load (repeatable)\n"
          "  --dt LIST            comma-separated steps in s (default 5e-5,1e-4)\n"
          "  --dt-key KEY         override key for dt (default simulation.dt)\n"
          "  --steps N            timed steps per case (default 20000)\n"
          "  --warmup N           untimed steps before timing (default 2000)\n"
          "  --chunk N            steps per case per round-robin turn (default 500)\n"
          "  --speed V            peak joint speed of the set-point, rad/s (default 0.9)\n"
          "  --mujoco-lib PATH    libmujoco.so to dlopen (without it MuJoCo is unavailable)\n"
          "  --mjcf-out FILE      also write the UR5-like MJCF used for mj_step\n"
          "  --json FILE          write the results as JSON\n"
          "  --cpu N              pin the process to CPU N\n"
          "  --dma-latency        hold /dev/cpu_dma_latency at 0 while running\n"
          "  --skip-urt, --skip-mujoco, --quiet (no table)\n");
}

bool parse_dts(const char *s, std::vector<double> *out) {
  out->clear();
  std::string str(s);
  size_t pos = 0;
  while (pos <= str.size()) {
    size_t end = str.find(',', pos);
    if (end == std::string::npos) {
      end = str.size();
    }
    std::string tok = str.substr(pos, end - pos);
    char *e = nullptr;
    double v = strtod(tok.c_str(), &e);
    if (tok.empty() || *e != '\0' || !(v > 0.0) || !std::isfinite(v)) {
      return false;
    }
    out->push_back(v);
    pos = end + 1;
  }
  return !out->empty();
}

bool parse_long(const char *s, long min, long *out) {
  char *e = nullptr;
  long v = strtol(s, &e, 10);
  if (*s == '\0' || *e != '\0' || v < min) {
    return false;
  }
  *out = v;
  return true;
}

// returns 0 on success, 1 to exit with success (help), 2 on a usage error
int parse_options(int argc, char **argv, Options *o) {
  enum { kDtKey = 256, kMjcfOut, kDma, kSkipUrt, kSkipMj, kQuiet, kSpeed, kChunk };
  static const struct option longopts[] = {
      {"config", required_argument, nullptr, 'c'},
      {"set", required_argument, nullptr, 's'},
      {"dt", required_argument, nullptr, 'd'},
      {"dt-key", required_argument, nullptr, kDtKey},
      {"steps", required_argument, nullptr, 'n'},
      {"warmup", required_argument, nullptr, 'w'},
      {"speed", required_argument, nullptr, kSpeed},
      {"chunk", required_argument, nullptr, kChunk},
      {"mujoco-lib", required_argument, nullptr, 'm'},
      {"mjcf-out", required_argument, nullptr, kMjcfOut},
      {"json", required_argument, nullptr, 'j'},
      {"cpu", required_argument, nullptr, 'p'},
      {"dma-latency", no_argument, nullptr, kDma},
      {"skip-urt", no_argument, nullptr, kSkipUrt},
      {"skip-mujoco", no_argument, nullptr, kSkipMj},
      {"quiet", no_argument, nullptr, kQuiet},
      {"help", no_argument, nullptr, 'h'},
      {nullptr, 0, nullptr, 0}};
  int c;
  long v;
  while ((c = getopt_long(argc, argv, "c:s:d:n:w:m:j:p:h", longopts, nullptr)) != -1) {
    switch (c) {
      case 'c': o->config = optarg; break;
      case 's':
        if (strchr(optarg, '=') == nullptr) {
          fprintf(stderr, "urt_bench: --set expects KEY=VALUE, got '%s'\n", optarg);
          return 2;
        }
        o->sets.emplace_back(optarg);
        break;
      case 'd':
        if (!parse_dts(optarg, &o->dts)) {
          fprintf(stderr, "urt_bench: bad --dt list '%s'\n", optarg);
          return 2;
        }
        break;
      case kDtKey: o->dt_key = optarg; break;
      case 'n':
        if (!parse_long(optarg, 1, &o->steps)) {
          fprintf(stderr, "urt_bench: bad --steps '%s'\n", optarg);
          return 2;
        }
        break;
      case 'w':
        if (!parse_long(optarg, 0, &o->warmup)) {
          fprintf(stderr, "urt_bench: bad --warmup '%s'\n", optarg);
          return 2;
        }
        break;
      case kChunk:
        if (!parse_long(optarg, 1, &o->chunk)) {
          fprintf(stderr, "urt_bench: bad --chunk '%s'\n", optarg);
          return 2;
        }
        break;
      case kSpeed: {
        char *e = nullptr;
        o->speed = strtod(optarg, &e);
        if (*e != '\0' || !(o->speed > 0.0 && o->speed <= 3.2)) {
          fprintf(stderr, "urt_bench: bad --speed '%s' (0 < v <= 3.2 rad/s)\n", optarg);
          return 2;
        }
        break;
      }
      case 'm': o->mujoco_lib = optarg; break;
      case kMjcfOut: o->mjcf_out = optarg; break;
      case 'j': o->json = optarg; break;
      case 'p':
        if (!parse_long(optarg, 0, &v)) {
          fprintf(stderr, "urt_bench: bad --cpu '%s'\n", optarg);
          return 2;
        }
        o->cpu = static_cast<int>(v);
        break;
      case kDma: o->dma_latency = true; break;
      case kSkipUrt: o->skip_urt = true; break;
      case kSkipMj: o->skip_mujoco = true; break;
      case kQuiet: o->quiet = true; break;
      case 'h': usage(stdout); return 1;
      default: usage(stderr); return 2;
    }
  }
  if (optind < argc) {
    fprintf(stderr, "urt_bench: unexpected argument '%s'\n", argv[optind]);
    return 2;
  }
  return 0;
}

//---- urt_step ----

struct UrtRun {
  double dt = 0;
  std::string status = "ok";   // "ok" or "error"
  std::string error;
  Stats stats;
  long step_errors = 0, refused_commands = 0;
  unsigned pstop = 0, isat_count = 0, vsat_count = 0;
  double max_track_err = 0;    // max |q_set − q| over the timed steps [rad]
  int faults = 0;              // faults active during the run (kBenchFaults), 0: healthy
  bool standing = false;       // set-point at rest at q0 (the arm holding a pose)
};

// the model as loaded at the first rate, for the JSON (bench.py builds Pinocchio from it)
struct ArmDump {
  bool valid = false;
  urt_arm_params_t arm;
  double q0[URT_NJ], q_min[URT_NJ], q_max[URT_NJ];
};

std::string fmt_g(double v) {
  char b[64];
  snprintf(b, sizeof b, "%.12g", v);
  return b;
}

using ModelPtr = std::unique_ptr<urt_model_t, void (*)(urt_model_t *)>;

// The model of --config with the user's overrides, at dt when dt > 0. On failure *err says why
// and the returned pointer is empty.
ModelPtr load_model(const Options &o, double dt, std::string *err) {
  std::vector<std::string> ovr_s = o.sets;
  if (dt > 0) {
    ovr_s.push_back(o.dt_key + "=" + fmt_g(dt));
  }
  std::vector<const char *> ovr;
  for (const auto &s : ovr_s) {
    ovr.push_back(s.c_str());
  }
  ovr.push_back(nullptr);
  urt_model_t *m = nullptr;
  char e[512] = "";
  int rc = urt_model_load(o.config.c_str(), ovr.data(), &m, e, sizeof e);
  if (rc != 0) {
    g_config_error = true;
    *err = std::string("urt_model_load: ") + urt_strerror(rc) + (e[0] ? ": " : "") + e;
  }
  return ModelPtr(m, urt_model_free);
}

// The faults of the faulted case (issue 11: urt_step with five faults active against the
// healthy step, same run): one of each kind of work the faults add — a drive parameter
// (mesh stiffness), the friction law (lubricant), a state-dependent stiffness (crack), a
// sensor chain (current gain) and a per-step random draw (encoder noise).
constexpr int kBenchFaults = 5;
void bench_faults(urt_fault_scenario_t *s) {
  memset(s, 0, sizeof *s);
  s->n = kBenchFaults;
  const int cls[kBenchFaults] = {URT_FAULT_GEAR_STIFFNESS, URT_FAULT_LUBRICANT, URT_FAULT_CRACK,
                                 URT_FAULT_CURRENT_GAIN, URT_FAULT_ENCODER_NOISE};
  const double sev[kBenchFaults] = {0.5, 1.0, 0.3, 0.05, 1e-5};
  for (int k = 0; k < kBenchFaults; ++k) {
    s->f[k].cls = cls[k];
    s->f[k].joint = k + 1;
    s->f[k].severity = sev[k];
    s->f[k].profile = URT_FAULT_STEP;
    s->f[k].seed = 7;
  }
  s->f[4].component = URT_FAULT_ENC_JOINT;
}

// One urt_step workload at one dt: model, data and set-point. main() advances every case in
// chunks, round robin, so all of them share the machine's quiet and busy moments.
class UrtCase {
 public:
  UrtRun r;

  // load at dt (the user's overrides, then dt) and start at rest; on failure r.status is
  // "error" and the case is never stepped
  UrtCase(const Options &o, double dt, ArmDump *dump, bool faulted = false,
          bool standing = false) {
    r.dt = dt;
    r.standing = standing;
    m_ = load_model(o, dt, &r.error);
    if (!m_) {
      r.status = "error";
      return;
    }
    const urt_model_t *m = m_.get();

    // a wrong dt key would silently benchmark the file's rate
    if (std::fabs(m->dt - dt) > 1e-12 * dt) {
      fail("override " + o.dt_key + "=" + fmt_g(dt) + " not applied (model dt = " +
           fmt_g(m->dt) + "); pass the right key with --dt-key");
      return;
    }

    sp_ = make_setpoint(m, o.speed);
    if (standing) {
      // q = q0, q̇ = q̈ = 0 at every step: the arm holds its start pose against gravity
      std::fill(std::begin(sp_.amp), std::end(sp_.amp), 0.0);
    }
    if (dump != nullptr && !dump->valid) {
      dump->valid = true;
      dump->arm = m->arm;
      for (int j = 0; j < URT_NJ; ++j) {
        dump->q0[j] = m->q0[j];
        dump->q_min[j] = m->joint[j].q_min;
        dump->q_max[j] = m->joint[j].q_max;
      }
    }

    d_ = std::make_unique<urt_data_t>();
    int rc = urt_data_init(m, d_.get(), nullptr);
    if (rc != 0) {
      fail(std::string("urt_data_init: ") + urt_strerror(rc));
      return;
    }
    if (faulted) {
      urt_fault_scenario_t s;
      bench_faults(&s);
      rc = urt_data_set_faults(m, d_.get(), &s);
      if (rc != 0) {
        fail(std::string("urt_data_set_faults: ") + urt_strerror(rc));
        return;
      }
      r.faults = kBenchFaults;
    }
    memset(&cmd_, 0, sizeof cmd_);
    // preallocated so the timed loop touches no allocator
    samples_.assign(static_cast<size_t>(o.steps), 0);
  }

  bool ok() const { return r.status == "ok"; }

  // Advance n steps. Only urt_step is timed; the command is installed between steps, as the
  // RT loop does.
  void run(long n, bool timed) {
    urt_model_t *m = m_.get();
    urt_data_t *d = d_.get();
    for (long k = 0; k < n; ++k) {
      sp_.at(d->t, cmd_.q, cmd_.qd, cmd_.qdd);
      if (urt_command_set(m, d, &cmd_) != 0) {
        ++r.refused_commands;
      }
      int64_t t0 = now_ns();
      int rc = urt_step(m, d);
      int64_t t1 = now_ns();
      if (!timed || done_ >= samples_.size()) {
        continue;
      }
      samples_[done_++] = t1 - t0;
      if (rc != 0) {
        ++r.step_errors;
      }
      for (int j = 0; j < URT_NJ; ++j) {
        r.max_track_err = std::max(r.max_track_err, std::fabs(cmd_.q[j] - d->x[j][URT_X_Q]));
      }
    }
  }

  void finish() {
    if (!ok()) {
      return;
    }
    r.pstop = d_->pstop;
    r.isat_count = d_->isat_count;
    r.vsat_count = d_->vsat_count;
    samples_.resize(done_);
    r.stats = summarise(std::move(samples_));
  }

 private:
  void fail(const std::string &e) {
    r.status = "error";
    r.error = e;
  }

  ModelPtr m_{nullptr, urt_model_free};
  std::unique_ptr<urt_data_t> d_;
  Setpoint sp_{};
  urt_command_t cmd_;
  std::vector<int64_t> samples_;
  size_t done_ = 0;
};

//---- JSON ----

// A minimal writer: enough for numbers, strings, arrays and objects, with commas placed for us.
class Json {
 public:
  void begin_object(const char *key = nullptr) { open(key, '{'); }
  void end_object() { close('}'); }
  void begin_array(const char *key = nullptr) { open(key, '['); }
  void end_array() { close(']'); }
  void num(const char *key, double v) {
    prefix(key);
    if (std::isfinite(v)) {
      char b[64];
      snprintf(b, sizeof b, "%.9g", v);
      s_ += b;
    } else {
      s_ += "null";
    }
  }
  void integer(const char *key, long long v) {
    prefix(key);
    s_ += std::to_string(v);
  }
  void boolean(const char *key, bool v) {
    prefix(key);
    s_ += v ? "true" : "false";
  }
  void str(const char *key, const std::string &v) {
    prefix(key);
    quote(v);
  }
  void nums(const char *key, const double *v, int n) {
    begin_array(key);
    for (int i = 0; i < n; ++i) {
      num(nullptr, v[i]);
    }
    end_array();
  }
  const std::string &text() const { return s_; }

 private:
  void quote(const std::string &v) {
    s_ += '"';
    for (unsigned char c : v) {
      if (c == '"' || c == '\\') {
        s_ += '\\';
        s_ += static_cast<char>(c);
      } else if (c < 0x20) {
        char b[8];
        snprintf(b, sizeof b, "\\u%04x", c);
        s_ += b;
      } else {
        s_ += static_cast<char>(c);
      }
    }
    s_ += '"';
  }
  void prefix(const char *key) {
    if (!first_.empty()) {
      if (!first_.back()) {
        s_ += ',';
      }
      first_.back() = false;
      s_ += '\n';
      s_ += std::string(2 * first_.size(), ' ');
    }
    if (key != nullptr) {
      quote(key);
      s_ += ": ";
    }
  }
  void open(const char *key, char c) {
    prefix(key);
    s_ += c;
    first_.push_back(true);
  }
  void close(char c) {
    bool empty = first_.back();
    first_.pop_back();
    if (!empty) {
      s_ += '\n' + std::string(2 * first_.size(), ' ');
    }
    s_ += c;
  }
  std::string s_;
  std::vector<bool> first_;
};

void json_stats(Json &j, const Stats &s, double dt) {
  j.integer("n", s.n);
  j.num("median_us", s.median_us);
  j.num("p99_us", s.p99_us);
  j.num("p999_us", s.p999_us);
  j.num("max_us", s.max_us);
  j.num("mean_us", s.mean_us);
  j.num("min_us", s.min_us);
  // real-time factor: simulated time per wall time at the median cost (> 1 is faster than RT)
  j.num("rtf", s.median_us > 0 ? dt * 1e6 / s.median_us : NAN);
  j.num("wall_s_per_sim_s", s.median_us * 1e-6 / dt);
  j.num("budget_fraction_median", s.median_us * 1e-6 / dt);
  j.num("budget_fraction_p999", s.p999_us * 1e-6 / dt);
}

const MjRun *find_mj(const std::vector<MjRun> &runs, const char *variant, double dt) {
  for (const auto &r : runs) {
    if (r.status == "ok" && strcmp(r.variant->name, variant) == 0 && r.dt == dt) {
      return &r;
    }
  }
  return nullptr;
}

//---- report ----

struct Report {
  double clock_overhead_ns = 0;
  std::string urt_status = "ok", urt_error;
  std::vector<UrtRun> urt;
  ArmDump arm;
  std::string mj_status = "ok", mj_error, mj_version;
  std::vector<MjRun> mj;
};

// the healthy moving run at dt, or nullptr
const UrtRun *healthy_at(const std::vector<UrtRun> &runs, double dt) {
  for (const auto &r : runs) {
    if (r.faults == 0 && !r.standing && r.status == "ok" && r.dt == dt) {
      return &r;
    }
  }
  return nullptr;
}

std::string rate_label(double dt) {
  char b[32];
  snprintf(b, sizeof b, "%g kHz", 1e-3 / dt);
  return b;
}

std::string to_json(const Options &o, const Report &rep) {
  Json j;
  j.begin_object();
  j.str("tool", "urt_bench");
  j.integer("schema", 1);
  j.integer("steps", o.steps);
  j.integer("warmup", o.warmup);
  j.integer("interleave_chunk", o.chunk);
  j.integer("cpu", o.cpu);
  j.begin_object("clock");
  j.str("source", "CLOCK_MONOTONIC");
  j.num("overhead_ns", rep.clock_overhead_ns);
  j.str("note", "per-sample overhead, reported, not subtracted");
  j.end_object();

  j.begin_object("urt");
  j.str("status", rep.urt_status);
  if (!rep.urt_error.empty()) {
    j.str("error", rep.urt_error);
  }
  j.str("config", o.config);
  j.str("dt_key", o.dt_key);
  j.begin_array("overrides");
  for (const auto &s : o.sets) {
    j.str(nullptr, s);
  }
  j.end_array();
  j.str("timed", "urt_step only (urt_command_set runs between steps, untimed)");
  j.str("setpoint", "q = q0 + A(1 - cos wt), f = 0.25..0.5 Hz per joint, peak speed <= --speed");
  j.num("speed_rad_s", o.speed);
  // the moving set-point's runs, then the arm holding q0 (set-point at rest), in one layout
  auto runs = [&](const char *key, bool standing) {
    j.begin_array(key);
    for (const auto &r : rep.urt) {
      if (r.standing != standing) {
        continue;
      }
      j.begin_object();
      j.num("dt", r.dt);
      j.num("rate_hz", 1.0 / r.dt);
      j.integer("faults", r.faults);
      j.str("status", r.status);
      if (r.status != "ok") {
        j.str("error", r.error);
      } else {
        json_stats(j, r.stats, r.dt);
        j.integer("step_errors", r.step_errors);
        j.integer("refused_commands", r.refused_commands);
        j.integer("pstop", r.pstop);
        j.integer("isat_count", r.isat_count);
        j.integer("vsat_count", r.vsat_count);
        j.num("max_tracking_error_rad", r.max_track_err);
      }
      j.end_object();
    }
    j.end_array();
  };
  runs("runs", false);
  j.str("standing_setpoint", "q = q0, qd = qdd = 0 (the arm holding its start pose)");
  runs("standing_runs", true);
  j.end_object();

  // the arm as the core loaded it, in urt_config's JSON layout
  if (rep.arm.valid) {
    const urt_arm_params_t &a = rep.arm.arm;
    j.begin_object("arm");
    j.nums("gravity", a.gravity, 3);
    j.nums("tcp", a.tcp, 6);
    j.begin_array("links");
    for (int i = 0; i < URT_NJ; ++i) {
      const urt_link_params_t &l = a.link[i];
      j.begin_object();
      j.num("a", l.a);
      j.num("alpha", l.alpha);
      j.num("beta", l.beta);
      j.num("d", l.d);
      j.num("theta", l.theta);
      j.num("mass", l.mass);
      j.nums("com", l.com, 3);
      j.nums("inertia", l.inertia, 6);
      j.end_object();
    }
    j.end_array();
    j.nums("q0", rep.arm.q0, URT_NJ);
    j.nums("q_min", rep.arm.q_min, URT_NJ);
    j.nums("q_max", rep.arm.q_max, URT_NJ);
    j.end_object();
  }

  j.begin_object("mujoco");
  j.str("status", rep.mj_status);
  if (!rep.mj_error.empty()) {
    j.str("error", rep.mj_error);
  }
  j.str("lib", o.mujoco_lib);
  j.str("version", rep.mj_version);
  j.str("model",
        "UR5-like MJCF: 6 hinges, nominal UR5 DH, model.md Table 5 masses/CoMs/inertias, "
        "armature tau^2 J_M, damping 8/2 N m s/rad, position actuators (kp 2e4..2e3, kv) "
        "limited to 150/28 N m, no contacts (contype=conaffinity=0)");
  j.str("timestep", "matched to each urt dt");
  j.str("timed", "mj_step only (ctrl set between steps, untimed)");
  j.begin_array("runs");
  for (const auto &r : rep.mj) {
    j.begin_object();
    j.str("variant", r.variant->name);
    j.str("integrator", r.variant->integrator);
    j.boolean("frictionloss", r.variant->frictionloss);
    j.num("dt", r.dt);
    j.str("status", r.status);
    if (r.status != "ok") {
      j.str("error", r.error);
    } else {
      json_stats(j, r.stats, r.dt);
      j.num("max_tracking_error_rad", r.max_track_err);
    }
    j.end_object();
  }
  j.end_array();
  j.end_object();

  // urt_step / mj_step medians at the same dt, for every MuJoCo variant measured; and the
  // faulted step against the healthy one
  // one ratio of medians (and of p99s) at a step dt
  auto ratio = [&](double dt, const std::string &num, const std::string &den, const Stats &a,
                   const Stats &b) {
    j.begin_object();
    j.num("dt", dt);
    j.str("numerator", num);
    j.str("denominator", den);
    j.num("value", a.median_us / b.median_us);
    j.num("p99_value", a.p99_us / b.p99_us);
    j.end_object();
  };
  j.begin_array("ratios");
  for (const auto &f : rep.urt) {
    const UrtRun *h = healthy_at(rep.urt, f.dt);
    if (f.faults == 0 || f.status != "ok" || h == nullptr) {
      continue;
    }
    ratio(f.dt, "urt_step median, " + std::to_string(f.faults) + " faults active",
          "urt_step median (healthy, same run)", f.stats, h->stats);
  }
  for (const auto &u : rep.urt) {
    if (u.status != "ok" || u.faults || u.standing) {
      continue;
    }
    for (const auto &v : kMjVariants) {
      const MjRun *mr = find_mj(rep.mj, v.name, u.dt);
      if (mr == nullptr) {
        continue;
      }
      ratio(u.dt, "urt_step median", std::string("mj_step median (") + v.name + ")", u.stats,
            mr->stats);
    }
  }
  j.end_array();
  // the standing arm against the same mj_step runs (MuJoCo's cost does not depend on the motion:
  // no contacts, one step per call) and against the moving urt_step
  j.begin_array("standing_ratios");
  for (const auto &u : rep.urt) {
    if (u.status != "ok" || !u.standing) {
      continue;
    }
    for (const auto &v : kMjVariants) {
      const MjRun *mr = find_mj(rep.mj, v.name, u.dt);
      if (mr == nullptr) {
        continue;
      }
      ratio(u.dt, "urt_step median, standing arm", std::string("mj_step median (") + v.name + ")",
            u.stats, mr->stats);
    }
    const UrtRun *h = healthy_at(rep.urt, u.dt);
    if (h != nullptr) {
      ratio(u.dt, "urt_step median, standing arm", "urt_step median (moving set-point, same run)",
            u.stats, h->stats);
    }
  }
  j.end_array();
  j.end_object();
  return j.text() + "\n";
}

void print_row(const std::string &name, double dt, const Stats &s) {
  printf("%-34s %7.1f %9.3f %9.3f %9.3f %9.1f %9.3f %8.2f %8.3f\n", name.c_str(), dt * 1e6,
         s.median_us, s.p99_us, s.p999_us, s.max_us, s.mean_us, dt * 1e6 / s.median_us,
         s.median_us * 1e-6 / dt);
}

void print_table(const Options &o, const Report &rep) {
  printf("urt_bench: %ld timed steps (+%ld warm-up) per case, cases interleaved every %ld "
         "steps; CLOCK_MONOTONIC, overhead %.0f ns per sample (not subtracted)\n",
         o.steps, o.warmup, o.chunk, rep.clock_overhead_ns);
  printf("%-34s %7s %9s %9s %9s %9s %9s %8s %8s\n", "case", "dt[us]", "median", "p99", "p99.9",
         "max", "mean", "RTF", "wall/sim");
  printf("%-34s %7s %9s %9s %9s %9s %9s %8s %8s\n", "", "", "[us]", "[us]", "[us]", "[us]", "[us]",
         "", "[s/s]");
  if (rep.urt.empty()) {
    printf("%-34s %s\n", "urt_step", rep.urt_status.c_str());
  }
  for (const auto &r : rep.urt) {
    std::string name = "urt_step " + rate_label(r.dt) +
                       (r.faults ? ", " + std::to_string(r.faults) + " faults" : "") +
                       (r.standing ? ", standing" : "");
    if (r.status == "ok") {
      print_row(name, r.dt, r.stats);
    } else {
      printf("%-34s error: %s\n", name.c_str(), r.error.c_str());
    }
  }
  if (rep.mj_status != "ok") {
    printf("%-34s %s: %s\n", "mj_step", rep.mj_status.c_str(), rep.mj_error.c_str());
  }
  for (const auto &r : rep.mj) {
    std::string name = std::string("mj_step ") + r.variant->name + " " + rate_label(r.dt);
    if (r.status == "ok") {
      print_row(name, r.dt, r.stats);
    } else {
      printf("%-34s error: %s\n", name.c_str(), r.error.c_str());
    }
  }
  for (const auto &u : rep.urt) {
    const UrtRun *h = healthy_at(rep.urt, u.dt);
    if (u.status == "ok" && u.faults && h != nullptr) {
      printf("ratio urt_step %d faults / healthy at %s: %.3f (median), %.3f (p99)\n", u.faults,
             rate_label(u.dt).c_str(), u.stats.median_us / h->stats.median_us,
             u.stats.p99_us / h->stats.p99_us);
    }
    if (u.status != "ok" || u.faults) {
      continue;
    }
    for (const auto &v : kMjVariants) {
      const MjRun *mr = find_mj(rep.mj, v.name, u.dt);
      if (mr != nullptr) {
        printf("ratio urt_step%s / mj_step(%s) at %s: %.2f (median), %.2f (p99)\n",
               u.standing ? " standing" : "", v.name, rate_label(u.dt).c_str(),
               u.stats.median_us / mr->stats.median_us, u.stats.p99_us / mr->stats.p99_us);
      }
    }
  }
}

}  // namespace
}  // namespace urt::tools

int main(int argc, char **argv) {
  using namespace urt::tools;
  Options o;
  int prc = parse_options(argc, argv, &o);
  if (prc != 0) {
    return prc == 1 ? 0 : 2;
  }

  // optional environment tweaks; failures are warnings, the numbers just get noisier
  if (o.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(o.cpu, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
      fprintf(stderr, "urt_bench: warning: cannot pin to CPU %d: %s\n", o.cpu, strerror(errno));
    }
  }
  int dma_fd = -1;
  if (o.dma_latency) {
    // the kernel keeps C-states shallow only while this fd stays open
    dma_fd = open("/dev/cpu_dma_latency", O_WRONLY);
    int32_t zero = 0;
    if (dma_fd < 0 || write(dma_fd, &zero, sizeof zero) != sizeof zero) {
      fprintf(stderr, "urt_bench: warning: /dev/cpu_dma_latency: %s\n", strerror(errno));
    }
  }

  Report rep;
  rep.clock_overhead_ns = clock_overhead_ns();

  // urt_step at every rate
  std::vector<std::unique_ptr<UrtCase>> urt_cases;
  if (o.skip_urt) {
    rep.urt_status = "skipped";
  } else {
    for (double dt : o.dts) {
      urt_cases.push_back(std::make_unique<UrtCase>(o, dt, &rep.arm));
    }
    // the same workload at the first rate with five faults active, interleaved with the rest
    urt_cases.push_back(std::make_unique<UrtCase>(o, o.dts.front(), nullptr, true));
    // the arm holding q0 at every rate
    for (double dt : o.dts) {
      urt_cases.push_back(std::make_unique<UrtCase>(o, dt, nullptr, false, true));
    }
  }

  // MuJoCo gets the same arm, drives' inertia and friction, and set-point, from the same file
  std::string model_err;
  ModelPtr mj_model = load_model(o, 0.0, &model_err);

  // mj_step on the same set-point; never fatal
  MjApi mj;
  std::string mj_err;
  std::vector<std::unique_ptr<MjCase>> mj_cases;
  if (o.skip_mujoco) {
    rep.mj_status = "skipped";
  } else if (o.mujoco_lib.empty()) {
    rep.mj_status = "unavailable";
    rep.mj_error = "no --mujoco-lib given";
  } else if (!mj.open(o.mujoco_lib, &mj_err)) {
    rep.mj_status = "unavailable";
    rep.mj_error = mj_err;
  } else if (!mj_model) {
    rep.mj_status = "unavailable";
    rep.mj_error = "no model: " + model_err;
  } else {
    rep.mj_version = mj.version;
    Setpoint sp = make_setpoint(mj_model.get(), o.speed);
    for (double dt : o.dts) {
      for (const auto &v : kMjVariants) {
        mj_cases.push_back(std::make_unique<MjCase>(mj, mj_model.get(), v, dt, sp, o.steps));
      }
    }
  }

  // warm up each case, then time them round robin in chunks: a busy spell on this shared
  // machine then lands on every case alike, instead of on whichever ran at that moment
  for (auto &c : urt_cases) {
    if (c->ok()) {
      c->run(o.warmup, false);
    }
  }
  for (auto &c : mj_cases) {
    if (c->ok()) {
      c->run(o.warmup, false);
    }
  }
  for (long left = o.steps; left > 0; left -= o.chunk) {
    long n = std::min(left, o.chunk);
    for (auto &c : urt_cases) {
      if (c->ok()) {
        c->run(n, true);
      }
    }
    for (auto &c : mj_cases) {
      if (c->ok()) {
        c->run(n, true);
      }
    }
  }

  for (auto &c : urt_cases) {
    c->finish();
    const UrtRun &r = c->r;
    if (r.status != "ok") {
      fprintf(stderr, "urt_bench: urt_step at dt=%g: %s\n", r.dt, r.error.c_str());
      rep.urt_status = "error";
      rep.urt_error = r.error;
    } else if (r.step_errors || r.refused_commands || r.pstop) {
      fprintf(stderr,
              "urt_bench: warning: dt=%g: %ld step errors, %ld refused commands, pstop=0x%x "
              "(timings may not be of a moving arm)\n",
              r.dt, r.step_errors, r.refused_commands, r.pstop);
    }
    rep.urt.push_back(r);
  }
  for (auto &c : mj_cases) {
    c->finish();
    if (c->r.status != "ok") {
      fprintf(stderr, "urt_bench: mj_step %s dt=%g: %s\n", c->r.variant->name, c->r.dt,
              c->r.error.c_str());
    }
    rep.mj.push_back(c->r);
  }
  mj_cases.clear();  // before mj (declared earlier) closes the library

  if (!o.mjcf_out.empty()) {
    FILE *f = fopen(o.mjcf_out.c_str(), "w");
    if (f == nullptr || !mj_model ||
        fputs(mjcf_from_model(mj_model.get(), o.dts.front(), kMjVariants[0]).c_str(), f) < 0) {
      fprintf(stderr, "urt_bench: cannot write %s\n", o.mjcf_out.c_str());
    }
    if (f != nullptr) {
      fclose(f);
    }
  }

  if (!o.json.empty()) {
    FILE *f = fopen(o.json.c_str(), "w");
    std::string text = to_json(o, rep);
    if (f == nullptr || fputs(text.c_str(), f) < 0) {
      fprintf(stderr, "urt_bench: cannot write %s: %s\n", o.json.c_str(), strerror(errno));
      if (f != nullptr) {
        fclose(f);
      }
      return 1;
    }
    fclose(f);
  }
  if (!o.quiet) {
    print_table(o, rep);
  }
  if (dma_fd >= 0) {
    close(dma_fd);
  }
  // the core is what is being measured: failing to run it is a failure (2 for a bad config, as
  // every urtwin tool), MuJoCo's absence is not
  if (g_config_error) {
    return 2;
  }
  return rep.urt_status == "error" ? 1 : 0;
}
