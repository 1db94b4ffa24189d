// SPDX-License-Identifier: Apache-2.0
// core/motion_path.cpp — planned paths made of pieces (urt_path_state_t): movej/optimovej and
// movel with a blend radius r > 0, movep, movec and optimovel. One online speed profile runs
// along the pieces (accelerate at a to the piece's speed, look ahead to brake for a slower
// piece or the end), the set-point is the geometry at the path position: a joint line, or a
// tool line or arc resolved by one IK per period from the last set-point (bounded, no
// allocation). Its time is path time (speed slider, pause), as movej/movel.
//
// Blends (UR's script manual, movej/movel/movep: "the robot arm trajectory will be modified to
// avoid the robot stopping at the point"):
// - A move with r > 0 marks its id done early, so that the program goes on to its next motion
//   while the arm still moves: when the rest of the move is within r (its blend zone) plus its
//   braking distance plus four periods at the current speed. UR evaluates the next motion "when
//   entering the blend radius"; the braking distance is added so that the next motion is known
//   before the arm would have to brake, for the via point or for a slower next motion.
// - The next planned motion arriving while the move runs is queued behind it (c->pending, so
//   that a HALT or any other command marks it done too). The path becomes: the move up to its
//   blend zone, a blend, the next move from the blend's end. A tool blend is a circular arc
//   tangent to both lines, entering and leaving at the same distance d from the via point; a
//   joint blend (joint moves) is a cubic in joint space from the point where the TCP is d from
//   the via point on the first move to the point where it is d from it on the next. d is r, shrunk to half
//   of either move's length (UR's motion version 2: "dynamically reduce blend radii to prevent
//   blend radius overlaps"; version 1 skips the move with an 'Overlapping Blends' warning) and
//   to what is left of the move when the next one arrives late.
// - Other pairs (a joint move and a tool move, movec before or after) blend on a joint-space
//   cubic between the same two points (one IK at each end for a tool move), the time of each
//   half its length at its end's speed. Not blended (the move stops at its target and the next
//   starts from rest there): a pure rotation, a line turning back on itself, a move whose TCP
//   does not move.
// - With nothing queued the move stops at its target, as the last motion of a sequence does.
// Context: RT.
#include <Eigen/Geometry>

#include "motion.hpp"

