#include "pmg/hal/bus/mit_protocol.hpp"

#include <cmath>

namespace pmg::hal::bus {

std::uint32_t MitProtocol::toUint(double x, double lo, double hi, int bits) noexcept {
  const double full = static_cast<double>((1u << bits) - 1u);
  if (std::isnan(x)) return 0;
  if (x <= lo) return 0;
  if (x >= hi) return static_cast<std::uint32_t>(full);
  const double r = std::round((x - lo) / (hi - lo) * full);
  return static_cast<std::uint32_t>(r < 0.0 ? 0.0 : (r > full ? full : r));
}

double MitProtocol::fromUint(std::uint32_t raw, double lo, double hi, int bits) noexcept {
  const double full = static_cast<double>((1u << bits) - 1u);
  return lo + static_cast<double>(raw) * (hi - lo) / full;
}

bool MitProtocol::encodeCommand(const MotorSpec& m, const MotorCommand& c,
                                CanFrame& out) const noexcept {
  if (!std::isfinite(c.q) || !std::isfinite(c.qd) || !std::isfinite(c.kp) || !std::isfinite(c.kd) ||
      !std::isfinite(c.tau_ff)) {
    return false;
  }
  const MotorRanges& r = m.ranges;
  const std::uint32_t q = toUint(c.q, r.q_min, r.q_max, 16);
  const std::uint32_t v = toUint(c.qd, r.qd_min, r.qd_max, 12);
  const std::uint32_t kp = toUint(c.kp, r.kp_min, r.kp_max, 12);
  const std::uint32_t kd = toUint(c.kd, r.kd_min, r.kd_max, 12);
  const std::uint32_t t = toUint(c.tau_ff, r.tau_min, r.tau_max, 12);
  out = CanFrame{};
  out.id = m.command_can_id;
  out.len = 8;
  out.data[0] = static_cast<std::uint8_t>(q >> 8);
  out.data[1] = static_cast<std::uint8_t>(q & 0xFF);
  out.data[2] = static_cast<std::uint8_t>(v >> 4);
  out.data[3] = static_cast<std::uint8_t>(((v & 0xF) << 4) | (kp >> 8));
  out.data[4] = static_cast<std::uint8_t>(kp & 0xFF);
  out.data[5] = static_cast<std::uint8_t>(kd >> 4);
  out.data[6] = static_cast<std::uint8_t>(((kd & 0xF) << 4) | (t >> 8));
  out.data[7] = static_cast<std::uint8_t>(t & 0xFF);
  return true;
}

void MitProtocol::encodeControl(const MotorSpec& m, ControlRequest req, CanFrame& out) const noexcept {
  out = CanFrame{};
  out.id = m.command_can_id;
  out.len = 8;
  for (int i = 0; i < 7; ++i) out.data[static_cast<std::size_t>(i)] = 0xFF;
  switch (req) {
    case ControlRequest::kEnable: out.data[7] = 0xFC; break;
    case ControlRequest::kDisable: out.data[7] = 0xFD; break;
    case ControlRequest::kZero: out.data[7] = 0xFE; break;
  }
}

int MitProtocol::replyMotorId(const CanFrame& f) const noexcept {
  // Route on the id byte alone; decodeReply() then checks the rest and counts a bad frame against
  // the motor it claims to come from.
  if (f.error || f.fd || f.extended || f.len < 1) return -1;
  return f.data[0];
}

ReplyStatus MitProtocol::decodeReply(const MotorSpec& m, const CanFrame& f,
                                     MotorFeedback& out) const noexcept {
  if (f.error || f.fd || f.extended) return ReplyStatus::kNotData;
  if (f.id != m.reply_can_id) return ReplyStatus::kWrongCanId;
  if (f.len != 6) return ReplyStatus::kWrongLength;
  if (f.data[0] != m.motor_id) return ReplyStatus::kWrongId;
  const MotorRanges& r = m.ranges;
  const std::uint32_t q = (static_cast<std::uint32_t>(f.data[1]) << 8) | f.data[2];
  const std::uint32_t v = (static_cast<std::uint32_t>(f.data[3]) << 4) | (f.data[4] >> 4);
  const std::uint32_t t = (static_cast<std::uint32_t>(f.data[4] & 0xF) << 8) | f.data[5];
  MotorFeedback fb;
  fb.motor_id = f.data[0];
  fb.q = fromUint(q, r.q_min, r.q_max, 16);
  fb.qd = fromUint(v, r.qd_min, r.qd_max, 12);
  fb.tau = fromUint(t, r.tau_min, r.tau_max, 12);
  const ReplyLimits& lim = m.reply_limits;
  if (fb.q < lim.q_min || fb.q > lim.q_max || std::fabs(fb.qd) > lim.qd_abs_max ||
      std::fabs(fb.tau) > lim.tau_abs_max) {
    return ReplyStatus::kOutOfRange;
  }
  out = fb;
  return ReplyStatus::kOk;
}

bool MitProtocol::decodeControl(const CanFrame& f, ControlRequest& out) noexcept {
  if (f.error || f.fd || f.len != 8) return false;
  for (int i = 0; i < 7; ++i) {
    if (f.data[static_cast<std::size_t>(i)] != 0xFF) return false;
  }
  switch (f.data[7]) {
    case 0xFC: out = ControlRequest::kEnable; return true;
    case 0xFD: out = ControlRequest::kDisable; return true;
    case 0xFE: out = ControlRequest::kZero; return true;
    default: return false;
  }
}

bool MitProtocol::decodeCommand(const MotorSpec& m, const CanFrame& f, MotorCommand& out) noexcept {
  ControlRequest ignored{};
  if (f.error || f.fd || f.len != 8 || decodeControl(f, ignored)) return false;
  const MotorRanges& r = m.ranges;
  const std::uint32_t q = (static_cast<std::uint32_t>(f.data[0]) << 8) | f.data[1];
  const std::uint32_t v = (static_cast<std::uint32_t>(f.data[2]) << 4) | (f.data[3] >> 4);
  const std::uint32_t kp = (static_cast<std::uint32_t>(f.data[3] & 0xF) << 8) | f.data[4];
  const std::uint32_t kd = (static_cast<std::uint32_t>(f.data[5]) << 4) | (f.data[6] >> 4);
  const std::uint32_t t = (static_cast<std::uint32_t>(f.data[6] & 0xF) << 8) | f.data[7];
  out.q = fromUint(q, r.q_min, r.q_max, 16);
  out.qd = fromUint(v, r.qd_min, r.qd_max, 12);
  out.kp = fromUint(kp, r.kp_min, r.kp_max, 12);
  out.kd = fromUint(kd, r.kd_min, r.kd_max, 12);
  out.tau_ff = fromUint(t, r.tau_min, r.tau_max, 12);
  return true;
}

void MitProtocol::encodeReply(const MotorSpec& m, const MotorFeedback& fb, CanFrame& out) noexcept {
  const MotorRanges& r = m.ranges;
  const std::uint32_t q = toUint(fb.q, r.q_min, r.q_max, 16);
  const std::uint32_t v = toUint(fb.qd, r.qd_min, r.qd_max, 12);
  const std::uint32_t t = toUint(fb.tau, r.tau_min, r.tau_max, 12);
  out = CanFrame{};
  out.id = m.reply_can_id;
  out.len = 6;
  out.data[0] = m.motor_id;
  out.data[1] = static_cast<std::uint8_t>(q >> 8);
  out.data[2] = static_cast<std::uint8_t>(q & 0xFF);
  out.data[3] = static_cast<std::uint8_t>(v >> 4);
  out.data[4] = static_cast<std::uint8_t>(((v & 0xF) << 4) | (t >> 8));
  out.data[5] = static_cast<std::uint8_t>(t & 0xFF);
}

}  // namespace pmg::hal::bus
