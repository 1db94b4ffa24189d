// SPDX-License-Identifier: Apache-2.0
// tools/urt_sim.cpp — the offline runner: plays a test trajectory (tools/traj.h) through the
// model with the fixed-step scheme (urt_step) or the CVODE reference (urt_reference_step), or
// both side by side (--compare), and writes a CSV trace. With --realtime it paces the loop to
// wall time, standing in for the emulator until that exists (`make run`).
//
//   urt_sim [--config FILE] [--set KEY=VALUE]... [--traj excitation|pickplace|hold] [--seed N]
//           [--duration S] [--rate HZ] [--reference [--rtol R] | --compare] [--decimate N]
//           [--out FILE.csv] [--realtime] [--quiet]
//   urt_sim [--config FILE] [--set KEY=VALUE]... --print-model [--json]
//   urt_sim [--config FILE] [--overlay FILE]... [--set KEY=VALUE]... --replay REC.csv
//           [--out TRACE] [--summary-json OUT] [--plot DIR] [--noise] [--quiet]
//
// Per step: evaluate the trajectory at t = d.t, install it with urt_command_set (q, q̇, q̈,
// no torque feed-forward), write a CSV row of the state at t, then advance one step. Each row
// therefore pairs the set-point and the state at the same instant.
//
// Exit status: 0 success (also when stopped by SIGINT/SIGTERM), 1 run-time failure (solver,
// refused command, I/O), 2 usage, configuration or trajectory error.

#include <errno.h>
#include <getopt.h>
#include <signal.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>

#include "replay.h"
#include "replay_csv.h"
#include "traj.h"
#include "urt/core.h"
#include "urt/reference.h"

extern "C" char **environ;

namespace {

constexpr double kRad2Deg = 180.0 / 3.14159265358979323846;

//---- options ----

struct Options {
  std::string config = "config/ur5.yaml";
  std::vector<std::string> sets;   // --set KEY=VALUE, in order
  std::vector<std::string> overlays;  // --overlay FILE, in order
  std::string replay;              // --replay: a recording to play (tools/replay.h)
  std::string summary_json;        // --summary-json
  std::string plot_dir;            // --plot
  bool noise = false;              // --noise: keep the sensor noise in a replay
  urt_traj_kind_t traj = URT_TRAJ_PICKPLACE;
  uint64_t seed = 1;
  double duration = -1.0;          // < 0: the trajectory's own duration
  double rate = 0.0;               // 0: the config's simulation.dt
  bool reference = false;
  double rtol = 1e-10;
  bool compare = false;
  long decimate = 1;
  std::string faults;              // --faults: a fault scenario file (urt/faults.h)
  std::string out;                 // empty: no CSV
  bool print_model = false;
  bool json = false;
  bool realtime = false;
  bool quiet = false;
};

void usage(FILE *f) {
  std::fputs(
      "usage: urt_sim [options]\n"
      "Play a test trajectory through the UR5 model and write a CSV trace.\n"
      "  -c, --config FILE      robot parameter file (default config/ur5.yaml)\n"
      "      --overlay FILE     apply an overlay (config/README.md) after the config and\n"
      "                         before --set. Repeatable, applied in order.\n"
      "  -s, --set KEY=VALUE    override a config key, e.g. sensors.noise=false or\n"
      "                         joints.4.qdd_max=50 (0-based joint index). Repeatable.\n"
      "  -t, --traj KIND        excitation | pickplace (default) | hold\n"
      "      --seed N           seed of the random excitation (default 1)\n"
      "  -d, --duration S       simulated time [s] (default: the trajectory's duration, 1 s\n"
      "                         for hold; afterwards the end pose is held). With --realtime,\n"
      "                         0 runs until SIGINT/SIGTERM.\n"
      "  -r, --rate HZ          physics rate, e.g. 20000 or 10000; overrides simulation.dt\n"
      "                         (default: the config's simulation.dt, 20 kHz in ur5.yaml)\n"
      "      --reference        integrate with CVODE instead of the fixed-step scheme (slow)\n"
      "      --rtol R           CVODE relative tolerance (default 1e-10)\n"
      "      --compare          run fixed-step and CVODE side by side, print per joint the max\n"
      "                         |dq| [rad], the RMS current error [% of RMS current] and the\n"
      "                         max tracking error |q_set - q| [deg] of each; with --out,\n"
      "                         write both traces (see below)\n"
      "      --decimate N       write every Nth step to the CSV (default 1)\n"
      "      --faults FILE      inject the fault scenario FILE (YAML, core/include/urt/faults.h)\n"
      "                         into the run (both runs with --compare); the CSV gains the\n"
      "                         ground truth per fault: fault<k>_<class>_active, _severity\n"
      "  -o, --out PATH         CSV file to write. With --compare: PATH.csv gives\n"
      "                         PATH.fixed.csv, PATH.reference.csv and PATH.summary.txt;\n"
      "                         any other PATH is a directory that receives fixed.csv,\n"
      "                         reference.csv and summary.txt\n"
      "      --print-model      print the fully resolved model (YAML) and exit\n"
      "      --json             with --print-model: JSON instead of YAML\n"
      "      --realtime         pace the loop to wall time; status line every second\n"
      "  -q, --quiet            no status lines or summary (the --compare table still prints)\n"
      "      --replay FILE      play a recording (RTDE record.py layout: timestamp,\n"
      "                         target_q_*, target_qd_*, actual_current_*; target_qdd_*,\n"
      "                         target_current_*, actual_q_*, actual_qd_* used when there) as\n"
      "                         the controller's set-point, from rest at its first pose, and\n"
      "                         print per joint RMS(measured current), RMS(twin - measured),\n"
      "                         RMS(target_current - measured), their ratios and\n"
      "                         correlations. --out writes the twin beside the recording.\n"
      "                         Sensor noise and quantisation are off unless --noise.\n"
      "      --summary-json OUT with --replay: the table as JSON\n"
      "      --plot DIR         with --replay: per-joint PNGs (tools/plot_replay.py)\n"
      "      --noise            with --replay: keep the sensor noise and quantisation\n"
      "  -h, --help             this text\n"
      "CSV columns: t, per joint j = 1..6: q_set_j q_j qd_j qm_j qdm_j i_j i_meas_j v_j tcs_j\n"
      "tf_j, then tcp_x tcp_y tcp_z tcp_rx tcp_ry tcp_rz (SI units, %.17g).\n"
      "exit status: 0 ok, 1 run-time failure, 2 usage, configuration or trajectory error\n",
      f);
}

// strict numeric parsing: the whole argument must be a finite number
bool parse_double(const char *s, double *out) {
  char *end = nullptr;
  errno = 0;
  double v = std::strtod(s, &end);
  if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
    return false;
  }
  *out = v;
  return true;
}