namespace urt::core {

namespace {

constexpr double kLookTicks = 4.0;  // periods of look-ahead beyond the braking distance
constexpr double kMinBlend = 1e-6;  // a blend shorter than this is no blend [m]

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

Vec3 tcp_position(const urt_model_t* m, const urt_ctrl_t* c, const double* q) noexcept {
  Mat3 R;
  Vec3 p;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(q), R, p, nullptr);
  return p;
}

// ---- geometry of a piece ----

// the TCP pose at σ and its derivative d(v; ω)/dσ (tool pieces)
void tool_eval(const urt_path_seg_t& g, double sigma, Vec3& p, Mat3& R, Vec6& dx) noexcept {
  Vec3 dp;
  if (g.kind == URT_SEG_ARC) {
    const double psi = sigma / g.rho;
    p = v3(g.p0) + g.rho * (std::cos(psi) * v3(g.e1) + std::sin(psi) * v3(g.e2));
    dp = -std::sin(psi) * v3(g.e1) + std::cos(psi) * v3(g.e2);
  } else {
    p = v3(g.p0) + v3(g.u) * sigma;
    dp = v3(g.u);
  }
  const Mat3 R0 = rotation_from_rotvec(v3(g.r0));
  Vec3 w;
  if (g.orient == 1) {
    const Vec3 n = v3(g.e1).cross(v3(g.e2));
    R = rotation_from_rotvec(n * (sigma / g.rho)) * R0;
    w = n / g.rho;
  } else {
    const double k = g.L > 0.0 ? g.theta / g.L : 0.0;
    R = R0 * rotation_from_rotvec(v3(g.axis) * (k * sigma));
    w = R0 * v3(g.axis) * k;
  }
  for (int i = 0; i < 3; i++) {
    dx[i] = dp[i];
    dx[3 + i] = w[i];
  }
}

// joint piece at σ: q and dq/dσ
void joint_eval(const urt_path_seg_t& g, double sigma, double* q, double* dq) noexcept {
  for (int j = 0; j < URT_NJ; j++) {
    const double k = g.L > 0.0 ? g.dq[j] / g.L : 0.0;
    q[j] = g.q0[j] + k * sigma;
    dq[j] = k;
  }
}

// a tool piece's orientation interpolated from R0 to R1 over L
void set_orientation(urt_path_seg_t& g, const Mat3& R0, const Mat3& R1) noexcept {
  put3(rotvec_from_rotation(R0), g.r0);
  const Vec3 rel = rotvec_from_rotation(R0.transpose() * R1);
  g.theta = rel.norm();
  put3(g.theta > 0.0 ? Vec3(rel / g.theta) : Vec3(0.0, 0.0, 1.0), g.axis);
  g.orient = 0;
}

// the TCP distance from P of a joint piece at σ
double joint_dist(const urt_model_t* m, const urt_ctrl_t* c, const urt_path_seg_t& g,
                  double sigma, const Vec3& P) noexcept {
  double q[URT_NJ], dq[URT_NJ];
  joint_eval(g, sigma, q, dq);
  return (tcp_position(m, c, q) - P).norm();
}

// σ on a joint piece where the TCP is d from P: from_end searches down from σ = L (P its end),
// else up from σ = 0 (P its start); bisection, 33 forward kinematics at most
double joint_sigma_at(const urt_model_t* m, const urt_ctrl_t* c, const urt_path_seg_t& g,
                      const Vec3& P, double d, bool from_end) noexcept {
  double near = from_end ? g.L : 0.0, far = from_end ? 0.0 : g.L;
  if (joint_dist(m, c, g, far, P) <= d) {
    return far;
  }
  for (int k = 0; k < 32; k++) {
    const double mid = 0.5 * (near + far);
    if (joint_dist(m, c, g, mid, P) < d) {
      near = mid;
    } else {
      far = mid;
    }
  }
  return 0.5 * (near + far);
}

// σ on any piece where the TCP is d from P (P its end if from_end, else its start)
double sigma_at(const urt_model_t* m, const urt_ctrl_t* c, const urt_path_seg_t& g,
                const Vec3& P, double d, bool from_end) noexcept {
  double x;
  if (g.kind == URT_SEG_JOINT) {
    return joint_sigma_at(m, c, g, P, d, from_end);
  } else if (g.kind == URT_SEG_ARC) {  // a chord of length d
    x = 2.0 * g.rho * std::asin(std::fmin(1.0, d / (2.0 * g.rho)));
  } else {
    x = d;
  }
  x = std::fmin(x, g.L);
  return from_end ? g.L - x : x;
}

// the TCP position of any piece at σ
Vec3 piece_position(const urt_model_t* m, const urt_ctrl_t* c, const urt_path_seg_t& g,
                    double sigma) noexcept {
  if (g.kind == URT_SEG_JOINT) {
    double q[URT_NJ], dq[URT_NJ];
    joint_eval(g, sigma, q, dq);
    return tcp_position(m, c, q);
  }
  Vec3 p;
  Mat3 R;
  Vec6 dx;
  tool_eval(g, sigma, p, R, dx);
  return p;
}

// the joints of any piece at σ and their rate per unit path speed (tool pieces: IK near
// q_near, one solve); false: no IK solution
bool piece_joints(const urt_model_t* m, const urt_ctrl_t* c, const urt_path_seg_t& g,
                  double sigma, const double* q_near, double* q, double* dq) noexcept {
  if (g.kind == URT_SEG_JOINT) {
    joint_eval(g, sigma, q, dq);
    return true;
  }
  Vec3 p;
  Mat3 R;
  Vec6 dx;
  tool_eval(g, sigma, p, R, dx);
  const Vec3 r = rotvec_from_rotation(R);
  const double pose[6] = {p[0], p[1], p[2], r[0], r[1], r[2]};
  if (urt_ctrl_inverse_kinematics_tcp(m, c->tcp_offset, pose, q_near, q) != URT_OK) {
    return false;
  }
  Mat3 Rq;
  Vec3 pq;
  Mat6 J;
  tcp_kinematics(m->arm, c->tcp_offset, vec6(q), Rq, pq, &J);
  put6(dls_solve(J, dx, 0.0), dq);
  return true;
}

// ---- building a move's piece ----

bool bad_joint(const urt_ctrl_cmd_t& cmd) {
  if (cmd.kind == URT_CTRL_OPTIMOVEJ) {
    return !(cmd.a > 0.0 && cmd.a <= 1.0) || !(cmd.v > 0.0 && cmd.v <= 1.0) ||
           !std::isfinite(cmd.r) || cmd.r < 0.0;
  }
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.t) || cmd.t < 0.0 || !std::isfinite(cmd.r) || cmd.r < 0.0;
}

