/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/core.h — the public API of the physics core.
 *
 *   config/ur5.yaml ──urt_model_load()──▶ const urt_model_t ──urt_data_init()──▶ urt_data_t
 *   urt_command_set(m, d, cmd)  then  urt_step(m, d)  advances exactly m->dt.
 */
#ifndef URT_CORE_H
#define URT_CORE_H

#include <stddef.h>
#include <stdio.h>

#include "urt/data.h"
#include "urt/errors.h"
#include "urt/faults.h"
#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

//---- model ----

/* Load and validate a robot parameter file, then prepare it (derived values, integrator
 * tables). overrides: NULL or a NULL-terminated list of "key.path=value" strings applied to
 * the YAML tree before validation (e.g. "sensors.noise=false", "simulation.dt=1e-4").
 * Context: non-RT (reads files, allocates).
 * Returns 0, or URT_ECONFIG / URT_EIO / URT_ENOMEM / URT_ESOLVER. On failure *out is untouched
 * and err (if not NULL, at most err_sz bytes) receives "file:line: key: reason" — or
 * "file:override: key: reason" for a bad override, "file:line: syntax error: …" for bad YAML,
 * "file: cannot open: …". Nullable: overrides, err. */
int urt_model_load(const char *path, const char *const *overrides, urt_model_t **out, char *err,
                   size_t err_sz);

/* As urt_model_load, with overlay files applied in order after the config (and its
 * `include:`s) and before the overrides. An overlay is YAML: `overlay:` (free-form
 * provenance), `include:` (overlays, relative to it) and `set:` with --set keys, each a bare
 * value or {value, unit, from, residual}; config/README.md has the rules. An overlay's error
 * reads "overlayfile:line: key: reason". Nullable: overlays, overrides, err. Context: non-RT. */
int urt_model_load_overlays(const char *path, const char *const *overlays,
                            const char *const *overrides, urt_model_t **out, char *err,
                            size_t err_sz);

/* The unit of a config key ("joints.1.friction.f_c" → "N m"), as urt_model_print writes it,
 * or NULL when the key is not one of the file's. Context: any. */
const char *urt_config_key_unit(const char *key);

/* Compute derived parameters and integrator tables of a filled-in model (the loader calls this).
 * Context: non-RT (allocates m->tables). Returns 0 or URT_ENOMEM / URT_ESOLVER. */
int urt_model_prepare(urt_model_t *m);

/* Free a model from urt_model_load (or prepared by urt_model_prepare). Nullable: m. */
void urt_model_free(urt_model_t *m);

/* Write the fully resolved model (every parameter, derived ones marked) as YAML or JSON.
 * Context: non-RT. json: 0 YAML, 1 JSON. */
void urt_model_print(const urt_model_t *m, FILE *f, int json);

//---- data ----

/* Initialise caller-owned data at rest at m->q0 (or at q when q is not NULL) with the
 * transient-free equilibrium of eq. (6) under gravity (model.md §1.5): set-point = q,
 * every filter at its measured value, z = 0. Context: any; no allocation. Nullable: q.
 * Returns 0 or URT_ESOLVER. */
int urt_data_init(const urt_model_t *m, urt_data_t *d, const double *q);

/* Mount a payload on link 6 from the next step on (urt_step, urt_rhs and the controller's
 * model all read d->live.payload). A payload urt_payload_invalid() refuses is not installed.
 * Context: RT (the controller calls it at a tick boundary). Returns 0 or URT_EINVAL. */
int urt_data_set_payload(const urt_model_t *m, urt_data_t *d, const urt_payload_t *p);

/* As urt_data_set_payload, reached linearly (mass, CoG and inertia element by element) over
 * transition_time [s] in steps of urt_data_live_advance; 0 is at once. transition_time must be
 * finite and in [0, 1000]. Context: RT. Returns 0 or URT_EINVAL (nothing changes). */
int urt_data_set_payload_target(const urt_model_t *m, urt_data_t *d, const urt_payload_t *p,
                                double transition_time);

/* Advance the live parameters' transitions by h [s] (the controller calls it once a tick, before
 * it plans; without a transition it changes nothing). Context: RT. */
void urt_data_live_advance(const urt_model_t *m, urt_data_t *d, double h);

/* Validate and install a joint command. A command with NaN/Inf, positions outside the joint
 * limits, speeds above qd_max, accelerations above qdd_max or torques above torque_max is
 * refused: the previous set-point is held (frozen at the current measured position, zero
 * speed) and d->pstop gets the cause. Context: RT. Returns 0 or URT_EPSTOP. */
