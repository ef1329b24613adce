// pmg_task_scene: composes a task scene (tables, a towel, a box: include/pmg/hal/task_scene.hpp,
// config/tasks/*.yaml) with the robot's MJCF for one trial, for issue 14's teleoperated tasks in
// the SIL: writes OUT/scene.xml (the robot's MJCF plus the scene's bodies, for MuJoCo or
// pmg_render_log) and OUT/robot.yaml (the robot config loading it), and prints where each object
// starts in the world frame.
//
//   pmg_task_scene --scene config/tasks/wipe_scene.yaml [--seed 3] [--robot config/robots/g1/g1.yaml] --out DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/task_scene.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  CLI::App app{"pmg_task_scene: a task scene (tables and objects) composed with the robot's MJCF for one trial"};
  std::string scene_path, out_dir;
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::uint64_t seed = 0;
  bool nominal = false;
  app.add_option("--scene", scene_path, "task scene YAML (config/tasks/*.yaml)")->required()->check(CLI::ExistingFile);
  app.add_option("--seed", seed, "trial seed: draws the objects' randomised poses (the same seed, the same scene)");
  app.add_flag("--nominal", nominal, "the objects' nominal poses instead of a drawn trial");
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--out", out_dir, "folder for scene.xml and robot.yaml (created)")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const pmg::TaskScene scene = pmg::loadTaskScene(scene_path);
    const pmg::TaskScene trial = nominal ? scene : pmg::drawTaskTrial(scene, seed);
    fs::create_directories(out_dir);
    const std::string xml = (fs::absolute(out_dir) / "scene.xml").string();
    const pmg::RobotConfig composed = pmg::robotWithTaskScene(robot, trial, xml);
    // The robot config with its model paths absolute and the MJCF replaced by the composed one.
    const std::string yaml = pmg::robotConfigTextWithModelPaths(composed);
    const std::string robot_out = (fs::absolute(out_dir) / "robot.yaml").string();
    {
      std::ofstream out(robot_out);
      if (!out) throw pmg::ConfigError(robot_out + ": cannot write");
      out << "# " << robot_path << " with the task scene " << scene_path
          << (nominal ? std::string(" (nominal poses)") : " (trial seed " + std::to_string(seed) + ")")
          << " (pmg_task_scene)\n"
          << yaml;
    }
    // Check that it loads, and report where the objects start (world frame W).
    const pmg::RobotConfig check = pmg::loadRobotConfig(robot_out);
    pmg::MujocoBackendOptions o;
    o.gantry.enabled = false;
    pmg::MujocoBackend sim(check, o);
    for (const auto& obj : trial.objects) {
      const pmg::TaskObjectState s = pmg::taskObjectState(sim.model(), sim.data(), obj.name);
      fmt::print("{}: on {} at ({:.3f}, {:.3f}, {:.3f}) m in the world, yaw {:.3f} rad\n", obj.name, obj.on, s.p_W.x(),
                 s.p_W.y(), s.p_W.z(), trial.table(obj.on).yaw + obj.yaw);
    }
    fmt::print("wrote {} and {}\n", xml, robot_out);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_task_scene: %s\n", e.what());
    return 1;
  }
}
