// The composition root (controller_app.cpp) on the G1 in the MuJoCo 2.2 SIL, as pmg_controller
// runs it: scripted runs track within bounds and record every tick; falls and faults are
// detected by the always-on supervisor and named in the summary, which exits non-zero; a stop
// flag (SIGINT/SIGTERM) ends a lockstep run cleanly with its log and summary.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/policy/contract.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

ControllerConfig silConfig(const std::string& file = test::g1SilControllerConfigPath()) {
  ControllerConfig c = loadControllerConfig(file);
  c.makeOffline();
  return c;
}

// Decodes every PMG_STATE message of the LCM log `log_file`, in order, and hands each to `visit`.
template <class Visit>
void forEachControllerState(const std::string& log_file, Visit&& visit) {
  lcm::LogFile file(log_file, "r");
  ASSERT_TRUE(file.good()) << log_file;
  pmg_lcm::controller_state_t m;
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel != "PMG_STATE") continue;
    ASSERT_GE(m.decode(ev->data, 0, ev->datalen), 0) << log_file;
    visit(m);
  }
}

CommandScript shortScript() {
  CommandScript s;
  const auto seg = [&](const char* name, double d, double vx, double wz) {
    CommandSegment g;
    g.name = name;
    g.start = s.duration();
    g.duration = d;
    g.command.vx = vx;
    g.command.wz = wz;
    s.segments.push_back(g);
  };
  seg("stand", 1.5, 0, 0);
  seg("forward", 3.0, 0.5, 0);
  seg("turn", 2.0, 0, 0.5);
  seg("stop", 1.5, 0, 0);
  return s;
}

// Leg tracking bound. The legs hang in the gantry and follow PMG references whose swing-phase
// velocities reach ~3 rad/s (hip pitch, knee). The motor-level PD (kp 150-200, kd 4-5 N*m*s/rad,
// armature 0.01 kg*m^2) lags such a reference by about (kd/kp)*qd ~ 0.03*3 = 0.08 rad at the
// peaks only, and gravity sags the hanging leg by m*g*l/kp ~ 0.005 rad; averaged over the cycle
// this is ~0.01-0.02 rad RMS. 0.05 rad RMS per joint flags a broken loop, delay or gain
// regression without flaking.
constexpr double kLegTrackingRmsBound = 0.05;

TEST(ControllerApp, ScriptedSequenceTracksWithinLimitsAndBounds) {
  ControllerApp app(silConfig());
  const ControllerConfig& config = app.config();
  const CommandScript script = shortScript();
  const int n = static_cast<int>(config.robot.numJoints());
  std::vector<double> sq_err(12, 0.0);
  int active_ticks = 0;
  bool within = true;
  const RunSummary s = app.run(script.duration(), &script, nullptr, [&](double now, const TickStatus& st, std::size_t) {
    const LowState& state = app.controller().lastState();
    const auto& ref = app.controller().reference();
    for (int i = 0; i < n && within; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const JointConfig& j = config.robot.joints[k];
      const MotorState& m = state.motors[k];
      within = std::isfinite(m.q) && std::isfinite(m.qd) && std::isfinite(m.tau) && m.q >= j.lower - 0.01 &&
               m.q <= j.upper + 0.01 && std::fabs(m.tau) <= j.torque_limit + 1e-9 && ref[k] >= j.lower - 1e-12 &&
               ref[k] <= j.upper + 1e-12;
      EXPECT_TRUE(within) << j.name << " at " << now;
    }
    if (st.mode == Mode::kActive && now > 2.0) {
      ++active_ticks;
      for (std::size_t i = 0; i < 12; ++i) {
        const double e = state.motors[i].q - ref[i];
        sq_err[i] += e * e;
      }
    }
  });
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_EQ(s.final_mode, Mode::kActive);
  EXPECT_EQ(s.exitCode(), 0);
  ASSERT_GT(active_ticks, 400);
  double worst = 0;
  for (std::size_t i = 0; i < 12; ++i) {
    const double rms = std::sqrt(sq_err[i] / active_ticks);
    worst = std::max(worst, rms);
    EXPECT_LT(rms, kLegTrackingRmsBound) << config.robot.joints[i].name;
  }
  std::printf("[ SIL ] leg tracking RMS worst joint %.4f rad (bound %.3f)\n", worst, kLegTrackingRmsBound);
  EXPECT_GT(app.controller().generator().output().period, 0.5) << "the walk really moved the legs";
}

