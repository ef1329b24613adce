#include "pmg/controller/controller_app.hpp"

#include <cstdio>
#include <sstream>

#include "pmg/clips/clip_io.hpp"
#include "pmg/controller/telemetry.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/safety/safe_backend.hpp"

namespace pmg {

std::string RunSummary::text() const {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line, "ran %lld ticks, %.2f s controller time in %.2f s wall (real-time factor %.1f)%s\n",
                static_cast<long long>(run.ticks), run.sim_time, run.wall_time, run.real_time_factor,
                run.stopped_by_flag ? ", stopped by a signal" : "");
  os << line;
  std::snprintf(line, sizeof line, "loop tick runtime  p50 %.1f us  p99 %.1f us  max %.1f us\n", 1e6 * loop.runtime_p50,
                1e6 * loop.runtime_p99, 1e6 * loop.runtime_max);
  os << line;
  std::snprintf(line, sizeof line, "HAL cycle runtime  p50 %.1f us  p99 %.1f us  max %.1f us\n", 1e6 * hal.runtime_p50,
                1e6 * hal.runtime_p99, 1e6 * hal.runtime_max);
  os << line;
  std::snprintf(line, sizeof line,
                "deadline misses %lld; commands: NaN rejected %llu, clamped %llu, stale ticks %llu, "
                "crouch-limited ticks %llu, bent-limited ticks %llu, height-floor ticks %llu, upsets %llu (held %llu ticks); "
                "reference limiter acted on %llu ticks\n",
                static_cast<long long>(deadline_misses), static_cast<unsigned long long>(commands.rejected_nan),
                static_cast<unsigned long long>(commands.clamped), static_cast<unsigned long long>(commands.stale_ticks),
                static_cast<unsigned long long>(commands.crouch_limited_ticks),
                static_cast<unsigned long long>(commands.bent_limited_ticks),
                static_cast<unsigned long long>(commands.height_floor_ticks),
                static_cast<unsigned long long>(commands.upsets),
                static_cast<unsigned long long>(commands.upset_hold_ticks),
                static_cast<unsigned long long>(reference_limited_ticks));
  os << line;
  os << "LCM command packets: accepted " << lcm_input[0] << ", rejected " << lcm_rejected;
  if (lcm_rejected > 0) {
    os << " (";
    bool first = true;
    for (std::size_t i = 1; i < kNumDecodeResults; ++i)
      if (lcm_input[i] > 0) {
        os << (first ? "" : ", ") << toString(static_cast<DecodeResult>(i)) << " " << lcm_input[i];
        first = false;
      }
    os << ")";
  }
  os << "\nmode requests posted " << mode_requests_posted << ", refused by the supervisor " << mode_requests_refused
     << "; telemetry frames written " << telemetry_written << ", dropped " << telemetry_dropped << "\n";
  os << "supervisor: " << hal_cycles << " HAL cycles, joint-cycles clamped " << clamped_joint_cycles << ", of them by the slew limit "
     << slew_clamped_joint_cycles << "\n";
  os << "final mode: " << toString(final_mode) << "; fault: " << toString(fault);
  if (fault != FaultCode::kNone) {
    std::snprintf(line, sizeof line, " (joint %d, value %.3f, at %.3f s)", fault_joint, fault_value, fault_time);
    os << line;
  }
  os << (fell() ? " -- the robot fell\n" : "\n");
  if (never_active) os << "never reached active (safety.startup: active): the motors or the IMU never all answered\n";
  if (!backend_report.empty()) os << "backend: " << backend_report << "\n";
  if (teleop_enabled)
    os << "VR teleop: engaged " << teleop_engagements << " times; stream went stale while engaged " << teleop_stale_events
       << " times\n";
  return os.str();
}

