#pragma once
/// @file gamepad.hpp
/// The gamepad commander's pure logic (no SDL): pmg::teleop::GamepadState (one reading of a game
/// controller), pmg::teleop::GamepadConfig (config/teleop/gamepad.yaml, read through pmg::yaml) and
/// pmg::teleop::GamepadMapper, which turns states into the project's operator commands (velocity,
/// posture, mode requests; include/pmg/controller/commands.hpp, include/pmg/hal/modes.hpp).
/// The SDL2 reader is in gamepad_sdl.hpp, the virtual-controller script in gamepad_script.hpp, the
/// button map and its sources in docs/teleop.md (picture docs/img/gamepad_map.png).
///
/// Sign conventions (robot side: the heading frame H of pmg::Command, x forward, y left, z up):
///   left stick up    → +vx (forward)      left stick left  → +vy (left positive)
///   right stick left → +wz (counter-clockwise positive)
/// The state itself keeps SDL's GameController convention (x right positive, y DOWN positive), so
///   vx = −left_y, vy = −left_x, wz = −right_x  (before dead zone, expo and scaling).
///
/// Default button map (after unitree_rl_lab's G1 deploy FSM and unitree_rl_gym's deploy_real;
/// every binding is configurable):
///   LT + B       e-stop chord → damping, latched in the mapper (level-triggered)
///   LT + d-pad ↑ stand (ModeRequest::kSoftStand)      RB + X   walk (kActive)
///   Back         damping (kDamping)                   LT + Start  reset (kReset) and re-arm
///   d-pad ↑/↓    pelvis height ± (step per press, continuous while held)
///   RT + d-pad ↑/↓  torso pitch ± (bend forward / back)    d-pad ←/→  roll (lean left / right)
///   RT + Y       neutral posture (pitch 0, roll 0, no height command)
/// While LT (the "mode layer") is held the d-pad never changes the posture.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pmg/hal/modes.hpp"

