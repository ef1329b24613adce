#pragma once
/// @file gco.hpp
/// Ground-aware Command Optimization (GCO), PMG eqs. 13-19.
///
/// A blended PMG template (generator output) does not exactly realise the commanded base motion:
/// with the template's base velocity, the stance feet slide and float. Every control tick GCO
/// finds the smallest change of the base command, x = (Δv_x, Δv_y, Δω, Δh), that makes every
/// foot in contact stationary on the ground, and publishes the optimized command
/// u' = [v_x + Δv_x, v_y + Δv_y, ω + Δω, pitch, roll, h + Δh] (eq. 19) that the policy observes.
///
/// Frames: W = world (z up, ground plane z = h_ground); H = heading frame (yaw-aligned with the
/// pelvis, z up, origin on the ground under the pelvis, moves and turns with the base);
/// B = pelvis; F = foot link; S = sole point of a foot (see leg_kinematics.hpp).
///
/// Model (eqs. 13-14), for foot f with pelvis orientation R_HB = Ry(pitch_B) * Rx(roll_B) w.r.t. H:
///   r_f      = R_HB p_BS_B(q_f)                                   sole position relative to pelvis, H axes
///   p_HS_f,z = h + Δh + r_f,z                                    sole height above the ground
///   v_WS_f   = v + Δv + (ω_B + Δω e_z) × r_f + R_HB J_v,f q̇_f      sole velocity (H axes)
///   ω_WF_f,z = ω + Δω + (R_HB J_ω,f q̇_f)_z                       foot yaw rate
/// Contact conditions (eq. 15), for every foot with c_f = 1:
///   v_WS_f,xy = 0,  ω_WF_f,z = 0,  p_HS_f,z = h_ground.
/// Least squares (eqs. 16-18), residuals (20, fixed size; ceres::TinySolver, analytic Jacobian):
///   per foot (4):   s_f w_foot_velocity v_WS_f,x, s_f w_foot_velocity v_WS_f,y,
///                   s_f w_foot_yaw_rate ω_WF_f,z, s_f w_foot_height (p_HS_f,z − h_ground)
///   prior (4):      w_prior_* x                         (stay close to the template)
///   smoothness (4): w_smooth_* (x − x_prev)             (hold the last solution in flight)
///   limits (4):     w_limit · hinge(u' outside CommandLimits) for v'_x, v'_y, ω', h'
/// s_f ∈ [0, 1] is the contact weight: it ramps from 0 to 1 over contact_ramp_time after touchdown
/// and drops to 0 at lift-off. Priorities (by weight): limits > foot contact > smoothness > prior.
///   - double support: both feet weigh equally; the solution is their least-squares compromise;
///   - flight (no contact): only smoothness and prior act, so x decays geometrically toward 0
///     by the factor w_smooth² / (w_smooth² + w_prior²) per tick (0.96 with the defaults);
///   - conflicting commands: a height command that a bent (pitched) posture cannot reach on the
///     ground, or a speed beyond the command limits, is resolved by the limit hinge (weight 100
///     vs. 1 for contact): u' stays inside CommandLimits and the foot is left to slide/float.
/// After the solve u' is clamped to CommandLimits and its change per tick is bounded by
/// max_jump (the documented bound on jumps of u' at contact switches and phase wrap).
///
/// Usage (setup may allocate and throw; the tick is noexcept and allocation-free). With the PMG
/// generator, prefer pmg::gco::GeneratorWithGco (generator_bridge.hpp); by hand:
/// @code
///   auto legs = pmg::gco::LegModel::fromRobotConfig(robot_config);           // KDL pelvis -> soles
///   pmg::gco::GcoOptions opt = pmg::gco::loadGcoOptionsFile("config/gco/g1.yaml");  // or {}
///   pmg::gco::Gco gco(legs, opt);
///   auto leg_idx = legs->jointIndices(robot_config.jointNames());          // once
///   pmg::gco::GcoInput in;    // preallocated member, filled in place every tick
///   pmg::gco::GcoResult res;
///   // every 100 Hz tick, after the generator produced q_ref, qd_ref, contacts, v, ω, h:
///   pmg::gco::fillLegState(leg_idx, q_ref, qd_ref, &in);
///   in.contact = {c_left, c_right}; in.v_HB_H = v; in.w_HB_H = {0, 0, ω}; in.base_height = h;
///   in.command = u;
///   gco.solve(in, &res);      // res.u_opt is the policy's command observation (eq. 19)
/// @endcode

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pmg/gco/leg_kinematics.hpp"
#include "pmg/gco/sole_levelling.hpp"
#include "pmg/gco/stride_adaptation.hpp"

