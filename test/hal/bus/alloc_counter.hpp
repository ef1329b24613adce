#pragma once
// Global operator new counter for "no allocation" tests. Include from exactly one translation unit
// per test executable (it replaces the global allocation functions).
#include <atomic>
#include <cstdlib>
#include <new>

namespace pmg_test {
inline thread_local bool g_count_allocs = false;  // only the thread that opened the scope counts
inline std::atomic<long> g_allocs{0};
/// Counts operator new calls made by this thread between construction and allocations().
struct AllocScope {
  AllocScope() {
    g_allocs = 0;
    g_count_allocs = true;
  }
  ~AllocScope() { g_count_allocs = false; }
  long allocations() const { return g_allocs.load(); }
};
}  // namespace pmg_test

// noinline: GCC 12 otherwise pairs the inlined malloc/free with new/delete and warns
// (-Wmismatched-new-delete) although they match.
[[gnu::noinline]] void* operator new(std::size_t n) {
  if (pmg_test::g_count_allocs) ++pmg_test::g_allocs;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t n) {
  if (pmg_test::g_count_allocs) ++pmg_test::g_allocs;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
