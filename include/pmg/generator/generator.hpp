#pragma once
/// @file generator.hpp
/// The Parameterized Motion Generator (PMG), header-only.
///
/// From a velocity command u_d = (v_x, v_y, ω) and a posture command u_s = (pitch, roll, height)
/// the generator blends the dynamic clips by convex weights, adds the posture offset of the static
/// clips and advances the shared gait phase φ, producing per tick: joint references q_ref, reference
/// velocities q̇_ref, per-foot contact schedule and the template's base velocity, yaw rate and height.
///
/// Equations (PMG paper, "Parameterized Motion Generator"):
///   eq. 4   α_i = clip(|u_i| / x̄_i, 0, 1)                     (x̄_i: clip nominal scale)
///   eq. 5   q̃_i(φ) = α_i q_Di(φ) + (1 − α_i) q_stand
///   eq. 6   w_i = |u_i| / (Σ_j |u_j| + ε)
///   eq. 7   q_d(φ) = Σ_i w_i q̃_i(φ)            [+ (1 − Σ_i w_i) q_stand, see "Standing" below]
///   eq. 8   μ_f = Σ_i w_i μ_f,i / Σ_i w_i      (contact centre of foot f)
///   eq. 9   σ_f = Σ_i w_i σ_f,i                [+ (1 − Σ_i w_i) · 0.5, see "Standing"]
///   eq. 10  q_ref = q_d + q_s                   (q_s: posture offset from the static clips)
///   eq. 11  φ ← (φ + Δt / T_u) mod 1
///   eq. 12  T_u = Σ_i w_i T_i                  [+ (1 − Σ_i w_i) T_stand]
///
/// Command-consistent blending (beyond the paper; GeneratorParams::blending, default kConsistent;
/// kPaper is eqs. 4–7 exactly, kept for the ablation). Eqs. 5 and 7 make q_d = q_stand +
/// Σ_i e_i (q_Di(φ) − q_stand) with the effective amplitude e_i = w_i α_i, so every channel of a
/// combined command is diluted by its weight, and a clip's nominal scale x̄_i (its mocap pelvis
/// speed) is not the speed its stance feet imply. kConsistent keeps eqs. 6, 8, 9, 11, 12 (weights
/// for the period and the contacts) but chooses the amplitudes e_i so that the stance-implied base
/// motion of the blended gait equals the command:
///   D_i,s(e) = T_i,s · V_i,s(e)   per-cycle displacement of the clip of axis i, sign s, played
///                                 alone at amplitude e (V: ImpliedMotionTable, piecewise linear)
///   Σ_i D_i,s_i(e_i) = u T_u      (3 equations: v_x, v_y, ω; T_u of eq. 12)
/// solved by kConsistentSweeps Gauss–Seidel sweeps: for axis i, r_i = u_i T_u − Σ_{j≠i}
/// D_j,s_j(e_j)[i], s_i = sign(r_i) (so a channel may use its opposite clip to cancel another
/// clip's drift, and e_i → 0 continuously as r_i → 0), e_i = D_i,s_i^{-1}(|r_i|) on the clip's own
/// axis, clamped to the table's largest amplitude (reported as amplitude_saturated). α_i then
/// reports e_i. A clip without a table gets the linear one D(e) = e T x̄ on its own axis, e ≤ 1.
/// Where an amplitude saturates, the stride cannot grow, so the gait steps faster instead (a human's
/// answer too): with ρ = min over the saturated axes i of Σ_j D_j(e_j)[i] / (u_i T_u), the achieved
/// share of the required per-cycle displacement, the period becomes T_u' = T_u · clamp(ρ,
/// 1 / max_cadence_ratio, 1) and the amplitudes are solved again for u T_u' (GeneratorParams::
/// max_cadence_ratio; GeneratorOutput::cadence_ratio = T_u / T_u'). ρ = 1 at the saturation's onset,
/// so the period is continuous in u; φ integrates dt / T_u', so q_ref stays continuous in time.
/// The contact schedule (eqs. 8–9) splits the walking share Σ w_i among the played clips in
/// proportion to e_i (eq. 6's split would time the contacts by a clip that barely moves).
/// What the per-clip tables cannot capture (channel interactions, the leg geometry of a squat) is
/// corrected first by the library's ConsistencyMap, when it has one: u ← u + Δu(u, height, pitch),
/// multilinear on its grid (inputs clamped to the grid), reported in GeneratorOutput::command_correction.
///
/// Conventions and decisions (docs/generator.md):
/// - **Standing / zero command.** Eq. 7 alone gives q_d = 0 at u_d = 0 (all w_i = 0). pmg gives the
///   remaining weight w_stand = 1 − Σ w_i to the standing pose, so q_d = q_stand exactly at zero
///   command, and moves continuously away from it as |u| grows (Σ w_i = Σ|u| / (Σ|u| + ε)). The
///   standing part of the cycle has both feet in contact (σ = 0.5) and period T_stand (the forward
///   clip's period), so φ keeps running while standing and a start from rest is continuous.
/// - **φ wrap.** Clips are periodic (sample N ≡ sample 0); phase interpolation wraps from the last
///   sample to the first, so q_ref is continuous across φ = 1 → 0.
/// - **Negative commands.** Each axis has a clip per sign. A missing one is derived at load time
///   with the clip library's transforms (include/pmg/clips/clip_transforms.hpp): backward walking =
///   the forward clip played in reverse time (q(1 − φ), velocities negated); right-sideways walking
///   and clockwise turning = the left/right mirror of the left clip (mirror map of the robot config,
///   contacts of the two feet swapped). Both are then rotated in phase so that φ = 0 is the left
///   foot's touchdown, as in every clip, so derived and real clips blend phase-consistently. A
///   derived capture says so in its metadata (provenance "mocap_time_reversed" / "mocap_mirrored").
/// - **Reference velocity** q̇_ref: central finite difference of q_d over one template sample in
///   phase, times dφ/dt = 1 / T_u (the posture offset is constant in φ).
/// - **Posture offset** q_s: each static clip is a table q(value) over its command range; the
///   command is clamped to the range, β ∈ [−1, 1] reports where it lies between the neutral value
///   and the range end, and q_s,axis = q(value) − q(neutral) (piecewise-linear in value).
/// - q_ref is finally clamped to the joint limits (reported in the output).
///
/// Model/Data split: GeneratorModel is immutable after construction (may allocate and throw);
/// MotionGenerator::step() is noexcept and allocation-free (tested).
///
/// Header-only; the model's constructor (setup time) validates and derives clips with pmg::clips,
/// so the target pmg::generator links pmg::clips.

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "pmg/clips/clip_transforms.hpp"
#include "pmg/clips/clip_validation.hpp"
#include "pmg/generator/clip.hpp"
#include "pmg/generator/joint_space.hpp"

