// SPDX-License-Identifier: Apache-2.0
// core/motion_servoj.cpp — servoj, and servol (servoj on the IK of a pose, once per command):
// the set-point follows q̈ = gain (q_target − q − lookahead q̇), which follows a ramp with a lag
// of exactly lookahead, speeds and accelerations within the joints' limits. A command lasts t
// (at least one period); with no new one in time the arm decelerates to rest. Context: RT.
//
// A program's servoj that reaches the controller late runs from the tick after the one that
// issued it. The program runs on a thread paired to the controller tick by tick
// (net/urscript/README.md); descheduled, it delivers the missed ticks' commands late, several in
// one period, each stamped with its tick (urt_ctrl_cmd_t.tick). Taken on arrival, the set-point
// held each old target for as many periods as the thread was late and then jumped on: under
// load (no --rt-priority, two busy processes) a ur_rtde servoJ sine left the law's response to
// the commands by up to 8.6e-4 rad, and URCL's servo stream the same. On a controller the
// program runs every period. So the last URT_SERVOJ_REPLAY periods of the stream are kept (the
// set-point at each one's start), and a servoj stamped s < the last tick L
// re-runs periods s+1 … L toward its target, from the set-point at the start of s+1, rewriting
// them (the next command of the burst re-runs from its own tick on that): the set-point then
// jumps to where the stream would be had the program been on time (a few 1e-5 rad per late
// period at URCL's gain). Also when servoj's timeout began a stop meanwhile. On time nothing
// changes.
#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kServoH = 2.5e-4;  // largest servo-filter integration step [s]

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.lookahead_time >= 0.03 && cmd.lookahead_time <= 0.2) ||
         !(cmd.gain >= 100.0 && cmd.gain <= 2000.0) || !std::isfinite(cmd.t) || cmd.t < 0.0;
}

// one period of the law from (q, v) toward target, in place
void period(const urt_model_t* m, const urt_ctrl_t* c, const double* target, double* q,
            double* v) {
  const double T = c->period, gain = c->active.gain, la = c->active.lookahead_time;
  int n = (int)std::ceil(T / kServoH - 1e-9);
  double h = T / n;
  for (int j = 0; j < URT_NJ; j++) {
    double qj = q[j], vj = v[j];
    double vmax = kSpeedMargin * m->joint[j].qd_max, amax = kAccMargin * m->joint[j].qdd_max;
    for (int k = 0; k < n; k++) {
      double a = gain * (target[j] - qj - la * vj);
      a = std::fmax(-amax, std::fmin(amax, a));
      double v1 = std::fmax(-vmax, std::fmin(vmax, vj + a * h));
      qj += 0.5 * (vj + v1) * h;
      vj = v1;
    }
    q[j] = qj;
    v[j] = vj;
  }
}

