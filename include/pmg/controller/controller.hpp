#pragma once
/// @file controller.hpp
/// The 100 Hz tick of `pmg_controller`: read → shape → generate/optimise → policy → write.
///
///  read      newest HAL state (incl. the supervisor's mode) and operator input (lock-free);
///            operator mode requests go to the HAL supervisor, the only mode state machine;
///  teleop    (teleop.enabled) the VR stream: once engaged the headset's command replaces the
///            other sources' (teleop_mode.hpp);
///  shape     CommandShaper: validate, clamp to the one CommandLimits, slew;
///  feedback  (velocity_feedback / posture_feedback enabled) the integral corrections of the shaped
///            velocity on leg odometry + IMU and of pitch/roll on the measured torso attitude
///            (velocity_feedback.hpp): the generator gets u_fb, evaluations compare with u;
///  generate  PMG generator + GCO (kActive only); teleop's arm IK replaces the arm references of
///            the arms it controls; then ReferenceRateLimiter bounds every joint reference's
///            speed (CommandLimits::max_reference_speed);
///  policy    the trained actor (legs) and limb separation, when one is configured;
///  write     the motor command to the HAL (the supervisor passes it on only in kActive) and one
///            telemetry frame to the publisher.
/// tick() is noexcept and allocation-free (tested); it returns what happened as a TickStatus.
/// The objects around it (HAL stack, telemetry, command sources, runner) are built by
/// pmg::ControllerApp (controller_app.hpp), the composition root.

#include <array>
#include <cstdint>
#include <memory>

#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/controller/velocity_feedback.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/hal_runner.hpp"
#include "pmg/hal/latest_value.hpp"
#include "pmg/hal/safety/mode_requests.hpp"

namespace pmg {
namespace policy {
class PolicyStage;
}
namespace teleop {
class TeleopMode;
}
class TelemetryPublisher;
class LcmInputCounters;

/// What one tick did.
struct TickStatus {
  Mode mode = Mode::kPassive;          ///< the HAL supervisor's mode this tick
  FaultCode fault = FaultCode::kNone;  ///< its latched fault
  GeneratorStatus generator = GeneratorStatus::kOk;
  std::int32_t gco = 0;                ///< gco::GcoStatus of this tick (active only)
  std::int32_t policy = -1;            ///< policy::PolicyStepCode (-1: no policy / not active)
  bool reference_limited = false;      ///< the reference rate limiter acted this tick
  bool entered_active = false;         ///< the first tick of a kActive period
};

class Controller {
 public:
  /// @param generator the PMG generator + GCO; @param policy the actor or nullptr; @param hal the
  /// HAL (its backend is the makeHalStack() stack); @param requests the supervisor's mailbox;
  /// @param telemetry publisher or nullptr; @param input_counters LCM input counters or nullptr.
  /// Setup: allocates; throws ConfigError if the config's limits disagree with the generator.
  Controller(const ControllerConfig& config, std::unique_ptr<gco::GeneratorWithGco> generator,
             std::unique_ptr<policy::PolicyStage> policy, HalRunner& hal, hal::safety::ModeRequestMailbox& requests,
             TelemetryPublisher* telemetry, const LcmInputCounters* input_counters);
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  /// One 100 Hz tick at controller time @p now [s]. noexcept, allocation-free.
  TickStatus tick(double now) noexcept;
  /// Single-gait imitation baseline (Table I, pmg_policy_sil --config single_gait): the generator
  /// runs at @p u_d with a neutral posture whatever the command, while the actor still observes
  /// the shaped command. Setup only.
  void setFixedGeneratorCommand(const VelocityCommand& u_d) noexcept {
    fixed_generator_ = true;
    fixed_u_d_ = u_d;
  }
  /// Operator input (one producer at a time: the LCM thread, a script, or a test). Wait-free.
  void setInput(const CommandSample& sample) noexcept { input_.write(sample); }