namespace pmg::gco {

/// A base command u = (v_x, v_y, ω, pitch, roll, h) (PMG command; heading frame H).
struct BaseCommand {
  double v_x = 0.0;       ///< base linear velocity along H x (forward) [m/s]
  double v_y = 0.0;       ///< base linear velocity along H y (left) [m/s]
  double yaw_rate = 0.0;  ///< base yaw rate about z [rad/s], counter-clockwise positive
  double pitch = 0.0;     ///< torso pitch command [rad], positive = bend forward
  double roll = 0.0;      ///< torso roll command [rad], positive = lean right
  double height = 0.78;   ///< pelvis height above the ground [m]
};

/// Allowed range of the optimized command u' (the policy's training range).
struct CommandLimits {
  double v_x_min = -1.0, v_x_max = 1.5;              ///< [m/s]
  double v_y_min = -0.8, v_y_max = 0.8;              ///< [m/s]
  double yaw_rate_min = -1.5, yaw_rate_max = 1.5;    ///< [rad/s]
  double height_min = 0.45, height_max = 0.85;       ///< [m]

  /// Fields for pmg::yaml (yaml_archive.hpp): keys = field names.
  template <class A>
  void Serialize(A* a) {
    a->Visit("v_x_min", &v_x_min, "[m/s]");
    a->Visit("v_x_max", &v_x_max, "[m/s]");
    a->Visit("v_y_min", &v_y_min, "[m/s]");
    a->Visit("v_y_max", &v_y_max, "[m/s]");
    a->Visit("yaw_rate_min", &yaw_rate_min, "[rad/s]");
    a->Visit("yaw_rate_max", &yaw_rate_max, "[rad/s]");
    a->Visit("height_min", &height_min, "[m]");
    a->Visit("height_max", &height_max, "[m]");
  }
};

/// GCO parameters. Defaults are the documented G1 tuning (docs/gco.md).
struct GcoOptions {
  bool enabled = true;  ///< false = "PMG w/o GCO" ablation: u' = template (v, ω, h) unchanged
  double dt = 0.01;     ///< control period [s] (100 Hz)
  double ground_height = 0.0;  ///< h_ground: ground height in H [m]

  double w_foot_velocity = 1.0;   ///< weight of stance sole velocity residuals [1/(m/s)]
  double w_foot_yaw_rate = 0.2;   ///< weight of stance foot yaw-rate residual [1/(rad/s)]
  double w_foot_height = 1.0;     ///< weight of stance sole height residual [1/m]
  double w_prior_velocity = 0.01; ///< pull of Δv_x, Δv_y toward 0 [1/(m/s)]
  double w_prior_yaw_rate = 0.01; ///< pull of Δω toward 0 [1/(rad/s)]
  double w_prior_height = 0.01;   ///< pull of Δh toward 0 [1/m]
  double w_smooth_velocity = 0.05; ///< pull of Δv toward its last value [1/(m/s)]
  double w_smooth_yaw_rate = 0.05; ///< pull of Δω toward its last value [1/(rad/s)]
  double w_smooth_height = 0.05;   ///< pull of Δh toward its last value [1/m]
  double w_limit = 100.0;          ///< weight of the command-limit hinge residuals [1/SI unit]
  CommandLimits limits;

  double contact_ramp_time = 0.03;  ///< s_f rises 0 -> 1 over this time after touchdown [s], >= 0

  /// Largest change of u' between consecutive ticks (the jump bound), per component.
  double max_jump_velocity = 0.10;  ///< [m/s per tick] (10 m/s² at 100 Hz)
  double max_jump_yaw_rate = 0.20;  ///< [rad/s per tick]
  double max_jump_height = 0.010;   ///< [m per tick]

