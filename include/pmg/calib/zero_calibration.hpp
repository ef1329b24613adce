#pragma once
/// @file zero_calibration.hpp
/// Zero-point (encoder offset) calibration of the 12 leg joints by Motor–IMU alignment
/// (PMG eqs. 21–25, issue #6), through any pmg::HalBackend (MuJoCo SIL or the real robot on CAN).
///
/// Convention. z (12) is the correction added to a joint reading r to get the model's joint angle,
///   q = r + z   [rad],
/// so the encoder zero offset (reading − true angle, as pmg::MujocoBackendOptions::encoder_offsets
/// and the robot config's `zero_offset`) is −z.
///
/// Protocol (docs/calibration.md, "Zero-point calibration"). Both feet stay flat and planted on level
/// ground; the pelvis is moved slowly (PD targets in reading space, solved by IK on the nominal model)
/// through varied, partly asymmetric static poses and held; readings and the IMU's gravity direction are
/// averaged over each hold. Per pose k the data are r_k (12) and g_k (unit "up" vector in the IMU frame,
/// R_WI^T e_z; the IMU yaw is not used).
///
/// Model of pose k, with the world frame W := the left sole frame (gauge: both soles flat on the floor):
///   X_WB = X_BL(q_L)^-1, and the right sole X_WR(p) = (p_x, p_y, 0, yaw p_ψ) (placement p, shared over
///   poses, unknown). Constraint residual c_k(q, p) ∈ R^8:
///     [ position of X_WB X_BR(q_R) − (p_x, p_y, 0)          (3, m)
///       log(R_WR(p)^T R_WB R_BR(q_R))                        (3, rad)  closed chain, right foot flat
///       xy of R_WB R_BI g_k                                  (2, rad)  model tilt = IMU tilt ]
/// Estimator (eqs. 21–25): for each iteration, with J_k = ∂c_k/∂(z, p) at the current (z, p̂),
/// H = Σ_j J_jᵀ J_j and g = Σ_j J_jᵀ c_j over the used poses:
///   δ_k = −(H − J_kᵀJ_k)⁻¹ (g − J_kᵀ c_k)   (eq. 22, ZeroPerPose::kLeaveOneOut, default: the model
///                                           correction the other poses imply; all 12 joints + p)
///   δ   = median_k δ_k              (eq. 23, per joint)
///   z  ← z + α δ,  p̂ ← p̂ + α δp     (eq. 24)
///   converged when |α δ_i| < ε for all joints in M consecutive iterations (eq. 25).
/// On consistent data every δ_k equals the Gauss–Newton step, so the iteration converges like
/// Gauss–Newton iff the stacked Jacobian (observability()) has full rank 15. The literal per-pose variant
/// (ZeroPerPose::kProjection: q_sim_k = argmin |q − (r_k + z)|² + |p − p̂|² + w_c |c_k(q, p)|², the model
/// configuration nearest to r_k + z that reproduces the measured IMU under the pose's constraints,
/// δ_k = q_sim_k − (r_k + z)) gives δ_k only in the 8-dim row space of pose k; their per-joint median
/// does not converge (test MedianNeedsFullCorrectionsPerPose, docs).
/// τ gate (eq. 21): a pose whose model at the current estimate disagrees with its IMU by more than τ
/// (tilt angle of the pelvis implied by either leg vs. the measured one) is excluded from the median;
/// the gate is applied each time the iteration has converged on the current set, until no pose is
/// newly excluded (a slipped or rocked foot, a bump, a bad IMU sample).

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/gco/leg_kinematics.hpp"

namespace pmg {
class HalBackend;
struct HalStackConfig;
struct RobotConfig;
}  // namespace pmg