bool parse_u64(const char *s, uint64_t *out) {
  char *end = nullptr;
  errno = 0;
  if (*s == '-') {
    return false;
  }
  unsigned long long v = std::strtoull(s, &end, 0);
  if (end == s || *end != '\0' || errno == ERANGE) {
    return false;
  }
  *out = v;
  return true;
}

// Returns -1 to go on, otherwise the exit status (0 after --help).
int parse_args(int argc, char **argv, Options *o) {
  enum {
    OPT_SEED = 1000,
    OPT_REFERENCE,
    OPT_RTOL,
    OPT_COMPARE,
    OPT_DECIMATE,
    OPT_PRINT_MODEL,
    OPT_JSON,
    OPT_REALTIME,
    OPT_OVERLAY,
    OPT_REPLAY,
    OPT_SUMMARY_JSON,
    OPT_PLOT,
    OPT_NOISE,
    OPT_FAULTS
  };
  static const struct option options[] = {
      {"config", required_argument, nullptr, 'c'},
      {"set", required_argument, nullptr, 's'},
      {"traj", required_argument, nullptr, 't'},
      {"seed", required_argument, nullptr, OPT_SEED},
      {"duration", required_argument, nullptr, 'd'},
      {"rate", required_argument, nullptr, 'r'},
      {"reference", no_argument, nullptr, OPT_REFERENCE},
      {"rtol", required_argument, nullptr, OPT_RTOL},
      {"compare", no_argument, nullptr, OPT_COMPARE},
      {"decimate", required_argument, nullptr, OPT_DECIMATE},
      {"out", required_argument, nullptr, 'o'},
      {"print-model", no_argument, nullptr, OPT_PRINT_MODEL},
      {"json", no_argument, nullptr, OPT_JSON},
      {"realtime", no_argument, nullptr, OPT_REALTIME},
      {"overlay", required_argument, nullptr, OPT_OVERLAY},
      {"replay", required_argument, nullptr, OPT_REPLAY},
      {"summary-json", required_argument, nullptr, OPT_SUMMARY_JSON},
      {"plot", required_argument, nullptr, OPT_PLOT},
      {"noise", no_argument, nullptr, OPT_NOISE},
      {"faults", required_argument, nullptr, OPT_FAULTS},
      {"quiet", no_argument, nullptr, 'q'},
      {"help", no_argument, nullptr, 'h'},
      {nullptr, 0, nullptr, 0},
  };

  int opt;
  uint64_t u;
  while ((opt = getopt_long(argc, argv, "c:s:t:d:r:o:qh", options, nullptr)) != -1) {
    switch (opt) {
      case 'c':
        o->config = optarg;
        break;
      case 's':
        o->sets.emplace_back(optarg);
        break;
      case 't':
        if (std::strcmp(optarg, "excitation") == 0) {
          o->traj = URT_TRAJ_FOURIER;
        } else if (std::strcmp(optarg, "pickplace") == 0) {
          o->traj = URT_TRAJ_PICKPLACE;
        } else if (std::strcmp(optarg, "hold") == 0) {
          o->traj = URT_TRAJ_HOLD;
        } else {
          std::fprintf(stderr, "urt_sim: --traj: expected excitation, pickplace or hold, got "
                               "'%s'\n", optarg);
          return 2;
        }
        break;
      case OPT_SEED:
        if (!parse_u64(optarg, &o->seed)) {
          std::fprintf(stderr, "urt_sim: --seed: expected an unsigned integer, got '%s'\n",
                       optarg);
          return 2;
        }
        break;
      case 'd':
        if (!parse_double(optarg, &o->duration) || o->duration < 0.0) {
          std::fprintf(stderr, "urt_sim: --duration: expected seconds >= 0, got '%s'\n", optarg);
          return 2;
        }
        break;
      case 'r':
        if (!parse_double(optarg, &o->rate) || o->rate <= 0.0) {
          std::fprintf(stderr, "urt_sim: --rate: expected a rate > 0 Hz, got '%s'\n", optarg);
          return 2;
        }
        break;
      case OPT_REFERENCE:
        o->reference = true;
        break;
      case OPT_RTOL:
        if (!parse_double(optarg, &o->rtol) || o->rtol <= 0.0) {
          std::fprintf(stderr, "urt_sim: --rtol: expected a tolerance > 0, got '%s'\n", optarg);
          return 2;
        }
        break;
      case OPT_COMPARE:
        o->compare = true;
        break;
      case OPT_DECIMATE:
        if (!parse_u64(optarg, &u) || u < 1 || u > 1000000000u) {
          std::fprintf(stderr, "urt_sim: --decimate: expected an integer >= 1, got '%s'\n",
                       optarg);
          return 2;
        }
        o->decimate = (long)u;
        break;
      case 'o':
        o->out = optarg;
        break;
      case OPT_PRINT_MODEL:
        o->print_model = true;
        break;
      case OPT_JSON:
        o->json = true;
        break;
      case OPT_REALTIME:
        o->realtime = true;
        break;
      case OPT_OVERLAY:
        o->overlays.emplace_back(optarg);
        break;
      case OPT_REPLAY:
        o->replay = optarg;
        break;
      case OPT_SUMMARY_JSON:
        o->summary_json = optarg;
        break;
      case OPT_PLOT:
        o->plot_dir = optarg;
        break;
      case OPT_NOISE:
        o->noise = true;
        break;
      case OPT_FAULTS:
        o->faults = optarg;
        break;
      case 'q':
        o->quiet = true;
        break;
      case 'h':
        usage(stdout);
        return 0;
      default:
        usage(stderr);
        return 2;
    }
  }
  if (optind < argc) {
    std::fprintf(stderr, "urt_sim: unexpected argument '%s'\n", argv[optind]);
    usage(stderr);
    return 2;
  }

  // combinations that cannot work
  if (o->reference && o->compare) {
    std::fprintf(stderr, "urt_sim: --compare already runs the reference; drop --reference\n");
    return 2;
  }
  if (o->realtime && (o->reference || o->compare)) {
    std::fprintf(stderr, "urt_sim: CVODE runs far slower than real time: --realtime cannot be "
                         "combined with --reference or --compare\n");
    return 2;
  }
  if (!o->replay.empty() && !o->faults.empty()) {
    std::fprintf(stderr, "urt_sim: --faults is not supported with --replay (a replay plays a "
                         "recording of a healthy robot): drop one of them\n");
    return 2;
  }
  if (!o->replay.empty() && (o->compare || o->reference || o->realtime || o->print_model)) {
    std::fprintf(stderr, "urt_sim: --replay runs the fixed-step model offline: drop --compare, "
                         "--reference, --realtime and --print-model\n");
    return 2;
  }
  if (o->replay.empty() && (!o->summary_json.empty() || !o->plot_dir.empty() || o->noise)) {
    std::fprintf(stderr, "urt_sim: --summary-json, --plot and --noise go with --replay\n");
    return 2;
  }
  if (o->duration == 0.0 && !o->realtime) {
    std::fprintf(stderr, "urt_sim: --duration 0 (run until stopped) needs --realtime\n");
    return 2;
  }
  return -1;
}