  /// Newton steps on the active hinge set that polish the warm start before the LM solve, 0..20
  /// (0 = plain Levenberg-Marquardt from the projected last iterate). The residuals are affine per
  /// active set, so a few steps reach the exact minimiser; LM alone zig-zags across hinge kinks.
  int newton_polish_iterations = 6;
  int max_iterations = 20;                 ///< Levenberg-Marquardt iteration cap per tick, 1..100
  double failure_gradient_norm = 1e-6;     ///< HIT_MAX_ITERATIONS with a larger max |gradient| = failure

  /// Stance sole levelling of the reference before GCO (GeneratorWithGco; beyond the paper,
  /// sole_levelling.hpp). Off by default; independent of `enabled`.
  SoleLevellingOptions sole_levelling;

  /// Stride adaptation of the reference after the levelling and before GCO (GeneratorWithGco; beyond
  /// the paper, stride_adaptation.hpp): stance soles held still under the command. Off by default.
  StrideAdaptationOptions stride_adaptation;

  /// Throws std::invalid_argument naming the field and its allowed range.
  void validate() const;

  /// Fields for pmg::yaml (yaml_archive.hpp): keys = field names, `limits:` a sub-map.
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, "false = PMG w/o GCO");
    a->Visit("dt", &dt, "control period [s]");
    a->Visit("ground_height", &ground_height, "[m]");
    a->Visit("w_foot_velocity", &w_foot_velocity, "[1/(m/s)]");
    a->Visit("w_foot_yaw_rate", &w_foot_yaw_rate, "[1/(rad/s)]");
    a->Visit("w_foot_height", &w_foot_height, "[1/m]");
    a->Visit("w_prior_velocity", &w_prior_velocity, "[1/(m/s)]");
    a->Visit("w_prior_yaw_rate", &w_prior_yaw_rate, "[1/(rad/s)]");
    a->Visit("w_prior_height", &w_prior_height, "[1/m]");
    a->Visit("w_smooth_velocity", &w_smooth_velocity, "[1/(m/s)]");
    a->Visit("w_smooth_yaw_rate", &w_smooth_yaw_rate, "[1/(rad/s)]");
    a->Visit("w_smooth_height", &w_smooth_height, "[1/m]");
    a->Visit("w_limit", &w_limit, "[1/SI unit]");
    a->Visit("limits", &limits, "command limits");
    a->Visit("contact_ramp_time", &contact_ramp_time, "[s]");
    a->Visit("max_jump_velocity", &max_jump_velocity, "[m/s per tick]");
    a->Visit("max_jump_yaw_rate", &max_jump_yaw_rate, "[rad/s per tick]");
    a->Visit("max_jump_height", &max_jump_height, "[m per tick]");
    a->Visit("newton_polish_iterations", &newton_polish_iterations, "0..20");
    a->Visit("max_iterations", &max_iterations, "1..100");
    a->Visit("failure_gradient_norm", &failure_gradient_norm, "");
    a->Visit("sole_levelling", &sole_levelling, "stance sole levelling of the reference");
    a->Visit("stride_adaptation", &stride_adaptation, "stance soles held still under the command");
  }
};

/// Reads a GcoOptions YAML mapping (keys = field names; `limits:` sub-map; missing keys keep
/// their defaults), bare or under a top-level `gco:` key, with pmg::yaml (yaml_archive.hpp).
/// Throws pmg::ConfigError naming the file, line and key on unknown keys (with the nearest valid
/// key), wrong types, non-finite numbers, and on validate() failures.
GcoOptions loadGcoOptionsFile(const std::string& path);
/// Same as loadGcoOptionsFile() for YAML text; `source_name` is used in error messages.
GcoOptions parseGcoOptionsYaml(const std::string& yaml_text, const std::string& source_name);

/// One tick of generator output, as GCO consumes it (all vectors in H unless noted).
struct GcoInput {
  std::array<LegVector, kNumFeet> q_leg{LegVector::Zero(), LegVector::Zero()};   ///< q_ref per leg, chain order [rad]
  std::array<LegVector, kNumFeet> qd_leg{LegVector::Zero(), LegVector::Zero()};  ///< q̇_ref per leg [rad/s]
  std::array<bool, kNumFeet> contact{true, true};    ///< c_f(φ), order Foot::kLeft, Foot::kRight
  Eigen::Vector3d v_HB_H = Eigen::Vector3d::Zero();  ///< template pelvis linear velocity v [m/s]
  Eigen::Vector3d w_HB_H = Eigen::Vector3d::Zero();  ///< template pelvis angular velocity; z = yaw rate ω [rad/s]
  double base_height = 0.78;  ///< template pelvis height h above the ground [m]
  double base_roll = 0.0;     ///< template pelvis roll w.r.t. H [rad] (0 = level pelvis)
  double base_pitch = 0.0;    ///< template pelvis pitch w.r.t. H [rad]
  BaseCommand command;        ///< commanded u; pitch and roll pass through to u' (eq. 19)
};

