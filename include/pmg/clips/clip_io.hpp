#pragma once
/// @file clip_io.hpp
/// Reading and writing PMG clip files (versioned YAML text, format described in
/// docs/clip_format.md), part of the clip library pmg::clips. Every clip read is validated by
/// validateClip() (clip_validation.hpp). Setup-time code: allocates and throws pmg::ClipFormatError.
///
/// Reading is strict: an unknown key is an error naming the file, the line, the key and the
/// nearest valid key ("walk.yaml:8: unknown key 'perod' at the top level (did you mean 'period'?)").
///
/// Writing is deterministic: every number is printed with a fixed format ("%.6f", negative zero
/// printed as 0), keys in a fixed order, so the same clip gives a byte-identical file, and
/// read → write of a file written by this library reproduces the file byte for byte.

#include <string>
#include <vector>

#include "pmg/clips/clip_validation.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/generator/clip.hpp"

namespace pmg {

/// Serialises a clip to the clip file text (deterministic). Does not validate.
std::string clipToYaml(const DynamicClip& clip);
std::string clipToYaml(const StaticClip& clip);

/// Writes the clip text to @p path (creating parent directories). The text goes to a temporary
/// file beside @p path first, which is then renamed onto it: a reader never sees half a file.
/// @throws ClipFormatError if the file cannot be written.
void writeClip(const DynamicClip& clip, const std::string& path);
void writeClip(const StaticClip& clip, const std::string& path);

/// Kind of a clip file (`kind:` key).
enum class ClipKind { kDynamic, kStatic };

/// Reads the `kind` of a clip file without validating the rest. @throws ClipFormatError.
ClipKind readClipKind(const std::string& path);

/// Reads and validates a dynamic clip file. @throws ClipFormatError (file, line, field, range),
/// including when format_version is not kClipFormatVersion or `kind` is not "dynamic"; a plain
/// pmg::ConfigError naming the robot config when its joints do not match its URDF (validateClip()).
DynamicClip readDynamicClip(const std::string& path, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});
/// Reads and validates a static clip file. @throws ClipFormatError / ConfigError as above.
StaticClip readStaticClip(const std::string& path, const RobotConfig& robot,
                          const ClipValidationOptions& options = {});

/// File name of the consistency map inside a clip folder (not a clip).
inline constexpr const char* kConsistencyMapFile = "consistency_map.yaml";

/// Serialises / writes / reads a ConsistencyMap (docs/clip_format.md). Reading validates shapes,
/// strictly increasing grids and finite values. @throws ClipFormatError naming file, line and field.
std::string consistencyMapToYaml(const ConsistencyMap& map, const std::string& comment);
void writeConsistencyMap(const ConsistencyMap& map, const std::string& comment, const std::string& path);
ConsistencyMap readConsistencyMap(const std::string& path);

/// Loads every `*.yaml` clip file of a directory (sorted by file name) into a library, and
/// `consistency_map.yaml` (kConsistencyMapFile) into ClipLibrary::consistency when present.
/// @throws ClipFormatError on any invalid file, on two dynamic clips with the same
/// (axis, direction) or two static clips with the same axis, or if the directory does not exist.
ClipLibrary loadClipLibrary(const std::string& directory, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});
/// Loads the listed clip files (in the given order) into a library. @throws ClipFormatError.
ClipLibrary loadClipLibrary(const std::vector<std::string>& files, const RobotConfig& robot,
                            const ClipValidationOptions& options = {});

/// Digest of a clip library's joint data, the policy contract's `pmg.clips_digest`: a policy is run
/// only on the clips it was trained on (docs/policy.md "The contract"). FNV-1a 64-bit over every
/// clip, dynamic and static, in the order of their names: the name's bytes, then each q value
/// (row-major) as the int64 floor(q · 1e4 + 0.5) in 8 little-endian bytes. Returned as
/// "fnv1a64:" and 16 lower-case hex digits. The file formatting does not enter it; a joint value moved by more than
/// 1e-4 rad changes it (up to hash collisions). The training side computes the same
/// (training/pmg_train/contract.py clips_digest).
std::string clipsDigest(const ClipLibrary& library);

}  // namespace pmg