//---- time and signals ----

volatile sig_atomic_t g_stop = 0;

void on_signal(int) { g_stop = 1; }

int64_t now_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

//---- CSV ----

// One trace file; rows are written straight from urt_data_t.
class Csv {
 public:
  ~Csv() { close(); }

  bool open(const std::string &path, const urt_fault_scenario_t &faults) {
    f_ = std::fopen(path.c_str(), "w");
    if (!f_) {
      std::fprintf(stderr, "urt_sim: %s: %s\n", path.c_str(), std::strerror(errno));
      return false;
    }
    path_ = path;
    // a big buffer: rows are ~1.5 kB and there are 20 000 of them per simulated second
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
    std::fputs("t", f_);
    static const char *const cols[] = {"q_set", "q",      "qd", "qm",  "qdm",
                                       "i",     "i_meas", "v",  "tcs", "tf"};
    for (int j = 1; j <= URT_NJ; j++) {
      for (const char *c : cols) {
        std::fprintf(f_, ",%s_%d", c, j);
      }
    }
    std::fputs(",tcp_x,tcp_y,tcp_z,tcp_rx,tcp_ry,tcp_rz", f_);
    // ground truth, one pair per fault of the scenario: numbered, so that two faults of one
    // class stay apart
    nfaults_ = faults.n;
    for (int k = 0; k < faults.n; k++) {
      const char *c = urt_fault_class_name(faults.f[k].cls);
      std::fprintf(f_, ",fault%d_%s_active,fault%d_%s_severity", k, c, k, c);
    }
    std::fputc('\n', f_);
    return true;
  }

