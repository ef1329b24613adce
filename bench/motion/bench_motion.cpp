// Speed of the offline motion tools: keypoint retargeting per frame (Ceres over KDL) and loading
// the shipped clip library (data of pmg's data directory, pmg::dataDir()):
//   build/bin/bench_motion
#include <benchmark/benchmark.h>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/keypoint_retarget.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

void BM_RetargetWalkCycle(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig(resolveData("config/robots/g1/g1.yaml").string());
  const KinematicModel model(robot);
  const HumanMotion human = deepMimicToHuman(readDeepMimicMotion(resolveData("data/motions/deepmimic/humanoid3d_walk.txt").string()));
  for (auto _ : state) {
    RetargetResult r = retargetKeypoints(human, model);
    benchmark::DoNotOptimize(r.motion.q.data());
  }
  state.counters["frames_per_s"] = benchmark::Counter(human.numFrames(), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RetargetWalkCycle)->Unit(benchmark::kMillisecond);

void BM_LoadClipLibrary(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig(resolveData("config/robots/g1/g1.yaml").string());
  for (auto _ : state) {
    ClipLibrary lib = loadClipLibrary(resolveData("config/clips/g1").string(), robot);
    benchmark::DoNotOptimize(lib.dynamic_clips.data());
  }
}
BENCHMARK(BM_LoadClipLibrary)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
