// SPDX-License-Identifier: Apache-2.0
// core/controller_commands.cpp — the controller's commands that are not motions (urt_ctrl_apply
// hands them here; motions start in controller.cpp): digital and analog outputs, the speed
// slider, the TCP, the payload, power and brakes, unlocking a protective stop, restarting
// safety, the program state, pause and resume, an external wrench, the inputs' levels, live
// fault injection, zeroing the F/T sensor, the tool voltage, gravity, ending freedrive, force
// mode and its end, the script's protective stop and HALT. A bad argument is refused
// (URT_CTRL_FAULT_BAD_ARGUMENT) and changes nothing. Moved unchanged out of controller.cpp (the
// choices are listed there). Context: RT: no allocation, no exceptions.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "controller_internal.hpp"
#include "motion.hpp"
#include "step_internal.h"
#include "urt/controller.h"
#include "urt/core.h"
#include "urt/faults.h"

namespace urt::core {

namespace {

constexpr double kWrenchMaxF = 1000.0;  // SET_WRENCH / FORCE_MODE force bound per axis [N]
constexpr double kWrenchMaxT = 200.0;   // and torque bound [N m]
constexpr double kGravityMax = 100.0;   // SET_GRAVITY bound per axis (the loader's) [m/s²]

}  // namespace

void apply_setting(const MotionEnv& e, const urt_ctrl_cmd_t* cmd) noexcept {
  const urt_model_t* m = e.m;
  urt_ctrl_t* c = e.c;
  urt_data_t* d = e.d;
  const int kind = cmd->kind;
  switch (kind) {
    case URT_CTRL_SET_DIGITAL_OUT:
      if (cmd->index < 0 || cmd->index > 17) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else if (cmd->value != 0.0) {
        c->digital_out |= 1u << cmd->index;
      } else {
        c->digital_out &= ~(1u << cmd->index);
      }
      break;
    case URT_CTRL_SET_ANALOG_OUT:
      if (cmd->index < 0 || cmd->index > 1 || !(cmd->value >= 0.0 && cmd->value <= 1.0)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->analog_out[cmd->index] = cmd->value;
      }
      break;
    case URT_CTRL_SET_SPEED_SLIDER:
      if (!(cmd->value >= 0.0 && cmd->value <= 1.0)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->speed_slider = cmd->value;
      }
      break;
    case URT_CTRL_SET_TCP:
      if (!all_finite(cmd->pose, 6)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(c->tcp_offset, cmd->pose, sizeof c->tcp_offset);
      }
      break;
    case URT_CTRL_SET_PAYLOAD: {
      // mounted from this tick boundary on: the physics' next step and this tick's feed-forward
      // (tau_model1; tau_model0 still carries the old payload, so the feed-forward moves over
      // one period, as a real controller's does within its cycle)
      urt_payload_t p = {};
      p.mass = cmd->value;
      std::memcpy(p.cog, cmd->pose, sizeof p.cog);
      std::memcpy(p.inertia, cmd->tau, sizeof p.inertia);
      if (urt_data_set_payload_target(m, d, &p, cmd->t) != URT_OK) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->payload_mass = p.mass;
        std::memcpy(c->payload_cog, p.cog, sizeof c->payload_cog);
      }
      break;
    }
    case URT_CTRL_POWER_ON:
      // a faulted joint keeps the arm off until the safety system is restarted
      if (c->safety_mode == URT_SAFETY_MODE_FAULT) {
        c->fault |= URT_CTRL_FAULT_NOT_RUNNING;
      } else if (c->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
        c->robot_mode = URT_ROBOT_MODE_IDLE;
      }
      break;
    case URT_CTRL_POWER_OFF:
      power_off(c, d);
      break;
    case URT_CTRL_BRAKE_RELEASE:
      if (c->safety_mode == URT_SAFETY_MODE_FAULT) {
        c->fault |= URT_CTRL_FAULT_NOT_RUNNING;
      } else if (c->robot_mode == URT_ROBOT_MODE_IDLE ||
                 c->robot_mode == URT_ROBOT_MODE_POWER_OFF) {
        c->robot_mode = URT_ROBOT_MODE_RUNNING;  // the set-point keeps holding where it was
      }
      break;
    case URT_CTRL_UNLOCK_PSTOP:
      if (c->safety_mode == URT_SAFETY_MODE_PROTECTIVE_STOP || d->pstop) {
        urt_pstop_reset(m, d);
        c->safety_mode = URT_SAFETY_MODE_NORMAL;
        c->enc_joint = -1;
        hold_at(c, measured_q(d));
        model_torque(m, c, d->live.payload, c->q1, c->qd1, c->qdd1, c->tau_model1);
        std::memcpy(c->tau_model0, c->tau_model1, sizeof c->tau_model0);
      }
      break;
    case URT_CTRL_RESTART_SAFETY:
      // the way out of a joint fault: NORMAL, still powered off (power on, brake release next)
      if (c->safety_mode == URT_SAFETY_MODE_FAULT) {
        power_off(c, d);
        c->safety_mode = URT_SAFETY_MODE_NORMAL;
        c->fault_joint = -1;
      }
      break;
    case URT_CTRL_PROGRAM_STATE:
      c->program_state = cmd->index;
      if (cmd->index == URT_PROGRAM_STOPPED && c->paused) {
        // the program ended while paused: the held motion is over
        c->paused = 0;
        if (c->motion != URT_MOTION_IDLE || c->has_pending) {
          stop_to_rest(e, StopCause::kHalt);
        }
      }
      break;
    case URT_CTRL_PAUSE:
      if (!c->paused) {
        c->paused = 1;
        motion_of(c->motion).stop(e, StopCause::kPause);
      }
      break;
    case URT_CTRL_RESUME:
      c->paused = 0;
      break;
    case URT_CTRL_SET_WRENCH: {
      bool ok = all_finite(cmd->pose, 6);
      for (int i = 0; i < 6 && ok; i++) {
        ok = std::fabs(cmd->pose[i]) <= (i < 3 ? kWrenchMaxF : kWrenchMaxT);
      }
      if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(d->wrench_ext, cmd->pose, sizeof d->wrench_ext);
      }
      break;
    }
    case URT_CTRL_SET_INPUTS: {
      // the levels the outside world puts on the inputs: a mask outside the 18 pins, bits
      // outside the mask, or an analog value a UR input cannot read (0–10 V) is refused whole
      const double amask = cmd->a, bits = cmd->value;
      bool ok = cmd->index >= 0 && cmd->index < (1 << 18) && amask >= 0.0 && amask < 16.0 &&
                amask == std::floor(amask) && bits >= 0.0 && bits < (1 << 18) &&
                bits == std::floor(bits) && (static_cast<uint32_t>(bits) & ~cmd->index) == 0;
      const uint32_t am = ok ? static_cast<uint32_t>(amask) : 0;
      for (int k = 0; k < 4 && ok; k++) {
        ok = !(am & (1u << k)) || (cmd->q[k] >= 0.0 && cmd->q[k] <= 10.0);
      }
      if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
        break;
      }
      const uint32_t mask = static_cast<uint32_t>(cmd->index);
      c->digital_in = (c->digital_in & ~mask) | static_cast<uint32_t>(bits);
      for (int k = 0; k < 4; k++) {
        if (am & (1u << k)) {
          (k < 2 ? c->analog_in[k] : c->tool_analog_in[k - 2]) = cmd->q[k];
        }
      }
      break;
    }
    case URT_CTRL_FAULT: {
      // live injection: a fault into the physics from this tick on (its onset no earlier than
      // now), or the faults matching a target cleared; refused whole when invalid or full
      urt_fault_spec_t f;
      const int what = urt_fault_cmd_unpack(cmd, &f);
      int rc = what < 0 ? what : URT_OK;
      if (what == 1) {
        f.onset = std::fmax(f.onset, d->t);
        rc = urt_data_add_fault(m, d, &f);
      } else if (what == 0) {
        urt_data_clear_faults(m, d, f.cls, f.joint, f.component);
      }
      if (rc != URT_OK) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
        c->faults_refused++;
      } else {
        c->faults_applied++;
      }
      break;
    }
    case URT_CTRL_ZERO_FTSENSOR:
      if (!all_finite(cmd->pose, 6)) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(c->ft_bias, cmd->pose, sizeof c->ft_bias);
      }
      break;
    case URT_CTRL_SET_TOOL_VOLTAGE:
      // set_tool_voltage: the three supplies a UR tool connector has
      if (cmd->value != 0.0 && cmd->value != 12.0 && cmd->value != 24.0) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->tool_voltage = static_cast<int32_t>(cmd->value);
      }
      break;
    case URT_CTRL_SET_GRAVITY: {
      bool ok = all_finite(cmd->pose, 3);
      for (int i = 0; i < 3 && ok; i++) {
        ok = std::fabs(cmd->pose[i]) <= kGravityMax;
      }
      if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        std::memcpy(c->gravity, cmd->pose, sizeof c->gravity);
      }
      break;
    }
    case URT_CTRL_FREEDRIVE:  // index 0 (index 1 is a motion): end, decelerate, hold
      if (c->motion == URT_MOTION_FREEDRIVE) {
        stop_to_rest(e, StopCause::kHalt);
      }
      break;
    case URT_CTRL_FORCE_MODE: {
      bool ok = all_finite(cmd->pose, 6) && all_finite(cmd->q, 6) && all_finite(cmd->tau, 6) &&
                all_finite(cmd->qd, 6) && cmd->index >= 1 && cmd->index <= 3;
      for (int i = 0; i < 6 && ok; i++) {
        ok = (cmd->q[i] == 0.0 || cmd->q[i] == 1.0) && cmd->qd[i] >= 0.0 &&
             std::fabs(cmd->tau[i]) <= (i < 3 ? kWrenchMaxF : kWrenchMaxT);
      }
      if (!running(c) || d->pstop) {
        c->fault |= URT_CTRL_FAULT_NOT_RUNNING;
      } else if (!ok) {
        c->fault |= URT_CTRL_FAULT_BAD_ARGUMENT;
      } else {
        c->force = *cmd;
        if (!c->force_mode || c->motion != URT_MOTION_FORCE) {
          force_begin(e);
        }
      }
      break;
    }
    case URT_CTRL_FORCE_MODE_END:
      if (c->force_mode || c->motion == URT_MOTION_FORCE) {
        bool was_force = c->motion == URT_MOTION_FORCE;
        c->force_mode = 0;
        if (was_force) {
          finish_motion(c);
          start_stop(c, tcp_twist_decel_time(m, c, kForceAcc, kForceAccRot));
        }
      }
      break;
    case URT_CTRL_PROTECTIVE_STOP:
      // as the physics' own stop, from where the set-point is; only a running arm can stop
      if (c->robot_mode == URT_ROBOT_MODE_RUNNING &&
          c->safety_mode != URT_SAFETY_MODE_PROTECTIVE_STOP) {
        protective_stop(c, d, URT_CTRL_FAULT_SCRIPT_PSTOP, 0);
      }
      break;
    case URT_CTRL_HALT:
      if (c->motion != URT_MOTION_IDLE || moving(c)) {
        motion_of(c->motion).stop(e, StopCause::kHalt);
      }
      break;
    default:
      break;
  }
}

}  // namespace urt::core