bool bad_tool(const urt_ctrl_cmd_t& cmd) {
  if (cmd.kind == URT_CTRL_OPTIMOVEL) {
    return !(cmd.a > 0.0 && cmd.a <= 1.0) || !(cmd.v > 0.0 && cmd.v <= 1.0) ||
           !std::isfinite(cmd.r) || cmd.r < 0.0;
  }
  if (cmd.kind == URT_CTRL_MOVEC && (!all_finite(cmd.q, 3) || (cmd.index != 0 && cmd.index != 1))) {
    return true;
  }
  return !(cmd.a > 0.0) || !(cmd.v > 0.0) || !std::isfinite(cmd.a) || !std::isfinite(cmd.v) ||
         !std::isfinite(cmd.t) || cmd.t < 0.0 || !std::isfinite(cmd.r) || cmd.r < 0.0;
}

// a joint move from q_s to cmd.q (movej's limits: the leading joint at a, v, every joint
// within its own; t as movej; optimovej's fractions)
void build_joint(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const double* q_s,
                 urt_path_move_t& mv, urt_path_seg_t& g) noexcept {
  const urt_model_t* m = e.m;
  std::memset(&g, 0, sizeof g);
  g.kind = URT_SEG_JOINT;
  double D = 0.0;
  for (int j = 0; j < URT_NJ; j++) {
    g.q0[j] = q_s[j];
    g.dq[j] = cmd.q[j] - q_s[j];
    D = std::fmax(D, std::fabs(g.dq[j]));
  }
  double v = cmd.v, a = cmd.a;
  if (cmd.kind == URT_CTRL_OPTIMOVEJ) {  // fractions of the limits: the slowest joint sets the pace
    v = a = HUGE_VAL;
    for (int j = 0; j < URT_NJ && D > 0.0; j++) {
      const double f = std::fabs(g.dq[j]) / D;
      if (f > 0.0) {
        v = std::fmin(v, cmd.v * kSpeedMargin * m->joint[j].qd_max / f);
        a = std::fmin(a, cmd.a * kAccMargin * m->joint[j].qdd_max / f);
      }
    }
  }
  for (int j = 0; j < URT_NJ && D > 0.0; j++) {
    const double f = std::fabs(g.dq[j]) / D;
    if (f > 0.0) {
      v = std::fmin(v, kSpeedMargin * m->joint[j].qd_max / f);
      a = std::fmin(a, kAccMargin * m->joint[j].qdd_max / f);
    }
  }
  if (cmd.kind == URT_CTRL_MOVEJ && cmd.t > 0.0 && D > 0.0) {
    const urt_trap_t fit = trap_plan(D, v, a, cmd.t);
    if (fit.vp <= v * 1.0000001 && fit.ap <= a * 1.0000001) {
      v = fit.vp;
      a = fit.ap;
    }
  }
  g.L = g.len = D;
  g.v_max = v;
  mv.a = a;
  mv.v = v;
  mv.joint = 1;
  mv.chord = (tcp_position(m, e.c, q_s) - tcp_position(m, e.c, cmd.q)).norm();
  put3(tcp_position(m, e.c, cmd.q), mv.end_p);
}

