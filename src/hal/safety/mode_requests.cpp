#include "pmg/hal/safety/mode_requests.hpp"

namespace pmg::hal::safety {

void ModeRequestMailbox::post(ModeRequest r) noexcept {
  if (r == ModeRequest::kNone) return;
  const auto v = static_cast<std::int8_t>(r);
  std::int8_t cur = slot_.load(std::memory_order_relaxed);
  do {
    if (cur == static_cast<std::int8_t>(ModeRequest::kDamping)) return;
  } while (!slot_.compare_exchange_weak(cur, v, std::memory_order_release, std::memory_order_relaxed));
}

ModeRequest ModeRequestMailbox::take() noexcept {
  return static_cast<ModeRequest>(slot_.exchange(kEmpty, std::memory_order_acquire));
}

}  // namespace pmg::hal::safety
