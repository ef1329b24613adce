#pragma once
/// @file clip_builder.hpp
/// Turns a retargeted robot trajectory (RobotMotion) into PMG clips (seed: D_robot^d →
/// D_robot^d-clip): contact detection, gait-cycle segmentation aligned on contact, periodic
/// closing with Gaussian smoothing across the cycle boundary, resampling to N phase samples,
/// finite differences in phase, contact model {μ, σ}, period T and nominal scale x̄.
/// Setup-time code (allocates, throws std::invalid_argument / std::runtime_error).

#include <array>
#include <string>
#include <vector>

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/clip.hpp"
#include "pmg/motion/robot_motion.hpp"

namespace pmg::motion {

/// Contact detection thresholds. A foot is in contact in a frame when its lowest sole point is
/// below `height_threshold` above the ground AND the horizontal speed of its sole centre is below
/// `speed_threshold`; runs shorter than `min_frames` frames (either state) are merged into their
/// surroundings (debouncing).
struct ContactOptions {
  double height_threshold = 0.02;  ///< [m], > 0
  double speed_threshold = 0.6;    ///< [m/s], > 0
  int min_frames = 2;              ///< ≥ 1
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Per-frame contact flags, index [frame][Foot].
using ContactSequence = std::vector<std::array<bool, kNumFeet>>;

/// Detects contacts from RobotMotion::p_WS (needs placeOnGround() first). @throws std::invalid_argument.
ContactSequence detectContacts(const RobotMotion& motion, const ContactOptions& options = {});

/// Contact events of one foot.
enum class ContactEvent { kTouchdown, kLiftoff };

/// Frames of `foot`'s events of kind `event` in [search_begin, search_end) (frame k is a touchdown
/// if the foot is in contact at k and not at k − 1; liftoff the reverse).
std::vector<int> findContactEvents(const ContactSequence& contacts, Foot foot, ContactEvent event, int search_begin,
                                   int search_end);

/// One gait cycle of a motion: frames [begin, end), end − begin = frames per cycle; frame `end`
/// (which must exist) is the same gait state one cycle later.
struct CycleWindow {
  int begin = 0;
  int end = 0;
};

/// First cycle between two consecutive `event`s of `foot` that both lie in [search_begin, search_end).
/// @throws std::runtime_error if fewer than two events are found (names foot, event and window).
CycleWindow findGaitCycle(const ContactSequence& contacts, Foot foot, ContactEvent event, int search_begin,
                          int search_end);

/// Contact model of one foot from its flags over one cycle (phase k / M): μ = centre of the longest
/// circular run of contact, σ = half its length. Always in contact → {0.5, 0.5}; never → {0, 0}.
FootContact contactModel(const std::vector<bool>& in_contact);

/// Options of clip building.
struct DynamicClipOptions {
  std::string name;                              ///< clip name, e.g. "walk_forward"
  CommandAxis axis = CommandAxis::kForward;      ///< command component realised
  int num_samples = 96;                          ///< N phase samples, ≥ 8
  double smoothing_sigma = 0.05;                 ///< Gaussian smoothing σ across the cycle [s], ≥ 0
  bool align_on_left_touchdown = true;           ///< φ = 0 at the left foot's touchdown (if it has one)
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Builds one dynamic clip from frames [window.begin, window.end] of @p motion. Joint angles,
/// base velocities (heading frame H: yaw of the pelvis, z up) and base height are made periodic
/// by removing the linear drift x(end) − x(begin) over the cycle and smoothing with a circular
/// Gaussian; they are then resampled to N phases with periodic cubic (Catmull-Rom) interpolation
/// and clamped to the joint limits. v_z, ω_x, ω_y get zero cycle mean (height, roll and pitch
/// close). q̇ = central difference in phase / T. direction = sign of the
/// mean command component, x̄ = its magnitude. Metadata other than frames/fps/joint names is left
/// to the caller. @throws std::invalid_argument / std::runtime_error.
DynamicClip buildDynamicClip(const RobotMotion& motion, const ContactSequence& contacts, const CycleWindow& window,
                             const RobotConfig& robot, const DynamicClipOptions& options);

/// Periodic helpers (exposed for tests). Circular Gaussian smoothing of the rows of @p x
/// (M × d) with σ in samples; σ = 0 returns x.
Eigen::MatrixXd circularGaussianSmooth(const Eigen::MatrixXd& x, double sigma_samples);
/// Periodic Catmull-Rom resampling of M samples (rows, at phases k/M) to N samples at phases k/N.
Eigen::MatrixXd resamplePeriodic(const Eigen::MatrixXd& x, int num_samples);
/// Central difference in phase of N periodic samples, divided by the period: (x[k+1] − x[k−1]) / (2 T / N).
Eigen::MatrixXd periodicDerivative(const Eigen::MatrixXd& x, double period);

}  // namespace pmg::motion

namespace pmg::motion {

/// Left↔right mirror of a dynamic clip with the robot's mirror map (RobotConfig joints' `mirror`
/// and `mirror_sign`): q'_j = sign_j · q_mirror(j) (same for q̇); v' = (v_x, −v_y, v_z);
/// ω' = (−ω_x, ω_y, −ω_z); contacts swapped; lateral and yaw clips change direction. The samples
/// are rotated so that φ = 0 stays at the (new) left foot's touchdown. Sets provenance
/// "mocap_mirrored" (a mirrored synthesized clip stays "synthesized") and appends to notes.
/// @throws std::invalid_argument if the clip's joint count differs from the robot's.
DynamicClip mirrorClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& new_name);

/// Options of static clip building.
struct StaticClipOptions {
  std::string name;                          ///< e.g. "squat"
  PostureAxis axis = PostureAxis::kHeight;   ///< posture command realised
  int num_samples = 16;                      ///< K, ≥ 2
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Posture command value of every frame of a robot motion: pelvis height above the ground [m]
/// (kHeight), torso forward pitch [rad] (kPitch: tilt of torso_link's z axis towards the pelvis
/// heading, positive forward) or torso roll [rad] (kRoll: tilt towards −y of the heading frame,
/// positive = lean right). Needs the chain base → torso_link of @p model.
Eigen::VectorXd postureValues(const RobotMotion& motion, const KinematicModel& model, PostureAxis axis);

/// Builds a static clip from the frames [begin, end] of @p motion, which go from the neutral
/// posture (frame begin) towards the extreme one (frame end): the posture value is made monotone
/// (running extreme), K values are spaced evenly between the neutral and the extreme value, and q
/// is interpolated linearly in the frames where the monotone value crosses each of them. Rows are
/// sorted by increasing value; `neutral` = the value of frame begin.
/// @throws std::invalid_argument if the range is empty or the value does not change by > 1e-3.
StaticClip buildStaticClip(const RobotMotion& motion, const Eigen::VectorXd& values, int begin, int end,
                           const RobotConfig& robot, const StaticClipOptions& options);

}  // namespace pmg::motion
