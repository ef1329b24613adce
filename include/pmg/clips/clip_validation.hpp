#pragma once
/// @file clip_validation.hpp
/// The one validation of PMG clips (pmg::clips). The clip file reader (clip_io.hpp) and the
/// generator (GeneratorModel's constructor, include/pmg/generator/generator.hpp) both call it, so a
/// clip is accepted or refused by the same rules whether it comes from a file or is built in memory.
/// Setup-time code: allocates and throws.
///
/// Rules (docs/clip_format.md, "Validation"):
/// - dynamic: N ≥ 2 rows; q, qd: N × n; v_base, omega_base: N × 3; base_height: N; every value
///   finite; base_height > 0 [m]; period T in (0, 10) [s]; nominal scale x̄ > 0; direction ±1;
///   contact μ ∈ [0, 1), σ ∈ [0, 0.5] (phase units);
/// - static: K ≥ 2 strictly increasing finite values, q: K × n, neutral within [values₀, values_K−1];
/// - both: n = the joint space's joint count; joint names (when given) equal its joint order; every
///   q within the joint limits (± limit_tolerance); metadata: format version, 0 ≤ frame_begin ≤
///   frame_end, source_fps ≥ 0, provenance one of mocap, mocap_mirrored, mocap_time_reversed,
///   synthesized.

#include <string>

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/clip.hpp"
#include "pmg/generator/joint_space.hpp"

namespace pmg {

/// Error raised by every clip reader and validator. what() names the source (file[:line] or
/// clip name), the field with its row/column index, the value and the expected range, e.g.
/// "config/clips/g1/walk_forward.yaml:40: q[3][4]: = 0.610000: expected within joint limits
///  [-0.87267, 0.5236] of left_ankle_pitch_joint". A pmg::ConfigError, like every config error.
class ClipFormatError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

/// Options of clip validation.
struct ClipValidationOptions {
  /// Allowed excursion beyond a joint limit [rad] (covers the 1e-6 rounding of the text format).
  double limit_tolerance = 1e-6;
  /// Check that the joint names equal the joint space's order (else only the count).
  bool check_joint_names = true;
  /// Refuse a clip without joint names (clip files always carry them). Clips built in memory (tests,
  /// tools) may leave meta.joint_names empty when this is false: then only the count is checked.
  bool require_joint_names = true;
  /// @throws ClipFormatError if limit_tolerance is negative or not finite.
  void validate() const;
};

/// Checks a dynamic clip against a joint space (rules in the file comment).
/// @param where names the source in messages (file name or "clip 'name'").
/// @throws ClipFormatError naming @p where, the field and the expected range.
void validateClip(const DynamicClip& clip, const GeneratorJointSpace& joints, const std::string& where,
                  const ClipValidationOptions& options = {});
/// Checks a static clip against a joint space. @throws ClipFormatError.
void validateClip(const StaticClip& clip, const GeneratorJointSpace& joints, const std::string& where,
                  const ClipValidationOptions& options = {});

/// Checks a dynamic clip against a robot config (its joint space, generatorJointSpace()).
/// When a joint name of the clip differs from the robot config's, the robot config is first checked
/// against its URDF: a config joint that is not a joint of the URDF is the config's error, not the
/// clip's. @throws pmg::ConfigError naming the robot config, the joint and the URDF in that case;
/// ClipFormatError naming @p where otherwise.
void validateClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options = {});
/// Checks a static clip against a robot config (as above). @throws ConfigError / ClipFormatError.
void validateClip(const StaticClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options = {});

/// Checks that a library holds at most one dynamic clip per (axis, direction) and one static clip
/// per posture axis. @p where names the library (directory) in messages. @throws ClipFormatError.
void validateLibraryAxes(const ClipLibrary& library, const std::string& where);

/// Text names of the enums as used in clip files ("forward", "lateral", "yaw"; "pitch", "roll",
/// "height").
std::string toString(CommandAxis axis);
std::string toString(PostureAxis axis);

}  // namespace pmg
