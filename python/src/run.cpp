// SPDX-License-Identifier: Apache-2.0
// python/src/run.cpp — see run.hpp. The loop is urt_sim's (tools/urt_sim.cpp, run()): per
// step, evaluate the set-point at t = d.t, install it with urt_command_set, record the state
// at t (every decimate-th step and the last), then advance one urt_step.
#include "run.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "urt/drivers/friction.h"

namespace urtpy {

namespace {

int64_t now_ns(clockid_t clock = CLOCK_MONOTONIC) {
  struct timespec ts;
  clock_gettime(clock, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

// The controller's thermal model (core/controller_thermal.cpp) stepped at its 500 Hz period
// from the current the physics ran; without a controller here, the run keeps its own copy.
constexpr double kThermalPeriod = 0.002;

enum Ch {
  CH_T,
  CH_Q_SET, CH_QD_SET, CH_QDD_SET,
  CH_Q, CH_QD, CH_QM, CH_QDM, CH_I, CH_I_MEAS, CH_V, CH_TCS, CH_TF,
  CH_TIN, CH_I_REF, CH_Q_MEAS, CH_QDM_MEAS, CH_QD_MEAS, CH_QDD, CH_Z, CH_I_TARGET, CH_TEMP,
  CH_TCP, CH_PSTOP,
  CH_COUNT
};

std::vector<Channel> make_channels() {
  struct Def { const char *name; int width; const char *unit; const char *what; };
  static const Def defs[CH_COUNT] = {
      {"t", 1, "s", "simulation time"},
      {"q_set", URT_NJ, "rad", "position set-point (urt_command_t.q)"},
      {"qd_set", URT_NJ, "rad/s", "speed set-point"},
      {"qdd_set", URT_NJ, "rad/s^2", "acceleration set-point"},
      {"q", URT_NJ, "rad", "joint angle (true)"},
      {"qd", URT_NJ, "rad/s", "joint speed (true)"},
      {"qm", URT_NJ, "rad", "motor angle (true)"},
      {"qdm", URT_NJ, "rad/s", "motor speed (true)"},
      {"i", URT_NJ, "A", "motor current (true)"},
      {"i_meas", URT_NJ, "A", "measured motor current"},
      {"v", URT_NJ, "V", "motor voltage"},
      {"tcs", URT_NJ, "N m", "gear output torque T_CS"},
      {"tf", URT_NJ, "N m", "friction torque"},
      {"tin", URT_NJ, "N m", "wave-generator input torque"},
      {"i_ref", URT_NJ, "A", "current reference of the PI cascade"},
      {"q_meas", URT_NJ, "rad", "measured joint position (joint encoder)"},
      {"qdm_meas", URT_NJ, "rad/s", "measured motor speed (motor encoder)"},
      {"qd_meas", URT_NJ, "rad/s", "measured joint speed: qdm_meas / gear ratio"},
      {"qdd", URT_NJ, "rad/s^2", "mean joint acceleration over the last step"},
      {"z", URT_NJ, "rad", "LuGre bristle deflection"},
      {"i_target", URT_NJ, "A",
       "target current: (RNEA of the set-point + steady friction) / (k_t N), as the snapshot"},
      {"temperature", URT_NJ, "degC", "motor winding temperature (the controller's model)"},
      {"tcp", 6, "m, rad", "TCP pose x y z rx ry rz (urt_data_update_outputs)"},
      {"pstop", 1, "-", "protective-stop bits (URT_PSTOP_*)"},
  };
  std::vector<Channel> out;
  int off = 0;
  for (const Def &d : defs) {
    out.push_back({d.name, off, d.width, d.unit, d.what});
    off += d.width;
  }
  // the fault truth (urt_faults_truth), per class whether or not the run has faults, so that
  // every run has the same columns; the names live as long as the process (channels() is static)
  static std::vector<std::string> names;
  const int nc = urt_fault_class_count();
  names.reserve(2 * (size_t)nc);
  for (int c = 0; c < nc; c++) {
    names.push_back(std::string("fault_active_") + urt_fault_class_name(c));
  }
  for (int c = 0; c < nc; c++) {
    names.push_back(std::string("severity_") + urt_fault_class_name(c));
  }
  for (int c = 0; c < nc; c++) {
    out.push_back({names[(size_t)c].c_str(), off++, 1, "-",
                   "1 if a fault of this class is active at this sample, else 0"});
  }
  for (int c = 0; c < nc; c++) {
    // encoder classes mix units by component (rad, rad/s, ...): the spec's unit applies
    out.push_back({names[(size_t)(nc + c)].c_str(), off++, 1, "class unit",
                   "severity now of this class's active fault; of several active ones, the "
                   "one with the largest |severity|; 0 when none is active"});
  }
  out.push_back({"health_index", off++, 1, "-",
                 "1 - max over active faults of |severity| / the larger |bound| of the class's "
                 "range (urt_fault_severity_range), clamped to [0, 1]; 1 when none is active"});
  return out;
}

// Where the truth columns start (after the physical channels).
int truth_offset(const std::vector<Channel> &ch) { return ch[CH_COUNT].offset; }

std::string pstop_text(uint32_t bits) {
  char buf[160];
  return urt_pstop_text(bits, buf, sizeof buf);
}

void put6(double *row, const std::vector<Channel> &ch, int c, const double *v) {
  std::memcpy(row + ch[c].offset, v, sizeof(double) * URT_NJ);
}

void record(const urt_model_t *m, const urt_data_t &d, const double temp[URT_NJ],
            const std::vector<Channel> &ch, double *row) {
  row[ch[CH_T].offset] = d.t;
  put6(row, ch, CH_Q_SET, d.cmd.q);
  put6(row, ch, CH_QD_SET, d.cmd.qd);
  put6(row, ch, CH_QDD_SET, d.cmd.qdd);
  double tau_id[URT_NJ];
  urt_arm_rnea_payload(m, &d.live.payload, d.cmd.q, d.cmd.qd, d.cmd.qdd, tau_id);
  for (int j = 0; j < URT_NJ; j++) {
    const double *x = d.x[j];
    const double ratio = m->gear[j].ratio, kt = m->motor[j].kt;
    row[ch[CH_Q].offset + j] = x[URT_X_Q];
    row[ch[CH_QD].offset + j] = x[URT_X_QD];
    row[ch[CH_QM].offset + j] = x[URT_X_QM];
    row[ch[CH_QDM].offset + j] = x[URT_X_QDM];
    row[ch[CH_I].offset + j] = x[URT_X_I];
    row[ch[CH_I_MEAS].offset + j] = d.i_fb[j];
    row[ch[CH_V].offset + j] = d.v_sup[j];
    row[ch[CH_TCS].offset + j] = d.t_cs[j];
    row[ch[CH_TF].offset + j] = d.t_f[j];
    row[ch[CH_TIN].offset + j] = d.t_in[j];
    row[ch[CH_I_REF].offset + j] = d.i_ref[j];
    row[ch[CH_Q_MEAS].offset + j] = d.q_fb[j];
    row[ch[CH_QDM_MEAS].offset + j] = d.qdm_fb[j];
    row[ch[CH_QD_MEAS].offset + j] = d.qdm_fb[j] / ratio;
    row[ch[CH_QDD].offset + j] = d.qdd[j];
    row[ch[CH_Z].offset + j] = x[URT_X_Z];
    // core/snapshot.cpp's target current, with the set-point in place of the controller's
    double f = 0.0;
    if (m->friction[j].enabled && d.cmd.qd[j] != 0.0) {
      f = urt_friction_g(&m->friction[j], d.cmd.qd[j]) * std::tanh(d.cmd.qd[j] / 2e-3);
    }
    row[ch[CH_I_TARGET].offset + j] = (tau_id[j] + f + d.cmd.tau_ff[j]) / (kt * ratio);
    row[ch[CH_TEMP].offset + j] = temp[j];
  }
  std::memcpy(row + ch[CH_TCP].offset, d.tcp_pose, sizeof d.tcp_pose);
  row[ch[CH_PSTOP].offset] = (double)d.pstop;
}

// The truth columns of one sample. bound[k]: fault k's range bound (max(|lo|, |hi|)).
void record_truth(const urt_model_t *m, const urt_data_t &d, const double *bound,
                  const std::vector<Channel> &ch, double *row) {
  const int nc = urt_fault_class_count();
  double *active = row + truth_offset(ch), *sev = active + nc, *health = sev + nc;
  std::fill(active, health + 1, 0.0);  // the row is zeroed already; a cheap guarantee
  *health = 1.0;
  urt_fault_truth_t tr;
  urt_faults_truth(m, &d, &tr);
  double worst = 0.0;
  for (int k = 0; k < tr.n; k++) {
    if (!tr.active[k]) {
      continue;
    }
    const int c = tr.cls[k];
    const double s = tr.severity[k];
    // several active faults of one class (on several joints, say): the one of largest |s|
    if (active[c] == 0.0 || std::fabs(s) > std::fabs(sev[c])) {
      sev[c] = s;
    }
    active[c] = 1.0;
    if (bound[k] > 0.0) {
      worst = std::max(worst, std::fabs(s) / bound[k]);
    }
  }
  *health = std::max(0.0, 1.0 - worst);
}

void thermal_step(const urt_model_t *m, const urt_data_t &d, double h, double temp[URT_NJ]) {
  for (int j = 0; j < URT_NJ; j++) {
    const urt_thermal_params_t &th = m->thermal[j];
    if (th.c_th <= 0.0 || th.r_th <= 0.0) {
      temp[j] = th.t_amb;
      continue;
    }
    double i = d.x[j][URT_X_I];
    double t_ss = th.t_amb + m->motor[j].r * i * i * th.r_th;
    temp[j] = t_ss + (temp[j] - t_ss) * std::exp(-h / (th.r_th * th.c_th));
  }
}

}  // namespace

const std::vector<Channel> &channels() {
  static const std::vector<Channel> ch = make_channels();
  return ch;
}

void SampledTraj::eval(double tt, double q_out[URT_NJ], double qd_out[URT_NJ],
                       double qdd_out[URT_NJ]) const {
  const size_t n = t.size();
  if (tt <= t[0] || tt >= t[n - 1]) {
    const size_t k = tt <= t[0] ? 0 : n - 1;
    // before the start and after the end the set-point rests (tools/traj.h's convention);
    // exactly at the first or last sample, that sample applies
    const bool at = tt == t[k];
    for (int j = 0; j < URT_NJ; j++) {
      q_out[j] = q[k * URT_NJ + j];
      qd_out[j] = at ? qd[k * URT_NJ + j] : 0.0;
      qdd_out[j] = at ? qdd[k * URT_NJ + j] : 0.0;
    }
    return;
  }
  // the interval [t[k], t[k+1]) holding tt
  const size_t k = (size_t)(std::upper_bound(t.begin(), t.end(), tt) - t.begin()) - 1;
  const double h = t[k + 1] - t[k], s = (tt - t[k]) / h;
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2,
               h11 = s3 - s2;
  const double *q0 = &q[k * URT_NJ], *q1 = q0 + URT_NJ;
  const double *v0 = &qd[k * URT_NJ], *v1 = v0 + URT_NJ;
  const double *a0 = &qdd[k * URT_NJ], *a1 = a0 + URT_NJ;
  for (int j = 0; j < URT_NJ; j++) {
    q_out[j] = h00 * q0[j] + h10 * h * v0[j] + h01 * q1[j] + h11 * h * v1[j];
    qd_out[j] = v0[j] + s * (v1[j] - v0[j]);
    qdd_out[j] = a0[j] + s * (a1[j] - a0[j]);
  }
}

void Trajectory::eval(double t, double q[URT_NJ], double qd[URT_NJ], double qdd[URT_NJ]) const {
  if (sampled) {
    samples.eval(t, q, qd, qdd);
  } else {
    urt_traj_eval(&builtin, t, q, qd, qdd);
  }
}

int run(const urt_model_t *m, const Trajectory &tr, const RunSpec &spec, RunOutput *out) {
  const std::vector<Channel> &ch = channels();
  out->channels = ch;
  out->row_width = ch.back().offset + ch.back().width;
  out->rows = 0;
  out->data.clear();
  if (spec.decimate < 1) {
    out->error = "decimate: expected an integer >= 1";
    return 2;
  }
  if (tr.sampled && tr.samples.n() < 2) {
    out->error = "samples: at least two are needed";
    return 2;
  }
  const double duration = spec.duration >= 0.0 ? spec.duration : tr.duration();
  if (!std::isfinite(duration) || duration <= 0.0 || duration > 1e6) {
    out->error = "duration: expected seconds in (0, 1e6]";
    return 2;
  }
  const uint64_t nsteps = (uint64_t)std::llround(duration / m->dt);
  const uint64_t dec = (uint64_t)spec.decimate;
  const size_t rows = (size_t)(nsteps / dec + 1 + (nsteps % dec != 0 ? 1 : 0));
  out->data.assign(rows * (size_t)out->row_width, 0.0);

  static thread_local urt_data_t d;  // ~20 kB: off the (Python thread's) stack
  double q_start[URT_NJ];
  if (tr.sampled) {
    std::memcpy(q_start, tr.samples.q.data(), sizeof q_start);
  }
  int rc = urt_data_init(m, &d, tr.sampled ? q_start : nullptr);
  if (rc != 0) {
    out->error = std::string("urt_data_init: ") + urt_strerror(rc);
    return 1;
  }
  if (spec.has_seed) {
    // what urt_data_init does with m->seed, with this seed
    urt_rng_seed(&d.rng, spec.seed);
    urt_sensors_sample(m, &d);
    urt_data_update_outputs(m, &d);
  }
  rc = urt_data_set_faults(m, &d, &spec.faults);
  if (rc != 0) {
    out->error = std::string("faults: ") + urt_strerror(rc);
    return 2;
  }
  double bound[URT_MAX_FAULTS] = {0};
  for (int k = 0; k < spec.faults.n; k++) {
    double lo, hi;
    urt_fault_severity_range(m, &spec.faults.f[k], &lo, &hi);
    bound[k] = std::max(std::fabs(lo), std::fabs(hi));
  }
  double temp[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    temp[j] = m->thermal[j].t_amb;
  }
  const uint64_t thermal_steps = std::max<int64_t>(1, std::llround(kThermalPeriod / m->dt));

  const int64_t wall0 = now_ns(), cpu0 = now_ns(CLOCK_THREAD_CPUTIME_ID);
  uint64_t k = 0;
  char msg[256];
  for (;; k++) {
    urt_command_t cmd;
    std::memset(&cmd, 0, sizeof cmd);
    tr.eval(d.t, cmd.q, cmd.qd, cmd.qdd);
    if (urt_command_set(m, &d, &cmd) != 0) {
      std::snprintf(msg, sizeof msg, "t = %.9g s: command refused (%s)", d.t,
                    pstop_text(d.pstop).c_str());
      out->error = msg;
      rc = 1;
      break;
    }
    if (k > 0 && k % thermal_steps == 0) {
      thermal_step(m, d, (double)thermal_steps * m->dt, temp);
    }
    if (k % dec == 0 || k == nsteps) {
      urt_data_update_outputs(m, &d);
      double *row = &out->data[out->rows * (size_t)out->row_width];
      record(m, d, temp, ch, row);
      record_truth(m, d, bound, ch, row);
      out->rows++;
    }
    if (k == nsteps) {
      break;
    }
    rc = urt_step(m, &d);
    if (rc != 0) {
      std::snprintf(msg, sizeof msg, "t = %.9g s: step failed: %s (pstop: %s)", d.t,
                    urt_strerror(rc), pstop_text(d.pstop).c_str());
      out->error = msg;
      rc = 1;
      break;
    }
  }
  out->wall_s = 1e-9 * (double)(now_ns() - wall0);
  out->cpu_s = 1e-9 * (double)(now_ns(CLOCK_THREAD_CPUTIME_ID) - cpu0);
  out->steps = k;
  out->data.resize(out->rows * (size_t)out->row_width);
  return rc;
}

}  // namespace urtpy