/// Copies the leg joints out of full joint vectors (robot order) using LegModel::jointIndices().
/// noexcept, no allocation. q and qd must have at least max(index)+1 entries (not checked).
void fillLegState(const LegJointIndex& leg_idx, const Eigen::Ref<const Eigen::VectorXd>& q,
                  const Eigen::Ref<const Eigen::VectorXd>& qd, GcoInput* in) noexcept;

enum class GcoStatus : int {
  kOk = 0,                  ///< solved; u' from this tick's solution
  kDisabled = 1,            ///< GCO switched off; u' = template
  kSolverFailure = 2,       ///< solver did not converge / non-finite: last good solution reused
  kInvalidInput = 3,        ///< non-finite input: last good u' reused
};
const char* toString(GcoStatus status) noexcept;

/// Result of one tick.
struct GcoResult {
  BaseCommand u_opt;                                ///< u' (eq. 19), the policy observation
  Eigen::Vector4d delta = Eigen::Vector4d::Zero();  ///< x = (Δv_x [m/s], Δv_y [m/s], Δω [rad/s], Δh [m])
  GcoStatus status = GcoStatus::kOk;
  int iterations = 0;        ///< Levenberg-Marquardt iterations used
  double initial_cost = 0.0; ///< ½|r|² at the warm start
  double final_cost = 0.0;   ///< ½|r|² at the solution
  std::array<double, kNumFeet> contact_weight{0.0, 0.0};  ///< s_f used this tick
  /// Sole velocity v_WS (H axes) implied by u' and the template joints [m/s].
  std::array<Eigen::Vector3d, kNumFeet> v_WS_H{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  /// Sole height above the ground implied by u' [m] (0 = on the ground).
  std::array<double, kNumFeet> sole_height{0.0, 0.0};
  bool jump_limited = false;  ///< max_jump clipped u' this tick
};

/// Fallback and clipping counters since construction or reset().
struct GcoCounters {
  std::uint64_t ticks = 0;
  std::uint64_t solver_failures = 0;  ///< ticks that reused the last good solution
  std::uint64_t invalid_inputs = 0;   ///< ticks with non-finite input
  std::uint64_t jump_limited = 0;     ///< ticks where max_jump clipped u'
  std::uint64_t limit_clamped = 0;    ///< ticks where u' was clamped to CommandLimits
};

/// The optimizer: persistent problem (fixed-size ceres::TinySolver), warm-started from the last
/// tick, bounded iterations. Not thread-safe; one instance per control loop.
class Gco {
 public:
  /// Setup: validates `options` (std::invalid_argument), allocates the workspace.
  Gco(std::shared_ptr<const LegModel> model, const GcoOptions& options);
  ~Gco();
  Gco(const Gco&) = delete;
  Gco& operator=(const Gco&) = delete;

  /// One control tick (eqs. 13-19). noexcept, no heap allocation. Always writes *out.
  GcoStatus solve(const GcoInput& in, GcoResult* out) noexcept;

  /// Forgets the warm start, contact ramps and the last good solution (e.g. on a controller
  /// restart). noexcept, no allocation.
  void reset() noexcept;

  /// Switch the ablation at run time (takes effect next tick; reset() is called).
  void setEnabled(bool enabled) noexcept;

  const GcoOptions& options() const noexcept { return options_; }
  const GcoCounters& counters() const noexcept { return counters_; }
  /// The leg chains GCO works on.
  const std::shared_ptr<const LegModel>& legModel() const noexcept { return model_; }

 private:
  struct Impl;
  std::shared_ptr<const LegModel> model_;
  GcoOptions options_;
  GcoCounters counters_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmg::gco
