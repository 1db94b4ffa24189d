// SPDX-License-Identifier: Apache-2.0
// core/fault_eval.cpp — what each fault class does to the physics and how its severity evolves
// (urt/faults.h; catalogue ../shared/docs/faults.md): the class table with units and ranges,
// the spec check the loader and the setter share, the per-step advance that turns severities
// into each faulted joint's effective parameters and sensor errors, and the ground truth.
// A scenario's lifecycle (set, add, clear, the controller command) is fault_scenario.cpp.
// Context: RT except where noted; nothing here allocates, locks or prints.
#include <cmath>
#include <cstring>

#include "urt/core.h"
#include "integrator.hpp"
#include "joint.hpp"
#include "urt/controller.h"
#include "urt/faults.h"

namespace {

struct ClassInfo {
  const char* name;
  const char* unit;        // the joint encoder's for encoder classes
  const char* unit_motor;  // the motor encoder's, or nullptr when the class has no component
  double lo, hi;           // the joint encoder's / the class's range
  double lo_motor, hi_motor;
};

constexpr double kArcmin = 3.14159265358979323846 / (180.0 * 60.0);  // [rad]

// Ranges: the catalogue's where it gives one [S], else its proposal [P] (faults.md §1).
constexpr ClassInfo kClasses[URT_FAULT_NCLASSES] = {
    // K_m falls to 25 % (WG–FS damage) or 4 % (worn tooth shape) of nominal [S,2]
    {"gear_stiffness", "1", nullptr, 0.0, 0.96, 0, 0},
    // ×(1 + s): −17 % on warm-up [S,9]; up to ×3 for starved grease [P]
    {"lubricant", "1", nullptr, -0.5, 2.0, 0, 0},
    // shorted fraction μ = 0–10 % [P]
    {"winding_short", "1", nullptr, 0.0, 0.1, 0, 0},
    // irreversible d = 5–30 % [P]; reversible −4 % at +40 °C [D]
    {"demagnetisation", "1", nullptr, 0.0, 0.3, 0, 0},
    // joint: within ±0.1 rad (thousands of counts); motor speed: within ±10 rad/s [P]
    {"encoder_bias", "rad", "rad/s", -0.1, 0.1, -10.0, 10.0},
    {"encoder_drift", "rad/s", "rad/s^2", -0.01, 0.01, -1.0, 1.0},
    {"encoder_noise", "rad", "rad/s", 0.0, 0.01, 0.0, 10.0},
    // stuck is on or off: severity 1 (its profile says when)
    {"encoder_stuck", "1", "1", 1.0, 1.0, 1.0, 1.0},
    // |b| ≤ 5 % of rated (here of the joint's i_max, checked per joint) [P]
    {"current_offset", "A", nullptr, -1.0, 1.0, 0, 0},
    // g = 0.9–1.1 [P]
    {"current_gain", "1", nullptr, -0.1, 0.1, 0, 0},
    // down to 12 V, past where k_e ω + R i reaches the bus in any UR5 motion [P]
    {"supply_sag", "V", nullptr, 0.0, 36.0, 0, 0},
    // a partly engaged brake: up to the UR5's smallest joint peak torque, 28 N m [P]
    {"brake_drag", "N m", nullptr, 0.0, 28.0, 0, 0},
    // foam / cable / carton impacts [S,19]: up to 500 N at the TCP [P]
    {"collision", "N", nullptr, 0.0, 500.0, 0, 0},
    // d ramps to fracture [S,3]: up to a 90 % local stiffness dip [P]
    {"crack", "1", nullptr, 0.0, 0.9, 0, 0},
    // a lost or unexpected load: up to the UR5's rated 5 kg [P]; the catalogue's can and axis
    // weights are 0.1–0.5 kg [S,19]
    {"payload", "kg", nullptr, 0.0, 5.0, 0, 0},
    // appears at the 4 % wear state [S,2]; swept over 0.5–10 arcmin [P]: up to 10 arcmin
    {"backlash", "rad", nullptr, 0.0, 10.0 * kArcmin, 0, 0},
    // spall size as amplitude [P]: a pulse up to 10 % of the joint's peak motor torque
    // k_t i_max (checked per joint)
    {"wg_bearing", "N m", nullptr, 0.0, 1.0, 0, 0},
    // catalogue accuracy 1–2 arcmin standard [S,4]; its growth up to 5 arcmin amplitude [P]
    {"transmission_error", "rad", nullptr, 0.0, 5.0 * kArcmin, 0, 0},
    // the fraction of counts lost, either encoder, up to one in two [P]
    {"encoder_missed", "1", "1", 0.0, 0.5, 0.0, 0.5},
};

constexpr const char* kProfiles[] = {"step", "linear", "exp", "intermittent", "random_walk"};

bool is_encoder(int c) {
  return c == URT_FAULT_ENCODER_BIAS || c == URT_FAULT_ENCODER_DRIFT ||
         c == URT_FAULT_ENCODER_NOISE || c == URT_FAULT_ENCODER_STUCK ||
         c == URT_FAULT_ENCODER_MISSED;
}

// Impacts per radian of the WG against the flexspline that holds the outer race (here fixed, so
// the race speed f_r is f_WG; faults.md's f_WG (1 + 1/N) is for a turning flexspline): the
// classic defect frequencies over f_r for n balls and ρ = d cos φ / D, a radial bearing (φ = 0)
// for the ball's spin [D,12]
//   BPFO = n/2 (1 − ρ),   BPFI = n/2 (1 + ρ),   BSF = (1 − ρ²)/(2ρ)
double bearing_rate(const urt_fault_spec_t& f) {
  const double n = f.balls, r = f.ball_ratio;
  switch (f.location) {
    case URT_FAULT_BEARING_INNER:
      return 0.5 * n * (1.0 + r);
    case URT_FAULT_BEARING_BALL:
      return (1.0 - r * r) / (2.0 * r);
    default:
      return 0.5 * n * (1.0 - r);
  }
}

// The class's severity range for this spec's target.
void class_range(const urt_model_t* m, const urt_fault_spec_t* f, double* lo, double* hi) {
  const ClassInfo& ci = kClasses[f->cls];
  bool motor = is_encoder(f->cls) && f->component == URT_FAULT_ENC_MOTOR;
  *lo = motor ? ci.lo_motor : ci.lo;
  *hi = motor ? ci.hi_motor : ci.hi;
  if (f->cls == URT_FAULT_CURRENT_OFFSET) {
    *hi = 0.05 * m->control[f->joint].i_max;
    *lo = -*hi;
  }
  if (f->cls == URT_FAULT_WG_BEARING) {
    *lo = 0.0;
    *hi = 0.1 * m->motor[f->joint].kt * m->control[f->joint].i_max;
  }
}

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

// s(t) of a profile before the random walk's and the range's say (fault_state.h).
double profile_value(const urt_fault_spec_t& f, double t, int* active) {
  *active = 0;
  if (t < f.onset) {
    return 0.0;
  }
  const double u = t - f.onset;
  *active = 1;
  switch (f.profile) {
    case URT_FAULT_LINEAR:
      return f.ramp > 0.0 ? f.severity * std::fmin(1.0, u / f.ramp) : f.severity;
    case URT_FAULT_EXP: {
      if (!(f.ramp > 0.0)) {
        return f.severity;
      }
      const double uu = std::fmin(u, f.ramp);
      return f.severity * std::expm1(uu / f.tau) / std::expm1(f.ramp / f.tau);
    }
    case URT_FAULT_INTERMITTENT: {
      const double period = f.on + f.off;
      if (std::fmod(u, period) >= f.on) {
        *active = 0;
        return 0.0;
      }
      return f.severity;
    }
    default:  // STEP; RANDOM_WALK's start
      return f.severity;
  }
}

// A joint's parameters with no fault: the model's, and neutral sensor errors.
void joint_reset(const urt_model_t* m, int j, urt_fault_joint_t* e) {
  std::memset(e, 0, sizeof *e);
  e->motor = m->motor[j];
  e->control = m->control[j];
  e->gear = m->gear[j];
  e->friction = m->friction[j];
  e->i_gain = 1.0;
  e->z_max = m->tables ? m->tables->z_max[j] : 0.0;
}

}  // namespace

