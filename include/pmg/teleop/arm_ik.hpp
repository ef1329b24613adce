#pragma once
/// @file arm_ik.hpp
/// Inverse kinematics of both G1 arms for teleoperation (issue 13, "Arms by IK"): hand pose targets
/// in the torso frame → 7 arm joint angles per side, every 100 Hz tick.
///
/// Frames (Drake-style names):
///   T = torso_link (x forward, y left, z up), the root of both arm chains. Targets, capsules and
///       every vector of this file are in T, so the IK does not depend on the waist joints.
///   H = hand frame: `left_rubber_hand` / `right_rubber_hand` (URDF, fixed to the wrist yaw link by
///       `*_hand_palm_joint`): origin at the palm, x along the forearm when the wrist is straight.
///
/// Chains (from the robot config's URDF through KDL / kdl_parser, pmg::KinematicModel):
///   torso_link → shoulder pitch, shoulder roll, shoulder yaw, elbow, wrist roll, wrist pitch,
///   wrist yaw → rubber hand. ArmJoints is that order.
///
/// Method (per solve, both arms together, at most ArmIkOptions::max_iterations iterations):
///   1. Input check: a non-finite target, or a quaternion whose norm is off 1 by more than
///      `quaternion_norm_tolerance` → kInvalidTarget, that arm's q unchanged (the quaternion is
///      normalised otherwise). A seed outside the joint limits is clamped into them.
///   2. Workspace clamp: the target position p_TH is moved onto the shell
///      minReach·(1 + m) ≤ |p_TH − p_TS| ≤ reach·(1 − m) around the shoulder point S (m =
///      workspace_margin); ArmIkResult::workspace_clamped and status kUnreachableClamped say so.
///      (The shell is a radius test: a target inside it may still be out of reach of the joint
///      limits; the IK then ends at the closest pose it finds, status kMaxIterations.)
///   3. Damped least squares on the weighted 6-D pose error e = [w_p (p* − p); w_o log(R* Rᵀ)]
///      with the hand Jacobian J (6×7, T frame, reference point H; built from the joint axes of
///      the KDL forward-kinematics frames, equal to KDL::ChainJntToJacSolver's, see jacobian()):
///        Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e + α N k_n (q_nominal − q),   N = I − Jᵀ (J Jᵀ + μ² I)⁻¹ J,
///      λ² = λ_max²·(1 − σ_min²/ε²) when the smallest singular value σ_min of the weighted J
///      (inverse iteration on the Cholesky factor, warm-started) is below ε, else 0 (Chiaverini's
///      variable damping: the stretched arm), plus error_damping·½|e|² (Sugihara's: large far from
///      the target, vanishing at convergence). μ² = 1e-10 m²: N is the undamped null-space
///      projector, so the pull toward the nominal pose does not disturb the hand. α ∈ [0, 1]
///      scales the pull so it never pushes a joint out of its bounds. Every solve takes at least one
///      step, so the null-space pull (the elbow swivel toward the nominal posture) acts while the
///      hand holds still. The step is capped at max_iteration_step per joint.
///   4. Hard bounds (never violated on output): joint limits ∩ [q_seed − max_joint_step,
///      q_seed + max_joint_step] (continuity with the previous solution). A joint the task step
///      pushes past its bound is pinned there and the task is re-solved with the others (active set).
///   5. Collisions: capsules (pmg::teleop::ArmCapsuleModel, arm_capsules.hpp) for torso, head,
///      pelvis, upper arm, forearm and hand. Every pair closer than `collision_activation` adds the
///      linearised constraint d + ∇d·Δq ≥ d_s, with d_s = collision_margin, or d + 0.2 (margin − d)
///      for a pair already inside the margin (∇d from the point Jacobians at the closest points;
///      arm–arm pairs couple both arms); Δq is projected onto these half-spaces and the box. A
///      step after which a pair would be closer than min(its distance before, margin / 2) is halved
///      (up to 4 times), then dropped. Hence: from a seed with every pair ≥ margin / 2 apart, every
///      output keeps every pair ≥ margin / 2 apart (and a pair already closer never gets closer).
///   6. Stop: an arm stops iterating when converged (both tolerances), or when two iterations in a
///      row each removed < 1 % of its error (stop_when_stalled), or at max_iterations.
///      max_restarts > 0 (off-line only) retries unconverged arms from pseudo-random seeds.
///
/// Real time: setup (constructor) allocates and throws; solve(), forwardKinematics() and the
/// accessors are noexcept and allocation-free (the KDL FK solver and its frame vector are sized at
/// setup; fixed-size Eigen matrices; test/teleop/ik/test_arm_ik.cpp proves it with
/// pmg::test::AllocationGuard). Not thread-safe: one instance per thread.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>

#include "pmg/teleop/arm_capsules.hpp"

namespace pmg {
struct RobotConfig;
}

