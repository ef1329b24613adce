#include "pmg/hal/bus/motor_protocol.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pmg/hal/bus/mit_protocol.hpp"

namespace pmg::hal::bus {

namespace {
std::string checkRange(const char* field, double lo, double hi, bool nonneg) {
  std::ostringstream os;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
    os << field << "_min/" << field << "_max must be finite with min < max (got [" << lo << ", " << hi
       << "])";
    return os.str();
  }
  if (nonneg && lo < 0.0) {
    os << field << "_min must be >= 0 (got " << lo << ")";
    return os.str();
  }
  return {};
}
}  // namespace

std::string MotorRanges::validate() const {
  for (const auto& msg : {checkRange("q", q_min, q_max, false), checkRange("qd", qd_min, qd_max, false),
                          checkRange("kp", kp_min, kp_max, true), checkRange("kd", kd_min, kd_max, true),
                          checkRange("tau", tau_min, tau_max, false)}) {
    if (!msg.empty()) return msg;
  }
  return {};
}

const char* toString(ReplyStatus s) noexcept {
  switch (s) {
    case ReplyStatus::kOk: return "ok";
    case ReplyStatus::kNotData: return "not a data frame of this protocol";
    case ReplyStatus::kWrongCanId: return "wrong arbitration id";
    case ReplyStatus::kWrongLength: return "wrong payload length";
    case ReplyStatus::kWrongId: return "wrong motor id";
    case ReplyStatus::kOutOfRange: return "value outside plausibility window";
  }
  return "unknown";
}

std::unique_ptr<MotorProtocol> makeMotorProtocol(const std::string& name) {
  if (name == "mit") return std::make_unique<MitProtocol>();
  throw std::invalid_argument("unknown motor protocol '" + name + "' (known: mit)");
}

MotorCommand toMotorSide(const MotorSpec& m, const MotorCommand& c) noexcept {
  MotorCommand o;
  o.q = m.direction * c.q + m.offset;
  o.qd = m.direction * c.qd;
  o.kp = c.kp;
  o.kd = c.kd;
  o.tau_ff = m.direction * c.tau_ff;
  return o;
}

MotorFeedback toJointSide(const MotorSpec& m, const MotorFeedback& f) noexcept {
  // direction is +-1, so it is its own inverse.
  MotorFeedback o;
  o.motor_id = f.motor_id;
  o.q = m.direction * (f.q - m.offset);
  o.qd = m.direction * f.qd;
  o.tau = m.direction * f.tau;
  return o;
}

}  // namespace pmg::hal::bus
