#pragma once
/// @file commands.hpp
/// The one command vocabulary of pmg, from the wire (LCM decoding, command scripts) to the policy
/// observation:
///  - pmg::Command: u = u_d ⊕ u_s (PMG eqs. 4–12) with "no height command" explicit
///    (std::optional), never a ≤ 0 sentinel;
///  - pmg::CommandSample: the newest operator input as a command source writes it (timestamps,
///    mode request);
///  - pmg::CommandLimits: the one set of command limits, validated once at setup; the shaper
///    clamps against it and the stages downstream only check (the generator and GCO limits are
///    cross-checked against it when the controller is built);
///  - pmg::CommandShaper: validation (NaN, range, staleness) and slew limits, so that no command
///    step makes a joint reference jump (docs/controller.md, "Reference continuity");
///  - pmg::CommandScript: the one command-script format, read by pmg_controller,
///    pmg_command_script and pmg_policy_sil.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pmg/generator/generator.hpp"
#include "pmg/hal/modes.hpp"
#include "pmg/teleop/vr_sample.hpp"

namespace pmg {

/// Operator command u = u_d ⊕ u_s. Velocities in the heading frame H (yaw-aligned base frame):
/// vx forward [m/s], vy left [m/s], wz yaw rate counter-clockwise [rad/s]; posture: torso pitch
/// (forward bend) [rad], roll (lean right) [rad], pelvis height above the ground [m] or none.
struct Command {
  double vx = 0.0, vy = 0.0, wz = 0.0;
  double pitch = 0.0, roll = 0.0;
  std::optional<double> height;  ///< nullopt: no height command (the standing height)
};

/// The newest operator input, as a command source (LCM receiver, script, test) writes it.
/// Trivially copyable (crosses pmg::LatestValue).
struct CommandSample {
  Command command;
  double velocity_time = -1.0;  ///< receive time of the velocity part [s, controller clock]; < 0: none yet
  double posture_time = -1.0;   ///< receive time of the posture part [s]; < 0: none yet
  ModeRequest mode_request = ModeRequest::kNone;
  std::uint32_t mode_request_seq = 0;  ///< increments with every mode request
  teleop::VrSample vr;                 ///< newest VR teleoperation sample (PMG_VR_POSE)
  double vr_time = -1.0;               ///< its receive time [s, controller clock]; < 0: none yet
};

/// Command limits: the operator's envelope. Validated once (validate()); the shaper clamps to it.
struct CommandLimits {
  double timeout = 0.5;                                   ///< velocity command older than this is stale [s]
  std::array<double, 3> max_velocity{1.0, 0.5, 1.0};      ///< |v_x|, |v_y| [m/s], |ω| [rad/s]
  std::array<double, 3> max_acceleration{1.0, 1.0, 2.0};  ///< slew limits [m/s², m/s², rad/s²]
  std::array<double, 2> pitch_range{-0.3, 0.6};           ///< torso pitch [rad]
  std::array<double, 2> roll_range{-0.3, 0.3};            ///< torso roll [rad]
  std::array<double, 2> height_range{0.45, 0.85};         ///< pelvis height [m]
  double posture_rate = 0.5;                              ///< pitch/roll slew limit [rad/s]
  double height_rate = 0.2;                               ///< height slew limit [m/s]
  /// Pelvis height that "no height command" means [m] (set from the generator's squat clip at setup).
  double standing_height = 0.78;
  /// Crouched velocity envelope (0 = off): at and below this pelvis height [m] the velocity command
  /// is held inside crouched_max_velocity by an L1 rule, Σ_i |u_i| / m_i ≤ 1 (combinations count
  /// against each other), scaled along its direction so the robot still goes where it is told,
  /// only slower. Between the standing height and crouched_height both the limits m_i and the rule
  /// blend linearly with the crouch f = (standing − h) / (standing − crouched_height) ∈ [0, 1]:
  /// s = (1 − f) max_i |u_i| / M_i + f Σ_i |u_i| / m_i(f), u ← u / s when s > 1. h is the shaped
  /// (slewed) height, so the limit moves continuously and the velocity slew keeps the command
  /// continuous. Why: the default policy falls when stopping from 0.8 m/s forward or 0.5 m/s
  /// backward at 0.62 m, and in arcs there (docs/controller.md "Crouched velocity envelope").
  double crouched_height = 0.0;
  /// |v_x|, |v_y| [m/s], |ω| [rad/s] at crouched_height; each in (0, max_velocity].
  std::array<double, 3> crouched_max_velocity{0.4, 0.3, 0.6};
  /// The crouched envelope per axis instead of the L1 rule: s = (1 − f) max_i |u_i| / M_i +
  /// f max_i |u_i| / m_i(f), so a combination is slowed only where one of its axes is beyond its
  /// own limit (as the bent envelope); false (the default): the L1 rule above. For an actor trained
  /// on crouched combinations (H5c, trained with the crouched envelope off): with
  /// crouched_max_velocity = max_velocity nothing is slowed beyond the box, while crouchFraction()
  /// (the braking steps' weight, VelocityFeedbackConfig::brake_crouch_scaled) still follows the crouch.
  bool crouched_per_axis = false;
  /// Bent velocity envelope (0 = off): torso pitch [rad], in (0, pitch_range max], at and beyond
  /// which the velocity command is held inside bent_max_velocity, per axis, scaled along its
  /// direction (s = max_i |u_i| / m_i(f), u ← u / s when s > 1). The limits blend linearly with the
  /// bend f = clamp(pitch / bent_pitch, 0, 1): m_i(f) = M_i + f (b_i − M_i), where pitch is the
  /// shaped (slewed) pitch command, so the limit moves continuously and the velocity slew keeps the
  /// command continuous; upright and leaning back (pitch ≤ 0) nothing is limited. Applied together
  /// with the crouched envelope: the larger of the two scales wins. Why: bent 0.4 rad at 1.0 m/s the
  /// default policy could not stop (posture_walks.yaml, 24 seeds: 11 still walked faster than
  /// 0.3 m/s 1–3 s after the stop command, one ran away at 2 m/s and fell), while from 0.6 m/s
  /// bent, and from 1.0 m/s upright, every seed stopped (docs/controller.md "Bent velocity envelope").
  double bent_pitch = 0.0;
  /// |v_x|, |v_y| [m/s], |ω| [rad/s] at bent_pitch; each in (0, max_velocity].
  std::array<double, 3> bent_max_velocity{0.6, 0.4, 0.8};
  /// Walking height floor (0 = off) [m], in [height_range min, standing height]: while the robot is
  /// told to walk (velocity target or shaped velocity not zero) and for walking_min_height_hold_s
  /// after both are zero, the height goal is at least this; below it the robot stands, crouched as
  /// deep as commanded. The floor's changes pass through the height slew, so the shaped height stays
  /// continuous. Why: on 144 runs of a crouched sweep at 0.62 m (seeds 0–143) the default policy
  /// falls in 9 without the floor and in none with it at 0.66 m, 1.5 s (docs/controller.md
  /// "Walking height floor").
  double walking_min_height = 0.0;
  /// How long the floor holds after the robot was last told to walk [s], in [0, 10].
  double walking_min_height_hold_s = 1.5;
  /// Bound on the speed of every joint reference the loop sends [rad/s] (walking peaks near
  /// 3.6 rad/s on the G1 clips); enforced by pmg::ReferenceRateLimiter after the generator.
  double max_reference_speed = 6.0;
  /// Empty when valid, else "commands.<field>: expected ..." for the first bad field.
  std::string validate() const;
};

/// Counters of rejected and shaped input (telemetry and the run summary).
struct CommandCounters {
  std::uint64_t rejected_nan = 0;  ///< commands with NaN/Inf (ignored: the previous valid one is kept)
  std::uint64_t clamped = 0;       ///< commands outside the limits (clamped)
  std::uint64_t stale_ticks = 0;   ///< ticks on which the velocity command was stale (→ zero velocity)
  std::uint64_t crouch_limited_ticks = 0;  ///< ticks on which the crouched velocity envelope slowed the command
  std::uint64_t height_floor_ticks = 0;    ///< ticks on which the walking height floor raised the height goal
  std::uint64_t bent_limited_ticks = 0;    ///< ticks on which the bent velocity envelope slowed the command
  std::uint64_t upsets = 0;               ///< times the velocity command was held at zero after an upset (UpsetGuard)
  std::uint64_t upset_hold_ticks = 0;     ///< ticks on which it was held
};

/// Turns raw operator input into the command the generator gets: validated, clamped to the
/// limits, slew-limited; the height is resolved ("none" → CommandLimits::standing_height) and
/// slewed like any other value, so "none" ↔ value transitions are continuous.
/// noexcept, allocation-free.
class CommandShaper {
 public:
  explicit CommandShaper(CommandLimits limits);
  /// @param sample newest input; @param now controller time [s]; @param dt tick [s];
  /// @param hold_velocity the velocity command goes to zero at the slew limits whatever the operator
  /// commands (UpsetGuard latched); the posture goes on, unless @p upright: then the pitch and roll
  /// go to 0 at posture_rate too (UpsetGuardConfig::upright), the height goes on.
  void update(const CommandSample& sample, double now, double dt, bool hold_velocity = false,
              bool upright = false) noexcept;
  /// Zero velocity, neutral posture, standing height at once (only when the motors do not follow
  /// the references: before the loop enters kActive).
  void reset() noexcept;
  /// The operator's velocity command as clamped to the limits, before the envelopes and the slew
  /// (zero while stale) (heading frame).
  const VelocityCommand& target() const noexcept { return target_; }
  /// Shaped velocity u_d (heading frame).
  const VelocityCommand& velocity() const noexcept { return velocity_; }
  /// Shaped posture u_s; height always a value [m] (resolved).
  const PostureCommand& posture() const noexcept { return posture_; }
  /// (v_x, v_y, ω, pitch, roll, height): the command as the policy observes it.
  std::array<double, 6> vector() const noexcept {
    return {velocity_.vx, velocity_.vy, velocity_.wz, posture_.pitch, posture_.roll, posture_.height};
  }
  bool stale() const noexcept { return stale_; }
  /// How far @p v (heading frame) lies beyond the crouched and bent velocity envelopes at the shaped
  /// posture of the last update: the larger of the two envelopes' scales s (CommandLimits::
  /// crouched_height, bent_pitch); v / s is on the envelope's edge when s > 1, and v is inside when
  /// s <= 1 (0 with both envelopes off or upright at the standing height). noexcept.
  /// @p min_limit (v_x, v_y [m/s], ω [rad/s], each >= 0; zeros by default): each axis's limit in
  /// both envelopes (and the max_velocity it blends from) is at least this, so an envelope never
  /// binds an axis below it (VelocityFeedbackConfig::headroom_in_envelopes passes |u_i| + h_i).
  double envelopeScale(const VelocityCommand& v, const std::array<double, 3>& min_limit = {}) const noexcept;
  /// For VelocityFeedbackConfig::yaw_beyond_envelopes: the scale s >= 1 by which @p v's v_x and v_y
  /// must be divided so that (v_x / s, v_y / s, ω of the shaped command) is inside the envelopes, on
  /// their edge (scale 1) as envelopeScale() would put it, or, while the shaped ω alone lies beyond
  /// the edge (a transient of the slews), as far as that ω does; @p v's own ω is not counted. 1 when
  /// no division is needed. With ω = 0 it equals envelopeScale(v) (the envelopes are homogeneous).
  /// The envelope scale falls monotonically with s, so s is found by bisection of fixed length (at
  /// most 20 doublings, to 2^21, then 50 halvings; relative error below 1e-12); noexcept, no
  /// allocation. @p min_limit as for envelopeScale().
  double envelopeScaleBesideYaw(const VelocityCommand& v, const std::array<double, 3>& min_limit = {}) const noexcept;
  /// How crouched the shaped posture of the last update is, in [0, 1]: the crouched envelope's
  /// crouch f = (standing − h) / (standing − crouched_height), clamped (the blend factor of
  /// envelopeScale()); 0 with the crouched envelope off (crouched_height 0) or at the standing height,
  /// 1 at or below crouched_height. Continuous: it follows the slewed height. noexcept.
  double crouchFraction() const noexcept;
  const CommandCounters& counters() const noexcept { return counters_; }
  const CommandLimits& limits() const noexcept { return limits_; }