extern "C" const char* urt_fault_class_name(int c) {
  return c >= 0 && c < URT_FAULT_NCLASSES ? kClasses[c].name : nullptr;
}
extern "C" int urt_fault_class_count(void) { return URT_FAULT_NCLASSES; }
extern "C" const char* urt_fault_class_unit(int c, int component) {
  if (c < 0 || c >= URT_FAULT_NCLASSES) {
    return nullptr;
  }
  const ClassInfo& ci = kClasses[c];
  return ci.unit_motor && component == URT_FAULT_ENC_MOTOR ? ci.unit_motor : ci.unit;
}
extern "C" const char* urt_fault_profile_name(int p) {
  return p >= 0 && p < (int)(sizeof kProfiles / sizeof kProfiles[0]) ? kProfiles[p] : nullptr;
}

extern "C" void urt_fault_severity_range(const urt_model_t* m, const urt_fault_spec_t* f,
                                         double* lo, double* hi) {
  class_range(m, f, lo, hi);
}

extern "C" const char* urt_fault_spec_invalid(const urt_model_t* m, const urt_fault_spec_t* f) {
  if (f->cls < 0 || f->cls >= URT_FAULT_NCLASSES) {
    return "unknown fault class";
  }
  const bool at_tcp = f->cls == URT_FAULT_COLLISION || f->cls == URT_FAULT_PAYLOAD;
  if (!at_tcp && (f->joint < 0 || f->joint >= URT_NJ)) {
    return "joint must be 0..5";
  }
  if (is_encoder(f->cls) ? (f->component != URT_FAULT_ENC_JOINT &&
                            f->component != URT_FAULT_ENC_MOTOR)
                         : f->component != 0) {
    return "component must be motor or joint for an encoder fault, and absent otherwise";
  }
  double lo, hi;
  class_range(m, f, &lo, &hi);
  if (!std::isfinite(f->severity) || f->severity < lo || f->severity > hi) {
    return "severity out of the class's range";
  }
  if (!finite_nonneg(f->onset) || !finite_nonneg(f->ramp) || !finite_nonneg(f->on) ||
      !finite_nonneg(f->off) || !finite_nonneg(f->sigma) || !std::isfinite(f->tau)) {
    return "profile times must be finite and >= 0";
  }
  switch (f->profile) {
    case URT_FAULT_STEP:
    case URT_FAULT_LINEAR:
    case URT_FAULT_RANDOM_WALK:
      break;
    case URT_FAULT_EXP:
      if (!(f->tau > 0.0)) {
        return "exp profile needs tau > 0";
      }
      break;
    case URT_FAULT_INTERMITTENT:
      if (!(f->on > 0.0 && f->on + f->off > 0.0)) {
        return "intermittent profile needs on > 0";
      }
      break;
    default:
      return "unknown profile";
  }
  if (f->cls == URT_FAULT_PAYLOAD) {
    for (int i = 0; i < 3; i++) {
      if (!(std::fabs(f->offset[i]) <= URT_PAYLOAD_COG_MAX)) {
        return "payload offset must be within 1 m of the flange on each axis";
      }
    }
  }
  if (f->cls == URT_FAULT_WG_BEARING) {
    if (f->location < URT_FAULT_BEARING_OUTER || f->location > URT_FAULT_BEARING_BALL) {
      return "bearing location must be outer, inner or ball";
    }
    if (f->balls < 6 || f->balls > 60) {
      return "bearing balls must be 6..60";
    }
    if (!(f->ball_ratio >= 0.05 && f->ball_ratio <= 0.5)) {
      return "bearing ball_ratio (d cos(phi) / D) must be in [0.05, 0.5]";
    }
  } else if (f->location != 0 || f->balls != 0 || f->ball_ratio != 0.0) {
    return "only a wg_bearing fault has a location, balls and ball_ratio";
  }
  if (f->cls == URT_FAULT_COLLISION) {
    const double* u = f->direction;
    double n = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(std::fabs(n - 1.0) < 1e-9)) {
      return "collision direction must be a unit vector";
    }
  }
  return nullptr;
}

