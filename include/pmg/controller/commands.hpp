#pragma once
/// @file commands.hpp
/// Operator commands (velocity u_d, posture u_s, mode requests) as they reach the 100 Hz loop,
/// their validation (NaN, range, staleness) and shaping (slew-rate limits), and the scripted
/// command sequences used by the demo, the tests and `pmg_command_script`.

#include <cstdint>
#include <string>
#include <vector>

#include "pmg/generator/generator.hpp"

namespace pmg {

/// Controller modes (see docs/controller.md). Values match pmg_lcm::mode_command_t.mode.
enum class ControllerMode : std::int8_t {
  kPassive = 0,    ///< zero torque
  kSoftStand = 1,  ///< interpolate from the measured pose to the standing pose
  kActive = 2,     ///< PMG (and the policy, when one is loaded) drives the joints
  kDamping = 3,    ///< latched e-stop: kp = 0, kd only
};

/// The newest operator input, as written by the LCM receiver or a script (trivially copyable).
struct CommandSample {
  VelocityCommand velocity{};
  PostureCommand posture{};
  double velocity_time = -1.0;  ///< receive time of the velocity command [s, controller clock]; < 0: none yet
  double posture_time = -1.0;
  std::int8_t mode_request = -1;  ///< requested ControllerMode, 4 = clear the damping latch, -1 = none
  std::uint32_t mode_request_seq = 0;  ///< increments with every mode request
};

/// Command validation and shaping limits.
struct CommandLimits {
  double timeout = 0.5;                            ///< a velocity command older than this is stale [s]
  std::array<double, 3> max_velocity{1.0, 0.5, 1.0};     ///< |v_x|, |v_y| [m/s], |ω| [rad/s]
  std::array<double, 3> max_acceleration{1.0, 1.0, 2.0}; ///< slew limits [m/s², m/s², rad/s²]
  std::array<double, 3> posture_min{-0.3, -0.3, 0.0};    ///< pitch, roll [rad], height [m] (0: standing)
  std::array<double, 3> posture_max{0.6, 0.3, 1.0};
  double posture_rate = 0.5;                       ///< posture slew limit [rad/s or m/s]
  std::string validate() const;
};

/// Counters of rejected/shaped input (telemetry).
struct CommandCounters {
  std::uint64_t rejected_nan = 0;     ///< commands with NaN/Inf (ignored: the previous valid one is kept)
  std::uint64_t clamped = 0;          ///< commands beyond max_velocity / posture range (clamped)
  std::uint64_t stale_ticks = 0;      ///< ticks on which the velocity command was stale (→ zero velocity)
};

/// Turns raw operator input into the command the generator gets. noexcept, allocation-free.
class CommandShaper {
 public:
  explicit CommandShaper(CommandLimits limits) : limits_(limits) {}
  /// @param sample newest input; @param now controller time [s]; @param dt tick [s].
  void update(const CommandSample& sample, double now, double dt) noexcept;
  /// Brings the shaped command back to zero velocity / neutral posture at once (mode changes).
  void reset() noexcept;
  const VelocityCommand& velocity() const noexcept { return velocity_; }
  const PostureCommand& posture() const noexcept { return posture_; }
  bool stale() const noexcept { return stale_; }
  const CommandCounters& counters() const noexcept { return counters_; }

 private:
  CommandLimits limits_;
  VelocityCommand target_{}, velocity_{};
  PostureCommand posture_target_{}, posture_{};
  double last_velocity_time_ = -2.0, last_posture_time_ = -2.0;
  bool stale_ = true;
  CommandCounters counters_;
};

/// One segment of a scripted command sequence.
struct CommandSegment {
  double duration = 1.0;  ///< [s]
  VelocityCommand velocity{};
  PostureCommand posture{};
  std::string label;
};

/// A scripted command sequence (config/commands/*.yaml): segments played back to back.
struct CommandScript {
  std::string source_file;
  std::vector<CommandSegment> segments;
  double duration() const;
  /// Command at time @p t since the start [s]; the last segment holds after the end.
  const CommandSegment& at(double t) const;
};

/// Loads a command script. @throws ConfigError naming file, segment and field.
CommandScript loadCommandScript(const std::string& path);

}  // namespace pmg
