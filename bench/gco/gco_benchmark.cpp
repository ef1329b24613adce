// Google Benchmark of the GCO tick: GCO alone (synthetic G1 template), the generator alone and
// generator + GCO on the shipped G1 clips (of pmg's data directory, pmg::dataDir()):
//   build/bin/pmg_gco_benchmark
// Tail latency (p50/p99/max per tick) is printed by pmg_gco_tick_bench.
#include <benchmark/benchmark.h>

#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/gco/synthetic_gait.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {

using namespace pmg;
using namespace pmg::gco;

std::shared_ptr<const GeneratorModel> generatorModel(const RobotConfig& r, Blending blending = Blending::kConsistent) {
  const GeneratorJointSpace js = pmg::generatorJointSpace(r);
  GeneratorParams p;
  p.blending = blending;
  return std::make_shared<const GeneratorModel>(loadClipLibrary(resolveData("config/clips/g1").string(), r), js, p);
}

void BM_GcoSolveSyntheticWalk(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig(resolveData("config/robots/g1/g1.yaml").string());
  auto legs = LegModel::fromRobotConfig(robot);
  LegKinematics kin(legs);
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  o.yaw_rate = 0.3;
  o.height_error = 0.01;
  const SyntheticGait g = makeSyntheticGait(kin, o);
  Gco gco(legs, GcoOptions{});
  GcoResult res;
  std::size_t k = 0;
  for (auto _ : state) {
    gco.solve(g.ticks[k], &res);
    benchmark::DoNotOptimize(res.u_opt.v_x);
    k = (k + 1) % g.ticks.size();
  }
}
BENCHMARK(BM_GcoSolveSyntheticWalk);

// Arg 0: the paper's blending; 1: command-consistent (amplitude solve + consistency map), walking
// crouched and bent so that every map dimension interpolates.
void BM_GeneratorStep(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig(resolveData("config/robots/g1/g1.yaml").string());
  MotionGenerator gen(generatorModel(robot, state.range(0) == 0 ? Blending::kPaper : Blending::kConsistent));
  state.SetLabel(state.range(0) == 0 ? "paper" : "consistent");
  for (auto _ : state) {
    gen.step({0.6, 0.1, 0.3}, {0.1, 0.0, 0.7}, 0.01);
    benchmark::DoNotOptimize(gen.output().q_ref.data());
  }
}
BENCHMARK(BM_GeneratorStep)->Arg(0)->Arg(1);

void BM_GeneratorPlusGco(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig(resolveData("config/robots/g1/g1.yaml").string());
  GeneratorWithGco pipe(generatorModel(robot), LegModel::fromRobotConfig(robot), GcoOptions{});
  for (auto _ : state) {
    const GcoResult& r = pipe.step({0.6, 0.0, 0.3}, {}, 0.01);
    benchmark::DoNotOptimize(r.u_opt.v_x);
  }
}
BENCHMARK(BM_GeneratorPlusGco);

}  // namespace

BENCHMARK_MAIN();
