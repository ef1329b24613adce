#include "pmg/clips/clip_validation.hpp"

#include <cmath>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "pmg/common/kinematics.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg {
namespace {

/// Longest period accepted [s]: a gait cycle of 10 s is not a walk (the shipped ones are ~1.3 s).
constexpr double kMaxPeriod = 10.0;
constexpr double kMaxImpliedAmplitude = 3.0;  // implied_motion.amplitude: the generator extrapolates a clip at most 3x

[[noreturn]] void invalid(const std::string& where, const std::string& field, const std::string& what) {
  throw ClipFormatError(where + ": " + field + ": " + what);
}

/// "robot 'unitree_g1' (config/robots/g1/g1.yaml)" or "the joint space" when it has no source.
std::string describe(const GeneratorJointSpace& js) {
  return js.source.empty() ? std::string("the joint space") : "robot config " + js.source;
}

void checkFinite(const Eigen::MatrixXd& m, const std::string& where, const char* field) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j)
      if (!std::isfinite(m(i, j))) invalid(where, fmt::format("{}[{}][{}]", field, i, j), "expected a finite number");
}

void checkJoints(const Eigen::MatrixXd& q, const ClipMetadata& meta, const GeneratorJointSpace& js,
                 const std::string& where, const ClipValidationOptions& options) {
  const std::size_t n = js.joint_names.size();
  if (static_cast<std::size_t>(q.cols()) != n)
    invalid(where, "q", fmt::format("has {} columns: expected {} (joints of {})", q.cols(), n, describe(js)));
  if (js.lower.size() != q.cols() || js.upper.size() != q.cols())
    throw std::invalid_argument(fmt::format("validateClip({}): the joint space has {} names but {}/{} limits", where, n,
                                            js.lower.size(), js.upper.size()));
  if (!meta.joint_names.empty() || options.require_joint_names) {
    if (meta.joint_names.size() != n)
      invalid(where, "joint_names", fmt::format("has {} names: expected {} (joints of {})", meta.joint_names.size(), n,
                                                describe(js)));
    if (options.check_joint_names) {
      for (std::size_t j = 0; j < n; ++j)
        if (meta.joint_names[j] != js.joint_names[j])
          invalid(where, fmt::format("joint_names[{}]", j),
                  fmt::format("= '{}': expected '{}' (joint order of {})", meta.joint_names[j], js.joint_names[j],
                              describe(js)));
    }
  }
  checkFinite(q, where, "q");
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    for (Eigen::Index j = 0; j < q.cols(); ++j) {
      const double v = q(i, j);
      if (v < js.lower[j] - options.limit_tolerance || v > js.upper[j] + options.limit_tolerance)
        invalid(where, fmt::format("q[{}][{}]", i, j),
                fmt::format("= {:.6f}: expected within joint limits [{}, {}] of {}", v, js.lower[j], js.upper[j],
                            js.joint_names[static_cast<std::size_t>(j)]));
    }
  }
}

void checkMetadata(const ClipMetadata& meta, const std::string& where) {
  if (meta.format_version != kClipFormatVersion)
    invalid(where, "format_version", fmt::format("= {}: expected {}", meta.format_version, kClipFormatVersion));
  if (meta.frame_begin < 0 || meta.frame_end < meta.frame_begin)
    invalid(where, "metadata.frame_begin/frame_end",
            fmt::format("= {}/{}: expected 0 <= frame_begin <= frame_end", meta.frame_begin, meta.frame_end));
  if (!(meta.source_fps >= 0.0) || !std::isfinite(meta.source_fps))
    invalid(where, "metadata.source_fps", fmt::format("= {}: expected finite >= 0 [Hz]", meta.source_fps));
  static const std::set<std::string> kProvenance = {"mocap", "mocap_mirrored", "mocap_time_reversed", "synthesized"};
  if (kProvenance.count(meta.provenance) == 0)
    invalid(where, "metadata.provenance",
            "= '" + meta.provenance + "': expected one of mocap, mocap_mirrored, mocap_time_reversed, synthesized");
}

/// A clip names joint @p clip_name where the robot config has another one. If the config's joint is
/// not a joint of its URDF, the config (or the URDF) is what is wrong: KinematicModel's check says
/// so, naming the config, the joint and the URDF. Otherwise the clip does not fit the robot.
void checkConfigAgainstUrdf(const RobotConfig& robot, const std::string& where, std::size_t j,
                            const std::string& clip_name) {
  std::error_code ec;
  if (robot.urdf_path.empty() || !std::filesystem::is_regular_file(robot.urdf_path, ec)) return;
  try {
    const KinematicModel model(robot);
  } catch (const ConfigError& e) {
    throw ConfigError(fmt::format("{} (the robot config does not match its URDF; clip {} is not at fault: its "
                                  "joint_names[{}] = '{}')",
                                  e.what(), where, j, clip_name));
  }
}

