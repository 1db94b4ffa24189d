// SPDX-License-Identifier: Apache-2.0
// tools/replay.cpp — urt_sim --replay (tools/replay.h): the recorded set-point through the
// controller (URT_CTRL_SETPOINT, the same interpolation and model feed-forward the emulator
// gives a client's targets) into the physics, then the comparison of currents.
#include "replay.h"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "urt/controller.h"

namespace {

double clock_s(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double now_s() { return clock_s(CLOCK_MONOTONIC); }

// this thread's CPU time: on a shared machine the wall time also counts the other processes'
double cpu_s() { return clock_s(CLOCK_THREAD_CPUTIME_ID); }

// The recorded set-point at time t: the sample itself when t is on one, otherwise between the
// two samples around it (a gap): q by cubic Hermite on (q, q̇) at both ends, q̇ and q̈ linear.
// Without target_qdd in the file, q̈ is the q̇ slope between the two samples.
void setpoint_at(const ReplayRecording &r, size_t *cursor, double t, double q[URT_NJ],
                 double qd[URT_NJ], double qdd[URT_NJ]) {
  size_t n = r.t.size();
  size_t i = *cursor;
  while (i + 1 < n && r.t[i + 1] <= t) {
    i++;
  }
  *cursor = i;
  if (i + 1 >= n || t <= r.t[i]) {  // at (or beyond) a sample: take it
    size_t k = (i + 1 >= n && t > r.t[i]) ? n - 1 : i;
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = r.target_q[k][(size_t)j];
      qd[j] = r.target_qd[k][(size_t)j];
      qdd[j] = r.has_target_qdd ? r.target_qdd[k][(size_t)j]
               : k + 1 < n      ? (r.target_qd[k + 1][(size_t)j] - r.target_qd[k][(size_t)j]) /
                                  (r.t[k + 1] - r.t[k])
                                : 0.0;
    }
    return;
  }
  const double h = r.t[i + 1] - r.t[i], u = (t - r.t[i]) / h;
  const double u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2,
               h11 = u3 - u2;
  for (int j = 0; j < URT_NJ; j++) {
    const size_t jj = (size_t)j;
    double q0 = r.target_q[i][jj], q1 = r.target_q[i + 1][jj];
    double v0 = r.target_qd[i][jj], v1 = r.target_qd[i + 1][jj];
    q[j] = h00 * q0 + h10 * h * v0 + h01 * q1 + h11 * h * v1;
    qd[j] = (1 - u) * v0 + u * v1;
    qdd[j] = r.has_target_qdd ? (1 - u) * r.target_qdd[i][jj] + u * r.target_qdd[i + 1][jj]
                              : (v1 - v0) / h;
  }
}

// Whether the arm stands at time t: all six recorded target_qd are 0 at the sample at or
// before t and, between two samples, at the next one too.
bool arm_holds(const ReplayRecording &r, size_t i, double t) {
  size_t n = r.t.size();
  for (int j = 0; j < URT_NJ; j++) {
    if (r.target_qd[i][(size_t)j] != 0.0) {
      return false;
    }
    if (i + 1 < n && t > r.t[i] && r.target_qd[i + 1][(size_t)j] != 0.0) {
      return false;
    }
  }
  return true;
}

struct Moments {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, see = 0;
  void add(double x, double y) {  // x model, y measured
    n++;
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
    see += (x - y) * (x - y);
  }
  double rms_err() const { return n > 0 ? std::sqrt(see / n) : 0.0; }
  double rms_y() const { return n > 0 ? std::sqrt(syy / n) : 0.0; }
  double corr() const {
    double cxx = sxx - sx * sx / n, cyy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
    return cxx > 0 && cyy > 0 ? cxy / std::sqrt(cxx * cyy) : 0.0;
  }
};

const char *fmt_or_null(char *buf, size_t n, double v) {
  if (!std::isfinite(v)) {
    return "null";
  }
  std::snprintf(buf, n, "%.6g", v);
  return buf;
}

}  // namespace

