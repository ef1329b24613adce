#pragma once
/// @file spsc_ring.hpp
/// Bounded lock-free single-producer / single-consumer queue. The real-time side pushes
/// (wait-free, allocation-free; a full queue drops the item and counts it), a non-real-time
/// thread pops (e.g. to publish telemetry over LCM and write the event log).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace pmg {

template <typename T, std::size_t Capacity>
class SpscRing {
  static_assert((Capacity & (Capacity - 1)) == 0, "Capacity must be a power of two");

 public:
  /// Producer: returns false (and counts a drop) if the queue is full.
  bool push(const T& item) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= Capacity) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    items_[head & (Capacity - 1)] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  /// Consumer: returns false if empty.
  bool pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = items_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  std::uint64_t dropped() const noexcept { return dropped_.load(); }

 private:
  std::array<T, Capacity> items_{};
  std::atomic<std::size_t> head_{0}, tail_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace pmg
