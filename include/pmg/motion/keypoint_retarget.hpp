#pragma once
/// @file keypoint_retarget.hpp
/// Optimisation-based retargeting "ceres_keypoints_v1" (seed: human mocap → D_robot^d).
///
/// Per frame, Ceres (Levenberg-Marquardt, dense QR, central numeric derivatives of a KDL forward
/// kinematics pass) solves for the robot base pose x_B = (p_WB [m], roll/pitch/yaw [rad], R_WB =
/// Rz·Ry·Rx) and the joint angles q (n, bounded by the joint limits) that minimise
///   Σ w_kp |p_WK(x) − p̂_WK|²                  keypoints: knees, ankles, toes, shoulders, elbows,
///                                               wrists (+ pelvis position, weak in z)
/// + w_ori (|log R̂ᵀR|²) for pelvis, torso and feet
/// + w_contact (|p_xy − anchor|² + |z_ankle − z_flat|² + |flatness|²) for feet in contact
/// + w_ground Σ max(0, −z_sole)²                 no ground penetration (4 sole points per foot)
/// + w_smooth |x − x_prev|²                      temporal smoothness (warm-started sequence)
/// + w_posture |q − q_default|²                  resolves unobserved joints (wrists)
/// Targets p̂ handle the size difference by scaling: the pelvis position is scaled by s
/// (robot/human leg length), and each limb keypoint is placed from its parent target along the
/// human segment direction with the robot's segment length (hip → knee → ankle, shoulder → elbow
/// → wrist); toes = ankle + R̂_foot·(kToeOffset, 0, 0). Contacts are detected on the human
/// (foot height and speed thresholds), or set by hand over spans of frames (ContactOverride); during
/// a contact run the robot foot is held at the run's mean target position (unsliding), flat, on the ground.
/// Setup-time/offline code (allocates, throws).

#include <array>
#include <string>
#include <vector>

#include "pmg/common/kinematics.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/motion/human_motion.hpp"
#include "pmg/motion/robot_motion.hpp"