TEST(ControllerApp, LockstepRunRecordsEveryTick) {
  test::TempDir dir;
  ControllerConfig config = silConfig();
  config.log_file = dir.file("run.lcmlog");
  RunSummary s;
  {
    ControllerApp app(config);
    const CommandScript script = shortScript();
    s = app.run(4.0, &script, nullptr);
  }
  EXPECT_EQ(s.run.ticks, 400);
  EXPECT_EQ(s.telemetry_dropped, 0u);
  EXPECT_EQ(s.telemetry_written, 400u);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_EQ(s.loop.cycles, 400);
  EXPECT_NE(s.text().find("final mode: active; fault: none"), std::string::npos) << s.text();
  std::printf("[ SIL ] RTF %.1f, loop p99 %.1f us, HAL p99 %.1f us, deadline misses %lld\n", s.run.real_time_factor,
              1e6 * s.loop.runtime_p99, 1e6 * s.hal.runtime_p99, static_cast<long long>(s.deadline_misses));
  std::int64_t expected_tick = 0;
  int active = 0;
  forEachControllerState(config.log_file, [&](const pmg_lcm::controller_state_t& m) {
    EXPECT_EQ(m.tick, expected_tick++);
    EXPECT_EQ(m.num_joints, 29);
    active += m.mode == 2;
  });
  EXPECT_EQ(expected_tick, 400);
  EXPECT_GT(active, 250) << "telemetry carries the supervisor's mode";
}

// Defect 5 of issue 11: a robot that falls is detected (always on) and the run says so.
TEST(ControllerApp, FallIsDetectedNamedAndExitsNonZero) {
  ControllerConfig config = silConfig();
  config.mujoco.gantry.enabled = false;  // on the ground, PMG references and no policy: it falls
  ControllerApp app(config);
  CommandScript script = shortScript();
  const RunSummary s = app.run(8.0, &script, nullptr);
  EXPECT_TRUE(s.fell()) << s.text();
  EXPECT_EQ(s.final_mode, Mode::kDamping);
  EXPECT_NE(s.exitCode(), 0);
  EXPECT_NE(s.text().find("fall: base"), std::string::npos) << s.text();
  EXPECT_NE(s.text().find("final mode: damping"), std::string::npos) << s.text();
}

