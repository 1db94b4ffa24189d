// SPDX-License-Identifier: Apache-2.0
// core/motion_speedj.cpp — speedj: every joint's speed ramps to its goal, the joints arriving
// together (the leading one at a). With t > 0 the arm decelerates at a after t; without, the
// call returns once the speed is reached and the speed holds until replaced. Context: RT.
//
// The speed slider (and the pause) scales it as it scales movej: the command runs in motion
// time, which advances at s = speed_scaling · pause_scale per second. The speed in motion time
// (qd_s) ramps at a per motion-second toward the goal, the set-point moves at qd_s · s, and t
// is motion time: at s = 0.25 a speedj(qd, a, 0.002) lasts 8 ms at a quarter of qd, covering
// the same joint distance. URCL's spline execution relies on it (one speedj per step of its
// spline time; its speed-scaling test expects each step to hold 1/s controller cycles). At
// s = 1 the set-point is bit for bit the unscaled one.
//
// A program's speedj that reaches the controller late makes up the lost speed. The program runs
// on a thread paired to the controller tick by tick (net/urscript/README.md); when that thread
// is descheduled, the controller goes on without it (the previous speedj's t runs out and the
// arm begins to stop at its a), and the thread then runs the missed ticks back to back: their
// commands arrive late, several in one period, each stamped with the tick that issued it
// (urt_ctrl_cmd_t.tick). URCL's spline runs one speedj(qd, a, steptime) per period with a = the
// change of its own speed over that period, so from the speed the arm kept it could only ever
// reach the previous period's goal: the lag stayed through the whole acceleration phase, a 2 s
// spline ended 2–8 mrad short of its target, and the 10 ms spline after it closed the gap at
// 170 rad/s² (a protective stop, torque limit; URCL's trajectory_streaming tests, e-Series). On
// a controller the program runs every period and the command would have come in time. So a
// speedj late by L > 0 periods (or superseding, in the same period, one that was) owes what the
// arm's speed lost since the last speedj ran plus L periods of its ramp (a·T each), never past
// its goal, and each period the ramp may go up to a·T further until that is paid (at most twice
// the commanded acceleration; the next on-time speedj of the stream inherits the debt; reaching
// a goal clears it). The position lost while the program was late (about L²·a·T² per event) is
// not made up. On time nothing changes.
//
// Nor does a program's speedj begin to stop when its t runs out while the program's thread is
// behind: the next command of the stream has not come because the thread has not run, not
// because the program ended the stream. On a controller the program runs every period and the
// next speedj would supersede it at once. So it runs on as if its t were longer, for as long as
// the thread is behind (urt_ctrl_t.program_slice) and at most kRunOnMax, then stops at its a.
// Stopping there and making the speed up when the late command came moved the set-point's
// position by what the arm lost in between; URCL's next spline point starts from that
// position (get_joint_positions) and its quintic closes the gap within 10 ms, at up to 6·gap/T²:
// with the runner 2–4 periods late at 5 % of the periods the shoulder's set-point swung
// between ±50 rad/s² and the stream ended in a torque-limit protective stop
// (tests/net/urscript/test_speedj_stream_late.c). On time the stop begins the period after t ran
// out, as before, with the same set-points.
//
// A goal faster than a joint can turn is not a protective stop: the trajectory limiter scales
// the whole goal down (every joint by the same fraction, so the direction holds) until the
// fastest joint, relative to its limit, runs at qd_max; RTDE's speed_scaling ("speed scaling
// of the trajectory limiter") reports that fraction while it holds. URCL's spline execution
// relies on it: its zero_time_trajectory tests send a 1 s cubic segment whose peak speed is
// 1.5 times its mean, above 180°/s on the elbow from the home pose, and expect it to run to
// SUCCESS (the next segment starts from the set-point the limiter left, so the end is exact).
#include "motion.hpp"

namespace urt::core {

namespace {

// how long a program's speedj runs on past its t for a late program thread [s]: the lateness
// a loaded host gives (up to 9 periods at 500 Hz seen in URCL's runs); 12 periods at 500 Hz,
// 3 at 125 Hz
constexpr double kRunOnMax = 0.025;

bool bad_argument(const urt_ctrl_cmd_t& cmd) {
  return !(cmd.a > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.t);
}

uint32_t bad_target(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  (void)m;
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(cmd.q[j])) {
      return URT_PSTOP_NONFINITE_CMD;
    }
  }
  return 0;
}