namespace pmg::calib {

/// Number of calibrated joints: both leg chains, left chain then right chain, each in chain order
/// (hip pitch, hip roll, hip yaw, knee, ankle pitch, ankle roll).
inline constexpr int kZeroJoints = 2 * gco::kLegDofs;
using ZeroVector = Eigen::Matrix<double, kZeroJoints, 1>;

/// One static pose as measured (averaged over its hold).
struct ZeroSample {
  std::string name;                                   ///< pose name from the protocol
  ZeroVector readings = ZeroVector::Zero();           ///< r_k: joint readings (reading space) [rad]
  Eigen::Vector3d up_I = Eigen::Vector3d::UnitZ();    ///< g_k: unit up vector in the IMU frame (R_WI^T e_z)
  bool valid = true;                                  ///< false: refused at capture (reason says why)
  std::string reason;                                 ///< why the capture refused it
  double gyro_rms = 0.0;                              ///< |ω| RMS over the averaging window [rad/s]
  double tilt_spread = 0.0;                           ///< max angle of up_I from its mean in the window [rad]
};

/// How the per-pose deviation δ_k of eq. 22 is formed.
enum class ZeroPerPose {
  /// δ_k = q_sim_k − (r_k + z), q_sim_k the constrained model configuration nearest to r_k + z (Euclidean).
  /// Each δ_k lies in the 8-dim row space of pose k's constraints; their per-joint median does not
  /// converge (measured, docs). Kept for comparison.
  kProjection,
  /// δ_k = −K H⁻¹ J_kᵀ c_k: pose k's share of the Gauss–Newton step of the K used poses (H = Σ J_jᵀ J_j),
  /// scaled so that mean_k δ_k is the full step. The shares are large and of mixed sign (H is
  /// ill-conditioned): their median diverges (measured, docs). Kept for comparison.
  kGaussNewtonShare,
  /// δ_k = −(H − J_kᵀJ_k)⁻¹ (g − J_kᵀ c_k), g = Σ J_jᵀ c_j: the Gauss–Newton correction implied by the
  /// pose set without pose k (all 12 offsets, since any K−1 poses of the protocol observe them). On
  /// consistent data every δ_k is the same full correction, so the median converges like Gauss–Newton;
  /// a corrupted pose shifts all δ_j but its own, and the τ gate removes it. Default.
  kLeaveOneOut,
};

/// How eq. 23 combines the per-pose deviations.
enum class ZeroCombine { kMedian, kMean };

/// Options of the estimator (eqs. 21–25). validate() throws std::invalid_argument naming the field.
struct ZeroEstimatorOptions {
  double tau = 0.01;              ///< τ: IMU agreement gate [rad], in (0, 1]
  double alpha = 1.0;             ///< α: update gain, in (0, 1]
  double epsilon = 1e-6;          ///< ε: convergence threshold on |α δ_i| [rad], in (0, 0.1]
  int consecutive = 5;            ///< M: consecutive iterations below ε, in [1, 1000]
  int max_iterations = 3000;      ///< iteration limit, in [1, 1e6]
  int min_poses = 4;              ///< fewer used poses than this is an error, in [2, 1000]
  ZeroPerPose per_pose = ZeroPerPose::kLeaveOneOut;
  ZeroCombine combine = ZeroCombine::kMedian;  ///< eq. 23: the median (issue); the mean for comparison
  double constraint_weight = 1e6; ///< w_c of the per-pose solve (constraints vs. prior), in [1e2, 1e12]
  /// Rotation IMU frame -> pelvis frame (G1: identity, site imu_in_pelvis has no rotation).
  Eigen::Matrix3d R_BI = Eigen::Matrix3d::Identity();
  void validate() const;
};

/// Estimator output.
struct ZeroEstimate {
  ZeroVector z = ZeroVector::Zero();      ///< correction q = r + z [rad]; encoder offset = −z
  Eigen::Vector3d placement = Eigen::Vector3d::Zero();  ///< right sole in left sole frame (x [m], y [m], yaw [rad])
  bool converged = false;
  int iterations = 0;
  std::vector<int> used;                  ///< indices of the samples in the final median
  std::vector<int> rejected_capture;      ///< refused at capture (ZeroSample::valid false)
  std::vector<int> rejected_tau;          ///< excluded by the τ gate
  std::vector<double> imu_disagreement;   ///< per sample at the final estimate [rad]
  std::vector<double> closure_residual;   ///< per sample: |position part of c_k| at the final estimate [m]
  std::vector<ZeroVector> history;        ///< z after each iteration
  std::vector<double> step_history;       ///< max_i |α δ_i| of each iteration [rad]
  std::string message;                    ///< human-readable status (why not converged)
};

/// Observability of (z, p) from a pose set: SVD of the stacked constraint Jacobian ∂c/∂(z, p).
struct ZeroObservability {
  Eigen::VectorXd singular_values;        ///< descending (15)
  int rank = 0;                           ///< singular values above 1e-6 · σ_max
  Eigen::VectorXd weakest_direction;      ///< right singular vector of σ_min (12 joints, then x, y, yaw)
};

/// Implements eqs. 21–25 on the KDL leg chains. Not thread-safe (owns a LegKinematics workspace).
class ZeroEstimator {
 public:
  /// @throws std::invalid_argument if model is null or options are invalid (names the field).
  ZeroEstimator(std::shared_ptr<const gco::LegModel> model, ZeroEstimatorOptions options);
  ~ZeroEstimator();