// Defect 7 of issue 11: the stop flag (set by SIGINT/SIGTERM in pmg_controller) ends a lockstep
// run at once, and the log and the summary are still written.
TEST(ControllerApp, StopFlagEndsALockstepRunCleanly) {
  test::TempDir dir;
  ControllerConfig config = silConfig();
  config.log_file = dir.file("stopped.lcmlog");
  std::atomic<bool> stop{false};
  RunSummary s;
  {
    ControllerApp app(config);
    const CommandScript script = shortScript();
    s = app.run(1000.0, &script, &stop, [&](double now, const TickStatus&, std::size_t) {
      if (now >= 1.0) stop = true;
    });
  }
  EXPECT_TRUE(s.run.stopped_by_flag);
  EXPECT_EQ(s.run.ticks, 101);
  EXPECT_EQ(s.telemetry_written, 101u);
  EXPECT_NE(s.text().find("stopped by a signal"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(config.log_file), 10000u);
}

// A signal that arrives while the controller is still starting (a slow start on a loaded machine)
// stops the run cleanly; the summary does not claim the motors never answered, and it exits 0.
TEST(ControllerApp, StopFlagBeforeTheFirstTickIsNotNeverActive) {
  ControllerConfig config = silConfig();
  std::atomic<bool> stop{true};
  ControllerApp app(config);
  const RunSummary s = app.run(1000.0, nullptr, &stop);
  EXPECT_TRUE(s.run.stopped_by_flag);
  EXPECT_LT(s.run.sim_time, 1.0);
  EXPECT_FALSE(s.never_active) << s.text();
  EXPECT_EQ(s.exitCode(), 0) << s.text();
  EXPECT_EQ(s.text().find("never reached active"), std::string::npos) << s.text();
}

// A backend that serves the MuJoCo SIL but, in a window of cycles, one motor replies NaN.
class CorruptingBackend final : public HalBackend {
 public:
  CorruptingBackend(const RobotConfig& r, MujocoBackendOptions o, std::uint64_t bad_cycle,
                    std::uint64_t good_again = ~std::uint64_t{0})
      : sim_(r, std::move(o)), bad_cycle_(bad_cycle), good_again_(good_again) {}
  const char* name() const noexcept override { return "corrupting"; }
  double cyclePeriod() const noexcept override { return sim_.cyclePeriod(); }
  BackendStatus exchange(const LowCommand& c, LowState& s) noexcept override {
    last_command = c;
    const BackendStatus st = sim_.exchange(c, s);
    ++cycles_;
    if (cycles_ >= bad_cycle_ && cycles_ < good_again_) s.motors[3].q = std::nan("");  // a motor replying NaN
    return st;
  }
  LowCommand last_command{};

 private:
  MujocoBackend sim_;
  std::uint64_t bad_cycle_, good_again_, cycles_ = 0;
};

TEST(ControllerApp, NanStateLatchesDampingWithKdOnly) {
  ControllerConfig config = silConfig();
  ControllerAppOptions o;
  auto backend = std::make_unique<CorruptingBackend>(config.robot, config.mujoco, 1000);
  CorruptingBackend* raw = backend.get();
  o.backend = std::move(backend);
  ControllerApp app(config, std::move(o));
  CommandSample sample;
  for (int k = 0; k < 400; ++k) app.stepLockstep(sample);
  EXPECT_EQ(app.controller().mode(), Mode::kDamping);
  EXPECT_EQ(app.controller().fault(), FaultCode::kMotorStale) << "a NaN reply is no reply; it timed out";
  for (std::size_t i = 0; i < 29; ++i) {
    EXPECT_EQ(raw->last_command.motors[i].kp, 0.0);
    EXPECT_GT(raw->last_command.motors[i].kd, 0.0);
  }
  sample.mode_request = ModeRequest::kActive;
  sample.mode_request_seq = 1;
  app.stepLockstep(sample);
  app.stepLockstep(sample);
  EXPECT_EQ(app.controller().mode(), Mode::kDamping) << "latched";
  const RunSummary s = app.finish();
  EXPECT_NE(s.text().find("fault: motor reply timeout (joint 3"), std::string::npos) << s.text();
  EXPECT_EQ(s.fault_joint_name, "left_knee_joint");
}

// Two cycles of NaN from one motor (corrupted frames) are held over by the HAL within the motor
// watchdog (5 cycles): the robot stays active.
TEST(ControllerApp, BriefInvalidStateIsToleratedWithoutLatching) {
  ControllerConfig config = silConfig();
  ControllerAppOptions o;
  o.backend = std::make_unique<CorruptingBackend>(config.robot, config.mujoco, 1001, 1003);
  ControllerApp app(config, std::move(o));
  CommandSample sample;
  for (int k = 0; k < 400; ++k) app.stepLockstep(sample);
  EXPECT_EQ(app.controller().mode(), Mode::kActive);
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
}

// The stride adaptation (gco.stride_adaptation) in the product path: the gantry config walks its
// references with it through the controller's loop (forward, then sideways and turning) without a fault,
// and the reference it plays is the adapted one (it differs from the generator's in the legs). No shipped
// actor was trained on it, so a policy config with it on refuses to start, naming the contract key.
TEST(ControllerApp, StrideAdaptationRunsInTheLoopAndShippedPoliciesRefuseIt) {
  ControllerConfig config = silConfig();
  config.gco.stride_adaptation.enabled = true;
  ControllerApp app(config);
  CommandSample sample;
  double largest_leg_change = 0.0;
  for (int k = 0; k < 600; ++k) {
    sample.velocity_time = k * 0.01;
    sample.command.vx = k < 100 ? 0.0 : (k < 350 ? 0.4 : 0.1);
    sample.command.vy = k < 350 ? 0.0 : 0.2;
    sample.command.wz = k < 350 ? 0.0 : 0.3;
    app.stepLockstep(sample);
  }
  EXPECT_EQ(app.controller().mode(), Mode::kActive);
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
  const auto& sa = app.controller().referencePipeline().strideAdaptation();
  ASSERT_TRUE(sa.enabled());
  for (const Foot f : {Foot::kLeft, Foot::kRight})
    largest_leg_change = std::max(largest_leg_change, sa.correction(f).cwiseAbs().maxCoeff());
  EXPECT_GT(largest_leg_change, 1e-3);
  EXPECT_EQ(sa.counters().failures, 0u);

  ControllerConfig policy = silConfig(test::sourcePath("config/controller/g1_sil_policy.yaml"));
  policy.gco.stride_adaptation.enabled = true;
  try {
    ControllerApp refused(policy);
    FAIL() << "ran a policy trained without the stride adaptation with it";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("stride_adaptation"), std::string::npos) << e.what();
  }
}

