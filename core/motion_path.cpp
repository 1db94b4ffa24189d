// SPDX-License-Identifier: Apache-2.0
// core/motion_path.cpp — planned paths made of pieces (urt_path_state_t): movej/optimovej and
// movel with a blend radius r > 0, movep, movec and optimovel. One online speed profile runs
// along the pieces (accelerate at a to the piece's speed, look ahead to brake for a slower
// piece or the end), the set-point is the geometry at the path position: a joint line, or a
// tool line or arc resolved by one IK per period from the last set-point (bounded, no
// allocation). Its time is path time (speed slider, pause), as movej/movel.
//
// The parts, one translation unit (each included inside the anonymous namespace below):
// core/motion_path_geometry.inc (the pieces' geometry), core/motion_path_build.inc (a move's
// piece from its command), core/motion_path_setpoint.inc (the set-point, optimovel's limits),
// core/motion_path_blend.inc (blends, and how UR's blend radius is modelled). This file: the
// small helpers, the speed profile and the motion's hooks.
// Context: RT.
#include <Eigen/Geometry>

#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kLookTicks = 4.0;  // periods of look-ahead beyond the braking distance

// ---- small vector helpers ----

inline Vec3 v3(const double* x) noexcept { return Vec3(x[0], x[1], x[2]); }
inline void put3(const Vec3& v, double* x) noexcept {
  x[0] = v[0];
  x[1] = v[1];
  x[2] = v[2];
}

bool is_joint_kind(int kind) { return kind == URT_CTRL_MOVEJ || kind == URT_CTRL_OPTIMOVEJ; }

bool is_planned_kind(int kind) {
  return kind == URT_CTRL_MOVEJ || kind == URT_CTRL_OPTIMOVEJ || kind == URT_CTRL_MOVEL ||
         kind == URT_CTRL_MOVEP || kind == URT_CTRL_MOVEC || kind == URT_CTRL_OPTIMOVEL;
}

#include "motion_path_geometry.inc"

#include "motion_path_build.inc"

#include "motion_path_setpoint.inc"

#include "motion_path_blend.inc"

// ---- the speed profile ----

double accel(const urt_path_state_t& st) noexcept {
  const urt_path_move_t& mv = st.move[st.seg[0].move];
  return mv.fa > 0.0 ? mv.opt_a : mv.a;
}

double piece_vmax(const urt_path_state_t& st, int k) noexcept {
  const urt_path_move_t& mv = st.move[st.seg[k].move];
  double v = st.seg[k].v_max;
  if (mv.fv > 0.0) {
    v = std::fmin(v, mv.opt_v);
  }
  return v;
}

// the path speed the pieces allow now: the head piece's limit and what can still brake to
// every slower piece ahead; to_end is the path left to the end (HUGE_VAL: it goes on beyond a
// blend into other units). Braking to rest at the end is rest_limit's.
double speed_limit(const urt_path_state_t& st, double a, double& to_end) noexcept {
  double lim = piece_vmax(st, 0);
  double dist = st.seg[0].len - st.s;
  for (int k = 1; k < st.nseg; k++) {
    lim = std::fmin(lim, std::sqrt(piece_vmax(st, k) * piece_vmax(st, k) + 2.0 * a * dist));
    if (st.seg[k].kind == URT_SEG_HERMITE && st.seg[k].orient == 1) {
      to_end = HUGE_VAL;  // beyond it the path is in other units, and goes on
      return lim;
    }
    dist += st.seg[k].len;
  }
  to_end = std::fmax(dist, 0.0);
  return lim;
}

// the speed at the end of this period (dt) from speed sd that still brakes to rest at a within
// to_end: after the period's trapezoidal travel (sd + sd1)·dt/2 the rest must stop in whole
// periods of a·dt (sd1²/2a, exact for such steps), so the last period leaves rest from at most
// a·dt. (√(2·a·to_end), taken before the period's travel, overshot and left up to 3·a·dt for
// the last step: an optimovel at full fractions stepped wrist 2 from 0.51 rad/s to rest.)
double rest_limit(double a, double dt, double sd, double to_end) noexcept {
  if (!(to_end < HUGE_VAL)) {
    return HUGE_VAL;
  }
  const double adt = a * dt;
  return 0.5 * (-adt + std::sqrt(std::fmax(0.0, adt * adt + 8.0 * a * to_end - 4.0 * adt * sd)));
}

// past the end of the head piece (not a blend, whose s is a time): on into the next, as far as
// s reaches, through pieces it passes whole; into a blend, the distance left over becomes time
// at the path speed
void pass_covered_pieces(const MotionEnv& e, urt_path_state_t& st) noexcept {
  while (st.nseg > 1 && st.seg[0].kind != URT_SEG_HERMITE && st.s >= st.seg[0].len) {
    const double over = st.s - st.seg[0].len;
    next_piece(e, st);
    st.s = st.seg[0].kind == URT_SEG_HERMITE ? (st.sd > 0.0 ? over / st.sd : 0.0) : over;
  }
}