namespace pmg::teleop {

/// The controls of a gamepad, named as SDL2's GameController API names them. 0..20 are the
/// buttons with the values of SDL_GameControllerButton (checked by static_assert in the SDL
/// reader); the two triggers are analog axes that also act as buttons when pressed beyond
/// GamepadButtonsConfig::trigger_threshold. YAML names (yamlEnumNames): SDL's mapping-string names
/// ("a", "leftshoulder", "dpup", "lefttrigger", ...).
enum class GamepadControl : std::uint8_t {
  kA = 0,
  kB,
  kX,
  kY,
  kBack,
  kGuide,
  kStart,
  kLeftStick,      ///< left stick click (L3)
  kRightStick,     ///< right stick click (R3)
  kLeftShoulder,   ///< LB / L1
  kRightShoulder,  ///< RB / R1
  kDpadUp,
  kDpadDown,
  kDpadLeft,
  kDpadRight,
  kMisc1,  ///< Xbox Series share, PS5 microphone, Switch Pro capture button
  kPaddle1,
  kPaddle2,
  kPaddle3,
  kPaddle4,
  kTouchpad,
  kLeftTrigger,   ///< LT / L2 as a button (analog axis above the threshold)
  kRightTrigger,  ///< RT / R2 as a button
  kCount
};
/// Number of real buttons (SDL_CONTROLLER_BUTTON_MAX in SDL 2.26): bits 0..20 of GamepadState::buttons.
inline constexpr int kNumGamepadButtons = 21;
/// The YAML / log name of a control ("a", "lefttrigger", ...).
const char* toString(GamepadControl c) noexcept;
/// Name table for pmg::yaml (found by argument-dependent lookup).
std::vector<std::pair<std::string, GamepadControl>> yamlEnumNames(GamepadControl);
/// Bit of @p c in a control mask (buttons 0..20, then the two triggers).
constexpr std::uint32_t controlBit(GamepadControl c) noexcept { return 1u << static_cast<unsigned>(c); }

/// One reading of a game controller. Plain data, trivially copyable.
/// Axes are normalised from SDL's Sint16 (−32768..32767, divided by 32767 and clamped) and keep
/// SDL's convention: x right positive, y DOWN positive. Triggers: 0 released .. 1 fully pressed.
struct GamepadState {
  double left_x = 0.0;         ///< left stick, right positive [-1, 1]
  double left_y = 0.0;         ///< left stick, down positive [-1, 1] (push up = −1 = forward)
  double right_x = 0.0;        ///< right stick, right positive [-1, 1]
  double right_y = 0.0;        ///< right stick, down positive [-1, 1] (unused by the default map)
  double left_trigger = 0.0;   ///< LT [0, 1]
  double right_trigger = 0.0;  ///< RT [0, 1]
  std::uint32_t buttons = 0;   ///< bit i (i < kNumGamepadButtons) = GamepadControl i pressed
  bool attached = false;       ///< a controller is open and attached
  double time = -1.0;          ///< when this state was read [s, CLOCK_MONOTONIC]; < 0: never
  bool pressed(GamepadControl c) const noexcept { return (buttons & controlBit(c)) != 0; }
};

/// Shaping of one velocity axis: dead zone → expo → scale → slew limit.
struct GamepadAxisConfig {
  double dead_zone = 0.1;  ///< |input| ≤ dead_zone gives exactly 0; above, rescaled to (0, 1] [-], 0..0.5
  double expo = 0.3;       ///< y = (1 − expo)·x + expo·x³ on the rescaled input [-], 0..1
  double max = 0.5;        ///< command at full deflection [m/s or rad/s], (0, CommandLimits max]
  double accel = 1.0;      ///< slew limit while |command| grows [m/s² or rad/s²], > 0
  double decel = 2.0;      ///< slew limit while |command| shrinks or changes sign [m/s² or rad/s²], > 0
  template <class A>
  void Serialize(A* a) {
    a->Visit("dead_zone", &dead_zone, "stick dead zone, fraction of full deflection, 0..0.5");
    a->Visit("expo", &expo, "expo curve weight 0 (linear) .. 1 (cubic)");
    a->Visit("max", &max, "command at full deflection [m/s | rad/s]");
    a->Visit("accel", &accel, "slew limit while the command grows [m/s^2 | rad/s^2] > 0");
    a->Visit("decel", &decel, "slew limit while the command shrinks [m/s^2 | rad/s^2] > 0");
  }
  /// "" when valid (max is checked by GamepadSticksConfig against the command limits).
  std::string validate() const;
};

/// The three velocity axes. Defaults lie inside pmg::CommandLimits::max_velocity {1.0, 0.5, 1.0}.
struct GamepadSticksConfig {
  GamepadAxisConfig vx{0.1, 0.3, 0.6, 1.0, 2.0};  ///< left stick vertical → forward velocity [m/s]
  GamepadAxisConfig vy{0.1, 0.3, 0.3, 1.0, 2.0};  ///< left stick horizontal → lateral velocity [m/s]
  GamepadAxisConfig wz{0.1, 0.3, 0.8, 2.0, 4.0};  ///< right stick horizontal → yaw rate [rad/s]
  template <class A>
  void Serialize(A* a) {
    a->Visit("vx", &vx, "left stick up/down -> forward velocity [m/s]");
    a->Visit("vy", &vy, "left stick left/right -> lateral velocity, left positive [m/s]");
    a->Visit("wz", &wz, "right stick left/right -> yaw rate, counter-clockwise positive [rad/s]");
  }
  /// "" when valid; else names the field and its range, e.g.
  /// "vx.max = 1.5: expected (0, 1] (CommandLimits::max_velocity[0], include/pmg/controller/commands.hpp)".
  std::string validate() const;
};

/// Posture set points: stepped by the d-pad, bounded to ranges inside pmg::CommandLimits.
struct GamepadPostureConfig {
  double standing_height = 0.76;  ///< first height step starts here [m] (≈ the controller's standing height)
  std::array<double, 2> height_range{0.55, 0.80};  ///< pelvis height [m], inside CommandLimits::height_range
  double height_step = 0.02;                       ///< change per d-pad press [m]
  double height_rate = 0.10;                       ///< change while held beyond hold_delay [m/s]
  std::array<double, 2> pitch_range{-0.2, 0.5};    ///< torso pitch (forward bend +) [rad], inside CommandLimits
  double pitch_step = 0.05;                        ///< [rad]
  double pitch_rate = 0.20;                        ///< [rad/s]
  std::array<double, 2> roll_range{-0.2, 0.2};     ///< torso roll (lean right +) [rad], inside CommandLimits
  double roll_step = 0.05;                         ///< [rad]
  double roll_rate = 0.20;                         ///< [rad/s]
  double hold_delay = 0.4;                         ///< a d-pad press held this long starts the continuous change [s]
  template <class A>
  void Serialize(A* a) {
    a->Visit("standing_height", &standing_height, "height the first height step starts from [m]");
    a->Visit("height_range", &height_range, "[min, max] pelvis height [m]");
    a->Visit("height_step", &height_step, "height change per d-pad press [m]");
    a->Visit("height_rate", &height_rate, "height change while the d-pad is held [m/s]");
    a->Visit("pitch_range", &pitch_range, "[min, max] torso pitch, forward bend positive [rad]");
    a->Visit("pitch_step", &pitch_step, "pitch change per press [rad]");
    a->Visit("pitch_rate", &pitch_rate, "pitch change while held [rad/s]");
    a->Visit("roll_range", &roll_range, "[min, max] torso roll, lean right positive [rad]");
    a->Visit("roll_step", &roll_step, "roll change per press [rad]");
    a->Visit("roll_rate", &roll_rate, "roll change while held [rad/s]");
    a->Visit("hold_delay", &hold_delay, "hold time before the continuous change starts [s]");
  }
  /// "" when valid; ranges must lie inside pmg::CommandLimits{} and contain 0 (pitch, roll) and
  /// standing_height (height); steps ≥ 0, rates ≥ 0, hold_delay 0..5 s.
  std::string validate() const;
};

/// Which controls do what. A binding is one or two controls that must be held together; a mode
/// request fires on the update on which its whole binding becomes held (press edge).
struct GamepadButtonsConfig {
  double trigger_threshold = 0.5;  ///< a trigger counts as pressed at ≥ this value [-], 0.05..0.95
  std::vector<GamepadControl> estop{GamepadControl::kLeftTrigger, GamepadControl::kB};  ///< chord → damping, latched
  std::vector<GamepadControl> stand{GamepadControl::kLeftTrigger, GamepadControl::kDpadUp};  ///< kSoftStand
  std::vector<GamepadControl> walk{GamepadControl::kRightShoulder, GamepadControl::kX};      ///< kActive
  std::vector<GamepadControl> damping{GamepadControl::kBack};                                ///< kDamping
  std::vector<GamepadControl> reset{GamepadControl::kLeftTrigger, GamepadControl::kStart};   ///< kReset + re-arm
  std::vector<GamepadControl> neutral_posture{GamepadControl::kRightTrigger, GamepadControl::kY};
  GamepadControl mode_layer = GamepadControl::kLeftTrigger;    ///< while held the d-pad is for modes only
  GamepadControl pitch_layer = GamepadControl::kRightTrigger;  ///< while held d-pad ↑/↓ = pitch, not height
  template <class A>
  void Serialize(A* a) {
    a->Visit("trigger_threshold", &trigger_threshold, "trigger value that counts as pressed, 0.05..0.95");
    a->Visit("estop", &estop, "two-control chord: damping, latched until released and reset");
    a->Visit("stand", &stand, "controls held together: soft stand");
    a->Visit("walk", &walk, "controls held together: active (PMG / policy walking)");
    a->Visit("damping", &damping, "controls held together: damping");
    a->Visit("reset", &reset, "controls held together: reset (damping -> passive), re-arms the e-stop");
    a->Visit("neutral_posture", &neutral_posture, "controls held together: pitch 0, roll 0, no height command");
    a->Visit("mode_layer", &mode_layer, "control that turns the d-pad into mode buttons while held");
    a->Visit("pitch_layer", &pitch_layer, "control that turns d-pad up/down into pitch while held");
  }
  /// "" when valid: every binding 1..2 distinct controls (the e-stop exactly 2), no binding equal to
  /// or contained in another one, the layers not the d-pad.
  std::string validate() const;
};

/// Link supervision.
struct GamepadLinkConfig {
  double stale_timeout = 0.5;    ///< a state older than this = controller lost [s], 0.05..5
  double damping_timeout = 1.0;  ///< lost this long → one damping request [s], > 0 (after the loss)
  bool damping_on_loss = true;   ///< false: a lost controller only zeroes the velocity
  double estop_repeat = 0.5;     ///< while latched, repeat the damping request every … [s]; 0 = once
  template <class A>
  void Serialize(A* a) {
    a->Visit("stale_timeout", &stale_timeout, "state age that counts as a lost controller [s]");
    a->Visit("damping_timeout", &damping_timeout, "time after the loss until the damping request [s]");
    a->Visit("damping_on_loss", &damping_on_loss, "request damping after damping_timeout of loss");
    a->Visit("estop_repeat", &estop_repeat,
             "repeat period of the damping request while the e-stop is latched [s], 0 = once");
  }
  std::string validate() const;
};

/// Everything in config/teleop/gamepad.yaml. Unknown keys are errors (file:line, nearest key).
struct GamepadConfig {
  GamepadSticksConfig sticks;
  GamepadPostureConfig posture;
  GamepadButtonsConfig buttons;
  GamepadLinkConfig link;
  template <class A>
  void Serialize(A* a) {
    a->Visit("sticks", &sticks, "velocity axes");
    a->Visit("posture", &posture, "posture set points");
    a->Visit("buttons", &buttons, "button map");
    a->Visit("link", &link, "controller loss handling");
  }
  /// "" when valid, else "<section>: <field> = <value>: expected <range>" (the sections' checks).
  std::string validate() const;
};

/// Loads and validates a gamepad config. @throws pmg::ConfigError naming file, line, field and range.
GamepadConfig loadGamepadConfig(const std::string& path);
/// The same from YAML text (tests). @throws pmg::ConfigError.
GamepadConfig parseGamepadConfig(const std::string& yaml_text, const std::string& source_name = "<gamepad config>");

/// State of the controller link as the mapper sees it.
enum class GamepadLink : std::uint8_t {
  kNone = 0,  ///< no controller seen yet (no loss handling: nothing to lose)
  kOk,        ///< fresh states from an attached controller
  kLost,      ///< detached or stale: zero velocity; damping requested after damping_timeout
};
const char* toString(GamepadLink l) noexcept;

/// The mapper's output of one update: the operator command to publish.
struct GamepadOutput {
  double vx = 0.0;                        ///< forward velocity, heading frame [m/s]
  double vy = 0.0;                        ///< lateral velocity, left positive [m/s]
  double wz = 0.0;                        ///< yaw rate, counter-clockwise positive [rad/s]
  double pitch = 0.0;                     ///< torso pitch, forward bend positive [rad]
  double roll = 0.0;                      ///< torso roll, lean right positive [rad]
  std::optional<double> height;           ///< pelvis height [m]; nullopt = no height command (standing height)
  ModeRequest mode = ModeRequest::kNone;  ///< request to publish on this update (kNone: none)
  GamepadLink link = GamepadLink::kNone;
  bool estop_latched = false;       ///< e-stop chord seen and not yet re-armed
  bool waiting_for_centre = false;  ///< velocity held at 0 until the sticks are seen inside their dead zones
};

/// What the mapper did so far (status lines and the run summary).
struct GamepadCounters {
  std::uint64_t updates = 0;
  std::uint64_t mode_requests = 0;     ///< requests output (every kind, repeats of the e-stop included)
  std::uint64_t estops = 0;            ///< e-stop latches
  std::uint64_t losses = 0;            ///< transitions into GamepadLink::kLost
  std::uint64_t loss_dampings = 0;     ///< damping requests sent because of a loss
  std::uint64_t invalid_states = 0;    ///< states with non-finite values (treated as lost)
  std::uint64_t dropped_requests = 0;  ///< edges that lost against a higher-priority request on the same update
};

/// GamepadState → operator command. Pure logic, no SDL, no I/O; construction validates the config
/// (may throw pmg::ConfigError), update() is noexcept and allocation-free.
///
/// Per update, with dt = now − previous now (0 on the first):
///  1. Link: the state is fresh if attached, time ≥ 0, now − time ≤ stale_timeout and every value
///     finite. Not fresh → velocity exactly 0 at once (no slew), posture held, no mode edges;
///     after damping_timeout of loss (measured from the update that saw it), one kDamping request
///     (only if a controller had been seen: a commander started without one does not stop the robot).
///  2. After any loss, (re)connection or e-stop the velocity stays 0 until all three stick axes are
///     seen inside their dead zones (a stick held while reconnecting never starts the robot).
///     The first state after a (re)connection sets the button history without edges.
///  3. E-stop chord (level-triggered): held → kDamping at once, latched: velocity 0, posture frozen,
///     other requests ignored, the damping request repeated every estop_repeat. Cleared only by the
///     reset binding pressed while the chord is released (→ kReset, re-armed).
///  4. Mode edges, at most one request per update, priority damping > reset > stand > walk
///     (a lower one on the same update is dropped and counted).
///  5. Velocity: dead zone (exactly 0 inside) → expo → ×max → slew (accel growing, decel shrinking);
///     the slewed value lands exactly on its target, so released sticks give exactly 0.
///  6. Posture (not while the mode layer is held): d-pad press = one step, held beyond hold_delay =
///     rate·dt per update; bounded to the ranges. The first height change starts from
///     standing_height; neutral_posture → pitch 0, roll 0, height none.
class GamepadMapper {
 public:
  /// @throws pmg::ConfigError if @p config is invalid (message names the field and range).
  explicit GamepadMapper(const GamepadConfig& config);
  /// One step; see the class comment. @p now: [s], same clock as GamepadState::time.
  const GamepadOutput& update(const GamepadState& state, double now) noexcept;
  const GamepadOutput& output() const noexcept { return out_; }
  const GamepadCounters& counters() const noexcept { return counters_; }
  const GamepadConfig& config() const noexcept { return config_; }

