#pragma once
/// @file mit_protocol.hpp
/// @brief The "MIT mode" CAN protocol of the MIT Mini Cheetah motor driver, also spoken by
/// CubeMars AK-series, MyActuator, Steadywin, Robstride (MIT mode) and many other drivers.
///
/// Wire format (big-endian bit packing, unsigned fixed point over MotorSpec::ranges):
///  - Command, 8 bytes, sent on MotorSpec::command_can_id:
///    `[q:16][qd:12][kp:12][kd:12][tau_ff:12]` ->
///    b0 = q[15:8], b1 = q[7:0], b2 = qd[11:4], b3 = qd[3:0]<<4 | kp[11:8], b4 = kp[7:0],
///    b5 = kd[11:4], b6 = kd[3:0]<<4 | tau[11:8], b7 = tau[7:0].
///  - Reply, 6 bytes, received on MotorSpec::reply_can_id:
///    b0 = motor id, b1..b2 = q[16], b3 = qd[11:4], b4 = qd[3:0]<<4 | tau[11:8], b5 = tau[7:0].
///  - Control: `FF FF FF FF FF FF FF xx` with xx = FC enable, FD disable, FE set zero.
/// Quantisation: raw = round((x - min) / (max - min) * (2^bits - 1)); decoding is the inverse, so
/// the round-trip error is at most half a step, (max - min) / (2 (2^bits - 1)).
/// Source: B. Katz, "A low cost modular actuator for dynamic robots", MIT MS thesis 2018, and the
/// published Mini Cheetah motor firmware CAN format.

#include "pmg/hal/bus/motor_protocol.hpp"

namespace pmg::hal::bus {

/// MIT-mode codec. Immutable, thread-safe, all methods noexcept and allocation-free.
class MitProtocol final : public MotorProtocol {
 public:
  const char* name() const noexcept override { return "mit"; }
  std::size_t commandLength() const noexcept override { return 8; }
  std::size_t replyLength() const noexcept override { return 6; }
  bool encodeCommand(const MotorSpec& motor, const MotorCommand& cmd,
                     CanFrame& out) const noexcept override;
  void encodeControl(const MotorSpec& motor, ControlRequest req,
                     CanFrame& out) const noexcept override;
  ReplyStatus decodeReply(const MotorSpec& motor, const CanFrame& frame,
                          MotorFeedback& out) const noexcept override;
  int replyMotorId(const CanFrame& frame) const noexcept override;

  /// Driver side (used by the SIL motor emulator): decode a command frame. Returns false if the
  /// frame is not an 8-byte classic data frame. Control frames decode as false; see decodeControl.
  static bool decodeCommand(const MotorSpec& motor, const CanFrame& frame,
                            MotorCommand& out) noexcept;
  /// Driver side: true if `frame` is a control frame; writes the request.
  static bool decodeControl(const CanFrame& frame, ControlRequest& out) noexcept;
  /// Driver side: encode a reply frame (values clamped to ranges; NaN encodes as the range low end).
  static void encodeReply(const MotorSpec& motor, const MotorFeedback& fb, CanFrame& out) noexcept;

  /// Quantise x in [lo, hi] onto `bits` bits (clamped; NaN -> 0). Exposed for tests.
  static std::uint32_t toUint(double x, double lo, double hi, int bits) noexcept;
  /// Inverse of toUint.
  static double fromUint(std::uint32_t raw, double lo, double hi, int bits) noexcept;
};

}  // namespace pmg::hal::bus