// a tool move from the pose (p_s, R_s): a line (movel, movep, optimovel) or an arc (movec)
bool build_tool(const MotionEnv& e, const urt_ctrl_cmd_t& cmd, const Vec3& p_s, const Mat3& R_s,
                urt_path_move_t& mv, urt_path_seg_t& g) noexcept {
  std::memset(&g, 0, sizeof g);
  const Vec3 p1(cmd.pose[0], cmd.pose[1], cmd.pose[2]);
  const Mat3 R1 = rotation_from_rotvec(Vec3(cmd.pose[3], cmd.pose[4], cmd.pose[5]));
  double v = cmd.v, a = cmd.a;
  if (cmd.kind == URT_CTRL_MOVEC) {
    const Vec3 pv(cmd.q[0], cmd.q[1], cmd.q[2]);
    const Vec3 ea = pv - p_s, eb = p1 - p_s, n = ea.cross(eb);
    const double n2 = n.squaredNorm();
    if (!(n2 > 1e-18) || ea.norm() < 1e-6 || eb.norm() < 1e-6 || (p1 - pv).norm() < 1e-6) {
      return false;  // the three points do not make a circle
    }
    const Vec3 C = p_s + (ea.squaredNorm() * eb.cross(n) + eb.squaredNorm() * n.cross(ea)) /
                             (2.0 * n2);
    g.kind = URT_SEG_ARC;
    g.rho = (p_s - C).norm();
    const Vec3 e1 = (p_s - C) / g.rho, e2 = n.normalized().cross(e1);
    put3(C, g.p0);
    put3(e1, g.e1);
    put3(e2, g.e2);
    const Vec3 w = p1 - C;
    double psi = std::atan2(w.dot(e2), w.dot(e1));
    if (psi <= 0.0) {
      psi += 2.0 * M_PI;
    }
    g.L = g.len = g.rho * psi;
    if (cmd.index == 1) {
      put3(rotvec_from_rotation(R_s), g.r0);
      g.orient = 1;
    } else {
      set_orientation(g, R_s, R1);
    }
  } else {
    const Vec3 dp = p1 - p_s;
    g.kind = URT_SEG_LINE;
    put3(p_s, g.p0);
    set_orientation(g, R_s, R1);
    if (dp.norm() > 1e-7) {
      g.L = g.len = dp.norm();
      put3(dp / dp.norm(), g.u);
    } else {  // a pure rotation: the path is the angle (a, v in rad/s², rad/s)
      g.L = g.len = g.theta;
    }
  }
  if (cmd.t > 0.0 && g.L > 0.0 && cmd.kind == URT_CTRL_MOVEL) {
    const urt_trap_t fit = trap_plan(g.L, v, a, cmd.t);
    v = fit.vp;
    a = fit.ap;
  }
  mv.fa = mv.fv = 0.0;
  if (cmd.kind == URT_CTRL_OPTIMOVEL) {
    mv.fa = cmd.a;
    mv.fv = cmd.v;
    v = a = HUGE_VAL;  // the joints' limits where it runs (opt_v, opt_a)
  }
  g.v_max = v;
  mv.a = a;
  mv.v = v;
  mv.joint = 0;
  mv.chord = (p1 - p_s).norm();
  put3(p1, mv.end_p);
  return true;
}

void new_move(urt_path_move_t& mv, const urt_ctrl_cmd_t& cmd) noexcept {
  std::memset(&mv, 0, sizeof mv);
  mv.id = cmd.id;
  mv.kind = cmd.kind;
  mv.r = cmd.r;
}

// the blend zone of move k: the path length before its end where the blend would begin
void set_zone(const MotionEnv& e, urt_path_state_t& st, int k) noexcept {
  urt_path_move_t& mv = st.move[k];
  urt_path_seg_t& g = st.seg[st.nseg - 1];
  const double d = std::fmin(mv.r, 0.5 * mv.chord);
  mv.zone = mv.r <= 0.0 ? 0.0
                        : g.s0 + g.len - sigma_at(e.m, e.c, g, v3(mv.end_p), d, true);
}

// ---- optimovel: the tool speed and acceleration the joints allow at the set-point ----

// from the joint rates per unit path speed w: the fractions of the tool speed and acceleration
// at which the fastest joint reaches its planned limit
void opti_from_rates(const urt_model_t* m, urt_path_move_t& mv, const double* w) noexcept {
  double v = HUGE_VAL, a = HUGE_VAL;
  for (int j = 0; j < URT_NJ; j++) {
    if (std::fabs(w[j]) > 1e-12) {
      v = std::fmin(v, kSpeedMargin * m->joint[j].qd_max / std::fabs(w[j]));
      a = std::fmin(a, kAccMargin * m->joint[j].qdd_max / std::fabs(w[j]));
    }
  }
  mv.opt_v = mv.fv * v;
  mv.opt_a = mv.fa * a;
}

