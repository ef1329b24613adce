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
#include "pmg/controller/controller_app.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/clips/clip_io.hpp"

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
      const pmg::Command u = script.at(std::fmod(k * 0.01, script.duration()));
      const pmg::VelocityCommand ud{u.vx, u.vy, u.wz};
      const pmg::PostureCommand us_{u.pitch, u.roll, u.height.value_or(config.robot.standing_base_height)};
      const auto t0 = Clock::now();
      gen.step(ud, us_, 0.01);
      t.push_back(us(Clock::now() - t0));
    }
    const Pct p = percentiles(t);
    std::printf("generator step (29 joints, 3 dynamic clips)  p50 %7.2f us  p99 %7.2f us  max %7.2f us  (n=100000)\n",
                p.p50, p.p99, p.max);
  }
  // 2. Loop tick and HAL cycle inside a lockstep SIL run, through the product path: the same
  // ControllerApp (HAL stack with the supervisor, shaper, runner, telemetry) pmg_controller runs.
  config.makeOffline();
  pmg::ControllerApp controller(config);
  pmg::CommandScript looped = script;
  while (looped.duration() < seconds) {  // repeat the script to cover the benchmark time
    for (const auto& seg : script.segments) {
      pmg::CommandSegment next = seg;
      next.start = looped.duration();
      looped.segments.push_back(next);
    }
  }
  const pmg::RunSummary s = controller.run(seconds, &looped, nullptr);
  std::printf("loop tick (shaper + generator + GCO + limiter + telemetry push)  p50 %7.2f us  p99 %7.2f us  max %7.2f us  (n=%lld)\n",
              1e6 * s.loop.runtime_p50, 1e6 * s.loop.runtime_p99, 1e6 * s.loop.runtime_max,
              static_cast<long long>(s.run.ticks));
  std::printf("HAL cycle, MuJoCo SIL + supervisor (2 physics steps @1 kHz + motor PD + gantry)  p50 %7.1f us  p99 %7.1f us  max %7.1f us\n",
              1e6 * s.hal.runtime_p50, 1e6 * s.hal.runtime_p99, 1e6 * s.hal.runtime_max);
  std::printf("SIL real-time factor (lockstep): %.2f  (%.1f s simulated in %.2f s wall)\n", s.run.real_time_factor,
              s.run.sim_time, s.run.wall_time);
  std::printf("deadline budget: loop 10000 us, HAL 2000 us; final mode %s, fault %s\n", pmg::toString(s.final_mode),
              pmg::toString(s.fault));
  return 0;
}
