// SPDX-License-Identifier: Apache-2.0
// core/motion_freedrive.cpp — freedrive (teach mode): every drive in torque mode carrying the
// controller's gravity model, so that only friction and the drives' inertia resist a push.
// Held axes of the feature frame (free[i] = 0) get a Cartesian spring-damper toward the pose
// freedrive began at, τ += Jᵀ w with w = K e − D v per held axis (10 kN/m, 300 N s/m;
// 1000 N m/rad, 20 N m s/rad): a push on a held axis deflects it by about |F|/K plus what
// friction holds. The command returns at once; FREEDRIVE index 0 ends it. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kHoldK = 1e4;        // spring on held axes, translation [N/m]
constexpr double kHoldD = 300.0;      // and damper [N s/m]
constexpr double kHoldKRot = 1000.0;  // rotation [N m/rad]
constexpr double kHoldDRot = 20.0;    // [N m s/rad]

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  bool bad = false;
  for (int j = 0; j < URT_NJ; j++) {
    bad = bad || !(cmd.q[j] == 0.0 || cmd.q[j] == 1.0);
  }
  return bad || !all_finite(cmd.pose, 6);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s) {
  urt_ctrl_t* c = e.c;
  urt_freedrive_state_t& fd = c->motion_state.freedrive;
  if (s.prev != URT_MOTION_FREEDRIVE) {
    double pose[6];
    urt_ctrl_forward_kinematics_tcp(e.m, c->tcp_offset, c->q1, pose);
    std::memcpy(fd.p_hold, pose, sizeof fd.p_hold);
    std::memcpy(fd.r_hold, pose + 3, sizeof fd.r_hold);
  }
  std::memcpy(fd.free, cmd.q, sizeof fd.free);
  std::memcpy(fd.feature, cmd.pose, sizeof fd.feature);
  mark_done(c, cmd.id);  // teach mode returns at once; it lasts until ended
  c->motion = URT_MOTION_FREEDRIVE;
}

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  const urt_data_t* d = e.d;
  const urt_freedrive_state_t& fd = c->motion_state.freedrive;
  const Vec6 q = actual_q(d);
  follow_actual(m, c, d, kAllJoints);
  Vec6 tau;
  ctrl_rnea(m, c, d->live.payload, q, Vec6::Zero(), Vec6::Zero(), tau);

  bool held = false;
  for (int i = 0; i < 6; i++) {
    held = held || fd.free[i] == 0.0;
  }
  if (held) {
    Mat3 R;
    Vec3 pos;
    Mat6 J;
    tcp_kinematics(m->arm, c->tcp_offset, q, R, pos, &J);
    Vec6 qd;
    for (int j = 0; j < URT_NJ; j++) {
      qd[j] = d->x[j][URT_X_QD];
    }
    const Vec6 x = J * qd;
    const Mat3 Rf = rotation_from_rotvec(Vec3(fd.feature[3], fd.feature[4], fd.feature[5]));
    const Mat3 Rf_T = Rf.transpose();
    const Mat3 R_hold = rotation_from_rotvec(Vec3(fd.r_hold[0], fd.r_hold[1], fd.r_hold[2]));
    const Vec3 e_p = Rf_T * Vec3(Vec3(fd.p_hold[0], fd.p_hold[1], fd.p_hold[2]) - pos);
    const Vec3 e_r = Rf_T * Vec3(R * rotvec_from_rotation(R.transpose() * R_hold));
    const Vec3 v_f = Rf_T * Vec3(x.head<3>()), w_f = Rf_T * Vec3(x.tail<3>());
    Vec3 f_f, m_f;
    for (int i = 0; i < 3; i++) {
      f_f[i] = fd.free[i] == 0.0 ? kHoldK * e_p[i] - kHoldD * v_f[i] : 0.0;
      m_f[i] = fd.free[3 + i] == 0.0 ? kHoldKRot * e_r[i] - kHoldDRot * w_f[i] : 0.0;
    }
    Vec6 w;
    w.head<3>() = Rf * f_f;
    w.tail<3>() = Rf * m_f;
    tau += J.transpose() * w;
  }
  for (int j = 0; j < URT_NJ; j++) {
    c->tau_ff[j] = clamp_torque(m, j, tau[j]);
  }
  c->torque_mask = kAllJoints;
  return 0;
}

}  // namespace

const Motion kFreedriveMotion = {URT_MOTION_FREEDRIVE, false, false,        true,   bad_argument,
                                 no_bad_target,        start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
