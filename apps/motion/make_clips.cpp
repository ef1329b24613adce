/// pmg_make_clips: builds the shipped PMG clip set for the Unitree G1 from real human mocap in one
/// command, reproducibly (same input → byte-identical files):
///
///   build/bin/pmg_make_clips [--data data/motions] [--robot config/robots/g1/g1.yaml]
///                            [--out config/clips/g1] [--csv-dir DIR]
///
/// The defaults are the folders of pmg's data directory (pmg::dataDir(); in a build tree, the
/// checkout's data/ and config/), so the default run regenerates the shipped set in place.
///
/// Every clip: import (DeepMimic .txt / CMU .bvh) → optimisation-based retargeting
/// (ceres_keypoints_v1) → contact segmentation and one gait cycle (dynamic) or a monotone posture
/// sweep (static) → clip file. Mirrored clips use the robot's mirror map (pmg::mirrorClip). The lean
/// (roll) template has no capture: it is synthesized on the robot model (posture_ik_v1,
/// pmg::motion::synthesizeLean). Writes
/// <out>/report.md (per-clip retargeting quality) and, with --csv-dir, per-clip keypoint CSVs for
/// scripts/motion_plot_retarget.py.
///
/// All or nothing: every mocap file is read before any retargeting, every clip is built and
/// validated in memory, then the clip files and report.md are written to temporary files in <out>
/// and renamed onto their names only when all were written. A failure (a truncated BVH, a clip
/// that does not validate, a full disk) leaves <out> as it was.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/common/data_paths.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/clips/clip_transforms.hpp"
#include "pmg/clips/clip_validation.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/implied_motion.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/motion/bvh.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/keypoint_retarget.hpp"
#include "pmg/motion/posture_synthesis.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

constexpr double kCmuUnit = 0.056444;  // CMU BVH units → metres
const char* kDeepMimicLicense = "MIT (DeepMimic, Copyright (c) 2018 Xue Bin Peng)";
const char* kCmuLicense =
    "CMU Graphics Lab Motion Capture Database terms (mocap.cs.cmu.edu: free for all uses, no resale of the data); "
    "cgspeed BVH conversion adds no restrictions";

/// A mocap source: file (relative to the data root) and the seconds retargeted.
struct Source {
  std::string file;
  double begin_s = 0.0;
  double end_s = -1.0;  ///< −1 = end of file
};

struct DynamicSpec {
  std::string name;
  Source source;
  CommandAxis axis = CommandAxis::kForward;
  bool whole_file_cycle = false;  ///< the retargeted range is exactly one closed cycle
  double search_begin_s = 0.0;    ///< else: cycle between two `event`s of `anchor` in this window
  double search_end_s = 0.0;      ///<   (seconds relative to source.begin_s)
  Foot anchor = Foot::kLeft;
  ContactEvent event = ContactEvent::kTouchdown;
  std::string notes;
  /// Hand-set contact spans, frames of the source FILE (converted to the retargeted range).
  std::vector<ContactOverride> file_overrides;
  double swing_blend_s = 0.0;                          ///< KeypointRetargetOptions::swing_blend
  CycleClosing closing = CycleClosing::kLinearRamp;   ///< DynamicClipOptions::closing
};

struct MirrorSpec {
  std::string source_clip;
  std::string name;
};

struct StaticSpec {
  std::string name;
  Source source;
  PostureAxis axis = PostureAxis::kHeight;
  std::string notes;
};

/// Posture of every row of a static clip with the feet flat (PostureProbe), relative to the neutral
/// row: the coupling the template adds to the other posture axes, and its balance.
struct PostureCheck {
  double torso_pitch = 0.0;    ///< max |torso pitch − neutral| [rad]
  double torso_roll = 0.0;     ///< max |torso roll − neutral| [rad]
  double pelvis_pitch = 0.0;   ///< max |pelvis pitch − neutral| [rad]
  double height = 0.0;         ///< max |pelvis height − neutral| [m]
  double com_margin = 0.0;     ///< min centre-of-mass margin in the support polygon [m]
};

PostureCheck checkPosture(const StaticClip& clip, PostureProbe& probe) {
  Eigen::Index neutral_row = 0;
  (clip.values.array() - clip.neutral).abs().minCoeff(&neutral_row);
  const FlatFootPosture n = probe.measure(clip.q.row(neutral_row).transpose());
  PostureCheck c;
  c.com_margin = n.com_margin;
  for (Eigen::Index i = 0; i < clip.q.rows(); ++i) {
    const FlatFootPosture m = probe.measure(clip.q.row(i).transpose());
    c.torso_pitch = std::max(c.torso_pitch, std::abs(m.torso_pitch - n.torso_pitch));
    c.torso_roll = std::max(c.torso_roll, std::abs(m.torso_roll - n.torso_roll));
    c.pelvis_pitch = std::max(c.pelvis_pitch, std::abs(m.pelvis_pitch - n.pelvis_pitch));
    c.height = std::max(c.height, std::abs(m.pelvis_height - n.pelvis_height));
    c.com_margin = std::min(c.com_margin, m.com_margin);
  }
  return c;
}

