#pragma once
/// @file deepmimic.hpp
/// Reader for DeepMimic reference motions (`humanoid3d_*.txt`, JSON text; Peng et al.,
/// SIGGRAPH 2018) and the axis convention needed to use them on a Z-up robot.
///
/// File layout (see ../shared/data/motions/deepmimic/SOURCE.md): {"Loop": "wrap"|"none",
/// "Frames": [[44 numbers], ...]}; per frame: duration [s], root position (3, metres, file frame
/// M: Y up, X = walking direction at t = 0, Z = character's right), root orientation quaternion
/// (w,x,y,z) in M, then chest, neck, right hip (quaternions, local to parent), right knee [rad],
/// right ankle, right shoulder (quaternions), right elbow [rad], left hip, left knee, left ankle,
/// left shoulder, left elbow. Revolute joints (knee, elbow) rotate about the local +Z (= right) axis.
///
/// The file is parsed with yaml-cpp (JSON is a subset of YAML 1.2), so syntax errors carry a line.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/motion/human_motion.hpp"

namespace pmg::motion {

/// One DeepMimic frame. Quaternions are unit, expressed in the file's Y-up frame convention.
struct DeepMimicFrame {
  double duration = 0.0;                  ///< time to the next frame [s] (0 on the last frame)
  Eigen::Vector3d p_MR = Eigen::Vector3d::Zero();  ///< root position in the file frame M [m]
  Eigen::Quaterniond R_MR = Eigen::Quaterniond::Identity();  ///< root orientation in M
  Eigen::Quaterniond chest, neck;         ///< relative to root / chest
  Eigen::Quaterniond right_hip, right_ankle, right_shoulder;
  Eigen::Quaterniond left_hip, left_ankle, left_shoulder;
  double right_knee = 0.0, right_elbow = 0.0;  ///< about local +Z [rad]; knee ≤ 0 = flexion
  double left_knee = 0.0, left_elbow = 0.0;    ///< elbow ≥ 0 = flexion
};

/// A whole DeepMimic motion file.
struct DeepMimicMotion {
  std::string source_file;   ///< path it was read from
  bool loop_wrap = false;    ///< "Loop": "wrap" (last frame closes the cycle) vs "none"
  double fps = 0.0;          ///< frame rate [Hz] = 1 / duration of frame 0
  std::vector<DeepMimicFrame> frames;
};

/// Reads a DeepMimic motion. Every frame must have 44 finite numbers, unit quaternions (|q| within
/// 1e-2 of 1; renormalised) and the same duration as frame 0 (within 1e-4 s; the last may be 0).
/// @throws std::runtime_error naming the file, the line, frame index and field on any problem.
DeepMimicMotion readDeepMimicMotion(const std::string& path);

/// Keypoints of a DeepMimic motion by forward kinematics of the humanoid3d skeleton
/// (characters/humanoid3d.txt offsets: chest 0.236151 m above the root, shoulders at
/// (−0.02405, 0.2435, ±0.18311) m from the chest, upper arm 0.274788 m, forearm 0.258947 m, hips
/// ±0.084887 m, thigh 0.421546 m, shank 0.409870 m), in W (Z up), ground at z = 0
/// (ankle_height = 0.05 m: the foot box bottom is 0.05 m below the ankle joint).
HumanMotion deepMimicToHuman(const DeepMimicMotion& motion);

/// Rotation from the DeepMimic file frame M (x fwd, y up, z right) to the robot world/body
/// convention W (x fwd, y left, z up): v_W = C · v_M with C = [[1,0,0],[0,0,-1],[0,1,0]].
Eigen::Matrix3d deepMimicToZUp();

}  // namespace pmg::motion
