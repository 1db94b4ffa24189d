// SPDX-License-Identifier: Apache-2.0
// core/motion_stop.cpp — stopj/stopl and every other stop (HALT, PAUSE of a stream, servo and
// torque time-outs, a movej/movel arriving on a moving arm): every joint decelerates to rest
// at a constant rate, all reaching 0 together. At rest, a pending movej/movel starts; else
// the motion is over. Context: RT.
#include "motion.hpp"

namespace urt::core {

void start_stop(urt_ctrl_t* c, double t_stop) noexcept {
  urt_stop_state_t& st = c->motion_state.stop;
  for (int j = 0; j < URT_NJ; j++) {
    st.a[j] = t_stop > 0.0 ? std::fabs(c->qd1[j]) / t_stop : 0.0;
  }
  c->motion = URT_MOTION_STOP;
  c->seg_time = 0.0;
}

void stop_to_rest(const MotionEnv& e, StopCause) noexcept {
  finish_motion(e.c);
  start_stop(e.c, joint_stop_time(e.c, kHaltDecel));
}

void stop_on_path(const MotionEnv& e, StopCause why) noexcept {
  if (why == StopCause::kHalt) {
    stop_to_rest(e, why);
  }
}

namespace {

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.a_rot);
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  if (cmd.kind == URT_CTRL_STOPJ) {
    start_stop(e.c, joint_stop_time(e.c, cmd.a));
  } else {  // stopl: the tool's deceleration (a_rot, else a, for the rotation)
    start_stop(e.c,
               tcp_twist_decel_time(e.m, e.c, cmd.a, cmd.a_rot > 0.0 ? cmd.a_rot : cmd.a));
  }
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  const urt_stop_state_t& st = c->motion_state.stop;
  const double T = c->period;
  bool rest = true;
  for (int j = 0; j < URT_NJ; j++) {
    double v0 = c->qd0[j], dv = st.a[j] * T;
    double v1 = std::fabs(v0) <= dv ? 0.0 : v0 - std::copysign(dv, v0);
    c->qd1[j] = v1;
    c->q1[j] = c->q0[j] + 0.5 * (v0 + v1) * T;
    c->qdd1[j] = (v1 - v0) / T;
    rest = rest && v1 == 0.0;
  }
  if (rest) {
    std::memset(c->qdd1, 0, sizeof c->qdd1);
  }
  if (!moving(c)) {
    if (c->has_pending) {
      urt_ctrl_cmd_t next = c->pending;
      c->has_pending = 0;
      motion_for_command(next)->start(e, next, MotionStart{URT_MOTION_STOP, nullptr});
    } else {
      finish_motion(c);
    }
  }
  return 0;
}

}  // namespace

const Motion kStopMotion = {URT_MOTION_STOP, false, false,        false,  bad_argument,
                            no_bad_target,   start, tick, stop_on_path, nullptr};

}  // namespace urt::core
