// Speed of the offline motion tools: keypoint retargeting per frame (Ceres over KDL) and loading
// the shipped clip library. Run from the repository root:
//   build/bin/bench_motion
#include <benchmark/benchmark.h>

#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/clip_io.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/keypoint_retarget.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

void BM_RetargetWalkCycle(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig("config/robots/g1/g1.yaml");
  const KinematicModel model(robot);
  const HumanMotion human = deepMimicToHuman(readDeepMimicMotion("data/motions/deepmimic/humanoid3d_walk.txt"));
  for (auto _ : state) {
    RetargetResult r = retargetKeypoints(human, model);
    benchmark::DoNotOptimize(r.motion.q.data());
  }
  state.counters["frames_per_s"] = benchmark::Counter(human.numFrames(), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RetargetWalkCycle)->Unit(benchmark::kMillisecond);

void BM_LoadClipLibrary(benchmark::State& state) {
  const RobotConfig robot = loadRobotConfig("config/robots/g1/g1.yaml");
  for (auto _ : state) {
    ClipLibrary lib = loadClipLibrary(std::string("config/clips/g1"), robot);
    benchmark::DoNotOptimize(lib.dynamic_clips.data());
  }
}
BENCHMARK(BM_LoadClipLibrary)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
