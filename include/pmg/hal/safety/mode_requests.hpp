#pragma once
/// @file mode_requests.hpp
/// @brief How mode requests reach the HAL thread: command sources (LCM, scripts, gamepad) post
/// pmg::ModeRequest values (include/pmg/hal/modes.hpp) into a lock-free single-slot mailbox that
/// the SafeBackend takes once per HAL cycle. noexcept, no allocation.

#include <atomic>
#include <cstdint>

#include "pmg/hal/modes.hpp"

namespace pmg::hal::safety {

/// Single-slot lock-free mailbox from the command threads to the HAL thread. post() never blocks;
/// a pending kDamping is never overwritten by another request (e-stop wins).
class ModeRequestMailbox {
 public:
  void post(ModeRequest r) noexcept;
  /// Take and clear the pending request (kNone if none).
  ModeRequest take() noexcept;

 private:
  static constexpr std::int8_t kEmpty = static_cast<std::int8_t>(ModeRequest::kNone);
  std::atomic<std::int8_t> slot_{kEmpty};
};

}  // namespace pmg::hal::safety
