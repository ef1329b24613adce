#include "pmg/controller/controller.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/timing_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>

#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/hal/zero_offset_backend.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/bus/realtime.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"
#include "pmg/motion/clip_io.hpp"
#include "pmg/policy/policy_stage.hpp"

namespace pmg {
namespace {

double wallSeconds() { return monotonicSeconds(); }

std::int64_t toUtime(double t) { return static_cast<std::int64_t>(std::llround(t * 1e6)); }

}  // namespace

Controller::Controller(ControllerConfig config) : Controller(config, nullptr) {}

Controller::Controller(ControllerConfig config, std::unique_ptr<HalBackend> backend)
    : config_(std::move(config)), shaper_(config_.commands) {
  const RobotConfig& robot = config_.robot;
  if (robot.numJoints() > static_cast<std::size_t>(kMaxMotors))
    throw ConfigError(robot.source_file + ": joints: " + std::to_string(robot.numJoints()) + " joints, at most " +
                      std::to_string(kMaxMotors) + " supported");
  const ClipLibrary clips = loadClipLibrary(config_.clips_dir, robot);
  generator_model_ = std::make_shared<const GeneratorModel>(clips, generatorJointSpace(robot), config_.generator);
  pmg_ = std::make_unique<gco::GeneratorWithGco>(generator_model_, gco::LegModel::fromRobotConfig(robot), config_.gco);
  dt_ = 1.0 / config_.loop_rate_hz;
  if (!config_.policy_file.empty()) {
    policy::PolicyStageOptions po;
    po.backend = config_.policy_native ? policy::PolicyBackend::kNative : policy::PolicyBackend::kOnnxRuntime;
    po.control_period = dt_;
    po.gco = config_.gco.enabled;
    policy_ = std::make_unique<policy::PolicyStage>(config_.policy_file, robot, po);
  }
  if (!backend) {
    if (config_.backend == BackendKind::kCan) {
      hal::bus::CanBackendSetup setup;
      setup.plan_file = config_.can.plan_file;
      setup.transport = config_.can.transport;
      setup.udp_base_port = static_cast<std::uint16_t>(config_.can.udp_port);
      setup.lockstep = config_.timing == TimingMode::kLockstep;
      setup.paced = config_.can.paced;
      backend = hal::bus::makeCanBackend(setup);
    } else {
      backend = std::make_unique<MujocoBackend>(robot, config_.mujoco);
    }
  }
  if (robot.zeroOffsets().cwiseAbs().maxCoeff() > 0.0)  // calibrated encoder zeros (pmg_calib_zero)
    backend = std::make_unique<ZeroOffsetBackend>(std::move(backend), robot.zeroOffsets());
  if (config_.hal_supervisor) {
    auto options = hal::safety::SafetyOptions::fromRobot(robot);
    options.guard_mode = true;  // the loop runs the modes; the HAL guards inputs and the envelope
    auto safe = std::make_unique<hal::safety::SafeBackend>(std::move(backend), options);
    hal_safety_ = safe.get();
    backend = std::move(safe);
  }
  hal_ = std::make_unique<HalRunner>(std::move(backend), static_cast<int>(robot.numJoints()), config_.hal);
  command_.num_motors = static_cast<int>(robot.numJoints());

  if (config_.lcm_enabled) {
    lcm_ = std::make_unique<lcm::LCM>(config_.lcm_url);
    if (!lcm_->good()) {
      // Not fatal in the SIL: commands can come from a script; say so loudly at start-up.
      std::fprintf(stderr, "[pmg_controller] warning: LCM '%s' not available; telemetry is not published\n",
                   config_.lcm_url.c_str());
      lcm_.reset();
    }
  }
  if (!config_.log_file.empty()) {
    log_ = std::make_unique<lcm::LogFile>(config_.log_file, "w");
    if (!log_->good()) throw std::runtime_error(config_.log_file + ": cannot open LCM event log for writing");
  }
  // Prime the state so the first tick has data.
  hal_->cycle();
  hal_->latest(state_);
  publisher_running_ = true;
  publisher_ = std::thread([this] { publisherMain(); });
}

Controller::~Controller() {
  input_running_ = false;
  if (input_thread_.joinable()) input_thread_.join();
  publisher_running_ = false;
  if (publisher_.joinable()) publisher_.join();
}

void Controller::enterDamping(ControllerFault why) noexcept {
  if (mode_ != ControllerMode::kDamping && fault_ == ControllerFault::kNone) fault_ = why;
  mode_ = ControllerMode::kDamping;
}

void Controller::tick(double now) noexcept {
  const double wall_start = wallSeconds();
  hal_->latest(state_);
  input_.read(sample_);
  shaper_.update(sample_, now, dt_);
  const int n = command_.num_motors;
  const RobotConfig& robot = config_.robot;

  // Faults: invalid state or backend fault → latched damping.
  bool valid = state_.imu.valid && state_.num_motors == n;
  for (int i = 0; i < n && valid; ++i) {
    const MotorState& m = state_.motors[static_cast<std::size_t>(i)];
    valid = m.valid && std::isfinite(m.q) && std::isfinite(m.qd) && std::isfinite(m.tau);
  }
  for (double v : state_.imu.quat_wxyz) valid = valid && std::isfinite(v);
  for (double v : state_.imu.gyro) valid = valid && std::isfinite(v);
  // A few invalid ticks in a row are tolerated (the last valid command is held, below); longer
  // runs latch damping. Backend faults (simulation diverged, bus down) count the same way.
  const bool backend_fault = hal_->faultCycles() > backend_faults_seen_;
  backend_faults_seen_ = hal_->faultCycles();
  if (!valid || backend_fault) {
    if (++invalid_ticks_ > config_.max_invalid_ticks)
      enterDamping(valid ? ControllerFault::kBackendFault : ControllerFault::kInvalidState);
  } else {
    invalid_ticks_ = 0;
  }
  const bool hold = invalid_ticks_ > 0 && mode_ != ControllerMode::kDamping;

  // Operator mode requests.
  if (sample_.mode_request >= 0 && sample_.mode_request_seq != last_mode_seq_) {
    last_mode_seq_ = sample_.mode_request_seq;
    const auto req = sample_.mode_request;
    if (req == static_cast<std::int8_t>(ControllerMode::kDamping)) {
      enterDamping(ControllerFault::kEstopRequest);
      if (hal_safety_) hal_safety_->requests().post(hal::safety::ModeRequest::kDamping);
    } else if (req == 4) {  // clear the latch: only to passive, and only with a valid state
      if (mode_ == ControllerMode::kDamping && valid) {
        mode_ = ControllerMode::kPassive;
        fault_ = ControllerFault::kNone;
        if (hal_safety_) hal_safety_->requests().post(hal::safety::ModeRequest::kPassive);
      }
    } else if (mode_ != ControllerMode::kDamping) {
      if (req == static_cast<std::int8_t>(ControllerMode::kPassive)) mode_ = ControllerMode::kPassive;
      if (req == static_cast<std::int8_t>(ControllerMode::kSoftStand)) {
        mode_ = ControllerMode::kSoftStand;
        have_stand_start_ = false;
      }
      if (req == static_cast<std::int8_t>(ControllerMode::kActive) && mode_ == ControllerMode::kSoftStand) {
        mode_ = ControllerMode::kActive;
        pmg_->reset(0.0);
        if (policy_) policy_->reset();
      }
    }
  }

  GeneratorStatus gen_status = GeneratorStatus::kOk;
  // While an invalid state is being tolerated the last command is held unchanged.
  if (!hold) switch (mode_) {
    case ControllerMode::kPassive:
      for (int i = 0; i < n; ++i) command_.motors[static_cast<std::size_t>(i)] = MotorCommand{};
      break;
    case ControllerMode::kSoftStand: {
      if (!have_stand_start_) {
        for (int i = 0; i < n; ++i) stand_start_[static_cast<std::size_t>(i)] = state_.motors[static_cast<std::size_t>(i)].q;
        mode_start_time_ = now;
        have_stand_start_ = true;
      }
      const double T = config_.soft_stand_duration;
      const double s = T > 0 ? std::clamp((now - mode_start_time_) / T, 0.0, 1.0) : 1.0;
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const JointConfig& j = robot.joints[k];
        command_.motors[k] = MotorCommand{(1 - s) * stand_start_[k] + s * j.default_position, 0.0, j.kp, j.kd, 0.0};
      }
      if (s >= 1.0) {  // standing reached: hand over to PMG (and the policy)
        mode_ = ControllerMode::kActive;
        pmg_->reset(0.0);
        shaper_.reset();
        if (policy_) policy_->reset();
      }
      break;
    }
    case ControllerMode::kActive: {
      pmg_->step(shaper_.velocity(), shaper_.posture(), dt_);
      const GeneratorOutput& out = pmg_->generatorOutput();
      gen_status = out.status;
      if (policy_) {
        // The actor observes u' (PMG eq. 19) when GCO runs, else the shaped command.
        const gco::GcoResult& g = pmg_->gcoResult();
        const VelocityCommand& v = shaper_.velocity();
        const PostureCommand& p = shaper_.posture();
        const std::array<double, 6> u =
            config_.gco.enabled
                ? std::array<double, 6>{g.u_opt.v_x, g.u_opt.v_y, g.u_opt.yaw_rate, g.u_opt.pitch, g.u_opt.roll,
                                        g.u_opt.height}
                : std::array<double, 6>{v.vx, v.vy, v.wz, p.pitch, p.roll, p.height > 0 ? p.height : out.base_height};
        policy_->step(state_, u, out, command_);
      } else {
        for (int i = 0; i < n; ++i) {
          const auto k = static_cast<std::size_t>(i);
          const JointConfig& j = robot.joints[k];
          command_.motors[k] = MotorCommand{out.q_ref[i], out.qd_ref[i], j.kp, j.kd, 0.0};
        }
      }
      break;
    }
    case ControllerMode::kDamping:
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        command_.motors[k] = MotorCommand{0.0, 0.0, 0.0, config_.damping_kd_scale * robot.joints[k].kd, 0.0};
      }
      break;
  }
  ++command_.sequence;
  hal_->submit(command_);

  // Telemetry frame (copied into the ring; published by another thread).
  TelemetryFrame& f = frame_;
  f.time = now;
  f.tick = ticks_;
  f.mode = static_cast<std::int8_t>(mode_);
  f.num_joints = n;
  const GeneratorOutput& out = pmg_->generatorOutput();
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    f.q[k] = state_.motors[k].q;
    f.qd[k] = state_.motors[k].qd;
    f.tau[k] = state_.motors[k].tau;
    // q_ref = the PMG reference while active (with a policy the motor targets are the actor's),
    // else the motor command (soft stand, damping).
    const bool pmg_ref = mode_ == ControllerMode::kActive;
    f.q_ref[k] = pmg_ref ? out.q_ref[i] : command_.motors[k].q;
    f.qd_ref[k] = pmg_ref ? out.qd_ref[i] : command_.motors[k].qd;
  }
  f.phase = out.phase;
  f.period = out.period;
  f.in_contact = out.in_contact;
  const VelocityCommand& v = shaper_.velocity();
  const PostureCommand& p = shaper_.posture();
  f.command = {v.vx, v.vy, v.wz, p.pitch, p.roll, p.height};
  const gco::GcoResult& g = pmg_->gcoResult();
  f.command_opt = {g.u_opt.v_x, g.u_opt.v_y, g.u_opt.yaw_rate, g.u_opt.pitch, g.u_opt.roll, g.u_opt.height};
  f.gco_status = static_cast<std::int32_t>(g.status);
  f.base_position = state_.base_position;
  f.base_quat = state_.base_quat_wxyz;
  f.imu_gyro = state_.imu.gyro;
  f.imu_acc = state_.imu.acc;
  f.generator_status = static_cast<std::int32_t>(gen_status);
  f.fault = static_cast<std::int32_t>(fault_);
  f.hal_runtime = state_.hal_runtime;
  f.hal_period = state_.hal_period;
  f.hal_overruns = state_.hal_overruns;
  const double wall_end = wallSeconds();
  f.loop_runtime = wall_end - wall_start;
  f.loop_period = last_tick_wall_ > 0 ? wall_start - last_tick_wall_ : 0.0;
  last_tick_wall_ = wall_start;
  if (f.loop_runtime > dt_) ++deadline_misses_;
  telemetry_.push(f);
  ++ticks_;
}

