#include "pmg/controller/controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "pmg/controller/lcm_command_source.hpp"
#include "pmg/controller/telemetry.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/policy/contract.hpp"
#include "pmg/policy/policy_stage.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace pmg {

Controller::Controller(const ControllerConfig& config, std::unique_ptr<gco::GeneratorWithGco> generator,
                       std::unique_ptr<policy::PolicyStage> policy, HalRunner& hal,
                       hal::safety::ModeRequestMailbox& requests, TelemetryPublisher* telemetry,
                       const LcmInputCounters* input_counters)
    : config_(config),
      pmg_(std::move(generator)),
      policy_(std::move(policy)),
      hal_(hal),
      requests_(requests),
      telemetry_(telemetry),
      input_counters_(input_counters),
      shaper_(config.commands),
      limiter_(config.commands.max_reference_speed) {
  const RobotConfig& robot = config_.robot;
  const int n = static_cast<int>(robot.numJoints());
  if (n > kMaxMotors)
    throw ConfigError(robot.source_file + ": joints: " + std::to_string(n) + " joints, at most " +
                      std::to_string(kMaxMotors) + " supported");
  if (pmg_->generatorOutput().q_ref.size() != n)
    throw ConfigError(config_.source_file + ": the generator's joint space (" +
                      std::to_string(pmg_->generatorOutput().q_ref.size()) + ") differs from the robot's " +
                      std::to_string(n) + " joints");
  // One set of command limits: the generator must accept every command the shaper lets through
  // (it would clamp a second time otherwise), so its limits must contain the shaper's.
  const CommandLimits& L = config_.commands;
  const auto& gmax = config_.generator.max_command;
  for (std::size_t i = 0; i < 3; ++i)
    if (L.max_velocity[i] > gmax[i] + 1e-12)
      throw ConfigError(config_.source_file + ": commands.max_velocity[" + std::to_string(i) + "] = " +
                        std::to_string(L.max_velocity[i]) + " exceeds generator.max_command[" + std::to_string(i) +
                        "] = " + std::to_string(gmax[i]) + ": expected <= (one set of limits, docs/controller.md)");
  // ... and GCO's u' range (the policy's training range) must contain them too.
  const gco::CommandLimits& G = config_.gco.limits;
  const auto inside = [&](const char* what, double lo, double hi, double glo, double ghi) {
    if (lo < glo - 1e-12 || hi > ghi + 1e-12)
      throw ConfigError(config_.source_file + ": commands: " + what + " [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "] exceeds the GCO limits [" + std::to_string(glo) + ", " +
                        std::to_string(ghi) + "] of " + config_.gco_file + ": expected inside");
  };
  inside("max_velocity[0]", -L.max_velocity[0], L.max_velocity[0], G.v_x_min, G.v_x_max);
  inside("max_velocity[1]", -L.max_velocity[1], L.max_velocity[1], G.v_y_min, G.v_y_max);
  inside("max_velocity[2]", -L.max_velocity[2], L.max_velocity[2], G.yaw_rate_min, G.yaw_rate_max);
  inside("height_range", L.height_range[0], L.height_range[1], G.height_min, G.height_max);
  // The velocity feedback's reach beyond max_velocity (max_velocity_headroom) must fit both as well.
  if (config_.velocity_feedback.enabled) {
    const VelocityFeedbackConfig& F = config_.velocity_feedback;
    const double glo[3] = {G.v_x_min, G.v_y_min, G.yaw_rate_min}, ghi[3] = {G.v_x_max, G.v_y_max, G.yaw_rate_max};
    for (std::size_t i = 0; i < 3; ++i) {
      const std::string axis = "[" + std::to_string(i) + "]";
      const double m = L.max_velocity[i] + F.max_velocity_headroom[i];
      const double lo = std::max(F.envelope_min[i], -m), hi = std::min(F.envelope_max[i], m);
      const double reach = std::max(-lo, hi);
      if (reach > gmax[i] + 1e-12)
        throw ConfigError(config_.source_file + ": velocity_feedback.max_velocity_headroom" + axis +
                          ": the corrected command may reach " + std::to_string(reach) + ", beyond generator.max_command" +
                          axis + " = " + std::to_string(gmax[i]) +
                          ": expected max_velocity + headroom (within envelope_min/max) <= it");
      inside(("max_velocity" + axis + " + velocity_feedback.max_velocity_headroom" + axis).c_str(), lo, hi, glo[i], ghi[i]);
    }
  }
  dt_ = 1.0 / config_.loop_rate_hz;
  ref_out_ = pmg_->generatorOutput();  // sizes the vectors once
  if (config_.teleop.enabled) teleop_ = std::make_unique<teleop::TeleopMode>(robot, config_.teleop);
  if (config_.velocity_feedback.enabled)
    feedback_ = std::make_unique<VelocityFeedback>(config_.velocity_feedback, pmg_->gco().legModel(),
                                                   pmg_->legJointIndex(), L.max_velocity);
  if (config_.velocity_feedback.enabled && config_.velocity_feedback.upset_guard.enabled)
    upset_guard_ = std::make_unique<UpsetGuard>(config_.velocity_feedback.upset_guard, pmg_->gco().legModel(),
                                                pmg_->legJointIndex(), config_.velocity_feedback);
  if (config_.posture_feedback.enabled)
    posture_feedback_ =
        std::make_unique<PostureFeedback>(config_.posture_feedback, robot, L.pitch_range, L.roll_range, L.height_range,
                                          L.standing_height, pmg_->gco().legModel(), pmg_->legJointIndex(),
                                          L.walking_min_height);
  if (config_.upper_body.enabled) {
    // The actor's joints (the legs, and the waist if it commands it) are refused.
    std::vector<std::string> actor = policy::makePolicyRobotSpec(robot, dt_).leg_joints;
    if (policy_) actor.insert(actor.end(), policy_->contract().actuated_joints.begin(), policy_->contract().actuated_joints.end());
    upper_body_ = std::make_unique<UpperBodyCompensation>(robot, config_.upper_body, actor);
  }
  command_.num_motors = n;
  holdStandingPose();
}

