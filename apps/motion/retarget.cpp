/// pmg_retarget: retargets one human mocap file onto the robot (ceres_keypoints_v1) and prints the
/// quality report; optionally writes per-frame keypoints (human-target and robot) as CSV for
/// scripts/motion_plot_retarget.py.
///
///   build/bin/pmg_retarget <file.txt|file.bvh|file.npz> [--robot config/robots/g1/g1.yaml]
///                          [--begin 0] [--end -1] (seconds) [--mirror] [--csv out.csv]
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/motion/amp_npz.hpp"
#include "pmg/motion/bvh.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/keypoint_retarget.hpp"

using namespace pmg;
using namespace pmg::motion;

namespace {

HumanMotion loadHuman(const std::string& path) {
  if (path.size() > 4 && path.substr(path.size() - 4) == ".bvh") return bvhToHuman(readBvh(path), 0.056444);
  if (path.size() > 4 && path.substr(path.size() - 4) == ".npz") return ampNpzToHuman(path);
  return deepMimicToHuman(readDeepMimicMotion(path));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Retarget human mocap onto the robot (Ceres over KDL chains) and report the match"};
  std::string input, robot_yaml = pmg::resolveData("config/robots/g1/g1.yaml").string(), csv;
  double begin_s = 0.0, end_s = -1.0;
  bool mirror = false;
  app.add_option("input", input, "DeepMimic .txt, CMU .bvh or Isaac Lab AMP .npz file")->required();
  app.add_option("--robot", robot_yaml, "robot config YAML")->capture_default_str();
  app.add_option("--begin", begin_s, "first second used");
  app.add_option("--end", end_s, "last second used (-1 = end of file)");
  app.add_flag("--mirror", mirror, "mirror left/right before retargeting");
  app.add_option("--csv", csv, "write per-frame human-target and robot keypoints (W, m) to this CSV");
  CLI11_PARSE(app, argc, argv);
  try {
    const RobotConfig robot = loadRobotConfig(robot_yaml);
    const KinematicModel model(robot);
    HumanMotion human = loadHuman(input);
    const int b = static_cast<int>(std::lround(begin_s * human.fps));
    const int e = end_s < 0 ? human.numFrames() : std::min(human.numFrames(), static_cast<int>(std::lround(end_s * human.fps)) + 1);
    human = human.slice(b, e);
    if (mirror) human = human.mirrored();
    const RetargetResult res = retargetKeypoints(human, model);
    const RetargetStats st = retargetStats(res, robot, 0, res.motion.numFrames());
    std::printf("%s\n", fmt::format("{}: {} frames @ {:.1f} Hz, scale {:.3f}\n"
                                    "  keypoint error: mean {:.3f} m, max {:.3f} m\n"
                                    "  joint-limit violations: {}\n"
                                    "  foot skating during contact: mean {:.1f} mm, max {:.1f} mm per stance ({} stances)\n"
                                    "  ground penetration: max {:.1f} mm\n"
                                    "  solve time: {:.1f} ms per frame",
                                    input, res.motion.numFrames(), human.fps, res.scale, st.keypoint_error_mean,
                                    st.keypoint_error_max, st.joint_limit_violations, st.skate_mean_mm, st.skate_max_mm,
                                    st.stances, st.penetration_max_mm, st.solve_ms_per_frame)
                            .c_str());
    if (!csv.empty()) writeRetargetCsv(res, csv, 0, res.motion.numFrames());
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "pmg_retarget: %s\n", ex.what());
    return 1;
  }
  return 0;
}
