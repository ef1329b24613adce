// The 100 Hz tick (controller.cpp) through the product path (ControllerApp: HAL stack with the
// supervisor, shaper, generator + GCO, reference limiter), on the G1 in the MuJoCo 2.2 gantry SIL.
//
// Reference continuity (defect 2 of issue 11): a sweep of abrupt command steps on every axis and
// combination, "none" <-> value heights, reversals, operator mode changes and script edges. Two
// things are asserted on every tick / HAL cycle:
//  - the PMG reference the loop sends moves at most CommandLimits::max_reference_speed (6 rad/s;
//    walking references peak near 3.6 rad/s), and the reference limiter never had to act: the
//    command shaper alone keeps the references continuous;
//  - the position the supervisor actually sends to the motors (kp > 0) moves at most as fast, over
//    every loop period (within one period the HAL sees the 100 Hz target as a step that its
//    q_rate_max slew spreads over the cycles).
#include <cmath>
#include <cstdio>

#include <utility>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"

namespace pmg {
namespace {

ControllerConfig silConfig(bool velocity_feedback = false, double brake_ratio = 0.0) {
  ControllerConfig c = loadControllerConfig(test::g1SilControllerConfigPath());
  c.makeOffline();
  c.velocity_feedback.enabled = velocity_feedback;
  c.velocity_feedback.brake_ratio = brake_ratio;
  c.posture_feedback.enabled = velocity_feedback;  // both feedback stages together, the height too
  c.posture_feedback.height_ki = velocity_feedback ? 1.0 : 0.0;
  return c;
}

// Wraps the SIL and records the fastest change of the position sent to a motor with kp > 0, over
// one loop period (5 HAL cycles: the loop's 100 Hz targets reach the 500 Hz HAL as steps).
class RecordingBackend final : public HalBackend {
 public:
  RecordingBackend(const RobotConfig& r, const MujocoBackendOptions& o) : sim_(r, o) {}
  const char* name() const noexcept override { return "recording"; }
  double cyclePeriod() const noexcept override { return sim_.cyclePeriod(); }
  BackendStatus exchange(const LowCommand& c, LowState& s) noexcept override {
    const LowCommand& old = history_[cycle_ % kWindow];  // the command kWindow cycles ago
    if (cycle_ >= kWindow) {
      for (int i = 0; i < c.num_motors; ++i) {
        const auto k = static_cast<std::size_t>(i);
        bool stiff = c.motors[k].kp > 0;
        for (const LowCommand& h : history_) stiff = stiff && h.motors[k].kp > 0;
        if (!stiff) continue;
        const double speed = std::fabs(c.motors[k].q - old.motors[k].q) / (kWindow * sim_.cyclePeriod());
        if (speed > max_sent_speed) {
          max_sent_speed = speed;
          max_joint = i;
          std::snprintf(max_at, sizeof max_at, "%s", phase);
          max_time = time;
        }
      }
    }
    history_[cycle_ % kWindow] = c;
    ++cycle_;
    return sim_.exchange(c, s);
  }
  double max_sent_speed = 0.0;
  int max_joint = -1;
  const char* phase = "";  // label of the sweep step (set by the test)
  char max_at[64] = "";
  double time = 0.0, max_time = 0.0;

 private:
  static constexpr std::size_t kWindow = 5;
  MujocoBackend sim_;
  std::array<LowCommand, kWindow> history_{};
  std::size_t cycle_ = 0;
};

struct Sweep {
  ControllerConfig config;
  RecordingBackend* recorder = nullptr;
  std::unique_ptr<ControllerApp> app;
  CommandSample sample;
  double t = 0.0;
  double max_ref_speed = 0.0;
  std::string worst_at;
  std::array<double, kMaxMotors> prev_ref{};
  bool have_prev = false;

