#include "pmg/teleop/arm_capsules.hpp"

#include <algorithm>
#include <cmath>

namespace pmg::teleop {

namespace {

Capsule make(const char* name, const char* link, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  Capsule c;
  c.name = name;
  c.link = link;
  c.a = a;
  c.b = b;
  c.radius = radius;
  return c;
}

/// The right arm's capsule is the left's mirrored in the sagittal plane (y → −y of the link frame):
/// the G1's right arm links are the left's mirrored (URDF origins and meshes).
Capsule mirrorY(const Capsule& left, const char* name, const char* link) {
  const Eigen::Vector3d m(1.0, -1.0, 1.0);
  return make(name, link, left.a.cwiseProduct(m), left.b.cwiseProduct(m), left.radius);
}

}  // namespace

ArmCapsuleModel ArmCapsuleModel::g1() {
  // Mesh extents (config/robots/g1/meshes, link frames) these were fitted to, per capsule:
  //   torso_link:  x −0.067..0.084, y ±0.108 (±0.068 at z = 0, ±0.10 at z = 0.05..0.25), z −0.009..0.312
  //   head_link:   in T (head_joint offset (0.004, 0, −0.044)): x −0.062..0.078, y ±0.078, z 0.281..0.487
  //   pelvis_contour_link + hip pitch links, in T at waist = 0 (pelvis origin at (0.004, 0, −0.044)):
  //                x −0.06..0.06, y ±0.16, z −0.20..−0.07
  //   shoulder_yaw_link: x −0.033..0.048, y −0.041..0.033, z −0.114..0.032 (elbow joint at (0.0158, 0, −0.0805))
  //   elbow_link: x −0.03..0.10, y ±0.031, z −0.045..0.03; wrist roll + pitch links continue to the
  //               wrist pitch joint at (0.138, 0.0019, −0.010) of the elbow link (on the wrist roll axis)
  //   rubber_hand: x 0..0.132, y −0.048..0.019, z −0.043..0.063; wrist yaw joint at (−0.0415, −0.003, 0)
  ArmCapsuleModel m;
  m.body[kTorsoLeft] = make("torso_left", "torso_link", {0.008, 0.035, 0.07}, {0.008, 0.035, 0.24}, 0.068);
  m.body[kTorsoRight] = make("torso_right", "torso_link", {0.008, -0.035, 0.07}, {0.008, -0.035, 0.24}, 0.068);
  m.body[kHead] = make("head", "torso_link", {0.008, 0.0, 0.36}, {0.008, 0.0, 0.42}, 0.07);
  m.body[kPelvis] = make("pelvis", "torso_link", {0.004, -0.085, -0.13}, {0.004, 0.085, -0.13}, 0.07);

  m.arm[0][kUpperArm] =
      make("left_upper_arm", "left_shoulder_yaw_link", {0.0, 0.0, 0.05}, {0.0158, 0.0, -0.0805}, 0.035);
  m.arm[0][kForearm] = make("left_forearm", "left_elbow_link", {0.0, 0.0, 0.0}, {0.138, 0.0019, -0.010}, 0.032);
  m.arm[0][kHandCapsule] = make("left_hand", "left_rubber_hand", {-0.035, 0.0, 0.0}, {0.09, -0.01, 0.01}, 0.045);
  m.arm[1][kUpperArm] = mirrorY(m.arm[0][kUpperArm], "right_upper_arm", "right_shoulder_yaw_link");
  m.arm[1][kForearm] = mirrorY(m.arm[0][kForearm], "right_forearm", "right_elbow_link");
  m.arm[1][kHandCapsule] = mirrorY(m.arm[0][kHandCapsule], "right_hand", "right_rubber_hand");
  return m;
}

std::string ArmCapsuleModel::validate() const {
  auto check = [](const Capsule& c) -> std::string {
    if (c.link.empty()) return "capsule '" + c.name + "': empty link name";
    if (!c.a.allFinite() || !c.b.allFinite()) return "capsule '" + c.name + "': non-finite end point";
    if (!(c.radius > 0.0) || !std::isfinite(c.radius) || c.radius > 0.5) {
      return "capsule '" + c.name + "': radius = " + std::to_string(c.radius) + ": expected 0 < r <= 0.5 m";
    }
    return "";
  };
  for (const Capsule& c : body) {
    if (std::string e = check(c); !e.empty()) return e;
  }
  for (const auto& side : arm) {
    for (const Capsule& c : side) {
      if (std::string e = check(c); !e.empty()) return e;
    }
  }
  return "";
}

double segmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                              const Eigen::Vector3d& q1, double* s_out, double* t_out) noexcept {
  // Closest points of two segments: minimise |p0 + s d1 − q0 − t d2|² over the unit square
  // (Ericson, Real-Time Collision Detection, sec. 5.1.9).
  constexpr double kEps = 1e-12;
  const Eigen::Vector3d d1 = p1 - p0;
  const Eigen::Vector3d d2 = q1 - q0;
  const Eigen::Vector3d r = p0 - q0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  double s = 0.0;
  double t = 0.0;
  if (a <= kEps && e <= kEps) {
    s = t = 0.0;
  } else if (a <= kEps) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEps) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > kEps ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  if (s_out != nullptr) *s_out = s;
  if (t_out != nullptr) *t_out = t;
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

}  // namespace pmg::teleop