void replay_limit_overrides(const urt_model_t *m, const ReplayRecording &rec,
                            std::vector<std::string> *out) {
  for (int j = 0; j < URT_NJ; j++) {
    double vmax = 0.0, amax = 0.0;
    for (size_t i = 0; i < rec.t.size(); i++) {
      vmax = std::max(vmax, std::fabs(rec.target_qd[i][(size_t)j]));
      if (rec.has_target_qdd) {
        amax = std::max(amax, std::fabs(rec.target_qdd[i][(size_t)j]));
      }
    }
    char buf[96];
    if (vmax > m->joint[j].qd_max) {
      std::snprintf(buf, sizeof buf, "joints.%d.qd_max=%.4g", j, 1.02 * vmax);
      out->push_back(buf);
    }
    if (amax > m->joint[j].qdd_max) {
      std::snprintf(buf, sizeof buf, "joints.%d.qdd_max=%.4g", j, 1.02 * amax);
      out->push_back(buf);
    }
  }
}

int replay_run(const urt_model_t *m, const ReplayRecording &rec, ReplayResult *res,
               std::string *err) {
  const size_t n = rec.t.size();

  // the period: the recording's own sample interval, as a whole number of physics steps. Not
  // the median: a file that drops samples often (no1.csv has as many 24 ms as 8 ms intervals)
  // would give a multiple of it; the 10th percentile is near the interval itself
  std::vector<double> dts(n - 1);
  for (size_t i = 0; i + 1 < n; i++) {
    dts[i] = rec.t[i + 1] - rec.t[i];
  }
  std::vector<double> sorted = dts;
  std::sort(sorted.begin(), sorted.end());
  const double p10 = sorted[sorted.size() / 10];
  // then the median of the intervals near it, so that a millisecond of logging jitter does not
  // move the period
  std::vector<double> near;
  for (double d : sorted) {
    if (d > 0.5 * p10 && d < 1.5 * p10) {
      near.push_back(d);
    }
  }
  const double interval = near[near.size() / 2];
  const long n_sub = std::max(1L, std::lround(interval / m->dt));
  const double T = (double)n_sub * m->dt;
  res->period = T;
  for (double d : dts) {
    res->max_gap = std::max(res->max_gap, d);
    res->gaps += d > 1.5 * T;
  }

  // the set-point on the controller's grid. The controller ran at a fixed period, but the
  // logged times jitter and drift against it (no1.csv: 6.542, 6.567, 6.574 for ticks 24 ms and
  // 8 ms apart; by 12 s its times are half a period off a grid from t0), and interpolating
  // positions at the logged times feeds velocity errors of up to 0.13 rad/s, which the position
  // gain turns into current spikes of several amperes. So each sample sits the nearest whole
  // number of periods after the previous one; a sample less than half a period after it is
  // dropped.
  static ReplayRecording fed;
  static std::vector<long> tick_of;
  fed = ReplayRecording{};
  fed.has_target_qdd = rec.has_target_qdd;
  tick_of.assign(n, 0);
  long last_k = 0;
  size_t last_i = 0;
  for (size_t i = 0; i < n; i++) {
    long k = i == 0 ? 0 : last_k + std::lround((rec.t[i] - rec.t[last_i]) / T);
    tick_of[i] = std::max(k, last_k);
    if (i > 0 && k <= last_k) {
      res->dropped++;
      continue;
    }
    res->max_time_offset = std::max(res->max_time_offset,
                                    std::fabs(rec.t[i] - rec.t[last_i] - (double)(k - last_k) * T));
    last_k = k;
    last_i = i;
    fed.t.push_back(rec.t[0] + (double)k * T);
    fed.line.push_back(rec.line[i]);
    fed.target_q.push_back(rec.target_q[i]);
    fed.target_qd.push_back(rec.target_qd[i]);
    if (rec.has_target_qdd) {
      fed.target_qdd.push_back(rec.target_qdd[i]);
    }
  }

  // start at rest at the first recorded set-point
  static urt_data_t d;  // ~10 kB: not on the stack
  static urt_ctrl_t c;
  double q0[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    q0[j] = rec.target_q[0][(size_t)j];
  }
  int rc = urt_data_init(m, &d, q0);
  if (rc == 0) {
    rc = urt_ctrl_init(m, &c, &d, T, 1);
  }
  if (rc != 0) {
    *err = std::string("cannot start the twin at the first recorded pose: ") + urt_strerror(rc);
    return 1;
  }

  // the twin on the controller's grid t0 + k T; each recorded sample reads its tick
  const double t0 = rec.t[0];
  const long ticks = last_k;
  std::vector<Joints> grid_q((size_t)ticks + 1), grid_qd((size_t)ticks + 1),
      grid_i((size_t)ticks + 1);
  auto sample = [&](long k) {
    urt_data_update_outputs(m, &d);
    for (int j = 0; j < URT_NJ; j++) {
      grid_q[(size_t)k][(size_t)j] = d.x[j][URT_X_Q];
      grid_qd[(size_t)k][(size_t)j] = d.x[j][URT_X_QD];
      grid_i[(size_t)k][(size_t)j] = d.i_fb[j];
    }
  };
  sample(0);

  const double wall0 = now_s(), cpu0 = cpu_s();
  size_t cursor = 0;
  for (long k = 0; k < ticks; k++) {
    urt_ctrl_cmd_t cmd;
    std::memset(&cmd, 0, sizeof cmd);
    cmd.kind = URT_CTRL_SETPOINT;
    cmd.id = (uint64_t)k + 1;
    setpoint_at(fed, &cursor, t0 + (double)(k + 1) * T, cmd.q, cmd.qd, cmd.pose);
    // A standing arm: UR's controller sets each cycle's target_q to the joint position it
    // measured the cycle before (the shared recordings: in every sample where all six
    // target_qd are 0, target_q equals the previous sample's actual_q to the logged digit), so
    // its drives never hold a position error that stiction leaves, and their speed integrators
    // do not wind up against one. The recorded target_q there is the real robot's position,
    // not a set-point for the twin; the twin gets its own measured position instead, the
    // previous tick's, as the real drive does.
    if (arm_holds(fed, cursor, t0 + (double)(k + 1) * T)) {
      for (int j = 0; j < URT_NJ; j++) {
        cmd.q[j] = d.q_fb[j];
        cmd.qd[j] = 0.0;
        cmd.pose[j] = 0.0;
      }
    }
    urt_ctrl_apply(m, &c, &d, &cmd);
    urt_ctrl_tick(m, &c, &d);
    if (c.safety_mode != URT_SAFETY_MODE_NORMAL) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "t = %.3f s (line %d): the controller refused the set-point (fault 0x%x, "
                    "pstop 0x%x)",
                    t0 + (double)(k + 1) * T, fed.line[std::min(cursor + 1, fed.t.size() - 1)],
                    (unsigned)c.fault, (unsigned)d.pstop);
      *err = buf;
      return 1;
    }
    for (int s = 0; s < c.n_sub; s++) {
      urt_command_t sp;
      urt_ctrl_setpoint(m, &c, s, &sp);
      urt_command_set(m, &d, &sp);
      rc = urt_step(m, &d);
      if (rc != 0) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "t = %.6f s: step failed: %s", d.t, urt_strerror(rc));
        *err = buf;
        return 1;
      }
    }
    sample(k + 1);
  }
  res->wall = now_s() - wall0;
  res->cpu = cpu_s() - cpu0;
  res->ticks = ticks;
  res->steps = (long)d.steps;
  res->refined = (long)d.refined_count;

  // the twin at the recorded samples, and the statistics
  Moments mt[URT_NJ], mu[URT_NJ];
  double lo[URT_NJ], hi[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    lo[j] = hi[j] = rec.target_q[0][(size_t)j];
  }
  res->twin_q.resize(n);
  res->twin_qd.resize(n);
  res->twin_current.resize(n);
  for (size_t i = 0; i < n; i++) {
    long k = tick_of[i];
    res->twin_q[i] = grid_q[(size_t)k];
    res->twin_qd[i] = grid_qd[(size_t)k];
    res->twin_current[i] = grid_i[(size_t)k];
    for (int j = 0; j < URT_NJ; j++) {
      const size_t jj = (size_t)j;
      double meas = rec.actual_current[i][jj];
      mt[j].add(res->twin_current[i][jj], meas);
      if (rec.has_target_current) {
        mu[j].add(rec.target_current[i][jj], meas);
      }
      lo[j] = std::min(lo[j], rec.target_q[i][jj]);
      hi[j] = std::max(hi[j], rec.target_q[i][jj]);
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    ReplayJointStats &s = res->joint[j];
    s.range = hi[j] - lo[j];
    s.moves = s.range > 0.05;
    s.rms_meas = mt[j].rms_y();
    s.rms_err_twin = mt[j].rms_err();
    s.ratio_twin = s.rms_meas > 0 ? s.rms_err_twin / s.rms_meas : NAN;
    s.corr_twin = mt[j].corr();
    if (rec.has_target_current) {
      s.rms_err_ur = mu[j].rms_err();
      s.ratio_ur = s.rms_meas > 0 ? s.rms_err_ur / s.rms_meas : NAN;
      s.corr_ur = mu[j].corr();
    } else {
      s.rms_err_ur = s.ratio_ur = s.corr_ur = NAN;
    }
  }
  return 0;
}

