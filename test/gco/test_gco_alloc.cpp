// Proves the per-tick API allocates nothing: a global operator new counter is switched on around
// Gco::solve() and LegKinematics::compute() (after setup and a warm-up tick).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "gco_test_util.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& t) noexcept { return operator new(size, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace pmg::gco {
namespace {

TEST(GcoNoAlloc, CounterSeesAllocations) {
  // The instrument works: a vector allocation is counted.
  g_allocations = 0;
  g_counting = true;
  std::vector<double>* v = new std::vector<double>(100);
  g_counting = false;
  delete v;
  EXPECT_GE(g_allocations.load(), 2);
}

TEST(GcoNoAlloc, SolveAndKinematicsAllocateNothingPerTick) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  o.yaw_rate = 0.3;
  o.height_error = 0.01;
  LegKinematics setup_kin(test::g1Legs());
  const SyntheticGait g = makeSyntheticGait(setup_kin, o);
  Gco gco(test::g1Legs(), GcoOptions{});
  LegKinematics kin(test::g1Legs());
  GcoResult res;
  FootKinematics fk;
  gco.solve(g.ticks[0], &res);  // warm-up
  GcoInput nan_tick = g.ticks[3];
  nan_tick.v_HB_H.x() = std::nan("");

  g_allocations = 0;
  g_counting = true;
  int ok = 0;
  for (int c = 0; c < 3; ++c) {
    for (const GcoInput& in : g.ticks) {
      ok += gco.solve(in, &res) == GcoStatus::kOk ? 1 : 0;
      kin.compute(Foot::kLeft, in.q_leg[0], in.qd_leg[0], &fk);
    }
  }
  gco.solve(nan_tick, &res);  // the fallback path too
  gco.reset();
  gco.solve(g.ticks[5], &res);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(ok, 3 * static_cast<int>(g.ticks.size()));
}

TEST(GcoNoAlloc, GeneratorPlusGcoTickAllocatesNothing) {
  const RobotConfig robot = loadRobotConfig("config/robots/g1/g1.yaml");
  const GeneratorJointSpace js = pmg::generatorJointSpace(robot);
  auto model = std::make_shared<const GeneratorModel>(loadClipLibrary("config/clips/g1", robot), js);
  GeneratorWithGco pipe(model, LegModel::fromRobotConfig(robot), GcoOptions{});
  pipe.step({0.3, 0.0, 0.0}, {}, 0.01);  // warm-up
  g_allocations = 0;
  g_counting = true;
  double sum = 0.0;
  for (int k = 0; k < 600; ++k) {
    const double s = k / 600.0;
    const GcoResult& r = pipe.step({0.9 * s - 0.3, 0.0, 0.5 - s}, {0.0, 0.0, 0.0}, 0.01);
    sum += r.u_opt.v_x;
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace pmg::gco