int urt_command_set(const urt_model_t *m, urt_data_t *d, const urt_command_t *cmd);

/* Clear the protective stop; the set-point becomes the current joint position at rest.
 * Context: RT. */
void urt_pstop_reset(const urt_model_t *m, urt_data_t *d);

/* The protective-stop causes of bits (URT_PSTOP_*) as text, "position limit, speed limit", or
 * "none", into buf (always NUL-terminated when n > 0). Returns buf. Context: any. */
const char *urt_pstop_text(uint32_t bits, char *buf, size_t n);

//---- step ----

/* Advance the simulation by exactly m->dt with the fixed-step ROS2 scheme (model.md §5.3);
 * updates the state, time, d->qdd and the held sensor errors (see urt_data_update_outputs).
 * Context: RT — no allocation, no locks, no system calls, no printing.
 * Returns 0, or URT_ESOLVER if the state became non-finite (the step is undone and
 * URT_PSTOP_NONFINITE_STATE set). */
int urt_step(const urt_model_t *m, urt_data_t *d);

/* Right-hand side of the whole continuous model, xdot = f(t, x), for the reference solver:
 * time s since the beginning of the current step (the set-point follows the step's command),
 * with d's held errors. Context: RT. */
void urt_rhs(const urt_model_t *m, const urt_data_t *d, double s, const double *x, double *xdot);

/* Recompute d's derived outputs (torques, voltages, measurements, TCP pose) from its state
 * and command. urt_step does not: call this before reading them. Context: RT. */
void urt_data_update_outputs(const urt_model_t *m, urt_data_t *d);

/* Sample the sensors: draw noise, quantise and hold the measurement errors for the next
 * step (called by urt_step at the start of each step). Context: RT. */
void urt_sensors_sample(const urt_model_t *m, urt_data_t *d);

//---- arm (rigid-body kinematics and dynamics of the Hayati-DH chain) ----

/* TCP pose in the base frame: x y z [m], then the axis-angle rotation vector [rad] (UR
 * convention, angle in [0, π]). Context: RT. */
void urt_arm_tcp_pose(const urt_model_t *m, const double q[URT_NJ], double pose[6]);

/* Homogeneous transform of frame i (i = 0..6, 7 = TCP) in the base frame, row-major 4×4.
 * Context: RT. */
void urt_arm_frame(const urt_model_t *m, const double q[URT_NJ], int i, double T[16]);

/* Geometric Jacobian of the TCP in the base frame, rows (v; ω), row-major 6×6. Context: RT. */
void urt_arm_jacobian(const urt_model_t *m, const double q[URT_NJ], double J[36]);

/* Inverse dynamics by RNEA: tau = M(q) q̈ + C(q, q̇) q̇ + g(q). Context: RT. */
void urt_arm_rnea(const urt_model_t *m, const double q[URT_NJ], const double qd[URT_NJ],
                  const double qdd[URT_NJ], double tau[URT_NJ]);

/* Joint-space mass matrix M(q) by CRBA, row-major 6×6. Context: RT. */
void urt_arm_mass_matrix(const urt_model_t *m, const double q[URT_NJ], double M[36]);

/* Gravity torque g(q). Context: RT. */
void urt_arm_gravity(const urt_model_t *m, const double q[URT_NJ], double g[URT_NJ]);

/* Forward dynamics: q̈ = M⁻¹ (tau − C q̇ − g). Context: RT. */
void urt_arm_forward_dynamics(const urt_model_t *m, const double q[URT_NJ],
                              const double qd[URT_NJ], const double tau[URT_NJ],
                              double qdd[URT_NJ]);

/* The same three with an explicit payload on link 6 instead of the model's (what a running
 * robot carries: urt_data_t.live.payload, or the snapshot's payload fields). Context: RT. */
void urt_arm_rnea_payload(const urt_model_t *m, const urt_payload_t *p, const double q[URT_NJ],
                          const double qd[URT_NJ], const double qdd[URT_NJ], double tau[URT_NJ]);
void urt_arm_mass_matrix_payload(const urt_model_t *m, const urt_payload_t *p,
                                 const double q[URT_NJ], double M[36]);
void urt_arm_gravity_payload(const urt_model_t *m, const urt_payload_t *p, const double q[URT_NJ],
                             double g[URT_NJ]);

/* Kinetic plus potential energy of the rigid arm (potential zero at the base origin). */
double urt_arm_energy(const urt_model_t *m, const double q[URT_NJ], const double qd[URT_NJ]);

#ifdef __cplusplus
}
#endif
#endif
