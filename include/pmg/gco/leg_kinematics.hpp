#pragma once
/// @file leg_kinematics.hpp
/// KDL leg chains pelvis -> sole point of each foot, built from the robot URDF, for the
/// Ground-aware Command Optimization (GCO, PMG eqs. 13-14).
///
/// Frames (Drake-style names):
///   B = pelvis (base link), F = foot link (ankle roll link), S = sole point, a point fixed in F
///   at p_FS_F (centre of the sole contact patch, on the sole plane).
/// Model / Data split: LegModel is immutable after fromUrdfFile() (may allocate and throw);
/// LegKinematics is a per-thread workspace whose per-tick methods are noexcept and do not
/// allocate (proved by test/gco/gco_no_alloc_test.cpp).

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <kdl/chain.hpp>

#include "pmg/generator/clip.hpp"

namespace pmg {
struct RobotConfig;
}

namespace pmg::gco {

/// Number of joints of one G1 leg chain (hip pitch, hip roll, hip yaw, knee, ankle pitch, ankle roll).
inline constexpr int kLegDofs = 6;
using LegVector = Eigen::Matrix<double, kLegDofs, 1>;  ///< one leg's joint vector [rad] or [rad/s]
/// Column of each leg-chain joint in a full joint vector: [foot][chain joint] (LegModel::jointIndices()).
using LegJointIndex = std::array<std::array<int, kLegDofs>, kNumFeet>;

/// Which links the leg chains connect, and where the sole point sits on the foot.
struct LegModelOptions {
  std::string base_link = "pelvis";  ///< B: chain root (the floating base)
  std::array<std::string, kNumFeet> foot_links{"left_ankle_roll_link", "right_ankle_roll_link"};
  /// p_FS_F: sole point in the foot-link frame [m]. G1 default from the URDF collision spheres of
  /// the ankle roll link: toes at x = 0.12, heel at x = -0.05, sphere centres at z = -0.03 with
  /// radius 0.005, so the sole plane is z = -0.035 and the patch centre x = 0.035.
  Eigen::Vector3d p_FS_F{0.035, 0.0, -0.035};

  /// Throws std::invalid_argument naming the field when a link name is empty or p_FS_F is
  /// non-finite or farther than 0.5 m from the foot link.
  void validate() const;
};

/// Immutable leg-chain model (one KDL::Chain per foot, root B, tip S).
class LegModel {
 public:
  /// Parses the URDF with kdl_parser and extracts both chains.
  /// Throws std::runtime_error naming the file when it cannot be parsed, a link is missing, or a
  /// chain does not have exactly kLegDofs moving joints; std::invalid_argument from validate().
  static std::shared_ptr<const LegModel> fromUrdfFile(const std::string& urdf_path,
                                                      const LegModelOptions& options = {});

  /// Preferred in the controller: the leg chains of the robot config (pmg::KinematicModel of
  /// include/pmg/common/kinematics.hpp: base_link -> left/right_foot_link of the config's URDF).
  /// `options.base_link` / `foot_links` are replaced by the config's; p_FS_F is kept.
  /// Throws pmg::ConfigError / std::runtime_error naming the file on a URDF/config mismatch.
  static std::shared_ptr<const LegModel> fromRobotConfig(const RobotConfig& config, const LegModelOptions& options = {});

  const KDL::Chain& chain(Foot foot) const { return chains_[index(foot)]; }
  /// Joint names of one chain, root to tip (URDF names, e.g. "left_hip_pitch_joint").
  const std::array<std::string, kLegDofs>& jointNames(Foot foot) const { return joint_names_[index(foot)]; }
  /// Joint position limits of one chain from the URDF [rad], (lower, upper).
  const std::array<std::pair<double, double>, kLegDofs>& jointLimits(Foot foot) const {
    return limits_[index(foot)];
  }
  const LegModelOptions& options() const { return options_; }
  const std::string& urdfPath() const { return urdf_path_; }