// a late servoj (see the top): periods s+1 … L again, toward its target
void replay(const urt_model_t* m, urt_ctrl_t* c, const urt_ctrl_cmd_t& cmd, urt_ctrl_motion_t prev,
            const double* target) {
  auto& r = c->servoj_replay;
  const uint64_t L = c->tick, s = cmd.tick;
  const bool stream = prev == URT_MOTION_SERVOJ || prev == URT_MOTION_SERVOL ||
                      (prev == URT_MOTION_STOP && r.timeout_tick > s);
  if (s == 0 || s >= L || L - s >= URT_SERVOJ_REPLAY || !stream ||
      r.tick[(s + 1) % URT_SERVOJ_REPLAY] != s + 1) {
    return;
  }
  // first without writing: refused below, the stream's periods stay as they ran
  double q[URT_NJ], v[URT_NJ], v_before[URT_NJ];
  for (int pass = 0; pass < 2; pass++) {
    std::memcpy(q, r.q[(s + 1) % URT_SERVOJ_REPLAY], sizeof q);
    std::memcpy(v, r.qd[(s + 1) % URT_SERVOJ_REPLAY], sizeof v);
    for (uint64_t t = s + 1; t <= L; t++) {
      if (pass == 1) {
        const uint64_t k = t % URT_SERVOJ_REPLAY;
        r.tick[k] = t;
        std::memcpy(r.q[k], q, sizeof q);
        std::memcpy(r.qd[k], v, sizeof v);
      }
      std::memcpy(v_before, v, sizeof v);
      period(m, c, target, q, v);
    }
    // a stream's correction is small (a 0.2 rad, 0.5 Hz sine 12 periods late: 0.12 rad/s,
    // tests/core/test_controller_motions.c); a target
    // that jumps (URCL's target_outside_limits_servoj: 2.5 rad) would leave the set-point's
    // speed further behind than one period of the law's largest acceleration: the arm cannot
    // take that step, and the command starts from where the set-point is, as on arrival
    for (int j = 0; pass == 0 && j < URT_NJ; j++) {
      if (std::fabs(v[j] - c->qd1[j]) > kAccMargin * m->joint[j].qdd_max * c->period) {
        return;
      }
    }
  }
  std::memcpy(c->q1, q, sizeof q);
  std::memcpy(c->qd1, v, sizeof v);
  for (int j = 0; j < URT_NJ; j++) {
    c->qdd1[j] = (v[j] - v_before[j]) / c->period;
  }
}

// a command without a time lasts one period
void begin(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s, const double* q,
           urt_ctrl_motion_t motion) {
  urt_ctrl_t* c = e.c;
  urt_servoj_state_t& sv = c->motion_state.servoj;
  std::memcpy(sv.target, q, sizeof sv.target);
  sv.since = 0.0;
  if (!(c->active.t > 0.0)) {
    c->active.t = c->period;
  }
  c->motion = motion;
  replay(e.m, c, cmd, s.prev, q);
  c->servoj_replay.timeout_tick = 0;
}

void start_servoj(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s) {
  begin(e, cmd, s, cmd.q, URT_MOTION_SERVOJ);
}

void start_servol(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& s) {
  begin(e, cmd, s, s.q_goal, URT_MOTION_SERVOL);
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  urt_servoj_state_t& sv = c->motion_state.servoj;
  const double T = c->period;
  // this period, for a late servoj to re-run (replay)
  auto& r = c->servoj_replay;
  const uint64_t k = c->tick % URT_SERVOJ_REPLAY;
  r.tick[k] = c->tick;
  std::memcpy(r.q[k], c->q0, sizeof r.q[k]);
  std::memcpy(r.qd[k], c->qd0, sizeof r.qd[k]);
  std::memcpy(c->q1, c->q0, sizeof c->q1);
  std::memcpy(c->qd1, c->qd0, sizeof c->qd1);
  period(e.m, c, sv.target, c->q1, c->qd1);
  for (int j = 0; j < URT_NJ; j++) {
    c->qdd1[j] = (c->qd1[j] - c->qd0[j]) / T;
  }
  sv.since += T;
  if (sv.since >= c->active.t) {
    mark_done(c, c->motion_id);  // the call has controlled the robot for its t
  }
  if (sv.since > std::fmax(c->active.t, c->period) + c->period) {
    // no new servoj in time: decelerate to rest
    mark_done(c, c->motion_id);
    start_stop(c, joint_stop_time(c, kHaltDecel));
    c->servoj_replay.timeout_tick = c->tick;
  }
  return 0;
}

}  // namespace

const Motion kServojMotion = {URT_MOTION_SERVOJ,   false,        true,  false, bad_argument,
                              joint_target_faults, start_servoj, tick,  stop_to_rest, nullptr};
const Motion kServolMotion = {URT_MOTION_SERVOL, true,         true,  false, bad_argument,
                              pose_faults,       start_servol, tick,  stop_to_rest, nullptr};

}  // namespace urt::core