  bool is_open() const { return f_ != nullptr; }

  // %.17g round-trips every double, so the same seed gives a bit-identical file
  void row(const urt_data_t &d) {
    std::fprintf(f_, "%.17g", d.t);
    for (int j = 0; j < URT_NJ; j++) {
      const double *x = d.x[j];
      std::fprintf(f_, ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g",
                   d.cmd.q[j], x[URT_X_Q], x[URT_X_QD], x[URT_X_QM], x[URT_X_QDM], x[URT_X_I],
                   d.i_fb[j], d.v_sup[j], d.t_cs[j], d.t_f[j]);
    }
    for (int k = 0; k < 6; k++) {
      std::fprintf(f_, ",%.17g", d.tcp_pose[k]);
    }
    for (int k = 0; k < nfaults_; k++) {
      std::fprintf(f_, ",%d,%.17g", (int)d.faults.active[k], d.faults.severity[k]);
    }
    std::fputc('\n', f_);
  }

  // Returns false (with a message) if anything failed to reach the file.
  bool close() {
    if (!f_) {
      return true;
    }
    bool ok = !std::ferror(f_);
    ok = std::fclose(f_) == 0 && ok;
    f_ = nullptr;
    if (!ok) {
      std::fprintf(stderr, "urt_sim: %s: write failed\n", path_.c_str());
    }
    return ok;
  }

 private:
  FILE *f_ = nullptr;
  std::string path_;
  int nfaults_ = 0;
};

//---- one simulated robot: fixed-step or CVODE ----

struct Sim {
  const char *name = "fixed";       // "fixed" or "reference"
  urt_data_t d;
  urt_reference_t *ref = nullptr;   // non-NULL: step with CVODE
  Csv csv;
  double track_max[URT_NJ] = {0};   // max |q_set − q| [rad]
  int64_t step_ns_sum = 0, step_ns_max = 0;

  ~Sim() { urt_reference_free(ref); }

  int step(const urt_model_t *m) {
    int64_t t0 = now_ns();
    int rc = ref ? urt_reference_step(ref, m, &d) : urt_step(m, &d);
    int64_t dt = now_ns() - t0;
    step_ns_sum += dt;
    step_ns_max = dt > step_ns_max ? dt : step_ns_max;
    return rc;
  }

  void track() {
    for (int j = 0; j < URT_NJ; j++) {
      double e = std::fabs(d.cmd.q[j] - d.x[j][URT_X_Q]);
      track_max[j] = e > track_max[j] ? e : track_max[j];
    }
  }
};

// Names of the protective-stop bits, for the message when a command is refused.
std::string pstop_text(uint32_t bits) {
  char buf[160];
  return urt_pstop_text(bits, buf, sizeof buf);
}

// Output paths of --compare: PATH.csv → PATH.{fixed,reference}.csv, else a directory.
bool compare_paths(const std::string &out, std::string *fixed, std::string *ref,
                   std::string *summary) {
  const std::string ext = ".csv";
  if (out.size() > ext.size() && out.compare(out.size() - ext.size(), ext.size(), ext) == 0) {
    std::string stem = out.substr(0, out.size() - ext.size());
    *fixed = stem + ".fixed.csv";
    *ref = stem + ".reference.csv";
    *summary = stem + ".summary.txt";
    return true;
  }
  if (mkdir(out.c_str(), 0777) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "urt_sim: %s: %s\n", out.c_str(), std::strerror(errno));
    return false;
  }
  *fixed = out + "/fixed.csv";
  *ref = out + "/reference.csv";
  *summary = out + "/summary.txt";
  return true;
}

//---- the run ----

