#pragma once
/// @file mode_requests.hpp
/// @brief Where mode requests come from: gamepad buttons (edge-triggered combos) and LCM integer
/// codes, merged through a lock-free mailbox into the HAL thread. noexcept, no allocation.

#include <atomic>
#include <cstdint>

#include "pmg/hal/safety/supervisor.hpp"

namespace pmg::hal::safety {

/// Gamepad button bits (layout of common Xbox/Logitech/Unitree remotes; the gamepad reader maps
/// its device's buttons onto these).
enum GamepadButton : std::uint32_t {
  kBtnA = 1u << 0, kBtnB = 1u << 1, kBtnX = 1u << 2, kBtnY = 1u << 3,
  kBtnL1 = 1u << 4, kBtnR1 = 1u << 5, kBtnL2 = 1u << 6, kBtnR2 = 1u << 7,
  kBtnStart = 1u << 8, kBtnSelect = 1u << 9,
};

/// Button combos per request. A request fires on the tick its combo becomes fully pressed.
struct GamepadMapping {
  std::uint32_t damping = kBtnL2 | kBtnB;   ///< E-stop (checked first: wins over any other combo).
  std::uint32_t soft_stand = kBtnStart;     ///< Passive -> soft stand; active -> soft stand.
  std::uint32_t active = kBtnR1 | kBtnA;    ///< Soft stand -> active (PMG / policy).
  std::uint32_t passive = kBtnSelect;       ///< Soft stand -> passive; reset damping -> passive.
};

/// Edge detector turning a button bit mask per tick into requests.
class GamepadRequests {
 public:
  explicit GamepadRequests(GamepadMapping mapping = {}) noexcept : map_(mapping) {}
  /// Feed the current button mask; returns the request whose combo was just completed, or kNone.
  ModeRequest update(std::uint32_t buttons) noexcept;

 private:
  GamepadMapping map_;
  std::uint32_t prev_ = 0;
};

/// LCM integer code -> request: 0 none, 1 passive, 2 soft stand, 3 active, 4 damping. Any other
/// code returns kNone and sets `valid` false.
ModeRequest modeRequestFromCode(std::int32_t code, bool& valid) noexcept;

/// Single-slot lock-free mailbox from the gamepad/LCM threads to the HAL thread. post() never
/// blocks; a pending kDamping is never overwritten by another request (e-stop wins).
class ModeRequestMailbox {
 public:
  void post(ModeRequest r) noexcept;
  /// Take and clear the pending request (kNone if none).
  ModeRequest take() noexcept;

 private:
  std::atomic<std::uint8_t> slot_{0};
};

}  // namespace pmg::hal::safety