 private:
  double shape(const GamepadAxisConfig& c, double x) const noexcept;
  static double slew(double current, double target, const GamepadAxisConfig& c, double dt) noexcept;
  bool edge(std::uint32_t mask) const noexcept;
  bool held(std::uint32_t mask) const noexcept { return mask != 0 && (controls_ & mask) == mask; }
  void updatePosture(double now, double dt) noexcept;
  void request(ModeRequest m) noexcept;

  GamepadConfig config_;
  std::uint32_t estop_mask_ = 0, stand_mask_ = 0, walk_mask_ = 0, damping_mask_ = 0, reset_mask_ = 0, neutral_mask_ = 0,
                mode_layer_mask_ = 0, pitch_layer_mask_ = 0;
  std::uint32_t controls_ = 0, prev_controls_ = 0;
  bool have_prev_ = false;  ///< prev_controls_ belongs to the current connection
  bool ever_connected_ = false;
  bool loss_damping_sent_ = false;
  double loss_since_ = 0.0;
  double last_now_ = 0.0;
  bool have_now_ = false;
  double last_estop_send_ = 0.0;
  std::array<double, 4> dpad_since_{};  ///< press time of up, down, left, right [s]
  unsigned dpad_active_ = 0;            ///< bit d: d-pad direction d pressed on an edge of this connection
  GamepadOutput out_;
  GamepadCounters counters_;
};

}  // namespace pmg::teleop