// the fraction of the commanded speeds the joints' limits allow (1: within them)
double limiter_fraction(const urt_model_t* m, const double* qd) {
  double worst = 1.0;
  for (int j = 0; j < URT_NJ; j++) {
    worst = std::fmax(worst, std::fabs(qd[j]) / m->joint[j].qd_max);
  }
  return 1.0 / worst;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart& st) {
  urt_ctrl_t* c = e.c;
  urt_speedj_state_t& sj = c->motion_state.speedj;
  // the scale the set-point's speed qd1 was made with (this tick's has not been slewed yet)
  const double s = c->speed_scaling * c->pause_scale;
  const bool was_speedj = st.prev == URT_MOTION_SPEEDJ;
  // periods late: since the tick that issued it; or as the late speedj it supersedes before
  // that one ever ran
  const double own = cmd.tick && c->tick > cmd.tick ? (double)(c->tick - cmd.tick) : 0.0;
  const double late = std::fmax(own, was_speedj && sj.fresh != 0.0 ? sj.late : 0.0);
  // the speed the last speedj ran at, if it ran just before the program fell behind
  const bool last_w = c->speedj_tick != 0 && c->tick - c->speedj_tick <= (uint64_t)late;
  // the stream goes on at once (the previous period ran a speedj, whose t has just run out)
  const bool follows = c->speedj_tick != 0 && c->speedj_tick == c->tick;
  sj.limit = limiter_fraction(e.m, cmd.q);
  double dmax = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    // a stopped scale (0) leaves nothing to divide by: a speedj continues its own speed
    sj.qd_s[j] = s > 0.0 ? c->qd1[j] / s : (was_speedj ? sj.qd_s[j] : 0.0);
    // (scaled, the fastest joint's goal could round to a hair above its limit)
    const double qd_max = e.m->joint[j].qd_max;
    sj.qd_goal[j] = sj.limit < 1.0 ? std::fmax(-qd_max, std::fmin(qd_max, cmd.q[j] * sj.limit))
                                   : cmd.q[j];
    dmax = std::fmax(dmax, std::fabs(sj.qd_goal[j] - sj.qd_s[j]));
  }
  double tr = dmax / cmd.a;
  for (int j = 0; j < URT_NJ; j++) {
    const double gap = std::fabs(sj.qd_goal[j] - sj.qd_s[j]);
    sj.a[j] = tr > 0.0 ? gap / tr : 0.0;
    const double ramp = sj.a[j] * s * c->period;
    if (late > 0.0) {
      // behind the on-time stream by what the arm lost since the last speedj ran and by the
      // ramp of the periods missed (never past this one's goal)
      const double lost = last_w ? std::fabs(c->speedj_w[j] - sj.qd_s[j]) : 0.0;
      c->speedj_owed[j] = std::fmin(std::fmax(0.0, gap - ramp), lost + late * ramp);
    } else {
      c->speedj_owed[j] = follows ? std::fmin(c->speedj_owed[j], gap) : 0.0;
    }
  }
  sj.late = late;
  sj.fresh = 1.0;
  sj.tau = 0.0;
  sj.expired = 0;
  sj.held = 0.0;
  c->motion = URT_MOTION_SPEEDJ;
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  urt_speedj_state_t& sj = c->motion_state.speedj;
  const double T = c->period, s = e.scale;
  if (sj.expired != 0) {
    // its t ran out last period and the command due at this period's start did not come: the
    // program's thread has not yet delivered that slice (behind), or it issued no speedj
    const bool behind = c->program_slice != 0 && c->program_slice + 1 < c->tick;
    if (!behind || sj.held + T > kRunOnMax + 1e-9 * T) {
      start_stop(c, joint_stop_time(c, c->active.a));
      c->seg_time = T;  // (as if begun at the end of the last period, where t ran out)
      return kStopMotion.tick(e);
    }
    sj.held += T;
  }
  sj.tau += s * T;
  bool reached = true;
  for (int j = 0; j < URT_NJ; j++) {
    const double ramp = sj.a[j] * s * T, extra = std::fmin(c->speedj_owed[j], ramp);
    double w0 = sj.qd_s[j], g = sj.qd_goal[j], dw = ramp + extra;
    double w1 = std::fabs(g - w0) <= dw ? g : w0 + std::copysign(dw, g - w0);
    double v0 = c->qd0[j], v1 = w1 * s;
    sj.qd_s[j] = w1;
    c->speedj_w[j] = w1;
    c->speedj_owed[j] = w1 == g ? 0.0 : std::fmax(0.0, c->speedj_owed[j] - std::fmax(0.0, std::fabs(w1 - w0) - ramp));
    c->qd1[j] = v1;
    c->q1[j] = c->q0[j] + 0.5 * (v0 + v1) * T;
    c->qdd1[j] = (v1 - v0) / T;
    reached = reached && w1 == g;
  }
  sj.fresh = 0.0;
  c->speedj_tick = c->tick;
  if (reached && c->active.t <= 0.0) {
    mark_done(c, c->motion_id);  // speedj without t returns once the speed is reached
  }
  // (t as the VM counts it)
  if (c->active.t > 0.0 && sj.expired == 0 && sj.tau >= c->active.t - 1e-6 * T) {
    mark_done(c, c->motion_id);
    if (c->active.tick != 0 && c->program_slice != 0) {
      sj.expired = c->tick;  // a program's: whether to stop is known next period
    } else {
      start_stop(c, joint_stop_time(c, c->active.a));
    }
  }
  return 0;
}

}  // namespace

const Motion kSpeedjMotion = {URT_MOTION_SPEEDJ, false, false,        false,  bad_argument,
                              bad_target,        start, tick, stop_to_rest, nullptr};

}  // namespace urt::core
