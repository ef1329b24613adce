#pragma once
/// @file motor_protocol.hpp
/// @brief Vendor-neutral motor-driver protocol interface: one command frame out, one reply frame in,
/// per motor and per 2 ms HAL tick.
///
/// A protocol is stateless and immutable after construction; every cyclic method is `noexcept`,
/// allocation-free and returns a status. A new vendor adds one class implementing MotorProtocol
/// and one line in makeMotorProtocol(); the bus plan names the protocol per bus, so neither the HAL
/// loop nor the transports change.
///
/// All values are joint-side SI quantities in the motor's own sign convention (MotorSpec::direction
/// and MotorSpec::offset map joint to motor and are applied by the caller, see toMotorSide()).

#include <cstdint>
#include <memory>
#include <string>

#include "pmg/hal/bus/can_frame.hpp"

namespace pmg::hal::bus {

/// Value ranges the driver firmware maps onto its fixed-point fields (vendor and model specific,
/// e.g. CubeMars AK80-9: q +-12.5 rad, qd +-50 rad/s, tau +-18 N m; read them from the datasheet).
/// A value outside a range is clamped to it before quantisation.
struct MotorRanges {
  double q_min = -12.5;    ///< Position range low end [rad].
  double q_max = 12.5;     ///< Position range high end [rad].
  double qd_min = -45.0;   ///< Velocity range low end [rad/s].
  double qd_max = 45.0;    ///< Velocity range high end [rad/s].
  double kp_min = 0.0;     ///< Stiffness range low end [N m/rad].
  double kp_max = 500.0;   ///< Stiffness range high end [N m/rad].
  double kd_min = 0.0;     ///< Damping range low end [N m s/rad].
  double kd_max = 5.0;     ///< Damping range high end [N m s/rad].
  double tau_min = -18.0;  ///< Torque (feed-forward and reply) range low end [N m].
  double tau_max = 18.0;   ///< Torque range high end [N m].

  /// Empty string when every range is finite with min < max (kp_min, kd_min >= 0); otherwise a
  /// message naming the first bad field and the expected range.
  std::string validate() const;
};

/// Plausibility window for replies: a decoded reply outside it is rejected as corrupted
/// (ReplyStatus::kOutOfRange). Defaults accept the whole codec range; the bus plan narrows it to
/// the joint's mechanical range plus margin.
struct ReplyLimits {
  double q_min = -1e9;         ///< Lowest plausible position [rad].
  double q_max = 1e9;          ///< Highest plausible position [rad].
  double qd_abs_max = 1e9;     ///< Largest plausible |velocity| [rad/s].
  double tau_abs_max = 1e9;    ///< Largest plausible |torque| [N m].
};

/// Static description of one motor on a bus (part of the immutable bus plan).
struct MotorSpec {
  std::string name;                ///< Joint name, e.g. "left_knee_joint".
  int joint_index = -1;            ///< Index in the robot's joint order (G1: 0..28).
  std::uint8_t motor_id = 1;       ///< Driver id (1..254; 0 and 255 are reserved).
  std::uint32_t command_can_id = 1;  ///< Arbitration id of frames to this motor (11 bit).
  std::uint32_t reply_can_id = 0;    ///< Arbitration id the driver replies on (11 bit).
  double direction = 1.0;          ///< +1 or -1: motor sign relative to the joint axis.
  double offset = 0.0;             ///< Motor position at joint zero [rad].
  MotorRanges ranges;              ///< Codec ranges (datasheet).
  ReplyLimits reply_limits;        ///< Plausibility window on replies.
};

/// Set-point of the driver's internal PD law tau = kp (q - q_meas) + kd (qd - qd_meas) + tau_ff,
/// in motor-side SI units.
struct MotorCommand {
  double q = 0.0;       ///< Position set-point [rad].
  double qd = 0.0;      ///< Velocity set-point [rad/s].
  double kp = 0.0;      ///< Stiffness [N m/rad].
  double kd = 0.0;      ///< Damping [N m s/rad].
  double tau_ff = 0.0;  ///< Feed-forward torque [N m].
};

/// Decoded driver reply, motor-side SI units.
struct MotorFeedback {
  std::uint8_t motor_id = 0;  ///< Id field of the reply.
  double q = 0.0;             ///< Measured position [rad].
  double qd = 0.0;            ///< Measured velocity [rad/s].
  double tau = 0.0;           ///< Measured torque (from phase current) [N m].
};

/// Non-PD control messages every protocol supports.
enum class ControlRequest : std::uint8_t {
  kEnable,   ///< Enter closed-loop (motor) mode.
  kDisable,  ///< Leave closed-loop mode: zero torque.
  kZero,     ///< Set the current position as encoder zero (only with the joint in a known pose).
};

/// Outcome of decoding one received frame.
enum class ReplyStatus : std::uint8_t {
  kOk = 0,
  kNotData,      ///< Error frame or frame of the wrong kind (FD flag mismatch, extended id).
  kWrongCanId,   ///< Arbitration id is not the motor's reply id.
  kWrongLength,  ///< Payload length differs from the protocol's reply length.
  kWrongId,      ///< Motor id field names another motor.
  kOutOfRange,   ///< Decoded value outside MotorSpec::reply_limits.
};

/// Human-readable name of a ReplyStatus (static string).
const char* toString(ReplyStatus s) noexcept;

/// One motor-driver protocol (e.g. "MIT mode"). Implementations are immutable and thread-safe.
class MotorProtocol {
 public:
  virtual ~MotorProtocol() = default;
  /// Protocol name as used in the bus plan ("mit").
  virtual const char* name() const noexcept = 0;
  /// Command payload length [bytes].
  virtual std::size_t commandLength() const noexcept = 0;
  /// Reply payload length [bytes].
  virtual std::size_t replyLength() const noexcept = 0;
  /// Encode a PD set-point for `motor` into `out` (classic CAN frame). Values are clamped to
  /// MotorSpec::ranges. Returns false (and leaves `out` untouched) if a value is NaN or infinite.
  virtual bool encodeCommand(const MotorSpec& motor, const MotorCommand& cmd,
                             CanFrame& out) const noexcept = 0;
  /// Encode enable / disable / set-zero for `motor` into `out`.
  virtual void encodeControl(const MotorSpec& motor, ControlRequest req,
                             CanFrame& out) const noexcept = 0;
  /// Decode a reply that should come from `motor`. On kOk `out` holds the values; otherwise `out`
  /// is untouched. Checks frame kind, arbitration id, length, motor id and reply_limits.
  virtual ReplyStatus decodeReply(const MotorSpec& motor, const CanFrame& frame,
                                  MotorFeedback& out) const noexcept = 0;
  /// Motor id a frame claims to come from (for routing a reply to its motor), or -1 if the frame
  /// cannot be a reply of this protocol at all. Routing only: decodeReply() does the full checks.
  virtual int replyMotorId(const CanFrame& frame) const noexcept = 0;
};

/// Factory: "mit" -> MitProtocol. Throws std::invalid_argument naming the unknown protocol and the
/// known ones. Setup only.
std::unique_ptr<MotorProtocol> makeMotorProtocol(const std::string& name);

/// Joint-side command -> motor-side command (applies direction and offset). noexcept, no allocation.
MotorCommand toMotorSide(const MotorSpec& motor, const MotorCommand& joint_cmd) noexcept;
/// Motor-side feedback -> joint-side feedback (inverse of toMotorSide). noexcept, no allocation.
MotorFeedback toJointSide(const MotorSpec& motor, const MotorFeedback& motor_fb) noexcept;

}  // namespace pmg::hal::bus
