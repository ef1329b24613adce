#pragma once
/// @file mujoco_model.hpp
/// Loading the robot MJCF into MuJoCo 2.2 (the SIL and calibration simulator).
///
/// Unitree's G1 MJCF targets newer MuJoCo releases; MuJoCo 2.2.2 rejects it as shipped
/// (config/robots/g1/SOURCE.md). adaptMjcfForMujoco22() is the one reproducible, documented
/// transform (docs/robot_model.md) applied in memory at load time; the shipped file stays pristine:
///  1. delete every `actuatorfrcrange` / `actuatorfrclimited` attribute (2.2 does not know them;
///     torque limits are enforced by the motor model from the robot config instead);
///  2. `<compiler autolimits="true">` (2.2 otherwise rejects `range` without `limited`), and an
///     absolute `meshdir` so the text can be loaded from any folder;
///  3. `<option timestep>` = the requested physics step; `<size nconmax="500" njmax="2000"/>`
///     (the default contact buffer overflows when the robot falls);
///  4. `<default><joint armature damping frictionloss/>` with Unitree's unitree_mujoco values
///     (armature 0.01 kg·m², damping 0.05 N·m·s/rad, frictionloss 0.2 N·m); without armature the
///     stiff motor-level PD at 1 kHz is unstable;
///  5. a `framequat` sensor on the IMU site (orientation of the IMU frame in world, w x y z), as an
///     IMU's attitude filter would report it.

#include <cstddef>
#include <memory>
#include <string>

#include <mujoco/mujoco.h>

namespace pmg {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

/// While alive, MuJoCo's fatal errors (mju_error) call @p handler instead of MuJoCo's default, which
/// prints, waits for Enter and exits the process; the previous handler comes back on destruction. A
/// handler may throw: libmujoco is built with unwind tables, so the exception crosses its C frames (what
/// MuJoCo had allocated in the failed call is lost). mju_user_error is process-wide: setup code only.
class ScopedMujocoErrorHandler {
 public:
  explicit ScopedMujocoErrorHandler(void (*handler)(const char*)) : previous_(mju_user_error) {
    mju_user_error = handler;
  }
  ~ScopedMujocoErrorHandler() { mju_user_error = previous_; }
  ScopedMujocoErrorHandler(const ScopedMujocoErrorHandler&) = delete;
  ScopedMujocoErrorHandler& operator=(const ScopedMujocoErrorHandler&) = delete;

 private:
  void (*previous_)(const char*);
};

/// Options of the MuJoCo 2.2 adaptation.
struct Mujoco22Options {
  double timestep = 0.001;      ///< physics step [s] (≥ 1 kHz for the SIL), in (0, 0.01]
  double armature = 0.01;       ///< default joint armature (rotor inertia at the joint) [kg·m²]
  double damping = 0.05;        ///< default joint viscous damping [N·m·s/rad]
  double frictionloss = 0.2;    ///< default joint dry friction [N·m]
  std::string imu_site = "imu_in_pelvis";  ///< site that gets the framequat sensor "<site>-orientation"
};

/// @p mjcf_text with its `<compiler meshdir>` made absolute against @p mjcf_dir (the folder of the
/// file it came from; a missing meshdir becomes that folder), so the text can be written and loaded
/// from any folder. @throws std::runtime_error if the text has no `<compiler>` element.
std::string withAbsoluteMeshdir(const std::string& mjcf_text, const std::string& mjcf_dir);

/// Returns the MJCF text adapted for MuJoCo 2.2 (see file comment). @p mjcf_dir is the folder of
/// the original file, used to make `meshdir` absolute. @throws std::runtime_error if the text has
/// no `<compiler>` or `<sensor>`/`</mujoco>` element to anchor the edits.
std::string adaptMjcfForMujoco22(const std::string& mjcf_text, const std::string& mjcf_dir,
                                 const Mujoco22Options& options = {});

/// Reads @p mjcf_path, adapts it and compiles it with MuJoCo 2.2.
///
/// Compiled-model cache (opt-in): when the environment variable `PMG_MJCF_CACHE_DIR` names a folder
/// (created if missing), the compiled model is kept there as `<key>.mjb` (MuJoCo's binary model) with
/// `<key>.mjb.b2`, the BLAKE2b-256 of its bytes. The key is the BLAKE2b-256 of the adapted text, the
/// content of every file its `file="..."` attributes name (meshes resolved against the absolute
/// meshdir, else the MJCF's folder), MuJoCo's run-time version and sizeof(mjtNum); a file that cannot
/// be found disables the cache for that load. A later load with the same key reads the binary instead
/// of compiling (the G1: 0.36-0.51 s of compile, mostly qhull's convex hulls, against 0.08-0.11 s, most of
/// it hashing the 19 MB of meshes and checking the 15 MB image), and the model is the same bytes
/// (test_mujoco_model). An entry whose checksum does not match its
/// bytes, or that MuJoCo rejects, is counted (mujocoModelCacheStats().rejected), reported on stderr,
/// compiled again and rewritten. Entries are written to a private temporary file and renamed into
/// place, so concurrent processes never read a partial entry. The folder keeps at most
/// kMujocoModelCacheMaxEntries entries: storing one more removes the least recently used (about 15 MB each
/// for the G1). scripts/run_tests.sh sets the variable
/// (build/mjcf_cache); unset, nothing is read or written. Not for the real-time path: it allocates
/// and does file I/O, like the compile it replaces.
/// @throws std::runtime_error with MuJoCo's message and the file name on failure.
MjModelPtr loadMujocoModel(const std::string& mjcf_path, const Mujoco22Options& options = {});

/// Entries the compiled-model cache keeps in its folder (loadMujocoModel).
inline constexpr std::size_t kMujocoModelCacheMaxEntries = 32;

/// Counters of the compiled-model cache since the process started (all loads, every thread).
struct MujocoModelCacheStats {
  long hits = 0;      ///< loads served from an entry
  long misses = 0;    ///< loads with the cache on that compiled (no entry, or a rejected one)
  long rejected = 0;  ///< entries found but not used: checksum mismatch, unreadable, or refused by MuJoCo
  long stored = 0;    ///< entries written
};
MujocoModelCacheStats mujocoModelCacheStats();

}  // namespace pmg
