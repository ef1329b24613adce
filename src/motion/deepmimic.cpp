#include "pmg/motion/deepmimic.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

namespace pmg::motion {
namespace {

constexpr int kNumbersPerFrame = 44;

[[noreturn]] void fail(const std::string& file, const YAML::Node& node, const std::string& what) {
  std::string where = file;
  if (node.IsDefined() && node.Mark().line >= 0) where += ":" + std::to_string(node.Mark().line + 1);
  throw std::runtime_error(where + ": " + what);
}

Eigen::Quaterniond quat(const std::vector<double>& v, int at, const std::string& file, const YAML::Node& node,
                        int frame, const char* field) {
  Eigen::Quaterniond q(v[at], v[at + 1], v[at + 2], v[at + 3]);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-2)
    fail(file, node, fmt::format("Frames[{}] {} quaternion (numbers {}..{}) has norm {:.4f}: expected a unit quaternion", frame,
                                 field, at, at + 3, norm));
  q.normalize();
  return q;
}

}  // namespace

Eigen::Matrix3d deepMimicToZUp() {
  Eigen::Matrix3d C;
  C << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return C;
}

HumanMotion deepMimicToHuman(const DeepMimicMotion& motion) {
  const Eigen::Matrix3d C = deepMimicToZUp();
  HumanMotion h;
  h.source_file = motion.source_file;
  h.format = "deepmimic";
  h.fps = motion.fps;
  h.ankle_height = 0.05;
  h.frames.resize(motion.frames.size());
  auto W = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return C * p; };
  auto WR = [&](const Eigen::Matrix3d& R) { return Eigen::Quaterniond(C * R * C.transpose()); };
  auto Rz = [](double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); };
  for (std::size_t k = 0; k < motion.frames.size(); ++k) {
    const DeepMimicFrame& f = motion.frames[k];
    HumanFrame& o = h.frames[k];
    auto set = [&](Keypoint kp, const Eigen::Vector3d& p_M) { o.p_WK[static_cast<std::size_t>(kp)] = W(p_M); };
    const Eigen::Matrix3d R0 = f.R_MR.toRotationMatrix();
    set(Keypoint::kPelvis, f.p_MR);
    const Eigen::Vector3d p_chest = f.p_MR + R0 * Eigen::Vector3d(0, 0.236151, 0);
    const Eigen::Matrix3d R_chest = R0 * f.chest.toRotationMatrix();
    o.R_WPelvis = WR(R0);
    o.R_WTorso = WR(R_chest);
    for (int side = 0; side < 2; ++side) {
      const bool left = side == 0;
      const double zs = left ? -1.0 : 1.0;  // DeepMimic z = character's right
      const Eigen::Vector3d p_hip = f.p_MR + R0 * Eigen::Vector3d(0, 0, zs * 0.084887);
      const Eigen::Matrix3d R_hip = R0 * (left ? f.left_hip : f.right_hip).toRotationMatrix();
      const Eigen::Vector3d p_knee = p_hip + R_hip * Eigen::Vector3d(0, -0.421546, 0);
      const Eigen::Matrix3d R_knee = R_hip * Rz(left ? f.left_knee : f.right_knee);
      const Eigen::Vector3d p_ankle = p_knee + R_knee * Eigen::Vector3d(0, -0.409870, 0);
      const Eigen::Matrix3d R_ankle = R_knee * (left ? f.left_ankle : f.right_ankle).toRotationMatrix();
      const Eigen::Vector3d p_sh = p_chest + R_chest * Eigen::Vector3d(-0.02405, 0.2435, zs * 0.18311);
      const Eigen::Matrix3d R_sh = R_chest * (left ? f.left_shoulder : f.right_shoulder).toRotationMatrix();
      const Eigen::Vector3d p_el = p_sh + R_sh * Eigen::Vector3d(0, -0.274788, 0);
      const Eigen::Matrix3d R_el = R_sh * Rz(left ? f.left_elbow : f.right_elbow);
      const Eigen::Vector3d p_wr = p_el + R_el * Eigen::Vector3d(0, -0.258947, 0);
      set(left ? Keypoint::kLeftHip : Keypoint::kRightHip, p_hip);
      set(left ? Keypoint::kLeftKnee : Keypoint::kRightKnee, p_knee);
      set(left ? Keypoint::kLeftAnkle : Keypoint::kRightAnkle, p_ankle);
      set(left ? Keypoint::kLeftShoulder : Keypoint::kRightShoulder, p_sh);
      set(left ? Keypoint::kLeftElbow : Keypoint::kRightElbow, p_el);
      set(left ? Keypoint::kLeftWrist : Keypoint::kRightWrist, p_wr);
      o.R_WFoot[static_cast<std::size_t>(side)] = WR(R_ankle);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftToe : Keypoint::kRightToe)] =
          W(p_ankle) + o.R_WFoot[static_cast<std::size_t>(side)].toRotationMatrix() * Eigen::Vector3d(kToeOffset, 0, 0);
    }
  }
  putOnGround(h);
  return h;
}