  Mode mode() const noexcept { return state_.mode; }
  FaultCode fault() const noexcept { return state_.fault; }
  const MotionGenerator& generator() const noexcept { return pmg_->generator(); }
  /// The whole reference pipeline: generator, sole levelling, stride adaptation, GCO (generator_bridge.hpp).
  const gco::GeneratorWithGco& referencePipeline() const noexcept { return *pmg_; }
  const gco::GcoResult& gcoResult() const noexcept { return pmg_->gcoResult(); }
  /// The PMG reference of the last active tick after the rate limiter (n) [rad].
  const std::array<double, kMaxMotors>& reference() const noexcept { return q_ref_; }
  /// The reference the policy was given on the last active tick: the generator output with the
  /// rate-limited (and teleop) joint references (q_ref, qd_ref (n), contacts, template base state).
  const GeneratorOutput& referenceOutput() const noexcept { return ref_out_; }
  const policy::PolicyStage* policy() const noexcept { return policy_.get(); }
  const LowCommand& lastCommand() const noexcept { return command_; }
  const LowState& lastState() const noexcept { return state_; }
  const CommandShaper& commands() const noexcept { return shaper_; }
  /// The velocity feedback stage (config velocity_feedback.enabled), or nullptr.
  const VelocityFeedback* velocityFeedback() const noexcept { return feedback_.get(); }
  /// The upset guard (velocity_feedback.upset_guard.enabled), or nullptr.
  const UpsetGuard* upsetGuard() const noexcept { return upset_guard_.get(); }
  /// The posture feedback stage (config posture_feedback.enabled), or nullptr.
  const PostureFeedback* postureFeedback() const noexcept { return posture_feedback_.get(); }
  /// The upper-body feed-forward stage (`upper_body:`), nullptr when off.
  const UpperBodyCompensation* upperBody() const noexcept { return upper_body_.get(); }
  const ReferenceRateLimiter& referenceLimiter() const noexcept { return limiter_; }
  /// Mode requests the loop forwarded to the supervisor (operator and start-up sequence).
  std::uint64_t modeRequestsPosted() const noexcept { return requests_posted_; }
  const ControllerConfig& config() const noexcept { return config_; }
  /// The teleoperation stage (config teleop.enabled), or nullptr.
  const teleop::TeleopMode* teleop() const noexcept { return teleop_.get(); }
  /// Whether the supervisor was active on any tick so far.
  bool everActive() const noexcept { return ever_active_; }
  /// Whether the start-up sequence found every motor and the IMU answering (and asked to stand).
  bool startupStandPosted() const noexcept { return startup_stand_posted_; }

 private:
  void holdStandingPose() noexcept;
  void publish(double now, const TickStatus& status, double wall_start) noexcept;

  const ControllerConfig& config_;
  std::unique_ptr<gco::GeneratorWithGco> pmg_;
  std::unique_ptr<policy::PolicyStage> policy_;
  std::unique_ptr<teleop::TeleopMode> teleop_;
  CommandSample teleop_sample_{};
  HalRunner& hal_;
  hal::safety::ModeRequestMailbox& requests_;
  TelemetryPublisher* telemetry_;
  const LcmInputCounters* input_counters_;
  CommandShaper shaper_;
  std::unique_ptr<VelocityFeedback> feedback_;
  std::unique_ptr<UpsetGuard> upset_guard_;  ///< velocity_feedback.upset_guard (nullptr when off)
  std::unique_ptr<PostureFeedback> posture_feedback_;
  std::unique_ptr<UpperBodyCompensation> upper_body_;  ///< upper_body (nullptr when off)
  ReferenceRateLimiter limiter_;
  GeneratorOutput ref_out_;  // generator output with the rate-limited reference (preallocated)
  LatestValue<CommandSample> input_;
  CommandSample sample_{};
  LowState state_{};
  LowCommand command_{};
  std::array<double, kMaxMotors> q_ref_{};
  Mode prev_mode_ = Mode::kPassive;
  std::uint32_t last_mode_seq_ = 0;
  bool startup_stand_posted_ = false, startup_active_posted_ = false;
  std::uint64_t requests_posted_ = 0;
  std::int64_t ticks_ = 0;
  double last_tick_wall_ = -1;
  double dt_ = 0.01;
  bool fixed_generator_ = false;
  bool ever_active_ = false;
  VelocityCommand fixed_u_d_{};
};

}  // namespace pmg