// pmg_controller with a shipped walking policy and no gantry (config/controller/g1_sil_policy.yaml,
// the default: H10a, the crouched box's actor, crouched envelope opened per axis; and
// g1_sil_table2_baseline.yaml, the leg-contact actor the earlier defaults were fine-tuned from, which
// also drives teleoperation), and g1_sil_policy_uplev.yaml (the reference settings beyond the paper:
// upright walking and levelled stance soles, with the actor fine-tuned on them), and
// g1_sil_policy_walking_height.yaml (the raised walking templates and their actor), and
// g1_sil_policy_v20b.yaml (V20b, trained from scratch, at the HAL's default slew), and
// g1_sil_policy_n24b.yaml (N24b, trained from scratch in 17.7 min, at the same slew), and
// g1_sil_policy_wh6g.yaml (wh6g, the default until 2026-12-06): the actor keeps the G1 upright and walks
// it forward on command; the tick allocates nothing.
class PolicyConfigTest : public ::testing::TestWithParam<const char*> {};

TEST_P(PolicyConfigTest, PolicyWalksTheG1WithoutGantry) {
  ControllerConfig config = silConfig(test::sourcePath(std::string("config/controller/") + GetParam()));
  ASSERT_FALSE(config.mujoco.gantry.enabled);
  const bool uplev = std::string(GetParam()) == "g1_sil_policy_uplev.yaml";
  EXPECT_EQ(config.gco.sole_levelling.enabled, uplev);
  EXPECT_EQ(config.generator.upright_walking, uplev);
  ControllerApp app(config);
  ASSERT_NE(app.controller().policy(), nullptr);
  CommandSample sample;
  double min_height = 10;
  std::size_t allocations = 0;
  for (int k = 0; k < 700; ++k) {
    const double now = k * 0.01;
    sample.command.vx = now < 1.5 ? 0.0 : 0.4;
    sample.velocity_time = now;
    if (k == 300) test::startCountingAllocations();
    app.stepLockstep(sample);
    if (k == 400) {
      test::stopCountingAllocations();
      allocations = test::allocationCount();
    }
    min_height = std::min(min_height, app.controller().lastState().base_position[2]);
  }
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
  EXPECT_GT(min_height, 0.6) << "the robot fell";
  EXPECT_GT(app.controller().lastState().base_position[0], 0.5) << "the robot did not walk forward";
  EXPECT_EQ(allocations, 0u);
  std::printf("[ SIL ] %s: walked %.2f m forward in 5.5 s, lowest pelvis %.2f m\n", GetParam(),
              app.controller().lastState().base_position[0], min_height);
}

