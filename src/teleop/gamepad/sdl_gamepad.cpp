// SDL2 GameController reader and virtual controller (include/pmg/teleop/gamepad_sdl.hpp).
#include <SDL.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pmg/teleop/gamepad_sdl.hpp"

namespace pmg::teleop {

// GamepadControl 0..20 are SDL_GameControllerButton values.
static_assert(static_cast<int>(GamepadControl::kA) == SDL_CONTROLLER_BUTTON_A);
static_assert(static_cast<int>(GamepadControl::kB) == SDL_CONTROLLER_BUTTON_B);
static_assert(static_cast<int>(GamepadControl::kBack) == SDL_CONTROLLER_BUTTON_BACK);
static_assert(static_cast<int>(GamepadControl::kStart) == SDL_CONTROLLER_BUTTON_START);
static_assert(static_cast<int>(GamepadControl::kLeftShoulder) == SDL_CONTROLLER_BUTTON_LEFTSHOULDER);
static_assert(static_cast<int>(GamepadControl::kRightShoulder) == SDL_CONTROLLER_BUTTON_RIGHTSHOULDER);
static_assert(static_cast<int>(GamepadControl::kDpadUp) == SDL_CONTROLLER_BUTTON_DPAD_UP);
static_assert(static_cast<int>(GamepadControl::kDpadRight) == SDL_CONTROLLER_BUTTON_DPAD_RIGHT);
static_assert(static_cast<int>(GamepadControl::kMisc1) == SDL_CONTROLLER_BUTTON_MISC1);
static_assert(static_cast<int>(GamepadControl::kTouchpad) == SDL_CONTROLLER_BUTTON_TOUCHPAD);
static_assert(kNumGamepadButtons == SDL_CONTROLLER_BUTTON_MAX);

namespace {

constexpr Uint32 kSubsystems = SDL_INIT_GAMECONTROLLER | SDL_INIT_EVENTS;

void initSdl() {
  // Before the first SDL_Init: no window needed for joystick events, and no SDL signal handlers
  // (SDL_INIT_EVENTS would otherwise turn SIGINT/SIGTERM into SDL_QUIT events).
  SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
  SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
  if (SDL_InitSubSystem(kSubsystems) != 0)
    throw std::runtime_error(std::string("SDL game controller subsystem: ") + SDL_GetError());
}

double axis(Sint16 v) noexcept { return std::clamp(static_cast<double>(v) / 32767.0, -1.0, 1.0); }
double trigger(Sint16 v) noexcept { return std::clamp(static_cast<double>(v) / 32767.0, 0.0, 1.0); }

Sint16 toAxis(double v) noexcept {
  if (!std::isfinite(v)) v = 0.0;
  return static_cast<Sint16>(std::lround(std::clamp(v, -1.0, 1.0) * 32767.0));
}
Sint16 toTrigger(double t) noexcept {
  if (!std::isfinite(t)) t = 0.0;
  return static_cast<Sint16>(std::lround(std::clamp(t, 0.0, 1.0) * 65535.0 - 32768.0));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
SdlGamepad::SdlGamepad(std::string name_contains) : name_contains_(std::move(name_contains)) { initSdl(); }

SdlGamepad::~SdlGamepad() {
  close();
  SDL_QuitSubSystem(kSubsystems);
}

bool SdlGamepad::tryOpen(int device_index) {
  if (controller_ || !SDL_IsGameController(device_index)) return false;
  if (!name_contains_.empty()) {
    const char* n = SDL_GameControllerNameForIndex(device_index);
    if (!n || std::string(n).find(name_contains_) == std::string::npos) return false;
  }
  SDL_GameController* gc = SDL_GameControllerOpen(device_index);
  if (!gc) return false;
  controller_ = gc;
  instance_id_ = SDL_JoystickInstanceID(SDL_GameControllerGetJoystick(gc));
  const char* n = SDL_GameControllerName(gc);
  name_ = n ? n : "(unnamed controller)";
  ++connects_;
  return true;
}

void SdlGamepad::close() {
  if (!controller_) return;
  SDL_GameControllerClose(controller_);
  controller_ = nullptr;
  instance_id_ = -1;
  name_.clear();
}

GamepadState SdlGamepad::poll(double now) {
  SDL_Event e;
  while (SDL_PollEvent(&e)) {
    if (e.type == SDL_CONTROLLERDEVICEADDED) {
      tryOpen(e.cdevice.which);  // which = device index
    } else if (e.type == SDL_CONTROLLERDEVICEREMOVED) {
      if (controller_ && e.cdevice.which == instance_id_) {  // which = instance id
        close();
        ++disconnects_;
      }
    }
  }
  if (controller_ && !SDL_GameControllerGetAttached(controller_)) {
    close();
    ++disconnects_;
  }
  if (!controller_) {  // e.g. the open one went away while another is still plugged in
    const int n = SDL_NumJoysticks();
    for (int i = 0; i < n && !controller_; ++i) tryOpen(i);
  }
  GamepadState s;
  s.time = now;
  if (!controller_) return s;
  s.attached = true;
  s.left_x = axis(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_LEFTX));
  s.left_y = axis(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_LEFTY));
  s.right_x = axis(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_RIGHTX));
  s.right_y = axis(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_RIGHTY));
  s.left_trigger = trigger(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_TRIGGERLEFT));
  s.right_trigger = trigger(SDL_GameControllerGetAxis(controller_, SDL_CONTROLLER_AXIS_TRIGGERRIGHT));
  for (int b = 0; b < kNumGamepadButtons; ++b)
    if (SDL_GameControllerGetButton(controller_, static_cast<SDL_GameControllerButton>(b))) s.buttons |= 1u << b;
  return s;
}

