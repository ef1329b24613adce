#pragma once
/// @file kinematics.hpp
/// Kinematic chains of the robot from its URDF through KDL (kdl_parser + orocos KDL).
///
/// A LimbChain is a KDL chain from a root link (normally the floating base, "pelvis") to a tip
/// link, together with the index of each chain joint in the robot config's joint order, so a full
/// joint vector q (n, config order) can be mapped onto it. Built at setup (allocates, throws);
/// forwardKinematics() with a preallocated workspace is allocation-free.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>

#include "pmg/common/robot_config.hpp"

namespace pmg {

/// One kinematic chain root → tip with its mapping onto the robot's joint order.
struct LimbChain {
  std::string root_link;           ///< e.g. "pelvis"
  std::string tip_link;            ///< e.g. "left_ankle_roll_link"
  KDL::Chain chain;                ///< KDL chain (fixed segments included)
  std::vector<int> joint_index;    ///< (chain.getNrOfJoints()) index of each chain joint in RobotConfig::joints
};

/// Pelvis tilt without yaw, R_WB = Ry(pitch)·Rx(roll), that maps the sole normal @p n_B (pelvis
/// frame B; e.g. the sum of the flat-standing feet's z axes, need not be unit) onto the world z axis:
/// the least-squares tilt that puts those soles flat (Rᵀ e_z = n̂). Writes pitch (positive = pelvis
/// forward) and roll [rad] when given. Identity for a zero or non-finite normal. noexcept, no allocation.
Eigen::Matrix3d soleLevelingRotation(const Eigen::Vector3d& n_B, double* pitch = nullptr, double* roll = nullptr) noexcept;

/// Preallocated workspace for forward kinematics on one LimbChain (Model/Data split).
class ChainFkWorkspace {
 public:
  explicit ChainFkWorkspace(const LimbChain& limb);
  /// Pose of the tip link in the root frame, X_RT, for the full joint vector @p q (n, config order,
  /// [rad]). Allocation-free, noexcept. Returns false if KDL reports an error.
  bool tipPose(const Eigen::VectorXd& q, Eigen::Isometry3d& X_RT) noexcept;
  /// Pose of the frame after segment @p segment (0-based, KDL convention) in the root frame.
  bool segmentPose(const Eigen::VectorXd& q, int segment, Eigen::Isometry3d& X_RS) noexcept;

 private:
  const LimbChain* limb_;
  KDL::ChainFkSolverPos_recursive solver_;
  KDL::JntArray q_chain_;
  KDL::Frame frame_;
};

/// KDL tree of the URDF at @p urdf_path (parsed with urdfdom, built with kdl_parser). KDL cannot
/// represent an inertia on the root link (the G1's "pelvis" has one), which kdl_parser drops with a
/// warning on every load; the root inertia is dropped before the tree is built, so the tree is the
/// same and nothing is printed. @throws ConfigError naming the file if it cannot be read or parsed.
KDL::Tree kdlTreeFromUrdfFile(const std::string& urdf_path);

/// The robot's KDL tree, loaded from the URDF named in the robot config.
class KinematicModel {
 public:
  /// @throws ConfigError if the URDF cannot be parsed, or a URDF joint on a requested chain is
  /// not in the robot config (URDF/config mismatch), or vice versa for chain(): names the file.
  explicit KinematicModel(const RobotConfig& config);

  const KDL::Tree& tree() const { return tree_; }
  const RobotConfig& config() const { return config_; }
  /// Chain from @p root_link to @p tip_link. @throws ConfigError if either link is unknown.
  LimbChain chain(const std::string& root_link, const std::string& tip_link) const;
  /// Base → left/right foot link (RobotConfig::left_foot_link / right_foot_link).
  LimbChain leftLeg() const { return chain(config_.base_link, config_.left_foot_link); }
  LimbChain rightLeg() const { return chain(config_.base_link, config_.right_foot_link); }

 private:
  RobotConfig config_;
  KDL::Tree tree_;
};

/// KDL frame → Eigen isometry.
Eigen::Isometry3d toEigen(const KDL::Frame& frame);

}  // namespace pmg