namespace pmg {

/// Velocity command u_d in the heading (yaw-aligned base) frame: v_x forward [m/s], v_y left
/// [m/s], ω yaw rate counter-clockwise [rad/s].
struct VelocityCommand {
  double vx = 0.0;
  double vy = 0.0;
  double wz = 0.0;
  double operator[](std::size_t i) const { return i == 0 ? vx : (i == 1 ? vy : wz); }
};

/// Posture command u_s: torso pitch (forward bend) [rad], roll (lean right) [rad], pelvis height
/// above the ground [m]. NaN-free; values outside a static clip's range are clamped to it.
struct PostureCommand {
  double pitch = 0.0;
  double roll = 0.0;
  double height = 0.0;  ///< absolute pelvis height [m]; <= 0 means "the standing height" (the squat clip's neutral)
  double operator[](std::size_t i) const { return i == 0 ? pitch : (i == 1 ? roll : height); }
};

/// How the velocity channels are blended (see the file comment).
enum class Blending : int {
  kPaper = 0,       ///< PMG eqs. 4–7: α_i = |u_i| / x̄_i, convex weights w_i
  kConsistent = 1,  ///< amplitudes chosen so that the stance-implied base motion equals the command
};

/// Gauss–Seidel sweeps of the command-consistent amplitude solve (fixed: deterministic cost).
inline constexpr int kConsistentSweeps = 4;

/// Tunables of the generator.
struct GeneratorParams {
  Blending blending = Blending::kConsistent;  ///< kPaper reproduces the paper's eqs. 4–7 (ablation)
  double epsilon = 0.05;  ///< ε of eq. 6 [command units]; keeps w finite at zero command
  /// |command| accepted per axis (v_x, v_y, ω) [m/s, m/s, rad/s]; larger values are clamped.
  std::array<double, kNumCommandAxes> max_command{1.5, 0.8, 1.5};
  /// kConsistent: at most this much faster than eq. 12's cadence where an amplitude saturates
  /// (file comment), [1, 2]; 1 = eq. 12's period always. The library's ConsistencyMap is computed
  /// with the default (pmg::gco::computeConsistencyMap), so set another value only for an ablation
  /// or for a policy trained before the cadence existed (controller config generator.max_cadence_ratio).
  /// Where it acts the amplitude solve runs twice (a few more table look-ups in the tick).
  double max_cadence_ratio = 1.3;
  /// Beyond the paper: shift the waist pitch and waist roll of every dynamic clip (derived ones
  /// included) by a constant so that their mean over the cycle equals the standing pose's
  /// (q_D,j(φ) −= mean_φ q_D,j − q_stand,j; the oscillation is kept). The captured walks lean the
  /// torso forward by 0.07–0.28 rad with the waist (mean over the cycle, more when clips are
  /// superposed above amplitude one; docs/policy.md), which a robot asked for an upright torso must
  /// undo with its pelvis. Joints named waist_pitch_joint / waist_roll_joint; a robot without them is
  /// unchanged. The legs, and so the implied-motion tables and the ConsistencyMap, are unchanged.
  bool upright_walking = false;