bool replay_write_trace(const std::string &path, const ReplayRecording &rec,
                        const ReplayResult &res, std::string *err) {
  FILE *f = std::fopen(path.c_str(), "w");
  if (!f) {
    *err = path + ": " + std::strerror(errno);
    return false;
  }
  std::setvbuf(f, nullptr, _IOFBF, 1 << 20);
  struct Col {
    const char *name;
    const std::vector<Joints> *v;
  };
  std::vector<Col> cols = {{"target_q", &rec.target_q},        {"target_qd", &rec.target_qd},
                           {"actual_current", &rec.actual_current},
                           {"twin_q", &res.twin_q},            {"twin_qd", &res.twin_qd},
                           {"twin_current", &res.twin_current}};
  if (rec.has_target_current) {
    cols.push_back({"target_current", &rec.target_current});
  }
  if (rec.has_actual_q) {
    cols.push_back({"actual_q", &rec.actual_q});
  }
  if (rec.has_actual_qd) {
    cols.push_back({"actual_qd", &rec.actual_qd});
  }
  std::fputs("timestamp", f);
  for (const Col &c : cols) {
    for (int j = 0; j < URT_NJ; j++) {
      std::fprintf(f, " %s_%d", c.name, j);
    }
  }
  std::fputc('\n', f);
  for (size_t i = 0; i < rec.t.size(); i++) {
    std::fprintf(f, "%.6f", rec.t[i]);
    for (const Col &c : cols) {
      for (int j = 0; j < URT_NJ; j++) {
        std::fprintf(f, " %.9g", (*c.v)[i][(size_t)j]);
      }
    }
    std::fputc('\n', f);
  }
  bool ok = !std::ferror(f);
  ok = std::fclose(f) == 0 && ok;
  if (!ok) {
    *err = path + ": write failed";
  }
  return ok;
}

