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
#include "pmg/clips/clip_transforms.hpp"
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

/// How buildDynamicClip closes the cycle (makes row M equal row 0).
enum class CycleClosing {
  /// The drift x(end) − x(begin) of every column is removed with one zero-mean linear ramp over the
  /// cycle. Right for a steady gait cut between two like events: the drift is small (capture noise)
  /// and spreading it costs nothing.
  kLinearRamp,
  /// The leg joints of foot f (DynamicClipOptions::leg_joints[f]) take their drift only while foot f
  /// is in swing (contact labels of the window), with a raised-cosine rate that is zero at lift-off
  /// and touchdown; the base velocities and height take theirs only in single support (in double
  /// support they are what keeps the two planted soles still against each other); waist and arms
  /// keep the linear ramp.
  /// For a one-shot motion cut from standing to standing (turn in place), whose last stance differs
  /// from the first (CMU 69_17 ends 3 cm wider and with the left foot toed in 10°): corrected while a
  /// foot is in the air, the difference moves where that foot lands instead of sliding the feet
  /// against each other in double support. A leg that has no swing frame in the window falls back
  /// to the linear ramp.
  kInSwing,
};

/// Options of clip building.
struct DynamicClipOptions {
  std::string name;                              ///< clip name, e.g. "walk_forward"
  CommandAxis axis = CommandAxis::kForward;      ///< command component realised
  int num_samples = 96;                          ///< N phase samples, ≥ 8
  double smoothing_sigma = 0.05;                 ///< Gaussian smoothing σ across the cycle [s], ≥ 0
  bool align_on_left_touchdown = true;           ///< φ = 0 at the left foot's touchdown (if it has one)
  CycleClosing closing = CycleClosing::kLinearRamp;  ///< how the cycle is closed
  /// kInSwing only: joint indices (robot config order) of the left and right leg, index Foot, e.g.
  /// KinematicModel::leftLeg().joint_index. Each index in [0, n), no joint in both legs.
  std::array<std::vector<int>, kNumFeet> leg_joints;
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Builds one dynamic clip from frames [window.begin, window.end] of @p motion. Joint angles,
/// base velocities (heading frame H: yaw of the pelvis, z up) and base height are made periodic
/// by removing the drift x(end) − x(begin) over the cycle (options.closing) and smoothing with a circular
/// Gaussian; they are then resampled to N phases with periodic cubic (Catmull-Rom) interpolation
/// and clamped to the joint limits. v_z, ω_x, ω_y get zero cycle mean (height, roll and pitch
/// close). q̇ = central difference in phase / T. direction = sign of the
/// mean command component, x̄ = its magnitude. Metadata other than frames/fps/joint names is left
/// to the caller. @throws std::invalid_argument / std::runtime_error.
DynamicClip buildDynamicClip(const RobotMotion& motion, const ContactSequence& contacts, const CycleWindow& window,
                             const RobotConfig& robot, const DynamicClipOptions& options);

/// Periodic helpers (exposed for tests). Circular Gaussian smoothing of the rows of @p x
/// (M × d) with σ in samples, the kernel cut at ±ceil(truncate_sigmas · σ) samples; σ = 0 returns x.
Eigen::MatrixXd circularGaussianSmooth(const Eigen::MatrixXd& x, double sigma_samples, double truncate_sigmas = 4.0);
/// Periodic Catmull-Rom resampling of M samples (rows, at phases k/M) to N samples at phases k/N.
Eigen::MatrixXd resamplePeriodic(const Eigen::MatrixXd& x, int num_samples);
/// Central difference in phase of N periodic samples, divided by the period: (x[k+1] − x[k−1]) / (2 T / N).
Eigen::MatrixXd periodicDerivative(const Eigen::MatrixXd& x, double period);

}  // namespace pmg::motion