Controller::~Controller() = default;

void Controller::holdStandingPose() noexcept {
  const RobotConfig& robot = config_.robot;
  for (int i = 0; i < command_.num_motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const JointConfig& j = robot.joints[k];
    command_.motors[k] = MotorCommand{j.default_position, 0.0, j.kp, j.kd, 0.0};
    q_ref_[k] = j.default_position;
  }
}

TickStatus Controller::tick(double now) noexcept {
  const double wall_start = hal::rt::now();
  TickStatus status;
  // ---- read
  hal_.latest(state_);
  input_.read(sample_);
  status.mode = state_.mode;
  status.fault = state_.fault;
  const int n = command_.num_motors;

  // Operator mode requests go to the supervisor (the only mode state machine).
  if (sample_.mode_request != ModeRequest::kNone && sample_.mode_request_seq != last_mode_seq_) {
    last_mode_seq_ = sample_.mode_request_seq;
    requests_.post(sample_.mode_request);
    ++requests_posted_;
    startup_stand_posted_ = startup_active_posted_ = true;  // the operator has taken over
  }
  // Start-up sequence (safety.startup: active): stand up once every input is healthy, engage
  // once standing. Posted once each; after a fault only an operator re-engages.
  if (config_.startup == StartupMode::kActive && !startup_active_posted_) {
    bool inputs_ok = state_.imu.valid && state_.num_motors == n;
    for (int i = 0; i < n && inputs_ok; ++i) inputs_ok = state_.motors[static_cast<std::size_t>(i)].valid;
    if (!startup_stand_posted_ && state_.mode == Mode::kPassive && inputs_ok) {
      requests_.post(ModeRequest::kSoftStand);
      ++requests_posted_;
      startup_stand_posted_ = true;
    } else if (startup_stand_posted_ && !startup_active_posted_ && state_.mode == Mode::kSoftStand &&
               state_.stand_progress >= 1.0) {
      requests_.post(ModeRequest::kActive);
      ++requests_posted_;
      startup_active_posted_ = true;
    }
  }

  // ---- teleop, shape
  const bool active = state_.mode == Mode::kActive;
  const CommandSample* input = &sample_;
  if (teleop_) {
    if (!active) {
      teleop_->reset();
    } else if (teleop_->updateCommand(sample_, now, config_.commands.standing_height).command_override) {
      teleop_sample_ = sample_;
      teleop_sample_.command = teleop_->status().command;
      teleop_sample_.velocity_time = teleop_sample_.posture_time = now;
      input = &teleop_sample_;
    }
  }
  // Upset guard (velocity_feedback.upset_guard): the last tick's shaped command against its own
  // estimate of this tick's state.
  const bool hold_velocity = active && upset_guard_ && upset_guard_->update(shaper_.velocity(), shaper_.target(), state_, dt_);
  const bool upright = hold_velocity && config_.velocity_feedback.upset_guard.upright;
  shaper_.update(*input, now, dt_, hold_velocity, upright);
  ever_active_ = ever_active_ || active;
  if (active && prev_mode_ != Mode::kActive) {
    // Entering active from the standing pose: the generator, the actor and the command start
    // from rest; the reference limiter starts from the standing pose the supervisor held.
    status.entered_active = true;
    shaper_.reset();
    if (upset_guard_) upset_guard_->reset();
    if (feedback_) feedback_->reset();
    if (posture_feedback_) posture_feedback_->reset();
    pmg_->reset(0.0);
    if (policy_) policy_->reset();
    if (upper_body_) upper_body_->reset();  // the feed-forward fades in from zero
    limiter_.reset(q_ref_.data(), n);
  }
  if (!active) {  // the command takes effect only while the loop drives the motors
    shaper_.reset();
    if (upset_guard_) upset_guard_->reset();
    if (feedback_) feedback_->reset();
    if (posture_feedback_) posture_feedback_->reset();
  }
  prev_mode_ = state_.mode;

  // ---- generate / optimise
  if (active) {
    if (feedback_ && config_.velocity_feedback.brake_crouch_scaled) feedback_->setBrakeWeight(shaper_.crouchFraction());
    if (feedback_) feedback_->setCrouch(config_.commands.standing_height - shaper_.posture().height);
    const VelocityCommand* u_fb = feedback_ ? &feedback_->update(shaper_.velocity(), state_, dt_) : &shaper_.velocity();
    if (feedback_ && config_.velocity_feedback.within_posture_envelopes) {  // kept inside the crouched and bent envelopes
      const bool keep_yaw = config_.velocity_feedback.yaw_beyond_envelopes;
      std::array<double, 3> min_limit{0.0, 0.0, 0.0};  // headroom_in_envelopes: |u_i| + h_i
      if (config_.velocity_feedback.headroom_in_envelopes)
        for (std::size_t i = 0; i < 3; ++i)
          min_limit[i] = std::fabs(shaper_.velocity()[i]) + config_.velocity_feedback.max_velocity_headroom[i];
      u_fb = &feedback_->scaleDown(
          keep_yaw ? shaper_.envelopeScaleBesideYaw(*u_fb, min_limit) : shaper_.envelopeScale(*u_fb, min_limit), keep_yaw);
    }
    const VelocityCommand& u_d = *u_fb;
    const PostureCommand& u_s =
        posture_feedback_ ? posture_feedback_->update(shaper_.posture(), shaper_.velocity(), state_, dt_,
                                                      feedback_ ? &feedback_->lastEstimate() : nullptr, upright)
                          : shaper_.posture();
    const gco::GcoResult& g =
        fixed_generator_ ? pmg_->step(fixed_u_d_, PostureCommand{0.0, 0.0, config_.commands.standing_height}, dt_)
                         : pmg_->step(u_d, u_s, dt_);
    const GeneratorOutput& out = pmg_->generatorOutput();
    status.generator = out.status;
    status.gco = static_cast<std::int32_t>(g.status);
    ref_out_ = out;  // same sizes: no allocation; the limiter bounds its reference in place
    if (teleop_) teleop_->applyArms(ref_out_.q_ref.data(), ref_out_.qd_ref.data(), n, dt_);
    status.reference_limited = limiter_.apply(ref_out_.q_ref.data(), n, dt_);
    for (int i = 0; i < n; ++i) q_ref_[static_cast<std::size_t>(i)] = ref_out_.q_ref[i];

    // ---- policy (legs) or the references directly
    if (policy_) {
      // The actor observes u' (PMG eq. 19) when GCO runs, else the shaped command (after the
      // velocity feedback, when on).
      std::array<double, 6> u = shaper_.vector();
      if (config_.gco.enabled) {
        u = {g.u_opt.v_x, g.u_opt.v_y, g.u_opt.yaw_rate, g.u_opt.pitch, g.u_opt.roll, g.u_opt.height};
      } else if (!fixed_generator_) {
        u[0] = u_d.vx;
        u[1] = u_d.vy;
        u[2] = u_d.wz;
        u[3] = u_s.pitch;
        u[4] = u_s.roll;
      }
      status.policy = static_cast<std::int32_t>(policy_->step(state_, u, ref_out_, command_).code);
    } else {
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const JointConfig& j = config_.robot.joints[k];
        command_.motors[k] = MotorCommand{q_ref_[k], ref_out_.qd_ref[i], j.kp, j.kd, 0.0};
      }
    }
    if (upper_body_) upper_body_->apply(state_, command_, dt_);
  } else {
    holdStandingPose();  // ignored by the supervisor outside kActive; keeps the stream fresh
  }

  // ---- write
  ++command_.sequence;
  hal_.submit(command_);
  publish(now, status, wall_start);
  ++ticks_;
  return status;
}

