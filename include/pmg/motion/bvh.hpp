#pragma once
/// @file bvh.hpp
/// Biovision Hierarchy (BVH) motion files: parser, forward kinematics and conversion to
/// HumanMotion for the CMU/cgspeed skeleton (../shared/data/motions/cmu_bvh/SOURCE.md).
///
/// BVH: HIERARCHY (ROOT/JOINT/End Site blocks with OFFSET and CHANNELS), then MOTION (Frames,
/// Frame Time, one line of channel values per frame). Rotation channels are Euler angles in
/// degrees applied in the listed order as intrinsic rotations (R = R_c1·R_c2·R_c3); a joint's
/// global pose is p = p_parent + R_parent·offset, R = R_parent·R_local. No third-party C++ BVH
/// parser is packaged for Debian, so this one is small and strict: every error names the file
/// and line.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/motion/human_motion.hpp"

namespace pmg::motion {

/// One BVH joint (End Sites are stored as joints with no channels, name "<parent>_end").
struct BvhJoint {
  std::string name;
  int parent = -1;                 ///< index into BvhMotion::joints, −1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< in file units, parent frame
  std::vector<std::string> channels;  ///< e.g. {"Xposition", ..., "Zrotation", ...}
  int channel_begin = 0;           ///< index of its first channel in a frame line
};

struct BvhMotion {
  std::string source_file;
  std::vector<BvhJoint> joints;
  int num_channels = 0;
  double frame_time = 0.0;         ///< [s]
  Eigen::MatrixXd values;          ///< (frames × num_channels), file units / degrees

  int numFrames() const { return static_cast<int>(values.rows()); }
  /// Index of a joint by name. @throws std::runtime_error naming the file if absent.
  int jointIndex(const std::string& name) const;
};

/// Parses a BVH file. @throws std::runtime_error "file:line: what" on any syntax or count error
/// (unknown keyword, bad channel name, wrong number of values in a frame line, Frames mismatch).
BvhMotion readBvh(const std::string& path);

/// Global joint positions (file units) and orientations (file axes) of one frame.
void bvhForwardKinematics(const BvhMotion& motion, int frame, std::vector<Eigen::Vector3d>& p,
                          std::vector<Eigen::Matrix3d>& R);

/// Converts a CMU/cgspeed BVH motion (joints Hips, LeftUpLeg, LeftLeg, LeftFoot, Spine1, LeftArm,
/// LeftForeArm, LeftHand and the Right* ones; Y up, character facing +Z, left = +X at rest) to a
/// HumanMotion in W (x = rest facing, y = left, z = up), positions × @p unit_scale [m per file
/// unit] (0.056444 for CMU), ground at z = 0 (ankle_height 0.08 m, typical adult ankle centre).
/// @throws std::runtime_error naming the file and a missing joint.
HumanMotion bvhToHuman(const BvhMotion& motion, double unit_scale);

}  // namespace pmg::motion