void opti_limits(const MotionEnv& e, urt_path_move_t& mv, const Mat6& J, const Vec6& dx) {
  if (mv.fv <= 0.0) {
    return;
  }
  const Vec6 w = dls_solve(J, dx, dls_lambda(J));  // joint speed per unit path speed
  opti_from_rates(e.m, mv, w.data());
}

// ---- the set-point at the path position ----

// q1, qd1 at the head piece's position; false: no IK solution
bool place(const MotionEnv& e, urt_path_state_t& st) noexcept {
  urt_ctrl_t* c = e.c;
  const urt_path_seg_t& g = st.seg[0];
  const double sigma = g.s0 + st.s, rate = st.sd * e.scale;
  double q[URT_NJ], dq[URT_NJ];
  if (g.kind == URT_SEG_HERMITE) {
    const double T = g.T, u = T > 0.0 ? std::fmin(1.0, st.s / T) : 1.0;
    const double u2 = u * u, u3 = u2 * u;
    const double h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
    const double d00 = 6 * u2 - 6 * u, d10 = 3 * u2 - 4 * u + 1, d11 = 3 * u2 - 2 * u;
    for (int j = 0; j < URT_NJ; j++) {
      c->q1[j] = g.q0[j] + h10 * T * g.qd0[j] + h01 * g.dq[j] + h11 * T * g.qd1[j];
      const double qdt = (T > 0.0 ? -d00 * g.dq[j] / T : 0.0) + d10 * g.qd0[j] + d11 * g.qd1[j];
      c->qd1[j] = qdt * e.scale;
    }
    return true;
  }
  if (g.kind == URT_SEG_JOINT) {
    joint_eval(g, sigma, q, dq);
    for (int j = 0; j < URT_NJ; j++) {
      c->q1[j] = q[j];
      c->qd1[j] = dq[j] * rate;
    }
    return true;
  }
  Vec3 p;
  Mat3 R;
  Vec6 dx;
  tool_eval(g, sigma, p, R, dx);
  const Vec3 r = rotvec_from_rotation(R);
  const double pose[6] = {p[0], p[1], p[2], r[0], r[1], r[2]};
  if (urt_ctrl_inverse_kinematics_tcp(e.m, c->tcp_offset, pose, c->q1, q) != URT_OK) {
    return false;
  }
  Mat3 Rq;
  Vec3 pq;
  Mat6 J;
  tcp_kinematics(e.m->arm, c->tcp_offset, vec6(q), Rq, pq, &J);
  const Vec6 w = dls_solve(J, dx, 0.0);
  for (int j = 0; j < URT_NJ; j++) {
    c->q1[j] = q[j];
    c->qd1[j] = w[j] * rate;
  }
  opti_limits(e, st.move[g.move], J, dx);
  return true;
}

// ---- blending ----

// may move B (segment b, move record mb) follow move A (the last piece) with a blend?
bool blendable(const urt_path_state_t& st, const urt_path_move_t& mb,
               const urt_path_seg_t& b) noexcept {
  const urt_path_seg_t& a = st.seg[st.nseg - 1];
  const urt_path_move_t& ma = st.move[a.move];
  if (st.nseg + 2 > URT_PATH_SEGS || ma.r <= 0.0 || !(a.L > 0.0) || !(b.L > 0.0) ||
      std::fmin(ma.r, std::fmin(0.5 * ma.chord, 0.5 * mb.chord)) < kMinBlend) {
    return false;
  }
  // a tool line that is a pure rotation has no TCP path to blend along
  if ((a.kind == URT_SEG_LINE && v3(a.u).norm() < 0.5) ||
      (b.kind == URT_SEG_LINE && v3(b.u).norm() < 0.5)) {
    return false;
  }
  // two lines: not turning back on themselves
  return !(a.kind == URT_SEG_LINE && b.kind == URT_SEG_LINE) || v3(a.u).dot(v3(b.u)) > -1.0 + 1e-6;
}

