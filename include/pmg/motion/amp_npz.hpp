#pragma once
/// @file amp_npz.hpp
/// Reader for Isaac Lab "humanoid_amp" reference motions (`humanoid_{walk,run}.npz`, see
/// ../shared/data/motions/isaaclab_amp/SOURCE.md) and their conversion to HumanMotion.
///
/// An .npz file is a ZIP archive of .npy arrays. numpy writes them *stored* (uncompressed), so a
/// small reader suffices: ZIP local file headers → .npy header (dict with descr, fortran_order,
/// shape) → little-endian data. Compressed members (np.savez_compressed) are rejected with a
/// clear error. No C++ npz library is packaged for Debian (cnpy is not).

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "pmg/motion/human_motion.hpp"

namespace pmg::motion {

/// One numeric .npy array, converted to double (row-major, C order).
struct NpyArray {
  std::string descr;                ///< numpy dtype string, e.g. "<f4", "<i8", "<U16"
  std::vector<std::size_t> shape;   ///< e.g. {154, 15, 3}; {} for a scalar
  std::vector<double> values;       ///< numeric arrays only (empty for string arrays)
  std::size_t size() const;         ///< product of shape (1 for a scalar)
};

/// Reads every member of an .npz archive (numeric dtypes <f4, <f8, <i4, <i8 are converted;
/// unicode/bytes arrays keep only descr and shape). Keys are member names without ".npy".
/// @throws std::runtime_error naming the file and member on any problem (not a ZIP, compressed
/// member, bad .npy magic/header, Fortran order, unsupported dtype, truncated data).
std::map<std::string, NpyArray> readNpz(const std::string& path);

/// Converts an Isaac Lab AMP motion: body_positions (N, 15, 3) [m, Z up] and body_rotations
/// (N, 15, 4) (w, x, y, z) of the bodies pelvis, torso, head, right_upper_arm, right_lower_arm,
/// right_hand, left_upper_arm, left_lower_arm, left_hand, right_thigh, right_shin, right_foot,
/// left_thigh, left_shin, left_foot (body origins = joint centres: shoulder, elbow, wrist, hip,
/// knee, ankle). The AMP humanoid faces +x with left +y at zero pose, like the robot.
/// @throws std::runtime_error naming the file and key if a key is missing or has the wrong shape.
HumanMotion ampNpzToHuman(const std::string& path);

}  // namespace pmg::motion