DeepMimicMotion readDeepMimicMotion(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open DeepMimic motion file");
  } catch (const YAML::ParserException& e) {
    throw std::runtime_error(fmt::format("{}:{}: JSON syntax error: {}", path, e.mark.line + 1, e.msg));
  }
  if (!root.IsMap()) throw std::runtime_error(path + ": expected a JSON object with keys Loop and Frames");
  DeepMimicMotion m;
  m.source_file = path;
  const YAML::Node loop = root["Loop"];
  if (loop.IsDefined()) {
    if (!loop.IsScalar()) fail(path, loop, "Loop: expected \"wrap\" or \"none\"");
    const std::string s = loop.Scalar();
    if (s != "wrap" && s != "none") fail(path, loop, "Loop = '" + s + "': expected \"wrap\" or \"none\"");
    m.loop_wrap = s == "wrap";
  }
  const YAML::Node frames = root["Frames"];
  if (!frames.IsDefined() || !frames.IsSequence()) fail(path, root, "Frames: missing or not a list of frames");
  if (frames.size() < 2) fail(path, frames, fmt::format("Frames has {} frames: expected >= 2", frames.size()));
  std::vector<double> v(kNumbersPerFrame);
  m.frames.reserve(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const YAML::Node fr = frames[i];
    const int fi = static_cast<int>(i);
    if (!fr.IsSequence() || fr.size() != kNumbersPerFrame)
      fail(path, fr, fmt::format("Frames[{}]: expected a list of {} numbers, got {}", fi, kNumbersPerFrame,
                                 fr.IsSequence() ? fr.size() : 0));
    for (int k = 0; k < kNumbersPerFrame; ++k) {
      try {
        v[k] = fr[k].as<double>();
      } catch (const YAML::Exception&) {
        fail(path, fr[k], fmt::format("Frames[{}][{}] = '{}': not a number", fi, k, fr[k].Scalar()));
      }
      if (!std::isfinite(v[k])) fail(path, fr[k], fmt::format("Frames[{}][{}]: expected a finite number", fi, k));
    }
    DeepMimicFrame f;
    f.duration = v[0];
    f.p_MR = Eigen::Vector3d(v[1], v[2], v[3]);
    f.R_MR = quat(v, 4, path, fr, fi, "root");
    f.chest = quat(v, 8, path, fr, fi, "chest");
    f.neck = quat(v, 12, path, fr, fi, "neck");
    f.right_hip = quat(v, 16, path, fr, fi, "right_hip");
    f.right_knee = v[20];
    f.right_ankle = quat(v, 21, path, fr, fi, "right_ankle");
    f.right_shoulder = quat(v, 25, path, fr, fi, "right_shoulder");
    f.right_elbow = v[29];
    f.left_hip = quat(v, 30, path, fr, fi, "left_hip");
    f.left_knee = v[34];
    f.left_ankle = quat(v, 35, path, fr, fi, "left_ankle");
    f.left_shoulder = quat(v, 39, path, fr, fi, "left_shoulder");
    f.left_elbow = v[43];
    if (i == 0) {
      if (!(f.duration > 0.0)) fail(path, fr, fmt::format("Frames[0][0] (duration) = {}: expected > 0 [s]", f.duration));
      m.fps = 1.0 / f.duration;
    } else {
      const bool last = i + 1 == frames.size();
      const double d0 = m.frames.front().duration;
      if (!(last && f.duration == 0.0) && std::abs(f.duration - d0) > 1e-4)
        fail(path, fr, fmt::format("Frames[{}][0] (duration) = {}: expected {} (uniform frame rate)", fi, f.duration, d0));
    }
    m.frames.push_back(f);
  }
  return m;
}

}  // namespace pmg::motion