// Crouched to 0.74 m and told to walk backward 0.5 m/s, then to stop: wh6g (the default until
// 2026-12-06, g1_sil_policy_wh6g.yaml) walks at its command and stops (here -0.46 m/s, and 0.07 m/s at
// most 2-3 s after the stop). The actors of V20b's
// recipe break into a faster backward gait there and run on through the stop (training/README.md
// "V20b's recipe over three seeds"): with g1_sil_policy_v20b.yaml this test measures -0.92 m/s and
// 0.69 m/s, with V20e's config -1.19 and 2.19, and fails, so a default actor that runs away crouched
// cannot ship unnoticed. g1_sil_policy_n24b.yaml (N24b, trained from scratch at half the exploration
// noise, with its feed-forward per crouch) is held to the same: here -0.476 and 0.008; with the
// feed-forward fitted upright only, its battery walked -0.71 at 0.74 m and one of two seeds fell in the
// stop after the 0.70 m walk
// (training/README.md "Half the exploration noise"). The default, H10a (g1_sil_policy.yaml, trained against the run-on
// in crouched backward stops; training/results/fidelity/crouched_box/README.md "H10a, H10b, H10c"), is held to the same:
// here -0.587 and 0.052 (its crouched backward battery, through the velocity feedback's estimate: 15 of 15 in band). Velocities are the pelvis's, world frame
// (the robot starts facing +x; the heading drifts a few degrees at most).
class CrouchedBackwardTest : public ::testing::TestWithParam<const char*> {};

TEST_P(CrouchedBackwardTest, WalksBackwardCrouchedAtItsCommandAndStops) {
  ControllerConfig config = silConfig(test::sourcePath(std::string("config/controller/") + GetParam()));
  ControllerApp app(config);
  CommandSample sample;
  sample.command.height = 0.74;
  double walk_vx = 0.0, stop_speed = 0.0, min_height = 10.0;
  int walk_n = 0;
  for (int k = 0; k < 1000; ++k) {  // 0-3 s crouch, 3-7 s backward, 7-10 s stop
    const double now = k * 0.01;
    sample.velocity_time = sample.posture_time = now;
    sample.command.vx = now >= 3.0 && now < 7.0 ? -0.5 : 0.0;
    app.stepLockstep(sample);
    const auto& st = app.controller().lastState();
    min_height = std::min(min_height, st.base_position[2]);
    if (now >= 4.6 && now < 7.0) walk_vx += st.base_linear_velocity[0], ++walk_n;  // last 60 % of the walk
    if (now >= 9.0) stop_speed = std::max(stop_speed, std::hypot(st.base_linear_velocity[0], st.base_linear_velocity[1]));
  }
  walk_vx /= walk_n;
  std::printf("[ SIL ] %s: crouched 0.74 m, backward 0.5 m/s: %.3f m/s; largest speed 2-3 s after the stop %.3f m/s\n",
              GetParam(), walk_vx, stop_speed);
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
  EXPECT_GT(min_height, 0.5) << "the robot fell";
  EXPECT_LT(walk_vx, -0.35) << "walked backward at its command, not short of it";
  EXPECT_GT(walk_vx, -0.7) << "a runaway: beyond the command by 0.2 m/s";
  EXPECT_LT(stop_speed, 0.2) << "stopped";
}

INSTANTIATE_TEST_SUITE_P(ControllerApp, CrouchedBackwardTest,
                         ::testing::Values("g1_sil_policy.yaml", "g1_sil_policy_n24b.yaml", "g1_sil_policy_wh6g.yaml"));

