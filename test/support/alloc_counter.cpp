#include "alloc_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
thread_local bool g_counting = false;
thread_local std::size_t g_count = 0;
std::atomic<bool> g_process_counting{false};
std::atomic<std::size_t> g_process_count{0};

void count() noexcept {
  if (g_counting) ++g_count;
  if (g_process_counting.load(std::memory_order_relaxed)) g_process_count.fetch_add(1, std::memory_order_relaxed);
}

void* countedAlloc(std::size_t size) {
  count();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

void* countedAllocNoThrow(std::size_t size) noexcept {
  count();
  return std::malloc(size == 0 ? 1 : size);
}
}  // namespace

namespace pmg::test {
std::size_t allocationCount() noexcept { return g_count; }
void startCountingAllocations() noexcept {
  g_count = 0;
  g_counting = true;
}
void stopCountingAllocations() noexcept { g_counting = false; }

std::size_t processAllocationCount() noexcept { return g_process_count.load(std::memory_order_relaxed); }
void startCountingProcessAllocations() noexcept {
  g_process_count.store(0, std::memory_order_relaxed);
  g_process_counting.store(true, std::memory_order_relaxed);
}
void stopCountingProcessAllocations() noexcept { g_process_counting.store(false, std::memory_order_relaxed); }
}  // namespace pmg::test

void* operator new(std::size_t size) { return countedAlloc(size); }
void* operator new[](std::size_t size) { return countedAlloc(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return countedAllocNoThrow(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return countedAllocNoThrow(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
