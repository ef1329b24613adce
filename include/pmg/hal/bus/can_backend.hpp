#pragma once
/// @file can_backend.hpp
/// @brief The HAL backend that drives real motor buses: pmg::HalBackend over a BusPlan, one
/// CanTransport per bus (SocketCAN on the robot, UDP towards pmg_sil) and an optional IMU channel.
///
/// exchange(), once per 2 ms HAL cycle (noexcept, allocation-free):
///  1. drain frames left over from the previous cycle (counted as late replies, not used);
///  2. per motor: joint command -> motor side (direction, offset) -> protocol frame -> send (until
///     the driver has answered once, ControlRequest::kEnable is sent instead, every cycle: a lost
///     enable request is repeated, never left as a limp motor). A non-finite command is never encoded:
///     the motor gets a zero-torque command instead (counted in nonfinite_commands). By default
///     all frames are queued at the slot start, bus by bus in plan order: the controller's TX
///     queue and CAN arbitration serialise them, and the plan's schedule bounds when each goes out.
///     With Options::paced each frame is sent at its slot offset from the plan's schedule
///     (BusPlan::schedule()), collecting replies meanwhile, for drivers that cannot take
///     back-to-back frames or interfaces with a short TX queue;
///  3. poll all channels until every motor has replied and (lockstep) the IMU frame arrived, or
///     until the reply window closes; decode and check each reply (id, length, range); route it by
///     motor id; duplicates and rejected frames are counted, not used;
///  4. a bus that reports bus-off is restarted after Options::bus_off_restart_cycles cycles;
///  5. status: kOk if every motor replied, kPartial if some did, kFault if none did.
/// LowState::time is cycles * period (deterministic in lockstep); MotorState::valid tells which
/// motors replied this cycle.

#include <poll.h>

#include <array>
#include <memory>
#include <vector>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/bus/bus_plan.hpp"
#include "pmg/hal/bus/transport.hpp"

namespace pmg::hal::bus {

struct CanBackendOptions {
  /// Reply window after the sends [s]; 0 = automatic: busiest bus's request-reply time + 0.2 ms,
  /// at most 0.9 period.
  double reply_window_s = 0.0;
  /// Lockstep with pmg_sil: wait for every motor reply and the IMU frame (the SIL sends it last),
  /// up to lockstep_timeout_s, instead of the real-time reply window.
  bool lockstep = false;
  /// [s]; generous because a loaded machine can take tens of ms for one SIL physics step, and a
  /// reply that misses the wait counts as missing.
  double lockstep_timeout_s = 0.25;
  /// Lockstep: once every motor replied, wait at most this long for the IMU frame [s] (the SIL
  /// sends it right after the replies; the slack covers a descheduled SIL on a loaded machine).
  double lockstep_imu_grace_s = 0.1;
  int bus_off_restart_cycles = 50;   ///< Cycles in bus-off before restart() (100 ms at 500 Hz).
  /// Send each motor's frame at its offset in the slot (BusPlan::schedule()) instead of queueing
  /// all at the slot start. Occupies the HAL thread for the busiest bus's round (<= 80 % of 2 ms).
  bool paced = false;
  std::string validate() const;
};

/// Per-motor reply counters (joint order).
struct MotorLinkCounters {
  std::uint64_t replies = 0;       ///< Valid replies used.
  std::uint64_t missing = 0;       ///< Cycles without a valid reply.
  std::uint64_t rejected = 0;      ///< Replies failing id/length/range checks.
  std::uint64_t duplicates = 0;    ///< Extra replies in the same cycle.
  std::uint64_t late = 0;          ///< Replies drained at the start of the next cycle.
};

class CanBackend final : public pmg::HalBackend {
 public:
  /// `transports[b]` serves plan.buses()[b]; `imu` may be null (then LowState::imu.valid is false).
  /// Throws std::invalid_argument if counts differ or the plan has more than pmg::kMaxMotors joints.
  CanBackend(BusPlan plan, std::vector<std::unique_ptr<CanTransport>> transports,
             std::unique_ptr<CanTransport> imu, CanBackendOptions options = {});
  ~CanBackend() override;