  /// Returns an empty string when valid, else what is wrong (field and expected range).
  std::string validate() const {
    if (blending != Blending::kPaper && blending != Blending::kConsistent)
      return "GeneratorParams.blending: expected paper or consistent";
    if (!(epsilon > 0 && epsilon < 1)) return "GeneratorParams.epsilon: expected in (0, 1)";
    for (double m : max_command)
      if (!(m > 0 && m < 10)) return "GeneratorParams.max_command: expected each in (0, 10)";
    if (!(max_cadence_ratio >= 1.0 && max_cadence_ratio <= 2.0))
      return "GeneratorParams.max_cadence_ratio: expected in [1, 2]";
    return {};
  }
};

/// Status of one generator tick.
enum class GeneratorStatus : int {
  kOk = 0,
  kCommandClamped = 1,   ///< a command exceeded max_command or a static clip's range
  kInvalidCommand = 2,   ///< NaN/Inf in the command: treated as zero velocity / neutral posture
  kBadTimeStep = 3,      ///< dt not finite or ≤ 0: phase not advanced
};

/// Everything the generator produces per tick. Sized once by MotionGenerator's constructor.
struct GeneratorOutput {
  double phase = 0.0;                 ///< φ at which the references were evaluated [0, 1)
  double next_phase = 0.0;            ///< φ after the update of eq. 11
  double period = 1.0;                ///< T_u of eq. 12 [s] (kConsistent: shortened where an amplitude saturates)
  double cadence_ratio = 1.0;         ///< kConsistent: eq. 12's period / the period played, in [1, max_cadence_ratio]
  Eigen::VectorXd q_ref;              ///< (n) q_ref = q_d + q_s (eq. 10), clamped to limits [rad]
  Eigen::VectorXd qd_ref;             ///< (n) reference joint velocity [rad/s]
  Eigen::VectorXd q_dynamic;          ///< (n) q_d of eq. 7 [rad]
  Eigen::VectorXd q_posture;          ///< (n) q_s [rad]
  std::array<double, kNumCommandAxes> alpha{};    ///< kPaper: α_i (eq. 4); kConsistent: the amplitude e_i
  std::array<double, kNumCommandAxes> weight{};   ///< w_i (eq. 6): period and contact blend
  std::array<double, kNumCommandAxes> amplitude{};  ///< e_i: q_d = q_stand + Σ e_i (q_Di − q_stand) (= w_i α_i for kPaper)
  std::array<int, kNumCommandAxes> clip_direction{1, 1, 1};  ///< sign of the clip played on each axis
  int amplitude_saturated = 0;        ///< axes whose amplitude hit its table's end (kConsistent: command not carried)
  std::array<double, kNumCommandAxes> command_correction{};  ///< Δu of the ConsistencyMap applied (kConsistent) [m/s, m/s, rad/s]
  double standing_weight = 1.0;       ///< 1 − Σ w_i
  std::array<double, kNumPostureAxes> beta{};     ///< β per posture axis in [−1, 1]
  std::array<FootContact, kNumFeet> contact{};    ///< blended μ_f, σ_f (eqs. 8–9)
  std::array<bool, kNumFeet> in_contact{};        ///< c_f(φ): foot f in stance
  Eigen::Vector3d v_base{0, 0, 0};    ///< template base linear velocity, heading frame [m/s]
  double yaw_rate = 0.0;              ///< template base yaw rate [rad/s] (= omega_base.z())
  Eigen::Vector3d omega_base{0, 0, 0};  ///< template pelvis angular velocity, heading frame [rad/s]
  double base_height = 0.0;           ///< template pelvis height above ground [m] (incl. posture)
  int clamped_joints = 0;             ///< joints clamped to their limits this tick
  GeneratorStatus status = GeneratorStatus::kOk;
};

namespace detail {

inline double wrapPhase(double phi) noexcept {
  phi -= std::floor(phi);
  return phi >= 1.0 ? 0.0 : phi;
}

/// Segment of a strictly increasing grid (size ≥ 2) holding x: *k with grid[k] ≤ x ≤ grid[k+1]
/// (the first / last segment outside the grid) and the fraction of x in it, clamped to [0, 1].
inline double gridSegment(const Eigen::VectorXd& grid, double x, Eigen::Index* k) noexcept {
  const Eigen::Index n = grid.size();
  Eigen::Index i = 0;
  while (i + 2 < n && x > grid[i + 1]) ++i;
  *k = i;
  return std::clamp((x - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0);
}

/// Circular distance between two phases, in [0, 0.5].
inline double phaseDistance(double a, double b) noexcept {
  const double d = std::fabs(wrapPhase(a) - wrapPhase(b));
  return std::min(d, 1.0 - d);
}

/// PMG contact model: a foot is in stance while |φ − μ| (circular) < σ, always when σ ≥ 0.5.
inline bool inStance(const FootContact& c, double phi) noexcept {
  return phaseDistance(phi, c.mu) < c.sigma || c.sigma >= 0.5;
}

/// Sample index and fraction for phase φ on N samples: φ·N = k + t.
inline void phaseSample(double phi, std::size_t n_samples, std::size_t& k0, std::size_t& k1, double& t) noexcept {
  const double x = wrapPhase(phi) * static_cast<double>(n_samples);
  const double fl = std::floor(x);
  k0 = static_cast<std::size_t>(fl) % n_samples;
  k1 = (k0 + 1) % n_samples;
  t = x - fl;
}

}  // namespace detail

/// Immutable generator model: six dynamic clips (3 axes × 2 signs), up to three static clips,
/// and the joint space. Construction validates every clip with the clip library's one validation
/// (pmg::validateClip, include/pmg/clips/clip_validation.hpp; clips built in memory may leave
/// meta.joint_names empty) and derives a missing sign of an axis with its transforms
/// (pmg::timeReverseClip, pmg::mirrorClip, include/pmg/clips/clip_transforms.hpp).
/// @throws pmg::ClipFormatError naming the clip, the field and the expected range on an invalid
/// clip or two clips for one slot; std::invalid_argument on invalid params or joint space.
class GeneratorModel {
 public:
  GeneratorModel(const ClipLibrary& library, GeneratorJointSpace joint_space, GeneratorParams params = {})
      : js_(std::move(joint_space)), params_(params) {
    if (const std::string e = params_.validate(); !e.empty()) throw std::invalid_argument(e);
    const auto n = static_cast<Eigen::Index>(js_.joint_names.size());
    if (n == 0) throw std::invalid_argument("GeneratorJointSpace.joint_names: empty");
    if (js_.q_stand.size() != n || js_.lower.size() != n || js_.upper.size() != n ||
        js_.mirror_index.size() != js_.joint_names.size() || js_.mirror_sign.size() != js_.joint_names.size())
      throw std::invalid_argument("GeneratorJointSpace: q_stand/lower/upper/mirror sizes differ from joint_names (" +
                                  std::to_string(n) + ")");
    ClipValidationOptions check;
    check.require_joint_names = false;
    for (const auto& c : library.dynamic_clips) validateClip(c, js_, "clip '" + c.name + "'", check);
    for (const auto& s : library.static_clips) validateClip(s, js_, "static clip '" + s.name + "'", check);
    validateLibraryAxes(library, "clip library");
    for (const auto& c : library.dynamic_clips) dynamic_[slotOf(c.axis, c.direction)] = std::make_unique<DynamicClip>(c);
    for (std::size_t a = 0; a < kNumCommandAxes; ++a) {
      auto& pos = dynamic_[2 * a];
      auto& neg = dynamic_[2 * a + 1];
      const auto derive = [&](const DynamicClip& src) {
        return static_cast<CommandAxis>(a) == CommandAxis::kForward ? timeReverseClip(src, src.name + "_time_reversed")
                                                                    : mirrorClip(src, js_, src.name + "_mirrored");
      };
      if (pos && !neg) neg = std::make_unique<DynamicClip>(derive(*pos));
      if (neg && !pos) pos = std::make_unique<DynamicClip>(derive(*neg));
    }
    if (params_.upright_walking) {
      for (const char* name : {"waist_pitch_joint", "waist_roll_joint"}) {
        const auto it = std::find(js_.joint_names.begin(), js_.joint_names.end(), name);
        if (it == js_.joint_names.end()) continue;
        const auto j = static_cast<Eigen::Index>(it - js_.joint_names.begin());
        for (auto& d : dynamic_) {
          if (d && d->q.rows() > 0) d->q.col(j).array() -= d->q.col(j).mean() - js_.q_stand[j];
        }
      }
    }
    for (const auto& s : library.static_clips) static_[static_cast<std::size_t>(s.axis)] = std::make_unique<StaticClip>(s);
    for (std::size_t k = 0; k < dynamic_.size(); ++k)
      if (dynamic_[k]) displacement_[k] = makeDisplacementTable(*dynamic_[k]);
    consistency_ = library.consistency;
    if (!consistency_.empty()) {
      Eigen::Index rows = 1;
      for (const auto& g : consistency_.grid) {
        if (g.size() < 1) throw std::invalid_argument("ClipLibrary.consistency.grid: an axis is empty");
        for (Eigen::Index i = 1; i < g.size(); ++i)
          if (!(g[i] > g[i - 1])) throw std::invalid_argument("ClipLibrary.consistency.grid: expected strictly increasing");
        rows *= g.size();
      }
      if (consistency_.delta.rows() != rows || consistency_.delta.cols() != 3 || !consistency_.delta.allFinite())
        throw std::invalid_argument("ClipLibrary.consistency.delta: expected " + std::to_string(rows) + " x 3 finite values");
    }
    t_stand_ = dynamic_[0] ? dynamic_[0]->period : 1.0;
    for (const auto& d : dynamic_)
      if (d) max_samples_ = std::max(max_samples_, d->numSamples());
  }