  /// Runs the iteration on @p samples from z = z0 (default 0). Progress: called after each iteration.
  /// @throws std::invalid_argument when fewer than min_poses samples are usable (message says how many).
  ZeroEstimate estimate(const std::vector<ZeroSample>& samples, const ZeroVector& z0 = ZeroVector::Zero(),
                        const std::function<void(int, const ZeroVector&, double, int)>& progress = {});

  /// Constraint residual c_k ∈ R^8 (see file comment) for model joints q (12) and placement p.
  Eigen::Matrix<double, 8, 1> constraint(const ZeroVector& q, const Eigen::Vector3d& p, const Eigen::Vector3d& up_I);
  /// Placement implied by model joints q (right sole in left sole frame, flattened): x, y, yaw.
  Eigen::Vector3d placementOf(const ZeroVector& q);
  /// Tilt disagreement [rad] between the pelvis orientation implied by either leg (left sole flat at
  /// the origin, right sole flat at yaw p_ψ) and the IMU: max over the two legs.
  double imuDisagreement(const ZeroVector& q, const Eigen::Vector3d& p, const Eigen::Vector3d& up_I);
  /// Stacked Jacobian ∂c/∂(z, p) at (z, p) over @p samples (8·K × 15) and its SVD.
  ZeroObservability observability(const std::vector<ZeroSample>& samples, const ZeroVector& z,
                                  const Eigen::Vector3d& p);
  /// The per-pose solve: the model configuration near q0 = r_k + z (and placement near p0) that satisfies
  /// c_k = 0. Returns q_sim; *p_out receives the pose's placement.
  ZeroVector solvePose(const ZeroVector& q0, const Eigen::Vector3d& p0, const Eigen::Vector3d& up_I,
                       Eigen::Vector3d* p_out);

  const ZeroEstimatorOptions& options() const { return options_; }
  gco::LegKinematics& kinematics() { return *kin_; }

