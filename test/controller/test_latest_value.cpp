// Lock-free hand-overs: the triple buffer always yields complete, newest-or-previous values under
// concurrency; the SPSC ring delivers in order and counts drops.
#include <array>
#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "pmg/controller/spsc_ring.hpp"
#include "pmg/hal/latest_value.hpp"

namespace pmg {
namespace {

struct Big {
  std::array<std::uint64_t, 64> v{};  // every element equals the sequence number when complete
};

TEST(LatestValue, ReaderNeverSeesATornOrOlderValue) {
  LatestValue<Big> lv;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    Big b;
    for (std::uint64_t s = 1; s <= 200000; ++s) {
      b.v.fill(s);
      lv.write(b);
    }
    done = true;
  });
  Big r;
  std::uint64_t last = 0, fresh = 0;
  while (true) {
    const bool finished = done.load();
    const bool got = lv.read(r);
    if (got) ++fresh;
    for (auto x : r.v) ASSERT_EQ(x, r.v[0]);  // complete copy
    ASSERT_GE(r.v[0], last);                   // never goes back in time
    last = r.v[0];
    if (finished && !got) break;  // the writer is done and its last value has been seen
  }
  writer.join();
  EXPECT_EQ(r.v[0], 200000u);
  EXPECT_GT(fresh, 0u);
}

TEST(SpscRing, DeliversInOrderAndCountsDrops) {
  SpscRing<int, 8> ring;
  for (int i = 0; i < 10; ++i) ring.push(i);
  EXPECT_EQ(ring.dropped(), 2u);
  int x = -1;
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.pop(x));
    EXPECT_EQ(x, i);
  }
  EXPECT_FALSE(ring.pop(x));
}

}  // namespace
}  // namespace pmg
