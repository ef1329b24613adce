#pragma once
/// @file clip.hpp
/// Motion clip data types of the Parameterized Motion Generator (PMG).
///
/// A *dynamic* clip is one gait cycle of a periodic motion (walk forward, walk sideways, turn),
/// sampled at N equally spaced phases φ_k = k / N, k = 0..N-1 (φ ∈ [0, 1), sample N would equal
/// sample 0). A *static* clip is a posture template sampled over a command range (squat = height,
/// bend = pitch, lean = roll). Source: PMG "Motion Preprocessing" (D_robot^d-clip, D_robot^s).
///
/// Clips are immutable after loading (Model/Data split): the generator only reads them.
/// The on-disk format (versioned YAML) is documented in docs/clip_format.md and read/written by
/// the clip library pmg::clips (include/pmg/clips/clip_io.hpp), which also holds the one clip
/// validation (clip_validation.hpp) and the clip transforms (clip_transforms.hpp).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace pmg {

/// Current clip file format version (`format_version` in the file).
inline constexpr int kClipFormatVersion = 1;

/// Which velocity-command component a dynamic clip realises (u_d = (v_x, v_y, ω)).
enum class CommandAxis : int {
  kForward = 0,  ///< v_x, base linear velocity along heading x [m/s]
  kLateral = 1,  ///< v_y, base linear velocity along heading y (left positive) [m/s]
  kYaw = 2,      ///< ω, base yaw rate about world z (counter-clockwise positive) [rad/s]
};
inline constexpr std::size_t kNumCommandAxes = 3;

/// Which posture-command component a static clip realises (u_s = (pitch, roll, height)).
enum class PostureAxis : int {
  kPitch = 0,   ///< torso forward bend [rad], positive = bend forward
  kRoll = 1,    ///< torso side lean [rad], positive = lean right (roll about +x)
  kHeight = 2,  ///< pelvis height above ground [m]
};
inline constexpr std::size_t kNumPostureAxes = 3;

/// Feet, in the order used by every contact array.
enum class Foot : int { kLeft = 0, kRight = 1 };
inline constexpr std::size_t kNumFeet = 2;

/// Contact schedule of one foot over the cycle: in contact while the circular phase distance
/// |φ − μ| < σ (PMG contact model c = {μ, σ}). μ ∈ [0, 1), σ ∈ [0, 0.5] (0.5 = always in contact).
struct FootContact {
  double mu = 0.0;     ///< contact centre [phase units, 0..1)
  double sigma = 0.5;  ///< contact half-range [phase units, 0..0.5]
};

/// Provenance and bookkeeping stored with every clip (written into the clip file).
struct ClipMetadata {
  int format_version = kClipFormatVersion;
  std::string source_file;   ///< mocap file the clip was cut from (path relative to the data root)
  std::string license;       ///< license of the source data (e.g. "MIT (DeepMimic)")
  std::string robot;         ///< robot model name, e.g. "unitree_g1_29dof_rev_1_0"
  std::vector<std::string> joint_names;  ///< joint order of every q row (size n)
  int frame_begin = 0;       ///< first source frame used (inclusive)
  int frame_end = 0;         ///< last source frame used (exclusive)
  double source_fps = 0.0;   ///< source frame rate [Hz]
  /// "mocap" (retargeted real capture), "mocap_mirrored" (left/right mirror of a real capture),
  /// "mocap_time_reversed" or "synthesized" (not from capture; must be declared as such).
  std::string provenance = "mocap";
  std::string retargeting;   ///< retargeting method, e.g. "ceres_keypoints_v1"
  std::string notes;         ///< free text (what was done to the data)
};

/// Stance-implied motion of a dynamic clip played alone at amplitude a (beyond the paper; used by
/// the generator's command-consistent blending, docs/generator.md): the clip's joints are scaled
/// about the standing pose, q(φ) = q_stand + a (q_D(φ) − q_stand), and played at the clip's period
/// T; the table holds the cycle mean of the base velocity that holds the stance soles still
/// (pmg::gco::stanceImpliedVelocity over the clip's contact schedule). Computed with the robot's
/// leg kinematics by pmg::gco::computeImpliedMotion (include/pmg/gco/implied_motion.hpp) and stored
/// in the clip file (`implied_motion:`, docs/clip_format.md). Empty when a clip has none.
/// Shapes: K amplitudes (K ≥ 2, strictly increasing, amplitude(0) = 0) × 3.
struct ImpliedMotionTable {
  Eigen::VectorXd amplitude;  ///< (K) a_k [-], a_0 = 0
  Eigen::MatrixXd velocity;   ///< (K × 3) (v_x [m/s], v_y [m/s], ω [rad/s]) in the heading frame H at period T
  bool empty() const { return amplitude.size() == 0; }
};

