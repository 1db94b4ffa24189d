// SPDX-License-Identifier: Apache-2.0
// core/model_units.cpp — the unit of every config key (config/README.md's Keys tables), in the
// words urt_model_print writes after each value ("N m", "kg m^2", "-" for a pure number). The
// printed model's layout differs from the file's (each joint carries its own gear, friction and
// sensor blocks), so the table is keyed by the file's paths; tests/python/test_model_units.py
// checks that every key of config/ur5.yaml is here and that each unit equals the printed one.
// A key added to the loader needs its line here, or an overlay cannot state its unit.
#include "model_units.hpp"

#include <cstring>

namespace urt::core {

namespace {

struct KeyUnit {
  const char *key, *unit;
};

// gear_sizes.A and .B share their keys; so do thermal.A and .B
const KeyUnit kUnits[] = {
    {"name", "-"},
    {"simulation.dt", "s"},
    {"simulation.seed", "-"},
    {"simulation.drives_engaged", "-"},
    {"simulation.substep_h_max", "s"},
    {"simulation.substep_ratio", "-"},
    {"simulation.refine_every", "steps"},
    {"supply.v_net", "V"},
    {"arm.gravity", "m/s^2"},
    {"arm.tcp", "m, m, m, rad, rad, rad"},
    {"arm.links[].a", "m"},
    {"arm.links[].alpha", "rad"},
    {"arm.links[].beta", "rad"},
    {"arm.links[].d", "m"},
    {"arm.links[].theta", "rad"},
    {"arm.links[].mass", "kg"},
    {"arm.links[].com", "m"},
    {"arm.links[].inertia", "kg m^2; Ixx Iyy Izz Ixy Ixz Iyz"},
    {"gear_sizes.*.z_fs", "-"},
    {"gear_sizes.*.z_cs", "-"},
    {"gear_sizes.*.r_g", "m"},
    {"gear_sizes.*.alpha_t", "rad"},
    {"gear_sizes.*.k_wg", "N m/rad"},
    {"gear_sizes.*.k_b", "N/m"},
    {"gear_sizes.*.k_fs", "N m/rad"},
    {"gear_sizes.*.k_m", "N/m"},
    {"gear_sizes.*.k_cs", "N m/rad"},
    {"gear_sizes.*.j_wg", "kg m^2"},
    {"gear_sizes.*.j_fs", "kg m^2"},
    {"gear_sizes.*.j_cs", "kg m^2"},
    {"gear_sizes.*.zeta", "-"},
    {"friction_common.enabled", "-"},
    {"friction_common.sigma0", "N m/rad"},
    {"friction_common.sigma1", "N m s/rad"},
    {"sensors.noise", "-"},
    {"sensors.quantise", "-"},
    {"sensors.current.f", "Hz"},
    {"sensors.current.sigma", "A"},
    {"sensors.current.adc_bits", "bit"},
    {"sensors.current.adc_range", "-"},
    {"sensors.motor_encoder.f", "Hz"},
    {"sensors.motor_encoder.zeta", "-"},
    {"sensors.motor_encoder.sigma", "rad/s"},
    {"sensors.motor_encoder.counts_per_rev", "-"},
    {"sensors.joint_encoder.f", "Hz"},
    {"sensors.joint_encoder.zeta", "-"},
    {"sensors.joint_encoder.sigma", "rad"},
    {"sensors.joint_encoder.counts_per_rev", "-"},
    {"thermal.t_amb", "degC"},
    {"thermal.*.r_th", "K/W"},
    {"thermal.*.c_th", "J/K"},
    {"joints[].name", "-"},
    {"joints[].size", "-"},
    {"joints[].q_min", "rad"},
    {"joints[].q_max", "rad"},
    {"joints[].qd_max", "rad/s"},
    {"joints[].qdd_max", "rad/s^2"},
    {"joints[].torque_max", "N m"},
    {"joints[].q0", "rad"},
    {"joints[].current_offset", "A"},
    {"joints[].control.p_pos", "rad_motor/s per rad_joint"},
    {"joints[].control.p_vel", "A s/rad"},
    {"joints[].control.i_vel", "A/rad"},
    {"joints[].control.p_cur", "V/A"},
    {"joints[].control.i_cur", "V/(A s)"},
    {"joints[].motor.j", "kg m^2"},
    {"joints[].motor.r", "Ohm"},
    {"joints[].motor.l", "H"},
    {"joints[].motor.kt", "N m/A"},
    {"joints[].friction.f_c", "N m"},
    {"joints[].friction.f_v", "N m (s/rad)^(2/3)"},
    {"joints[].friction.k_q", "-"},
    {"joints[].friction.k_static", "-"},
    {"joints[].friction.qd_s", "rad/s"},
    {"joints[].friction.asym", "-"},
    {"joints[].friction.relax", "1/s"},
    // the payload (issue 10 item 1); harmless while the file has no payload section
    {"payload.mass", "kg"},
    // as urt_model_print writes them (the payload's own frame and reference point)
    {"payload.cog", "m, flange frame"},
    {"payload.inertia", "kg m^2 about the CoG; Ixx Iyy Izz Ixy Ixz Iyz"},
};

// "gear_sizes.A.k_wg" matches "gear_sizes.*.k_wg" (* is one component: A or B)
bool matches(const char *pattern, const std::string &path) {
  const char *star = std::strchr(pattern, '*');
  if (!star) {
    return path == pattern;
  }
  size_t pre = (size_t)(star - pattern);
  const char *post = star + 1;
  size_t post_len = std::strlen(post);
  if (path.size() < pre + post_len + 1 || path.compare(0, pre, pattern, pre) != 0 ||
      path.compare(path.size() - post_len, post_len, post) != 0) {
    return false;
  }
  std::string mid = path.substr(pre, path.size() - pre - post_len);
  return mid == "A" || mid == "B";
}

}  // namespace

const char *config_unit(const std::string &generic_path) {
  for (const KeyUnit &k : kUnits) {
    if (matches(k.key, generic_path)) {
      return k.unit;
    }
  }
  return nullptr;
}

}  // namespace urt::core
