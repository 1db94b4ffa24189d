// SPDX-License-Identifier: Apache-2.0
// core/joint.cpp — one joint's 18-state drive block: PI cascade → PWM → motor → gear, with
// the sensor filters. Equations live in the drivers' headers; this file only wires them.
#include "joint.hpp"

#include <cmath>

#include "urt/data.h"
#include "urt/drivers/friction_inline.h"
#include "urt/drivers/harmonic_drive_inline.h"
#include "urt/drivers/motor_inline.h"
#include "urt/drivers/pi_cascade_inline.h"
#include "urt/drivers/sensors_inline.h"

namespace urt::core {

void drive_rhs(const urt_model_t* m, int j, const double* x, const JointInput& in, int forced,
               double* f, JointAux* aux) noexcept {
  const urt_fault_joint_t* fj = in.fault;
  const urt_pi_cascade_params_t& pc = fj ? fj->control : m->control[j];
  const urt_harmonic_drive_params_t& gp = fj ? fj->gear : m->gear[j];
  const urt_motor_params_t& mp = fj ? fj->motor : m->motor[j];

  // the drivers' states, gathered from the joint's slice of x
  urt_motor_state_t ms = {x[URT_X_I], x[URT_X_QM], x[URT_X_QDM]};
  urt_pi_cascade_state_t cs = {x[URT_X_XI_V], x[URT_X_XI_C]};
  urt_harmonic_drive_state_t gs = {x[URT_X_QWG], x[URT_X_QDWG], x[URT_X_XFS], x[URT_X_XDFS],
                                   x[URT_X_YFS], x[URT_X_YDFS], x[URT_X_QCS], x[URT_X_QDCS]};
  urt_sensors_state_t ss = {x[URT_X_I_F], x[URT_X_W], x[URT_X_WD], x[URT_X_P], x[URT_X_PD]};

  // measurements: continuous filter outputs plus the held error of this sample
  // the measurement's zero offset is added only when there is one: x + 0.0 turns a −0.0 into
  // +0.0, and the paper's robot must keep its bits
  double i_fb = ss.i_f + in.eps_i;
  if (in.i_offset != 0.0) {
    i_fb += in.i_offset;
  }
  double qdm_fb = motor_speed_reading(ss.w, in.eps_w, fj);
  double q_fb = joint_q_reading(ss.p, in.eps_q, fj);
  if (fj) {
    // sensor faults: the measurement chain's gain, offset, bias, noise, or a stuck value
    i_fb = fj->i_gain * (ss.i_f + in.eps_i) + in.i_offset + fj->i_bias;
  }

  // controller: natural saturations, or forced ones for the tables
  urt_pi_cascade_in_t ci = {in.q_set, in.qd_set, in.i_ff, q_fb, qdm_fb, i_fb, in.torque};
  urt_pi_cascade_out_t co;
  if (forced == kNatural) {
    co = urt_pi_cascade_eval_inline(&pc, gp.ratio, &cs, &ci);
  } else {
    // affine in x: saturated signals become constants, held integrators get zero rates
    co.qdm_ref = pc.p_pos * (in.q_set - q_fb) + gp.ratio * in.qd_set;
    double e_v = co.qdm_ref - qdm_fb;
    co.i_sat = (forced & kCurrentSat) != 0;
    co.i_ref = co.i_sat ? pc.i_max : pc.p_vel * e_v + pc.i_vel * cs.xi_v + in.i_ff;
    co.d.xi_v = co.i_sat ? 0.0 : e_v;
    double e_c = co.i_ref - i_fb;
    co.v_sat = (forced & kVoltageSat) != 0;
    co.v_sup = co.v_sat ? pc.v_net : pc.p_cur * e_c + pc.i_cur * cs.xi_c;
    co.d.xi_c = co.v_sat ? 0.0 : e_c;
  }

  // gear between the motor and the arm's joint angle, then the motor, then the sensors
  urt_harmonic_drive_ends_t ge = {ms.q_m, ms.qd_m, x[URT_X_Q], x[URT_X_QD]};
  const urt_harmonic_drive_params_t* gq = &gp;
  urt_harmonic_drive_params_t cracked;
  if (fj && fj->crack > 0.0) {
    // a flexspline crack: the mesh stiffness dips while a WG lobe passes it, twice per WG
    // revolution against the (fixed) flexspline
    // (cos², the modulation at exactly twice the WG rate: a narrower dip adds its harmonics,
    // which the loop's response can make stronger than the fundamental)
    const double c = std::cos(gs.q_wg);
    cracked = gp;
    cracked.k_m *= 1.0 - fj->crack * c * c;
    gq = &cracked;
  }
  urt_harmonic_drive_out_t go = urt_harmonic_drive_eval_inline(gq, &gs, &ge);

  // gear faults on the output spring: a kinematic error shifts where the CS drives the joint,
  // backlash opens a dead zone in the spring (nothing is carried inside it); the tables' forced
  // sets take the gap as k_CS = c_CS = 0
  int gap = forced != kNatural && (forced & kGearGap) != 0;
  int gap_tables = gap;
  if (fj && forced == kNatural && (fj->backlash > 0.0 || fj->te_amp != 0.0)) {
    double e = gs.q_cs - ge.q, ed = gs.qd_cs - ge.qd;
    if (fj->te_amp != 0.0) {
      e += fj->te_amp * std::sin(2.0 * gs.q_wg);
      ed += 2.0 * fj->te_amp * std::cos(2.0 * gs.q_wg) * gs.qd_wg;
    }
    const double half = 0.5 * fj->backlash;
    if (e > half) {
      e -= half;
    } else if (e < -half) {
      e += half;
    } else {
      gap = 1;
      // the gap's tables only while the spring stays open over a whole step at this rate: a
      // step that may close it keeps the contact's W (stiff), or the spring's force would come
      // in explicitly and ring
      gap_tables = std::fabs(e) + std::fabs(ed) * m->dt < half;
    }
    if (!gap) {
      const double t_cs = gp.k_cs * e + gp.c_cs * ed;
      go.d.qd_cs += (go.t_cs - t_cs) / gp.j_cs;
      go.t_cs = t_cs;
    }
  }
  if (gap) {
    go.d.qd_cs += go.t_cs / gp.j_cs;
    go.t_cs = 0.0;
  }
  if (fj && fj->wg_pulse > 0.0) {
    // a WG-bearing spall: a torque pulse against the WG's turning each time a ball passes it,
    // ((1 + cos φ)/2)^8 in the impact phase φ = rate·q_WG (one pulse per impact, its harmonics
    // falling off), its sign the WG's direction, smoothed over 1 rad/s of WG speed
    const double c = 0.5 * (1.0 + std::cos(fj->wg_pulse_rate * gs.q_wg));
    const double c2 = c * c, c4 = c2 * c2;
    const double dir = gs.qd_wg / (std::fabs(gs.qd_wg) + 1.0);
    go.d.qd_wg -= fj->wg_pulse * c4 * c4 * dir / gp.j_wg;
  }
  urt_motor_deriv_t md = urt_motor_deriv_inline(&mp, &ms, co.v_sup, go.t_in);
  urt_sensors_state_t sd = urt_sensors_deriv_inline(&m->sensors[j], &ss, ms.i, ms.qd_m, x[URT_X_Q]);

  f[URT_X_I] = md.di;
  f[URT_X_XI_C] = co.d.xi_c;
  f[URT_X_I_F] = sd.i_f;
  f[URT_X_QM] = md.dq;
  f[URT_X_QDM] = md.dqd;
  f[URT_X_QWG] = go.d.q_wg;
  f[URT_X_QDWG] = go.d.qd_wg;
  f[URT_X_XFS] = go.d.x_fs;
  f[URT_X_XDFS] = go.d.xd_fs;
  f[URT_X_YFS] = go.d.y_fs;
  f[URT_X_YDFS] = go.d.yd_fs;
  f[URT_X_QCS] = go.d.q_cs;
  f[URT_X_QDCS] = go.d.qd_cs;
  f[URT_X_XI_V] = co.d.xi_v;
  f[URT_X_W] = sd.w;
  f[URT_X_WD] = sd.wd;
  f[URT_X_P] = sd.p;
  f[URT_X_PD] = sd.pd;

  // disengaged drives (brakes released, no gear): the block holds still and passes no torque
  if (!in.drives_engaged) {
    for (int k = 0; k < URT_NXD; k++) {
      f[k] = 0.0;
    }
    go.t_cs = 0.0;
  }

  if (aux) {
    aux->t_cs = go.t_cs;
    aux->t_in = go.t_in;
    aux->i_ref = co.i_ref;
    aux->v_sup = co.v_sup;
    aux->i_fb = i_fb;
    aux->qdm_fb = qdm_fb;
    aux->q_fb = q_fb;
    // torque mode has the current-saturated structure: i_ref independent of the state, ξ_v held
    aux->active_set = (co.i_sat || in.torque ? kCurrentSat : 0) | (co.v_sat ? kVoltageSat : 0) |
                      (gap_tables ? kGearGap : 0);
  }
}

// within a step the set-point is the quadratic the command describes
JointInput joint_input(const urt_model_t* m, const urt_data_t* d, int j, double s) noexcept {
  const urt_command_t& c = d->cmd;
  JointInput in;
  in.q_set = c.q[j] + c.qd[j] * s + 0.5 * c.qdd[j] * s * s;
  in.qd_set = c.qd[j] + c.qdd[j] * s;
  in.i_ff = c.tau_ff[j] / (m->motor[j].kt * m->gear[j].ratio);
  in.eps_i = d->eps_i[j];
  in.i_offset = m->joint[j].i_offset;
  in.eps_w = d->eps_w[j];
  in.eps_q = d->eps_q[j];
  in.drives_engaged = m->drives_engaged;
  in.torque = (int)((c.torque_mask >> j) & 1u);
  in.fault = joint_fault(d, j);
  return in;
}

double joint_rates(const urt_model_t* m, const urt_data_t* d, int j, double s, const double* x,
                   double* f, JointAux* aux) noexcept {
  const JointInput in = joint_input(m, d, j, s);
  drive_rhs(m, j, x, in, kNatural, f, aux);
  urt_friction_state_t fs = {x[URT_X_Z]};
  const urt_friction_params_t& fp = in.fault ? in.fault->friction : m->friction[j];
  aux->fr = urt_friction_eval_inline(&fp, &fs, x[URT_X_QD]);
  f[URT_X_Q] = x[URT_X_QD];
  f[URT_X_Z] = aux->fr.dz;
  return aux->t_cs - aux->fr.t_f;
}

}  // namespace urt::core