// ---- the motion's hooks ----

void begin(const MotionEnv& e, const urt_ctrl_cmd_t& cmd) {
  urt_ctrl_t* c = e.c;
  urt_path_state_t& st = c->motion_state.path;
  std::memset(&st, 0, sizeof st);
  new_move(st.move[0], cmd);
  st.nmove = 1;
  st.nseg = 1;
  if (is_joint_kind(cmd.kind)) {
    build_joint(e, cmd, c->q1, st.move[0], st.seg[0]);
  } else {
    Mat3 R;
    Vec3 p;
    Mat6 J;
    tcp_kinematics(e.m->arm, c->tcp_offset, vec6(c->q1), R, p, &J);
    if (!build_tool(e, cmd, p, R, st.move[0], st.seg[0])) {
      c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;  // movec: the three points make no circle
      finish_motion(c);
      std::memset(c->qd1, 0, sizeof c->qd1);
      std::memset(c->qdd1, 0, sizeof c->qdd1);
      return;
    }
    Vec3 pe;
    Mat3 Re;
    Vec6 dx;
    tool_eval(st.seg[0], 0.0, pe, Re, dx);
    opti_limits(e, st.move[0], J, dx, c->q1);
  }
  set_zone(e, st, 0);
  c->motion = URT_MOTION_PATH;
  c->traj_time = 0.0;
  c->seg_time = 0.0;
}

void start(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const MotionStart&) {
  urt_ctrl_t* c = e.c;
  if (moving(c)) {  // from another motion: to rest first, as movej/movel
    c->pending = cmd;
    c->has_pending = 1;
    if (cmd.kind == URT_CTRL_OPTIMOVEJ || cmd.kind == URT_CTRL_OPTIMOVEL) {
      double a_stop = HUGE_VAL;  // the fraction of the slowest joint's limit
      for (int j = 0; j < URT_NJ; j++) {
        a_stop = std::fmin(a_stop, cmd.a * kAccMargin * e.m->joint[j].qdd_max);
      }
      start_stop(c, joint_stop_time(c, a_stop));
    } else if (is_joint_kind(cmd.kind)) {
      start_stop(c, joint_stop_time(c, cmd.a));
    } else {
      start_stop(c, tcp_twist_decel_time(e.m, c, cmd.a, cmd.a));
    }
  } else {
    begin(e, cmd);
  }
}

// the move at the end of the path is over: the queued one starts from rest, or the path ends
void arrive(const MotionEnv& e) noexcept {
  urt_ctrl_t* c = e.c;
  std::memset(c->qd1, 0, sizeof c->qd1);
  std::memset(c->qdd1, 0, sizeof c->qdd1);
  urt_path_state_t& st = c->motion_state.path;
  if (st.queued_stop && c->has_pending) {
    mark_done(c, c->motion_id);
    const urt_ctrl_cmd_t next = c->pending;
    c->has_pending = 0;
    c->active = next;
    c->motion_id = next.id;
    c->seg_time = 0.0;
    motion_for_command(next)->start(e, next, MotionStart{URT_MOTION_PATH, nullptr});
  } else {
    finish_motion(c);
  }
}

uint32_t tick(const MotionEnv& e) {
  urt_ctrl_t* c = e.c;
  urt_path_state_t& st = c->motion_state.path;
  const double T = c->period, dt = e.scale * T;
  c->traj_time += dt;
  bool end = false;
  if (st.seg[0].kind == URT_SEG_HERMITE) {
    st.s += dt;
    if (st.s >= st.seg[0].T) {
      // the blend is over: on to B at the speed it ends with, through whatever of B the rest
      // of the period covers (a piece between two blends can be shorter than that)
      const double over = st.s - st.seg[0].T;
      next_piece(e, st);
      st.s = st.seg[0].kind == URT_SEG_HERMITE ? over : over * st.sd;
      pass_covered_pieces(e, st);
    }
  } else {
    const double a = accel(st);
    double to_end;
    const double lim = speed_limit(st, a, to_end);
    // never slower than braking at a: a limit that drops at once (a new piece whose speed the
    // joints allow is lower where it really begins than estimated when it was planned, an
    // optimovel after a fast joint move) is met by braking, not by a step in the joints' speed.
    // Braking to rest at the end is not held back by that floor: an optimovel's a follows the
    // pose, and where it shrinks on the way in, the floor at the last tick's a let the path
    // reach its end at speed and step to rest (wrist 2: 0.41 rad/s to 0 in one period)
    const double lim_end = rest_limit(a, dt, st.sd, to_end);
    const double sd1 = std::fmax(
        0.0, std::fmin(std::fmax(std::fmin(st.sd + a * dt, lim), st.sd - a * dt), lim_end));
    const double ds = 0.5 * (st.sd + sd1) * dt;
    if (dt > 0.0 && (ds >= to_end || (sd1 <= a * dt && to_end <= sd1 * dt + 1e-12))) {
      end = true;  // lands on the end
      while (st.nseg > 1) {
        next_piece(e, st);
      }
      st.s = st.seg[0].len;
      st.sd = 0.0;
    } else {
      st.s += ds;
      st.sd = sd1;
      pass_covered_pieces(e, st);
    }
  }
  if (!place(e, st)) {
    return URT_CTRL_FAULT_IK;  // the path left the workspace
  }
  for (int j = 0; j < URT_NJ; j++) {
    c->qdd1[j] = (c->qd1[j] - c->qd0[j]) / T;
  }
  if (end) {
    arrive(e);
    return 0;
  }
  // a move with a blend radius lets the program go on before it would brake for its target
  urt_path_move_t& mv = st.move[0];
  if (!mv.done && mv.r > 0.0 && st.nmove == 1) {
    double left = 0.0;
    for (int k = 0; k < st.nseg; k++) {  // (a blend's s is its time: not counted)
      if (k > 0 || st.seg[k].kind != URT_SEG_HERMITE) {
        left += st.seg[k].len - (k == 0 ? st.s : 0.0);
      }
    }
    const double a = accel(st);
    const double brake = a > 0.0 ? st.sd * st.sd / (2.0 * a) : 0.0;
    if (left <= mv.zone + brake + kLookTicks * st.sd * dt) {
      mv.done = 1;
      mark_done(c, mv.id);
    }
  }
  return 0;
}