ControllerApp::ControllerApp(ControllerConfig config, ControllerAppOptions options) : config_(std::move(config)) {
  const RobotConfig& robot = config_.robot;
  const ClipLibrary clips = options.clip_files.empty() ? loadClipLibrary(config_.clips_dir, robot)
                                                       : loadClipLibrary(options.clip_files, robot);
  auto model = std::make_shared<const GeneratorModel>(clips, generatorJointSpace(robot), config_.generator);
  // The shaper's standing height ("no height command") is the generator's: the squat clip's neutral.
  if (const StaticClip* squat = model->staticClip(PostureAxis::kHeight)) config_.commands.standing_height = squat->neutral;
  if (const std::string e = config_.commands.validate(); !e.empty()) throw ConfigError(config_.source_file + ": " + e);
  auto generator = std::make_unique<gco::GeneratorWithGco>(model, gco::LegModel::fromRobotConfig(robot), config_.gco);
  std::unique_ptr<policy::PolicyStage> policy;
  if (!config_.policy_file.empty()) {
    policy::PolicyStageOptions po = options.policy;
    po.backend = config_.policy_native ? policy::PolicyBackend::kNative : policy::PolicyBackend::kOnnxRuntime;
    po.control_period = 1.0 / config_.loop_rate_hz;
    po.gco = config_.gco.enabled;
    po.sole_levelling = config_.gco.sole_levelling.enabled;
    po.stride_adaptation = config_.gco.stride_adaptation.enabled;
    po.stride_standing_hold = config_.gco.stride_adaptation.standing_hold;
    po.upright_walking = config_.generator.upright_walking;
    po.upper_body_ff = config_.upper_body.enabled;
    po.clips_digest = clipsDigest(clips);
    policy = std::make_unique<policy::PolicyStage>(config_.policy_file, robot, po);
  }
  HalStack stack = makeHalStack(robot, config_.halStack(), std::move(options.backend));
  safety_ = stack.safety;
  inner_ = stack.device;
  hal_ = std::make_unique<HalRunner>(std::move(stack.backend), static_cast<int>(robot.numJoints()));
  if (options.telemetry && (config_.lcm_enabled || !config_.log_file.empty()))
    telemetry_ = std::make_unique<TelemetryPublisher>(config_.lcm_enabled ? config_.lcm_url : "", config_.log_file);
  else if (options.telemetry)
    telemetry_ = std::make_unique<TelemetryPublisher>("", "");  // timing statistics only
  if (config_.lcm_enabled && config_.timing == TimingMode::kRealtime) {
    try {
      lcm_input_ = std::make_unique<LcmCommandSource>(
          config_.lcm_url,
          [](void* c, const CommandSample& s) noexcept { static_cast<ControllerApp*>(c)->controller_->setInput(s); },
          this, [](const void* c) noexcept { return static_cast<const ControllerApp*>(c)->runner_->now(); }, this);
      // security.key_file: every command must carry a valid MAC trailer; plain ones are refused.
      if (config_.security.enabled()) {
        lcm_input_->requireAuthentication(config_.security.key, config_.security.verifier);
        std::fprintf(stderr, "[pmg] LCM commands authenticated (key id %s, max age %.3g s)\n",
                     comms::keyId(config_.security.key).c_str(), config_.security.verifier.max_age_s);
      } else if (config_.lcm_url.find("ttl=0") == std::string::npos) {
        std::fprintf(stderr, "[pmg] warning: LCM commands are not authenticated (security.key_file empty) and the "
                             "URL '%s' is not host-local (ttl=0)\n", config_.lcm_url.c_str());
      }
    } catch (const std::exception& e) {
      lcm_input_.reset();  // never a half-configured (e.g. unauthenticated) command input
      std::fprintf(stderr, "[pmg] warning: %s; commands only from a script\n", e.what());
    }
  }
  controller_ = std::make_unique<Controller>(config_, std::move(generator), std::move(policy), *hal_,
                                             safety_->requests(), telemetry_.get(),
                                             lcm_input_ ? &lcm_input_->counters() : nullptr);
  runner_ = std::make_unique<Runner>(config_.runner(), *hal_, [this](double now) { loopTick(now); });
  hal_->cycle();  // prime: the first tick has a state
  if (telemetry_) telemetry_->start();
}

ControllerApp::~ControllerApp() {
  if (lcm_input_) lcm_input_->stop();
  if (telemetry_) telemetry_->stop();
}

