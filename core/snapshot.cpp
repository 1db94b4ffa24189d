// SPDX-License-Identifier: Apache-2.0
// core/snapshot.cpp — urt_snapshot_fill: everything the protocol encoders may know, computed
// from the physics (urt_data_t) and the controller (urt_ctrl_t) once per controller period.
//
// Readings and their sources:
// - q: the joint encoder (d->q_fb: filter, noise, quantisation); qd: the motor encoder speed
//   through the gear ratio (d->qdm_fb / τ); qdd: the physics' mean acceleration of the last step.
// - Targets: the controller's set-point at the end of the period (c->q1, qd1, qdd1);
//   m_target = inverse dynamics (RNEA) + steady friction of the target + any external
//   feed-forward; i_target = m_target / (k_t τ).
// - tau: the gear output torque T_CS; i_control: the PI cascade's current reference.
// - tcp_force: the wrench at the active TCP from the joint-torque residual,
//   Jᵀ w = M q̈ + C q̇ + g − (T_CS − T_f), solved with damping near singular poses; it is the
//   wrench the environment applies (same sign as d->wrench_ext); tcp_force_raw is that estimate,
//   tcp_force the estimate less what zero_ftsensor zeroed (c->ft_bias), as a UR's reading.
// - elbow: the origin of DH frame 2, on the elbow joint's axis (joint 3 turns about z₂).
// - tcp_pose, tcp_speed: forward kinematics of the measured q, qd (what a controller knows).
// - tool_accel: specific force (acceleration minus gravity) of the TCP point, tool frame.
// - v_robot: the 48 V supply; i_robot = Σ V_j i_j / v_robot (power balance of the drives,
//   regeneration included); v_main: the same bus.
// - program_state: the runner's, shown as PAUSED while the controller is paused over PLAYING;
//   speed_scaling: the slider's scaling times the pause's (and the speedj limiter's);
//   control_mode (RTDE): 0 position, 1 teach (freedrive), 2 force, 3 torque; m_target of a torque-controlled joint: its command.
// - digital_in, analog_in, tool_analog_in: the levels set from outside (URT_CTRL_SET_INPUTS:
//   LCM, urtwin --io), all in voltage mode, as the primary interface reports. Loop diagnostics (exec_time, overruns, …) are zero
//   here: the loop writes them after this call.
#include <cmath>
#include <cstring>

#include <Eigen/Geometry>

#include "controller_internal.hpp"
#include "urt/core.h"
#include "urt/drivers/friction.h"
#include "urt/snapshot.h"
#include "urt/faults.h"

namespace {

using urt::core::Mat3;
using urt::core::Mat6;
using urt::core::Vec3;
using urt::core::Vec6;

void put_pose(const Mat3& R, const Vec3& p, double* pose) {
  Vec3 r = urt::core::rotvec_from_rotation(R);
  for (int i = 0; i < 3; i++) {
    pose[i] = p[i];
    pose[3 + i] = r[i];
  }
}

int32_t joint_mode(int32_t robot_mode) {
  switch (robot_mode) {
    case URT_ROBOT_MODE_RUNNING:
      return URT_JOINT_MODE_RUNNING;
    case URT_ROBOT_MODE_IDLE:
    case URT_ROBOT_MODE_POWER_ON:
      return URT_JOINT_MODE_IDLE;
    case URT_ROBOT_MODE_BACKDRIVE:
      return URT_JOINT_MODE_BACKDRIVE;
    default:
      return URT_JOINT_MODE_POWER_OFF;
  }
}

}  // namespace