// append the blend into B and B's rest behind the last piece (A's), shortening A
bool append_blend(const MotionEnv& e, urt_path_state_t& st, urt_path_seg_t b) noexcept {
  const urt_model_t* m = e.m;
  const urt_ctrl_t* c = e.c;
  urt_path_seg_t& a = st.seg[st.nseg - 1];
  const urt_path_move_t& ma = st.move[a.move];
  const urt_path_move_t& mb = st.move[b.move];
  const bool head = st.nseg == 1;
  const double left = a.len - (head ? st.s : 0.0);  // of A still to run
  double d = std::fmin(ma.r, std::fmin(0.5 * ma.chord, 0.5 * mb.chord));
  urt_path_seg_t bl;
  std::memset(&bl, 0, sizeof bl);
  bl.move = b.move;
  const bool lines = a.kind == URT_SEG_LINE && b.kind == URT_SEG_LINE;
  const bool joints = a.kind == URT_SEG_JOINT && b.kind == URT_SEG_JOINT;
  if (!lines && !joints) {
    // a joint move and a tool move, or an arc: a joint-space cubic between the points where the
    // TCP is d from the via point (one IK each end for a tool piece), timed from both speeds
    const Vec3 via = v3(ma.end_p);
    double sa = sigma_at(m, c, a, via, d, true);
    sa = std::fmax(sa, a.s0 + (a.len - left));
    const double dist_in = (piece_position(m, c, a, sa) - via).norm();
    const double sb = sigma_at(m, c, b, via, std::fmin(dist_in, d), false);
    double qa[URT_NJ], dqa[URT_NJ], qb[URT_NJ], dqb[URT_NJ];
    if (!piece_joints(m, c, a, sa, c->q1, qa, dqa) || !piece_joints(m, c, b, sb, qa, qb, dqb)) {
      return false;
    }
    a.len = sa - a.s0;
    bl.kind = URT_SEG_HERMITE;
    bl.orient = 1;           // mixed: A's units up to it, B's after it
    bl.len = bl.L = a.L - sa;  // of A (the look-ahead stops here)
    bl.rho = sb;               // of B
    bl.v_max = ma.v;
    for (int j = 0; j < URT_NJ; j++) {
      bl.q0[j] = qa[j];
      bl.dq[j] = qb[j] - qa[j];
      bl.qd0[j] = dqa[j];
      bl.qd1[j] = dqb[j];
    }
    if (mb.fv > 0.0) {  // optimovel after it: what the joints allow where it begins
      opti_from_rates(m, st.move[b.move], dqb);
    }
    b.s0 = sb;
    b.len = b.L - sb;
  } else if (joints) {
    // the TCP d from the via point on both moves; not before where A is now
    const Vec3 via = v3(ma.end_p);
    double sa = joint_sigma_at(m, c, a, via, d, true);
    sa = std::fmax(sa, a.s0 + (a.len - left));
    const double dist_in = joint_dist(m, c, a, sa, via);
    const double sb = joint_sigma_at(m, c, b, via, std::fmin(dist_in, d), false);
    a.len = sa - a.s0;
    double qa[URT_NJ], dqa[URT_NJ], qb[URT_NJ], dqb[URT_NJ];
    joint_eval(a, sa, qa, dqa);
    joint_eval(b, sb, qb, dqb);
    bl.kind = URT_SEG_HERMITE;
    bl.len = bl.L = (a.L - sa) + sb;  // path length it stands for (the look-ahead)
    bl.v_max = std::fmin(ma.v, mb.v);
    for (int j = 0; j < URT_NJ; j++) {
      bl.q0[j] = qa[j];
      bl.dq[j] = qb[j] - qa[j];
      bl.qd0[j] = dqa[j];  // per unit path speed; scaled when it starts
      bl.qd1[j] = dqb[j];
    }
    b.s0 = sb;
    b.len = b.L - sb;
  } else {
    d = std::fmin(d, left);
    a.len -= d;
    const Vec3 ua = v3(a.u), ub = v3(b.u);
    const Vec3 P0 = v3(a.p0) + ua * (a.s0 + a.len);
    const double cphi = std::fmax(-1.0, std::fmin(1.0, ua.dot(ub)));
    const double phi = std::acos(cphi);
    Vec3 p;
    Mat3 Ra, Rb;
    Vec6 dx;
    tool_eval(a, a.s0 + a.len, p, Ra, dx);
    tool_eval(b, b.s0 + d, p, Rb, dx);
    if (phi < 1e-9) {  // straight on
      bl.kind = URT_SEG_LINE;
      put3(P0, bl.p0);
      put3(ua, bl.u);
      bl.L = bl.len = 2.0 * d;
    } else {
      const Vec3 n1 = (ub - cphi * ua).normalized();
      bl.kind = URT_SEG_ARC;
      bl.rho = d / std::tan(0.5 * phi);
      put3(P0 + bl.rho * n1, bl.p0);
      put3(-n1, bl.e1);
      put3(ua, bl.e2);
      bl.L = bl.len = bl.rho * phi;
    }
    set_orientation(bl, Ra, Rb);
    bl.v_max = std::fmin(st.seg[st.nseg - 1].v_max, b.v_max);
    b.s0 += d;
    b.len -= d;
  }
  st.seg[st.nseg++] = bl;
  st.seg[st.nseg++] = b;
  return true;
}