TickStatus ControllerApp::stepLockstep(const CommandSample& sample) noexcept {
  controller_->setInput(sample);
  runner_->stepLockstep();
  return last_status_;
}

void ControllerApp::loopTick(double now) noexcept {
  // The script (a command source, when run() has one) writes the input, then the controller
  // ticks, then the observer sees the result.
  if (script_ != nullptr && !script_->segments.empty()) {
    segment_ = script_->segmentIndex(now);
    script_sample_.command = script_->at(now);
    script_sample_.velocity_time = script_sample_.posture_time = now;
    if (segment_ != last_segment_) {
      last_segment_ = segment_;
      const ModeRequest m = script_->segments[segment_].mode;
      if (m != ModeRequest::kNone) {
        script_sample_.mode_request = m;
        ++script_sample_.mode_request_seq;
      }
    }
    controller_->setInput(script_sample_);
  }
  last_status_ = controller_->tick(now);
  if (observer_ != nullptr && *observer_) (*observer_)(now, last_status_, segment_);
}

RunSummary ControllerApp::run(double duration, const CommandScript* script, const std::atomic<bool>* stop,
                              const TickObserver& observer) {
  script_ = script;
  observer_ = &observer;
  last_segment_ = static_cast<std::size_t>(-1);
  segment_ = 0;
  if (lcm_input_ && script == nullptr) lcm_input_->start();
  report_ = runner_->run(duration, stop);
  if (lcm_input_) lcm_input_->stop();
  script_ = nullptr;
  observer_ = nullptr;
  return finish();
}

RunSummary ControllerApp::finish() {
  RunSummary s;
  s.run = report_;
  if (telemetry_) {
    telemetry_->stop();
    s.loop = telemetry_->loopTiming().summary();
    s.telemetry_written = telemetry_->written();
    s.telemetry_dropped = telemetry_->dropped();
  }
  s.hal = hal_->timing().summary();
  s.deadline_misses = s.loop.deadline_misses + (config_.timing == TimingMode::kRealtime ? s.hal.deadline_misses : 0);
  s.commands = controller_->commands().counters();
  if (lcm_input_) {
    for (std::size_t i = 0; i < kNumDecodeResults; ++i)
      s.lcm_input[i] = lcm_input_->counters().count(static_cast<DecodeResult>(i));
    s.lcm_rejected = lcm_input_->counters().rejected();
  }
  s.reference_limited_ticks = controller_->referenceLimiter().limitedTicks();
  s.mode_requests_posted = controller_->modeRequestsPosted();
  // Asked to engage, but the motors or the IMU never all answered (a short run that was still
  // standing up is not this, nor a run a signal stopped before the inputs had kStartupGraceS to
  // answer: a SIGTERM during a slow start says nothing about the motors).
  constexpr double kStartupGraceS = 1.0;
  const bool stopped_early = s.run.stopped_by_flag && s.run.sim_time < kStartupGraceS;
  s.never_active = config_.startup == StartupMode::kActive && !controller_->everActive() &&
                   !controller_->startupStandPosted() && !stopped_early;
  s.backend_report = inner_->report();
  if (const teleop::TeleopMode* t = controller_->teleop()) {
    s.teleop_enabled = true;
    s.teleop_engagements = t->status().engagements;
    s.teleop_stale_events = t->status().stale_events;
  }
  hal::safety::SafetyStatus hs;
  safety_->status(hs);  // the newest status (fresh or not: the last cycle may have been read already)
  s.final_mode = hs.mode;
  s.fault = hs.fault.code;
  s.fault_joint = hs.fault.index;
  if (s.fault_joint >= 0 && static_cast<std::size_t>(s.fault_joint) < config_.robot.joints.size())
    s.fault_joint_name = config_.robot.joints[static_cast<std::size_t>(s.fault_joint)].name;
  s.fault_time = hs.fault.time_s;
  s.fault_value = hs.fault.value;
  s.mode_requests_refused = hs.refused_requests;
  s.hal_cycles = hs.ticks;
  s.clamped_joint_cycles = hs.clamped_joint_ticks;
  s.slew_clamped_joint_cycles = hs.slew_clamped_joint_ticks;
  return s;
}

}  // namespace pmg