struct CompareStats {
  double dq_max[URT_NJ] = {0};      // max |q_fixed − q_ref| [rad]
  double di2[URT_NJ] = {0};         // Σ (i_fixed − i_ref)²
  double i2[URT_NJ] = {0};          // Σ i_ref²
  uint64_t n = 0;                   // samples in the sums

  // the same after the paper's 10 Hz low-pass (two causal first-order stages on both traces,
  // so both see the same lag)
  double lp_f[URT_NJ][2] = {{0}}, lp_r[URT_NJ][2] = {{0}};
  double di2_lp[URT_NJ] = {0}, i2_lp[URT_NJ] = {0};

  void add(int j, double i_fixed, double i_ref, double a) {
    di2[j] += (i_fixed - i_ref) * (i_fixed - i_ref);
    i2[j] += i_ref * i_ref;
    if (n == 1) {
      lp_f[j][0] = lp_f[j][1] = i_fixed;
      lp_r[j][0] = lp_r[j][1] = i_ref;
    }
    lp_f[j][0] = a * lp_f[j][0] + (1.0 - a) * i_fixed;
    lp_f[j][1] = a * lp_f[j][1] + (1.0 - a) * lp_f[j][0];
    lp_r[j][0] = a * lp_r[j][0] + (1.0 - a) * i_ref;
    lp_r[j][1] = a * lp_r[j][1] + (1.0 - a) * lp_r[j][0];
    di2_lp[j] += (lp_f[j][1] - lp_r[j][1]) * (lp_f[j][1] - lp_r[j][1]);
    i2_lp[j] += lp_r[j][1] * lp_r[j][1];
  }
};

void print_compare(FILE *f, const urt_model_t *m, const Sim &fx, const Sim &rf,
                   const CompareStats &c, double rtol, uint64_t steps) {
  std::fprintf(f, "fixed-step (dt = %.6g s) against CVODE (rtol = %.3g, %ld internal steps), "
                  "%" PRIu64 " steps, t = %.6g s\n",
               m->dt, rtol, urt_reference_nsteps(rf.ref), steps, fx.d.t);
  std::fprintf(f, "%-10s %14s %14s %14s %14s %18s %18s\n", "joint", "max|dq| [rad]",
               "i RMS [A]", "i err RMS [%]", "10 Hz LP [%]", "track fixed [deg]",
               "track ref [deg]");
  for (int j = 0; j < URT_NJ; j++) {
    double pct = c.i2[j] > 0.0 ? 100.0 * std::sqrt(c.di2[j] / c.i2[j]) : 0.0;
    double pct_lp = c.i2_lp[j] > 0.0 ? 100.0 * std::sqrt(c.di2_lp[j] / c.i2_lp[j]) : 0.0;
    double rms = c.n > 0 ? std::sqrt(c.i2[j] / (double)c.n) : 0.0;
    std::fprintf(f, "%-10s %14.4e %14.4f %14.4f %14.4f %18.6f %18.6f\n", m->joint[j].name,
                 c.dq_max[j], rms, pct, pct_lp, fx.track_max[j] * kRad2Deg,
                 rf.track_max[j] * kRad2Deg);
  }
}

