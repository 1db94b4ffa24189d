// SPDX-License-Identifier: Apache-2.0
// core/motion_types.cpp — which motion type a command starts, and which one runs. Context: RT.
#include "motion.hpp"

namespace urt::core {

const Motion* motion_for_command(const urt_ctrl_cmd_t& cmd) noexcept {
  switch (cmd.kind) {
    // with a blend radius a planned motion runs as a path (motion_path.cpp); without one as
    // before
    case URT_CTRL_MOVEJ:
      return cmd.r > 0.0 ? &kPathJointMotion : &kMovejMotion;
    case URT_CTRL_OPTIMOVEJ:
      return cmd.r > 0.0 ? &kPathJointMotion : &kOptimovejMotion;
    case URT_CTRL_MOVEL:
      return cmd.r > 0.0 ? &kPathToolMotion : &kMovelMotion;
    case URT_CTRL_MOVEP:
    case URT_CTRL_OPTIMOVEL:
      return &kPathToolMotion;
    case URT_CTRL_MOVEC:
      return &kPathArcMotion;
    case URT_CTRL_SERVOJ:
      return &kServojMotion;
    case URT_CTRL_SPEEDJ:
      return &kSpeedjMotion;
    case URT_CTRL_SPEEDL:
      return &kSpeedlMotion;
    case URT_CTRL_STOPJ:
    case URT_CTRL_STOPL:
      return &kStopMotion;
    case URT_CTRL_DIRECT:
    case URT_CTRL_SETPOINT:
      return &kDirectMotion;
    case URT_CTRL_SERVOL:
      return &kServolMotion;
    case URT_CTRL_SERVOC:
      return &kServocMotion;
    case URT_CTRL_TORQUE:
      return &kTorqueMotion;
    case URT_CTRL_FREEDRIVE:  // index 1 starts teach mode; index 0 ends it (not a motion)
      return cmd.index == 1 ? &kFreedriveMotion : nullptr;
    default:
      return nullptr;
  }
}

const Motion& motion_of(urt_ctrl_motion_t id) noexcept {
  switch (id) {
    case URT_MOTION_MOVEJ:
      return kMovejMotion;
    case URT_MOTION_MOVEL:
      return kMovelMotion;
    case URT_MOTION_SERVOJ:
      return kServojMotion;
    case URT_MOTION_SPEEDJ:
      return kSpeedjMotion;
    case URT_MOTION_SPEEDL:
      return kSpeedlMotion;
    case URT_MOTION_STOP:
      return kStopMotion;
    case URT_MOTION_DIRECT:
      return kDirectMotion;
    case URT_MOTION_SERVOL:
      return kServolMotion;
    case URT_MOTION_SERVOC:
      return kServocMotion;
    case URT_MOTION_TORQUE:
      return kTorqueMotion;
    case URT_MOTION_FREEDRIVE:
      return kFreedriveMotion;
    case URT_MOTION_FORCE:
      return kForceMotion;
    case URT_MOTION_PATH:
      return kPathToolMotion;  // the hooks of a path are the same for every kind
    case URT_MOTION_IDLE:
    default:
      return kIdleMotion;
  }
}

}  // namespace urt::core
