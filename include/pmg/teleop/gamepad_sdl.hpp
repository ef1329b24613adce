#pragma once
/// @file gamepad_sdl.hpp
/// Game controllers through SDL2's GameController API (SDL ≥ 2.24; Debian `libsdl2-dev`), never raw
/// /dev/input: SDL maps hundreds of controllers (Xbox, PlayStation, Switch Pro, 8BitDo, Logitech,
/// Steam) onto one layout, A/B/X/Y, shoulders, triggers, d-pad, back/start/guide; extra mappings
/// come from the environment variable SDL_GAMECONTROLLERCONFIG (SDL reads it itself).
///
///  - pmg::teleop::SdlGamepad reads one controller with hot plug (SDL_CONTROLLERDEVICEADDED /
///    SDL_CONTROLLERDEVICEREMOVED): the first controller (or the first whose name contains a given
///    text) is opened, and when it goes away the next one present is taken.
///  - pmg::teleop::SdlVirtualGamepad is a controller made by SDL itself
///    (SDL_JoystickAttachVirtualEx, type SDL_JOYSTICK_TYPE_GAMECONTROLLER): tests and
///    `pmg_gamepad --virtual-script` drive SdlGamepad through the same API as a real controller.
///
/// Only SDL_INIT_GAMECONTROLLER | SDL_INIT_EVENTS are initialised (ref-counted per object), with the
/// hints SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS=1 (no window, works headless) and
/// SDL_HINT_NO_SIGNAL_HANDLERS=1 (SIGINT/SIGTERM stay with the application). Setup code: allocates,
/// constructors throw std::runtime_error with SDL_GetError()'s text. Use from one thread.

#include <cstdint>
#include <string>

#include "pmg/teleop/gamepad.hpp"

struct _SDL_GameController;
struct _SDL_Joystick;

namespace pmg::teleop {

/// Reads the state of one SDL game controller, with hot plug.
class SdlGamepad {
 public:
  /// @param name_contains open only controllers whose SDL name contains this text ("" = any).
  /// @throws std::runtime_error if SDL's game controller subsystem cannot be initialised.
  explicit SdlGamepad(std::string name_contains = "");
  ~SdlGamepad();
  SdlGamepad(const SdlGamepad&) = delete;
  SdlGamepad& operator=(const SdlGamepad&) = delete;

  /// Pumps SDL's events (hot plug), opens a controller if none is open, and reads it.
  /// @param now time stamp of the reading [s, CLOCK_MONOTONIC] → GamepadState::time.
  /// @return attached = false (all values 0, time = now) when no controller is open.
  GamepadState poll(double now);

  bool connected() const noexcept { return controller_ != nullptr; }
  /// SDL's name of the open controller ("" when none), e.g. "Xbox Series X Controller".
  const std::string& name() const noexcept { return name_; }
  /// SDL joystick instance id of the open controller (-1 when none).
  int instanceId() const noexcept { return instance_id_; }
  /// Controllers opened / lost (removed or detached) so far.
  std::uint64_t connects() const noexcept { return connects_; }
  std::uint64_t disconnects() const noexcept { return disconnects_; }

 private:
  bool tryOpen(int device_index);
  void close();
  std::string name_contains_;
  _SDL_GameController* controller_ = nullptr;
  int instance_id_ = -1;
  std::string name_;
  std::uint64_t connects_ = 0, disconnects_ = 0;
};

/// A virtual game controller inside this process (SDL's virtual joystick driver), with all 21
/// buttons and 6 axes of the GameController layout. set() values are seen by SdlGamepad (and any
/// SDL reader) at its next poll.
class SdlVirtualGamepad {
 public:
  /// Attaches at once. @throws std::runtime_error with SDL's error text.
  explicit SdlVirtualGamepad(std::string name = "pmg virtual gamepad");
  ~SdlVirtualGamepad();  ///< detaches
  SdlVirtualGamepad(const SdlVirtualGamepad&) = delete;
  SdlVirtualGamepad& operator=(const SdlVirtualGamepad&) = delete;

  /// Plugs the device in again (after detach()); the axes start centred, triggers released.
  /// @throws std::runtime_error.
  void attach();
  /// Unplugs the device (SDL sends SDL_CONTROLLERDEVICEREMOVED). No-op when detached.
  void detach() noexcept;
  bool attached() const noexcept { return joystick_ != nullptr; }
  /// Sets axes, triggers and buttons from @p s (GamepadState's convention: y down positive;
  /// s.attached and s.time are ignored). Sint16 = round(v · 32767); a trigger t ∈ [0, 1] is sent as
  /// the raw axis t · 65535 − 32768, which SDL's GameController layer maps back to t · 32767.
  /// No-op when detached.
  void set(const GamepadState& s) noexcept;
  /// SDL joystick instance id (-1 when detached).
  int instanceId() const noexcept { return instance_id_; }
  const std::string& name() const noexcept { return name_; }

 private:
  std::string name_;
  _SDL_Joystick* joystick_ = nullptr;
  int instance_id_ = -1;
};

}  // namespace pmg::teleop
