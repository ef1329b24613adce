#pragma once
/// @file posture_synthesis.hpp
/// Static posture templates measured, corrected and synthesized on the robot itself, with both
/// feet flat on the ground (offline clip building; allocates, throws).
///
/// Why "feet flat": the generator adds a static template's offset q(value) − q(neutral) to the
/// walking joints (eq. 10) and plays it with a level pelvis, but a robot standing on flat feet takes
/// the pelvis tilt that its legs imply: with the captured squat the ankle pitch reaches its limit
/// below 0.6 m and the pelvis tilts back by up to 0.27 rad. What the robot's torso does is the
/// pelvis tilt implied by the feet plus the waist (measure()).
///
/// Frames: W = world, z up, ground z = 0, pelvis yaw 0 (so W is also the heading frame H);
/// B = pelvis (base link); T = torso_link; F = foot (ankle roll) link; S = sole centre (centre of
/// the four sole points of g1SolePoints_F()). Angles as postureValues() (clip_builder.hpp): torso
/// pitch = tilt of T's z axis towards +x (forward positive), roll = towards −y (lean right positive).

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/common/kinematics.hpp"
#include "pmg/generator/clip.hpp"

namespace pmg::motion {

/// What a joint vector implies with both soles flat on the ground.
struct FlatFootPosture {
  Eigen::Quaterniond R_WB = Eigen::Quaterniond::Identity();  ///< pelvis orientation, yaw 0, that puts the soles flat (least squares over both feet)
  double pelvis_roll = 0.0;   ///< [rad] about x of R_WB = Ry(pitch)·Rx(roll)
  double pelvis_pitch = 0.0;  ///< [rad] positive = pelvis tilted forward
  double torso_pitch = 0.0;   ///< torso_link pitch [rad], forward positive
  double torso_roll = 0.0;    ///< torso_link roll [rad], lean right positive
  double pelvis_height = 0.0; ///< pelvis origin above the lowest sole point [m]
  double foot_tilt = 0.0;     ///< largest remaining tilt of a sole from flat [rad] (0 when the two feet are parallel in B)
  std::array<Eigen::Vector3d, kNumFeet> p_WS;  ///< sole centres in W [m] (pelvis at (0, 0, pelvis_height))
  Eigen::Vector3d p_WC = Eigen::Vector3d::Zero();  ///< whole-body centre of mass in W [m] (MuJoCo, the robot's MJCF)
  /// Signed distance of the centre of mass's ground projection from the edge of the support
  /// polygon (convex hull of the 8 sole points) [m]: > 0 inside (statically balanced), < 0 outside.
  double com_margin = 0.0;
};

/// Measures postures on the robot model: KDL forward kinematics of the URDF (legs, torso) and the
/// whole-body centre of mass of the MJCF (MuJoCo). Holds its workspaces (not thread-safe).
class PostureProbe {
 public:
  /// @throws ConfigError / std::runtime_error if the chains (pelvis → feet, pelvis → torso_link) or
  /// the MJCF cannot be loaded, or a robot-config joint is missing from the MJCF (names it).
  explicit PostureProbe(const KinematicModel& model);
  ~PostureProbe();
  PostureProbe(const PostureProbe&) = delete;
  PostureProbe& operator=(const PostureProbe&) = delete;

  /// FlatFootPosture of @p q (n, robot config order [rad]). @throws std::invalid_argument if q has
  /// the wrong size or is not finite, std::runtime_error if forward kinematics fails.
  FlatFootPosture measure(const Eigen::VectorXd& q);

  /// Pose-given measures (no flat-foot solve): for pelvis pose X_WB and q, the torso_link pitch and
  /// roll [rad], the sole-centre poses X_WF·S and the centre of mass in W. Used by the solvers.
  struct Kinematics {
    double torso_pitch = 0.0, torso_roll = 0.0, torso_yaw = 0.0;  ///< torso_link [rad]; yaw = heading of its x axis
    std::array<Eigen::Isometry3d, kNumFeet> X_WF;  ///< foot link poses in W
    Eigen::Vector3d p_WC = Eigen::Vector3d::Zero(); ///< centre of mass in W [m]
  };
  Kinematics kinematics(const Eigen::Isometry3d& X_WB, const Eigen::VectorXd& q);

  const KinematicModel& model() const { return *model_; }

