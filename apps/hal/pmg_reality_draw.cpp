// pmg_reality_draw: draws a random plausible "reality" for pmg_sil --reality (issue 15): which leg
// joints carry which actuator effect and how strong, which encoders have a zero offset, whether the
// torso is heavier than modelled. Ranges: include/pmg/hal/reality.hpp (drawReality) and
// docs/calibration.md "Drawn realities". Tests draw realities and never read them back into the
// tools under test.
//
//   pmg_reality_draw --seed 7 --out reality.yaml [--robot config/robots/g1/g1.yaml] [--joints 5]
//                    [--zero-offsets 3] [--no-links]
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/reality.hpp"

int main(int argc, char** argv) {
  CLI::App app{"pmg_reality_draw: a random plausible hidden truth for pmg_sil --reality"};
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string out;
  std::uint64_t seed = 0;
  bool no_links = false;
  pmg::hal::RealityDrawOptions opt;
  app.add_option("--seed", seed, "random seed (the same seed draws the same reality)")->required();
  app.add_option("--out", out, "reality file to write (YAML)")->required();
  app.add_option("--robot", robot_path, "robot config YAML (legs = its first 12 joints)")
      ->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--joints", opt.joints, "leg joints with an actuator effect (0 = draw 4..6)")->check(CLI::Range(0, 12));
  app.add_option("--zero-offsets", opt.zero_offsets, "leg joints with a zero offset (-1 = draw 2..4)")
      ->check(CLI::Range(-1, 12));
  app.add_flag("--no-links", no_links, "no link mass error");
  CLI11_PARSE(app, argc, argv);
  opt.links = !no_links;
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const pmg::hal::Reality r = pmg::hal::drawReality(robot, seed, opt);
    pmg::hal::writeReality(out, r,
                           "pmg_reality_draw --seed " + std::to_string(seed) +
                               ": a hidden truth for pmg_sil --reality (docs/calibration.md)\n"
                               "Do not read this file into a calibration tool: it is what they must find.");
    std::printf("pmg_reality_draw: seed %llu: %zu joints with an actuator effect, %zu zero offsets, %zu link errors -> %s\n",
                static_cast<unsigned long long>(seed), r.joints.size(), r.zero_offsets.size(), r.links.size(),
                out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_reality_draw: %s\n", e.what());
    return 1;
  }
}
