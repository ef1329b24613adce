// pmg_shaper_vectors: runs the controller's command shaper (include/pmg/controller/commands.hpp,
// pmg::CommandShaper) over a fixed goal schedule and writes the goals and the shaped commands as JSON,
// so that the training environment's port of the shaper (training/pmg_train/g1_env.py,
// EnvConfig.command_envelopes: the velocity slews, the crouched and bent velocity envelopes and the
// walking height floor) is proven equal to it (test/policy: training_command_envelopes_equal_cpp).
//
//   build/bin/pmg_shaper_vectors --controller config/controller/g1_sil_policy.yaml --out shaper.json
//
// The schedule walks upright, crouches while walking to below the walking height floor, stops there
// (the floor's hold, then the descent), walks bent and bent-crouched, backward, and stands; every goal
// lies inside the config's `commands:` ranges, so the shaper's clamping never acts. The goal is fresh
// every tick (never stale). The standing height is the squat clip's neutral, as pmg::ControllerApp sets it. Output: {"dt", "limits": {the `commands:` keys the port reads, and
// standing_height [m]}, "ticks": [{"goal": [6], "shaped": [6]}]}, (v_x, v_y, w, pitch, roll, height)
// in SI units (m/s, rad/s, rad, m), heading frame.
#include <array>
#include <cstdio>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "pmg/clips/clip_io.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace {
struct Segment {
  int ticks;
  double vx, vy, wz, pitch, roll, height;
};
// (ticks, v_x [m/s], v_y [m/s], w [rad/s], pitch [rad], roll [rad], height [m])
constexpr Segment kSchedule[] = {
    {150, 0.8, 0.0, 0.0, 0.0, 0.0, 0.78},   {300, 0.8, 0.3, 0.0, 0.0, 0.0, 0.62},  {250, 0.5, 0.2, 0.6, 0.0, 0.1, 0.62},
    {350, 0.0, 0.0, 0.0, 0.0, 0.0, 0.62},   {250, 1.0, 0.0, 0.0, 0.4, 0.0, 0.78},  {250, 0.6, 0.0, 0.5, 0.3, 0.0, 0.66},
    {250, -0.5, 0.0, 0.0, 0.0, 0.0, 0.70},  {200, 0.0, -0.4, -0.8, 0.0, -0.2, 0.64}, {250, 0.0, 0.0, 0.0, 0.0, 0.0, 0.78},
};
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The controller's command shaper over a fixed goal schedule, as JSON (the training port's reference)"};
  std::string controller_path = pmg::resolveData("config/controller/g1_sil_policy.yaml").string(), out = "shaper.json";
  app.add_option("--controller", controller_path, "controller config whose `commands:` limits shape the goals")
      ->check(CLI::ExistingFile);
  app.add_option("--out", out, "JSON file to write");
  CLI11_PARSE(app, argc, argv);
  try {
    pmg::ControllerConfig config = pmg::loadControllerConfig(controller_path);
    // The standing height ("no height command") as pmg::ControllerApp sets it: the squat clip's neutral.
    const pmg::GeneratorModel model(pmg::loadClipLibrary(config.clips_dir, config.robot),
                                    pmg::generatorJointSpace(config.robot), config.generator);
    if (const pmg::StaticClip* squat = model.staticClip(pmg::PostureAxis::kHeight))
      config.commands.standing_height = squat->neutral;
    const pmg::CommandLimits& l = config.commands;
    pmg::CommandShaper shaper(l);
    const double dt = 1.0 / config.loop_rate_hz;
    nlohmann::ordered_json doc;
    doc["dt"] = dt;
    doc["limits"] = {{"standing_height", l.standing_height},
                     {"max_velocity", l.max_velocity},
                     {"max_acceleration", l.max_acceleration},
                     {"posture_rate", l.posture_rate},
                     {"height_rate", l.height_rate},
                     {"crouched_height", l.crouched_height},
                     {"crouched_max_velocity", l.crouched_max_velocity},
                     {"bent_pitch", l.bent_pitch},
                     {"bent_max_velocity", l.bent_max_velocity},
                     {"walking_min_height", l.walking_min_height},
                     {"walking_min_height_hold_s", l.walking_min_height_hold_s}};
    auto& ticks = doc["ticks"] = nlohmann::ordered_json::array();
    double now = 0.0;
    for (const Segment& s : kSchedule) {
      for (int k = 0; k < s.ticks; ++k) {
        pmg::CommandSample sample;
        sample.command = {s.vx, s.vy, s.wz, s.pitch, s.roll, s.height};
        sample.velocity_time = now;
        sample.posture_time = now;
        shaper.update(sample, now, dt);
        ticks.push_back({{"goal", std::array<double, 6>{s.vx, s.vy, s.wz, s.pitch, s.roll, s.height}},
                         {"shaped", shaper.vector()}});
        now += dt;
      }
    }
    std::ofstream f(out);
    f << doc.dump() << "\n";
    if (!f) {
      std::fprintf(stderr, "pmg_shaper_vectors: cannot write %s\n", out.c_str());
      return 1;
    }
    std::printf("wrote %s\n", out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_shaper_vectors: %s\n", e.what());
    return 1;
  }
}