/// Relabels a pitch template by the torso pitch its rows give where the generator plays them: the
/// row's offset from the neutral row added to the standing pose @p q_stand (PMG eq. 10), measured with
/// the feet flat, minus the standing pose's own. The capture's values are absolute (its upright
/// frame already leans 0.065 rad), so a command p used to bend the reference by p − 0.065 only.
/// Returns the largest change of a value [rad]. @throws std::runtime_error if the measured values
/// are not strictly increasing (the clip's rows must stay ordered by their command).
double relabelOnStandingPose(StaticClip& clip, PostureProbe& probe, const Eigen::VectorXd& q_stand) {
  Eigen::Index neutral_row = 0;
  (clip.values.array() - clip.neutral).abs().minCoeff(&neutral_row);
  const double stand = probe.measure(q_stand).torso_pitch;
  const Eigen::VectorXd q0 = clip.q.row(neutral_row).transpose();
  Eigen::VectorXd v(clip.values.size());
  for (Eigen::Index i = 0; i < clip.q.rows(); ++i) {
    const Eigen::VectorXd q = q_stand + (clip.q.row(i).transpose() - q0);
    v(i) = probe.measure(q).torso_pitch - stand;
    if (i > 0 && !(v(i) > v(i - 1)))
      throw std::runtime_error(fmt::format("static clip '{}': torso pitch on the standing pose not increasing at row {} ({:.4f} after {:.4f})",
                                           clip.name, i, v(i), v(i - 1)));
  }
  const double change = (v - clip.values).cwiseAbs().maxCoeff();
  clip.neutral = v(neutral_row);
  clip.values = v;
  return change;
}

std::string postureLine(const StaticClip& clip, const PostureCheck& c) {
  return fmt::format("| {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.1f} | {:.1f} |\n", clip.name, toString(clip.axis), c.torso_pitch,
                     c.torso_roll, c.pelvis_pitch, 1000.0 * c.height, 1000.0 * c.com_margin);
}

/// What the clip set needs beyond the clips: the stance-implied motion table of every dynamic
/// clip and the consistency map of the set (command-consistent blending, docs/generator.md).
struct ImpliedContext {
  GeneratorJointSpace joints;
  std::shared_ptr<const pmg::gco::LegModel> legs;
  ClipLibrary written;  ///< every clip written, with its table (for the consistency map)
};

/// The values a clip file holds (6 decimals): the tables and the map are computed from what a
/// reader gets, so `pmg_clip_implied --check` on the written folder finds them current.
Eigen::MatrixXd asWritten(const Eigen::MatrixXd& m) { return (m.array() * 1e6).round() / 1e6; }
double asWritten(double x) { return std::round(x * 1e6) / 1e6; }

/// The one place where a clip becomes file text: a dynamic clip gets its implied_motion table.
std::string clipText(const DynamicClip& clip, ImpliedContext& ctx) {
  DynamicClip c = clip;
  c.q = asWritten(c.q);
  c.qd = asWritten(c.qd);
  c.v_base = asWritten(c.v_base);
  c.omega_base = asWritten(c.omega_base);
  c.base_height = asWritten(c.base_height);
  c.period = asWritten(c.period);
  c.nominal_scale = asWritten(c.nominal_scale);
  for (auto& f : c.contact) f = {asWritten(f.mu), asWritten(f.sigma)};
  c.implied = pmg::gco::computeImpliedMotion(c, ctx.joints, ctx.legs, pmg::gco::defaultImpliedAmplitudes());
  c.implied.velocity = asWritten(c.implied.velocity);
  ctx.written.dynamic_clips.push_back(c);
  return clipToYaml(c);
}
std::string clipText(const StaticClip& clip, ImpliedContext& ctx) {
  StaticClip c = clip;
  c.q = asWritten(c.q);
  c.values = asWritten(c.values);
  c.neutral = asWritten(c.neutral);
  ctx.written.static_clips.push_back(c);
  return clipToYaml(clip);
}

std::string license(const std::string& file) { return file.rfind("cmu_bvh/", 0) == 0 ? kCmuLicense : kDeepMimicLicense; }

/// Reads and imports one mocap file (whole). @throws what the readers throw (file, line, field).
HumanMotion importFile(const std::string& root, const std::string& file) {
  const std::string path = root + "/" + file;
  return file.size() > 4 && file.substr(file.size() - 4) == ".bvh" ? bvhToHuman(readBvh(path), kCmuUnit)
                                                                   : deepMimicToHuman(readDeepMimicMotion(path));
}

