#pragma once
/// @file stride_adaptation.hpp
/// Stride adaptation of the PMG reference: the stance soles held still on the ground under the
/// commanded base motion, the swing leg placing the next step (beyond the paper's eqs. 13–19).
///
/// Why: the blended walking clips imply a base motion that is close to the command on average (the
/// consistent blending, docs/generator.md), but not at every tick. Measured on the envelope grid with
/// GCO, the reference's stance soles still move about 0.1 m/s, and in combined commands a stance sole
/// rises several centimetres at some tick (docs/policy.md "The price"). GCO (eqs. 13–19) answers by
/// changing the command the policy observes (u′) to agree with the feet; this step changes the feet
/// to agree with the command u, as issue 12 asks ("the feet imply u rather than only reporting u′").
///
/// What, per foot f, every tick (frames: B = pelvis, held level by the generator, so its axes are the
/// heading frame H's; S = sole point, F = foot link; leg_kinematics.hpp):
///   - the reference's sole pose X_BS,ref = (p_ref, R_ref) (forward kinematics of q_ref) and its
///     change since the last tick;
///   - a sole offset e_f ∈ R³ [m] (B axes) and a yaw offset ψ_f [rad], the state of this step:
///       stance (c_f = 1): integrated so that the point the foot rolls on, c = S + r_c, is still in
///       the world (r_c = l k R_ref e_x, k = clamp(−(R_ref e_x)_z / rolling_slope, −1, 1), l =
///       sole_half_length: the heel at heel strike, S while the sole is level, the toe at toe-off):
///         ė = s (−v_u − ω_u e_z × p_c − Δc_ref / dt) − (1 − s) e_s / τ_stand,  ė_z uses −ḣ − Δc_ref,z / dt,
///       p_c = p_ref + r_c + e, Δc_ref the reference's own displacement of that point (of the sole
///       frame's point c_S, fixed over the tick) since the last tick: positions, so the held point
///       does not drift by the integration of velocities;
///         ψ̇ = s (−ω_u − Δψ_ref / dt)           − (1 − s) ψ_s / τ_stand (ψ_ref: the foot's yaw in B),
///       with u = (v_u [m/s, H], ω_u [rad/s]) the velocity command given to the generator, ḣ the
///       rate of the template's pelvis height, and s = clamp((0.5 − σ_f) / stepping_margin, 0, 1)
///       the stepping share from the foot's blended contact window (eqs. 8–9: σ_f = 0.5 while
///       standing, so s = 0 and the soles are not held against a posture change; s = 1 once the
///       window leaves room for a swing); standing, e_s = (0, 0, e_z) and ψ_s = 0 with
///       standing_hold (the feet stay where the last steps put them; the next swings return them),
///       else e_s = e, ψ_s = ψ (all offsets decay, sliding the planted feet);
///       swing (c_f = 0): from its lift-off value (e_lo, ψ_lo) toward the touchdown value
///         e_td = (−λ e_lo,x, −λ e_lo,y, 0), ψ_td = −λ ψ_lo   (λ = touchdown_lead)
///       along a smoothstep over the first return_fraction of the swing (phase progress through
///       the generator's contact window {μ_f, σ_f}, eqs. 8–9). With λ > 0 the swing foot lands
///       ahead of the clip's placement by a share of the last stance's drift, so the stance is
///       centred under the hip: in steady walking e_lo → D / (1 + λ) and e_td → −λ D / (1 + λ)
///       for a per-stance drift D (λ = 0.5: two thirds behind, one third ahead; λ < 1 keeps that
///       step-to-step recursion convergent).
///     |ė| ≤ max_offset_speed, |ψ̇| ≤ max_offset_yaw_rate, |e| ≤ max_offset, |e_z| ≤
///     max_offset_height, |ψ| ≤ max_offset_yaw
///     in both phases, so the offsets, and through them the reference, stay continuous in time
///     through every contact switch, phase wrap and command step.
///   - the leg joints q = q_ref + δ_f that place the sole at X_BS* = (p_ref + e, Rz(ψ) R_ref): the
///     foot keeps the (levelled) reference's pitch and roll; `iterations` Levenberg–Marquardt steps
///     on the 6-D pose error (its height row weighted by height_weight) from the last tick's δ_f, damped by |error|² + damping (Sugihara 2011,
///     so an out-of-reach pose gives a short step), each δ_f,j bounded to ±max_correction, to the
///     URDF limits and to max_correction_rate·dt from the last tick's. q̇_ref gains (δ_f − δ_f,prev) / dt (0 on the first tick after reset()).
/// Where the bounds act (a command the clips cannot carry, a pose out of the leg's reach), the sole
/// is left to slide by what the bound removes; the counters show how often.
///
/// Order in GeneratorWithGco: generator → SoleLevelling → StrideAdaptation → GCO. GCO then sees
/// stance feet that imply u, so u′ ≈ u.
///
/// Setup may allocate and throw; apply() is noexcept and allocation-free (test/gco/test_gco_alloc.cpp).