void Controller::publish(double now, const TickStatus& status, double wall_start) noexcept {
  if (!telemetry_) return;
  TelemetryFrame f;
  const int n = command_.num_motors;
  f.time = now;
  f.tick = ticks_;
  f.mode = status.mode;
  f.fault = status.fault;
  f.num_joints = n;
  const bool active = status.mode == Mode::kActive;
  const GeneratorOutput& out = ref_out_;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    f.q[k] = state_.motors[k].q;
    f.qd[k] = state_.motors[k].qd;
    f.tau[k] = state_.motors[k].tau;
    // q_ref: the (rate-limited) PMG reference while active, else the standing pose
    f.q_ref[k] = q_ref_[k];
    f.qd_ref[k] = active ? out.qd_ref[i] : 0.0;
  }
  f.phase = out.phase;
  f.period = out.period;
  f.in_contact = out.in_contact;
  f.command = shaper_.vector();
  if (feedback_) {
    const VelocityCommand& u_fb = feedback_->command();
    f.command_feedback = {u_fb.vx, u_fb.vy, u_fb.wz};
    f.velocity_estimate = feedback_->filteredEstimate();
  } else {
    f.command_feedback = {f.command[0], f.command[1], f.command[2]};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    f.velocity_estimate = {nan, nan, nan};
  }
  const PostureCommand& p_fb = posture_feedback_ && active ? posture_feedback_->command() : shaper_.posture();
  f.posture_feedback = {p_fb.pitch, p_fb.roll, p_fb.height};
  const gco::GcoResult& g = pmg_->gcoResult();
  f.command_opt = {g.u_opt.v_x, g.u_opt.v_y, g.u_opt.yaw_rate, g.u_opt.pitch, g.u_opt.roll, g.u_opt.height};
  f.gco_status = status.gco;
  f.base_position = state_.base_position;
  f.base_quat = state_.base_quat_wxyz;
  f.imu_gyro = state_.imu.gyro;
  f.imu_acc = state_.imu.acc;
  f.generator_status = static_cast<std::int32_t>(status.generator);
  f.policy_status = status.policy;
  f.commands_rejected = shaper_.counters().rejected_nan + (input_counters_ ? input_counters_->rejected() : 0);
  f.reference_limited = limiter_.limitedTicks();
  if (teleop_) {
    const teleop::TeleopStatus& t = teleop_->status();
    f.teleop = (t.engaged ? 1 : 0) | (t.stream_fresh ? 2 : 0) | (static_cast<int>(t.arm[0]) << 2) |
               (static_cast<int>(t.arm[1]) << 4);
  }
  f.hal_runtime = state_.hal_runtime;
  f.hal_period = state_.hal_period;
  f.hal_overruns = state_.hal_overruns;
  f.hal_budget = hal_.cyclePeriod();
  f.loop_budget = dt_;
  const double wall_end = hal::rt::now();
  f.loop_runtime = wall_end - wall_start;
  f.loop_period = last_tick_wall_ > 0 ? wall_start - last_tick_wall_ : 0.0;
  last_tick_wall_ = wall_start;
  telemetry_->push(f);
}

}  // namespace pmg