/// The seconds of @p s cut from its imported file @p whole.
HumanMotion load(const HumanMotion& whole, const Source& s) {
  HumanMotion h = whole;
  const int b = static_cast<int>(std::lround(s.begin_s * h.fps));
  const int e = s.end_s < 0 ? h.numFrames() : std::min(h.numFrames(), static_cast<int>(std::lround(s.end_s * h.fps)) + 1);
  h = h.slice(b, e);
  h.source_file = s.file;
  return h;
}

std::string statsLine(const RetargetStats& st) {
  return fmt::format("keypoint error mean {:.3f} m / max {:.3f} m; joint-limit violations {}; foot skating {:.1f} mm mean / "
                     "{:.1f} mm max per stance ({} stances); ground penetration {:.1f} mm",
                     st.keypoint_error_mean, st.keypoint_error_max, st.joint_limit_violations, st.skate_mean_mm, st.skate_max_mm,
                     st.stances, st.penetration_max_mm);
}

namespace fs = std::filesystem;

/// Writes every (path, text) to a temporary file beside its path, then renames them all onto their
/// paths: either every file is replaced or, if one cannot be written, none is (temporary files
/// removed). @throws std::runtime_error naming the file.
void writeAllOrNothing(const std::vector<std::pair<fs::path, std::string>>& files) {
  std::vector<fs::path> temps;
  std::error_code ec;
  const auto removeTemps = [&] {
    for (const fs::path& t : temps) fs::remove(t, ec);
  };
  for (const auto& [path, text] : files) {
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    const fs::path tmp = path.parent_path() / ("." + path.filename().string() + ".tmp");
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (f) temps.push_back(tmp);
    f << text;
    f.flush();
    if (!f) {
      removeTemps();
      throw std::runtime_error(path.string() + ": cannot write (" + tmp.string() + "); no file of the set was changed");
    }
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    fs::rename(temps[i], files[i].first, ec);
    if (ec) {
      removeTemps();
      throw std::runtime_error(files[i].first.string() + ": cannot rename " + temps[i].string() + " onto it: " + ec.message() +
                               fmt::format(" ({} of {} files were replaced)", i, files.size()));
    }
  }
}

/// Creates @p dir if needed and checks that a file can be created in it.
/// @throws std::runtime_error naming the folder.
void checkOutputFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw std::runtime_error(dir + ": cannot create the output folder" + (ec ? ": " + ec.message() : ""));
  const fs::path probe = fs::path(dir) / ".pmg_make_clips.probe";
  if (!std::ofstream(probe, std::ios::binary | std::ios::trunc)) throw std::runtime_error(dir + ": cannot write into the output folder");
  fs::remove(probe, ec);
}