#include <array>
#include <cstdint>
#include <memory>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pmg/gco/leg_kinematics.hpp"

namespace pmg::gco {

/// Options of StrideAdaptation (a sub-map `stride_adaptation:` of the GCO options YAML).
struct StrideAdaptationOptions {
  bool enabled = false;               ///< off: the reference is left as the generator (and levelling) made it
  double touchdown_lead = 0.5;        ///< λ: share of the last lift-off offset placed ahead at touchdown, [0, 1)
  double return_fraction = 0.7;       ///< share of the swing over which the offset reaches its touchdown value, (0, 1]
  double standing_time_constant = 0.3;  ///< τ_stand: decay of the offsets while standing [s], (0, 10]
  /// Standing (s = 0), hold the offsets' horizontal part and yaw, so the feet stay where the last steps
  /// put them, and decay only the height part with τ_stand. false: decay all of them with τ_stand,
  /// which slides both planted feet back under the hips after a stop (the reference's planted soles
  /// moved 91-127 mm in total after stops from 0.3-0.5 m/s, 14-16 mm held; docs/gco.md "Stride adaptation").
  bool standing_hold = true;
  double stepping_margin = 0.02;      ///< σ_f below 0.5 at which a stance is held fully [phase units], (0, 0.5]
  double max_offset = 0.15;           ///< bound on |e| [m], (0, 0.3]
  /// Bound on |e_z| [m], (0, 0.3]: a clip that lifts a foot well inside its contact window (by more
  /// than this) keeps its lift beyond the bound instead of a deep knee bend.
  double max_offset_height = 0.03;
  double max_offset_yaw = 0.4;        ///< bound on |ψ| [rad], (0, 1]
  double max_offset_speed = 1.0;      ///< bound on |ė| [m/s], (0, 5]
  double max_offset_yaw_rate = 3.0;   ///< bound on |ψ̇| [rad/s], (0, 10]
  int iterations = 3;                 ///< damped Gauss–Newton steps per foot and tick, 1..10
  double max_correction = 0.6;        ///< bound on |δ_f,j| per leg joint [rad], (0, 1.5]
  /// Weight of the sole's height against its horizontal position and orientation in the inverse
  /// kinematics, (0, 1]: where the pose is out of the leg's reach (a straight stance knee), the
  /// height gives way first.
  double height_weight = 0.3;
  double damping = 1e-3;              ///< Levenberg damping added to |pose error|² [m² or rad²], [0, 1]
  double max_correction_rate = 4.0;   ///< bound on |δ̇_f,j| [rad/s], (0, 100]: the reference stays continuous
  /// Half the sole's length from S to heel and toe [m], [0, 0.2]: the held point rolls from the heel
  /// (x = −l) through S to the toe (x = +l) along the sole's x axis (G1: toe 0.12, heel −0.05 from
  /// the ankle, S at 0.035; leg_kinematics.hpp). 0 holds S itself.
  double sole_half_length = 0.085;
  /// Sole slope (−(sole x axis)_z in B) at which the held point reaches the toe or heel, (0, 1].
  double rolling_slope = 0.05;

  /// Throws std::invalid_argument naming the field and its range.
  void validate() const;

  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, "hold the reference's stance soles still under the command");
    a->Visit("touchdown_lead", &touchdown_lead, "[0, 1)");
    a->Visit("return_fraction", &return_fraction, "(0, 1]");
    a->Visit("standing_time_constant", &standing_time_constant, "[s] (0, 10]");
    a->Visit("standing_hold", &standing_hold, "standing, hold the horizontal offsets and yaw (the feet stay put)");
    a->Visit("stepping_margin", &stepping_margin, "[phase] (0, 0.5]");
    a->Visit("max_offset", &max_offset, "[m] (0, 0.3]");
    a->Visit("max_offset_height", &max_offset_height, "[m] (0, 0.3]");
    a->Visit("max_offset_yaw", &max_offset_yaw, "[rad] (0, 1]");
    a->Visit("max_offset_speed", &max_offset_speed, "[m/s] (0, 5]");
    a->Visit("max_offset_yaw_rate", &max_offset_yaw_rate, "[rad/s] (0, 10]");
    a->Visit("iterations", &iterations, "1..10");
    a->Visit("max_correction", &max_correction, "[rad] (0, 1.5]");
    a->Visit("height_weight", &height_weight, "(0, 1]");
    a->Visit("damping", &damping, "[0, 1]");
    a->Visit("max_correction_rate", &max_correction_rate, "[rad/s] (0, 100]");
    a->Visit("sole_half_length", &sole_half_length, "[m] [0, 0.2]");
    a->Visit("rolling_slope", &rolling_slope, "(0, 1]");
  }
};