// Play tr through m (one or two simulations), write the traces and report. Returns the exit
// status. The simulations are locals, so their CVODE memory is gone before m is freed.
int run(const Options &o, const urt_model_t *m, const urt_traj_t *tr,
        const urt_fault_scenario_t &faults) {
  int rc;

  // how many steps: 0 with --realtime means until a signal
  double duration = o.duration >= 0.0 ? o.duration : urt_traj_duration(tr);
  bool forever = o.realtime && duration == 0.0;
  uint64_t nsteps = forever ? UINT64_MAX : (uint64_t)std::llround(duration / m->dt);

  // one or two simulations from the same transient-free start
  Sim fixed_sim, ref_sim;
  std::vector<Sim *> sims;
  fixed_sim.name = o.reference ? "reference" : "fixed";
  sims.push_back(&fixed_sim);
  if (o.compare) {
    ref_sim.name = "reference";
    sims.push_back(&ref_sim);
  }
  for (Sim *s : sims) {
    rc = urt_data_init(m, &s->d, nullptr);
    if (rc != 0) {
      std::fprintf(stderr, "urt_sim: urt_data_init: %s\n", urt_strerror(rc));
      return 1;
    }
    rc = urt_data_set_faults(m, &s->d, &faults);
    if (rc != 0) {
      std::fprintf(stderr, "urt_sim: urt_data_set_faults: %s\n", urt_strerror(rc));
      return 1;
    }
  }
  if (o.reference || o.compare) {
    Sim *s = o.compare ? &ref_sim : &fixed_sim;
    rc = urt_reference_create(m, &s->d, o.rtol, &s->ref);
    if (rc != 0) {
      std::fprintf(stderr, "urt_sim: urt_reference_create: %s\n", urt_strerror(rc));
      return 1;
    }
  }

  // output files
  std::string summary_path;
  if (!o.out.empty()) {
    bool ok;
    if (o.compare) {
      std::string pf, pr;
      ok = compare_paths(o.out, &pf, &pr, &summary_path) && fixed_sim.csv.open(pf, faults) &&
           ref_sim.csv.open(pr, faults);
    } else {
      ok = fixed_sim.csv.open(o.out, faults);
    }
    if (!ok) {
      return 1;
    }
  }

  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  // real-time pacing: sleep to an absolute deadline after every batch of steps worth >= 1 ms,
  // which keeps the sleep count (and its jitter) low at 20 kHz
  const int64_t dt_ns = std::llround(m->dt * 1e9);
  const uint64_t batch = std::max<int64_t>(1, std::llround(1e-3 / m->dt));
  int64_t wall0 = now_ns(), next_ns = wall0, next_status = wall0 + 1000000000;
  uint64_t overruns = 0;
  CompareStats cmp;
  int status = 0;
  uint64_t k = 0;

  for (;; k++) {
    // the set-point at t = d.t, installed on every simulation
    urt_command_t cmd;
    std::memset(&cmd, 0, sizeof cmd);
    urt_traj_eval(tr, fixed_sim.d.t, cmd.q, cmd.qd, cmd.qdd);
    for (Sim *s : sims) {
      if (urt_command_set(m, &s->d, &cmd) != 0) {
        std::fprintf(stderr, "urt_sim: %s: t = %.9g s: command refused (%s)\n", s->name,
                     s->d.t, pstop_text(s->d.pstop).c_str());
        status = 1;
      }
    }
    if (status) {
      break;
    }

    // record the state at t together with the set-point at t
    for (Sim *s : sims) {
      s->track();
      if (s->csv.is_open() && (k % (uint64_t)o.decimate == 0 || k == nsteps)) {
        // urt_step leaves torques, measurements and the TCP pose to the sampling rate
        urt_data_update_outputs(m, &s->d);
        s->csv.row(s->d);
      }
    }
    if (o.compare) {
      cmp.n++;
      for (int j = 0; j < URT_NJ; j++) {
        const double *xf = fixed_sim.d.x[j], *xr = ref_sim.d.x[j];
        cmp.dq_max[j] = std::max(cmp.dq_max[j], std::fabs(xf[URT_X_Q] - xr[URT_X_Q]));
        cmp.add(j, xf[URT_X_I], xr[URT_X_I], std::exp(-2.0 * M_PI * 10.0 * m->dt));
      }
    }
    if (k == nsteps || g_stop) {
      break;
    }

    // advance
    for (Sim *s : sims) {
      rc = s->step(m);
      if (rc != 0) {
        std::fprintf(stderr, "urt_sim: %s: t = %.9g s: step failed: %s (pstop: %s)\n", s->name,
                     s->d.t, urt_strerror(rc), pstop_text(s->d.pstop).c_str());
        status = 1;
      }
    }
    if (status) {
      break;
    }

    // pace to wall time; after an overrun of more than 100 ms, skip ahead instead of racing
    // to catch up
    if (o.realtime && (k + 1) % batch == 0) {
      next_ns += (int64_t)batch * dt_ns;
      int64_t now = now_ns();
      if (now > next_ns) {
        overruns++;
        if (now - next_ns > 100000000) {
          next_ns = now;
        }
      } else {
        struct timespec ts = {(time_t)(next_ns / 1000000000), (long)(next_ns % 1000000000)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR &&
               !g_stop) {
        }
      }
    }

    // a status line every wall-clock second in real time, every 5 s offline (a CVODE run
    // takes minutes); the clock is read once per batch, not per step
    if (!o.quiet && (k + 1) % batch == 0) {
      int64_t now = now_ns();
      if (now >= next_status) {
        const Sim &s = fixed_sim;
        std::fprintf(stderr, "t %9.3f s  steps %10" PRIu64 "  step avg %7.2f us max %8.2f us",
                     s.d.t, k + 1, 1e-3 * (double)s.step_ns_sum / (double)(k + 1),
                     1e-3 * (double)s.step_ns_max);
        if (o.realtime) {
          std::fprintf(stderr, "  overruns %" PRIu64, overruns);
        }
        std::fprintf(stderr, "  q [deg]");
        for (int j = 0; j < URT_NJ; j++) {
          std::fprintf(stderr, " %8.3f", s.d.x[j][URT_X_Q] * kRad2Deg);
        }
        std::fputc('\n', stderr);
        next_status = now + (o.realtime ? 1 : 5) * (int64_t)1000000000;
      }
    }
  }
  double wall = 1e-9 * (double)(now_ns() - wall0);

  // close the traces before reporting, so a write error shows in the exit status
  for (Sim *s : sims) {
    if (!s->csv.close()) {
      status = 1;
    }
  }

  // report
  if (o.compare) {
    print_compare(stdout, m, fixed_sim, ref_sim, cmp, o.rtol, k);
    if (!summary_path.empty()) {
      FILE *f = std::fopen(summary_path.c_str(), "w");
      if (f) {
        print_compare(f, m, fixed_sim, ref_sim, cmp, o.rtol, k);
      }
      if (!f || std::fclose(f) != 0) {
        std::fprintf(stderr, "urt_sim: %s: write failed\n", summary_path.c_str());
        status = 1;
      }
    }
  }
  if (!o.quiet) {
    const Sim &s = fixed_sim;
    std::printf("%s trajectory, %s, %.6g s simulated in %" PRIu64 " steps of %.6g s, wall %.3f s "
                "(%.2f x real time)\n",
                urt_traj_kind_name(tr->kind), s.name, s.d.t, k, m->dt, wall,
                wall > 0.0 ? s.d.t / wall : 0.0);
    if (k > 0) {
      std::printf("step cost (%s): mean %.2f us, max %.2f us%s\n", s.name,
                  1e-3 * s.step_ns_sum / (double)k, 1e-3 * s.step_ns_max,
                  o.realtime ? "" : " (offline, no CPU isolation)");
    }
    if (o.realtime) {
      std::printf("overruns: %" PRIu64 " of %" PRIu64 " batches of %" PRIu64 " steps\n", overruns,
                  k / batch, batch);
    }
    std::printf("max tracking error |q_set - q| [deg]:");
    for (int j = 0; j < URT_NJ; j++) {
      std::printf(" %s %.5g", m->joint[j].name, s.track_max[j] * kRad2Deg);
    }
    std::printf("\n");
  }

  return status;
}