template <class Clip>
void validateAgainstRobot(const Clip& clip, const RobotConfig& robot, const std::string& where,
                          const ClipValidationOptions& options) {
  if (options.check_joint_names && clip.meta.joint_names.size() == robot.numJoints()) {
    for (std::size_t j = 0; j < robot.numJoints(); ++j)
      if (clip.meta.joint_names[j] != robot.joints[j].name) {
        checkConfigAgainstUrdf(robot, where, j, clip.meta.joint_names[j]);
        break;
      }
  }
  validateClip(clip, generatorJointSpace(robot), where, options);
}

}  // namespace

void ClipValidationOptions::validate() const {
  if (!(limit_tolerance >= 0.0) || !std::isfinite(limit_tolerance))
    throw ClipFormatError(fmt::format("ClipValidationOptions.limit_tolerance = {}: expected finite >= 0", limit_tolerance));
}

std::string toString(CommandAxis axis) {
  switch (axis) {
    case CommandAxis::kForward: return "forward";
    case CommandAxis::kLateral: return "lateral";
    case CommandAxis::kYaw: return "yaw";
  }
  return "unknown";
}

std::string toString(PostureAxis axis) {
  switch (axis) {
    case PostureAxis::kPitch: return "pitch";
    case PostureAxis::kRoll: return "roll";
    case PostureAxis::kHeight: return "height";
  }
  return "unknown";
}

void validateClip(const DynamicClip& clip, const GeneratorJointSpace& joints, const std::string& where,
                  const ClipValidationOptions& options) {
  options.validate();
  checkMetadata(clip.meta, where);
  const Eigen::Index N = clip.q.rows();
  if (N < 2) invalid(where, "q", fmt::format("has {} rows: expected >= 2 phase samples", N));
  checkJoints(clip.q, clip.meta, joints, where, options);
  if (clip.qd.rows() != N || clip.qd.cols() != clip.q.cols())
    invalid(where, "qd", fmt::format("is {}x{}: expected {}x{} (same shape as q)", clip.qd.rows(), clip.qd.cols(), N, clip.q.cols()));
  if (clip.v_base.rows() != N || clip.v_base.cols() != 3)
    invalid(where, "v_base", fmt::format("is {}x{}: expected {}x3", clip.v_base.rows(), clip.v_base.cols(), N));
  if (clip.omega_base.rows() != N || clip.omega_base.cols() != 3)
    invalid(where, "omega_base", fmt::format("is {}x{}: expected {}x3", clip.omega_base.rows(), clip.omega_base.cols(), N));
  if (clip.base_height.size() != N)
    invalid(where, "base_height", fmt::format("has {} entries: expected {}", clip.base_height.size(), N));
  checkFinite(clip.qd, where, "qd");
  checkFinite(clip.v_base, where, "v_base");
  checkFinite(clip.omega_base, where, "omega_base");
  for (Eigen::Index i = 0; i < N; ++i)
    if (!(clip.base_height(i) > 0.0) || !std::isfinite(clip.base_height(i)))
      invalid(where, fmt::format("base_height[{}]", i), fmt::format("= {}: expected finite > 0 [m]", clip.base_height(i)));
  if (!(clip.period > 0.0 && clip.period < kMaxPeriod))
    invalid(where, "period", fmt::format("= {}: expected T in (0, {}) [s]", clip.period, kMaxPeriod));
  if (!(clip.nominal_scale > 0.0) || !std::isfinite(clip.nominal_scale))
    invalid(where, "nominal_scale", fmt::format("= {}: expected x̄ > 0 [m/s or rad/s]", clip.nominal_scale));
  if (clip.direction != 1 && clip.direction != -1)
    invalid(where, "direction", fmt::format("= {}: expected +1 or -1", clip.direction));
  if (!clip.implied.empty()) {
    const ImpliedMotionTable& t = clip.implied;
    const Eigen::Index K = t.amplitude.size();
    if (K < 2) invalid(where, "implied_motion.amplitude", fmt::format("has {} entries: expected >= 2", K));
    if (t.velocity.rows() != K || t.velocity.cols() != 3)
      invalid(where, "implied_motion.velocity", fmt::format("is {}x{}: expected {}x3", t.velocity.rows(), t.velocity.cols(), K));
    checkFinite(t.amplitude, where, "implied_motion.amplitude");
    checkFinite(t.velocity, where, "implied_motion.velocity");
    if (t.amplitude(0) != 0.0)
      invalid(where, "implied_motion.amplitude[0]", fmt::format("= {}: expected 0 (the standing pose)", t.amplitude(0)));
    for (Eigen::Index i = 1; i < K; ++i) {
      if (!(t.amplitude(i) > t.amplitude(i - 1)) || t.amplitude(i) > kMaxImpliedAmplitude)
        invalid(where, fmt::format("implied_motion.amplitude[{}]", i),
                fmt::format("= {}: expected strictly increasing, <= {}", t.amplitude(i), kMaxImpliedAmplitude));
      // The generator inverts the clip's own axis: it must grow with the amplitude in the clip's direction.
      const double own = clip.direction * t.velocity(i, static_cast<Eigen::Index>(clip.axis));
      const double prev = clip.direction * t.velocity(i - 1, static_cast<Eigen::Index>(clip.axis));
      if (!(own > prev))
        invalid(where, fmt::format("implied_motion.velocity[{}][{}]", i, static_cast<int>(clip.axis)),
                fmt::format("= {}: expected the clip's own axis (direction {:+d}) to grow strictly with the amplitude "
                            "(previous {})", t.velocity(i, static_cast<Eigen::Index>(clip.axis)), clip.direction,
                            t.velocity(i - 1, static_cast<Eigen::Index>(clip.axis))));
    }
    if (t.velocity.row(0).cwiseAbs().maxCoeff() > 1e-6)
      invalid(where, "implied_motion.velocity[0]", "expected (0, 0, 0): the standing pose implies no motion");
  }
  const char* feet[kNumFeet] = {"contact.left", "contact.right"};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const FootContact& c = clip.contact[f];
    if (!(c.mu >= 0.0 && c.mu < 1.0))
      invalid(where, std::string(feet[f]) + ".mu", fmt::format("= {}: expected in [0, 1) (phase units)", c.mu));
    if (!(c.sigma >= 0.0 && c.sigma <= 0.5))
      invalid(where, std::string(feet[f]) + ".sigma", fmt::format("= {}: expected in [0, 0.5] (phase units)", c.sigma));
  }
}

