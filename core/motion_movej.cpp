// SPDX-License-Identifier: Apache-2.0
// core/motion_movej.cpp — movej: a joint-space trapezoid from rest to rest, the joints moving
// together (the leading joint at a, v within every joint's limits; t > 0 sets the duration when
// the joints can make it). Its time is the path time c->traj_time, which the speed slider and
// the pause scale. Arriving while the set-point moves, it first stops at its own deceleration
// (c->pending) and starts from rest. optimovej is the same motion with a and v given as
// fractions of the joints' own maximum acceleration and speed. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.t) || cmd.t < 0.0;
}

bool bad_fraction(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0 && cmd.a <= 1.0) || !(cmd.v > 0.0 && cmd.v <= 1.0);
}

void plan(const MotionEnv& e, const urt_ctrl_cmd_t& cmd) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_movej_state_t& mj = c->motion_state.movej;
  double D = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    mj.q_start[j] = c->q1[j];
    mj.dq[j] = cmd.q[j] - c->q1[j];
    D = std::fmax(D, std::fabs(mj.dq[j]));
  }
  double v = cmd.v, a = cmd.a;
  if (cmd.kind == URT_CTRL_OPTIMOVEJ) {
    // the fraction of every joint's limit: the joint that needs the longest sets the pace;
    // the acceleration a fraction of what the drives' torques allow along the move
    v = a = HUGE_VAL;
    for (int j = 0; j < URT_NJ && D > 0.0; j++) {
      double f = std::fabs(mj.dq[j]) / D;
      if (f > 0.0) {
        v = std::fmin(v, cmd.v * kSpeedMargin * m->joint[j].qd_max / f);
        a = std::fmin(a, cmd.a * kAccMargin * m->joint[j].qdd_max / f);
      }
    }
    a = std::fmin(a, cmd.a * feasible_joint_move_accel(m, c, e.d->live.payload, mj.q_start,
                                                       mj.dq, D));
  }
  for (int j = 0; j < URT_NJ && D > 0.0; j++) {
    double f = std::fabs(mj.dq[j]) / D;  // this joint's share of the leading axis' motion
    if (f > 0.0) {
      v = std::fmin(v, kSpeedMargin * m->joint[j].qd_max / f);
      a = std::fmin(a, kAccMargin * m->joint[j].qdd_max / f);
    }
  }
  if (cmd.t > 0.0 && cmd.kind == URT_CTRL_MOVEJ) {
    // t overrides a and v, but never beyond the joints' limits
    urt_trap_t fit = trap_plan(D, v, a, cmd.t);
    if (fit.vp <= v * 1.0000001 && fit.ap <= a * 1.0000001) {
      mj.tr = fit;
    } else {
      mj.tr = trap_plan(D, v, a, 0.0);
    }
  } else {
    mj.tr = trap_plan(D, v, a, 0.0);
  }
  c->motion = URT_MOTION_MOVEJ;
  c->traj_time = 0.0;
  c->seg_time = 0.0;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_ctrl_t* c = e.c;
  if (moving(c)) {
    c->pending = cmd;
    c->has_pending = 1;
    double a_stop = cmd.a;
    if (cmd.kind == URT_CTRL_OPTIMOVEJ) {  // the fraction of the slowest joint's limit
      a_stop = HUGE_VAL;
      for (int j = 0; j < URT_NJ; j++) {
        a_stop = std::fmin(a_stop, cmd.a * kAccMargin * e.m->joint[j].qdd_max);
      }
    }
    start_stop(c, joint_stop_time(c, a_stop));
  } else {
    plan(e, cmd);
  }
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  c->traj_time += e.scale * c->period;
  const urt_movej_state_t& mj = c->motion_state.movej;
  double s, sd, sdd;
  trap_eval(mj.tr, c->traj_time, s, sd, sdd);
  double D = mj.tr.D;
  for (int j = 0; j < URT_NJ; j++) {
    double f = D > 0.0 ? mj.dq[j] / D : 0.0;
    c->q1[j] = mj.q_start[j] + f * s;
    c->qd1[j] = f * sd * e.scale;
    c->qdd1[j] = f * (sdd * e.scale * e.scale + sd * e.dscale);
  }
  if (c->traj_time >= mj.tr.T) {
    for (int j = 0; j < URT_NJ; j++) {
      c->q1[j] = mj.q_start[j] + mj.dq[j];
      c->qd1[j] = c->qdd1[j] = 0.0;
    }
    finish_motion(c);
  }
  return 0;
}

}  // namespace

const Motion kOptimovejMotion = {URT_MOTION_MOVEJ,    false, false,        false,  bad_fraction,
                                 joint_target_faults, start, tick, stop_on_path, nullptr};
const Motion kMovejMotion = {URT_MOTION_MOVEJ, false, false,        false,  bad_argument,
                             joint_target_faults, start, tick, stop_on_path, nullptr};

}  // namespace urt::core
