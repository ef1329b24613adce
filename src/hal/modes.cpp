#include "pmg/hal/modes.hpp"

namespace pmg {

bool modeRequestFromWire(std::int32_t code, ModeRequest& out) noexcept {
  if (code < 0 || code > 4) return false;
  out = static_cast<ModeRequest>(code);
  return true;
}

const char* toString(Mode m) noexcept {
  switch (m) {
    case Mode::kPassive: return "passive";
    case Mode::kSoftStand: return "soft_stand";
    case Mode::kActive: return "active";
    case Mode::kDamping: return "damping";
  }
  return "unknown";
}

const char* toString(ModeRequest r) noexcept {
  switch (r) {
    case ModeRequest::kNone: return "none";
    case ModeRequest::kPassive: return "passive";
    case ModeRequest::kSoftStand: return "soft_stand";
    case ModeRequest::kActive: return "active";
    case ModeRequest::kDamping: return "damping";
    case ModeRequest::kReset: return "reset";
  }
  return "unknown";
}

const char* toString(FaultCode c) noexcept {
  switch (c) {
    case FaultCode::kNone: return "none";
    case FaultCode::kEstop: return "e-stop requested";
    case FaultCode::kCommandStale: return "command stream stale";
    case FaultCode::kCommandInvalid: return "command not finite";
    case FaultCode::kPolicyStale: return "policy output stale";
    case FaultCode::kPolicyInvalid: return "policy output invalid";
    case FaultCode::kMotorStale: return "motor reply timeout";
    case FaultCode::kMotorInvalid: return "motor measurement not finite";
    case FaultCode::kImuStale: return "IMU timeout";
    case FaultCode::kImuInvalid: return "IMU sample invalid";
    case FaultCode::kImuFrozen: return "IMU frozen";
    case FaultCode::kJointPosition: return "joint position limit";
    case FaultCode::kJointVelocity: return "joint velocity limit";
    case FaultCode::kJointTorque: return "joint torque limit";
    case FaultCode::kFallTilt: return "fall: base tilt";
    case FaultCode::kFallHeight: return "fall: base height";
    case FaultCode::kBackend: return "backend fault";
    case FaultCode::kCount: break;
  }
  return "unknown";
}

}  // namespace pmg