 private:
  std::shared_ptr<const gco::LegModel> model_;
  ZeroEstimatorOptions options_;
  std::unique_ptr<gco::LegKinematics> kin_;
};

/// One pose of the protocol: the pelvis displaced from its home pose (the settled default stance),
/// expressed in the stance frame M (midpoint of the soles, level, x forward): translation [m] and
/// roll/pitch/yaw [rad] (R = Rz(yaw) Ry(pitch) Rx(roll), applied to the home orientation).
struct ZeroPoseSpec {
  std::string name;
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();
};

/// The capture protocol (config/calib/zero_poses_g1.yaml). validate() throws pmg::ConfigError naming
/// the source, field and expected range.
struct ZeroProtocol {
  std::string source = "<defaults>";
  std::vector<ZeroPoseSpec> poses;
  double settle_s = 1.0;        ///< hold of the home pose before the first pose [s], [0.2, 30]
  double move_s = 1.0;          ///< cosine-interpolated move between poses [s], [0.2, 30]
  double hold_s = 0.8;          ///< hold of each pose [s], [0.1, 30]
  double average_s = 0.4;       ///< averaging window at the end of each hold [s], (0, hold_s]
  double max_gyro_rms = 0.02;   ///< a hold with a larger |ω| RMS is refused (robot moving) [rad/s], > 0
  double max_tilt_spread = 0.003;  ///< a hold whose up vector wanders more is refused [rad], > 0
  double max_tilt_error = 0.2;  ///< IMU tilt vs. the planned pelvis tilt beyond this = tipped: abort [rad], > 0
  double max_home_drift = 0.01; ///< home orientation (incl. yaw) change start -> end = feet moved [rad], > 0
  double max_shift_m = 0.12;    ///< |dp| limit for any pose [m] (safety), > 0
  double max_angle_rad = 0.35;  ///< |rpy| limit for any pose [rad] (safety), > 0
  /// Motor PD gains of the leg joints during the capture, chain order, both legs (6 each, or empty = the
  /// robot config's). The G1's default ankle kp (40 N·m/rad) cannot hold the standing robot without a
  /// balance controller (ankle stiffness < m g h): the protocol raises it. [N·m/rad], [N·m·s/rad], [0, 2000].
  std::vector<double> leg_kp, leg_kd;
  /// true: the planned foot poses are the home's feet flattened on the nominal model (level soles in the
  /// model); false: the home's feet as the model sees them (with hidden offsets the model's feet are
  /// tilted, the real ones flat: keeping them makes the planned moves fit the real chain to second order).
  bool flatten_feet = true;
  /// true: the capture starts by holding the joint readings it finds (for a robot already standing with
  /// both soles flat); false: it first ramps to the robot config's default pose in reading space (with
  /// hidden offsets the real pose is then default − offset, which does not fit both soles flat).
  bool start_from_current = false;
  void validate() const;
};

/// Loads a protocol YAML file (`zero_calibration: {settle_s, ..., poses: [{name, dp: [x,y,z], rpy: [r,p,y]}]}`).
/// @throws pmg::ConfigError naming the file, field and expected range.
ZeroProtocol loadZeroProtocol(const std::string& path);

/// What the capture measured.
struct ZeroCapture {
  std::vector<ZeroSample> samples;
  bool feet_moved = false;          ///< home orientation drifted beyond max_home_drift
  double home_drift = 0.0;          ///< [rad]
  double duration_s = 0.0;          ///< backend time spent [s]
  /// Ground truth of the SIL (sole slip over the whole capture) when the backend provides it; else NaN.
  double max_base_drift_m = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd final_targets;    ///< (n) joint targets the robot is left holding (reading space) [rad]
};

/// Drives the robot through @p protocol via @p backend (one exchange per backend cycle, lockstep in
/// the SIL, paced by the backend on hardware) with the robot config's kp/kd, and captures one sample
/// per pose. Joints other than the legs hold their default pose. Leg IK on the nominal model; with
/// @p z_guess (a previous estimate, model = reading + z_guess) the targets are consistent with it, which
/// lowers the internal stress of the closed chain in a second pass.
/// @p start_targets (n joint targets in reading space [rad], or empty): the targets the robot is held at
/// when the capture starts (e.g. the previous pass's ZeroCapture::final_targets); with
/// protocol.start_from_current the capture keeps holding them instead of taking the first readings as
/// targets (which would drop the torque that carries the standing robot's weight).
/// @throws std::runtime_error when the backend faults, the IK of a pose fails or leaves the joint
/// limits (names the pose), or the IMU says the robot tipped (tilt error > max_tilt_error); std::invalid_argument
/// when start_targets has neither 0 nor n entries.
ZeroCapture captureZeroPoses(HalBackend& backend, const RobotConfig& robot,
                             std::shared_ptr<const gco::LegModel> model, const ZeroProtocol& protocol,
                             const std::function<void(const std::string&)>& log = {},
                             const ZeroVector& z_guess = ZeroVector::Zero(),
                             const Eigen::VectorXd& start_targets = {});

/// Noise-free samples of @p protocol on the nominal leg model, for design-time observability analysis and
/// tests: home = the robot config's default leg pose levelled (feet flat, pelvis level), each pose's pelvis
/// displaced by (dp, rpy) in M (pure kinematics: dp.xy moves the pelvis, no balance), true joints by IK,
/// readings = true − z_true, up_I from the true pelvis tilt (R_BI = identity).
/// @throws std::runtime_error naming the pose when its IK fails.
std::vector<ZeroSample> synthesizeZeroSamples(std::shared_ptr<const gco::LegModel> model, const RobotConfig& robot,
                                              const ZeroProtocol& protocol, const ZeroVector& z_true);

/// Full-joint-vector index of each of the 12 calibrated joints (left chain, right chain).
std::array<int, kZeroJoints> zeroJointIndices(const gco::LegModel& model, const RobotConfig& robot);

/// Declares the protocol's leg gains to the HAL supervisor of @p stack (makeHalStack()): the soft
/// stand uses them (the walking gains let the robot tip while it stands up on the calibration
/// floor), the gain ceilings admit them, and the stand is short (the robot starts standing). The
/// capture then runs through the same safety stack as pmg_controller.
void declareProtocolGains(const ZeroProtocol& protocol, const RobotConfig& robot, const gco::LegModel& model,
                          HalStackConfig& stack);

}  // namespace pmg::calib