  std::size_t numJoints() const { return js_.joint_names.size(); }
  const GeneratorJointSpace& jointSpace() const { return js_; }
  const GeneratorParams& params() const { return params_; }
  /// Clip for axis and sign of the command (direction +1 or −1), or nullptr if the axis has none.
  const DynamicClip* dynamicClip(CommandAxis axis, int direction) const { return dynamic_[slotOf(axis, direction)].get(); }
  const StaticClip* staticClip(PostureAxis axis) const { return static_[static_cast<std::size_t>(axis)].get(); }
  double standingPeriod() const { return t_stand_; }
  std::size_t maxSamples() const { return max_samples_; }

  /// Per-cycle displacement table of a clip slot (kConsistent): amplitudes (K) and
  /// D = T · ImpliedMotionTable::velocity (K × 3: [m, m, rad] per cycle). Derived clips carry
  /// their source's table transformed (pmg::timeReverseClip, pmg::mirrorClip).
  struct DisplacementTable {
    Eigen::VectorXd amplitude;
    Eigen::MatrixXd displacement;
  };
  const ConsistencyMap& consistencyMap() const { return consistency_; }
  const DisplacementTable* displacementTable(CommandAxis axis, int direction) const {
    const auto& t = displacement_[slotOf(axis, direction)];
    return t.amplitude.size() > 0 ? &t : nullptr;
  }

