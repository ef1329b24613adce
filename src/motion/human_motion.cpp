#include "pmg/motion/human_motion.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg::motion {

const char* keypointName(Keypoint k) {
  static const char* kNames[kNumKeypoints] = {"pelvis",        "left_hip",       "left_knee",   "left_ankle",
                                              "left_toe",      "right_hip",      "right_knee",  "right_ankle",
                                              "right_toe",     "left_shoulder",  "left_elbow",  "left_wrist",
                                              "right_shoulder", "right_elbow",   "right_wrist"};
  const int i = static_cast<int>(k);
  return i >= 0 && i < static_cast<int>(kNumKeypoints) ? kNames[i] : "unknown";
}

namespace {
double meanChain(const HumanMotion& m, Keypoint a0, Keypoint b0, Keypoint c0, Keypoint a1, Keypoint b1, Keypoint c1) {
  if (m.frames.empty()) return 0.0;
  double sum = 0.0;
  for (const HumanFrame& f : m.frames) {
    auto p = [&](Keypoint k) { return f.p_WK[static_cast<std::size_t>(k)]; };
    sum += (p(b0) - p(a0)).norm() + (p(c0) - p(b0)).norm() + (p(b1) - p(a1)).norm() + (p(c1) - p(b1)).norm();
  }
  return sum / (2.0 * static_cast<double>(m.frames.size()));
}
}  // namespace

double HumanMotion::legLength() const {
  return meanChain(*this, Keypoint::kLeftHip, Keypoint::kLeftKnee, Keypoint::kLeftAnkle, Keypoint::kRightHip,
                   Keypoint::kRightKnee, Keypoint::kRightAnkle);
}

double HumanMotion::armLength() const {
  return meanChain(*this, Keypoint::kLeftShoulder, Keypoint::kLeftElbow, Keypoint::kLeftWrist, Keypoint::kRightShoulder,
                   Keypoint::kRightElbow, Keypoint::kRightWrist);
}

HumanMotion HumanMotion::mirrored() const {
  HumanMotion out = *this;
  const Eigen::Matrix3d S = Eigen::Vector3d(1, -1, 1).asDiagonal();
  auto refl = [&](const Eigen::Quaterniond& q) { return Eigen::Quaterniond(S * q.toRotationMatrix() * S); };
  const std::pair<Keypoint, Keypoint> swaps[] = {
      {Keypoint::kLeftHip, Keypoint::kRightHip},           {Keypoint::kLeftKnee, Keypoint::kRightKnee},
      {Keypoint::kLeftAnkle, Keypoint::kRightAnkle},       {Keypoint::kLeftToe, Keypoint::kRightToe},
      {Keypoint::kLeftShoulder, Keypoint::kRightShoulder}, {Keypoint::kLeftElbow, Keypoint::kRightElbow},
      {Keypoint::kLeftWrist, Keypoint::kRightWrist}};
  for (HumanFrame& f : out.frames) {
    for (auto& p : f.p_WK) p = S * p;
    for (const auto& [a, b] : swaps) std::swap(f.p_WK[static_cast<std::size_t>(a)], f.p_WK[static_cast<std::size_t>(b)]);
    f.R_WPelvis = refl(f.R_WPelvis);
    f.R_WTorso = refl(f.R_WTorso);
    const Eigen::Quaterniond l = refl(f.R_WFoot[0]), r = refl(f.R_WFoot[1]);
    f.R_WFoot = {r, l};
  }
  return out;
}

HumanMotion HumanMotion::slice(int begin, int end) const {
  if (begin < 0 || end > numFrames() || begin >= end)
    throw std::out_of_range(fmt::format("HumanMotion::slice({}, {}): expected 0 <= begin < end <= {} ({})", begin, end,
                                        numFrames(), source_file));
  HumanMotion out = *this;
  out.frames.assign(frames.begin() + begin, frames.begin() + end);
  return out;
}

void putOnGround(HumanMotion& motion) {
  if (motion.frames.empty()) return;
  std::vector<double> low;
  low.reserve(motion.frames.size());
  for (const HumanFrame& f : motion.frames) {
    auto z = [&](Keypoint k) { return f.p_WK[static_cast<std::size_t>(k)].z(); };
    low.push_back(std::min({z(Keypoint::kLeftAnkle), z(Keypoint::kLeftToe), z(Keypoint::kRightAnkle), z(Keypoint::kRightToe)}));
  }
  const std::size_t i = low.size() / 20;
  std::nth_element(low.begin(), low.begin() + static_cast<std::ptrdiff_t>(i), low.end());
  const double ground = low[i] - motion.ankle_height;
  for (HumanFrame& f : motion.frames)
    for (auto& p : f.p_WK) p.z() -= ground;
}

}  // namespace pmg::motion
