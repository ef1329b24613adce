#pragma once
/// @file arm_capsules.hpp
/// Capsule collision model of the G1 upper body for the arm IK (pmg::teleop::ArmIk, arm_ik.hpp),
/// and the segment–segment distance it is built on.
///
/// A capsule is the set of points within `radius` of the segment [a, b]. Body capsules are fixed in
/// the torso frame T (torso_link: x forward, y left, z up); arm capsules are fixed in one link of
/// the arm chain and move with it.
///
/// Source of the constants (ArmCapsuleModel::g1()): the G1's URDF collision geometry of the arm and
/// torso links is the visual STL meshes (config/robots/g1/meshes), so the capsules are stated
/// constants fitted by hand to the mesh bounding boxes (per 2 cm slices for torso, head and pelvis),
/// each covering its mesh to within about 1 cm; docs/teleop.md lists them with the mesh extents.
/// The pelvis capsule (pelvis and hip pitch links) is placed for the waist joints at 0; the real
/// pelvis moves relative to T when the waist rolls or pitches.

#include <Eigen/Core>
#include <array>
#include <string>

namespace pmg::teleop {

/// A capsule: points within `radius` of the segment [a, b], a and b in the frame of `link`.
struct Capsule {
  std::string name;                             ///< e.g. "torso_left", "left_forearm"
  std::string link;                             ///< URDF link the points are fixed in ("torso_link" for body capsules)
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  ///< segment start in the link frame [m]
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  ///< segment end in the link frame [m]
  double radius = 0.0;                          ///< [m], > 0
};

/// Indices into ArmCapsuleModel::arm[hand].
enum ArmCapsule : int { kUpperArm = 0, kForearm = 1, kHandCapsule = 2 };
inline constexpr int kNumArmCapsules = 3;
/// Indices into ArmCapsuleModel::body.
enum BodyCapsule : int { kTorsoLeft = 0, kTorsoRight = 1, kHead = 2, kPelvis = 3 };
inline constexpr int kNumBodyCapsules = 4;

/// The capsules the IK keeps apart. Pairs checked: every arm capsule against every body capsule
/// (except upper arm – head), and every left arm capsule against every right arm capsule (except
/// upper arm – upper arm); capsules of one arm are never checked against each other.
struct ArmCapsuleModel {
  std::array<Capsule, kNumBodyCapsules> body;               ///< fixed in T (link "torso_link")
  std::array<std::array<Capsule, kNumArmCapsules>, 2> arm;  ///< [hand][ArmCapsule]

  /// The Unitree G1 29-DoF rev 1.0 model (constants in src/teleop/ik/arm_capsules.cpp).
  static ArmCapsuleModel g1();

  /// "" if valid, else what is wrong (non-finite point, radius ≤ 0, empty link name).
  std::string validate() const;
};

/// Closest points of the segments [p0, p1] and [q0, q1] (all in one frame) and their distance.
/// Returns |c_p − c_q| [m]; *s, *t ∈ [0, 1] receive the parameters of the closest points
/// c_p = p0 + s (p1 − p0), c_q = q0 + t (q1 − q0). Degenerate (zero-length) segments are handled.
/// noexcept, allocation-free.
double segmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                              const Eigen::Vector3d& q1, double* s, double* t) noexcept;

}  // namespace pmg::teleop
