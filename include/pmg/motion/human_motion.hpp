#pragma once
/// @file human_motion.hpp
/// Format-independent human motion: the keypoints and body orientations that the optimisation-
/// based retargeter matches (pmg::motion::retargetKeypoints). Every importer (DeepMimic, BVH, AMP
/// npz) produces one.
///
/// Frame W: world, Z up, metres, ground at z ≈ 0 (importers shift it there). Body orientations
/// R_WX map a body frame X whose rest orientation is x forward, y left, z up (the robot's
/// convention) into W. Setup-time code (allocates, throws).

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pmg::motion {

/// Keypoints matched by the retargeter (human joint centres).
enum class Keypoint : int {
  kPelvis = 0,
  kLeftHip, kLeftKnee, kLeftAnkle, kLeftToe,
  kRightHip, kRightKnee, kRightAnkle, kRightToe,
  kLeftShoulder, kLeftElbow, kLeftWrist,
  kRightShoulder, kRightElbow, kRightWrist,
  kCount
};
inline constexpr std::size_t kNumKeypoints = static_cast<std::size_t>(Keypoint::kCount);

/// Name of a keypoint ("pelvis", "left_knee", ...).
const char* keypointName(Keypoint k);

/// Distance of the toe keypoint ahead of the ankle along the foot's x axis [m]. Importers place
/// kLeftToe/kRightToe at p_ankle + R_WFoot · (kToeOffset, 0, 0), so the ankle→toe vector encodes
/// the foot's pitch and yaw with the same geometry on human and robot.
inline constexpr double kToeOffset = 0.10;

/// One frame of human motion.
struct HumanFrame {
  std::array<Eigen::Vector3d, kNumKeypoints> p_WK;  ///< keypoint positions in W [m]
  Eigen::Quaterniond R_WPelvis = Eigen::Quaterniond::Identity();  ///< pelvis orientation
  Eigen::Quaterniond R_WTorso = Eigen::Quaterniond::Identity();   ///< upper torso (chest) orientation
  std::array<Eigen::Quaterniond, 2> R_WFoot{Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()};  ///< left, right
};

/// A human motion clip.
struct HumanMotion {
  std::string source_file;  ///< path it was read from
  std::string format;       ///< "deepmimic", "bvh", "amp_npz"
  double fps = 0.0;         ///< frame rate [Hz]
  /// Height of the ankle keypoint above the sole when the foot is flat on the ground [m]
  /// (skeleton property, set by the importer; used for ground placement and contact detection).
  double ankle_height = 0.08;
  std::vector<HumanFrame> frames;

  int numFrames() const { return static_cast<int>(frames.size()); }
  /// Mean hip → knee → ankle length over frames and both legs [m].
  double legLength() const;
  /// Mean shoulder → elbow → wrist length [m].
  double armLength() const;
  /// Left/right mirror: reflects y (W) and swaps left/right keypoints and feet. Orientations are
  /// reflected as R' = S R S with S = diag(1, −1, 1).
  HumanMotion mirrored() const;
  /// Frames [begin, end) only. @throws std::out_of_range.
  HumanMotion slice(int begin, int end) const;
};

/// Moves the motion vertically so the ground is at z = 0: ground = 5th percentile over frames of
/// the lower of the two feet's min(ankle z, toe z), minus motion.ankle_height.
void putOnGround(HumanMotion& motion);

}  // namespace pmg::motion