 private:
  /// The crouched and the bent envelope's scales of @p v at the shaped posture (envelopeScale()).
  void envelopeScales(const VelocityCommand& v, const std::array<double, 3>& min_limit, double* crouch_scale,
                      double* bent_scale) const noexcept;

  CommandLimits limits_;
  VelocityCommand target_{}, velocity_{};
  PostureCommand posture_target_{}, posture_{};
  double last_velocity_time_ = -2.0, last_posture_time_ = -2.0;
  double last_walking_time_ = -1e9;  ///< controller time the robot was last told to walk [s]
  bool stale_ = true;
  bool held_ = false;
  CommandCounters counters_;
};

/// Bounds the speed of the joint references the loop sends: |q_k − q_{k−1}| ≤ max_speed · dt per
/// joint, whatever the generator (or a mode change) produced. The last line of reference
/// continuity behind the command shaper. noexcept, allocation-free (capacity pmg::kMaxMotors).
class ReferenceRateLimiter {
 public:
  /// @param max_speed [rad/s] > 0.
  explicit ReferenceRateLimiter(double max_speed) noexcept : max_speed_(max_speed) {}
  /// Starts from @p q (n values) without limiting (on entering kActive from the standing pose).
  void reset(const double* q, int n) noexcept;
  /// Limits @p q (n values, in place) against the previous output; returns true if any joint was
  /// limited this tick (counted in limitedTicks()).
  bool apply(double* q, int n, double dt) noexcept;
  std::uint64_t limitedTicks() const noexcept { return limited_ticks_; }
  double maxSpeed() const noexcept { return max_speed_; }