extern "C" void urt_faults_advance(const urt_model_t* m, urt_data_t* d) {
  urt_fault_state_t& fs = d->faults;
  const int n = fs.s.n;
  const double t = d->t, h = m->dt;

  // each joint's Coulomb level before this update: where it falls, the bristles follow (below)
  double fc_before[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    fc_before[j] = urt::core::friction_now(m, d, j).f_c;
  }

  // the joints any fault targets get the model's parameters back, then every fault's effect
  uint32_t mask = 0;
  for (int k = 0; k < n; k++) {
    if (fs.s.f[k].cls != URT_FAULT_COLLISION && fs.s.f[k].cls != URT_FAULT_PAYLOAD) {
      mask |= 1u << fs.s.f[k].joint;
    }
  }
  for (int j = 0; j < URT_NJ; j++) {
    if ((mask >> j) & 1u) {
      joint_reset(m, j, &fs.joint[j]);
    }
  }
  for (int i = 0; i < 6; i++) {
    fs.wrench[i] = 0.0;
  }
  fs.payload_mass = 0.0;
  for (int i = 0; i < 3; i++) {
    fs.payload_moment[i] = 0.0;
  }
  double fr_scale[URT_NJ], drag[URT_NJ];
  for (int j = 0; j < URT_NJ; j++) {
    fr_scale[j] = 1.0;
    drag[j] = 0.0;
  }

  for (int k = 0; k < n; k++) {
    const urt_fault_spec_t& f = fs.s.f[k];
    int active = 0;
    double s = profile_value(f, t, &active);
    if (f.profile == URT_FAULT_RANDOM_WALK && active) {
      // the walk holds its value from the last step and moves by one increment per step
      double lo, hi;
      class_range(m, &f, &lo, &hi);
      s = std::fmin(hi, std::fmax(lo, fs.acc[k]));
      fs.acc[k] = s + f.sigma * std::sqrt(h) * urt_rng_normal(&fs.rng[k]);
    }
    fs.active[k] = active;
    fs.severity[k] = s;
    if (active && fs.onset_time[k] < 0.0) {
      fs.onset_time[k] = t;
    }
    const int j = f.joint;
    urt_fault_joint_t* e =
        f.cls == URT_FAULT_COLLISION || f.cls == URT_FAULT_PAYLOAD ? nullptr : &fs.joint[j];
    const bool motor = f.component == URT_FAULT_ENC_MOTOR;

    switch (f.cls) {
      case URT_FAULT_GEAR_STIFFNESS:
        // the mesh spring loses stiffness; its damping c = 2ζ√(K m) follows √K
        e->gear.k_m *= 1.0 - s;
        e->gear.c_m *= std::sqrt(1.0 - s);
        break;
      case URT_FAULT_LUBRICANT:
        fr_scale[j] *= 1.0 + s;
        break;
      case URT_FAULT_WINDING_SHORT: {
        const double k = 1.0 - s / 3.0;
        e->motor.r *= k;
        e->motor.l *= k;
        e->motor.kt *= k;
        e->motor.ke *= k;
        break;
      }
      case URT_FAULT_DEMAGNETISATION:
        e->motor.kt *= 1.0 - s;
        e->motor.ke *= 1.0 - s;
        break;
      case URT_FAULT_ENCODER_BIAS:
        (motor ? e->qdm_bias : e->q_bias) += s;
        break;
      case URT_FAULT_ENCODER_DRIFT:
        // the bias is the drift rate integrated; it stays when the drift stops
        (motor ? e->qdm_bias : e->q_bias) += fs.acc[k];
        fs.acc[k] += s * h;
        break;
      case URT_FAULT_ENCODER_NOISE:
        if (active && s > 0.0) {
          (motor ? e->qdm_noise : e->q_noise) += s * urt_rng_normal(&fs.rng[k]);
        }
        break;
      case URT_FAULT_ENCODER_STUCK:
        if (!active) {
          fs.stuck_latched[k] = 0;
          break;
        }
        if (!fs.stuck_latched[k]) {
          // the value the sensor showed when it stuck (its filter and held error now)
          const double* x = d->x[j];
          (motor ? e->qdm_hold : e->q_hold) =
              motor ? x[URT_X_W] + d->eps_w[j] : x[URT_X_P] + d->eps_q[j];
          fs.stuck_latched[k] = 1;
          // the hold is kept across steps in acc: joint_reset clears e every step
          fs.acc[k] = motor ? e->qdm_hold : e->q_hold;
        }
        (motor ? e->qdm_stuck : e->q_stuck) = 1;
        (motor ? e->qdm_hold : e->q_hold) = fs.acc[k];
        break;
      case URT_FAULT_CURRENT_OFFSET:
        e->i_bias += s;
        break;
      case URT_FAULT_CURRENT_GAIN:
        e->i_gain *= 1.0 + s;
        break;
      case URT_FAULT_SUPPLY_SAG:
        e->control.v_net -= s;
        break;
      case URT_FAULT_BRAKE_DRAG:
        drag[j] += s;
        break;
      case URT_FAULT_CRACK:
        // the modulation follows the WG angle inside the step (core/joint.cpp)
        e->crack = std::fmin(0.9, e->crack + s);
        break;
      case URT_FAULT_PAYLOAD:
        // summed here, added to the run's payload where the physics reads it (step_internal.h)
        fs.payload_mass += s;
        for (int i = 0; i < 3; i++) {
          fs.payload_moment[i] += s * f.offset[i];
        }
        break;
      case URT_FAULT_BACKLASH:
        e->backlash += s;
        break;
      case URT_FAULT_TRANSMISSION_ERROR:
        e->te_amp += s;
        break;
      case URT_FAULT_WG_BEARING:
        // one spall per joint is modelled: a second one's rate replaces the first's
        e->wg_pulse += s;
        e->wg_pulse_rate = bearing_rate(f);
        break;
      case URT_FAULT_ENCODER_MISSED: {
        // the counts the (filtered) reading passed since the last step, each lost with
        // probability s; lost joint counts stay in the reading (acc), lost motor counts dip this
        // step's speed, one count over the step each
        const double* x = d->x[j];
        const urt_sensors_params_t& sp = m->sensors[j];
        const double lsb = motor ? sp.lsb_w * h : sp.lsb_q;
        const double now = std::floor((motor ? x[URT_X_QM] : x[URT_X_P]) / lsb + 0.5);
        if (!fs.stuck_latched[k]) {
          fs.last_count[k] = now;  // the first step counts from here (the latch marks it)
          fs.stuck_latched[k] = 1;
        }
        const double passed = now - fs.last_count[k];
        fs.last_count[k] = now;
        double lost = 0.0;
        if (active && s > 0.0 && passed != 0.0) {
          const double n_c = std::fabs(passed);
          if (n_c <= 32.0) {
            // one draw per count: 53 random bits against s
            for (int c = 0; c < (int)n_c; c++) {
              lost += (double)(urt_rng_next(&fs.rng[k]) >> 11) * 0x1.0p-53 < s ? 1.0 : 0.0;
            }
          } else {
            // many counts in one step (a fast motor): the binomial's normal approximation
            const double mu = n_c * s, sd = std::sqrt(n_c * s * (1.0 - s));
            const double draw = std::nearbyint(mu + sd * urt_rng_normal(&fs.rng[k]));
            lost = std::fmin(n_c, std::fmax(0.0, draw));
          }
          lost = std::copysign(lost, passed);
        }
        if (motor) {
          e->qdm_missed += lost * sp.lsb_w;
        } else {
          fs.missed[k] += lost * lsb;
          e->q_bias -= fs.missed[k];
        }
        break;
      }
      case URT_FAULT_COLLISION:
        for (int i = 0; i < 3; i++) {
          fs.wrench[i] += s * f.direction[i];
        }
        break;
      default:
        break;
    }
  }

  // friction last: the lubricant scales the LuGre levels, a brake adds a Coulomb torque that
  // the Stribeck excess does not multiply (f_c' = f_c + T_b, K_s' f_c' = K_s f_c, so
  // g' = g + T_b at every speed for a symmetric joint)
  for (int j = 0; j < URT_NJ; j++) {
    if (!((mask >> j) & 1u)) {
      continue;
    }
    urt_friction_params_t& fp = fs.joint[j].friction;
    if (fr_scale[j] != 1.0) {
      fp.f_c *= fr_scale[j];
      fp.f_v *= fr_scale[j];
    }
    if (drag[j] > 0.0 && fp.enabled) {
      const double f_c = fp.f_c + drag[j];
      fp.k_static *= fp.f_c / f_c;
      fp.asym *= fp.f_c / f_c;
      fp.f_c = f_c;
    }
    // the bound on z of changed levels (joint_reset gave the others the model's, the same
    // expression evaluated once by integrator_prepare: two exp and two pow a joint saved)
    if (fp.enabled && (fr_scale[j] != 1.0 || drag[j] > 0.0)) {
      const double qd_max = m->joint[j].qd_max;
      fs.joint[j].z_max =
          std::fmax(urt_friction_g(&fp, qd_max), urt_friction_g(&fp, -qd_max)) / fp.sigma0;
    }
  }
  fs.joint_mask = mask;
  for (int j = 0; j < URT_NJ; j++) {
    const urt_friction_params_t& fp = urt::core::friction_now(m, d, j);
    if (fp.f_c < fc_before[j]) {
      urt::core::bristles_to_level(fp, d->x[j]);
    }
  }
}

extern "C" void urt_faults_truth(const urt_model_t* m, const urt_data_t* d,
                                 urt_fault_truth_t* out) {
  (void)m;
  std::memset(out, 0, sizeof *out);
  const urt_fault_state_t& fs = d->faults;
  out->n = fs.s.n;
  for (int k = 0; k < fs.s.n; k++) {
    out->cls[k] = fs.s.f[k].cls;
    out->joint[k] = fs.s.f[k].joint;
    out->component[k] = fs.s.f[k].component;
    out->active[k] = fs.active[k];
    out->severity[k] = fs.severity[k];
    out->onset[k] = fs.onset_time[k];
  }
}
