#pragma once
/// @file clip_io.hpp
/// Reading, writing and validating PMG clip files (versioned YAML text, format described in
/// docs/clip_format.md). Setup-time code: allocates and throws pmg::ClipFormatError.
///
/// Writing is deterministic: every number is printed with a fixed format ("%.6f", negative zero
/// printed as 0), keys in a fixed order, so the same clip gives a byte-identical file, and
/// read → write of a file written by this library reproduces the file byte for byte.

#include <stdexcept>
#include <string>
#include <vector>

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/clip.hpp"

namespace pmg {

/// Error raised by every clip reader/validator. what() names the file, the field (with row/column
/// index where it applies), the offending value and the expected range, e.g.
/// "config/clips/g1/walk_forward.yaml:12: q[3][4] = 0.61: expected within joint limits
///  [-0.87267, 0.5236] of left_ankle_pitch_joint".
class ClipFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Options of clip validation.
struct ClipValidationOptions {
  /// Allowed excursion beyond a joint limit [rad] (covers the 1e-6 rounding of the text format).
  double limit_tolerance = 1e-6;
  /// Check that the joint names equal the robot config's joint order (else only the count).
  bool check_joint_names = true;
  /// @throws ClipFormatError if limit_tolerance is negative or not finite.
  void validate() const;
};

/// Checks a dynamic clip against the robot: shapes (N ≥ 2 rows; q, qd: N × n; v_base, omega_base:
/// N × 3; base_height: N), joint names = robot joint order, μ ∈ [0, 1), σ ∈ [0, 0.5], T > 0,
/// x̄ > 0, direction ±1, all values finite, base_height > 0, every q within the robot's joint
/// limits. @param where names the source in messages (file name or clip name).
/// @throws ClipFormatError naming @p where, the field and the expected range.
void validateClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options = {});

/// Checks a static clip: K ≥ 2 strictly increasing finite values, q: K × n within joint limits,
/// neutral within [values.front(), values.back()], joint names = robot order.
/// @throws ClipFormatError.
void validateClip(const StaticClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options = {});

/// Serialises a clip to the clip file text (deterministic). Does not validate.
std::string clipToYaml(const DynamicClip& clip);
std::string clipToYaml(const StaticClip& clip);

/// Writes the clip text to @p path (creating parent directories).
/// @throws ClipFormatError if the file cannot be written.
void writeClip(const DynamicClip& clip, const std::string& path);
void writeClip(const StaticClip& clip, const std::string& path);

/// Kind of a clip file (`kind:` key).
enum class ClipKind { kDynamic, kStatic };

/// Reads the `kind` of a clip file without validating the rest. @throws ClipFormatError.
ClipKind readClipKind(const std::string& path);

/// Reads and validates a dynamic clip file. @throws ClipFormatError (file, line, field, range),
/// including when format_version is not kClipFormatVersion or `kind` is not "dynamic".
DynamicClip readDynamicClip(const std::string& path, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});
/// Reads and validates a static clip file. @throws ClipFormatError.
StaticClip readStaticClip(const std::string& path, const RobotConfig& robot,
                          const ClipValidationOptions& options = {});

/// Loads every `*.yaml` clip file of a directory (sorted by file name) into a library.
/// @throws ClipFormatError on any invalid file, on two dynamic clips with the same
/// (axis, direction) or two static clips with the same axis, or if the directory does not exist.
ClipLibrary loadClipLibrary(const std::string& directory, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});
/// Loads the listed clip files (in the given order) into a library. @throws ClipFormatError.
ClipLibrary loadClipLibrary(const std::vector<std::string>& files, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});

/// Text names of the enums as used in the file ("forward", "lateral", "yaw"; "pitch", "roll",
/// "height").
std::string toString(CommandAxis axis);
std::string toString(PostureAxis axis);

}  // namespace pmg