 private:
  double max_speed_;
  std::array<double, 32> prev_{};
  bool have_prev_ = false;
  std::uint64_t limited_ticks_ = 0;
};

/// One segment of a command script.
struct CommandSegment {
  std::string name;       ///< key `name` (or `label`)
  double start = 0.0;     ///< [s] since the script start
  double duration = 0.0;  ///< [s]
  Command command;        ///< held (and ramped to, see CommandScript::ramp) during the segment
  ModeRequest mode = ModeRequest::kNone;  ///< key `mode`: request posted when the segment starts
};

/// A command script (config/commands/*.yaml, config/policies/eval_commands.yaml): segments played
/// back to back. One format, two ways to place segments (never mixed in one file):
///
///   ramp: 0.5          # optional [s]: linear ramp from the previous segment's command (0 = step)
///   duration: 48.0     # optional total [s]; required when segments give `t`
///   segments:          # each: name|label, duration [s] or t [s] (start), vx vy wz pitch roll
///     - {name: stand, duration: 2.0}                       #   height (optional), mode (optional:
///     - {name: squat, duration: 3.0, height: 0.66}         #   passive|soft_stand|active|damping|reset)
///
/// Unknown keys are errors naming the file, line, key and the nearest valid key.
struct CommandScript {
  std::string source_file;
  double ramp = 0.0;
  std::vector<CommandSegment> segments;
  double duration() const;
  /// Index of the segment at time @p t [s] (the last holds after the end).
  std::size_t segmentIndex(double t) const;
  /// Command at @p t [s], ramped from the previous segment over `ramp` seconds. A height ramps
  /// only between two explicit heights; "none" ↔ value steps are left to the shaper's slew.
  Command at(double t) const;
};

/// Loads a command script. @throws ConfigError naming file, line, segment and field.
CommandScript loadCommandScript(const std::string& path);

}  // namespace pmg