  /// Column of each chain joint in a full joint vector ordered by `joint_names` (e.g. the
  /// RobotConfig order). Throws std::runtime_error naming the missing joint.
  LegJointIndex jointIndices(const std::vector<std::string>& joint_names) const;

  static std::size_t index(Foot foot) { return static_cast<std::size_t>(foot); }

 private:
  LegModel() = default;
  static std::shared_ptr<const LegModel> build(std::array<KDL::Chain, kNumFeet> chains, const LegModelOptions& options,
                                               const std::string& source);
  std::array<KDL::Chain, kNumFeet> chains_;
  std::array<std::array<std::string, kLegDofs>, kNumFeet> joint_names_;
  std::array<std::array<std::pair<double, double>, kLegDofs>, kNumFeet> limits_;
  LegModelOptions options_;
  std::string urdf_path_;
};

/// Kinematics of one foot relative to the pelvis, all vectors in the pelvis frame B.
struct FootKinematics {
  Eigen::Vector3d p_BS_B = Eigen::Vector3d::Zero();  ///< sole point S relative to pelvis origin [m]
  Eigen::Matrix3d R_BF = Eigen::Matrix3d::Identity();  ///< foot orientation in B
  Eigen::Vector3d v_BS_B = Eigen::Vector3d::Zero();  ///< dp_BS/dt from q̇ (J_v q̇) [m/s]
  Eigen::Vector3d w_BF_B = Eigen::Vector3d::Zero();  ///< foot angular velocity relative to B (J_w q̇) [rad/s]
};

/// Workspace for forward kinematics, Jacobian and (setup-time) inverse kinematics of the legs.
/// Not thread-safe: one instance per thread.
class LegKinematics {
 public:
  /// Allocates the KDL solvers. Throws std::invalid_argument if `model` is null.
  explicit LegKinematics(std::shared_ptr<const LegModel> model);
  ~LegKinematics();
  LegKinematics(const LegKinematics&) = delete;
  LegKinematics& operator=(const LegKinematics&) = delete;

  /// Eq. 13-14 leg terms: pose of S and its velocity relative to B for joint state (q, q̇) of
  /// one leg (chain order, [rad], [rad/s]). Returns false (and leaves *out unchanged) when an
  /// input is non-finite or KDL reports an error. No allocation.
  bool compute(Foot foot, const LegVector& q, const LegVector& qd, FootKinematics* out) noexcept;

  /// Pose X_BS of the sole frame (origin S, axes of F) in B. No allocation.
  bool forward(Foot foot, const LegVector& q, Eigen::Isometry3d* X_BS) noexcept;

  /// Foot orientation R_BF and the angular part of the Jacobian, J_ω (column k = axis of chain
  /// joint k in B, unit), for one leg's q (chain order [rad]). No allocation. Used by
  /// SoleLevelling (sole_levelling.hpp): ∂(R_BF e_z)/∂q_k = J_ω,k × (R_BF e_z).
  bool orientation(Foot foot, const LegVector& q, Eigen::Matrix3d* R_BF,
                   Eigen::Matrix<double, 3, kLegDofs>* J_w_B) noexcept;

  /// Pose X_BS of the sole frame in B and the geometric Jacobian of S in B, rows (v_BS_B; ω_BF_B):
  /// J (6 x kLegDofs), [m/rad] over [rad/rad], reference point S. No allocation. Used by
  /// StrideAdaptation (stride_adaptation.hpp) for its per-tick differential inverse kinematics.
  bool jacobian(Foot foot, const LegVector& q, Eigen::Isometry3d* X_BS, Eigen::Matrix<double, 6, kLegDofs>* J_B) noexcept;

  /// Setup-time inverse kinematics (KDL Levenberg-Marquardt) for a target sole pose X_BS,
  /// starting from q_init. Returns the final position error norm [m + rad]; *q receives the
  /// solution clamped to the URDF joint limits.
  double inverse(Foot foot, const Eigen::Isometry3d& X_BS_target, const LegVector& q_init, LegVector* q);

  const LegModel& model() const { return *model_; }

 private:
  struct Impl;
  std::shared_ptr<const LegModel> model_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmg::gco
