// GamepadMapper: GamepadState → velocity, posture and mode requests (include/pmg/teleop/gamepad.hpp).
// noexcept and allocation-free in update(); every decision is documented on the class.
#include <algorithm>
#include <cmath>

#include "pmg/common/config_error.hpp"
#include "pmg/teleop/gamepad.hpp"

namespace pmg::teleop {
namespace {

std::uint32_t maskOf(const std::vector<GamepadControl>& b) {
  std::uint32_t m = 0;
  for (GamepadControl c : b) m |= controlBit(c);
  return m;
}

constexpr std::uint32_t kButtonBits = (1u << kNumGamepadButtons) - 1u;
constexpr GamepadControl kDpad[4] = {GamepadControl::kDpadUp, GamepadControl::kDpadDown, GamepadControl::kDpadLeft,
                                     GamepadControl::kDpadRight};

bool finiteState(const GamepadState& s) noexcept {
  return std::isfinite(s.left_x) && std::isfinite(s.left_y) && std::isfinite(s.right_x) && std::isfinite(s.right_y) &&
         std::isfinite(s.left_trigger) && std::isfinite(s.right_trigger) && std::isfinite(s.time);
}

}  // namespace

GamepadMapper::GamepadMapper(const GamepadConfig& config) : config_(config) {
  const std::string e = config_.validate();
  if (!e.empty()) throw ConfigError("gamepad config: " + e);
  const GamepadButtonsConfig& b = config_.buttons;
  estop_mask_ = maskOf(b.estop);
  stand_mask_ = maskOf(b.stand);
  walk_mask_ = maskOf(b.walk);
  damping_mask_ = maskOf(b.damping);
  reset_mask_ = maskOf(b.reset);
  neutral_mask_ = maskOf(b.neutral_posture);
  mode_layer_mask_ = controlBit(b.mode_layer);
  pitch_layer_mask_ = controlBit(b.pitch_layer);
}

double GamepadMapper::shape(const GamepadAxisConfig& c, double x) const noexcept {
  const double a = std::fabs(x);
  if (!(a > c.dead_zone)) return 0.0;  // exactly zero inside the dead zone (and for NaN)
  const double u = std::min(1.0, (a - c.dead_zone) / (1.0 - c.dead_zone));
  const double y = (1.0 - c.expo) * u + c.expo * u * u * u;
  return std::copysign(y * c.max, x);
}

double GamepadMapper::slew(double current, double target, const GamepadAxisConfig& c, double dt) noexcept {
  const double d = target - current;
  const bool growing = std::fabs(target) > std::fabs(current) && (current == 0.0 || (current > 0.0) == (target > 0.0));
  const double step = (growing ? c.accel : c.decel) * dt;
  if (std::fabs(d) <= step) return target;  // lands exactly on the target (0 when released)
  return current + std::copysign(step, d);
}

bool GamepadMapper::edge(std::uint32_t mask) const noexcept {
  return mask != 0 && (controls_ & mask) == mask && (prev_controls_ & mask) != mask;
}

void GamepadMapper::request(ModeRequest m) noexcept {
  if (out_.mode == ModeRequest::kNone) {
    out_.mode = m;
    ++counters_.mode_requests;
  } else if (out_.mode != m) {
    ++counters_.dropped_requests;
  }
}

const GamepadOutput& GamepadMapper::update(const GamepadState& s, double now) noexcept {
  ++counters_.updates;
  out_.mode = ModeRequest::kNone;
  if (!std::isfinite(now)) now = last_now_;  // never poisons the timers
  const double dt = have_now_ && now > last_now_ ? now - last_now_ : 0.0;
  last_now_ = now;
  have_now_ = true;

  const bool values_ok = finiteState(s);
  if (s.attached && !values_ok) ++counters_.invalid_states;
  const bool fresh = s.attached && values_ok && s.time >= 0.0 && now - s.time <= config_.link.stale_timeout;
  const GamepadLinkConfig& link = config_.link;

  if (!fresh) {
    if (out_.link == GamepadLink::kOk) {
      out_.link = GamepadLink::kLost;
      loss_since_ = now;
      loss_damping_sent_ = false;
      ++counters_.losses;
    }
    out_.vx = out_.vy = out_.wz = 0.0;  // at once, no slew
    out_.waiting_for_centre = true;
    have_prev_ = false;
    dpad_active_ = 0;
    if (out_.link == GamepadLink::kLost && link.damping_on_loss && !loss_damping_sent_ &&
        now - loss_since_ >= link.damping_timeout) {
      request(ModeRequest::kDamping);
      loss_damping_sent_ = true;
      ++counters_.loss_dampings;
    }
    if (out_.estop_latched && link.estop_repeat > 0.0 && now - last_estop_send_ >= link.estop_repeat) {
      request(ModeRequest::kDamping);
      last_estop_send_ = now;
    }
    return out_;
  }

  if (out_.link != GamepadLink::kOk) {  // (re)connected
    out_.link = GamepadLink::kOk;
    out_.waiting_for_centre = true;
  }
  const double thr = config_.buttons.trigger_threshold;
  controls_ = (s.buttons & kButtonBits) | (s.left_trigger >= thr ? controlBit(GamepadControl::kLeftTrigger) : 0u) |
              (s.right_trigger >= thr ? controlBit(GamepadControl::kRightTrigger) : 0u);
  if (!have_prev_) {  // first state of this connection: history without edges
    prev_controls_ = controls_;
    have_prev_ = true;
  }

  // E-stop chord: level-triggered, latched until released and re-armed by the reset binding.
  bool rearmed = false;
  const bool chord = held(estop_mask_);
  if (chord && !out_.estop_latched) {
    out_.estop_latched = true;
    ++counters_.estops;
    request(ModeRequest::kDamping);
    last_estop_send_ = now;
  } else if (out_.estop_latched) {
    if (!chord && edge(reset_mask_)) {
      out_.estop_latched = false;
      rearmed = true;
      request(ModeRequest::kReset);
    } else if (link.estop_repeat > 0.0 && now - last_estop_send_ >= link.estop_repeat) {
      request(ModeRequest::kDamping);
      last_estop_send_ = now;
    }
  }
  if (out_.estop_latched) {
    out_.vx = out_.vy = out_.wz = 0.0;
    out_.waiting_for_centre = true;
    dpad_active_ = 0;
    prev_controls_ = controls_;
    return out_;
  }

  // Mode requests on press edges, one per update: damping > reset > stand > walk.
  if (!rearmed) {
    const std::pair<std::uint32_t, ModeRequest> modes[] = {{damping_mask_, ModeRequest::kDamping},
                                                           {reset_mask_, ModeRequest::kReset},
                                                           {stand_mask_, ModeRequest::kSoftStand},
                                                           {walk_mask_, ModeRequest::kActive}};
    for (const auto& [mask, m] : modes)
      if (edge(mask)) request(m);
  }

  // Velocity: dead zone → expo → scale → slew. SDL's y is down positive, x right positive.
  const GamepadSticksConfig& st = config_.sticks;
  double tx = shape(st.vx, -s.left_y), ty = shape(st.vy, -s.left_x), tw = shape(st.wz, -s.right_x);
  if (out_.waiting_for_centre && tx == 0.0 && ty == 0.0 && tw == 0.0) out_.waiting_for_centre = false;
  if (out_.waiting_for_centre) {
    out_.vx = out_.vy = out_.wz = 0.0;
  } else {
    out_.vx = slew(out_.vx, tx, st.vx, dt);
    out_.vy = slew(out_.vy, ty, st.vy, dt);
    out_.wz = slew(out_.wz, tw, st.wz, dt);
  }

  updatePosture(now, dt);
  prev_controls_ = controls_;
  return out_;
}

void GamepadMapper::updatePosture(double now, double dt) noexcept {
  const GamepadPostureConfig& p = config_.posture;
  if (held(mode_layer_mask_)) {  // the d-pad belongs to the mode chords while the layer is held
    dpad_active_ = 0;
    return;
  }
  if (edge(neutral_mask_)) {
    out_.pitch = std::clamp(0.0, p.pitch_range[0], p.pitch_range[1]);
    out_.roll = std::clamp(0.0, p.roll_range[0], p.roll_range[1]);
    out_.height.reset();
  }
  const bool pitch_layer = held(pitch_layer_mask_);
  for (int d = 0; d < 4; ++d) {
    const std::uint32_t bit = controlBit(kDpad[d]);
    const std::uint32_t active = 1u << d;
    const bool pressed = (controls_ & bit) != 0;
    double fraction = 0.0;  // of one step (press) or of rate·dt (hold): sign below
    bool step = false;
    if (pressed && (prev_controls_ & bit) == 0) {
      dpad_active_ |= active;
      dpad_since_[static_cast<std::size_t>(d)] = now;
      step = true;
      fraction = 1.0;
    } else if (pressed && (dpad_active_ & active) && now - dpad_since_[static_cast<std::size_t>(d)] >= p.hold_delay) {
      fraction = dt;
    } else if (!pressed) {
      dpad_active_ &= ~active;
    }
    if (fraction == 0.0) continue;
    const double sign = (d == 0 || d == 3) ? 1.0 : -1.0;  // up: +, down: −, left: − roll, right: + roll
    if (d >= 2) {
      out_.roll = std::clamp(out_.roll + sign * fraction * (step ? p.roll_step : p.roll_rate), p.roll_range[0],
                             p.roll_range[1]);
    } else if (pitch_layer) {
      out_.pitch = std::clamp(out_.pitch + sign * fraction * (step ? p.pitch_step : p.pitch_rate), p.pitch_range[0],
                              p.pitch_range[1]);
    } else {
      const double base = out_.height.value_or(p.standing_height);
      out_.height = std::clamp(base + sign * fraction * (step ? p.height_step : p.height_rate), p.height_range[0],
                               p.height_range[1]);
    }
  }
}

}  // namespace pmg::teleop