extern "C" void urt_snapshot_fill(const urt_model_t* m, const urt_ctrl_t* c, urt_data_t* d,
                                  urt_snapshot_t* s) {
  using namespace urt::core;
  urt_data_update_outputs(m, d);

  s->tick = c->tick;
  s->period = c->period;
  s->time = (double)c->tick * c->period;
  s->sim_time = d->t;

  // joints
  Vec6 q_true, qd_true;
  for (int j = 0; j < URT_NJ; j++) {
    q_true[j] = d->x[j][URT_X_Q];
    qd_true[j] = d->x[j][URT_X_QD];
  }
  Vec6 id_target;
  rnea(m->arm, d->live.payload, vec6(c->q1), vec6(c->qd1), vec6(c->qdd1), id_target);
  for (int j = 0; j < URT_NJ; j++) {
    const double ratio = m->gear[j].ratio, kt = m->motor[j].kt;
    s->q_target[j] = c->q1[j];
    s->qd_target[j] = c->qd1[j];
    s->qdd_target[j] = c->qdd1[j];
    double f = 0.0;
    if (m->friction[j].enabled && c->qd1[j] != 0.0) {
      f = urt_friction_g(&m->friction[j], c->qd1[j]) * std::tanh(c->qd1[j] / 2e-3);
    }
    // a torque-controlled joint's target torque is what it was told to make
    s->m_target[j] = ((c->torque_mask >> j) & 1u) ? c->tau_ff[j] : id_target[j] + f + c->tau_ff[j];
    s->i_target[j] = s->m_target[j] / (kt * ratio);

    s->q[j] = d->q_fb[j];
    s->qd[j] = d->qdm_fb[j] / ratio;
    s->qdd[j] = d->qdd[j];
    s->i_actual[j] = d->i_fb[j];
    s->i_control[j] = d->i_ref[j];
    s->tau[j] = d->t_cs[j];
    s->tau_from_current[j] = d->i_fb[j] * kt * ratio;  // what UR's actual_current_as_torque is
    s->v_actual[j] = d->v_sup[j];
    s->temperature[j] = c->temperature[j];
    s->joint_mode[j] = c->safety_mode == URT_SAFETY_MODE_FAULT && j == c->fault_joint
                           ? URT_JOINT_MODE_FAULT
                           : joint_mode(c->robot_mode);

    s->motor_angle[j] = d->x[j][URT_X_QM];
    s->motor_speed[j] = d->x[j][URT_X_QDM];
    s->gear_in_torque[j] = d->t_in[j];
    s->friction_torque[j] = d->t_f[j];
    s->flex_x[j] = d->x[j][URT_X_XFS];
    s->flex_y[j] = d->x[j][URT_X_YFS];
    s->bristle_z[j] = d->x[j][URT_X_Z];
  }

  // tool, actual: the forward kinematics of what the encoders measure (s->q, s->qd), as a
  // controller computes it; the true state creeps by nanometres at rest, which a client
  // comparing two readings at rest exactly (URCL's target_outside_limits_pose) would see
  {
    Mat3 Rm;
    Vec3 pm;
    Mat6 Jm;
    tcp_kinematics(m->arm, c->tcp_offset, vec6(s->q), Rm, pm, &Jm);
    put_pose(Rm, pm, s->tcp_pose);
    Eigen::Map<Vec6>{s->tcp_speed} = Jm * vec6(s->qd);
  }
  // the physics' own quantities below (wrench, accelerometer) use the true state
  Mat3 R;
  Vec3 p;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, q_true, R, p, &J);
  {
    Mat3 Rt;
    Vec3 pt;
    Mat6 Jt;
    tcp_kinematics(m->arm, c->tcp_offset, vec6(c->q1), Rt, pt, &Jt);
    put_pose(Rt, pt, s->tcp_pose_target);
    Eigen::Map<Vec6>{s->tcp_speed_target} = Jt * vec6(c->qd1);
  }

  // wrench from the joint-torque residual
  {
    Vec6 id;
    rnea(m->arm, d->live.payload, q_true, qd_true, vec6(d->qdd), id);
    Vec6 r;
    for (int j = 0; j < URT_NJ; j++) {
      r[j] = id[j] - (d->t_cs[j] - d->t_f[j]);
    }
    double w = std::fabs(J.determinant());
    double lambda = w >= 1e-3 ? 0.0 : 0.05 * std::sqrt(1.0 - (w / 1e-3) * (w / 1e-3));
    Eigen::Map<Vec6>{s->tcp_force_raw} = dls_solve(J.transpose(), r, lambda);
    for (int k = 0; k < 6; k++) {
      s->tcp_force[k] = s->tcp_force_raw[k] - c->ft_bias[k];
    }
  }
  std::memcpy(s->tcp_offset, c->tcp_offset, sizeof s->tcp_offset);

  // tool accelerometer: (J q̈ + J̇ q̇ − g) in the tool frame, J̇ q̇ by a forward difference
  {
    const double h = 1e-6;
    Mat3 R2;
    Vec3 p2;
    Mat6 J2;
    tcp_kinematics(m->arm, c->tcp_offset, q_true + h * qd_true, R2, p2, &J2);
    Vec3 a = (J * vec6(d->qdd)).head<3>() + ((J2 - J) * qd_true).head<3>() / h;
    Vec3 g(m->arm.gravity[0], m->arm.gravity[1], m->arm.gravity[2]);
    Eigen::Map<Vec3>{s->tool_accel} = R.transpose() * (a - g);
  }

  // elbow: origin of frame 2, moved by joints 1 and 2 (axes z₀, z₁ through origins 0, 1)
  {
    double q[URT_NJ], T[3][16];
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = q_true[j];
    }
    for (int i = 0; i < 3; i++) {
      urt_arm_frame(m, q, i, T[i]);
    }
    Vec3 pe(T[2][3], T[2][7], T[2][11]);
    Vec3 v = Vec3::Zero();
    for (int i = 0; i < 2; i++) {
      Vec3 z(T[i][2], T[i][6], T[i][10]), o(T[i][3], T[i][7], T[i][11]);
      v += z.cross(pe - o) * qd_true[i];
    }
    for (int k = 0; k < 3; k++) {
      s->elbow_pos[k] = pe[k];
      s->elbow_vel[k] = v[k];
    }
  }
  // linear momentum of the arm: Σ m_j v_j over the links' centres of mass, their velocities by
  // a central difference of the CoM positions along q̇ (h·|q̇| ≈ 1e-7 rad: error ~1e-9 relative)
  {
    const double h = 1e-7;
    double qp[URT_NJ], qm[URT_NJ], Tp[16], Tm[16];
    for (int j = 0; j < URT_NJ; j++) {
      qp[j] = q_true[j] + h * qd_true[j];
      qm[j] = q_true[j] - h * qd_true[j];
    }
    Vec3 P = Vec3::Zero();
    for (int j = 0; j < URT_NJ; j++) {
      const urt_link_params_t& l = m->arm.link[j];
      urt_arm_frame(m, qp, j + 1, Tp);
      urt_arm_frame(m, qm, j + 1, Tm);
      for (int k = 0; k < 3; k++) {
        double cp = Tp[4 * k] * l.com[0] + Tp[4 * k + 1] * l.com[1] + Tp[4 * k + 2] * l.com[2] + Tp[4 * k + 3];
        double cm = Tm[4 * k] * l.com[0] + Tm[4 * k + 1] * l.com[1] + Tm[4 * k + 2] * l.com[2] + Tm[4 * k + 3];
        P[k] += l.mass * (cp - cm) / (2.0 * h);
      }
    }
    const urt_payload_t& load = d->live.payload;  // Tp, Tm are the flange's frames now
    for (int k = 0; k < 3 && load.mass != 0.0; k++) {
      const double* c3 = load.cog;
      double cp = Tp[4 * k] * c3[0] + Tp[4 * k + 1] * c3[1] + Tp[4 * k + 2] * c3[2] + Tp[4 * k + 3];
      double cm = Tm[4 * k] * c3[0] + Tm[4 * k + 1] * c3[1] + Tm[4 * k + 2] * c3[2] + Tm[4 * k + 3];
      P[k] += load.mass * (cp - cm) / (2.0 * h);
    }
    s->momentum = P.norm();
  }
  // the payload the physics carries (the controller's payload_mass/cog are the same values)
  s->payload_mass = d->live.payload.mass;
  std::memcpy(s->gravity_target, c->gravity, sizeof s->gravity_target);
  s->tool_voltage = c->tool_voltage;
  std::memcpy(s->payload_cog, d->live.payload.cog, sizeof s->payload_cog);
  // the tensor as the program declared it (the physics carries its nearest PSD one)
  std::memcpy(s->payload_inertia, d->live.payload_inertia_declared, sizeof s->payload_inertia);

  // power
  const double v_bus = m->control[0].v_net;
  double power = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    power += d->v_sup[j] * d->x[j][URT_X_I];
  }
  s->v_main = v_bus;
  s->v_robot = c->robot_mode == URT_ROBOT_MODE_POWER_OFF ? 0.0 : v_bus;
  s->i_robot = v_bus > 0.0 ? power / v_bus : 0.0;

  // I/O and modes
  s->digital_in = c->digital_in;
  std::memcpy(s->analog_in, c->analog_in, sizeof s->analog_in);
  std::memcpy(s->tool_analog_in, c->tool_analog_in, sizeof s->tool_analog_in);
  s->digital_out = c->digital_out;
  s->analog_out[0] = c->analog_out[0];
  s->analog_out[1] = c->analog_out[1];
  s->robot_mode = c->robot_mode;
  s->safety_mode = c->safety_mode;
  s->safety_status = c->safety_mode;
  // the controller's pause shows over the runner's PLAYING
  s->program_state = c->paused && c->program_state == URT_PROGRAM_PLAYING ? URT_PROGRAM_PAUSED
                                                                          : c->program_state;
  // RTDE robot control mode: 0 position, 1 teach, 2 force, 3 torque
  switch (c->motion) {
    case URT_MOTION_FREEDRIVE:
      s->control_mode = 1;
      break;
    case URT_MOTION_TORQUE:
      s->control_mode = 3;
      break;
    default:
      s->control_mode = c->force_mode ? 2 : 0;
      break;
  }
  s->pstop = d->pstop;
  s->ctrl_fault = c->fault;
  s->enc_joint = c->enc_joint;
  s->fault_joint = c->fault_joint;
  s->speed_slider = c->speed_slider;
  // the slider's and the pause's scaling, and the trajectory limiter's while a speedj needs it
  s->motion_rate = c->speed_scaling * c->pause_scale;
  s->speed_scaling = c->speed_scaling * c->pause_scale *
                     (c->motion == URT_MOTION_SPEEDJ ? c->motion_state.speedj.limit : 1.0);
  s->motion = c->motion;
  s->motion_id = c->motion_id;
  s->motion_done_id = c->motion_done_id;

  // the faults' ground truth, and what became of the live fault commands
  urt_faults_truth(m, d, &s->fault_truth);
  s->faults_applied = c->faults_applied;
  s->faults_refused = c->faults_refused;

  // the loop's own diagnostics: written by the loop after this call
  s->exec_time = 0.0;
  s->overruns = 0;
  s->missed_periods = 0;
  s->cmd_dropped = 0;
  s->published_wall_ns = 0;
}