//---- --replay ----

// tools/plot_replay.py with the project's venv (URT_PYTHON overrides); its exit status
int run_plot(const std::string &trace, const std::string &dir) {
  std::string py = std::getenv("URT_PYTHON") ? std::getenv("URT_PYTHON") : "";
  if (py.empty()) {
    std::string venv = std::string(URT_SOURCE_DIR) + "/.venv/bin/python";
    py = access(venv.c_str(), X_OK) == 0 ? venv : "python3";
  }
  std::string script = std::string(URT_SOURCE_DIR) + "/tools/plot_replay.py";
  std::vector<std::string> args = {py, script, trace, "--out", dir};
  std::vector<char *> argv;
  for (std::string &a : args) {
    argv.push_back(&a[0]);
  }
  argv.push_back(nullptr);
  pid_t pid;
  if (posix_spawnp(&pid, py.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
    std::fprintf(stderr, "urt_sim: --plot: cannot run %s: %s\n", py.c_str(),
                 std::strerror(errno));
    return 1;
  }
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(st) ? WEXITSTATUS(st) : 1;
}

int run_replay(const Options &o, const urt_model_t *m, const ReplayRecording &rec) {
  std::string err;
  static ReplayResult res;
  if (replay_run(m, rec, &res, &err) != 0) {
    std::fprintf(stderr, "urt_sim: %s: %s\n", o.replay.c_str(), err.c_str());
    return 1;
  }
  if (!o.quiet) {
    replay_print(stdout, m, rec, res);
  }
  std::string trace = o.out;
  if (trace.empty() && !o.plot_dir.empty()) {
    if (mkdir(o.plot_dir.c_str(), 0777) != 0 && errno != EEXIST) {
      std::fprintf(stderr, "urt_sim: %s: %s\n", o.plot_dir.c_str(), std::strerror(errno));
      return 1;
    }
    trace = o.plot_dir + "/replay.txt";
  }
  if (!trace.empty() && !replay_write_trace(trace, rec, res, &err)) {
    std::fprintf(stderr, "urt_sim: %s\n", err.c_str());
    return 1;
  }
  if (!o.summary_json.empty() && !replay_write_json(o.summary_json, m, rec, res, &err)) {
    std::fprintf(stderr, "urt_sim: %s\n", err.c_str());
    return 1;
  }
  if (!o.plot_dir.empty() && run_plot(trace, o.plot_dir) != 0) {
    std::fprintf(stderr, "urt_sim: --plot: tools/plot_replay.py failed\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  Options o;
  int rc = parse_args(argc, argv, &o);
  if (rc >= 0) {
    return rc;
  }

  // load the model; --rate goes last so that it wins over a --set of the same key; a replay
  // runs without sensor noise and without the encoders' quantisation unless asked (first, so
  // that a --set can still turn them on). A replay predicts the current; the quantisers are
  // part of the sensor noise: the joint encoder's count (2.4e-5 rad) through the position
  // loop (p_pos·p_vel = 7500 A/rad on the shoulder) is a ±0.1 A ripple in the twin's current,
  // uncorrelated with the real robot's own noise. Replaying urtwin's own noise-free excitation
  // recording, the wrists' RMS error is 0.085–0.11 A with the quantisers and 0.017 A without.
  std::vector<std::string> sets;
  const size_t n_quiet = !o.replay.empty() && !o.noise ? 2 : 0;
  if (n_quiet) {
    sets.emplace_back("sensors.noise=false");
    sets.emplace_back("sensors.quantise=false");
  }
  sets.insert(sets.end(), o.sets.begin(), o.sets.end());
  if (o.rate > 0.0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "simulation.dt=%.17g", 1.0 / o.rate);
    sets.emplace_back(buf);
  }
  std::vector<const char *> overrides;
  for (const std::string &s : sets) {
    overrides.push_back(s.c_str());
  }
  overrides.push_back(nullptr);
  urt_model_t *m = nullptr;
  char err[1024];
  std::vector<const char *> overlays;
  for (const std::string &s : o.overlays) {
    overlays.push_back(s.c_str());
  }
  overlays.push_back(nullptr);
  rc = urt_model_load_overlays(o.config.c_str(), overlays.data(), overrides.data(), &m, err,
                               sizeof err);
  if (rc != 0) {
    std::fprintf(stderr, "%s\n", err);
    return 2;
  }
  if (o.print_model) {
    urt_model_print(m, stdout, o.json ? 1 : 0);
    urt_model_free(m);
    return std::fflush(stdout) == 0 ? 0 : 1;
  }

  if (!o.replay.empty()) {
    // the recording is what the real robot followed: a speed or acceleration above the
    // model's command limits (proposed values, config/README.md) raises them for this replay,
    // with a note, rather than stopping it (a later --set still wins)
    static ReplayRecording rec;
    std::string rerr;
    if (replay_csv_read(o.replay, &rec, &rerr) != 0) {
      std::fprintf(stderr, "%s\n", rerr.c_str());
      urt_model_free(m);
      return 2;
    }
    std::vector<std::string> raised;
    replay_limit_overrides(m, rec, &raised);
    if (!raised.empty()) {
      urt_model_free(m);
      m = nullptr;
      std::vector<std::string> sets2(sets.begin(), sets.begin() + (long)n_quiet);
      for (const std::string &r : raised) {
        std::fprintf(stderr, "urt_sim: note: the recording exceeds a command limit: --set %s\n",
                     r.c_str());
        sets2.push_back(r);
      }
      sets2.insert(sets2.end(), sets.begin() + (long)n_quiet, sets.end());
      std::vector<const char *> ov2;
      for (const std::string &s : sets2) {
        ov2.push_back(s.c_str());
      }
      ov2.push_back(nullptr);
      rc = urt_model_load_overlays(o.config.c_str(), overlays.data(), ov2.data(), &m, err,
                                   sizeof err);
      if (rc != 0) {
        std::fprintf(stderr, "%s\n", err);
        return 2;
      }
    }
    rc = run_replay(o, m, rec);
    urt_model_free(m);
    return rc;
  }

  // the trajectory starts where the model starts, and must pass the model's command limits
  static urt_traj_t tr;
  switch (o.traj) {
    case URT_TRAJ_FOURIER:
      rc = urt_traj_make_excitation(&tr, m->q0, nullptr, o.seed);
      break;
    case URT_TRAJ_PICKPLACE:
      rc = urt_traj_make_pickplace(&tr, m->q0);
      break;
    case URT_TRAJ_HOLD:
    default:
      urt_traj_make_hold(&tr, m->q0, 1.0);
      rc = 0;
      break;
  }
  if (rc == 0) {
    rc = urt_traj_check(&tr, m, err, sizeof err);
    if (rc != 0) {
      std::fprintf(stderr,
                   "urt_sim: %s\n"
                   "urt_sim: the model would refuse this trajectory; raise the limit with "
                   "--set joints.<0-based index>.<limit>=VALUE or pick another trajectory\n",
                   err);
    }
  } else {
    std::fprintf(stderr, "urt_sim: cannot build the %s trajectory from the model's q0\n",
                 urt_traj_kind_name(o.traj));
  }
  if (rc != 0) {
    urt_model_free(m);
    return 2;
  }

  // the fault scenario, validated against this model (a bad file: its error, exit 2)
  urt_fault_scenario_t faults;
  std::memset(&faults, 0, sizeof faults);
  if (!o.faults.empty()) {
    rc = urt_faults_load(m, o.faults.c_str(), &faults, err, sizeof err);
    if (rc != 0) {
      std::fprintf(stderr, "%s\n", err);
      urt_model_free(m);
      return 2;
    }
  }

  rc = run(o, m, &tr, faults);
  urt_model_free(m);
  return rc;
}
