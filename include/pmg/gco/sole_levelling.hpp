#pragma once
/// @file sole_levelling.hpp
/// Stance sole levelling of the PMG reference (beyond the paper's eqs. 13–19).
///
/// Why: the generator plays a level pelvis, and superposing several walking clips at amplitudes
/// above one (the consistent blending, docs/generator.md) bends the stance leg so that its sole is
/// no longer parallel to the sole of the posture the user commanded. Measured on the envelope grid,
/// a robot standing flat on those soles pitches its torso by +0.02 to +0.25 rad with no pitch
/// commanded (largest in side-steps, backward walking and arcs; docs/policy.md). The actor keeps its
/// soles flat and so departs from the reference's leg angles by up to ~0.2 rad.
///
/// What: for each foot f, the ankle pitch and ankle roll offsets δ_f = (δ_pitch, δ_roll) [rad] that
/// turn the sole normal n_f = R_BF(q_f + δ_f) e_z (pelvis frame B) onto the sole normal of the
/// posture-only pose, n*_f = R_BF(q_stand,f + q_posture,f) e_z (eq. 10's q_s added to the standing
/// pose: the sole the commanded squat, bend or lean stands on; level for no posture command). The
/// foot's yaw and every other joint are untouched. δ_f is found by `iterations` Gauss–Newton steps
/// on the 3 components of n_f − n*_f with the analytic Jacobian ∂n/∂q_k = a_k × n (a_k: ankle axis
/// k in B, KDL), each step bounded to |δ| ≤ max_correction and to the URDF ankle limits.
///
/// It applies to the middle of each stance only, through a weight λ_f ∈ [0, 1] per foot that
/// follows the generator's contact window {μ_f, σ_f} (eqs. 8–9) in phase φ:
///   λ_f = clamp((σ_f − d_f) / (edge_fraction σ_f), 0, 1),   d_f = circular |φ − μ_f|,
/// i.e. 1 in mid-stance, falling linearly to 0 at touchdown and lift-off, 0 in swing. Heel strike and
/// toe-off, where the clips' soles tilt by up to ~0.4 rad on purpose, stay as captured. The
/// reference becomes
///   q_ref,ankle ← q_ref,ankle + λ_f δ_f,   q̇_ref,ankle ← q̇_ref,ankle + (λ_f δ_f − previous) / dt,
/// so it stays continuous in phase and command (the added q̇ is 0 on the first tick after reset()).
/// Frames: B = pelvis, F = foot (ankle roll) link (leg_kinematics.hpp).
///
/// Setup may allocate and throw; apply() is noexcept and allocation-free (test/gco/test_gco_alloc.cpp).

#include <array>
#include <memory>

#include <Eigen/Core>

#include "pmg/gco/leg_kinematics.hpp"

namespace pmg::gco {

/// Options of SoleLevelling (a sub-map `sole_levelling:` of the GCO options YAML).
struct SoleLevellingOptions {
  bool enabled = false;         ///< off: the reference is the generator's, unchanged
  double edge_fraction = 0.5;   ///< share of the stance half-window over which λ_f ramps 0 → 1, (0, 1]
  int iterations = 3;           ///< Gauss–Newton steps per foot and tick, 1..10
  double max_correction = 0.40; ///< [rad] bound on |δ| per ankle joint, (0, 1]

  /// Throws std::invalid_argument naming the field and its range.
  void validate() const;

  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, "level the stance soles of the reference");
    a->Visit("edge_fraction", &edge_fraction, "(0, 1]");
    a->Visit("iterations", &iterations, "1..10");
    a->Visit("max_correction", &max_correction, "[rad] (0, 1]");
  }
};

/// Per-control-loop state of the levelling (not thread-safe; one per GeneratorWithGco).
class SoleLevelling {
 public:
  /// Setup: `leg_idx` maps the chain joints into the full joint vector (LegModel::jointIndices).
  /// The last two joints of each chain must be ankle pitch and ankle roll (G1 order).
  /// Throws std::invalid_argument on a null model or bad options.
  SoleLevelling(std::shared_ptr<const LegModel> legs, const SoleLevellingOptions& options, const LegJointIndex& leg_idx);

  /// Levels the stance soles of one reference tick in place (see the file comment).
  /// q_stand, q_posture: (n) [rad], robot joint order (GeneratorOutput::q_posture = eq. 10's q_s).
  /// phase: φ the reference was evaluated at; contact: the blended windows {μ_f, σ_f}. dt: tick [s]
  /// (> 0). q_ref, qd_ref: (n) [rad], [rad/s]. Returns false, leaving the reference unchanged, when
  /// disabled or on non-finite input / a KDL failure.
  bool apply(const Eigen::VectorXd& q_stand, const Eigen::VectorXd& q_posture, double phase,
             const std::array<FootContact, kNumFeet>& contact, double dt, Eigen::VectorXd* q_ref,
             Eigen::VectorXd* qd_ref) noexcept;

  /// λ_f for a contact window and phase (see the file comment).
  static double weightAt(const FootContact& contact, double phase, double edge_fraction) noexcept;

  /// Start-up state: the next apply() adds no velocity.
  void reset() noexcept { started_ = false; }

  bool enabled() const noexcept { return options_.enabled; }
  const SoleLevellingOptions& options() const noexcept { return options_; }
  double weight(Foot f) const noexcept { return weight_[LegModel::index(f)]; }
  /// δ_f of the last apply(): (ankle pitch, ankle roll) offsets at full weight [rad]; zero where
  /// λ_f was 0 (not solved there).
  const Eigen::Vector2d& correction(Foot f) const noexcept { return delta_[LegModel::index(f)]; }

 private:
  bool solveFoot(std::size_t f, const LegVector& q_target, const LegVector& q) noexcept;

  std::shared_ptr<const LegModel> legs_;
  SoleLevellingOptions options_;
  LegJointIndex leg_idx_;
  LegKinematics kin_;
  bool started_ = false;
  std::array<double, kNumFeet> weight_{};
  std::array<Eigen::Vector2d, kNumFeet> delta_{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<Eigen::Vector2d, kNumFeet> applied_{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
};

}  // namespace pmg::gco
