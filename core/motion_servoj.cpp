// SPDX-License-Identifier: Apache-2.0
// core/motion_servoj.cpp — servoj, and servol (servoj on the IK of a pose, once per command):
// the set-point follows q̈ = gain (q_target − q − lookahead q̇), which follows a ramp with a lag
// of exactly lookahead, speeds and accelerations within the joints' limits. A command lasts t
// (at least one period); with no new one in time the arm decelerates to rest. Context: RT.
#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kServoH = 2.5e-4;  // largest servo-filter integration step [s]

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.lookahead_time >= 0.03 && cmd.lookahead_time <= 0.2) ||
         !(cmd.gain >= 100.0 && cmd.gain <= 2000.0) || !std::isfinite(cmd.t) || cmd.t < 0.0;
}

// a command without a time lasts one period
void begin(urt_ctrl_t* c, const double* q, urt_ctrl_motion_t motion) {
  urt_servoj_state_t& sv = c->motion_state.servoj;
  std::memcpy(sv.target, q, sizeof sv.target);
  sv.since = 0.0;
  if (!(c->active.t > 0.0)) {
    c->active.t = c->period;
  }
  c->motion = motion;
}

void start_servoj(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  begin(e.c, cmd.q, URT_MOTION_SERVOJ);
}

void start_servol(const MotionEnv& e, const urt_ctrl_cmd_t&, const MotionStart& s) {
  begin(e.c, s.q_goal, URT_MOTION_SERVOL);
}

uint32_t tick(const MotionEnv& e) {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_servoj_state_t& sv = c->motion_state.servoj;
  const double T = c->period, gain = c->active.gain, la = c->active.lookahead_time;
  int n = (int)std::ceil(T / kServoH - 1e-9);
  double h = T / n;
  for (int j = 0; j < URT_NJ; j++) {
    double q = c->q0[j], v = c->qd0[j], a = 0.0;
    double vmax = kSpeedMargin * m->joint[j].qd_max, amax = kAccMargin * m->joint[j].qdd_max;
    for (int k = 0; k < n; k++) {
      a = gain * (sv.target[j] - q - la * v);
      a = std::fmax(-amax, std::fmin(amax, a));
      double v1 = std::fmax(-vmax, std::fmin(vmax, v + a * h));
      q += 0.5 * (v + v1) * h;
      v = v1;
    }
    c->q1[j] = q;
    c->qd1[j] = v;
    c->qdd1[j] = (v - c->qd0[j]) / T;
  }
  sv.since += T;
  if (sv.since >= c->active.t) {
    mark_done(c, c->motion_id);  // the call has controlled the robot for its t
  }
  if (sv.since > std::fmax(c->active.t, c->period) + c->period) {
    // no new servoj in time: decelerate to rest
    mark_done(c, c->motion_id);
    start_stop(c, joint_stop_time(c, kHaltDecel));
  }
  return 0;
}

}  // namespace

const Motion kServojMotion = {URT_MOTION_SERVOJ,   false,        true,  false, bad_argument,
                              joint_target_faults, start_servoj, tick,  stop_to_rest, nullptr};
const Motion kServolMotion = {URT_MOTION_SERVOL, true,         true,  false, bad_argument,
                              pose_faults,       start_servol, tick,  stop_to_rest, nullptr};

}  // namespace urt::core
