#pragma once
// The one allocation guard of the tests. pmg_test_support replaces the global operator new / new[]
// (all forms that allocate) with malloc plus a counter; a pmg::test::AllocationGuard switches the
// counting on for its lifetime:
//   - AllocationScope::kThisThread (default): operator new calls made by the constructing thread;
//   - AllocationScope::kProcess: calls made by any thread of the process, including those made by
//     shared libraries that link the same libstdc++ (ONNX Runtime's, for example).
// Guards do not nest across scopes on one thread: use one guard per measured block.
#include <cstddef>

namespace pmg::test {

enum class AllocationScope { kThisThread, kProcess };

/// Number of operator new calls on this thread since startCountingAllocations().
std::size_t allocationCount() noexcept;
void startCountingAllocations() noexcept;
void stopCountingAllocations() noexcept;

/// Number of operator new calls by any thread since startCountingProcessAllocations().
std::size_t processAllocationCount() noexcept;
void startCountingProcessAllocations() noexcept;
void stopCountingProcessAllocations() noexcept;

/// RAII: counts operator new calls during its lifetime (this thread, or the whole process).
class AllocationGuard {
 public:
  explicit AllocationGuard(AllocationScope scope = AllocationScope::kThisThread) noexcept : scope_(scope) {
    if (scope_ == AllocationScope::kProcess) {
      startCountingProcessAllocations();
    } else {
      startCountingAllocations();
    }
  }
  ~AllocationGuard() {
    if (scope_ == AllocationScope::kProcess) {
      stopCountingProcessAllocations();
    } else {
      stopCountingAllocations();
    }
  }
  AllocationGuard(const AllocationGuard&) = delete;
  AllocationGuard& operator=(const AllocationGuard&) = delete;

  /// Allocations counted so far (the guard keeps counting until it is destroyed).
  std::size_t count() const noexcept {
    return scope_ == AllocationScope::kProcess ? processAllocationCount() : allocationCount();
  }

 private:
  AllocationScope scope_;
};

/// Allocations on this thread while @p f runs (a test's "no allocation" check around a loop).
template <class F>
std::size_t allocationsDuring(F&& f) {
  AllocationGuard guard;
  f();
  return guard.count();
}

}  // namespace pmg::test