/// One gait cycle (PMG dynamic clip {q, q̇, v, ω, c, T}).
/// Shapes: N samples (rows) × n joints (columns). N ≥ 2.
struct DynamicClip {
  std::string name;                   ///< e.g. "walk_forward"
  CommandAxis axis = CommandAxis::kForward;
  int direction = +1;                 ///< sign of the command the clip realises (+1 or -1), e.g. -1 on kForward = walking backward
  double nominal_scale = 1.0;         ///< x̄: mean command the clip realises, > 0 [m/s or rad/s] (PMG eq. 4)
  double period = 1.0;                ///< T: cycle duration [s], > 0 (PMG eq. 12)
  Eigen::MatrixXd q;                  ///< (N × n) joint positions [rad]
  Eigen::MatrixXd qd;                 ///< (N × n) joint velocities dq/dt [rad/s]
  Eigen::MatrixXd v_base;             ///< (N × 3) pelvis linear velocity in the heading frame [m/s]
  Eigen::MatrixXd omega_base;         ///< (N × 3) pelvis angular velocity in the heading frame [rad/s]
  Eigen::VectorXd base_height;        ///< (N) pelvis height above the ground [m]
  std::array<FootContact, kNumFeet> contact{};  ///< per foot, order Foot::kLeft, Foot::kRight
  ImpliedMotionTable implied;         ///< optional (empty: the generator derives a linear table from v_base/omega_base)
  ClipMetadata meta;

  std::size_t numSamples() const { return static_cast<std::size_t>(q.rows()); }
  std::size_t numJoints() const { return static_cast<std::size_t>(q.cols()); }
};

/// A posture template over its command range (PMG static clip).
/// Shapes: K samples (rows, strictly increasing `values`) × n joints. K ≥ 2.
struct StaticClip {
  std::string name;                   ///< e.g. "squat"
  PostureAxis axis = PostureAxis::kHeight;
  Eigen::VectorXd values;             ///< (K) command values, strictly increasing [rad or m]
  double neutral = 0.0;               ///< command value of the unmodified standing posture
  Eigen::MatrixXd q;                  ///< (K × n) joint positions at each value [rad]
  ClipMetadata meta;

  std::size_t numSamples() const { return static_cast<std::size_t>(q.rows()); }
  std::size_t numJoints() const { return static_cast<std::size_t>(q.cols()); }
};

/// Residual command correction of the command-consistent blending (docs/generator.md): on a grid
/// over (v_x, v_y, ω, height, pitch) the correction Δu such that the blended gait generated for u + Δu
/// implies, by its stance feet, the base motion u (found offline by fixed-point iteration with the
/// robot's leg kinematics, pmg::gco::computeConsistencyMap). Covers what the per-clip tables cannot:
/// channel interactions (e.g. side-stepping while turning) and the leg geometry of a squat or bend.
/// Read from `consistency_map.yaml` beside the clips (docs/clip_format.md); empty = no correction.
/// Shapes: grid[d] strictly increasing (size ≥ 1 each, d = v_x [m/s], v_y [m/s], ω [rad/s],
/// height [m], pitch [rad]); delta (n_vx·n_vy·n_ω·n_h·n_p × 3), row (((i·n_vy + j)·n_ω + k)·n_h + l)·n_p + m,
/// columns (Δv_x [m/s], Δv_y [m/s], Δω [rad/s]).
inline constexpr std::size_t kConsistencyMapDims = 5;
struct ConsistencyMap {
  std::array<Eigen::VectorXd, kConsistencyMapDims> grid;
  Eigen::MatrixXd delta;
  bool empty() const { return delta.rows() == 0; }
};

/// The clip library a generator is built from.
struct ClipLibrary {
  std::vector<DynamicClip> dynamic_clips;  ///< at most one per (axis, direction sign)
  std::vector<StaticClip> static_clips;    ///< at most one per posture axis
  ConsistencyMap consistency;              ///< optional (kConsistent blending only)
};

}  // namespace pmg