/// Sole tracks of a built clip (phase, height [m], speed [m/s], contact label per foot) as CSV.
void writeSoleTracks(const DynamicClip& clip, const KinematicModel& model, const std::string& path) {
  const ClipSoleTracks t = clipSoleTracks(clip, model);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << "phase,height_left,speed_left,contact_left,height_right,speed_right,contact_right,relative_speed\n";
  const Eigen::Index N = t.height.rows();
  for (Eigen::Index k = 0; k < N; ++k) {
    const double phi = static_cast<double>(k) / static_cast<double>(N);
    f << fmt::format("{:.6f}", phi);
    for (std::size_t ft = 0; ft < kNumFeet; ++ft) {
      const double d = std::abs(phi - clip.contact[ft].mu), dist = std::min(d, 1.0 - d);
      const bool c = dist < clip.contact[ft].sigma || clip.contact[ft].sigma >= 0.5;
      f << fmt::format(",{:.6f},{:.6f},{}", t.height(k, static_cast<Eigen::Index>(ft)), t.speed(k, static_cast<Eigen::Index>(ft)),
                       c ? 1 : 0);
    }
    f << fmt::format(",{:.6f}\n", t.relative_speed(k));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Build the PMG clip set for the G1 from human mocap (ceres_keypoints_v1 retargeting)"};
  std::string data_root = pmg::resolveData("data/motions").string();
  std::string robot_yaml = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string out_dir = pmg::resolveData("config/clips/g1").string(), csv_dir;
  app.add_option("--data", data_root, "mocap data root (holds deepmimic/ and cmu_bvh/)")->capture_default_str();
  app.add_option("--robot", robot_yaml, "robot config YAML")->capture_default_str();
  app.add_option("--out", out_dir, "output directory for the clip files and report.md (default: the shipped set)")
      ->capture_default_str();
  app.add_option("--csv-dir", csv_dir, "also write per-clip retargeting keypoint CSVs here");
  bool bend_on_standing_pose = false;
  app.add_flag("--bend-on-standing-pose", bend_on_standing_pose,
               "label the bend template's rows by the torso pitch they give added to the standing pose (feet flat), "
               "not by the capture's absolute torso pitch (docs/motion.md; not the shipped set)");
  std::string tracks_dir;
  app.add_option("--sole-tracks-dir", tracks_dir, "also write per-clip sole height/speed CSVs (phase, labels) here");
  pmg::motion::WalkingHeightOptions walking_height;
  walking_height.fraction = 0.0;
  app.add_option("--walking-height", walking_height.fraction,
                 "raise each walking template's pelvis by this share of its gap to the standing height, legs lengthened "
                 "by IK (0 = as captured, the shipped set; docs/motion.md \"Walking height\")")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--walking-height-min-knee", walking_height.min_knee,
                 "--walking-height: smallest knee flexion the raise may leave [rad]")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  bool symmetric_gaits = false;
  app.add_flag("--symmetric-gaits", symmetric_gaits,
               "average each captured forward/backward walk with its own mirror image half a cycle on, so that its left "
               "and right steps are mirror images (pmg::motion::symmetrizeGaitClip; not the shipped sets; docs/motion.md "
               "\"Symmetric gaits\")");
  CLI11_PARSE(app, argc, argv);

  // The clip set (built with push_back of named specs: GCC 12 warns falsely on nested brace
  // initialisation of aggregates holding strings).
  std::vector<DynamicSpec> dynamic_specs;
  auto dynamic = [&](const char* name, const char* file, double begin_s, double end_s, CommandAxis axis, bool whole,
                     double search_begin_s, double search_end_s, ContactEvent event, const char* notes) {
    DynamicSpec d;
    d.name = name;
    d.source.file = file;
    d.source.begin_s = begin_s;
    d.source.end_s = end_s;
    d.axis = axis;
    d.whole_file_cycle = whole;
    d.search_begin_s = search_begin_s;
    d.search_end_s = search_end_s;
    d.anchor = Foot::kLeft;
    d.event = event;
    d.notes = notes;
    dynamic_specs.push_back(d);
  };
  dynamic("walk_forward", "deepmimic/humanoid3d_walk.txt", 0.0, -1.0, CommandAxis::kForward, true, 0, 0, ContactEvent::kTouchdown,
          "DeepMimic walk: the file is one closed gait cycle (Loop: wrap)");
  // The cycle is cut with 0.1 s of standing at each end (double support 31 % of the cycle): with the
  // whole standing start (from t = 0.1 s) the template blends worse with walking (GCO stance height
  // error of (0.4 m/s, -0.3 rad/s) 4.4 mm instead of 3.2 mm) for x̄ 1.08 instead of 1.16 rad/s.
  dynamic("turn_left", "cmu_bvh/cmu_69_17_turn_in_place_left_excerpt_30fps.bvh", 0.2, 1.567, CommandAxis::kYaw, true, 0, 0,
          ContactEvent::kTouchdown,
          "CMU 69_17 turn in place to the left (one-shot, 93 deg), one cycle from standing (t = 0.2 s) to standing (t = 1.567 s) "
          "with one step of each foot; the left foot's pivot on the ground (ankle up 2 cm, turning 83 deg) is retargeted as a step "
          "(swing forced over file frames 9-23, targets raised by up to 0.03 m), the right step (frames 30-43) likewise raised "
          "0.03 m (its toe dragged); swing ends blended onto the stances over 0.15 s; cycle closed in swing (the last stance is "
          "3 cm wider and toed in 10 deg: the difference moves the landing instead of sliding the feet in double support)");
  {
    DynamicSpec& turn = dynamic_specs.back();
    for (const auto& [foot, begin, end] : {std::tuple{Foot::kLeft, 9, 24}, std::tuple{Foot::kRight, 30, 44}}) {
      ContactOverride o;
      o.foot = foot;
      o.begin = begin;
      o.end = end;
      o.contact = false;
      o.clearance = 0.03;
      turn.file_overrides.push_back(o);
    }
    turn.swing_blend_s = 0.15;
    turn.closing = CycleClosing::kInSwing;
  }
  dynamic("walk_lateral_left", "cmu_bvh/cmu_143_40_sidestep_left_excerpt.bvh", 0.0, -1.0, CommandAxis::kLateral, false, 0.0, 2.2,
          ContactEvent::kTouchdown, "CMU 143_40 crossover side-step to the left, cycle between two left-foot touchdowns");
  dynamic("walk_backward", "cmu_bvh/cmu_143_39_walk_backward_excerpt.bvh", 0.0, -1.0, CommandAxis::kForward, false, 0.0, 1.8,
          ContactEvent::kTouchdown, "CMU 143_39 walking backward, cycle between two left-foot touchdowns");
  std::vector<MirrorSpec> mirror_specs(2);
  mirror_specs[0].source_clip = "walk_lateral_left";
  mirror_specs[0].name = "walk_lateral_right";
  mirror_specs[1].source_clip = "turn_left";
  mirror_specs[1].name = "turn_right";
  std::vector<StaticSpec> static_specs;
  auto posture = [&](const char* name, const char* file, double begin_s, double end_s, PostureAxis axis, const char* notes) {
    StaticSpec st;
    st.name = name;
    st.source.file = file;
    st.source.begin_s = begin_s;
    st.source.end_s = end_s;
    st.axis = axis;
    st.notes = notes;
    static_specs.push_back(st);
  };
  posture("squat", "cmu_bvh/cmu_115_07_squat_excerpt.bvh", 0.0, 1.05, PostureAxis::kHeight,
          "CMU 115_07 squat (pick up a box bending the knees), standing to the bottom at t = 1.05 s");
  posture("bend", "cmu_bvh/cmu_115_01_bend_at_waist_excerpt.bvh", 0.0, 1.35, PostureAxis::kPitch,
          "CMU 115_01 forward bend at the waist (pick up a box), upright to trunk horizontal at t = 1.35 s");

  const RobotContactOptions robot_contacts;
  try {
    checkOutputFolder(out_dir);  // before minutes of work, not after
    const RobotConfig robot = loadRobotConfig(robot_yaml);
    const KinematicModel model(robot);
    ImpliedContext implied_ctx{generatorJointSpace(robot), pmg::gco::LegModel::fromRobotConfig(robot), {}};
    PostureProbe probe(model);  // static templates measured with the feet flat (posture_synthesis.hpp)
    // Arm joints: neither on a leg nor on the pelvis → torso_link chain (the waist).
    std::vector<int> arm_joints;
    {
      std::vector<int> body;
      for (const LimbChain& c : {model.leftLeg(), model.rightLeg(), model.chain(robot.base_link, "torso_link")})
        body.insert(body.end(), c.joint_index.begin(), c.joint_index.end());
      for (int j = 0; j < static_cast<int>(robot.numJoints()); ++j)
        if (std::find(body.begin(), body.end(), j) == body.end()) arm_joints.push_back(j);
    }
    std::string posture_report =
        "\nPosture templates measured on the robot with both feet flat (pmg::motion::PostureProbe: the pelvis tilt the legs\n"
        "imply, torso_link angles, MuJoCo centre of mass): largest change from the neutral row over the clip's range, and the\n"
        "smallest centre-of-mass margin inside the support polygon of the two soles (> 0: statically balanced).\n\n"
        "| clip | axis | torso pitch [rad] | torso roll [rad] | pelvis pitch [rad] | pelvis height [mm] | CoM margin [mm] |\n"
        "|---|---|---|---|---|---|---|\n";
    std::string report =
        "# G1 clip set: retargeting report\n\n"
        "Generated by `build/bin/pmg_make_clips` (do not edit). Retargeting: ceres_keypoints_v1 (docs/motion.md).\n"
        "Keypoint error: robot keypoints vs scaled human targets over the retargeted frames; skating: largest horizontal\n"
        "drift of the sole centre from its mean during each contact; penetration: deepest sole point below z = 0.\n\n"
        "| clip | kind | source | frames | T [s] | x̄ | contacts L (μ, σ) / R (μ, σ) | retargeting quality |\n"
        "|---|---|---|---|---|---|---|---|\n";
    // Read every mocap file first: a broken input fails here, before minutes of retargeting.
    std::map<std::string, HumanMotion> imported;
    for (const DynamicSpec& spec : dynamic_specs) imported.emplace(spec.source.file, importFile(data_root, spec.source.file));
    for (const StaticSpec& spec : static_specs) imported.emplace(spec.source.file, importFile(data_root, spec.source.file));
    std::vector<std::pair<fs::path, std::string>> outputs;  // written together at the end
    std::map<std::string, DynamicClip> built;
    for (const DynamicSpec& spec : dynamic_specs) {
      const HumanMotion human = load(imported.at(spec.source.file), spec.source);
      KeypointRetargetOptions rt_opt;
      rt_opt.level_pelvis = true;  // played with a level pelvis (clip format: no pelvis orientation)
      rt_opt.swing_blend = spec.swing_blend_s;
      const int first_frame = static_cast<int>(std::lround(spec.source.begin_s * human.fps));
      for (ContactOverride o : spec.file_overrides) {
        o.begin -= first_frame;
        o.end -= first_frame;
        rt_opt.contact_overrides.push_back(o);
      }
      const RetargetResult res = retargetKeypoints(human, model, rt_opt);
      RobotMotion rm = res.motion;
      rm.source_file = spec.source.file;
      CycleWindow window;
      if (spec.whole_file_cycle) {
        window = {0, rm.numFrames() - 1};
      } else {
        window = findGaitCycle(res.contacts, spec.anchor, spec.event, static_cast<int>(std::lround(spec.search_begin_s * rm.fps)),
                               static_cast<int>(std::lround(spec.search_end_s * rm.fps)));
      }
      DynamicClipOptions opt;
      opt.name = spec.name;
      opt.axis = spec.axis;
      opt.closing = spec.closing;
      opt.leg_joints = {model.leftLeg().joint_index, model.rightLeg().joint_index};
      DynamicClip clip = buildDynamicClip(rm, res.contacts, window, robot, opt);
      // Stance = the robot sole low and still as the generator plays the clip (the human labels
      // of the retargeting start stance while the robot sole is still up and moving).
      relabelContactsFromRobotFeet(clip, model, robot_contacts);
      std::string height_note;
      if (walking_height.fraction > 0.0) {
        const WalkingHeightReport wh = raiseWalkingHeight(clip, model, robot.defaultPose(), walking_height);
        height_note = fmt::format("; pelvis raised towards the standing height: mean {:.4f} -> {:.4f} m (standing {:.4f}, share "
                                  "{:.2f}, knee >= {:.2f} rad, smallest raise {:.4f} m)",
                                  wh.mean_height_before, wh.mean_height_after, wh.standing_height, walking_height.fraction,
                                  walking_height.min_knee, wh.min_raise);
        std::printf("%-20s walking height %.4f -> %.4f m (standing %.4f, smallest raise %.4f m)\n", clip.name.c_str(),
                    wh.mean_height_before, wh.mean_height_after, wh.standing_height, wh.min_raise);
      }
      if (symmetric_gaits && clip.axis == CommandAxis::kForward) {
        symmetrizeGaitClip(clip, robot);
        relabelContactsFromRobotFeet(clip, model, robot_contacts);
        height_note += "; left/right symmetrized (x(phi) <- (x(phi) + M x(phi + 1/2)) / 2), contacts relabelled from the robot soles";
        std::printf("%-20s symmetrized: contacts L (%.3f, %.3f) / R (%.3f, %.3f)\n", clip.name.c_str(), clip.contact[0].mu,
                    clip.contact[0].sigma, clip.contact[1].mu, clip.contact[1].sigma);
      }
      if (!tracks_dir.empty()) writeSoleTracks(clip, model, tracks_dir + "/" + spec.name + "_soles.csv");
      const int offset = static_cast<int>(std::lround(spec.source.begin_s * human.fps));
      clip.meta.frame_begin = window.begin + offset;
      clip.meta.frame_end = window.end + offset;
      clip.meta.license = license(spec.source.file);
      clip.meta.provenance = "mocap";
      clip.meta.retargeting = "ceres_keypoints_v1";
      const RetargetStats st = retargetStats(res, robot, window.begin, window.end + 1);
      clip.meta.notes = fmt::format("{}; scale {:.3f}; phase 0 = left-foot touchdown; contacts from the robot soles (level "
                                    "pelvis; touchdown < {} m above the lower sole, lift-off > {} m; double support only while the "
                                    "soles slide < {}/{} m/s against each other); {}",
                                    spec.notes, res.scale, robot_contacts.enter_height, robot_contacts.exit_height,
                                    robot_contacts.enter_relative_speed, robot_contacts.exit_relative_speed, statsLine(st)) +
                        height_note;
      validateClip(clip, robot, spec.name);
      outputs.emplace_back(fs::path(out_dir) / (spec.name + ".yaml"), clipText(clip, implied_ctx));
      if (!csv_dir.empty()) writeRetargetCsv(res, csv_dir + "/" + spec.name + ".csv", window.begin, window.end + 1);
      report += fmt::format("| {} | dynamic {} {:+d} | `{}` | [{}, {}) @ {:.0f} Hz | {:.3f} | {:.3f} | ({:.2f}, {:.2f}) / ({:.2f}, {:.2f}) | {} |\n",
                            clip.name, toString(clip.axis), clip.direction, spec.source.file, clip.meta.frame_begin,
                            clip.meta.frame_end, rm.fps, clip.period, clip.nominal_scale, clip.contact[0].mu, clip.contact[0].sigma,
                            clip.contact[1].mu, clip.contact[1].sigma, statsLine(st));
      std::printf("%-20s %s -> T %.3f s, x̄ %.3f (%s %+d), %.1f ms/frame\n", clip.name.c_str(), spec.source.file.c_str(), clip.period,
                  clip.nominal_scale, toString(clip.axis).c_str(), clip.direction, res.solve_ms_per_frame);
      built[clip.name] = clip;
    }
    for (const MirrorSpec& spec : mirror_specs) {
      const DynamicClip clip = mirrorClip(built.at(spec.source_clip), robot, spec.name);
      validateClip(clip, robot, spec.name);
      outputs.emplace_back(fs::path(out_dir) / (spec.name + ".yaml"), clipText(clip, implied_ctx));
      report += fmt::format("| {} | dynamic {} {:+d} | mirror of `{}` | - | {:.3f} | {:.3f} | ({:.2f}, {:.2f}) / ({:.2f}, {:.2f}) | as {} |\n",
                            clip.name, toString(clip.axis), clip.direction, spec.source_clip, clip.period, clip.nominal_scale,
                            clip.contact[0].mu, clip.contact[0].sigma, clip.contact[1].mu, clip.contact[1].sigma, spec.source_clip);
      std::printf("%-20s mirror of %s\n", clip.name.c_str(), spec.source_clip.c_str());
    }
    for (const StaticSpec& spec : static_specs) {
      const HumanMotion human = load(imported.at(spec.source.file), spec.source);
      // The height template is played with a level pelvis like the dynamic clips; the pitch
      // template needs the pelvis tilt (the waist pitch alone reaches 0.52 rad, the bend 1.31 rad).
      KeypointRetargetOptions rt_opt;
      rt_opt.level_pelvis = spec.axis == PostureAxis::kHeight;
      const RetargetResult res = retargetKeypoints(human, model, rt_opt);
      RobotMotion rm = res.motion;
      rm.source_file = spec.source.file;
      const Eigen::VectorXd values = postureValues(rm, model, spec.axis);
      // Sweep from the first frame to the extreme value (lowest pelvis / largest pitch or roll).
      Eigen::Index extreme = 0;
      if (spec.axis == PostureAxis::kHeight)
        values.minCoeff(&extreme);
      else
        values.maxCoeff(&extreme);
      StaticClipOptions opt;
      opt.name = spec.name;
      opt.axis = spec.axis;
      StaticClip clip = buildStaticClip(rm, values, 0, static_cast<int>(extreme), robot, opt);
      // A posture template moves both legs alike: average with its left/right mirror.
      symmetrizeStaticClip(clip, robot);
      // The height template shortens the legs without turning them about the hips; it keeps the
      // arms where they are (the capture reaches for a box) and the torso at the neutral pitch.
      std::string decoupling;
      if (spec.axis == PostureAxis::kHeight) {
        keepLegDirections(clip, model);
        const PostureCheck before = checkPosture(clip, probe);
        holdJointsAtNeutral(clip, arm_joints);
        const double residual = holdTorsoPitch(clip, probe);
        const PostureCheck after = checkPosture(clip, probe);
        decoupling = fmt::format(
            "; arms held at the neutral row and waist pitch set per row so that torso_link pitch with the feet flat stays at the "
            "neutral row's (max change {:.3f} -> {:.3f} rad, residual {:.1e}; centre-of-mass margin {:.0f} -> {:.0f} mm)",
            before.torso_pitch, after.torso_pitch, residual, 1000.0 * before.com_margin, 1000.0 * after.com_margin);
        std::printf("%-20s torso pitch coupling %.3f -> %.3f rad, CoM margin %.0f -> %.0f mm\n", spec.name.c_str(), before.torso_pitch,
                    after.torso_pitch, 1000.0 * before.com_margin, 1000.0 * after.com_margin);
      }
      if (spec.axis == PostureAxis::kPitch && bend_on_standing_pose) {
        const double n_before = clip.neutral;
        const double change = relabelOnStandingPose(clip, probe, robot.defaultPose());
        decoupling += fmt::format(
            "; values relabelled by the torso pitch each row gives added to the standing pose (feet flat), relative to the "
            "standing pose's (capture's upright row {:.3f} -> {:.3f} rad; largest change {:.3f} rad)", n_before, clip.neutral, change);
        std::printf("%-20s values on the standing pose: neutral %.3f -> %.3f rad, largest change %.3f rad\n", spec.name.c_str(),
                    n_before, clip.neutral, change);
      }
      const int offset = static_cast<int>(std::lround(spec.source.begin_s * human.fps));
      clip.meta.frame_begin += offset;
      clip.meta.frame_end += offset;
      clip.meta.license = license(spec.source.file);
      clip.meta.provenance = "mocap";
      clip.meta.retargeting = "ceres_keypoints_v1";
      const RetargetStats st = retargetStats(res, robot, 0, static_cast<int>(extreme) + 1);
      clip.meta.notes = fmt::format("{}; scale {:.3f}; values = {} of the retargeted robot; joints averaged with their left/right mirror (symmetric posture){}; {}", spec.notes, res.scale,
                                    spec.axis == PostureAxis::kHeight ? "pelvis height [m]" : "torso_link pitch [rad]", decoupling, statsLine(st));
      validateClip(clip, robot, spec.name);
      outputs.emplace_back(fs::path(out_dir) / (spec.name + ".yaml"), clipText(clip, implied_ctx));
      if (!csv_dir.empty()) writeRetargetCsv(res, csv_dir + "/" + spec.name + ".csv", 0, static_cast<int>(extreme) + 1);
      report += fmt::format("| {} | static {} | `{}` | [{}, {}) @ {:.0f} Hz | - | values {:.3f} … {:.3f}, neutral {:.3f} | - | {} |\n",
                            clip.name, toString(clip.axis), spec.source.file, clip.meta.frame_begin, clip.meta.frame_end, rm.fps,
                            clip.values(0), clip.values(clip.values.size() - 1), clip.neutral, statsLine(st));
      std::printf("%-20s %s -> %s %.3f .. %.3f (neutral %.3f)\n", clip.name.c_str(), spec.source.file.c_str(),
                  toString(clip.axis).c_str(), clip.values(0), clip.values(clip.values.size() - 1), clip.neutral);
      posture_report += postureLine(clip, checkPosture(clip, probe));
    }
    {
      // The lean (roll) template: no side-bend capture is shipped, so it is synthesized on the robot.
      const LeanOptions lean_opt;
      LeanSynthesis lean = synthesizeLean(probe, lean_opt);
      StaticClip& clip = lean.clip;
      clip.meta.license = "none needed (synthesized from the robot model, no capture data)";
      clip.meta.notes = fmt::format(
          "synthesized (no side-bend capture is shipped): per torso roll target in (0, {:.2f}] rad, Ceres over KDL and MuJoCo "
          "kinematics solves the pelvis position (pelvis level) and the leg and waist joints (arms at the default pose) with both "
          "soles held at the default pose's (planted, flat), torso pitch and heading held, the centre of mass held over the same "
          "point of the feet, and the smallest change from the default pose (pmg::motion::synthesizeLean); the waist rolls the "
          "torso and the legs shift the pelvis against the lean as a parallelogram (hip roll / ankle roll, equal leg lengths); "
          "negative rows are the left/right mirror; values = torso_link roll [rad] measured with the feet flat; sole error "
          "{:.1e} m, sole tilt {:.1e} rad, centre-of-mass shift {:.1e} m, roll error {:.1e} rad, pelvis height change {:.1f} mm",
          lean_opt.max_roll, lean.max_foot_error, lean.max_foot_tilt, lean.max_com_shift, lean.max_roll_error,
          1000.0 * lean.max_height_change);
      validateClip(clip, robot, clip.name);
      outputs.emplace_back(fs::path(out_dir) / (clip.name + ".yaml"), clipText(clip, implied_ctx));
      report += fmt::format("| {} | static {} | synthesized on the robot (posture_ik_v1) | - | - | values {:.3f} … {:.3f}, neutral {:.3f} | - | "
                            "soles planted: position error {:.2f} mm, tilt {:.1e} rad; centre of mass held within {:.2f} mm; "
                            "roll error {:.1e} rad; joint-limit violations 0 (bounded solve) |\n",
                            clip.name, toString(clip.axis), clip.values(0), clip.values(clip.values.size() - 1), clip.neutral,
                            1000.0 * lean.max_foot_error, lean.max_foot_tilt, 1000.0 * lean.max_com_shift, lean.max_roll_error);
      std::printf("%-20s synthesized -> %s %.3f .. %.3f (neutral %.3f)\n", clip.name.c_str(), toString(clip.axis).c_str(),
                  clip.values(0), clip.values(clip.values.size() - 1), clip.neutral);
      posture_report += postureLine(clip, checkPosture(clip, probe));
    }
    report += posture_report;
    report +=
        "\nNot in the set: a captured side lean. The shared mocap has no side-bend capture (CMU 132_35/36 \"walk leaning\"\n"
        "were located but not transcribed), so `lean` is synthesized on the robot model (provenance `synthesized`,\n"
        "docs/motion.md). The pitch template `bend` starts at the capture's upright 0.065 rad: leaning back (pitch < 0.065)\n"
        "has no template.\n";
    double worst_residual = 0.0;
    const ConsistencyMap map = pmg::gco::computeConsistencyMap(implied_ctx.written, robot, {}, &worst_residual);
    outputs.emplace_back(fs::path(out_dir) / kConsistencyMapFile,
                         consistencyMapToYaml(map, fmt::format("written by pmg_make_clips (pmg::gco::computeConsistencyMap); "
                                                               "worst residual after the fixed point and Gauss-Newton {:.4f}", worst_residual)));
    std::printf("%-20s %ld grid points, largest |correction| %.3f, worst residual %.4f\n", kConsistencyMapFile,
                static_cast<long>(map.delta.rows()), map.delta.cwiseAbs().maxCoeff(), worst_residual);
    outputs.emplace_back(fs::path(out_dir) / "report.md", report);
    writeAllOrNothing(outputs);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_make_clips: %s\n", e.what());
    return 1;
  }
  return 0;
}