namespace pmg::motion {

/// A span of frames in which the contact label of one foot is set by hand instead of detected on
/// the human. Used where the human's foot does something the robot's flat, rigid sole cannot: in
/// CMU 69_17 (turn in place) the left foot pivots 83° on the ground while barely unloaded (ankle up
/// 2 cm, still "in contact" by the thresholds); a stance foot that turns under load is not a stance
/// that GCO can hold still, so the robot steps instead (a forced swing with clearance).
struct ContactOverride {
  Foot foot = Foot::kLeft;
  int begin = 0;            ///< first frame (inclusive), index into the motion passed to retargetKeypoints
  int end = 0;              ///< last frame (exclusive), begin < end <= frames
  bool contact = false;     ///< label forced over [begin, end)
  /// Swing only (contact = false): the foot's ankle and toe targets are raised by
  /// clearance · sin(π s), s = (k − begin + ½) / (end − begin), on top of the human's own lift [m], ≥ 0.
  double clearance = 0.0;
};

struct KeypointRetargetOptions {
  double scale = 0.0;              ///< human → robot length scale; ≤ 0: robot leg / human leg length
  /// true: limb targets along the human segment directions with the robot's segment lengths;
  /// false: every keypoint target = scale · human keypoint (exact for motions generated from the
  /// robot itself, used by the recovery test).
  bool segment_directions = true;
  double w_keypoint = 1.0;         ///< limb keypoints [1/m]
  double w_foot_keypoint = 3.0;    ///< ankle and toe keypoints [1/m]
  double w_pelvis_xy = 1.0;        ///< pelvis horizontal position [1/m]
  double w_pelvis_z = 0.2;         ///< pelvis height [1/m] (weak: feet and ground decide)
  double w_orientation = 0.5;      ///< pelvis and torso orientation [1/rad]
  double w_foot_orientation = 0.3; ///< foot orientation [1/rad]
  double w_contact = 10.0;         ///< stance foot anchor/flat/on-ground [1/m, 1/rad]
  double w_ground = 30.0;          ///< ground penetration hinge [1/m]
  double w_smooth = 0.01;          ///< change from the previous frame [1/rad, 1/m]
  double w_posture = 0.003;        ///< pull to the default pose [1/rad]
  int max_iterations = 60;         ///< Ceres iterations per frame, ≥ 1
  /// true: pelvis roll and pitch held at 0 (the solve moves only the pelvis position and yaw; the
  /// legs, waist and arms take up the human pelvis tilt). Used for the dynamic clips: the clip
  /// format has no pelvis orientation and the generator and GCO play a clip with a level pelvis,
  /// so with a tilting pelvis in the retargeting the feet of the played clip would not be where
  /// the retargeting put them (stances slide, double support vanishes).
  bool level_pelvis = false;
  double contact_height = 0.03;    ///< human foot (min of ankle, toe) above its flat height [m]
  double contact_speed = 0.5;      ///< human ankle horizontal speed [m/s]
  /// Swing ends blended onto the stances [s], ≥ 0 (0 = off). A stance foot is held at its run's
  /// anchor (the mean of the run's target ankle positions), but the targets themselves move during
  /// the stance as the pelvis turns over the foot (robot and human hips differ); when the contact
  /// term releases, the foot snaps to the first swing target (3 cm in one frame at lift-off of the
  /// long right stance of the turn in place). With swing_blend > 0 the ankle and toe targets of the
  /// swing frames within swing_blend of a stance run of the same foot are moved horizontally towards
  /// that run's anchor with weight ½ (1 + cos(π d / (swing_blend · fps))), d = frames from the run.
  double swing_blend = 0.0;
  /// Hand-set contact labels applied after detection, in order (later spans win). Checked by
  /// retargetKeypoints against the motion's frame count (std::invalid_argument naming the span).
  std::vector<ContactOverride> contact_overrides;
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Target keypoints of one frame, robot scale, W [m].
using KeypointTargets = std::array<Eigen::Vector3d, kNumKeypoints>;

/// Quality numbers of a retargeted motion (over a frame window).
struct RetargetStats {
  double keypoint_error_mean = 0.0;  ///< mean |robot − target| over limb keypoints and frames [m]
  double keypoint_error_max = 0.0;   ///< max of the same [m]
  int joint_limit_violations = 0;    ///< samples outside the limits (bounds: must be 0)
  int stances = 0;                   ///< contact runs fully inside the window
  double skate_mean_mm = 0.0;        ///< mean over stances of the sole's max horizontal drift [mm]
  double skate_max_mm = 0.0;         ///< max of the same [mm]
  double penetration_max_mm = 0.0;   ///< deepest sole point below the ground [mm]
  double solve_ms_per_frame = 0.0;   ///< mean Ceres time per frame [ms]
};

struct RetargetResult {
  RobotMotion motion;                    ///< q, base pose, sole tracks (p_WS filled)
  ContactSequence contacts;              ///< human contacts the solve enforced
  std::vector<KeypointTargets> targets;  ///< (F) targets, robot scale
  std::vector<KeypointTargets> achieved; ///< (F) robot keypoints after the solve
  std::vector<KeypointTargets> human;    ///< (F) the human keypoints × scale (same vertical shift), for plots
  double scale = 1.0;                    ///< the s used
  double solve_ms_per_frame = 0.0;
};

/// Human contact detection (see KeypointRetargetOptions::contact_height/contact_speed), then the
/// contact_overrides. @throws std::invalid_argument if an override lies outside the motion's frames,
/// is empty or has a negative / non-finite clearance or a clearance on a contact span.
ContactSequence detectHumanContacts(const HumanMotion& human, const KeypointRetargetOptions& options);

/// Retargets @p human onto the robot of @p model. @throws std::invalid_argument / std::runtime_error.
RetargetResult retargetKeypoints(const HumanMotion& human, const KinematicModel& model,
                                 const KeypointRetargetOptions& options = {});

/// Statistics over frames [begin, end) of a result. @throws std::out_of_range.
RetargetStats retargetStats(const RetargetResult& result, const RobotConfig& robot, int begin, int end);

/// Writes frames [begin, end) of a result as CSV (frame, source = human|target|robot, keypoint, x,
/// y, z [m, W], contact_left, contact_right) for scripts/motion_plot_retarget.py. @throws std::runtime_error.
void writeRetargetCsv(const RetargetResult& result, const std::string& path, int begin, int end);

/// Robot keypoints (same set/meaning as the human ones) for base pose and q, by KDL forward
/// kinematics: hips = hip roll link origins, knees = knee links, ankles = ankle roll links,
/// toes = ankle roll link + R·(kToeOffset, 0, 0), shoulders = shoulder roll links, elbows = elbow
/// links, wrists = wrist roll links. Also returns torso and foot orientations in W.
/// Used to build synthetic motions for tests. @throws std::runtime_error.
HumanFrame robotKeypoints(const KinematicModel& model, const Eigen::Isometry3d& X_WB, const Eigen::VectorXd& q);

}  // namespace pmg::motion