bool replay_write_json(const std::string &path, const urt_model_t *m, const ReplayRecording &rec,
                       const ReplayResult &res, std::string *err) {
  FILE *f = std::fopen(path.c_str(), "w");
  if (!f) {
    *err = path + ": " + std::strerror(errno);
    return false;
  }
  char b[6][32];
  double dur = rec.t.back() - rec.t.front();
  std::fprintf(f, "{\n  \"file\": \"%s\",\n  \"samples\": %zu,\n  \"duration\": %.6g,\n",
               rec.path.c_str(), rec.t.size(), dur);
  std::fprintf(f, "  \"period\": %.6g,\n  \"gaps\": %ld,\n  \"max_gap\": %.6g,\n", res.period,
               res.gaps, res.max_gap);
  std::fprintf(f, "  \"wall\": %.6g,\n  \"speed\": %.6g,\n", res.wall,
               res.wall > 0 ? dur / res.wall : 0.0);
  std::fprintf(f, "  \"cpu\": %.6g,\n  \"speed_cpu\": %.6g,\n", res.cpu,
               res.cpu > 0 ? dur / res.cpu : 0.0);
  std::fprintf(f, "  \"max_time_offset\": %.6g,\n  \"dropped\": %ld,\n", res.max_time_offset,
               res.dropped);
  std::fprintf(f, "  \"steps\": %ld,\n  \"refined_steps\": %ld,\n  \"joints\": [\n", res.steps,
               res.refined);
  for (int j = 0; j < URT_NJ; j++) {
    const ReplayJointStats &s = res.joint[j];
    std::fprintf(f,
                 "    {\"name\": \"%s\", \"range\": %.6g, \"moves\": %s, \"rms_meas\": %.6g, "
                 "\"rms_err_twin\": %.6g, \"rms_err_ur\": %s, \"ratio_twin\": %s, "
                 "\"ratio_ur\": %s, \"corr_twin\": %.6g, \"corr_ur\": %s}%s\n",
                 m->joint[j].name, s.range, s.moves ? "true" : "false", s.rms_meas,
                 s.rms_err_twin, fmt_or_null(b[0], 32, s.rms_err_ur),
                 fmt_or_null(b[1], 32, s.ratio_twin), fmt_or_null(b[2], 32, s.ratio_ur),
                 s.corr_twin, fmt_or_null(b[3], 32, s.corr_ur), j + 1 < URT_NJ ? "," : "");
  }
  std::fputs("  ]\n}\n", f);
  bool ok = !std::ferror(f);
  ok = std::fclose(f) == 0 && ok;
  if (!ok) {
    *err = path + ": write failed";
  }
  return ok;
}

