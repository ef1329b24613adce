#pragma once
/// @file latest_value.hpp
/// Lock-free single-producer / single-consumer hand-over of the latest value (a triple buffer).
/// The writer never waits for the reader and vice versa: write() publishes a complete copy, read()
/// returns the newest complete copy (or the previous one again if nothing new arrived). Neither
/// call allocates, locks or throws; T must be trivially copyable.

#include <atomic>
#include <cstdint>
#include <type_traits>

namespace pmg {

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue<T> needs a trivially copyable T");

 public:
  LatestValue() = default;
  explicit LatestValue(const T& initial) {
    for (auto& b : buffers_) b = initial;
  }

  /// Producer side: publish @p value. Wait-free.
  void write(const T& value) noexcept {
    buffers_[back_] = value;
    // Swap the back buffer with the middle one and mark it fresh.
    const std::uint8_t old = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = old & kIndexMask;
  }

  /// Consumer side: copy the newest value into @p out. Returns true if it is new since the last
  /// read. Wait-free.
  bool read(T& out) noexcept {
    bool fresh = false;
    if (middle_.load(std::memory_order_acquire) & kFresh) {
      const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = old & kIndexMask;
      fresh = true;
    }
    out = buffers_[front_];
    return fresh;
  }

 private:
  static constexpr std::uint8_t kFresh = 0x4;
  static constexpr std::uint8_t kIndexMask = 0x3;
  T buffers_[3]{};
  std::uint8_t back_ = 0;                 // producer-owned
  std::atomic<std::uint8_t> middle_{1};   // shared
  std::uint8_t front_ = 2;                // consumer-owned
};

}  // namespace pmg