// The walking height feedback through the product path (docs/controller.md "Walking height
// correction"): N24b walks crouched backward 2-3 cm above its command; with its config's
// walking_height_ki the pelvis comes to within issue 12's 0.015 m, and with the same config but the
// walking integrator off it does not. The stop after it is calm and nothing faults. The telemetry
// (PMG_STATE's posture_feedback) shows the lowered height command the generator got.
TEST(ControllerApp, WalkingHeightFeedbackBringsACrouchedBackwardWalkToItsHeight) {
  test::TempDir dir;
  const auto walk = [&](double walking_height_ki, const std::string& log_file) {
    ControllerConfig config = silConfig(test::sourcePath("config/controller/g1_sil_policy_n24b.yaml"));
    config.posture_feedback.walking_height_ki = walking_height_ki;
    config.log_file = log_file;
    ControllerApp app(config);
    CommandSample sample;
    sample.command.height = 0.70;
    double height = 0.0, stop_speed = 0.0, min_height = 10.0;
    int n = 0;
    for (int k = 0; k < 1300; ++k) {  // 0-3 s crouch, 3-10 s backward 0.4 m/s, 10-13 s stop
      const double now = k * 0.01;
      sample.velocity_time = sample.posture_time = now;
      sample.command.vx = now >= 3.0 && now < 10.0 ? -0.4 : 0.0;
      app.stepLockstep(sample);
      const auto& st = app.controller().lastState();
      min_height = std::min(min_height, st.base_position[2]);
      if (now >= 6.0 && now < 10.0) height += st.base_position[2], ++n;
      if (now >= 12.0) stop_speed = std::max(stop_speed, std::hypot(st.base_linear_velocity[0], st.base_linear_velocity[1]));
    }
    EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
    EXPECT_GT(min_height, 0.5) << "the robot fell";
    EXPECT_LT(stop_speed, 0.2) << "stopped";
    return height / n;
  };
  const double config_ki = silConfig(test::sourcePath("config/controller/g1_sil_policy_n24b.yaml")).posture_feedback.walking_height_ki;
  ASSERT_GT(config_ki, 0.0) << "N24b's config feeds the walking height back";
  const std::string log = dir.file("walking_height.lcmlog");
  const double on = walk(config_ki, log), off = walk(0.0, "");
  std::printf("[ SIL ] N24b, backward 0.4 m/s crouched to 0.70 m: pelvis at %.3f m with the walking height feedback, %.3f without\n",
              on, off);
  EXPECT_NEAR(on, 0.70, 0.015);
  EXPECT_GT(off, 0.715) << "without it the actor walks high (the effect this feedback exists for)";
  // The log of the run with it: standing, the fed-back height is the command's (within the standing
  // correction's 5 mm); late in the walk it is lowered, never below the walking floor (0.66 m).
  double walk_fb = 0.0, walk_cmd = 0.0, lowest = 10.0;
  int n_walk = 0, n_stand = 0;
  forEachControllerState(log, [&](const pmg_lcm::controller_state_t& m) {
    if (m.mode != 2) return;
    const double t = 1e-6 * static_cast<double>(m.utime);
    lowest = std::min(lowest, m.posture_feedback[2]);
    if (t >= 2.5 && t < 3.0) {
      EXPECT_NEAR(m.posture_feedback[2], m.command[5], 0.0051) << "standing, at " << t;
      ++n_stand;
    }
    if (t >= 8.0 && t < 10.0) walk_fb += m.posture_feedback[2], walk_cmd += m.command[5], ++n_walk;
  });
  ASSERT_GT(n_stand, 10);
  ASSERT_GT(n_walk, 100);
  std::printf("[ SIL ] telemetry: height command %.3f m, after the walking height feedback %.3f m; lowest %.3f m\n",
              walk_cmd / n_walk, walk_fb / n_walk, lowest);
  EXPECT_LT(walk_fb / n_walk, walk_cmd / n_walk - 0.01) << "the telemetry shows the lowered command";
  EXPECT_GE(lowest, 0.66 - 1e-9) << "never below the walking floor";
}

