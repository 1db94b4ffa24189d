// SPDX-License-Identifier: Apache-2.0
// tools/traj.cpp — joint-space test trajectories (model.md §6.2); the contract is in traj.h.
#include "traj.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "urt/errors.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

// samples per period for the certified Fourier bounds: the h²/8 margin is then of order 10⁻⁴
// relative or less for 8 harmonics, tight enough to scale the coefficients against
constexpr int kGrid = 4096;

//---- deterministic random numbers ----

// splitmix64 (Steele, Lea, Flood 2014): one 64-bit state, full period, good enough to draw
// coefficients, and unlike rand() it gives the same stream on every platform
uint64_t splitmix64(uint64_t *s) {
  uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// uniform in [−1, 1) from the top 53 bits
double uniform_pm1(uint64_t *s) {
  return (double)(splitmix64(s) >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

bool finite6(const double q[URT_NJ]) {
  for (int j = 0; j < URT_NJ; j++) {
    if (!std::isfinite(q[j])) {
      return false;
    }
  }
  return true;
}

bool positive_finite(double x) { return std::isfinite(x) && x > 0.0; }

void set6(double *out, const double *in) {
  if (out) {
    std::memcpy(out, in, sizeof(double) * URT_NJ);
  }
}

void zero6(double *out) {
  if (out) {
    std::memset(out, 0, sizeof(double) * URT_NJ);
  }
}

//---- Fourier helpers ----

double fourier_duration(const urt_traj_fourier_t *f) { return f->periods / f->f_f; }

// sin(ωlt), cos(ωlt) for l = 1..n, shared by all joints
void harmonics(const urt_traj_fourier_t *f, double t, double *s, double *c) {
  double w = 2.0 * kPi * f->f_f;
  for (int l = 1; l <= f->n; l++) {
    double arg = w * l * t;
    s[l - 1] = std::sin(arg);
    c[l - 1] = std::cos(arg);
  }
}

// one joint's q − q0, q̇, q̈ from precomputed harmonics
void fourier_joint(const urt_traj_fourier_t *f, int i, const double *s, const double *c,
                   double *dq, double *qd, double *qdd) {
  double w = 2.0 * kPi * f->f_f;
  double p = 0.0, v = 0.0, acc = 0.0;
  for (int l = 1; l <= f->n; l++) {
    double a = f->a[i][l - 1], b = f->b[i][l - 1], wl = w * l;
    p += (a * s[l - 1] - b * (c[l - 1] - 1.0)) / wl;
    v += a * c[l - 1] + b * s[l - 1];
    acc += wl * (-a * s[l - 1] + b * c[l - 1]);
  }
  *dq = p;
  *qd = v;
  *qdd = acc;
}

//---- trapezoid helpers ----

// distance travelled by the lead joint, its speed and acceleration at time t within move mv;
// the boundaries are absolute times computed in one fixed order, so that t = t_stop (and the
// next move's t0) lands exactly on the rest phase
void profile(const urt_traj_move_t *mv, double t, int *phase, double *s, double *sd,
             double *sdd) {
  double t1 = mv->t0 + mv->t_acc, t2 = t1 + mv->t_cruise;
  if (t < t1) {
    double tau = t - mv->t0;
    *phase = 0;
    *s = 0.5 * mv->a * tau * tau;
    *sd = mv->a * tau;
    *sdd = mv->a;
  } else if (t < t2) {
    *phase = 1;
    *s = 0.5 * mv->a * mv->t_acc * mv->t_acc + mv->v_peak * (t - t1);
    *sd = mv->v_peak;
    *sdd = 0.0;
  } else if (t < mv->t_stop) {
    // measured back from the stop, so that the move ends exactly on its target
    double r = mv->t_stop - t;
    *phase = 2;
    *s = 0.5 * mv->d * r * r;
    *sd = mv->d * r;
    *sdd = -mv->d;
  } else {
    *phase = 3;
    *s = 0.0;
    *sd = 0.0;
    *sdd = 0.0;
  }
}

}  // namespace

//---- excitation ----

void urt_traj_fourier_opts_default(urt_traj_fourier_opts_t *o) {
  o->f_f = 0.1;
  o->n = 5;
  o->periods = 1;
  for (int j = 0; j < URT_NJ; j++) {
    // the wrists carry little and sit far from the floor, so they may swing further
    o->amp_max[j] = j < 4 ? 0.8 : 1.2;
    o->qd_max[j] = 1.0;
    o->qdd_max[j] = 3.0;
  }
}

void urt_traj_fourier_bounds(const urt_traj_fourier_t *f, double amp[URT_NJ],
                                        double qd[URT_NJ], double qdd[URT_NJ]) {
  double g_amp[URT_NJ] = {0}, g_qd[URT_NJ] = {0}, g_qdd[URT_NJ] = {0};
  double period = 1.0 / f->f_f, h = period / kGrid, w = 2.0 * kPi * f->f_f;

  // maxima on the grid; the series is periodic, so one period covers every later one
  for (int k = 0; k < kGrid; k++) {
    double s[URT_TRAJ_FOURIER_NMAX], c[URT_TRAJ_FOURIER_NMAX];
    harmonics(f, k * h, s, c);
    for (int i = 0; i < URT_NJ; i++) {
      double p, v, acc;
      fourier_joint(f, i, s, c, &p, &v, &acc);
      g_amp[i] = std::max(g_amp[i], std::fabs(p));
      g_qd[i] = std::max(g_qd[i], std::fabs(v));
      g_qdd[i] = std::max(g_qdd[i], std::fabs(acc));
    }
  }

  // an extremum lies within h/2 of a sample where the slope is zero, so it exceeds the
  // sample by at most (h/2)²/2 · max|second derivative|; bound that by the coefficients
  for (int i = 0; i < URT_NJ; i++) {
    double c_amp = 0.0, c_qd = 0.0, c_qdd = 0.0;
    for (int l = 1; l <= f->n; l++) {
      double r = std::hypot(f->a[i][l - 1], f->b[i][l - 1]), wl = w * l;
      c_amp += wl * r;
      c_qd += wl * wl * r;
      c_qdd += wl * wl * wl * r;
    }
    double m = h * h / 8.0;
    if (amp) {
      amp[i] = g_amp[i] + m * c_amp;
    }
    if (qd) {
      qd[i] = g_qd[i] + m * c_qd;
    }
    if (qdd) {
      qdd[i] = g_qdd[i] + m * c_qdd;
    }
  }
}

int urt_traj_fourier_random(urt_traj_fourier_t *f, const double q0[URT_NJ],
                                       const urt_traj_fourier_opts_t *o, uint64_t seed) {
  urt_traj_fourier_opts_t def;
  if (!o) {
    urt_traj_fourier_opts_default(&def);
    o = &def;
  }

  // validate everything before touching f
  if (!finite6(q0) || !positive_finite(o->f_f) || o->n < 1 || o->n > URT_TRAJ_FOURIER_NMAX ||
      o->periods < 1) {
    return URT_EINVAL;
  }
  for (int j = 0; j < URT_NJ; j++) {
    if (!positive_finite(o->amp_max[j]) || !positive_finite(o->qd_max[j]) ||
        !positive_finite(o->qdd_max[j])) {
      return URT_EINVAL;
    }
  }

  urt_traj_fourier_t g;
  std::memset(&g, 0, sizeof g);
  std::memcpy(g.q0, q0, sizeof g.q0);
  g.f_f = o->f_f;
  g.n = o->n;
  g.periods = o->periods;

  // draw, then project onto the rest conditions Σ a_l = 0 and Σ l·b_l = 0 (orthogonal
  // projections, so no harmonic is singled out)
  uint64_t state = seed;
  for (int i = 0; i < URT_NJ; i++) {
    for (int l = 0; l < g.n; l++) {
      g.a[i][l] = uniform_pm1(&state);
      g.b[i][l] = uniform_pm1(&state);
    }
    double sa = 0.0, slb = 0.0, sll = 0.0;
    for (int l = 1; l <= g.n; l++) {
      sa += g.a[i][l - 1];
      slb += l * g.b[i][l - 1];
      sll += (double)l * l;
    }
    for (int l = 1; l <= g.n; l++) {
      g.a[i][l - 1] -= sa / g.n;
      g.b[i][l - 1] -= slb * l / sll;
    }
  }

  // with one harmonic the rest conditions force a = b = 0: the joint stays at q0
  double amp[URT_NJ], qd[URT_NJ], qdd[URT_NJ];
  urt_traj_fourier_bounds(&g, amp, qd, qdd);

  // every quantity is linear in the coefficients, so one factor per joint meets the tightest
  // bound; the 1e-12 keeps rounding in the evaluation from landing a hair above it
  for (int i = 0; i < URT_NJ; i++) {
    double k = HUGE_VAL;
    if (amp[i] > 0.0) {
      k = std::min(k, o->amp_max[i] / amp[i]);
    }
    if (qd[i] > 0.0) {
      k = std::min(k, o->qd_max[i] / qd[i]);
    }
    if (qdd[i] > 0.0) {
      k = std::min(k, o->qdd_max[i] / qdd[i]);
    }
    if (!std::isfinite(k)) {
      k = 0.0;
    }
    k *= 1.0 - 1e-12;
    for (int l = 0; l < g.n; l++) {
      g.a[i][l] *= k;
      g.b[i][l] *= k;
    }
  }

  *f = g;
  return 0;
}

void urt_traj_fourier_eval(const urt_traj_fourier_t *f, double t, double q[URT_NJ],
                                      double qd[URT_NJ], double qdd[URT_NJ]) {
  // outside the played periods the arm rests at q0 (where the series starts and ends)
  if (!(t > 0.0 && t < fourier_duration(f))) {
    set6(q, f->q0);
    zero6(qd);
    zero6(qdd);
    return;
  }

  double s[URT_TRAJ_FOURIER_NMAX], c[URT_TRAJ_FOURIER_NMAX];
  harmonics(f, t, s, c);
  for (int i = 0; i < URT_NJ; i++) {
    double p, v, acc;
    fourier_joint(f, i, s, c, &p, &v, &acc);
    if (q) {
      q[i] = f->q0[i] + p;
    }
    if (qd) {
      qd[i] = v;
    }
    if (qdd) {
      qdd[i] = acc;
    }
  }
}

//---- pick-and-place ----

void urt_traj_pickplace_init(urt_traj_pickplace_t *p, const double q0[URT_NJ]) {
  std::memset(p, 0, sizeof *p);
  std::memcpy(p->q0, q0, sizeof p->q0);
}

int urt_traj_pickplace_add(urt_traj_pickplace_t *p, const double q[URT_NJ], double v,
                                      double a, double d, double dwell) {
  if (p->n >= URT_TRAJ_PICKPLACE_NMAX) {
    return URT_ENOSPC;
  }
  if (!finite6(q) || !positive_finite(v) || !positive_finite(a) || !std::isfinite(d) ||
      d < 0.0 || !std::isfinite(dwell) || dwell < 0.0) {
    return URT_EINVAL;
  }
  if (d == 0.0) {
    d = a;
  }

  urt_traj_move_t mv;
  std::memset(&mv, 0, sizeof mv);
  std::memcpy(mv.q, q, sizeof mv.q);
  mv.v = v;
  mv.a = a;
  mv.d = d;
  mv.dwell = dwell;
  mv.t0 = p->duration;
  const double *from = p->n > 0 ? p->move[p->n - 1].q : p->q0;
  std::memcpy(mv.q_from, from, sizeof mv.q_from);

  // the lead joint is the one with the largest distance; it alone runs at (v, a, d)
  mv.lead = -1;
  for (int j = 0; j < URT_NJ; j++) {
    double dj = std::fabs(q[j] - from[j]);
    if (dj > mv.dist) {
      mv.dist = dj;
      mv.lead = j;
    }
  }

  if (mv.lead >= 0) {
    // every joint follows the lead's normalised profile, so all start and stop together
    for (int j = 0; j < URT_NJ; j++) {
      mv.ratio[j] = (q[j] - from[j]) / mv.dist;
    }

    // trapezoid if v is reached, else triangular with the same a and d
    double t_c = (mv.dist - v * v / (2.0 * a) - v * v / (2.0 * d)) / v;
    if (t_c > 0.0) {
      mv.v_peak = v;
      mv.t_cruise = t_c;
    } else {
      mv.v_peak = std::sqrt(2.0 * mv.dist * a * d / (a + d));
      mv.t_cruise = 0.0;
    }
    mv.t_acc = mv.v_peak / a;
    mv.t_dec = mv.v_peak / d;
  }

  mv.t_stop = mv.t0 + mv.t_acc + mv.t_cruise + mv.t_dec;
  p->move[p->n++] = mv;
  p->duration = mv.t_stop + mv.dwell;
  return 0;
}

int urt_traj_pickplace_default(urt_traj_pickplace_t *p, const double q0[URT_NJ]) {
  if (!finite6(q0)) {
    return URT_EINVAL;
  }
  const double h = kPi / 2.0;

  // tool pointing down (q2 + q3 + q4 = −π/2, wrist 2 at −π/2); a pick site on one side of the
  // base and a place site on the other, each with an approach pose 15–20 cm above it (TCP
  // heights 7–43 cm above the base plane for the nominal UR5)
  const double home[URT_NJ] = {0.0, -h, h, -h, -h, 0.0};
  const double pick_above[URT_NJ] = {0.9, -1.25, 1.75, -h - 0.50, -h, 0.9};
  const double pick[URT_NJ] = {0.9, -1.00, 1.85, -h - 0.85, -h, 0.9};
  const double place_above[URT_NJ] = {-0.8, -1.35, 1.65, -h - 0.30, -h, -0.8};
  const double place[URT_NJ] = {-0.8, -1.05, 1.80, -h - 0.75, -h, -0.8};

  // the stress event: wrist 2 swings the (empty) flange 1.6 rad at 180°/s; the 2500°/s² stop
  // lasts 72 ms, and the 0.35 s dwell before it puts the stop at about 8.5 s as in Fig. 11
  double turn[URT_NJ];
  std::memcpy(turn, place_above, sizeof turn);
  turn[4] += 1.6;

  const double A = URT_TRAJ_MOVEJ_A, V = URT_TRAJ_MOVEJ_V;
  const double a_slow = 1.0, v_slow = 0.5;
  urt_traj_pickplace_init(p, q0);
  int rc = 0;
  rc |= urt_traj_pickplace_add(p, q0, V, A, 0.0, 0.5);  // rest before the first move
  rc |= urt_traj_pickplace_add(p, home, V, A, 0.0, 0.0);  // no-op when q0 is home
  rc |= urt_traj_pickplace_add(p, pick_above, V, A, 0.0, 0.2);
  rc |= urt_traj_pickplace_add(p, pick, v_slow, a_slow, 0.0, 0.4);  // grip
  rc |= urt_traj_pickplace_add(p, pick_above, v_slow, a_slow, 0.0, 0.1);
  rc |= urt_traj_pickplace_add(p, place_above, V, A, 0.0, 0.35);
  rc |= urt_traj_pickplace_add(p, turn, URT_TRAJ_STRESS_V, URT_TRAJ_STRESS_A, 0.0, 0.4);
  rc |= urt_traj_pickplace_add(p, place, V, A, 0.0, 0.4);  // release
  rc |= urt_traj_pickplace_add(p, place_above, v_slow, a_slow, 0.0, 0.1);
  rc |= urt_traj_pickplace_add(p, home, V, A, 0.0, 0.5);
  return rc ? URT_EINVAL : 0;
}

void urt_traj_pickplace_eval(const urt_traj_pickplace_t *p, double t,
                                        double q[URT_NJ], double qd[URT_NJ],
                                        double qdd[URT_NJ]) {
  // before the first move (or with none) rest at the start
  if (p->n == 0 || !(t >= p->move[0].t0)) {
    set6(q, p->q0);
    zero6(qd);
    zero6(qdd);
    return;
  }

  // the last move that has started (binary search: moves are in time order)
  int lo = 0, hi = p->n - 1;
  while (lo < hi) {
    int mid = (lo + hi + 1) / 2;
    if (p->move[mid].t0 <= t) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  const urt_traj_move_t *mv = &p->move[lo];

  // a pure dwell, or the move is over and the arm rests at its target
  int phase = 3;
  double s = 0.0, sd = 0.0, sdd = 0.0;
  if (mv->lead >= 0) {
    profile(mv, t, &phase, &s, &sd, &sdd);
  }
  for (int j = 0; j < URT_NJ; j++) {
    double pos;
    if (phase == 3) {
      pos = mv->q[j];
    } else if (phase == 2) {
      pos = mv->q[j] - mv->ratio[j] * s;
    } else {
      pos = mv->q_from[j] + mv->ratio[j] * s;
    }
    if (q) {
      q[j] = pos;
    }
    if (qd) {
      qd[j] = mv->ratio[j] * sd;
    }
    if (qdd) {
      qdd[j] = mv->ratio[j] * sdd;
    }
  }
}

//---- any trajectory ----

void urt_traj_make_hold(urt_traj_t *tr, const double q[URT_NJ], double duration) {
  std::memset(tr, 0, sizeof *tr);
  tr->kind = URT_TRAJ_HOLD;
  std::memcpy(tr->hold_q, q, sizeof tr->hold_q);
  tr->hold_duration = duration;
}

int urt_traj_make_excitation(urt_traj_t *tr, const double q0[URT_NJ],
                                        const urt_traj_fourier_opts_t *o, uint64_t seed) {
  urt_traj_fourier_t f;
  int rc = urt_traj_fourier_random(&f, q0, o, seed);
  if (rc) {
    return rc;
  }
  std::memset(tr, 0, sizeof *tr);
  tr->kind = URT_TRAJ_FOURIER;
  tr->u.fourier = f;
  return 0;
}

int urt_traj_make_pickplace(urt_traj_t *tr, const double q0[URT_NJ]) {
  if (!finite6(q0)) {
    return URT_EINVAL;
  }
  std::memset(tr, 0, sizeof *tr);
  tr->kind = URT_TRAJ_PICKPLACE;
  return urt_traj_pickplace_default(&tr->u.pp, q0);
}

void urt_traj_eval(const urt_traj_t *tr, double t, double q[URT_NJ],
                              double qd[URT_NJ], double qdd[URT_NJ]) {
  switch (tr->kind) {
    case URT_TRAJ_FOURIER:
      urt_traj_fourier_eval(&tr->u.fourier, t, q, qd, qdd);
      return;
    case URT_TRAJ_PICKPLACE:
      urt_traj_pickplace_eval(&tr->u.pp, t, q, qd, qdd);
      return;
    case URT_TRAJ_HOLD:
    default:
      set6(q, tr->hold_q);
      zero6(qd);
      zero6(qdd);
      return;
  }
}

double urt_traj_duration(const urt_traj_t *tr) {
  switch (tr->kind) {
    case URT_TRAJ_FOURIER:
      return fourier_duration(&tr->u.fourier);
    case URT_TRAJ_PICKPLACE:
      return tr->u.pp.duration;
    case URT_TRAJ_HOLD:
    default:
      return tr->hold_duration;
  }
}

void urt_traj_peaks(const urt_traj_t *tr, double q_lo[URT_NJ], double q_hi[URT_NJ],
                               double qd_peak[URT_NJ], double qdd_peak[URT_NJ]) {
  double lo[URT_NJ], hi[URT_NJ], vp[URT_NJ] = {0}, ap[URT_NJ] = {0};

  switch (tr->kind) {
    case URT_TRAJ_FOURIER: {
      const urt_traj_fourier_t *f = &tr->u.fourier;
      double amp[URT_NJ];
      urt_traj_fourier_bounds(f, amp, vp, ap);
      for (int j = 0; j < URT_NJ; j++) {
        lo[j] = f->q0[j] - amp[j];
        hi[j] = f->q0[j] + amp[j];
      }
      break;
    }
    case URT_TRAJ_PICKPLACE: {
      // every move is monotone per joint, so the range is spanned by the waypoints
      const urt_traj_pickplace_t *p = &tr->u.pp;
      std::memcpy(lo, p->q0, sizeof lo);
      std::memcpy(hi, p->q0, sizeof hi);
      for (int k = 0; k < p->n; k++) {
        const urt_traj_move_t *mv = &p->move[k];
        for (int j = 0; j < URT_NJ; j++) {
          lo[j] = std::min(lo[j], mv->q[j]);
          hi[j] = std::max(hi[j], mv->q[j]);
          if (mv->lead >= 0) {
            vp[j] = std::max(vp[j], std::fabs(mv->ratio[j]) * mv->v_peak);
            ap[j] = std::max(ap[j], std::fabs(mv->ratio[j]) * std::max(mv->a, mv->d));
          }
        }
      }
      break;
    }
    case URT_TRAJ_HOLD:
    default:
      std::memcpy(lo, tr->hold_q, sizeof lo);
      std::memcpy(hi, tr->hold_q, sizeof hi);
      break;
  }

  set6(q_lo, lo);
  set6(q_hi, hi);
  set6(qd_peak, vp);
  set6(qdd_peak, ap);
}

int urt_traj_check(const urt_traj_t *tr, const urt_model_t *m, char *err, size_t err_sz) {
  double lo[URT_NJ], hi[URT_NJ], vp[URT_NJ], ap[URT_NJ];
  urt_traj_peaks(tr, lo, hi, vp, ap);

  // the same comparisons urt_command_set makes, in the same direction (equal is accepted)
  for (int j = 0; j < URT_NJ; j++) {
    const urt_joint_params_t *jp = &m->joint[j];
    struct {
      bool bad;
      const char *what, *op, *limit, *unit;
      double val, lim;
    } c[] = {
        {lo[j] < jp->q_min, "lowest position", "<", "q_min", "rad", lo[j], jp->q_min},
        {hi[j] > jp->q_max, "highest position", ">", "q_max", "rad", hi[j], jp->q_max},
        {vp[j] > jp->qd_max, "peak speed", ">", "qd_max", "rad/s", vp[j], jp->qd_max},
        {ap[j] > jp->qdd_max, "peak acceleration", ">", "qdd_max", "rad/s^2", ap[j],
         jp->qdd_max},
    };
    for (const auto &ci : c) {
      if (!ci.bad) {
        continue;
      }
      if (err && err_sz) {
        std::snprintf(err, err_sz, "%s trajectory, joint %d (%s): %s %.10g %s %s %s %.10g %s",
                      urt_traj_kind_name(tr->kind), j + 1, jp->name, ci.what, ci.val, ci.unit,
                      ci.op, ci.limit, ci.lim, ci.unit);
      }
      return URT_ERANGE;
    }
  }
  return 0;
}

const char *urt_traj_kind_name(urt_traj_kind_t kind) {
  switch (kind) {
    case URT_TRAJ_HOLD:
      return "hold";
    case URT_TRAJ_FOURIER:
      return "excitation";
    case URT_TRAJ_PICKPLACE:
      return "pickplace";
  }
  return "unknown";
}