 private:
  static DisplacementTable makeDisplacementTable(const DynamicClip& c) {
    DisplacementTable t;
    if (!c.implied.empty()) {
      t.amplitude = c.implied.amplitude;
      t.displacement = c.implied.velocity * c.period;
      return t;
    }
    // No table: linear in the amplitude, the clip's nominal scale on its own axis, its mean
    // template velocity on the others, at most the clip itself (e = 1).
    t.amplitude.resize(2);
    t.amplitude << 0.0, 1.0;
    t.displacement.setZero(2, 3);
    t.displacement(1, 0) = c.v_base.col(0).mean() * c.period;
    t.displacement(1, 1) = c.v_base.col(1).mean() * c.period;
    t.displacement(1, 2) = c.omega_base.col(2).mean() * c.period;
    t.displacement(1, static_cast<Eigen::Index>(c.axis)) = c.direction * c.nominal_scale * c.period;
    return t;
  }

  static std::size_t slotOf(CommandAxis axis, int direction) {
    return 2 * static_cast<std::size_t>(axis) + (direction < 0 ? 1 : 0);
  }
  GeneratorJointSpace js_;
  GeneratorParams params_;
  std::array<std::unique_ptr<DynamicClip>, 2 * kNumCommandAxes> dynamic_{};
  std::array<std::unique_ptr<StaticClip>, kNumPostureAxes> static_{};
  std::array<DisplacementTable, 2 * kNumCommandAxes> displacement_{};
  ConsistencyMap consistency_;
  double t_stand_ = 1.0;
  std::size_t max_samples_ = 2;
};

/// The per-robot generator state and workspace (Data). One per controller.
class MotionGenerator {
 public:
  explicit MotionGenerator(std::shared_ptr<const GeneratorModel> model) : model_(std::move(model)) {
    if (!model_) throw std::invalid_argument("MotionGenerator: null model");
    const auto n = static_cast<Eigen::Index>(model_->numJoints());
    for (auto* v : {&out_.q_ref, &out_.qd_ref, &out_.q_dynamic, &out_.q_posture, &q_minus_, &q_plus_, &row_})
      v->setZero(n);
    reset(0.0);
  }

  /// Sets the phase (e.g. 0 at start-up) and the outputs to the standing pose.
  void reset(double phase) noexcept {
    phase_ = detail::wrapPhase(phase);
    out_.q_ref = model_->jointSpace().q_stand;
    out_.q_dynamic = model_->jointSpace().q_stand;
    out_.qd_ref.setZero();
    out_.q_posture.setZero();
    out_.phase = out_.next_phase = phase_;
  }

  double phase() const noexcept { return phase_; }
  const GeneratorOutput& output() const noexcept { return out_; }
  const GeneratorModel& model() const noexcept { return *model_; }

  /// One generator tick: evaluates the references at the current phase φ for the commands, then
  /// advances φ by dt / T_u (eq. 11). noexcept, allocation-free. @p dt control period [s].
  GeneratorStatus step(const VelocityCommand& u_d_in, const PostureCommand& u_s_in, double dt) noexcept {
    GeneratorStatus status = GeneratorStatus::kOk;
    VelocityCommand u_d = u_d_in;
    PostureCommand u_s = u_s_in;
    if (!std::isfinite(u_d.vx) || !std::isfinite(u_d.vy) || !std::isfinite(u_d.wz)) {
      u_d = {};
      status = GeneratorStatus::kInvalidCommand;
    }
    if (!std::isfinite(u_s.pitch) || !std::isfinite(u_s.roll) || !std::isfinite(u_s.height)) {
      u_s = {};
      status = GeneratorStatus::kInvalidCommand;
    }
    const auto& p = model_->params();
    std::array<double, kNumCommandAxes> u{u_d.vx, u_d.vy, u_d.wz};
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      if (std::fabs(u[i]) > p.max_command[i]) {
        u[i] = std::copysign(p.max_command[i], u[i]);
        if (status == GeneratorStatus::kOk) status = GeneratorStatus::kCommandClamped;
      }
    }
    const bool clamped_posture = evalPosture(u_s);
    if (clamped_posture && status == GeneratorStatus::kOk) status = GeneratorStatus::kCommandClamped;

    // kConsistent: the residual correction of the consistency map (file comment).
    out_.command_correction = {0.0, 0.0, 0.0};
    if (p.blending == Blending::kConsistent && !model_->consistencyMap().empty()) {
      lookupCorrection(u, posture_height_, u_s.pitch);
      for (std::size_t i = 0; i < kNumCommandAxes; ++i) u[i] += out_.command_correction[i];
    }

