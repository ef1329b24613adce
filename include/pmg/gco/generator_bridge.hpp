#pragma once
/// @file generator_bridge.hpp
/// The complete generator of issue 4: PMG generator tick (eqs. 4-12, pmg::MotionGenerator) followed
/// by GCO (eqs. 13-19), header-only (target pmg::gco_generator).
///
/// Per 100 Hz tick: MotionGenerator::step(u_d, u_s, dt) -> [SoleLevelling::apply() when
/// GcoOptions::sole_levelling.enabled: the stance soles of q_ref/qd_ref levelled, sole_levelling.hpp]
/// -> [StrideAdaptation::apply() when GcoOptions::stride_adaptation.enabled: the stance soles held
/// still under u_d, stride_adaptation.hpp] -> fillFromGenerator() -> Gco::solve().
/// generatorOutput() is the (levelled, adapted) reference the policy and the controller use.
/// The policy observes GcoResult::u_opt (u' of eq. 19) instead of the raw command; with
/// GcoOptions::enabled = false (the "PMG w/o GCO" ablation) u' is the template's own base state.
/// Setup allocates and may throw; step() is noexcept and allocation-free (test/gco/
/// test/gco/test_gco_alloc.cpp runs it under an operator-new counter).

#include <memory>

#include "pmg/gco/gco.hpp"
#include "pmg/generator/generator.hpp"

namespace pmg::gco {

/// Copies one generator tick into the GCO input (noexcept, no allocation):
/// q_leg/qd_leg from q_ref/qd_ref through `leg_idx`, c_f = in_contact, v = v_base,
/// ω = (0, 0, yaw_rate), h = base_height, pelvis level (roll = pitch = 0: clips carry joint angles
/// relative to the pelvis and no pelvis orientation), command = (u_d, u_s) with a "standing"
/// height (u_s.height <= 0) replaced by the template height.
/// The roll and pitch rates of GeneratorOutput::omega_base are not passed on: with the pelvis held
/// level (eq. 13 positions), a roll/pitch rate in eq. 14 makes the sole velocity differ from the
/// time derivative of the sole position by ω_xy × r (0.1 rad/s × 0.7 m = 70 mm/s), and GCO would
/// then hold still a foot that in fact slides (measured: 31 mm slip per stance over the grid with
/// them, docs/gco.md). A clip format with pelvis roll/pitch would pass both the angles
/// (base_roll/base_pitch) and their rates.
inline void fillFromGenerator(const GeneratorOutput& g, const LegJointIndex& leg_idx, const VelocityCommand& u_d,
                              const PostureCommand& u_s, GcoInput* in) noexcept {
  fillLegState(leg_idx, g.q_ref, g.qd_ref, in);
  in->contact = g.in_contact;
  in->v_HB_H = g.v_base;
  in->w_HB_H = Eigen::Vector3d(0.0, 0.0, g.omega_base.z());
  in->base_height = g.base_height;
  in->base_roll = 0.0;
  in->base_pitch = 0.0;
  in->command.v_x = u_d.vx;
  in->command.v_y = u_d.vy;
  in->command.yaw_rate = u_d.wz;
  in->command.pitch = u_s.pitch;
  in->command.roll = u_s.roll;
  in->command.height = u_s.height > 0.0 ? u_s.height : g.base_height;
}

/// Generator + GCO, one object per control loop (not thread-safe).
class GeneratorWithGco {
 public:
  /// Setup: `legs` must be built from the same robot as the generator's joint space
  /// (LegModel::fromRobotConfig). Throws std::runtime_error if a leg joint is missing from the
  /// generator's joint order, std::invalid_argument on bad options.
  GeneratorWithGco(std::shared_ptr<const GeneratorModel> generator_model, std::shared_ptr<const LegModel> legs,
                   const GcoOptions& options)
      : generator_(std::move(generator_model)),
        gco_(legs, options),
        leg_idx_(legs->jointIndices(generator_.model().jointSpace().joint_names)),
        levelling_(legs, options.sole_levelling, leg_idx_),
        stride_(legs, options.stride_adaptation, leg_idx_),
        output_(generator_.output()) {}  // sizes the levelled copy once

  /// One tick: generator at the current phase, then GCO. Returns GCO's result (u' etc.).
  const GcoResult& step(const VelocityCommand& u_d, const PostureCommand& u_s, double dt) noexcept {
    stepReference(u_d, u_s, dt);
    return solveGco();
  }

  /// step()'s first half: the generator tick, the sole levelling and the stride adaptation when
  /// enabled, and gcoInput(). (Split for tools that time the two halves, apps/gco/gco_eval.cpp.)
  void stepReference(const VelocityCommand& u_d, const PostureCommand& u_s, double dt) noexcept {
    generator_.step(u_d, u_s, dt);
    if (adapted()) output_ = generator_.output();  // same sizes: no allocation
    if (levelling_.enabled()) {
      levelling_.apply(generator_.model().jointSpace().q_stand, output_.q_posture, output_.phase, output_.contact,
                       dt, &output_.q_ref, &output_.qd_ref);
    }
    if (stride_.enabled()) {
      StrideAdaptationInput sin;
      sin.phase = output_.phase;
      sin.contact = output_.contact;
      sin.in_contact = output_.in_contact;
      sin.base_height = output_.base_height;
      sin.v_H = Eigen::Vector2d(u_d.vx, u_d.vy);
      sin.yaw_rate = u_d.wz;
      stride_.apply(sin, dt, &output_.q_ref, &output_.qd_ref);
    }
    fillFromGenerator(generatorOutput(), leg_idx_, u_d, u_s, &input_);
  }

  /// step()'s second half: GCO on gcoInput().
  const GcoResult& solveGco() noexcept {
    gco_.solve(input_, &result_);
    return result_;
  }

  /// Resets the phase and GCO's warm start / ramps (noexcept).
  void reset(double phase = 0.0) noexcept {
    generator_.reset(phase);
    gco_.reset();
    levelling_.reset();
    stride_.reset();
  }

  /// The reference of the last tick: the generator's, with the stance soles levelled when
  /// GcoOptions::sole_levelling.enabled and held still when GcoOptions::stride_adaptation.enabled.
  const GeneratorOutput& generatorOutput() const noexcept { return adapted() ? output_ : generator_.output(); }
  const SoleLevelling& soleLevelling() const noexcept { return levelling_; }
  const StrideAdaptation& strideAdaptation() const noexcept { return stride_; }
  const GcoInput& gcoInput() const noexcept { return input_; }
  const GcoResult& gcoResult() const noexcept { return result_; }
  MotionGenerator& generator() noexcept { return generator_; }
  Gco& gco() noexcept { return gco_; }
  const LegJointIndex& legJointIndex() const noexcept { return leg_idx_; }

 private:
  bool adapted() const noexcept { return levelling_.enabled() || stride_.enabled(); }

  MotionGenerator generator_;
  Gco gco_;
  LegJointIndex leg_idx_;
  SoleLevelling levelling_;
  StrideAdaptation stride_;
  GeneratorOutput output_;
  GcoInput input_;
  GcoResult result_;
};

}  // namespace pmg::gco