  explicit Sweep(bool velocity_feedback = false, double brake_ratio = 0.0) : Sweep(silConfig(velocity_feedback, brake_ratio)) {}
  explicit Sweep(ControllerConfig c) : config(std::move(c)) {
    ControllerAppOptions o;
    auto rec = std::make_unique<RecordingBackend>(config.robot, config.mujoco);
    recorder = rec.get();
    o.backend = std::move(rec);
    app = std::make_unique<ControllerApp>(config, std::move(o));
  }
  void hold(const Command& u, double seconds, const std::string& label) {
    const int n = static_cast<int>(config.robot.numJoints());
    for (int k = 0; k < static_cast<int>(std::lround(seconds / 0.01)); ++k, t += 0.01) {
      sample.command = u;
      sample.velocity_time = sample.posture_time = t;
      recorder->phase = label.c_str();
      recorder->time = t;
      const TickStatus s = app->stepLockstep(sample);
      const auto& ref = app->controller().reference();
      if (have_prev && s.mode == Mode::kActive && !s.entered_active) {
        for (int i = 0; i < n; ++i) {
          const double v = std::fabs(ref[static_cast<std::size_t>(i)] - prev_ref[static_cast<std::size_t>(i)]) / 0.01;
          if (v > max_ref_speed) {
            max_ref_speed = v;
            worst_at = label + " (" + config.robot.joints[static_cast<std::size_t>(i)].name + ")";
          }
        }
      }
      prev_ref = ref;
      have_prev = true;
    }
  }
  void request(ModeRequest r) {
    sample.mode_request = r;
    ++sample.mode_request_seq;
  }
};

Command cmd(double vx, double vy, double wz, double pitch = 0, double roll = 0, std::optional<double> h = {}) {
  return Command{vx, vy, wz, pitch, roll, h};
}

TEST(ReferenceContinuity, AbruptCommandSweepKeepsEveryJointReferenceUnderTheBound) {
  Sweep s;
  const CommandLimits& L = s.config.commands;
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  const double vx = L.max_velocity[0], vy = L.max_velocity[1], wz = L.max_velocity[2];
  const std::vector<std::pair<std::string, Command>> steps = {
      {"+vx", cmd(vx, 0, 0)},
      {"-vx", cmd(-vx, 0, 0)},
      {"+vy", cmd(0, vy, 0)},
      {"-vy", cmd(0, -vy, 0)},
      {"+wz", cmd(0, 0, wz)},
      {"-wz", cmd(0, 0, -wz)},
      {"+pitch", cmd(0, 0, 0, L.pitch_range[1])},
      {"-pitch", cmd(0, 0, 0, L.pitch_range[0])},
      {"+roll", cmd(0, 0, 0, 0, L.roll_range[1])},
      {"-roll", cmd(0, 0, 0, 0, L.roll_range[0])},
      {"height none->min", cmd(0, 0, 0, 0, 0, L.height_range[0])},
      {"height none->max", cmd(0, 0, 0, 0, 0, L.height_range[1])},
      {"vx+vy+wz", cmd(vx, vy, wz)},
      {"-vx-vy-wz", cmd(-vx, -vy, -wz)},
      {"vx-wz+pitch+squat", cmd(vx, 0, -wz, L.pitch_range[1], 0, L.height_range[0])},
      {"everything", cmd(vx, -vy, wz, L.pitch_range[0], L.roll_range[1], L.height_range[0])},
  };
  for (const auto& [label, u] : steps) {
    s.hold(u, 2.0, label);                    // step from rest ("none" height) to the target
    s.hold(cmd(0, 0, 0), 1.5, label + " back");  // and back to rest
  }
  // Reversals: +max -> -max without passing through a rest segment.
  s.hold(cmd(vx, 0, wz), 1.5, "reversal setup");
  s.hold(cmd(-vx, 0, -wz), 1.5, "reversal");
  s.hold(cmd(0, 0, 0, 0, 0, L.height_range[0]), 2.0, "squat");
  s.hold(cmd(vx, vy, 0, 0, 0, std::nullopt), 2.0, "squat -> none while walking");
  // Operator mode changes: active -> soft stand (while walking) -> active again.
  s.request(ModeRequest::kSoftStand);
  s.hold(cmd(0.5, 0, 0), 1.5, "active->soft stand");
  EXPECT_EQ(s.app->controller().mode(), Mode::kSoftStand);
  s.request(ModeRequest::kActive);
  s.hold(cmd(0.5, 0, 0), 2.0, "soft stand->active");
  EXPECT_EQ(s.app->controller().mode(), Mode::kActive);

  const double bound = L.max_reference_speed;
  std::printf("[ SIL ] abrupt-command sweep: fastest PMG reference %.2f rad/s at %s; fastest sent position %.2f rad/s "
              "(joint %d, %s, t %.2f s); bound %.1f rad/s; limiter acted on %llu ticks\n",
              s.max_ref_speed, s.worst_at.c_str(), s.recorder->max_sent_speed, s.recorder->max_joint,
              s.recorder->max_at, s.recorder->max_time, bound,
              static_cast<unsigned long long>(s.app->controller().referenceLimiter().limitedTicks()));
  EXPECT_LE(s.max_ref_speed, bound + 1e-9) << s.worst_at;
  EXPECT_LE(s.recorder->max_sent_speed, bound + 1e-9) << "joint " << s.recorder->max_joint;
  EXPECT_EQ(s.app->controller().referenceLimiter().limitedTicks(), 0u)
      << "the shaper alone should keep the references under the bound";
  EXPECT_GT(s.max_ref_speed, 1.0) << "the sweep really moved the references";
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
}

// The velocity feedback (velocity_feedback.hpp) in the gantry: the legs swing in the air, so leg
// odometry reads nonsense and the correction sits at its bound r |u| -- its worst case. Abrupt
// steps, reversals and mode changes still keep every reference under the bound.
TEST(ReferenceContinuity, VelocityFeedbackAtItsBoundKeepsEveryJointReferenceUnderTheBound) {
  Sweep s(true);
  const CommandLimits& L = s.config.commands;
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  ASSERT_NE(s.app->controller().velocityFeedback(), nullptr);
  const double vx = L.max_velocity[0], vy = L.max_velocity[1], wz = L.max_velocity[2];
  double max_correction_share = 0.0;
  for (const auto& [label, u] : std::vector<std::pair<std::string, Command>>{
           {"+vx", cmd(0.5 * vx, 0, 0)}, {"-vx+wz", cmd(-0.5 * vx, 0, 0.5 * wz)}, {"vy-wz", cmd(0, 0.5 * vy, -0.5 * wz)},
           {"reversal", cmd(-0.5 * vx, -0.5 * vy, 0.5 * wz)}, {"everything", cmd(vx, vy, wz, 0.2, 0.1, 0.7)}}) {
    s.hold(u, 2.0, label);
    const VelocityFeedback& fb = *s.app->controller().velocityFeedback();
    const VelocityCommand& shaped = s.app->controller().commands().velocity();
    for (std::size_t i = 0; i < 3; ++i)
      if (std::fabs(shaped[i]) > 1e-6)
        max_correction_share = std::max(max_correction_share, std::fabs(fb.correction()[i]) / std::fabs(shaped[i]));
  }
  s.hold(cmd(0, 0, 0), 1.5, "stop");
  EXPECT_EQ(s.app->controller().velocityFeedback()->command().vx, 0.0) << "standing: no correction left";
  s.request(ModeRequest::kSoftStand);
  s.hold(cmd(0.5, 0, 0), 1.0, "active->soft stand");
  s.request(ModeRequest::kActive);
  s.hold(cmd(0.5, 0, 0), 2.0, "soft stand->active");
  std::printf("[ SIL ] velocity feedback in the gantry: largest correction %.2f of |u|; fastest PMG reference %.2f "
              "rad/s at %s; limiter acted on %llu ticks\n",
              max_correction_share, s.max_ref_speed, s.worst_at.c_str(),
              static_cast<unsigned long long>(s.app->controller().referenceLimiter().limitedTicks()));
  EXPECT_GT(max_correction_share, 0.3) << "the correction really acted";
  EXPECT_LE(max_correction_share, s.config.velocity_feedback.max_ratio + 1e-9);
  EXPECT_LE(s.max_ref_speed, L.max_reference_speed + 1e-9) << s.worst_at;
  EXPECT_LE(s.recorder->max_sent_speed, L.max_reference_speed + 1e-9);
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
}

// Braking steps (velocity_feedback.brake_ratio) in the gantry, where leg odometry reads the legs
// swinging in the air as motion: abrupt commands and stops keep every joint reference under the
// bound, and the floor, which decays at least at brake_decel, is gone within |u| / brake_decel
// after the stop.
TEST(ReferenceContinuity, BrakingStepsInTheGantryKeepEveryJointReferenceUnderTheBound) {
  Sweep s(true, 0.8);
  const CommandLimits& L = s.config.commands;
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  const double vx = L.max_velocity[0], vy = L.max_velocity[1];
  for (const auto& [label, u] : std::vector<std::pair<std::string, Command>>{
           {"+vx", cmd(0.8 * vx, 0, 0)}, {"stop", cmd(0, 0, 0)}, {"-vx-vy", cmd(-0.5 * vx, -0.8 * vy, 0)},
           {"reversal", cmd(0.8 * vx, 0.8 * vy, 0)}, {"stop again", cmd(0, 0, 0)}})
    s.hold(u, 2.0, label);
  const double linger = 0.8 * vx / s.config.velocity_feedback.brake_decel + 0.5;
  s.hold(cmd(0, 0, 0), linger, "standing");
  const VelocityFeedback& fb = *s.app->controller().velocityFeedback();
  std::printf("[ SIL ] braking steps in the gantry: floor acted on %llu ticks; fastest PMG reference %.2f rad/s at %s\n",
              static_cast<unsigned long long>(fb.brakingTicks()), s.max_ref_speed, s.worst_at.c_str());
  EXPECT_EQ(fb.command().vx, 0.0) << "the floor is gone " << linger << " s after the stop";
  EXPECT_EQ(fb.command().vy, 0.0);
  EXPECT_LE(s.max_ref_speed, L.max_reference_speed + 1e-9) << s.worst_at;
  EXPECT_LE(s.recorder->max_sent_speed, L.max_reference_speed + 1e-9);
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
}

// Braking steps scaled by the crouch (velocity_feedback.brake_crouch_scaled), through the
// controller in the gantry, where the odometry reads the swinging legs as motion: at the standing
// height, upright or bent, the floor never acts; crouched it does, and the references stay under the
// bound through the stops and posture changes.
TEST(ReferenceContinuity, CrouchScaledBrakingActsOnlyCrouchedAndKeepsReferencesUnderTheBound) {
  // The same abrupt walks and stops as the test above, upright, bent to bent_pitch at the standing
  // height, and crouched to crouched_height (weight 1).
  struct Ticks {
    std::uint64_t upright = 0, bent = 0, crouched = 0;
  };
  const auto sweep = [](bool scaled) {
    ControllerConfig c = silConfig(true, 0.8);
    c.velocity_feedback.brake_crouch_scaled = scaled;
    c.commands.crouched_height = 0.62;
    c.commands.bent_pitch = 0.4;
    Sweep s(std::move(c));
    const CommandLimits& L = s.config.commands;
    s.hold(cmd(0, 0, 0), 1.5, "engage");
    EXPECT_EQ(s.app->controller().mode(), Mode::kActive);
    const VelocityFeedback& fb = *s.app->controller().velocityFeedback();
    const double vx = L.max_velocity[0], vy = L.max_velocity[1], linger = 0.8 * vx / s.config.velocity_feedback.brake_decel + 0.5;
    const auto walks = [&](double pitch, std::optional<double> h, const std::string& at) {
      const std::uint64_t before = fb.brakingTicks();
      s.hold(cmd(0, 0, 0, pitch, 0, h), 2.0, at + " pose");
      for (const auto& [label, u] : std::vector<std::pair<std::string, Command>>{
               {"+vx", cmd(0.8 * vx, 0, 0, pitch, 0, h)}, {"stop", cmd(0, 0, 0, pitch, 0, h)},
               {"-vx-vy", cmd(-0.5 * vx, -0.8 * vy, 0, pitch, 0, h)}, {"stop again", cmd(0, 0, 0, pitch, 0, h)}})
        s.hold(u, 2.0, at + " " + label);
      s.hold(cmd(0, 0, 0, pitch, 0, h), linger, at + " standing");
      EXPECT_EQ(fb.command().vx, 0.0) << at << ": the floor is gone " << linger << " s after the stop";
      EXPECT_EQ(fb.command().vy, 0.0) << at;
      return fb.brakingTicks() - before;
    };
    Ticks t;
    t.upright = walks(0.0, std::nullopt, "upright");
    t.bent = walks(0.4, std::nullopt, "bent");
    EXPECT_EQ(s.app->controller().commands().crouchFraction(), 0.0);
    t.crouched = walks(0.0, 0.62, "crouched");
    EXPECT_EQ(s.app->controller().commands().crouchFraction(), 1.0);
    s.hold(cmd(0, 0, 0), 2.0, "upright again");
    std::printf("[ SIL ] braking %s in the gantry: floor acted on %llu ticks upright, %llu bent, %llu crouched; fastest PMG "
                "reference %.2f rad/s at %s\n", scaled ? "scaled by the crouch" : "unscaled",
                static_cast<unsigned long long>(t.upright), static_cast<unsigned long long>(t.bent),
                static_cast<unsigned long long>(t.crouched), s.max_ref_speed, s.worst_at.c_str());
    EXPECT_LE(s.max_ref_speed, L.max_reference_speed + 1e-9) << s.worst_at;
    EXPECT_LE(s.recorder->max_sent_speed, L.max_reference_speed + 1e-9);
    EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
    return t;
  };
  const Ticks unscaled = sweep(false), scaled = sweep(true);
  ASSERT_GT(unscaled.upright, 0u) << "the gantry's odometry outruns the stopping command upright";
  ASSERT_GT(unscaled.bent, 0u) << "and bent";
  EXPECT_EQ(scaled.upright, 0u) << "scaled by the crouch: no braking at the standing height";
  EXPECT_EQ(scaled.bent, 0u) << "bent at the standing height neither";
  EXPECT_GT(scaled.crouched, 0u) << "crouched it brakes";
}

// The feed-forward's gains per crouch through the controller: it passes the shaped crouch
// (standing_height − the shaped pelvis height) to the feedback on every tick, so a backward walk
// crouched to 0.70 m gets the crouched gain's inverse and upright the upright one, and the
// feed-forward moves continuously while the height slews between them.
TEST(Controller, FeedforwardTakesItsGainsAtTheShapedCrouch) {
  ControllerConfig c = silConfig(true);
  c.commands.crouched_height = 0.62;
  CommandResponseModel& ff = c.velocity_feedback.feedforward;
  ff.enabled = true;
  ff.axes[0].gain_negative = 0.84;
  ff.axes[0].gain_negative_per_crouch = 6.0;  // 1.23 at 0.065 m
  ff.max_correction = {0.3, 0.2, 0.4};
  Sweep s(std::move(c));
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  const VelocityFeedback& fb = *s.app->controller().velocityFeedback();
  s.hold(cmd(-0.3, 0, 0), 1.0, "upright backward");
  EXPECT_NEAR(fb.crouch(), 0.0, 1e-12);
  EXPECT_NEAR(fb.feedforward()[0], -0.3 / 0.84, 1e-9) << "upright: the upright gain";
  double largest_step = 0.0, prev = fb.feedforward()[0];
  const int ticks = static_cast<int>(std::ceil(0.1 / s.config.commands.height_rate / 0.01)) + 50;  // the height's slew, and on
  for (int k = 0; k < ticks; ++k) {  // crouch to 0.70 m while walking backward
    s.hold(cmd(-0.3, 0, 0, 0, 0, 0.70), 0.01, "crouching backward");
    largest_step = std::max(largest_step, std::fabs(fb.feedforward()[0] - prev));
    prev = fb.feedforward()[0];
  }
  // The controller's standing height is the squat clip's neutral pelvis height (ControllerApp).
  const double crouch = s.app->controller().config().commands.standing_height - 0.70;
  ASSERT_GT(crouch, 0.05);
  EXPECT_NEAR(s.app->controller().commands().posture().height, 0.70, 1e-9);
  EXPECT_NEAR(fb.crouch(), crouch, 1e-9) << "the standing height - the shaped 0.70 m";
  EXPECT_NEAR(fb.feedforward()[0], -0.3 / (0.84 + 6.0 * crouch), 1e-9) << "crouched: the crouched gain";
  EXPECT_LT(largest_step, 0.005) << "the feed-forward follows the slewed height without a jump";
  EXPECT_LE(s.max_ref_speed, s.config.commands.max_reference_speed + 1e-9) << s.worst_at;
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
}

TEST(Controller, TickAndHalCycleDoNotAllocate) {
  Sweep s(true);  // with every stage on: the velocity feedback too
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  s.hold(cmd(0.4, 0.1, 0.2), 1.0, "walk");
  std::size_t allocations = 0;
  s.sample.command = cmd(0.4, 0.1, 0.2, 0.1, 0.0, 0.7);  // walking crouched and bent
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 200; ++k) {
      s.sample.velocity_time = s.sample.posture_time = s.t += 0.01;
      s.app->stepLockstep(s.sample);
    }
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u) << "the 100 Hz tick and the 500 Hz HAL cycle (MuJoCo SIL + supervisor) allocate nothing";
}

