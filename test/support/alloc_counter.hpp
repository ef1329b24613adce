#pragma once
// Counts heap allocations made by the current thread while a pmg::test::AllocationGuard is alive.
// Link the target with pmg_test_support (which replaces the global operator new) to use it.
#include <cstddef>

namespace pmg::test {

/// Number of operator new calls on this thread since the counter was switched on.
std::size_t allocationCount() noexcept;
void startCountingAllocations() noexcept;
void stopCountingAllocations() noexcept;

/// RAII: counts allocations of this thread during its lifetime.
class AllocationGuard {
 public:
  AllocationGuard() noexcept { startCountingAllocations(); }
  ~AllocationGuard() { stopCountingAllocations(); }
  std::size_t count() const noexcept { return allocationCount(); }
};

}  // namespace pmg::test