/// One reference tick as StrideAdaptation reads it (GeneratorOutput fields and the command).
struct StrideAdaptationInput {
  double phase = 0.0;                                  ///< φ the reference was evaluated at [0, 1)
  std::array<FootContact, kNumFeet> contact{};         ///< blended windows {μ_f, σ_f} (eqs. 8–9)
  std::array<bool, kNumFeet> in_contact{true, true};   ///< c_f(φ)
  double base_height = 0.78;                           ///< template pelvis height above the ground [m]
  Eigen::Vector2d v_H = Eigen::Vector2d::Zero();       ///< commanded base velocity (v_x, v_y), H [m/s]
  double yaw_rate = 0.0;                               ///< commanded yaw rate ω [rad/s]
};

/// Counters since construction or reset().
struct StrideAdaptationCounters {
  std::uint64_t ticks = 0;
  std::uint64_t speed_limited = 0;   ///< foot-ticks where max_offset_speed / _yaw_rate clipped ė / ψ̇
  std::uint64_t offset_limited = 0;  ///< foot-ticks where max_offset / _yaw clipped e / ψ
  std::uint64_t unreached = 0;       ///< foot-ticks whose pose error stayed above 2 mm or 0.01 rad
  std::uint64_t failures = 0;        ///< ticks left unchanged (non-finite input, KDL error)
};

/// Per-control-loop state (not thread-safe; one per GeneratorWithGco).
class StrideAdaptation {
 public:
  /// Setup: `leg_idx` maps the chain joints into the full joint vector (LegModel::jointIndices).
  /// Throws std::invalid_argument on a null model or bad options.
  StrideAdaptation(std::shared_ptr<const LegModel> legs, const StrideAdaptationOptions& options,
                   const LegJointIndex& leg_idx);

  /// Adapts one reference tick in place (see the file comment). q_ref, qd_ref: (n) [rad], [rad/s],
  /// robot joint order; dt: tick [s] (> 0). Returns false when disabled (reference unchanged), and
  /// on non-finite input or a KDL failure: then the last tick's δ_f is added again (no jump), the
  /// offsets are held and `failures` counts it.
  bool apply(const StrideAdaptationInput& in, double dt, Eigen::VectorXd* q_ref, Eigen::VectorXd* qd_ref) noexcept;

  /// Start-up state: offsets and counters zero, the next apply() adds no velocity.
  void reset() noexcept;

  bool enabled() const noexcept { return options_.enabled; }
  const StrideAdaptationOptions& options() const noexcept { return options_; }
  const StrideAdaptationCounters& counters() const noexcept { return counters_; }
  /// e_f of the last apply(): sole offset from the reference's sole, B axes [m].
  const Eigen::Vector3d& offset(Foot f) const noexcept { return offset_[LegModel::index(f)]; }
  /// ψ_f of the last apply() [rad].
  double yawOffset(Foot f) const noexcept { return yaw_offset_[LegModel::index(f)]; }
  /// δ_f of the last apply(): the change of the leg joints, chain order [rad].
  const LegVector& correction(Foot f) const noexcept { return delta_[LegModel::index(f)]; }
  /// Pose error left by the last apply()'s inverse kinematics: (position [m], angle [rad]).
  const Eigen::Vector2d& residual(Foot f) const noexcept { return residual_[LegModel::index(f)]; }

  /// Swing progress of a foot in [0, 1] (0 at lift-off, 1 at touchdown) for a contact window and
  /// phase; 0 in stance and for σ ≥ 0.5.
  static double swingProgress(const FootContact& contact, double phase) noexcept;

 private:
  bool solveFoot(std::size_t f, const LegVector& q_ref, const Eigen::Isometry3d& X_target, double dt) noexcept;

  std::shared_ptr<const LegModel> legs_;
  StrideAdaptationOptions options_;
  LegJointIndex leg_idx_;
  LegKinematics kin_;
  StrideAdaptationCounters counters_;
  bool started_ = false;
  double last_height_ = 0.0;
  std::array<bool, kNumFeet> last_contact_{true, true};
  std::array<Eigen::Vector3d, kNumFeet> offset_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<double, kNumFeet> yaw_offset_{0.0, 0.0};
  std::array<Eigen::Vector3d, kNumFeet> liftoff_offset_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<double, kNumFeet> liftoff_yaw_{0.0, 0.0};
  std::array<Eigen::Isometry3d, kNumFeet> last_pose_{Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()};
  std::array<LegVector, kNumFeet> delta_{LegVector::Zero(), LegVector::Zero()};
  std::array<LegVector, kNumFeet> applied_{LegVector::Zero(), LegVector::Zero()};
  std::array<Eigen::Vector2d, kNumFeet> residual_{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
};

}  // namespace pmg::gco
