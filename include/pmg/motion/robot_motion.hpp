#pragma once
/// @file robot_motion.hpp
/// A retargeted robot trajectory at the source frame rate (the seed's D_robot^d before it is cut
/// into a clip), plus the foot geometry derived from it by forward kinematics of the robot.
///
/// Frames: W = world, Z up, ground plane z = 0; B = pelvis (robot base link); F = foot link
/// (ankle roll link). Setup-time code (allocates, throws).

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/common/kinematics.hpp"

namespace pmg::motion {

/// Robot trajectory sampled at `fps`. F frames, n joints (robot config order).
struct RobotMotion {
  std::string source_file;   ///< mocap file the motion came from
  double fps = 0.0;          ///< frame rate [Hz]
  Eigen::MatrixXd q;         ///< (F × n) joint positions [rad]
  Eigen::MatrixXd p_WB;      ///< (F × 3) pelvis position in W [m] (z filled by placeOnGround)
  std::vector<Eigen::Quaterniond> R_WB;  ///< (F) pelvis orientation in W
  /// Filled by placeOnGround(): sole point of each foot in W, (F × 3) per foot [m], index
  /// Foot::kLeft / kRight: x, y = centre of the sole points, z = height of the lowest sole point
  /// above the ground.
  std::array<Eigen::MatrixXd, 2> p_WS;
  /// Per frame and joint: how far the retargeted angle was outside the joint limits before it was
  /// clamped [rad] (0 = inside). (F × n).
  Eigen::MatrixXd clamp_excess;

  int numFrames() const { return static_cast<int>(q.rows()); }
};

/// Sole contact points of the G1 foot in the foot (ankle roll link) frame F [m]: the four
/// collision spheres of the URDF (x = -0.05 and 0.12 m, y = ±0.025/±0.03 m, 0.03 m below the
/// ankle pitch axis, radius 0.005 m), moved to their lowest point.
std::array<Eigen::Vector3d, 4> g1SolePoints_F();

/// Places the pelvis height so that the lowest sole point of the two feet touches z = 0 in every
/// frame (no ground penetration, no floating; valid for motions that always keep a foot on the
/// ground: walking, turning, squatting) and fills RobotMotion::p_WS by forward kinematics.
/// @param legs  chains base → left foot link and base → right foot link (KinematicModel::leftLeg()).
/// @throws std::runtime_error if forward kinematics fails.
void placeOnGround(RobotMotion& motion, const LimbChain& left_leg, const LimbChain& right_leg);

/// Fills RobotMotion::p_WS by forward kinematics without moving the base (p_WB as given).
/// @throws std::runtime_error if forward kinematics fails.
void computeSoleTracks(RobotMotion& motion, const LimbChain& left_leg, const LimbChain& right_leg);

/// Heading (yaw) of a base orientation: angle of its x axis projected on the ground plane [rad].
double headingOf(const Eigen::Quaterniond& R_WB);

}  // namespace pmg::motion