void Controller::drainTelemetry() {
  TelemetryFrame f;
  pmg_lcm::controller_state_t msg;
  while (telemetry_.pop(f)) {
    loop_timing_.record(f.loop_runtime, f.loop_period, f.loop_runtime > dt_);
    if (f.hal_period > 0) hal_timing_.record(f.hal_runtime, f.hal_period, false);
    if (!lcm_ && !log_) continue;
    msg.utime = toUtime(f.time);
    msg.tick = f.tick;
    msg.mode = f.mode;
    msg.num_joints = f.num_joints;
    const auto nj = static_cast<std::size_t>(f.num_joints);
    msg.q.assign(f.q.begin(), f.q.begin() + static_cast<std::ptrdiff_t>(nj));
    msg.qd.assign(f.qd.begin(), f.qd.begin() + static_cast<std::ptrdiff_t>(nj));
    msg.tau.assign(f.tau.begin(), f.tau.begin() + static_cast<std::ptrdiff_t>(nj));
    msg.q_ref.assign(f.q_ref.begin(), f.q_ref.begin() + static_cast<std::ptrdiff_t>(nj));
    msg.qd_ref.assign(f.qd_ref.begin(), f.qd_ref.begin() + static_cast<std::ptrdiff_t>(nj));
    msg.phase = f.phase;
    msg.period = f.period;
    msg.in_contact[0] = f.in_contact[0];
    msg.in_contact[1] = f.in_contact[1];
    for (int i = 0; i < 6; ++i) {
      msg.command[i] = f.command[static_cast<std::size_t>(i)];
      msg.command_opt[i] = f.command_opt[static_cast<std::size_t>(i)];
    }
    msg.gco_status = f.gco_status;
    for (int i = 0; i < 3; ++i) {
      msg.base_position[i] = f.base_position[static_cast<std::size_t>(i)];
      msg.imu_gyro[i] = f.imu_gyro[static_cast<std::size_t>(i)];
      msg.imu_acc[i] = f.imu_acc[static_cast<std::size_t>(i)];
    }
    for (int i = 0; i < 4; ++i) msg.base_quat[i] = f.base_quat[static_cast<std::size_t>(i)];
    msg.generator_status = f.generator_status;
    msg.fault = f.fault;
    const int size = msg.getEncodedSize();
    std::vector<std::uint8_t> buffer(static_cast<std::size_t>(size));
    msg.encode(buffer.data(), 0, size);
    if (lcm_) lcm_->publish("PMG_STATE", buffer.data(), static_cast<unsigned>(size));
    if (log_) {
      lcm::LogEvent ev{};
      ev.eventnum = static_cast<int64_t>(telemetry_written_);
      ev.timestamp = msg.utime;
      ev.channel = "PMG_STATE";
      ev.datalen = size;
      ev.data = buffer.data();
      log_->writeEvent(&ev);
    }
    ++telemetry_written_;
    if (f.tick % 100 == 99) {  // 1 Hz timing reports: the loop, and the HAL (real time)
      publishTiming("loop", loop_timing_.summary(), dt_, msg.utime, loop_timing_.deadlineMisses());
      if (hal_timing_.cycles() > 0)
        publishTiming("hal", hal_timing_.summary(), hal_->cyclePeriod(), msg.utime,
                      static_cast<std::int64_t>(f.hal_overruns));
    }
  }
}

