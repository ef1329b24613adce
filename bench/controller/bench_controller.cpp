// bench_controller: per-tick compute time of the PMG generator and of the whole 100 Hz loop tick
// (p50 / p99 / max), the 500 Hz MuJoCo HAL cycle, and the SIL real-time factor (lockstep).
//
//   build/bin/bench_controller [--config config/controller/g1_sil.yaml] [--seconds 30]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/controller/controller.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/motion/clip_io.hpp"

namespace {
using Clock = std::chrono::steady_clock;

struct Pct {
  double p50, p99, max;
};
Pct percentiles(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v[std::min(v.size() - 1, v.size() * 99 / 100)], v.back()};
}
double us(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_controller: generator / loop / HAL cost and SIL real-time factor"};
  std::string config_path = pmg::resolveData("config/controller/g1_sil.yaml").string();
  std::string script_path = pmg::resolveData("config/commands/demo.yaml").string();
  double seconds = 28.0;
  app.add_option("--config", config_path, "controller config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--script", script_path, "command script YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--seconds", seconds, "simulated seconds of the SIL run");
  CLI11_PARSE(app, argc, argv);

  pmg::ControllerConfig config = pmg::loadControllerConfig(config_path);
  config.lcm_enabled = false;
  const pmg::CommandScript script = pmg::loadCommandScript(script_path);

  // 1. Generator alone: 100k ticks over the script's commands.
  {
    const auto& r = config.robot;
    const pmg::GeneratorJointSpace js = pmg::generatorJointSpace(r);
    auto model = std::make_shared<const pmg::GeneratorModel>(pmg::loadClipLibrary(config.clips_dir, r), js,
                                                             config.generator);
    pmg::MotionGenerator gen(model);
    std::vector<double> t;
    t.reserve(100000);
    for (int k = 0; k < 100000; ++k) {
      const auto& seg = script.at(std::fmod(k * 0.01, script.duration()));
      const auto t0 = Clock::now();
      gen.step(seg.velocity, seg.posture, 0.01);
      t.push_back(us(Clock::now() - t0));
    }
    const Pct p = percentiles(t);
    std::printf("generator step (29 joints, 3 dynamic clips)  p50 %7.2f us  p99 %7.2f us  max %7.2f us  (n=100000)\n",
                p.p50, p.p99, p.max);
  }
  // 2. Loop tick and HAL cycle inside a lockstep SIL run.
  pmg::Controller controller(config);
  const int ticks = static_cast<int>(seconds * config.loop_rate_hz);
  std::vector<double> tick_us, hal_us;
  tick_us.reserve(static_cast<std::size_t>(ticks));
  hal_us.reserve(static_cast<std::size_t>(ticks) * 5);
  pmg::CommandSample sample;
  const auto wall0 = Clock::now();
  for (int k = 0; k < ticks; ++k) {
    const double now = k / config.loop_rate_hz;
    const auto& seg = script.at(std::fmod(now, script.duration()));
    sample.velocity = seg.velocity;
    sample.posture = seg.posture;
    sample.velocity_time = sample.posture_time = now;
    controller.setInput(sample);
    const auto t0 = Clock::now();
    controller.tick(now);
    tick_us.push_back(us(Clock::now() - t0));
    for (int c = 0; c < config.cyclesPerTick(); ++c) {
      const auto h0 = Clock::now();
      controller.hal().cycle();
      hal_us.push_back(us(Clock::now() - h0));
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - wall0).count();
  const Pct pt = percentiles(tick_us), ph = percentiles(hal_us);
  std::printf("loop tick (generator + command shaping + modes + telemetry)  p50 %7.2f us  p99 %7.2f us  max %7.2f us  (n=%d)\n",
              pt.p50, pt.p99, pt.max, ticks);
  std::printf("HAL cycle, MuJoCo SIL (2 physics steps @1 kHz + motor PD + gantry)  p50 %7.1f us  p99 %7.1f us  max %7.1f us\n",
              ph.p50, ph.p99, ph.max);
  std::printf("SIL real-time factor (lockstep): %.2f  (%.1f s simulated in %.2f s wall)\n", seconds / wall, seconds, wall);
  std::printf("deadline budget: loop 10000 us, HAL 2000 us; final mode %d, fault %d\n",
              static_cast<int>(controller.mode()), static_cast<int>(controller.fault()));
  return 0;
}