TEST(Controller, NanAndStaleCommandsAreRejectedAndStopTheRobot) {
  Sweep s;
  s.hold(cmd(0.5, 0, 0), 3.0, "walk");
  const Controller& c = s.app->controller();
  EXPECT_NEAR(c.commands().velocity().vx, 0.5, 1e-9);
  s.hold(cmd(std::nan(""), 0, 0), 0.3, "nan");
  EXPECT_GT(c.commands().counters().rejected_nan, 0u);
  EXPECT_NEAR(c.commands().velocity().vx, 0.5, 1e-9) << "the previous valid command is kept";
  // No fresh command: stale after 0.5 s, then slewed to zero at 1 m/s^2.
  for (int k = 0; k < 150; ++k) s.app->stepLockstep(s.sample);
  EXPECT_TRUE(c.commands().stale());
  EXPECT_NEAR(c.commands().velocity().vx, 0.0, 1e-9);
  s.hold(cmd(5.0, 0, 0), 0.1, "too fast");
  EXPECT_GT(c.commands().counters().clamped, 0u);
  EXPECT_EQ(c.fault(), FaultCode::kNone);
}

TEST(Controller, UnknownModeCodesNeverReachTheSupervisorAndKnownOnesDo) {
  Sweep s;
  s.hold(cmd(0, 0, 0), 1.5, "engage");
  ASSERT_EQ(s.app->controller().mode(), Mode::kActive);
  s.request(ModeRequest::kDamping);  // wire code 3: e-stop
  s.hold(cmd(0, 0, 0), 0.1, "estop");
  EXPECT_EQ(s.app->controller().mode(), Mode::kDamping);
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kEstop);
  s.request(ModeRequest::kActive);
  s.hold(cmd(0, 0, 0), 0.5, "active while latched");
  EXPECT_EQ(s.app->controller().mode(), Mode::kDamping) << "latched";
  s.hold(cmd(0, 0, 0), 2.5, "wait until the legs are still");
  s.request(ModeRequest::kReset);  // wire code 4
  s.hold(cmd(0, 0, 0), 0.1, "reset");
  EXPECT_EQ(s.app->controller().mode(), Mode::kPassive);
  EXPECT_EQ(s.app->controller().fault(), FaultCode::kNone);
}

