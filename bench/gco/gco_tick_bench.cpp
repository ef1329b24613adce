// pmg_gco_tick_bench: tail latency of the complete generator + GCO tick (issue 4 target:
// p99 <= 150 us on the 2-core development machine). Sweeps the command over the grid of
// velocities and yaw rates so every blend and contact pattern is visited, times each tick with
// steady_clock and prints p50 / p90 / p99 / p99.9 / max for the GCO solve and the whole tick.
// Robot config and clips default to the G1 of pmg's data directory: build/bin/pmg_gco_tick_bench [--ticks N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {
double pct(std::vector<double>& v, double p) {
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}
}  // namespace

int main(int argc, char** argv) {
  using namespace pmg;
  using namespace pmg::gco;
  CLI::App app{"Generator + GCO tick latency"};
  int ticks = 200000;
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string clips_dir = pmg::resolveData("config/clips/g1").string();
  app.add_option("--ticks", ticks, "number of timed ticks")->check(CLI::Range(1000, 10000000));
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--clips", clips_dir, "clip directory")->check(CLI::ExistingDirectory)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const RobotConfig robot = loadRobotConfig(robot_path);
    const GeneratorJointSpace js = pmg::generatorJointSpace(robot);
    auto model = std::make_shared<const GeneratorModel>(loadClipLibrary(clips_dir, robot), js);
    auto legs = LegModel::fromRobotConfig(robot);
    MotionGenerator gen(model);
    Gco gco(legs, GcoOptions{});
    const LegJointIndex idx = legs->jointIndices(js.joint_names);
    GcoInput in;
    GcoResult res;
    std::vector<double> tick_us(static_cast<std::size_t>(ticks)), gco_us(static_cast<std::size_t>(ticks));
    const double vx[] = {-0.6, -0.3, 0.0, 0.3, 0.6, 0.9}, wz[] = {-0.6, 0.0, 0.6};
    const int per_command = 500;  // 5 s per command, then the next grid point
    for (int k = 0; k < ticks; ++k) {
      const int c = (k / per_command) % 18;
      const VelocityCommand u{vx[c / 3], 0.0, wz[c % 3]};
      const PostureCommand s{};
      const auto t0 = std::chrono::steady_clock::now();
      gen.step(u, s, 0.01);
      fillFromGenerator(gen.output(), idx, u, s, &in);
      const auto t1 = std::chrono::steady_clock::now();
      gco.solve(in, &res);
      const auto t2 = std::chrono::steady_clock::now();
      tick_us[static_cast<std::size_t>(k)] = std::chrono::duration<double, std::micro>(t2 - t0).count();
      gco_us[static_cast<std::size_t>(k)] = std::chrono::duration<double, std::micro>(t2 - t1).count();
    }
    std::printf("%d ticks (18 commands, 5 s each, cycled); solver failures %llu, jump-limited ticks %llu\n", ticks,
                static_cast<unsigned long long>(gco.counters().solver_failures),
                static_cast<unsigned long long>(gco.counters().jump_limited));
    std::printf("%-16s %8s %8s %8s %8s %9s\n", "[us]", "p50", "p90", "p99", "p99.9", "max");
    for (auto* v : {&gco_us, &tick_us}) {
      std::printf("%-16s %8.2f %8.2f %8.2f %8.2f %9.1f\n", v == &gco_us ? "GCO solve" : "generator+GCO", pct(*v, 50),
                  pct(*v, 90), pct(*v, 99), pct(*v, 99.9), pct(*v, 100));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_gco_tick_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
