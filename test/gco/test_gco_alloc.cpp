// Proves the per-tick API allocates nothing: the test-support allocation guard is switched on around
// Gco::solve() and LegKinematics::compute() (after setup and a warm-up tick).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "gco_test_util.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/clips/clip_io.hpp"

namespace pmg::gco {
namespace {

TEST(GcoNoAlloc, CounterSeesAllocations) {
  // The instrument works: a vector allocation is counted.
  std::size_t n = 0;
  {
    pmg::test::AllocationGuard guard;
    auto* v = new std::vector<double>(100);
    n = guard.count();
    delete v;
  }
  EXPECT_GE(n, 2u);
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

  std::optional<pmg::test::AllocationGuard> guard;
  guard.emplace();
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
  const std::size_t allocations = guard->count();
  guard.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(ok, 3 * static_cast<int>(g.ticks.size()));
}

class GcoNoAllocPipe : public ::testing::TestWithParam<int> {};

// Plain, with the stance sole levelling (sole_levelling.hpp) of the reference, and with the stride
// adaptation (stride_adaptation.hpp) on top of the levelling.
TEST_P(GcoNoAllocPipe, GeneratorPlusGcoTickAllocatesNothing) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const GeneratorJointSpace js = pmg::generatorJointSpace(robot);
  auto model = std::make_shared<const GeneratorModel>(loadClipLibrary(pmg::test::g1ClipDir(), robot), js);
  GcoOptions options;
  options.sole_levelling.enabled = GetParam() >= 1;
  options.stride_adaptation.enabled = GetParam() >= 2;
  GeneratorWithGco pipe(model, LegModel::fromRobotConfig(robot), options);
  pipe.step({0.3, 0.0, 0.0}, {}, 0.01);  // warm-up
  std::optional<pmg::test::AllocationGuard> guard;
  guard.emplace();
  double sum = 0.0;
  for (int k = 0; k < 600; ++k) {
    const double s = k / 600.0;
    const GcoResult& r = pipe.step({0.9 * s - 0.3, 0.3 * s, 0.5 - s}, {0.2 * s, 0.0, 0.0}, 0.01);
    sum += r.u_opt.v_x + pipe.generatorOutput().q_ref.sum();
    if (k == 300) pipe.reset(0.25);
  }
  const std::size_t allocations = guard->count();
  guard.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(std::isfinite(sum));
  if (GetParam() >= 1) {
    EXPECT_GT(pipe.soleLevelling().correction(Foot::kLeft).norm() + pipe.soleLevelling().correction(Foot::kRight).norm(), 0.0);
  }
  if (GetParam() >= 2) {
    EXPECT_GT(pipe.strideAdaptation().correction(Foot::kLeft).norm() +
                  pipe.strideAdaptation().correction(Foot::kRight).norm(), 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(ReferenceSettings, GcoNoAllocPipe, ::testing::Values(0, 1, 2));

}  // namespace
}  // namespace pmg::gco