void Controller::publishTiming(const char* task, const TimingSummary& s, double period, std::int64_t utime,
                               std::int64_t misses) {
  pmg_lcm::timing_t t;
  t.utime = utime;
  t.task = task;
  t.cycles = s.cycles;
  t.period_target_s = period;
  t.runtime_p50_s = s.runtime_p50;
  t.runtime_p99_s = s.runtime_p99;
  t.runtime_max_s = s.runtime_max;
  t.period_p50_s = s.period_p50;
  t.period_p99_s = s.period_p99;
  t.period_max_s = s.period_max;
  t.deadline_misses = misses;
  const int size = t.getEncodedSize();
  std::vector<std::uint8_t> buffer(static_cast<std::size_t>(size));
  t.encode(buffer.data(), 0, size);
  if (lcm_) lcm_->publish("PMG_TIMING", buffer.data(), static_cast<unsigned>(size));
  if (log_) {
    lcm::LogEvent ev{};
    ev.timestamp = utime;
    ev.channel = "PMG_TIMING";
    ev.datalen = size;
    ev.data = buffer.data();
    log_->writeEvent(&ev);
  }
}

void Controller::publisherMain() {
  while (publisher_running_.load()) {
    drainTelemetry();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  drainTelemetry();
}

void Controller::lcmInputMain() {
  // Own LCM instance for receiving (handled on this thread only).
  lcm::LCM rx(config_.lcm_url);
  if (!rx.good()) return;
  CommandSample sample;
  const double t0_wall = wallSeconds();
  struct Handler {
    Controller* self;
    CommandSample* sample;
    double t0;
    void velocity(const lcm::ReceiveBuffer*, const std::string&, const pmg_lcm::velocity_command_t* m) {
      sample->velocity = {m->vx, m->vy, m->wz};
      sample->velocity_time = wallSeconds() - t0;
      self->setInput(*sample);
    }
    void posture(const lcm::ReceiveBuffer*, const std::string&, const pmg_lcm::posture_command_t* m) {
      sample->posture = {m->pitch, m->roll, m->height};
      sample->posture_time = wallSeconds() - t0;
      self->setInput(*sample);
    }
    void mode(const lcm::ReceiveBuffer*, const std::string&, const pmg_lcm::mode_command_t* m) {
      sample->mode_request = m->mode;
      ++sample->mode_request_seq;
      self->setInput(*sample);
    }
  } handler{this, &sample, t0_wall};
  rx.subscribe("PMG_VELOCITY_COMMAND", &Handler::velocity, &handler);
  rx.subscribe("PMG_POSTURE_COMMAND", &Handler::posture, &handler);
  rx.subscribe("PMG_MODE_COMMAND", &Handler::mode, &handler);
  while (input_running_.load()) rx.handleTimeout(20);
}

void Controller::injectScript(const CommandScript& script, double now, CommandSample& sample) noexcept {
  const CommandSegment& seg = script.at(now);
  sample.velocity = seg.velocity;
  sample.posture = seg.posture;
  sample.velocity_time = sample.posture_time = now;
  setInput(sample);
}

RunSummary Controller::runLockstep(double duration, const CommandScript* script) {
  const int cycles = config_.cyclesPerTick();
  const auto ticks = static_cast<std::int64_t>(std::llround(duration * config_.loop_rate_hz));
  CommandSample sample;
  const double wall0 = wallSeconds();
  for (std::int64_t k = 0; k < ticks; ++k) {
    const double now = static_cast<double>(k) * dt_;
    if (script) injectScript(*script, now, sample);
    tick(now);
    for (int c = 0; c < cycles; ++c) {
      const double h0 = wallSeconds();
      hal_->cycle();
      const double h1 = wallSeconds();
      hal_->timing().record(h1 - h0, 0.0, (h1 - h0) > hal_->cyclePeriod());
    }
  }
  RunSummary s;
  s.wall_time = wallSeconds() - wall0;
  s.ticks = ticks;
  s.sim_time = static_cast<double>(ticks) * dt_;
  s.real_time_factor = s.wall_time > 0 ? s.sim_time / s.wall_time : 0;
  // Let the publisher drain everything, then summarise.
  while (true) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (telemetry_written_ + telemetry_.dropped() >= static_cast<std::uint64_t>(ticks_) || (!lcm_ && !log_)) break;
  }
  finishRun(s, /*count_hal_misses=*/false);
  return s;
}