TEST(Controller, GcoAblationIsSwitchableFromConfig) {
  for (bool enabled : {true, false}) {
    ControllerConfig config = silConfig();
    config.gco.enabled = enabled;
    ControllerApp app(config);
    CommandSample sample;
    sample.command.vx = 0.5;
    for (int k = 0; k < 250; ++k) {
      sample.velocity_time = k * 0.01;
      app.stepLockstep(sample);
    }
    ASSERT_EQ(app.controller().mode(), Mode::kActive);
    EXPECT_EQ(app.controller().gcoResult().status, enabled ? gco::GcoStatus::kOk : gco::GcoStatus::kDisabled);
    if (!enabled) {
      EXPECT_NEAR(app.controller().gcoResult().u_opt.v_x, app.controller().generator().output().v_base.x(), 1e-12);
    }
  }
}

TEST(Controller, CommandLimitsBeyondTheGeneratorAreAConfigError) {
  ControllerConfig config = silConfig();
  config.commands.max_velocity[0] = config.generator.max_command[0] + 0.5;
  try {
    ControllerApp app(config);
    FAIL() << "accepted limits the generator would clamp again";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("commands.max_velocity[0]"), std::string::npos) << e.what();
  }
}

TEST(Controller, FeedbackHeadroomBeyondTheGeneratorOrGcoIsAConfigError) {
  // The ConfigError's message, or "" when the controller accepts the config.
  const auto refusal = [](const ControllerConfig& config) -> std::string {
    try {
      ControllerApp app(config);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  ControllerConfig base = silConfig();
  base.velocity_feedback.enabled = true;
  base.velocity_feedback.envelope_min = {-1.5, -1.5, -1.5};
  base.velocity_feedback.envelope_max = {1.5, 1.5, 1.5};
  // Inside both: accepted (g1_sil.yaml's max_velocity w 1.0 rad/s + 0.5, the generator's and GCO's 1.5).
  ControllerConfig ok = base;
  ok.velocity_feedback.max_velocity_headroom = {0.0, 0.0, 1.5 - ok.commands.max_velocity[2]};
  EXPECT_EQ(refusal(ok), "");
  // The generator's v_y limit: the corrected command could reach beyond it.
  ControllerConfig gen = base;
  gen.velocity_feedback.max_velocity_headroom = {0.0, gen.generator.max_command[1] - gen.commands.max_velocity[1] + 0.1, 0.0};
  const std::string gen_error = refusal(gen);
  EXPECT_NE(gen_error.find("max_velocity_headroom[1]"), std::string::npos) << gen_error;
  EXPECT_NE(gen_error.find("generator.max_command[1]"), std::string::npos) << gen_error;
  // The envelope bounds the reach: the same headroom with the envelope at the generator's limit is accepted.
  gen.velocity_feedback.envelope_max[1] = gen.generator.max_command[1];
  gen.velocity_feedback.envelope_min[1] = -gen.generator.max_command[1];
  EXPECT_EQ(refusal(gen), "");
  // GCO's yaw-rate range, narrower than the generator's: named as such.
  ControllerConfig gco = base;
  gco.gco.limits.yaw_rate_max = gco.commands.max_velocity[2] + 0.1;
  gco.velocity_feedback.max_velocity_headroom = {0.0, 0.0, 0.2};
  const std::string gco_error = refusal(gco);
  EXPECT_NE(gco_error.find("max_velocity_headroom[2]"), std::string::npos) << gco_error;
  EXPECT_NE(gco_error.find("GCO limits"), std::string::npos) << gco_error;
}

}  // namespace
}  // namespace pmg