void replay_print(FILE *f, const urt_model_t *m, const ReplayRecording &rec,
                  const ReplayResult &res) {
  double dur = rec.t.back() - rec.t.front();
  std::fprintf(f,
               "replay of %s: %zu samples, %.3f s, fed every %.4g s (%ld gaps filled, longest "
               "interval %.4g s, intervals up to %.4g s off a whole number of periods, %ld on a taken tick dropped); %.3f s wall, %.1f x real time (%.3f s CPU, %.1f x); %ld of %ld steps refined\n",
               rec.path.c_str(), rec.t.size(), dur, res.period, res.gaps, res.max_gap,
               res.max_time_offset, res.dropped, res.wall, res.wall > 0 ? dur / res.wall : 0.0,
               res.cpu, res.cpu > 0 ? dur / res.cpu : 0.0,
               res.refined, res.steps);
  std::fprintf(f, "%-9s %5s %9s %12s %11s %10s %9s %9s %8s\n", "joint", "moves", "rms_meas",
               "rms_err_twin", "rms_err_ur", "ratio_twin", "ratio_ur", "corr_twin", "corr_ur");
  for (int j = 0; j < URT_NJ; j++) {
    const ReplayJointStats &s = res.joint[j];
    std::fprintf(f, "%-9s %5s %9.4f %12.4f %11.4f %10.3f %9.3f %9.3f %8.3f\n", m->joint[j].name,
                 s.moves ? "yes" : "no", s.rms_meas, s.rms_err_twin, s.rms_err_ur, s.ratio_twin,
                 s.ratio_ur, s.corr_twin, s.corr_ur);
  }
}
