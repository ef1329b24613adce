#pragma once
/// @file joint_angle_map.hpp
/// Retargeting "joint_angle_map_v1": maps each DeepMimic joint rotation onto the Unitree G1's joint
/// chain by Euler decomposition in the G1 axis order (issue-2 method; the optimisation-based
/// retargeter supersedes it where available).
///
/// Convention: every DeepMimic rotation R_M (file frame, Y up) is first expressed in the robot's
/// axes, R = C R_M Cᵀ with C = deepMimicToZUp() (x fwd, y left, z up). Both skeletons have the
/// same rest pose at zero angles (legs straight down, arms hanging, feet flat), except where an
/// offset is listed. Per joint (URDF g1_29dof_rev_1_0, a = 0.1749 rad hip-roll axis tilt,
/// b = ±0.27931 rad shoulder-pitch frame roll, + left / − right):
///   hip (pitch, roll, yaw):      Ry(p−a)·Rx(r)·Rz(y) = R_hip·Ry(−a)        (YXZ Euler), pitch = p
///   knee:                         q = −θ_knee (DeepMimic knee ≤ 0 about +z_M = −y)
///   ankle (pitch, roll):          Ry(p)·Rx(r)·Rz(ψ) = R_ankle, ψ (toe yaw) dropped
///   waist (yaw, roll, pitch):     Rz(y)·Rx(r)·Ry(p) = R_chest              (ZXY Euler)
///   shoulder (pitch, roll, yaw):  Ry(p)·Rx(r−b)·Rz(y) = Rx(−b)·R_shoulder (YXZ Euler)
///   elbow:                        q = π/2 − θ_elbow (G1 elbow 0 = forearm horizontal)
///   wrists: default pose (DeepMimic has no wrist); neck: unused (G1 has no neck).
/// Every angle is clamped to the robot's joint limits; the excess is recorded per frame/joint.
/// Base: R_WB = C R_MR Cᵀ; p_WB(x, y) = s · (C p_MR)(x, y), s = options.scale (human → robot
/// length ratio); the pelvis height is then set by placeOnGround() from G1 forward kinematics.

#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "pmg/motion/robot_motion.hpp"

namespace pmg::motion {

/// DeepMimic humanoid3d leg length, hip joint to ankle joint [m] (0.421546 + 0.409870, from
/// characters/humanoid3d.txt).
inline constexpr double kDeepMimicLegLength = 0.831416;

struct JointAngleMapOptions {
  /// Human → robot length scale for the base translation; ≤ 0 selects the leg-length ratio
  /// (G1 hip pitch axis to ankle roll axis at q = 0, over kDeepMimicLegLength).
  double scale = 0.0;
  /// @throws std::invalid_argument if scale is not finite.
  void validate() const;
};

/// G1 leg length: hip pitch joint to ankle roll joint at q = 0 [m], from the URDF via KDL.
double robotLegLength(const KinematicModel& model);

/// Euler decompositions used above (exposed for tests): R = Ry(a)·Rx(b)·Rz(c) → (a, b, c) and
/// R = Rz(a)·Rx(b)·Ry(c) → (a, b, c); b ∈ [−π/2, π/2].
Eigen::Vector3d eulerYXZ(const Eigen::Matrix3d& R);
Eigen::Vector3d eulerZXY(const Eigen::Matrix3d& R);

/// Retargets a DeepMimic motion onto the robot (joint order of @p model.config()).
/// Joint names the map needs must exist in the config (G1 29-DoF names).
/// @throws std::invalid_argument naming the missing joint, or on bad options.
RobotMotion retargetJointAngleMap(const DeepMimicMotion& motion, const KinematicModel& model,
                                  const JointAngleMapOptions& options = {});

}  // namespace pmg::motion