void validateClip(const StaticClip& clip, const GeneratorJointSpace& joints, const std::string& where,
                  const ClipValidationOptions& options) {
  options.validate();
  checkMetadata(clip.meta, where);
  const Eigen::Index K = clip.q.rows();
  if (K < 2) invalid(where, "q", fmt::format("has {} rows: expected >= 2 samples", K));
  if (clip.values.size() != K)
    invalid(where, "values", fmt::format("has {} entries: expected {} (rows of q)", clip.values.size(), K));
  for (Eigen::Index i = 0; i < K; ++i) {
    if (!std::isfinite(clip.values(i))) invalid(where, fmt::format("values[{}]", i), "expected a finite number");
    if (i > 0 && !(clip.values(i) > clip.values(i - 1)))
      invalid(where, fmt::format("values[{}]", i),
              fmt::format("= {}: expected strictly increasing (previous {})", clip.values(i), clip.values(i - 1)));
  }
  checkJoints(clip.q, clip.meta, joints, where, options);
  if (!std::isfinite(clip.neutral) || clip.neutral < clip.values(0) || clip.neutral > clip.values(K - 1))
    invalid(where, "neutral", fmt::format("= {}: expected within [{}, {}] (the values range)", clip.neutral,
                                          clip.values(0), clip.values(K - 1)));
}

void validateClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options) {
  validateAgainstRobot(clip, robot, where, options);
}

void validateClip(const StaticClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options) {
  validateAgainstRobot(clip, robot, where, options);
}

void validateLibraryAxes(const ClipLibrary& library, const std::string& where) {
  const auto& d = library.dynamic_clips;
  for (std::size_t j = 1; j < d.size(); ++j)
    for (std::size_t i = 0; i < j; ++i)
      if (d[i].axis == d[j].axis && (d[i].direction < 0) == (d[j].direction < 0))
        invalid(where, "axis/direction",
                fmt::format("clip '{}' ({} {:+d}) duplicates clip '{}': expected at most one dynamic clip per (axis, "
                            "direction)",
                            d[j].name, toString(d[j].axis), d[j].direction, d[i].name));
  const auto& s = library.static_clips;
  for (std::size_t j = 1; j < s.size(); ++j)
    for (std::size_t i = 0; i < j; ++i)
      if (s[i].axis == s[j].axis)
        invalid(where, "axis",
                fmt::format("clip '{}' ({}) duplicates clip '{}': expected at most one static clip per posture axis",
                            s[j].name, toString(s[j].axis), s[i].name));
}

}  // namespace pmg