// a planned motion arriving while a move with a blend radius runs is queued behind it
bool blend(const MotionEnv& e, const urt_ctrl_cmd_t& next) {
  urt_ctrl_t* c = e.c;
  urt_path_state_t& st = c->motion_state.path;
  if (!is_planned_kind(next.kind) || st.nmove != 1 || c->has_pending || st.move[0].r <= 0.0 ||
      c->paused) {
    return false;
  }
  urt_path_move_t mb;
  new_move(mb, next);
  urt_path_seg_t b;
  const urt_path_seg_t& a = st.seg[st.nseg - 1];
  bool ok = true;
  if (is_joint_kind(next.kind)) {
    double q_end[URT_NJ], dq[URT_NJ];
    if (a.kind == URT_SEG_JOINT) {
      joint_eval(a, a.L, q_end, dq);
    } else {
      ok = piece_joints(e.m, c, a, a.L, c->q1, q_end, dq);
    }
    if (ok) {
      build_joint(e, next, q_end, mb, b);
    }
  } else {
    Vec3 p;
    Mat3 R;
    if (a.kind == URT_SEG_JOINT) {
      double q_end[URT_NJ], dq[URT_NJ];
      joint_eval(a, a.L, q_end, dq);
      tcp_kinematics(e.m->arm, c->tcp_offset, vec6(q_end), R, p, nullptr);
    } else {
      Vec6 dx;
      tool_eval(a, a.L, p, R, dx);
    }
    ok = build_tool(e, next, p, R, mb, b);
  }
  if (ok && mb.fv > 0.0) {
    // optimovel queued: what the joints allow where it begins (A's target), one IK for a tool A
    double q_end[URT_NJ], dq[URT_NJ];
    if (piece_joints(e.m, c, a, a.L, c->q1, q_end, dq)) {
      Mat3 R;
      Vec3 p;
      Mat6 J;
      tcp_kinematics(e.m->arm, c->tcp_offset, vec6(q_end), R, p, &J);
      Vec3 pb;
      Mat3 Rb;
      Vec6 dx;
      tool_eval(b, 0.0, pb, Rb, dx);
      opti_limits(e, mb, J, dx, q_end);
    } else {
      ok = false;
    }
  }
  c->pending = next;
  c->has_pending = 1;
  b.move = 1;
  st.move[1] = mb;
  st.nmove = 2;
  if (ok && blendable(st, mb, b) && append_blend(e, st, b)) {
    st.queued_stop = 0;
    // B's own blend zone (its last piece is the last one now)
    set_zone(e, st, 1);
  } else {
    st.queued_stop = 1;  // runs to its target, B from rest there
  }
  return true;
}

uint32_t joint_faults(const urt_model_t* m, const urt_ctrl_cmd_t& cmd) {
  return target_faults(m, cmd.q);
}

uint32_t movec_faults(const urt_model_t*, const urt_ctrl_cmd_t& cmd) {
  return all_finite(cmd.pose, 6) && all_finite(cmd.q, 3) ? 0 : URT_PSTOP_NONFINITE_CMD;
}

}  // namespace

const Motion kPathJointMotion = {URT_MOTION_PATH, false, false, false, bad_joint,
                                 joint_faults,    start, tick,  stop_on_path, blend};
const Motion kPathToolMotion = {URT_MOTION_PATH, true,  false, false, bad_tool,
                                pose_faults,     start, tick,  stop_on_path, blend};
const Motion kPathArcMotion = {URT_MOTION_PATH, true,  false, false, bad_tool,
                               movec_faults,    start, tick,  stop_on_path, blend};

}  // namespace urt::core