 private:
  struct Impl;
  const KinematicModel* model_;
  std::unique_ptr<Impl> impl_;
};

/// Sets the columns @p joints (robot config indices) of every row of @p clip to those of the
/// neutral row (the row whose value is nearest to clip.neutral): the template no longer moves them.
/// Used for the arms of the squat: CMU 115_07 reaches for a box on the floor, and the arms swinging
/// forward moved the centre of mass 6 cm ahead (outside the support polygon with an upright torso).
/// @throws std::invalid_argument if an index is outside [0, joints of the clip).
void holdJointsAtNeutral(StaticClip& clip, const std::vector<int>& joints);

/// Squat without pitch coupling: for every row of @p clip, waist_pitch_joint is set (secant
/// iteration, clamped to its limits) so that the torso_link pitch with the feet flat equals the one
/// of the neutral row (the row whose value is nearest to clip.neutral). The pelvis tilt that the legs
/// imply is measured, not assumed level. Returns the largest |torso pitch − neutral torso pitch|
/// left over the rows [rad] (> 0 only where the waist pitch reached a limit).
/// @throws std::invalid_argument if the robot has no waist_pitch_joint or the clip's joint count differs.
double holdTorsoPitch(StaticClip& clip, PostureProbe& probe);

/// Options of the synthesized lean (roll) template.
struct LeanOptions {
  double max_roll = 0.25;      ///< largest torso roll [rad], in (0, 0.5)
  int samples_per_side = 5;    ///< rows on each side of the neutral one (K = 2·this + 1), ≥ 1
  double w_feet = 100.0;       ///< sole pose [1/m, 1/rad]: feet planted at the standing pose
  double w_torso = 30.0;       ///< torso roll target, pitch and heading held [1/rad]
  double w_com = 100.0;        ///< centre of mass held over the standing point [1/m]
  double w_posture = 0.03;     ///< pull to the default pose [1/rad]: picks the smallest change
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

/// Result of synthesizeLean(): the clip and how well each row met its targets.
struct LeanSynthesis {
  StaticClip clip;                 ///< values = measured torso_link roll [rad], neutral 0
  double max_foot_error = 0.0;     ///< largest sole position error against the standing pose [m]
  double max_foot_tilt = 0.0;      ///< largest sole orientation error [rad]
  double max_com_shift = 0.0;      ///< largest horizontal centre-of-mass move from standing [m]
  double max_roll_error = 0.0;     ///< largest |measured torso roll − target| [rad]
  double max_pitch_change = 0.0;   ///< largest |torso pitch − standing torso pitch| [rad]
  double max_height_change = 0.0;  ///< largest |pelvis height − standing| [m]
  double min_com_margin = 0.0;     ///< smallest centre-of-mass margin in the support polygon [m]
};

/// The lean (roll) template, synthesized (no side-bend capture is shipped): per target roll ρ in
/// (0, max_roll], Ceres (Levenberg-Marquardt, numeric derivatives of KDL and MuJoCo kinematics)
/// solves for the pelvis position (pelvis kept level: roll 0, pitch 0, yaw 0) and the leg and waist
/// joints (arms at the default pose) minimising
///   w_feet |X_WF − X_WF,stand| (both soles, position and orientation: the feet stay planted flat)
/// + w_torso (torso roll − ρ, torso pitch − standing, torso heading)
/// + w_com |p_WC,xy − p_WC,stand,xy|  (balance: the centre of mass stays over the same point of the feet)
/// + w_posture |q − q_default|,
/// warm-started from the previous ρ. The waist rolls the torso; the legs shift the pelvis sideways
/// against the lean as a parallelogram (hip roll and ankle roll), keeping both leg lengths, so the
/// template adds no leg-length difference to the walking templates it is added to. Negative ρ rows
/// are the left/right mirror (robot mirror map) of the positive ones; the neutral row is the
/// default pose. Values are the torso_link roll measured with the feet flat (PostureProbe::measure).
/// Metadata: provenance "synthesized", retargeting "posture_ik_v1", source_file "" (none), notes
/// say how. @throws std::invalid_argument (options, robot without waist_roll_joint),
/// std::runtime_error if a row misses its targets (foot error > 2 mm, roll error > 0.005 rad) or the
/// measured values are not strictly increasing.
LeanSynthesis synthesizeLean(PostureProbe& probe, const LeanOptions& options = {});

}  // namespace pmg::motion