namespace pmg::motion {

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

namespace pmg::motion {

/// Contact labelling of a built dynamic clip from the robot's own feet, as the generator plays the
/// clip: pelvis level (the clip format carries no pelvis roll/pitch), base moved with the clip's
/// v_base and yaw rate. Per phase sample, with h_f the height of sole centre f above the lower of
/// the two sole centres [m] (the lower foot carries the robot: walking always keeps a foot on the
/// ground) and s_rel the horizontal speed of one sole relative to the other [m/s]:
///   1. a foot in contact stays while h_f < exit_height;
///   2. if both feet are then in contact and s_rel >= exit_relative_speed, the foot whose stance
///      started first lifts off (the template legs slide against each other: no base motion can
///      keep both soles still, so it is not double support);
///   3. a foot not in contact touches down when h_f < enter_height and either the other foot is
///      in swing or s_rel < enter_relative_speed.
/// The absolute sole speed is not a criterion: the clip's base velocity differs from the one its
/// stance feet imply by up to 0.7 m/s (pelvis roll/pitch are not in the clip, eqs. 4–5 scale the
/// motion), and making the stance foot still by correcting the base velocity is GCO's job. The
/// relative speed is the part of the foot motion that no base correction removes. The human labels
/// of the retargeting (3 cm, 0.5 m/s on the human foot) put the robot's touchdown while its sole
/// is still 5–30 mm up and slides at 0.2–0.7 m/s against the other foot (docs/motion.md).
struct RobotContactOptions {
  double enter_height = 0.005;         ///< [m], > 0
  double exit_height = 0.010;          ///< [m], >= enter_height
  double enter_relative_speed = 0.20;  ///< [m/s], > 0
  double exit_relative_speed = 0.30;   ///< [m/s], >= enter_relative_speed
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Sole centre tracks of a dynamic clip over its N phase samples (see RobotContactOptions):
/// height(k, f) [m] above the lower sole, speed(k, f) [m/s] horizontal in H; f = Foot index.
struct ClipSoleTracks {
  Eigen::MatrixXd height;  ///< (N × 2)
  Eigen::MatrixXd speed;   ///< (N × 2)
  Eigen::VectorXd relative_speed;  ///< (N) |v_S,left − v_S,right| horizontal [m/s]: no base motion changes it
};

/// Computes ClipSoleTracks by forward kinematics of the leg chains of @p model (base → foot link)
/// with the sole centre of g1SolePoints_F(). @throws std::invalid_argument if the clip's joint
/// count differs from the model's robot, std::runtime_error if forward kinematics fails.
ClipSoleTracks clipSoleTracks(const DynamicClip& clip, const KinematicModel& model);

/// Contact labels of both feet over the N samples of @p tracks (rules of RobotContactOptions),
/// index [Foot][sample]. The state at sample 0 is taken from a first lap around the cycle, so the
/// labels are periodic. @throws std::invalid_argument if the track sizes differ or are 0.
std::array<std::vector<bool>, kNumFeet> robotContactLabels(const ClipSoleTracks& tracks, const RobotContactOptions& options);

/// Replaces the contact model {μ, σ} of both feet of @p clip by the longest run of the robot-foot
/// labels (robotContactLabels on clipSoleTracks), then rotates the samples so that φ = 0 is
/// the left foot's touchdown (pmg::alignPhaseOnLeftTouchdown). @throws std::runtime_error naming the clip and foot if a foot is
/// never in contact, and what clipSoleTracks throws.
void relabelContactsFromRobotFeet(DynamicClip& clip, const KinematicModel& model, const RobotContactOptions& options = {});

/// Left/right-symmetric static clip: every row q becomes ½ (q + M q), with M the robot's mirror
/// map (pmg::mirrorJoints, clip_transforms.hpp). A posture template should move both legs
/// alike; the captured squat and bend are lopsided (e.g. the squat's right hip yaw −0.22 rad against
/// the left +0.01), and added to a walking template in joint space, a lopsided offset lengthens one
/// leg and shortens the other. Joints that mirror onto themselves with sign −1 (waist yaw/roll)
/// become 0. Values and neutral are kept (the capture's pelvis height / torso pitch).
/// @throws std::invalid_argument if the clip's joint count differs from the robot's.
void symmetrizeStaticClip(StaticClip& clip, const RobotConfig& robot);

/// Left/right-symmetric gait: each step of a forward (or backward) walking clip is averaged with the
/// mirror image of the other foot's step, half a cycle on. With h = N / 2 and M the robot's mirror map
/// (pmg::mirrorJoints), every sample k becomes
/// - q(k) ← ½ (q(k) + M q(k + h)), and likewise q̇ [rad, rad/s];
/// - v_base(k) ← ½ (v(k) + S_v v(k + h)), S_v = diag(1, −1, 1) [m/s, heading frame H];
/// - ω_base(k) ← ½ (ω(k) + S_ω ω(k + h)), S_ω = diag(−1, 1, −1) (a pseudo-vector) [rad/s, H];
/// - base_height(k) ← ½ (h(k) + h(k + h)) [m];
/// (indices mod N). Afterwards x(k + h) = M x(k) exactly: the clip walks alike on both feet, so that
/// the generator's reference for a command and for its mirror image (v_y, ω negated) are mirror images
/// half a cycle apart, as a symmetric robot's should be. A captured walk is not: its left and right
/// steps differ (training/README.md "Mirror-symmetry loss": RMS 0.037 rad of 0.127 for the forward
/// walk at 0.5 m/s, 0.068 of 0.095 backward).
/// Contacts: the left foot's μ becomes the circular mean of μ_left and μ_right − ½, its σ the mean of
/// both σ; the right foot's is the left's half a cycle on. Callers with a kinematic model relabel them
/// from the robot's soles (relabelContactsFromRobotFeet), which also realigns φ = 0 on the left
/// touchdown. The implied-motion table is cleared (the clip writer recomputes it); the mean forward
/// velocity, so nominal_scale, is unchanged. Only the forward axis: a side-step or a turn is not its
/// own mirror image (M turns a left side-step into a right one; pmg_make_clips mirrors those instead).
/// @throws std::invalid_argument naming the clip if its joint count differs from the robot's, its
/// sample count is odd (no exact half cycle), or its axis is not forward.
void symmetrizeGaitClip(DynamicClip& clip, const RobotConfig& robot);

}  // namespace pmg::motion

namespace pmg::motion {

/// Leg-direction-preserving posture template (for the height axis). Per row and leg, δ = angle
/// of the vector hip pitch joint → ankle (foot link origin) about the pelvis y axis, minus the
/// same angle in the neutral row; then hip pitch −= δ and ankle pitch += δ (the sole keeps its
/// pitch). The template's leg offsets then change the leg length only, not its direction. Why:
/// the generator adds the template's offset to the walking joints of both legs (eq. 10); an
/// offset that also turns the legs about the hips (the captured squat pushes the hips back, so
/// the feet move ahead of them) lowers a leg that trails behind the pelvis less than one in
/// front, and in double support the two soles end up tens of millimetres apart vertically
/// (docs/gco.md, "Limits"). Needs the leg chains of @p model (first joint = hip pitch about y).
/// @throws std::invalid_argument if the clip's joint count differs from the robot's or a leg joint
/// (`<side>_hip_pitch_joint`, `<side>_ankle_pitch_joint`) is missing; std::runtime_error if
/// forward kinematics fails.
void keepLegDirections(StaticClip& clip, const KinematicModel& model);

}  // namespace pmg::motion

namespace pmg::motion {

/// Options of raiseWalkingHeight. Units: m, rad, phase samples.
struct WalkingHeightOptions {
  /// Share of the gap between the standing pelvis height and the clip's cycle-mean pelvis height
  /// to close, [0, 1]; 0 leaves the clip as it is.
  double fraction = 1.0;
  /// Smallest knee flexion [rad] the raise may leave in either leg, [0, 1]: a leg straighter than
  /// this cannot lengthen further, so the raise shrinks where a knee is near straight (heel strike).
  double min_knee = 0.15;
  /// σ [phase samples] of the truncated circular Gaussian that smooths the per-sample raise (after
  /// a min-filter of ±3σ, so the smoothed raise never exceeds what each sample allows), [0, 10].
  double smoothing_samples = 2.0;
  /// @throws std::invalid_argument naming the field and its range.
  void validate() const;
};

/// What raiseWalkingHeight did to one clip [m].
struct WalkingHeightReport {
  double standing_height = 0.0;  ///< pelvis above the lower sole centre in the standing pose
  double mean_height_before = 0.0;  ///< cycle mean of the same in the clip, before
  double mean_height_after = 0.0;   ///< and after
  double target_raise = 0.0;     ///< fraction × (standing − mean before), >= 0
  double min_raise = 0.0;        ///< the smallest per-sample raise applied (knee-limited samples)
};

/// Raises the pelvis of a walking template towards the standing height (beyond the paper; issue 12:
/// the captured gaits carry the pelvis 10–35 mm below the standing pose's, so a robot that
/// tracks them walks below a commanded standing height). Per phase sample k the pelvis rises by
/// d_k: both sole centres move d_k down along the pelvis z axis (the clip's pelvis is level), keeping
/// their horizontal place and their orientation in the pelvis frame, by solving each leg's six joints
/// (Newton on the KDL chain of @p model, finite-difference Jacobian); no other joint changes.
/// d_k = the target raise, or less where a knee would straighten beyond options.min_knee or a joint
/// would leave its limits (bisection), then min-filtered and smoothed (options.smoothing_samples).
/// The relative sole heights, and so the contact labels, are unchanged; base_height gains d_k,
/// v_base z its phase derivative, and q̇ is recomputed (periodicDerivative). Pelvis height of a
/// pose = the height of the pelvis above the lower of the two sole centres (g1SolePoints_F mean).
/// @param q_stand the standing pose (n, config order) [rad]. @throws std::invalid_argument if the
/// clip's or q_stand's joint count differs from the robot's, a leg chain has not 6 joints, the knee
/// joint is missing, or the options
/// are out of range; std::runtime_error if forward kinematics fails.
WalkingHeightReport raiseWalkingHeight(DynamicClip& clip, const KinematicModel& model, const Eigen::VectorXd& q_stand,
                                       const WalkingHeightOptions& options = {});

}  // namespace pmg::motion
