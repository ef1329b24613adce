#include "pmg/clips/clip_transforms.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "pmg/generator/robot_joint_space.hpp"

namespace pmg {

Eigen::MatrixXd mirrorJoints(const Eigen::MatrixXd& q, const GeneratorJointSpace& joints) {
  const auto n = static_cast<Eigen::Index>(joints.joint_names.size());
  if (q.cols() != n || joints.mirror_index.size() != joints.joint_names.size() ||
      joints.mirror_sign.size() != joints.joint_names.size())
    throw std::invalid_argument(fmt::format("mirrorJoints: {} columns, joint space of {} joints with a mirror map of {}/{}",
                                            q.cols(), n, joints.mirror_index.size(), joints.mirror_sign.size()));
  Eigen::MatrixXd m(q.rows(), q.cols());
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto k = static_cast<std::size_t>(j);
    const int src = joints.mirror_index[k];
    if (src < 0 || src >= n) throw std::invalid_argument(fmt::format("mirrorJoints: mirror_index[{}] = {}: out of range", j, src));
    m.col(j) = static_cast<double>(joints.mirror_sign[k]) * q.col(src);
  }
  return m;
}

void rotateClipPhase(DynamicClip& clip, Eigen::Index shift) {
  const Eigen::Index N = clip.q.rows();
  if (N == 0) return;
  shift = ((shift % N) + N) % N;
  if (shift == 0) return;
  auto rotate = [&](Eigen::MatrixXd& x) {
    const Eigen::MatrixXd y = x;
    for (Eigen::Index k = 0; k < N; ++k) x.row(k) = y.row((k + shift) % N);
  };
  rotate(clip.q);
  rotate(clip.qd);
  rotate(clip.v_base);
  rotate(clip.omega_base);
  Eigen::MatrixXd hgt = clip.base_height;
  rotate(hgt);
  clip.base_height = hgt.col(0);
  const double dphi = static_cast<double>(shift) / static_cast<double>(N);
  for (auto& c : clip.contact) {
    c.mu -= dphi;
    c.mu -= std::floor(c.mu);
    if (c.mu >= 1.0) c.mu = 0.0;
  }
}

Eigen::Index alignPhaseOnLeftTouchdown(DynamicClip& clip) {
  const Eigen::Index N = clip.q.rows();
  if (N == 0) return 0;
  double start = clip.contact[static_cast<std::size_t>(Foot::kLeft)].mu - clip.contact[static_cast<std::size_t>(Foot::kLeft)].sigma;
  start -= std::floor(start);
  const Eigen::Index shift = static_cast<Eigen::Index>(std::lround(start * static_cast<double>(N))) % N;
  rotateClipPhase(clip, shift);
  return shift;
}

DynamicClip mirrorClip(const DynamicClip& clip, const GeneratorJointSpace& joints, const std::string& new_name) {
  if (clip.q.cols() != static_cast<Eigen::Index>(joints.joint_names.size()))
    throw std::invalid_argument(fmt::format("mirrorClip({}): clip has {} joints, the joint space {}", clip.name, clip.q.cols(),
                                            joints.joint_names.size()));
  DynamicClip m = clip;
  m.name = new_name;
  m.q = mirrorJoints(clip.q, joints);
  m.qd = mirrorJoints(clip.qd, joints);
  m.v_base.col(1) *= -1.0;
  m.omega_base.col(0) *= -1.0;
  m.omega_base.col(2) *= -1.0;
  if (!m.implied.empty()) {
    m.implied.velocity.col(1) *= -1.0;  // v_y and ω change sign under the left/right mirror
    m.implied.velocity.col(2) *= -1.0;
  }
  if (clip.axis != CommandAxis::kForward) m.direction = -clip.direction;
  m.contact = {clip.contact[1], clip.contact[0]};
  const Eigen::Index shift = alignPhaseOnLeftTouchdown(m);
  if (m.meta.provenance == "mocap") m.meta.provenance = "mocap_mirrored";
  m.meta.notes = fmt::format("left/right mirror of clip '{}' (robot mirror map), phase rotated by {} samples; {}", clip.name,
                             shift, clip.meta.notes);
  return m;
}

DynamicClip mirrorClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& new_name) {
  return mirrorClip(clip, generatorJointSpace(robot), new_name);
}

DynamicClip timeReverseClip(const DynamicClip& clip, const std::string& new_name) {
  DynamicClip r = clip;
  r.name = new_name;
  const Eigen::Index N = clip.q.rows();
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::Index s = (N - k) % N;
    r.q.row(k) = clip.q.row(s);
    r.qd.row(k) = -clip.qd.row(s);
    r.v_base.row(k) = -clip.v_base.row(s);
    r.omega_base.row(k) = -clip.omega_base.row(s);
    r.base_height[k] = clip.base_height[s];
  }
  for (auto& fc : r.contact) {
    fc.mu = 1.0 - fc.mu;
    fc.mu -= std::floor(fc.mu);
    if (fc.mu >= 1.0) fc.mu = 0.0;
  }
  r.direction = -clip.direction;
  r.implied.velocity *= -1.0;  // the same stance-foot paths, travelled backwards
  const Eigen::Index shift = alignPhaseOnLeftTouchdown(r);
  if (r.meta.provenance == "mocap") r.meta.provenance = "mocap_time_reversed";
  r.meta.notes = fmt::format("time reversal of clip '{}', phase rotated by {} samples; {}", clip.name, shift, clip.meta.notes);
  return r;
}

}  // namespace pmg
