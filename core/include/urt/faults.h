/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/faults.h — faults in the physics, with ground truth (issue 11; catalogue
 * ../shared/docs/faults.md). A scenario (urt_fault_scenario_t, fixed size, memcpy-able) lists
 * up to URT_MAX_FAULTS faults, each a class, a target (joint, and for encoders the motor or
 * joint encoder), a severity in the class's physical unit and a profile from an onset time.
 * urt_data_set_faults installs it into urt_data_t; from then on every urt_step (and the CVODE
 * reference's step) evaluates each fault's severity at the step's start time and holds it over
 * the step, so a caller that only steps gets the scenario's evolution. The faults change the
 * model's parameters and the sensors where the physics reads them (core/joint.cpp), never the
 * outputs after the fact: a demagnetised motor draws more current, a biased joint encoder moves
 * the arm.
 *
 * The integrator's W tables stay the healthy model's: ROS2 is a W-method, second order with
 * any W, and the faults only soften (stiffness loss, sag) or change non-stiff terms; the fixed
 * step is checked against CVODE with three faults in tests/reference/test_reference.c. The one
 * exception is backlash: inside its dead zone the gear's output spring carries nothing, a change
 * of structure no W of the healthy block damps correctly (it would hold the gap shut), so the
 * model carries a second set of tables with k_CS = c_CS = 0 (built at load, independent of the
 * gap's width; core/joint.hpp kGearGap) and a step that starts in the gap uses them.
 */
#ifndef URT_FAULTS_H
#define URT_FAULTS_H

#include <stddef.h>

#include "urt/data.h"
#include "urt/fault_state.h"
#include "urt/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Class names as scenario files spell them ("gear_stiffness", ...), NULL outside
 * [0, urt_fault_class_count()). Context: any. */
const char *urt_fault_class_name(int c);
int urt_fault_class_count(void);
/* The unit of a class's severity for an encoder component (URT_FAULT_ENC_*; other classes
 * ignore it): "1", "A", "V", "N m", "N", "rad", "rad/s", "rad/s^2". Context: any. */
const char *urt_fault_class_unit(int c, int component);
/* Profile names ("step", "linear", "exp", "intermittent", "random_walk"), NULL outside. */
const char *urt_fault_profile_name(int p);

/* Read a scenario file (YAML):
 *
 *   faults:
 *     - class: demagnetisation      # urt_fault_class_name
 *       joint: 1                    # 0..5 (not for collision and payload)
 *       component: motor            # encoder classes only: motor or joint
 *       severity: 0.2
 *       unit: "1"                   # must be the class's unit
 *       direction: [0, 0, -1]       # collision only: the force's direction, base frame
 *       offset: [0, 0, 0.05]        # payload only: where the mass sits, flange frame [m]
 *       location: outer             # wg_bearing only: outer, inner or ball
 *       balls: 13                   # wg_bearing only: rolling elements, 6..60
 *       ball_ratio: 0.2             # wg_bearing only: d cos(phi) / D, 0.05..0.5
 *       profile: {kind: linear, onset: 0.5, ramp: 2.0}
 *
 * profile keys by kind: step {onset}, linear {onset, ramp}, exp {onset, ramp, tau},
 * intermittent {onset, on, off}, random_walk {onset, sigma, seed}; encoder_noise and
 * encoder_missed take a `seed:` of their own. Errors read "file:line: key: reason" (unknown key, unknown class,
 * bad unit, value out of the catalogue's range, ...) into err. Returns 0, or URT_ECONFIG /
 * URT_EIO; *out is written only on success. Context: non-RT. */
int urt_faults_load(const urt_model_t *m, const char *path, urt_fault_scenario_t *out, char *err,
                    size_t err_sz);
/* The same from text; name_for_errors stands for the file name in messages. */
int urt_faults_parse(const urt_model_t *m, const char *yaml_text, const char *name_for_errors,
                     urt_fault_scenario_t *out, char *err, size_t err_sz);

/* Why a spec is not valid for this model (class, target, range, profile), or NULL. The loader,
 * urt_data_set_faults and the live injection share it. Context: RT. */
const char *urt_fault_spec_invalid(const urt_model_t *m, const urt_fault_spec_t *f);

/* The severity range a spec's class has for its target (current_offset: ±5 % of the joint's
 * i_max; wg_bearing: up to 10 % of its k_t i_max), in the class's unit. The spec's cls, joint and component must be valid. */
void urt_fault_severity_range(const urt_model_t *m, const urt_fault_spec_t *f, double *lo,
                              double *hi);

/* Install a scenario (NULL or n = 0: no faults) into d, replacing any; the faults' clocks are
 * the simulation time, so onsets already past apply at once. Context: RT (a controller tick
 * boundary). Returns 0 or URT_EINVAL (d unchanged). */
int urt_data_set_faults(const urt_model_t *m, urt_data_t *d, const urt_fault_scenario_t *s);

/* Ground truth at the current step. */
typedef struct urt_fault_truth {
  int32_t n;                          /* = the scenario's n */
  int32_t cls[URT_MAX_FAULTS];
  int32_t joint[URT_MAX_FAULTS];
  int32_t component[URT_MAX_FAULTS];
  int32_t active[URT_MAX_FAULTS];     /* the profile is on at this step */
  double severity[URT_MAX_FAULTS];    /* s(t), the class's unit */
  double onset[URT_MAX_FAULTS];       /* when it first became active [s], −1: not yet */
} urt_fault_truth_t;
void urt_faults_truth(const urt_model_t *m, const urt_data_t *d, urt_fault_truth_t *out);

/* Add one fault to the installed scenario, keeping the others' state (their onsets, draws and
 * accumulated errors), or clear the faults that match (cls, joint, component; −1 matches any).
 * Live injection uses them (URT_CTRL_FAULT, applied by the controller at a tick). The new fault's
 * effect starts with the next urt_faults_advance, i.e. after the next physics step.
 * Context: RT (no allocation). add returns 0, URT_EINVAL (urt_fault_spec_invalid) or URT_ENOSPC
 * (URT_MAX_FAULTS installed), d unchanged on error; clear returns how many it removed. */
int urt_data_add_fault(const urt_model_t *m, urt_data_t *d, const urt_fault_spec_t *f);
int urt_data_clear_faults(const urt_model_t *m, urt_data_t *d, int cls, int joint, int component);

/* A fault injection or clearing as a controller command (URT_CTRL_FAULT in urt/controller.h),
 * so that it travels the command ring as a value: index 1 inject, 0 clear; q[0..3] class,
 * joint, component, profile (clear: class, joint, component, −1 for any); value severity;
 * t onset, r ramp, a tau, v on, a_rot off, gain sigma; tau[0] seed (below 2^53), pose[0..2]
 * direction, pose[3..5] offset, tau[1..3] location, balls, ball_ratio. Context: any. */
struct urt_ctrl_cmd;
void urt_fault_cmd_pack(const urt_fault_spec_t *f, int inject, struct urt_ctrl_cmd *out);
/* Returns 1 (inject: *f filled), 0 (clear: f->cls, joint, component filled, −1 = any) or
 * URT_EINVAL (not a fault command, or fields that are no integers where integers belong). */
int urt_fault_cmd_unpack(const struct urt_ctrl_cmd *c, urt_fault_spec_t *f);

/* Evaluate every fault at d->t and refresh the effective parameters (urt_step calls it after
 * each step; exposed for tests). Context: RT. */
void urt_faults_advance(const urt_model_t *m, urt_data_t *d);

#ifdef __cplusplus
}
#endif
#endif
