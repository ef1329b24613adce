#include "pmg/hal/safety/mode_requests.hpp"

namespace pmg::hal::safety {

ModeRequest GamepadRequests::update(std::uint32_t b) noexcept {
  auto fired = [&](std::uint32_t combo) { return combo != 0 && (b & combo) == combo && (prev_ & combo) != combo; };
  ModeRequest r = ModeRequest::kNone;
  if (fired(map_.damping)) r = ModeRequest::kDamping;
  else if (fired(map_.active)) r = ModeRequest::kActive;
  else if (fired(map_.soft_stand)) r = ModeRequest::kSoftStand;
  else if (fired(map_.passive)) r = ModeRequest::kPassive;
  prev_ = b;
  return r;
}

ModeRequest modeRequestFromCode(std::int32_t code, bool& valid) noexcept {
  valid = code >= 0 && code <= 4;
  if (!valid) return ModeRequest::kNone;
  return static_cast<ModeRequest>(code);
}

void ModeRequestMailbox::post(ModeRequest r) noexcept {
  if (r == ModeRequest::kNone) return;
  const auto v = static_cast<std::uint8_t>(r);
  std::uint8_t cur = slot_.load(std::memory_order_relaxed);
  do {
    if (cur == static_cast<std::uint8_t>(ModeRequest::kDamping)) return;
  } while (!slot_.compare_exchange_weak(cur, v, std::memory_order_release, std::memory_order_relaxed));
}

ModeRequest ModeRequestMailbox::take() noexcept {
  return static_cast<ModeRequest>(slot_.exchange(0, std::memory_order_acquire));
}

}  // namespace pmg::hal::safety