// ---------------------------------------------------------------------------------------------
SdlVirtualGamepad::SdlVirtualGamepad(std::string name) : name_(std::move(name)) {
  initSdl();
  try {
    attach();
  } catch (...) {
    SDL_QuitSubSystem(kSubsystems);
    throw;
  }
}

SdlVirtualGamepad::~SdlVirtualGamepad() {
  detach();
  SDL_QuitSubSystem(kSubsystems);
}

void SdlVirtualGamepad::attach() {
  if (joystick_) return;
  SDL_VirtualJoystickDesc desc;
  SDL_zero(desc);
  desc.version = SDL_VIRTUAL_JOYSTICK_DESC_VERSION;
  desc.type = SDL_JOYSTICK_TYPE_GAMECONTROLLER;
  desc.naxes = SDL_CONTROLLER_AXIS_MAX;
  desc.nbuttons = SDL_CONTROLLER_BUTTON_MAX;
  desc.name = name_.c_str();
  const int index = SDL_JoystickAttachVirtualEx(&desc);
  if (index < 0) throw std::runtime_error(std::string("SDL virtual controller: ") + SDL_GetError());
  joystick_ = SDL_JoystickOpen(index);  // SDL_JoystickSetVirtual* need an open handle
  if (!joystick_) {
    const std::string why = SDL_GetError();
    SDL_JoystickDetachVirtual(index);
    throw std::runtime_error("SDL virtual controller: cannot open it: " + why);
  }
  instance_id_ = SDL_JoystickInstanceID(joystick_);
  set(GamepadState{});  // centred sticks, released triggers (a raw 0 would read as a half-pressed trigger)
}

void SdlVirtualGamepad::detach() noexcept {
  if (!joystick_) return;
  SDL_JoystickClose(joystick_);
  joystick_ = nullptr;
  // Device indices shift as devices come and go: find ours by its instance id.
  const int n = SDL_NumJoysticks();
  for (int i = 0; i < n; ++i)
    if (SDL_JoystickGetDeviceInstanceID(i) == instance_id_) {
      SDL_JoystickDetachVirtual(i);
      break;
    }
  instance_id_ = -1;
}

void SdlVirtualGamepad::set(const GamepadState& s) noexcept {
  if (!joystick_) return;
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_LEFTX, toAxis(s.left_x));
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_LEFTY, toAxis(s.left_y));
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_RIGHTX, toAxis(s.right_x));
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_RIGHTY, toAxis(s.right_y));
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_TRIGGERLEFT, toTrigger(s.left_trigger));
  SDL_JoystickSetVirtualAxis(joystick_, SDL_CONTROLLER_AXIS_TRIGGERRIGHT, toTrigger(s.right_trigger));
  for (int b = 0; b < kNumGamepadButtons; ++b)
    SDL_JoystickSetVirtualButton(joystick_, b, (s.buttons >> b) & 1u ? SDL_PRESSED : SDL_RELEASED);
}

}  // namespace pmg::teleop
