/// pmg_make_clips: builds the shipped PMG clip set for the Unitree G1 from real mocap, in one
/// command, reproducibly (same input → byte-identical files).
///
///   build/bin/pmg_make_clips [--data data/motions] [--robot config/robots/g1/g1.yaml]
///                            [--out config/clips/g1] [--samples 64]
///
/// Prints one report line per clip (frames used, T, x̄, contacts, clamped joint samples).
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/motion/clip_io.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/joint_angle_map.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

const char* kDeepMimicLicense = "MIT (DeepMimic, Copyright (c) 2018 Xue Bin Peng)";

/// One clip to cut from a DeepMimic file.
struct DeepMimicClipSpec {
  std::string name;
  std::string file;           ///< relative to the data root
  CommandAxis axis;
  bool whole_file_cycle;      ///< the file is exactly one closed cycle (Loop: wrap)
  double search_begin_s = 0;  ///< otherwise: window searched for two anchor events [s]
  double search_end_s = 0;
  Foot anchor = Foot::kLeft;
  ContactEvent event = ContactEvent::kLiftoff;
  std::string notes;
};

int countClamped(const RobotMotion& m, int begin, int end) {
  int count = 0;
  for (int k = begin; k <= end; ++k)
    for (Eigen::Index j = 0; j < m.clamp_excess.cols(); ++j) count += m.clamp_excess(k, j) > 1e-9 ? 1 : 0;
  return count;
}

std::string clampedJoints(const RobotMotion& m, const RobotConfig& robot, int begin, int end) {
  std::string out;
  for (Eigen::Index j = 0; j < m.clamp_excess.cols(); ++j) {
    const double mx = m.clamp_excess.block(begin, j, end - begin + 1, 1).maxCoeff();
    if (mx > 1e-9) out += fmt::format("{}{} (max {:.3f} rad)", out.empty() ? "" : ", ", robot.joints[static_cast<std::size_t>(j)].name, mx);
  }
  return out.empty() ? "none" : out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Build the PMG clip set for the G1 from mocap (joint_angle_map_v1 retargeting)"};
  std::string data_root = "data/motions";
  std::string robot_yaml = "config/robots/g1/g1.yaml";
  std::string out_dir = "config/clips/g1";
  int samples = 96;
  app.add_option("--data", data_root, "mocap data root (holds deepmimic/)");
  app.add_option("--robot", robot_yaml, "robot config YAML");
  app.add_option("--out", out_dir, "output directory for the clip files");
  app.add_option("--samples", samples, "phase samples per dynamic clip")->check(CLI::Range(8, 4096));
  CLI11_PARSE(app, argc, argv);

  try {
    const RobotConfig robot = loadRobotConfig(robot_yaml);
    const KinematicModel model(robot);
    const std::vector<DeepMimicClipSpec> specs = {
        {"walk_forward", "deepmimic/humanoid3d_walk.txt", CommandAxis::kForward, true, 0, 0, Foot::kLeft,
         ContactEvent::kLiftoff, "whole file = one closed gait cycle (Loop: wrap)"},
        {"turn_left", "deepmimic/humanoid3d_long_walk3.txt", CommandAxis::kYaw, false, 1.8, 3.4, Foot::kLeft,
         ContactEvent::kLiftoff, "pivot turn to the left, cycle between two left-foot liftoffs in t = 1.8-3.4 s"},
    };
    for (const DeepMimicClipSpec& spec : specs) {
      const DeepMimicMotion dm = readDeepMimicMotion(data_root + "/" + spec.file);
      RobotMotion rm = retargetJointAngleMap(dm, model);
      rm.source_file = spec.file;
      // Contacts from the human skeleton (the joint-angle map does not preserve foot clearance).
      rm.p_WS = deepMimicSoleTracks(dm, robotLegLength(model) / kDeepMimicLegLength);
      const ContactSequence contacts = detectContacts(rm);
      CycleWindow window;
      if (spec.whole_file_cycle) {
        window = {0, rm.numFrames() - 1};
      } else {
        window = findGaitCycle(contacts, spec.anchor, spec.event, static_cast<int>(spec.search_begin_s * rm.fps),
                               static_cast<int>(spec.search_end_s * rm.fps));
      }
      DynamicClipOptions opt;
      opt.name = spec.name;
      opt.axis = spec.axis;
      opt.num_samples = samples;
      DynamicClip clip = buildDynamicClip(rm, contacts, window, robot, opt);
      clip.meta.license = kDeepMimicLicense;
      clip.meta.provenance = "mocap";
      clip.meta.retargeting = "joint_angle_map_v1";
      const int clamped = countClamped(rm, window.begin, window.end);
      clip.meta.notes = fmt::format("{}; phase 0 = left-foot touchdown; contacts: sole height < 0.02 m and speed < 0.6 m/s "
                                    "(DeepMimic skeleton forward kinematics, scaled to the G1); clamped to joint limits: {}",
                                    spec.notes, clampedJoints(rm, robot, window.begin, window.end));
      validateClip(clip, robot, spec.name);
      const std::string path = out_dir + "/" + spec.name + ".yaml";
      writeClip(clip, path);
      std::printf("%s\n", fmt::format("{:<14} {:>38} frames [{}, {}) @ {:.0f} Hz  T = {:.3f} s  x̄ = {:.3f} ({} {:+d})  "
                                      "contact L mu={:.3f} sigma={:.3f}  R mu={:.3f} sigma={:.3f}  clamped samples: {}  -> {}",
                                      spec.name, spec.file, window.begin, window.end, rm.fps, clip.period, clip.nominal_scale,
                                      toString(clip.axis), clip.direction, clip.contact[0].mu, clip.contact[0].sigma,
                                      clip.contact[1].mu, clip.contact[1].sigma, clamped, path)
                              .c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_make_clips: %s\n", e.what());
    return 1;
  }
  return 0;
}