// The controller refuses to start an actor on clips other than those it was trained on
// (pmg.clips_digest, docs/policy.md "The contract"): wh6hs, trained on the raised walking
// templates, on the captured ones; its own config starts (PolicyConfigTest).
TEST(ControllerApp, RefusesAPolicyOnClipsItWasNotTrainedOn) {
  ControllerConfig config = silConfig(test::sourcePath("config/controller/g1_sil_policy_walking_height.yaml"));
  config.clips_dir = test::sourcePath("config/clips/g1");
  try {
    ControllerApp app(config);
    FAIL() << "started wh6hs on the captured clips";
  } catch (const policy::ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.clips_digest") << e.what();
  }
}

// The supervisor's slew limit on commanded positions comes from the config (safety.q_rate_max) and
// every joint-cycle it acts in is counted. wh6g (the default until 2026-12-06) steps its leg targets every
// tick, as in training: at 20 rad/s (its config's, the value its settings were tuned with) the HAL holds
// them back in most cycles of a walk (the SIL walks 20-40 % slower than the actor's own environment,
// training/README.md "The HAL's slew limit"); at the HAL's default, 600 rad/s, it lets them through. The
// default config (H10a) runs at the HAL's default.
TEST(ControllerApp, HalSlewLimitIsConfiguredAndCounted) {
  EXPECT_DOUBLE_EQ(silConfig(test::sourcePath("config/controller/g1_sil_policy.yaml")).q_rate_max,
                   HalStackConfig{}.q_rate_max)
      << "the default config runs at the HAL's default slew limit";
  const auto walk = [](double q_rate_max) {
    ControllerConfig config = silConfig(test::sourcePath("config/controller/g1_sil_policy_wh6g.yaml"));
    EXPECT_DOUBLE_EQ(config.q_rate_max, 20.0) << "wh6g's config pins the value it was tuned with";
    config.q_rate_max = q_rate_max;
    ControllerApp app(config);
    EXPECT_DOUBLE_EQ(app.safety().supervisor().options().envelope.q_rate_max, config.q_rate_max);
    CommandSample sample;
    for (int k = 0; k < 400; ++k) {
      sample.command.vx = k < 100 ? 0.0 : 0.5;
      sample.velocity_time = k * 0.01;
      app.stepLockstep(sample);
    }
    EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
    EXPECT_GT(app.controller().lastState().base_position[0], 0.5) << "walked forward";
    hal::safety::SafetyStatus st;
    EXPECT_TRUE(app.safety().status(st));
    return st.slew_clamped_joint_ticks;
  };
  const std::uint64_t slow = walk(20.0);
  const std::uint64_t fast = walk(HalStackConfig{}.q_rate_max);
  EXPECT_DOUBLE_EQ(HalStackConfig{}.q_rate_max, 600.0);
  std::printf("[ SIL ] slew-limited joint-cycles over 4 s: %llu at 20 rad/s, %llu at the default\n",
              static_cast<unsigned long long>(slow), static_cast<unsigned long long>(fast));
  EXPECT_GT(slow, 1000u) << "20 rad/s holds back the actor's leg targets";
  EXPECT_LT(fast, slow / 100) << "the default lets them through";
}

INSTANTIATE_TEST_SUITE_P(ControllerApp, PolicyConfigTest,
                         ::testing::Values("g1_sil_policy.yaml", "g1_sil_table2_baseline.yaml",
                                                           "g1_sil_policy_uplev.yaml", "g1_sil_policy_walking_height.yaml",
                                                           "g1_sil_policy_v20b.yaml", "g1_sil_policy_n24b.yaml",
                                                           "g1_sil_policy_wh6g.yaml"));

}  // namespace
}  // namespace pmg