  const char* name() const noexcept override { return "can"; }
  /// Motors that never replied or missed replies, rejected / unroutable frames and the IMU, per bus.
  std::string report() const override;
  double cyclePeriod() const noexcept override { return plan_.options().period_s; }
  pmg::BackendStatus exchange(const pmg::LowCommand& command, pmg::LowState& state) noexcept override;

  const BusPlan& plan() const noexcept { return plan_; }
  CanTransport& transport(std::size_t bus) noexcept { return *transports_[bus]; }
  /// Counters of joint j (robot joint order).
  const MotorLinkCounters& motorCounters(int joint) const noexcept { return motor_counters_[static_cast<std::size_t>(joint)]; }
  std::uint64_t nonfiniteCommands() const noexcept { return nonfinite_commands_; }
  std::uint64_t imuFrames() const noexcept { return imu_frames_; }
  /// Data frames that no motor of their bus claims (foreign id, wrong kind).
  std::uint64_t unroutableFrames() const noexcept { return unroutable_; }
  std::uint64_t imuRejected() const noexcept { return imu_rejected_; }
  std::uint64_t cycles() const noexcept { return cycles_; }

 private:
  void handleFrame(std::size_t bus, const CanFrame& f, pmg::LowState& state, bool late) noexcept;
  bool allReplied() const noexcept;

  BusPlan plan_;
  CanBackendOptions opt_;
  std::vector<std::unique_ptr<CanTransport>> transports_;
  std::unique_ptr<CanTransport> imu_;
  std::vector<std::unique_ptr<MotorProtocol>> protocols_;
  std::vector<std::array<std::int16_t, 256>> route_;  ///< [bus][motor id] -> motor index or -1
  std::vector<MotorLinkCounters> motor_counters_;     ///< (num joints)
  std::vector<std::uint8_t> got_;                     ///< replied this cycle (num joints)
  std::vector<std::uint8_t> enabled_;                 ///< driver answered an enable request (num joints)
  std::vector<int> bus_off_cycles_;
  std::vector<::pollfd> pollfds_;
  struct SendEvent {
    double offset_s;
    std::size_t bus;
    std::size_t motor;
  };
  std::vector<SendEvent> events_;     ///< One slot's sends, in sending order.
  std::vector<std::uint8_t> skip_bus_;  ///< Bus in bus-off this cycle.
  int num_joints_ = 0;
  double window_s_ = 0.0;
  bool imu_got_ = false;
  std::uint64_t cycles_ = 0, nonfinite_commands_ = 0, imu_frames_ = 0, imu_rejected_ = 0, unroutable_ = 0;
};

/// How the CAN backend reaches the buses.
struct CanBackendSetup {
  std::string plan_file;            ///< Bus plan YAML (e.g. config/hal/g1_can.yaml).
  /// The robot config the plan must agree with (joint indices, bus names, motor ids; see
  /// checkPlanAgainstRobot()). Not owned; nullptr skips the check (bus-level tests only).
  const pmg::RobotConfig* robot = nullptr;
  std::string transport = "udp";    ///< "socketcan" (robot: interface = bus name) or "udp" (pmg_sil).
  std::uint16_t udp_base_port = 47000;  ///< UDP port layout base (see sil_emulator.hpp).
  bool lockstep = false;            ///< Lockstep with pmg_sil (see CanBackendOptions::lockstep).
  bool paced = false;               ///< Paced sends (see CanBackendOptions::paced).
};

/// Build a CanBackend from a setup (setup code: throws std::runtime_error / std::system_error
/// naming the file, interface or port; pmg::ConfigError when the plan disagrees with setup.robot).
/// With "socketcan" there is no IMU channel on CAN: the IMU must come from another reader.
std::unique_ptr<CanBackend> makeCanBackend(const CanBackendSetup& setup);

}  // namespace pmg::hal::bus