    // Weights (eqs. 4, 6). Axes without a clip get no weight.
    const DynamicClip* clip[kNumCommandAxes] = {};
    double sum_abs = 0.0;
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      clip[i] = model_->dynamicClip(static_cast<CommandAxis>(i), u[i] < 0 ? -1 : 1);
      out_.clip_direction[i] = u[i] < 0 ? -1 : 1;
      if (clip[i]) sum_abs += std::fabs(u[i]);
    }
    double sum_w = 0.0;
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      out_.alpha[i] = clip[i] ? std::clamp(std::fabs(u[i]) / clip[i]->nominal_scale, 0.0, 1.0) : 0.0;
      out_.weight[i] = clip[i] ? std::fabs(u[i]) / (sum_abs + p.epsilon) : 0.0;
      out_.amplitude[i] = out_.weight[i] * out_.alpha[i];
      sum_w += out_.weight[i];
    }
    out_.standing_weight = 1.0 - sum_w;

    // Period (eq. 12).
    double period = out_.standing_weight * model_->standingPeriod();
    for (std::size_t i = 0; i < kNumCommandAxes; ++i)
      if (clip[i]) period += out_.weight[i] * clip[i]->period;
    out_.period = period;

    // Command-consistent amplitudes (see the file comment); the weights above stay for the
    // period and the contact schedule.
    out_.amplitude_saturated = 0;
    out_.cadence_ratio = 1.0;
    if (p.blending == Blending::kConsistent) {
      const bool cadence = p.max_cadence_ratio > 1.0;
      const double rho = solveConsistentAmplitudes(u, period, cadence);
      if (cadence && rho < 1.0) {  // a stride at its end: step faster (file comment)
        period *= std::clamp(rho, 1.0 / p.max_cadence_ratio, 1.0);
        solveConsistentAmplitudes(u, period, false);
        out_.cadence_ratio = out_.period / period;
        out_.period = period;
      }
    }

    // The dynamic reference at φ and φ ± h (eqs. 5, 7; reference velocity).
    const double h = 0.5 / static_cast<double>(model_->maxSamples());
    const DynamicClip* play[kNumCommandAxes] = {};  // the clip each axis plays (its sign may differ from u's)
    for (std::size_t i = 0; i < kNumCommandAxes; ++i)
      play[i] = model_->dynamicClip(static_cast<CommandAxis>(i), out_.clip_direction[i]);
    blendJoints(play, phase_ - h, q_minus_);
    blendJoints(play, phase_ + h, q_plus_);
    blendJoints(play, phase_, out_.q_dynamic);