namespace pmg::teleop {

/// Degrees of freedom of one arm chain.
inline constexpr int kArmDofs = 7;

/// One arm's joints in chain order: shoulder pitch, roll, yaw, elbow, wrist roll, pitch, yaw [rad].
using ArmJoints = std::array<double, kArmDofs>;

/// A hand pose target: X_TH, the hand frame H in the torso frame T.
struct ArmPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< p_TH: palm origin in T [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< R_TH as a unit quaternion
};

/// Tuning of ArmIk. Defaults are for the 100 Hz teleop tick with a seed from the previous tick.
struct ArmIkOptions {
  int max_iterations = 8;                  ///< DLS iterations per solve (both arms together), 1..1000
  double damping = 0.05;                   ///< λ_max: damping at a singularity (σ_min = 0) [m], 0..1
  double singular_value_threshold = 0.04;  ///< ε: damping starts when σ_min of J_w < ε [m], > 0
  double error_damping = 0.5;              ///< error part: λ² += error_damping·½|e_w|² [1], 0..100
  double position_weight = 1.0;            ///< w_p: weight of the position error [1] (error in m), > 0
  double orientation_weight = 0.3;         ///< w_o: weight of the orientation error [m/rad], ≥ 0
  double nullspace_gain = 0.3;             ///< k_n: pull toward the nominal pose per iteration [1], 0..1
  double max_joint_step = 0.06;            ///< continuity: |q_out − q_seed| per joint per solve [rad], > 0
                                           ///< (0.06 = CommandLimits::max_reference_speed 6 rad/s at 100 Hz)
  double max_iteration_step = 0.3;         ///< Δq per iteration, max-norm [rad], > 0 (Newton step cap)
  double position_tolerance = 2e-4;        ///< converged when |p* − p| ≤ this [m], > 0
  double orientation_tolerance = 2e-3;     ///< ... and the rotation angle of R* Rᵀ ≤ this [rad], > 0
  /// Stop an arm's iterations when two in a row each removed less than 1 % of its error (the step
  /// bound, a joint limit or a collision holds it; the next solve goes on). false for off-line
  /// solves from far seeds, where the error may plateau before it falls again.
  bool stop_when_stalled = true;
  /// Off-line use only (0 in the loop: a restart jumps the joints): when an arm has not converged,
  /// retry it up to this many times from pseudo-random seeds inside its bounds (one arm at a
  /// time, the other frozen), keeping the best result. Each restart costs up to max_iterations.
  int max_restarts = 0;                     ///< 0..1000
  bool avoid_collisions = true;             ///< false: capsules are only measured (min_capsule_distance_m)
  double collision_margin = 0.01;           ///< d_s: capsule surfaces are kept this far apart [m], 0..0.1
                                            ///< (guaranteed: ≥ d_s / 2 from a seed that had it; method step 5)
  double collision_activation = 0.04;       ///< pairs closer than this constrain the step [m], > margin
  double workspace_margin = 0.02;           ///< m: targets are clamped to reach·(1 − m) [1], 0..0.5
  double quaternion_norm_tolerance = 0.05;  ///< | |q| − 1 | above this = kInvalidTarget [1], 0..0.5

  /// "" if valid, else "ArmIkOptions.<field> = <value>: expected <range>".
  std::string validate() const;