RunSummary Controller::runRealtime(double duration, const std::atomic<bool>* stop, const CommandScript* script) {
  if (lcm_ && !script) {
    input_running_ = true;
    input_thread_ = std::thread([this] { lcmInputMain(); });
  }
  std::string error;
  if (config_.lock_memory && !hal::rt::lockMemory(&error))
    std::fprintf(stderr, "[pmg_controller] warning: mlockall failed: %s\n", error.c_str());
  if (!hal_->start(&error)) std::fprintf(stderr, "[pmg_controller] warning: %s\n", error.c_str());
  if (config_.loop_fifo_priority > 0) {
    sched_param sp{};
    sp.sched_priority = config_.loop_fifo_priority;
    if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) != 0)
      std::fprintf(stderr, "[pmg_controller] warning: loop SCHED_FIFO not granted (running with normal priority)\n");
  }
  const double wall0 = wallSeconds();
  double next = wall0;
  CommandSample sample;
  std::int64_t k = 0;
  while (true) {
    const double now = wallSeconds() - wall0;
    if ((duration > 0 && now >= duration) || (stop && stop->load())) break;
    if (script) injectScript(*script, now, sample);
    tick(now);
    ++k;
    next += dt_;
    const double after = wallSeconds();
    if (after > next) {  // overran: count and re-anchor
      ++deadline_misses_;
      next = after;
    }
    sleepUntil(next);
  }
  hal_->stop();
  input_running_ = false;
  if (input_thread_.joinable()) input_thread_.join();
  RunSummary s;
  s.wall_time = wallSeconds() - wall0;
  s.ticks = k;
  s.sim_time = hal_->backend().cyclePeriod() * static_cast<double>(hal_->timing().cycles());
  s.real_time_factor = s.wall_time > 0 ? s.sim_time / s.wall_time : 0;
  finishRun(s, /*count_hal_misses=*/true);
  return s;
}

void Controller::finishRun(RunSummary& s, bool count_hal_misses) {
  publisher_running_ = false;  // drain the telemetry, then summarise
  if (publisher_.joinable()) publisher_.join();
  s.loop = loop_timing_.summary();
  s.hal = hal_->timing().summary();
  s.deadline_misses = deadline_misses_ + (count_hal_misses ? s.hal.deadline_misses : 0);
  s.commands = shaper_.counters();
  s.telemetry_dropped = telemetry_.dropped();
  s.telemetry_written = telemetry_written_;
  s.fault = fault_;
  s.final_mode = mode_;
  if (log_) log_.reset();  // flush and close the event log
}

}  // namespace pmg