// the head piece is done: the next one runs; entering B's pieces, B is the running move
void next_piece(const MotionEnv& e, urt_path_state_t& st) noexcept {
  urt_ctrl_t* c = e.c;
  for (int k = 1; k < st.nseg; k++) {
    st.seg[k - 1] = st.seg[k];
  }
  st.nseg--;
  urt_path_seg_t& g = st.seg[0];
  if (g.move == 1) {
    mark_done(c, st.move[0].id);
    st.move[0] = st.move[1];
    st.nmove = 1;
    for (int k = 0; k < st.nseg; k++) {
      st.seg[k].move = 0;
    }
    c->motion_id = st.move[0].id;
    c->active = c->pending;
    c->has_pending = 0;
  }
  if (g.kind == URT_SEG_HERMITE && g.orient == 1) {
    // mixed units: B starts at its own speed, as far as it can still stop; each half of the
    // blend takes the time its length needs at its end's speed
    const urt_path_seg_t& nb = st.seg[1];
    const urt_path_move_t& mb = st.move[nb.move];
    double rest = 0.0;
    for (int k = 1; k < st.nseg; k++) {
      rest += st.seg[k].len;
    }
    const double a_b = mb.fa > 0.0 ? mb.opt_a : mb.a;
    const double v_b = mb.fv > 0.0 ? mb.opt_v : nb.v_max;
    const double vin = std::fmax(st.sd, 1e-3),
                 vout = std::fmax(1e-3, std::fmin(v_b, std::sqrt(2.0 * a_b * rest)));
    g.T = g.len / vin + g.rho / vout;
    for (int j = 0; j < URT_NJ; j++) {
      g.qd0[j] *= st.sd;
      g.qd1[j] *= vout;
    }
    st.sd = vout;
  } else if (g.kind == URT_SEG_HERMITE) {
    // from the speed the arm has now to the speed B starts with
    const double vin = st.sd, vout = std::fmin(g.v_max, std::fmax(st.sd, 0.0));
    g.T = vin + vout > 1e-9 ? 2.0 * g.len / (vin + vout) : 0.0;
    for (int j = 0; j < URT_NJ; j++) {
      g.qd0[j] *= vin;
      g.qd1[j] *= vout;
    }
    st.sd = vout;
  }
}

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

// the path speed allowed now: the head piece's limit, what can still brake to every slower
// piece ahead and to rest at the end
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
  return std::fmin(lim, std::sqrt(2.0 * a * to_end));
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
    opti_limits(e, st.move[0], J, dx);
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
      // the blend is over: on to B at the speed it ends with
      const double over = st.s - st.seg[0].T;
      next_piece(e, st);
      st.s = over * st.sd;
    }
  } else {
    const double a = accel(st);
    double to_end;
    const double lim = speed_limit(st, a, to_end);
    const double sd1 = std::fmax(0.0, std::fmin(st.sd + a * dt, lim));
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
      while (st.nseg > 1 && st.seg[0].kind != URT_SEG_HERMITE && st.s >= st.seg[0].len) {
        const double over = st.s - st.seg[0].len;
        next_piece(e, st);
        st.s = st.seg[0].kind == URT_SEG_HERMITE ? (st.sd > 0.0 ? over / st.sd : 0.0) : over;
      }
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
      opti_limits(e, mb, J, dx);
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
