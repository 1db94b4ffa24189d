/* SPDX-License-Identifier: Apache-2.0
 * net/dds/dds_trajectory.c — sampling a joint trajectory by segment splines, as
 * joint_trajectory_controller does (linear, cubic or quintic by what the points give), and the
 * trajectory's own clock. */
#include "urt/net/dds_trajectory.h"

#include <math.h>
#include <stdlib.h>

// one joint over one segment of length T from (q0, v0, a0) to (q1, v1, a1) at time s in [0, T]
static void segment(int kind, double T, double q0, double v0, double a0, double q1, double v1,
                    double a1, double s, double *q, double *v) {
  if (kind == 0 || T <= 0.0) {  // linear
    double slope = T > 0.0 ? (q1 - q0) / T : 0.0;
    *q = q0 + slope * s;
    *v = slope;
    return;
  }
  double c0 = q0, c1 = v0, c2, c3, c4 = 0.0, c5 = 0.0;
  double T2 = T * T, T3 = T2 * T;
  if (kind == 1) {  // cubic Hermite
    c2 = (3.0 * (q1 - q0) - (2.0 * v0 + v1) * T) / T2;
    c3 = (2.0 * (q0 - q1) + (v0 + v1) * T) / T3;
  } else {  // quintic with end accelerations
    double T4 = T3 * T, T5 = T4 * T;
    c2 = 0.5 * a0;
    c3 = (20.0 * (q1 - q0) - (8.0 * v1 + 12.0 * v0) * T - (3.0 * a0 - a1) * T2) / (2.0 * T3);
    c4 = (30.0 * (q0 - q1) + (14.0 * v1 + 16.0 * v0) * T + (3.0 * a0 - 2.0 * a1) * T2) / (2.0 * T4);
    c5 = (12.0 * (q1 - q0) - 6.0 * (v1 + v0) * T - (a0 - a1) * T2) / (2.0 * T5);
  }
  *q = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))));
  *v = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)));
}

double urt_dds_traj_duration(const urt_dds_traj_t *tr) {
  return tr->n > 0 ? tr->p[tr->n - 1].t : 0.0;
}

void urt_dds_traj_eval(const urt_dds_traj_t *tr, double t, double q[URT_NJ], double qd[URT_NJ]) {
  const urt_dds_traj_point_t *last = &tr->p[tr->n - 1];
  if (t >= last->t || tr->n == 1) {
    for (int j = 0; j < URT_NJ; j++) {
      q[j] = last->q[j];
      qd[j] = 0.0;
    }
    return;
  }
  if (t < tr->p[0].t) {
    t = tr->p[0].t;
  }
  size_t i = 0;
  while (i + 2 < tr->n && t >= tr->p[i + 1].t) {
    i++;
  }
  const urt_dds_traj_point_t *a = &tr->p[i], *b = &tr->p[i + 1];
  int kind = a->has_qdd && b->has_qdd ? 2 : (a->has_qd && b->has_qd ? 1 : 0);
  double T = b->t - a->t, s = t - a->t;
  for (int j = 0; j < URT_NJ; j++) {
    segment(kind, T, a->q[j], a->qd[j], a->qdd[j], b->q[j], b->qd[j], b->qdd[j], s, &q[j], &qd[j]);
  }
}

void urt_dds_traj_clock_start(urt_dds_traj_clock_t *c, double t0) {
  c->t0 = t0;
  c->next = NAN;
}

double urt_dds_traj_clock_at(const urt_dds_traj_clock_t *c, double end) {
  return isnan(c->next) ? end - c->t0 : c->next;
}

void urt_dds_traj_clock_sent(urt_dds_traj_clock_t *c, double tau, double period) {
  c->next = tau + period;
}

void urt_dds_traj_free(urt_dds_traj_t *tr) {
  if (tr != NULL) {
    free(tr->p);
    tr->p = NULL;
    tr->n = 0;
  }
}