    // Contacts (eqs. 8–9). kConsistent: the walking share Σ w_i of eq. 6 is split among the clips
    // in proportion to the amplitudes they play, so the contact schedule follows the motion that
    // dominates (with eq. 6's split, a clip playing at e = 1.4 under w = 0.4 would move its feet
    // while the schedule says stance).
    std::array<double, kNumCommandAxes> cw = out_.weight;
    const DynamicClip* contact_clip[kNumCommandAxes] = {clip[0], clip[1], clip[2]};
    if (p.blending == Blending::kConsistent) {
      double e_sum = 0.0;
      for (std::size_t i = 0; i < kNumCommandAxes; ++i)
        if (play[i]) e_sum += out_.amplitude[i];
      if (e_sum > 1e-12) {
        for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
          cw[i] = play[i] ? sum_w * out_.amplitude[i] / e_sum : 0.0;
          contact_clip[i] = play[i];
        }
      }
    }
    const auto& js = model_->jointSpace();
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      double mu = 0.0, sigma = 0.5 * out_.standing_weight;
      for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
        if (!contact_clip[i]) continue;
        mu += cw[i] * contact_clip[i]->contact[f].mu;
        sigma += cw[i] * contact_clip[i]->contact[f].sigma;
      }
      out_.contact[f].mu = sum_w > 0 ? detail::wrapPhase(mu / sum_w) : 0.0;
      out_.contact[f].sigma = std::clamp(sigma, 0.0, 0.5);
      out_.in_contact[f] = detail::inStance(out_.contact[f], phase_);
    }
    out_.v_base.setZero();
    out_.omega_base.setZero();
    // Template base motion: h = h_stand + Σ e_i (h_i(φ) − h_stand), v = Σ e_i v_i(φ) (eqs. 5, 7
    // applied to the clips' base channels).
    double height = js.standing_base_height;
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      if (!play[i] || out_.amplitude[i] == 0.0) continue;
      std::size_t k0, k1;
      double t;
      detail::phaseSample(phase_, play[i]->numSamples(), k0, k1, t);
      const auto K0 = static_cast<Eigen::Index>(k0), K1 = static_cast<Eigen::Index>(k1);
      const double e = out_.amplitude[i];
      for (int a = 0; a < 3; ++a) out_.v_base[a] += e * ((1 - t) * play[i]->v_base(K0, a) + t * play[i]->v_base(K1, a));
      for (int a = 0; a < 3; ++a)
        out_.omega_base[a] += e * ((1 - t) * play[i]->omega_base(K0, a) + t * play[i]->omega_base(K1, a));
      const double h_clip = (1 - t) * play[i]->base_height[K0] + t * play[i]->base_height[K1];
      height += e * (h_clip - js.standing_base_height);
    }
    out_.yaw_rate = out_.omega_base.z();
    out_.base_height = height + posture_height_offset_;

    // q_ref = q_d + q_s (eq. 10), clamped to the limits; q̇_ref by central difference in phase.
    const double inv = 1.0 / (2.0 * h * period);
    out_.clamped_joints = 0;
    for (Eigen::Index j = 0; j < out_.q_ref.size(); ++j) {
      double q = out_.q_dynamic[j] + out_.q_posture[j];
      if (q < js.lower[j] || q > js.upper[j]) {
        q = std::clamp(q, js.lower[j], js.upper[j]);
        ++out_.clamped_joints;
      }
      out_.q_ref[j] = q;
      out_.qd_ref[j] = (q_plus_[j] - q_minus_[j]) * inv;
    }

    out_.phase = phase_;
    if (std::isfinite(dt) && dt > 0) {
      phase_ = detail::wrapPhase(phase_ + dt / period);  // eq. 11
    } else {
      status = GeneratorStatus::kBadTimeStep;
    }
    out_.next_phase = phase_;
    out_.status = status;
    return status;
  }

 private:
  // q_out = q_stand + Σ e_i (q_Di(φ) − q_stand), e_i = amplitude[i]. With kPaper, e_i = w_i α_i and
  // this equals Σ w_i (α_i q_Di(φ) + (1 − α_i) q_stand) + w_stand q_stand (eqs. 5, 7).
  void blendJoints(const DynamicClip* const* clip, double phi, Eigen::VectorXd& q_out) const noexcept {
    const auto& q_stand = model_->jointSpace().q_stand;
    double e_sum = 0.0;
    for (std::size_t i = 0; i < kNumCommandAxes; ++i)
      if (clip[i]) e_sum += out_.amplitude[i];
    for (Eigen::Index j = 0; j < q_out.size(); ++j) q_out[j] = (1.0 - e_sum) * q_stand[j];
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      if (!clip[i] || out_.amplitude[i] == 0.0) continue;
      std::size_t k0, k1;
      double t;
      detail::phaseSample(phi, clip[i]->numSamples(), k0, k1, t);
      const double e = out_.amplitude[i];
      const auto K0 = static_cast<Eigen::Index>(k0), K1 = static_cast<Eigen::Index>(k1);
      for (Eigen::Index j = 0; j < q_out.size(); ++j)
        q_out[j] += e * ((1.0 - t) * clip[i]->q(K0, j) + t * clip[i]->q(K1, j));
    }
  }

  // Multilinear interpolation of the consistency map at (u, height, pitch command), inputs
  // clamped to the grid.
  void lookupCorrection(const std::array<double, kNumCommandAxes>& u, double height, double pitch) noexcept {
    constexpr int D = static_cast<int>(kConsistencyMapDims);
    const ConsistencyMap& m = model_->consistencyMap();
    const double x[D] = {u[0], u[1], u[2], height, pitch};
    Eigen::Index lo[D];
    double f[D];
    Eigen::Index stride[D];
    for (int d = 0; d < D; ++d) {
      const Eigen::VectorXd& g = m.grid[static_cast<std::size_t>(d)];
      const Eigen::Index n = g.size();
      if (n == 1) {
        lo[d] = 0;
        f[d] = 0.0;
        continue;
      }
      f[d] = detail::gridSegment(g, x[d], &lo[d]);  // clamped: inputs outside the grid read its edge
    }
    stride[D - 1] = 1;
    for (int d = D - 2; d >= 0; --d) stride[d] = stride[d + 1] * m.grid[static_cast<std::size_t>(d + 1)].size();
    for (int corner = 0; corner < (1 << D); ++corner) {
      double w = 1.0;
      Eigen::Index row = 0;
      for (int d = 0; d < D; ++d) {
        const int bit = (corner >> d) & 1;
        if (bit && m.grid[static_cast<std::size_t>(d)].size() == 1) {
          w = 0.0;
          break;
        }
        w *= bit ? f[d] : 1.0 - f[d];
        row += (lo[d] + bit) * stride[d];
      }
      if (w == 0.0) continue;
      for (std::size_t i = 0; i < kNumCommandAxes; ++i) out_.command_correction[i] += w * m.delta(row, static_cast<Eigen::Index>(i));
    }
  }

  // Displacement of table `t` at amplitude e (piecewise linear; e within the table).
  static double tableAt(const GeneratorModel::DisplacementTable& t, double e, Eigen::Index column) noexcept {
    Eigen::Index k = 0;
    const double f = detail::gridSegment(t.amplitude, e, &k);
    return (1 - f) * t.displacement(k, column) + f * t.displacement(k + 1, column);
  }

  // Amplitude at which table `t` reaches |displacement| `target` on its own axis `column` (the
  // table grows strictly along `direction`, validated at load). Sets *saturated at the table's end.
  static double tableInverse(const GeneratorModel::DisplacementTable& t, double target, Eigen::Index column, int direction,
                             bool* saturated) noexcept {
    const Eigen::Index K = t.amplitude.size();
    const double last = direction * t.displacement(K - 1, column);
    if (target >= last) {
      *saturated = target > last;
      return t.amplitude[K - 1];
    }
    Eigen::Index k = 0;
    while (k + 2 < K && target > direction * t.displacement(k + 1, column)) ++k;
    const double d0 = direction * t.displacement(k, column), d1 = direction * t.displacement(k + 1, column);
    const double f = std::clamp((target - d0) / (d1 - d0), 0.0, 1.0);
    return (1 - f) * t.amplitude[k] + f * t.amplitude[k + 1];
  }

  // kConsistent: Gauss–Seidel sweeps for e with Σ_i D_i,s_i(e_i) = u T_u (file comment). Sets
  // amplitude, clip_direction, alpha (= e) and amplitude_saturated. With @p want_share, returns ρ,
  // the smallest share of its required displacement u_i T_u that a saturated axis achieves (1 when
  // none saturates, or without @p want_share). noexcept, no allocation.
  double solveConsistentAmplitudes(const std::array<double, kNumCommandAxes>& u, double period,
                                   bool want_share) noexcept {
    const GeneratorModel& m = *model_;
    std::array<const GeneratorModel::DisplacementTable*, kNumCommandAxes> table{};
    std::array<bool, kNumCommandAxes> saturated{};
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      out_.amplitude[i] = 0.0;
      table[i] = nullptr;
    }
    for (int sweep = 0; sweep < kConsistentSweeps; ++sweep) {
      for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
        const auto col = static_cast<Eigen::Index>(i);
        double r = u[i] * period;
        for (std::size_t j = 0; j < kNumCommandAxes; ++j)
          if (j != i && table[j] && out_.amplitude[j] > 0.0) r -= tableAt(*table[j], out_.amplitude[j], col);
        const int dir = r < 0 ? -1 : 1;
        const auto* t = m.displacementTable(static_cast<CommandAxis>(i), dir);
        if (!t) {  // the axis has no clip
          out_.amplitude[i] = 0.0;
          table[i] = nullptr;
          continue;
        }
        bool sat = false;
        out_.amplitude[i] = tableInverse(*t, std::fabs(r), col, dir, &sat);
        saturated[i] = sat;
        table[i] = t;
        out_.clip_direction[i] = dir;
      }
    }
    out_.amplitude_saturated = 0;
    double rho = 1.0;
    for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
      out_.alpha[i] = out_.amplitude[i];
      if (!saturated[i]) continue;
      ++out_.amplitude_saturated;
      const double need = u[i] * period;
      if (!want_share || std::fabs(need) < 1e-12) continue;
      double got = 0.0;
      for (std::size_t j = 0; j < kNumCommandAxes; ++j)
        if (table[j] && out_.amplitude[j] > 0.0) got += tableAt(*table[j], out_.amplitude[j], static_cast<Eigen::Index>(i));
      rho = std::min(rho, std::max(0.0, got / need));
    }
    return rho;
  }

  // Fills out_.q_posture and out_.beta; returns true if a command was clamped to a clip's range.
  bool evalPosture(const PostureCommand& u_s) noexcept {
    bool clamped = false;
    out_.q_posture.setZero();
    posture_height_offset_ = 0.0;
    posture_height_ = model_->jointSpace().standing_base_height;
    for (std::size_t a = 0; a < kNumPostureAxes; ++a) {
      out_.beta[a] = 0.0;
      const StaticClip* s = model_->staticClip(static_cast<PostureAxis>(a));
      if (!s) continue;
      double value = u_s[a];
      if (static_cast<PostureAxis>(a) == PostureAxis::kHeight && value <= 0.0) value = s->neutral;  // "no command"
      const double lo = s->values[0], hi = s->values[s->values.size() - 1];
      if (value < lo || value > hi) clamped = true;
      value = std::clamp(value, lo, hi);
      const double span = value >= s->neutral ? hi - s->neutral : s->neutral - lo;
      out_.beta[a] = span > 0 ? (value - s->neutral) / span : 0.0;
      interpolateStatic(*s, value, row_);
      interpolateStatic(*s, s->neutral, q_minus_);  // q_minus_ is scratch here
      for (Eigen::Index j = 0; j < row_.size(); ++j) out_.q_posture[j] += row_[j] - q_minus_[j];
      if (static_cast<PostureAxis>(a) == PostureAxis::kHeight) {
        posture_height_offset_ = value - s->neutral;
        posture_height_ = value;
      }
    }
    return clamped;
  }

  static void interpolateStatic(const StaticClip& s, double value, Eigen::VectorXd& q_out) noexcept {
    Eigen::Index i = 0;
    const double t = detail::gridSegment(s.values, value, &i);
    for (Eigen::Index j = 0; j < q_out.size(); ++j) q_out[j] = (1 - t) * s.q(i, j) + t * s.q(i + 1, j);
  }

  std::shared_ptr<const GeneratorModel> model_;
  GeneratorOutput out_;
  double phase_ = 0.0;
  double posture_height_offset_ = 0.0;
  double posture_height_ = 0.0;  ///< the height command evalPosture used (clamped; the squat's neutral when none) [m]
  Eigen::VectorXd q_minus_, q_plus_, row_;
};

}  // namespace pmg
