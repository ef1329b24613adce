#pragma once
/// @file sil_emulator.hpp
/// @brief Motor-driver and IMU emulation for the SIL: the far end of the CAN buses. It speaks the
/// same protocol as the real drivers (MotorProtocol of each bus, MIT mode for the G1 plans) over
/// UDP CAN transports, feeds the decoded set-points to a simulation backend whose motor model runs
/// the driver-side PD (pmg::MujocoBackend), replies with the measured state, and sends the IMU frame.
/// It also injects bus faults (dropped, late, duplicated, corrupted replies; a silent motor;
/// bus-off; a frozen, noisy or silent IMU).
///
/// Port layout (both sides derive it from one base port, see udpPorts()):
///   bus b: host (HAL) side base + 2b, SIL side base + 2b + 1; IMU: base + 2B (host), base + 2B + 1 (SIL),
///   with B the number of buses.
///
/// One cycle (runCycle):
///   1. wait for this cycle's frames from the host until every motor on a live bus was addressed or
///      the timeout passes; a command updates the motor's held set-point, enable/disable its state
///      (a disabled motor produces zero torque, as the drivers do);
///   2. reply to every addressed motor with the state measured before this cycle's step (the
///      driver replies at once with its latest measurement), with the configured faults applied;
///   3. send the IMU frame (last, which tells a lockstep host that the cycle's replies are out);
///   4. step the simulation by one HAL period with the held set-points.

#include <poll.h>

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <random>
#include <vector>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/bus/bus_plan.hpp"
#include "pmg/hal/bus/udp_transport.hpp"

namespace pmg::hal::bus {

/// Faults the SIL injects (probabilities are per reply frame, 0..1).
struct SilFaults {
  double drop_prob = 0.0;     ///< Reply not sent (lost on the bus).
  double late_prob = 0.0;     ///< Reply held back and sent in the next cycle.
  double dup_prob = 0.0;      ///< Reply sent twice.
  double corrupt_prob = 0.0;  ///< Reply corrupted: foreign motor id, short length, or position at
                              ///< full scale (outside the joint's window) - what the host checks.
  int silent_joint = -1;      ///< This joint's driver stops replying (joint index), -1 = none.
  int bus_off_bus = -1;       ///< Bus that goes bus-off (once; until the host restarts it), -1 = none.
  bool imu_frozen = false;    ///< IMU repeats its last sample.
  bool imu_silent = false;    ///< IMU sends nothing.
  double imu_gyro_noise = 0.0;  ///< Extra white noise on the gyro [rad/s] (std).
  std::uint32_t seed = 1;     ///< Random seed of the injections.
};

/// Counters of what the emulator did.
struct SilCounters {
  std::uint64_t cycles = 0, commands = 0, controls = 0, replies = 0, dropped = 0, late = 0,
                duplicated = 0, corrupted = 0, silenced = 0, bus_off_injected = 0, restarts_seen = 0,
                imu_frames = 0;
  /// Data frames no emulated driver takes: extended or unknown id, not a command or control frame.
  std::uint64_t rejected = 0;
};

/// UDP ports of bus `b` (host side, SIL side) for a plan with `num_buses` buses; b = num_buses is the IMU.
inline std::pair<std::uint16_t, std::uint16_t> udpPorts(std::uint16_t base, std::size_t num_buses, std::size_t b) {
  (void)num_buses;
  return {static_cast<std::uint16_t>(base + 2 * b), static_cast<std::uint16_t>(base + 2 * b + 1)};
}

/// UDP transports for `plan` (one per bus) and the IMU channel, bound to the port layout, for the
/// host (controller) side or the SIL (driver emulator) side.
enum class UdpSide { kHost, kSil };
std::vector<std::unique_ptr<UdpCanTransport>> makeUdpTransports(const BusPlan& plan, std::uint16_t base_port,
                                                                UdpSide side, std::unique_ptr<UdpCanTransport>& imu_out);
/// Host-side transports (makeUdpTransports with UdpSide::kHost).
std::vector<std::unique_ptr<CanTransport>> makeHostUdpTransports(const BusPlan& plan, std::uint16_t base_port,
                                                                 std::unique_ptr<CanTransport>& imu_out);

class SilDriverEmulator {
 public:
  /// `sim` steps the physics (its cyclePeriod() must equal the plan's period). Binds the SIL-side
  /// ports; throws std::system_error naming the port if one is taken.
  SilDriverEmulator(const BusPlan& plan, std::unique_ptr<pmg::HalBackend> sim, std::uint16_t base_port);

  /// One lockstep cycle (steps 1-4 above). Returns false if no frame arrived before `timeout_s`
  /// and `step_anyway` is false (no step); with `step_anyway` the physics advances regardless.
  bool runCycle(double timeout_s, bool step_anyway = false);
  /// One real-time cycle: until the absolute CLOCK_MONOTONIC time `step_at` [s], answer every
  /// command at once with the latest measured state (as a driver does, so the host's reply window
  /// is met whatever the phase between the two clocks), then send the IMU frame and step the
  /// physics. Call it with step_at advancing by the period.
  void runRealtimeCycle(double step_at);
  /// Replace the active faults (thread-safe; taken at the start of the next cycle).
  void setFaults(const SilFaults& faults);
  /// Run `action` on the simulation at the start of the next cycle, on the SIL thread (thread-safe),
  /// e.g. a push on the pelvis through pmg::MujocoBackend::push.
  void post(std::function<void(pmg::HalBackend&)> action);
  /// Baseline gyro white noise of the emulated IMU [rad/s] (std; a real IMU is never bit-constant).
  void setImuSensorNoise(double std_rad_s) noexcept { sensor_noise_ = std_rad_s; }
  const SilCounters& counters() const noexcept { return counters_; }
  pmg::HalBackend& sim() noexcept { return *sim_; }
  /// State measured after the latest step (what the next replies will carry).
  const pmg::LowState& state() const noexcept { return state_; }
  const pmg::LowCommand& heldCommand() const noexcept { return cmd_; }

 private:
  void reply(std::size_t bus, std::size_t k, const SilFaults& f);
  void beginCycle();
  bool pollFrames(bool reply_now);
  void flushLate();
  void sendImuAndStep();
  BusPlan plan_;
  std::unique_ptr<pmg::HalBackend> sim_;
  std::vector<std::unique_ptr<UdpCanTransport>> buses_;
  std::unique_ptr<UdpCanTransport> imu_;
  std::vector<std::vector<std::int16_t>> route_;  ///< [bus][command can id] -> motor index
  std::vector<std::uint8_t> addressed_, enabled_;  ///< per joint
  std::vector<std::uint8_t> bus_off_;              ///< per bus
  std::vector<std::uint8_t> bus_off_done_;
  std::vector<std::pair<std::size_t, CanFrame>> late_;
  std::vector<::pollfd> fds_;
  pmg::LowCommand cmd_{};
  pmg::LowState state_{};
  pmg::ImuState frozen_imu_{};
  bool frozen_captured_ = false;
  std::uint32_t imu_seq_ = 0;
  std::mutex faults_mutex_;
  SilFaults pending_faults_;
  std::atomic<bool> faults_changed_{false};
  std::vector<std::function<void(pmg::HalBackend&)>> actions_;
  double sensor_noise_ = 1e-3;
  SilFaults faults_;
  std::mt19937 rng_{1};
  SilCounters counters_;
};

}  // namespace pmg::hal::bus