  /// Fields for pmg::yaml (yaml_archive.hpp): keys = field names.
  template <class A>
  void Serialize(A* a) {
    a->Visit("max_iterations", &max_iterations, "DLS iterations per solve, 1..1000");
    a->Visit("damping", &damping, "damping at a singularity [m]");
    a->Visit("singular_value_threshold", &singular_value_threshold, "[m]");
    a->Visit("error_damping", &error_damping, "adaptive damping factor");
    a->Visit("position_weight", &position_weight, "[1]");
    a->Visit("orientation_weight", &orientation_weight, "[m/rad]");
    a->Visit("nullspace_gain", &nullspace_gain, "pull toward the nominal pose per iteration");
    a->Visit("max_joint_step", &max_joint_step, "per joint per solve [rad]");
    a->Visit("max_iteration_step", &max_iteration_step, "per iteration [rad]");
    a->Visit("position_tolerance", &position_tolerance, "[m]");
    a->Visit("orientation_tolerance", &orientation_tolerance, "[rad]");
    a->Visit("stop_when_stalled", &stop_when_stalled, "stop iterating when the error stops falling");
    a->Visit("max_restarts", &max_restarts, "off-line restarts from random seeds, 0..1000");
    a->Visit("avoid_collisions", &avoid_collisions, "capsule collision avoidance");
    a->Visit("collision_margin", &collision_margin, "[m]");
    a->Visit("collision_activation", &collision_activation, "[m]");
    a->Visit("workspace_margin", &workspace_margin, "fraction of the reach");
    a->Visit("quaternion_norm_tolerance", &quaternion_norm_tolerance, "[1]");
  }
};

enum class ArmIkStatus {
  kConverged,           ///< within position_tolerance and orientation_tolerance of the target
  kMaxIterations,       ///< not converged within this solve: iteration budget, stall, continuity bound, joint
                        ///< limit or collision; q is the iterate reached (the next solve continues)
  kUnreachableClamped,  ///< the target was outside the workspace shell and was clamped onto it (the arm is
                        ///< then solved for the clamped target; errors are relative to it)
  kInvalidTarget,       ///< non-finite target or non-unit quaternion (or non-finite seed); see ArmIk::solve
  kInactive,            ///< arm not active in this solve: q unchanged
};

/// Name of a status, e.g. "converged", for logs and telemetry.
const char* toString(ArmIkStatus status) noexcept;

/// Outcome of one arm in one solve.
struct ArmIkResult {
  ArmIkStatus status = ArmIkStatus::kInactive;
  double position_error_m = 0.0;        ///< |p* − p(q_out)|, p* after the workspace clamp [m]
  double orientation_error_rad = 0.0;   ///< rotation angle of R* R(q_out)ᵀ [rad]
  int iterations = 0;                   ///< DLS iterations used
  bool workspace_clamped = false;       ///< target moved onto the workspace shell (step 2)
  double clamp_distance_m = 0.0;        ///< how far the target position was moved by the clamp [m]
  bool collision_limited = false;       ///< a capsule pair constrained, shortened or rejected a step
  double min_capsule_distance_m = 0.0;  ///< smallest surface distance of this arm's capsules to the
                                        ///< body and the other arm at q_out [m] (< 0: penetration)
};

/// Both-arm IK solver (see the file comment for the method). Model (chains, limits, capsules) is
/// immutable after construction; the workspace lives inside (one instance per thread).
class ArmIk {
 public:
  /// Setup: builds both chains torso_link → {left,right}_rubber_hand from robot.urdf_path, maps
  /// their joints onto the robot's joint order, takes nominal pose and limits from the config,
  /// sizes all KDL workspaces. @throws ConfigError naming the file if a link or joint is missing
  /// or a chain does not have 7 moving joints; std::invalid_argument if options.validate() fails.
  explicit ArmIk(const RobotConfig& robot, const ArmIkOptions& options = {});
  ~ArmIk();
  ArmIk(const ArmIk&) = delete;
  ArmIk& operator=(const ArmIk&) = delete;

  /// Solves both arms together (the arm–arm collision pairs need both).
  /// @param targets_T  hand targets X_TH [left, right].
  /// @param active     which arms to solve; an inactive arm keeps its q (it is still an obstacle
  ///                   for the other arm) and gets status kInactive.
  /// @param q          in: previous solution (seed, continuity); out: new solution, always within
  ///                   the joint limits. A seed outside the limits is clamped into them first.
  ///                   A non-finite seed: status kInvalidTarget and q = nominal.
  /// @param results    per arm outcome.
  /// noexcept, allocation-free.
  void solve(const std::array<ArmPose, 2>& targets_T, const std::array<bool, 2>& active, std::array<ArmJoints, 2>& q,
             std::array<ArmIkResult, 2>& results) noexcept;

  /// X_TH for hand 0 = left, 1 = right (pmg::teleop::Hand). Non-finite q gives NaN.
  ArmPose forwardKinematics(int hand, const ArmJoints& q) const noexcept;

  /// Geometric Jacobian of hand H in T at q (6×7): rows ∂p_TH/∂q [m/rad] then the angular velocity
  /// of H in T [1]; the reference point is H's origin (as KDL::ChainJntToJacSolver). NaN for a
  /// non-finite q.
  Eigen::Matrix<double, 6, kArmDofs> jacobian(int hand, const ArmJoints& q) const noexcept;

  /// Smallest capsule surface distance of all pairs checked by the IK at (q_left, q_right) [m]
  /// (< 0: penetration). `per_hand` (optional) receives each arm's smallest distance.
  double minCapsuleDistance(const std::array<ArmJoints, 2>& q,
                            std::array<double, 2>* per_hand = nullptr) const noexcept;

  /// Index of each chain joint in the robot config's joint order.
  const std::array<int, kArmDofs>& jointIndices(int hand) const noexcept;
  /// The robot config's default pose of this arm [rad].
  const ArmJoints& nominal(int hand) const noexcept;
  /// Joint limits of this arm from the robot config [rad].
  const ArmJoints& lower(int hand) const noexcept;
  const ArmJoints& upper(int hand) const noexcept;
  /// p_TS: shoulder point S in T [m], the centre of the workspace shell: the shoulder roll joint
  /// origin at q = 0 projected onto the shoulder pitch axis (fixed in T).
  Eigen::Vector3d shoulderPosition(int hand) const noexcept;
  /// Largest |p_TH − p_TS| with the arm stretched (elbow and wrist swept over their limits) [m].
  double reach(int hand) const noexcept;
  /// Smallest |p_TH − p_TS| with the wrist straight, elbow swept over its limits [m] (inner radius
  /// of the workspace shell; a bent wrist can bring the palm closer).
  double minReach(int hand) const noexcept;
  /// The capsule model used for collisions (stated constants, arm_capsules.hpp).
  const ArmCapsuleModel& capsules() const noexcept;
  const ArmIkOptions& options() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmg::teleop
