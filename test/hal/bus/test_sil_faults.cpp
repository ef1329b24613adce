// End-to-end fault injection: the real bus code (MIT codec, UDP CAN transports, CanBackend) talks
// to the SIL driver emulator (MuJoCo 2.2 G1 with motor-side PD) on another thread; the safety
// supervisor sits in the HAL (SafeBackend) driven by the lead's HalRunner in lockstep. For each
// injected fault the test checks the mode reached and the bound on the cycles it took, that no
// command beyond the torque limits was sent, that no NaN appeared, and that telemetry has no gaps.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <system_error>
#include <thread>

#include "g1_fixture.hpp"
#include "alloc_counter.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"
#include "pmg/hal/hal_runner.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/safety/safe_backend.hpp"

using namespace pmg::hal::bus;
using pmg::hal::safety::FaultCode;
using pmg::hal::safety::Mode;
using pmg::hal::safety::ModeRequest;

namespace {

constexpr double kPeriod = 0.002;

// A port block per process (ctest runs tests in parallel); on a collision the rig moves on.
std::uint16_t basePort(int attempt) {
  return static_cast<std::uint16_t>(20000 + ((getpid() + 37 * attempt) % 1500) * 20);
}

class SilRig {
 public:
  explicit SilRig(bool gantry = true) {
    robot_ = pmg::test::g1Robot();
    BusPlan plan = BusPlan::fromYaml(pmg::test::g1CanPlanPath());
    pmg::MujocoBackendOptions mo;
    mo.gantry.enabled = gantry;
    std::unique_ptr<CanTransport> imu;
    std::vector<std::unique_ptr<CanTransport>> transports;
    for (int attempt = 0;; ++attempt) {
      const std::uint16_t base = basePort(attempt);
      try {
        auto sim = std::make_unique<pmg::MujocoBackend>(robot_, mo);
        sim_ = sim.get();
        sil_ = std::make_unique<SilDriverEmulator>(plan, std::move(sim), base);
        transports = makeHostUdpTransports(plan, base, imu);
        break;
      } catch (const std::system_error&) {
        if (attempt >= 20) throw;
      }
    }
    sil_thread_ = std::thread([this] {
      while (!stop_.load()) sil_->runCycle(0.02);
    });
    CanBackendOptions co;
    co.lockstep = true;
    auto can = std::make_unique<CanBackend>(plan, std::move(transports), std::move(imu), co);
    can_ = can.get();
    // The one HAL stack (makeHalStack: zero offsets, SafeBackend) around the CAN backend.
    pmg::HalStackConfig hs;
    hs.soft_stand_duration_s = 0.5;
    pmg::HalStack stack = pmg::makeHalStack(robot_, hs, std::move(can));
    safe_ = stack.safety;
    hal_ = std::make_unique<pmg::HalRunner>(std::move(stack.backend), static_cast<int>(robot_.numJoints()));
  }
  ~SilRig() {
    stop_ = true;
    if (sil_thread_.joinable()) sil_thread_.join();
  }

  // One HAL cycle; every 5th cycle the emulated 100 Hz loop submits the standing pose.
  void cycle() {
    if (k_ % 5 == 0 && feed_) {
      pmg::LowCommand c;
      c.sequence = ++seq_;
      c.num_motors = static_cast<int>(robot_.numJoints());
      for (std::size_t j = 0; j < robot_.numJoints(); ++j) {
        const pmg::JointConfig& jc = robot_.joints[j];
        c.motors[j] = pmg::MotorCommand{jc.default_position, 0.0, jc.kp, jc.kd, 0.0};
        if (nan_burst_ > 0) c.motors[j].q = std::nan("");
      }
      if (nan_burst_ > 0) --nan_burst_;
      hal_->submit(c);
    }
    ++k_;
    hal_->cycle();
    pmg::LowState st;
    hal_->latest(st);
    if (st.sequence != last_state_seq_ + 1) ++gaps_;
    last_state_seq_ = st.sequence;
    for (int j = 0; j < st.num_motors; ++j) {
      const auto& m = st.motors[static_cast<std::size_t>(j)];
      if (m.valid && !(std::isfinite(m.q) && std::isfinite(m.qd) && std::isfinite(m.tau))) nan_ = true;
      if (!m.valid) ++invalid_seen_by_loop_;
    }
    pmg::hal::safety::SafetyStatus s;
    safe_->status(s);
    if (s.ticks != last_tick_ + 1) ++gaps_;
    last_tick_ = s.ticks;
    max_tau_ratio_ = std::max(max_tau_ratio_, s.max_tau_ratio);
    status_ = s;
  }
  Mode mode() const { return status_.mode; }
  // Cycles until `m` (or max); returns max + 1 if not reached.
  int cyclesUntil(Mode m, int max) {
    for (int i = 1; i <= max; ++i) {
      cycle();
      if (mode() == m) return i;
    }
    return max + 1;
  }
  void toActive() {
    cycle();
    cycle();
    safe_->requests().post(ModeRequest::kSoftStand);
    ASSERT_LE(cyclesUntil(Mode::kSoftStand, 5), 5);
    for (int i = 0; i < 0.5 / kPeriod + 5; ++i) cycle();
    safe_->requests().post(ModeRequest::kActive);
    ASSERT_LE(cyclesUntil(Mode::kActive, 5), 5) << toString(status_.fault.code);
    for (int i = 0; i < 100; ++i) cycle();
    ASSERT_EQ(mode(), Mode::kActive) << toString(status_.fault.code);
  }
  void expectHealthyLogs() {
    EXPECT_EQ(gaps_, 0) << "telemetry lost cycles";
    EXPECT_FALSE(nan_) << "NaN in the measured state";
    EXPECT_LE(max_tau_ratio_, 1.0 + 1e-9) << "a command beyond the torque limit was sent";
    EXPECT_EQ(can_->nonfiniteCommands(), 0u) << "a non-finite command reached the bus";
  }

  pmg::RobotConfig robot_;
  pmg::MujocoBackend* sim_ = nullptr;
  std::unique_ptr<SilDriverEmulator> sil_;
  CanBackend* can_ = nullptr;
  pmg::hal::safety::SafeBackend* safe_ = nullptr;
  std::unique_ptr<pmg::HalRunner> hal_;
  pmg::hal::safety::SafetyStatus status_;
  bool feed_ = true;
  int nan_burst_ = 0;
  int gaps_ = 0;
  bool nan_ = false;
  double max_tau_ratio_ = 0.0;
  std::uint64_t invalid_seen_by_loop_ = 0;  ///< Motor states the loop received with valid = false.

 private:
  std::thread sil_thread_;
  std::atomic<bool> stop_{false};
  std::uint64_t k_ = 0, seq_ = 0, last_state_seq_ = 0, last_tick_ = 0;
};

// Faults the HAL must ride through: run 1 s (500 cycles) and stay active.
void expectStaysActive(const SilFaults& f, const std::function<void(SilRig&)>& check) {
  SilRig rig;
  rig.toActive();
  rig.sil_->setFaults(f);
  for (int i = 0; i < 500; ++i) rig.cycle();
  EXPECT_EQ(rig.mode(), Mode::kActive) << toString(rig.status_.fault.code);
  check(rig);
  rig.expectHealthyLogs();
}

std::uint64_t sum(SilRig& rig, std::uint64_t MotorLinkCounters::*field) {
  std::uint64_t s = 0;
  for (int j = 0; j < 29; ++j) s += rig.can_->motorCounters(j).*field;
  return s;
}

}  // namespace

TEST(SilFaults, CleanBusStaysActiveWithAllReplies) {
  SilRig rig;
  rig.toActive();
  for (int i = 0; i < 100; ++i) rig.cycle();
  EXPECT_EQ(sum(rig, &MotorLinkCounters::rejected), 0u);
  EXPECT_EQ(rig.can_->motorCounters(3).missing, 0u);
  EXPECT_GE(rig.can_->imuFrames() + 1, rig.can_->cycles()) << "one IMU frame per cycle";
  rig.expectHealthyLogs();
}

TEST(SilFaults, HalCycleDoesNotAllocate) {
  // HalRunner::cycle() -> SafeBackend -> CanBackend -> UDP, counted on this (the HAL's) thread only.
  SilRig rig;
  rig.toActive();
  SilFaults f;
  f.drop_prob = 0.05;
  f.dup_prob = 0.05;
  f.corrupt_prob = 0.05;
  rig.sil_->setFaults(f);
  rig.cycle();
  long allocs = 0;
  {
    pmg::test::AllocationGuard scope;
    for (int i = 0; i < 200; ++i) rig.cycle();
    allocs = static_cast<long>(scope.count());
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_EQ(rig.mode(), Mode::kActive);
}

TEST(SilFaults, DroppedFramesAreRiddenThrough) {
  SilFaults f;
  f.drop_prob = 0.05;
  expectStaysActive(f, [](SilRig& r) {
    EXPECT_GT(sum(r, &MotorLinkCounters::missing), 200u);
    // SafeBackend held the last valid reply: the 100 Hz loop never saw a gap.
    EXPECT_EQ(r.invalid_seen_by_loop_, 0u);
    EXPECT_GT(r.status_.held_replies, 200u);
  });
}

TEST(SilFaults, LateFramesAreRiddenThrough) {
  SilFaults f;
  f.late_prob = 0.05;
  expectStaysActive(f, [](SilRig& r) { EXPECT_GT(r.sil_->counters().late, 200u); });
}

TEST(SilFaults, DuplicatedFramesAreCountedNotUsedTwice) {
  SilFaults f;
  f.dup_prob = 0.1;
  expectStaysActive(f, [](SilRig& r) { EXPECT_GT(sum(r, &MotorLinkCounters::duplicates), 500u); });
}

TEST(SilFaults, CorruptedFramesAreRejected) {
  SilFaults f;
  f.corrupt_prob = 0.05;
  expectStaysActive(f, [](SilRig& r) {
    // Foreign-id frames are not routable; the other two kinds are rejected by the reply checks.
    EXPECT_GT(sum(r, &MotorLinkCounters::rejected), 200u);
  });
}

TEST(SilFaults, MildImuNoiseIsRiddenThrough) {
  SilFaults f;
  f.imu_gyro_noise = 0.05;
  expectStaysActive(f, [](SilRig&) {});
}

namespace {
// Bound: the watchdog's timeout in cycles + 2 (one cycle of measurement delay in SafeBackend, one
// for the step that detects it).
void expectDamping(const std::function<void(SilRig&)>& inject, FaultCode code, int index, int max_cycles,
                   bool gantry = true, int cycles_after = 100) {
  SilRig rig(gantry);
  rig.toActive();
  inject(rig);
  const int n = rig.cyclesUntil(Mode::kDamping, max_cycles);
  EXPECT_LE(n, max_cycles) << "expected " << toString(code) << ", fault " << toString(rig.status_.fault.code);
  EXPECT_EQ(rig.status_.fault.code, code) << toString(rig.status_.fault.code);
  if (index >= -1) {
    EXPECT_EQ(rig.status_.fault.index, index);
  }
  // Damping is latched and keeps the telemetry going.
  for (int i = 0; i < cycles_after; ++i) rig.cycle();
  EXPECT_EQ(rig.mode(), Mode::kDamping);
  rig.expectHealthyLogs();
}
const int kMotorBound = static_cast<int>(pmg::hal::safety::WatchdogOptions{}.motor_timeout_s / kPeriod) + 2;
}  // namespace

TEST(SilFaults, SilentMotorLatchesDamping) {
  expectDamping([](SilRig& r) {
    SilFaults f;
    f.silent_joint = 9;  // right knee
    r.sil_->setFaults(f);
  }, FaultCode::kMotorStale, 9, kMotorBound);
}

TEST(SilFaults, SilentMotorReachesTheLoopAsInvalidAfterTheTimeout) {
  SilRig rig;
  rig.toActive();
  SilFaults f;
  f.silent_joint = 9;
  rig.sil_->setFaults(f);
  rig.cyclesUntil(Mode::kDamping, kMotorBound);
  for (int i = 0; i < 5; ++i) rig.cycle();
  pmg::LowState st;
  rig.hal_->latest(st);
  EXPECT_FALSE(st.motors[9].valid) << "held no longer than the motor watchdog";
  EXPECT_TRUE(st.motors[8].valid);
}

TEST(SilFaults, BusOffLatchesDampingAndTheBusIsRestarted) {
  SilRig rig;
  rig.toActive();
  SilFaults f;
  f.bus_off_bus = 2;  // waist + left wrist
  rig.sil_->setFaults(f);
  const int n = rig.cyclesUntil(Mode::kDamping, kMotorBound + 1);
  EXPECT_LE(n, kMotorBound + 1);
  EXPECT_EQ(rig.status_.fault.code, FaultCode::kMotorStale);
  const int j = rig.status_.fault.index;
  EXPECT_TRUE(j == 12 || j == 13 || j == 14 || j == 19 || j == 20 || j == 21) << j;
  EXPECT_EQ(rig.can_->transport(2).counters().bus_off_events, 1u);
  // The backend restarts the bus after bus_off_restart_cycles; replies resume.
  for (int i = 0; i < 80; ++i) rig.cycle();
  EXPECT_EQ(rig.can_->transport(2).counters().restarts, 1u);
  EXPECT_EQ(rig.can_->transport(2).state(), BusState::kErrorActive);
  const auto before = rig.can_->motorCounters(12).replies;
  for (int i = 0; i < 20; ++i) rig.cycle();
  EXPECT_GE(rig.can_->motorCounters(12).replies, before + 19);
  EXPECT_EQ(rig.mode(), Mode::kDamping) << "still latched after the bus came back";
  rig.expectHealthyLogs();
}

TEST(SilFaults, FrozenImuLatchesDamping) {
  expectDamping([](SilRig& r) {
    SilFaults f;
    f.imu_frozen = true;
    r.sil_->setFaults(f);
  }, FaultCode::kImuFrozen, -1, pmg::hal::safety::WatchdogOptions{}.imu_frozen_samples + 3);
}

TEST(SilFaults, WildlyNoisyImuLatchesDamping) {
  expectDamping([](SilRig& r) {
    SilFaults f;
    f.imu_gyro_noise = 40.0;  // beyond the gyro's range
    r.sil_->setFaults(f);
  }, FaultCode::kImuInvalid, -1, 10);
}

TEST(SilFaults, SilentImuLatchesDamping) {
  expectDamping([](SilRig& r) {
    SilFaults f;
    f.imu_silent = true;
    r.sil_->setFaults(f);
  }, FaultCode::kImuStale, -1, static_cast<int>(pmg::hal::safety::WatchdogOptions{}.imu_timeout_s / kPeriod) + 2,
                true, /*cycles_after=*/10);  // each cycle waits the lockstep timeout for the IMU frame
}

TEST(SilFaults, NanBurstFromPolicyLatchesDampingAndNeverReachesTheBus) {
  // The bound is 5 cycles: the NaN command arrives with the next 100 Hz tick.
  expectDamping([](SilRig& r) { r.nan_burst_ = 3; }, FaultCode::kCommandInvalid, -2, 6);
}

TEST(SilFaults, StaleCommandStreamLatchesDamping) {
  expectDamping([](SilRig& r) { r.feed_ = false; }, FaultCode::kCommandStale, -1,
                static_cast<int>(pmg::hal::safety::WatchdogOptions{}.command_timeout_s / kPeriod) + 7);
}

TEST(SilFaults, PushOnThePelvisIsDetectedAsAFall) {
  // On the ground (no gantry): a 0.25 s, 800 N lateral push on the pelvis topples the robot; the
  // tilt check latches damping within 1.5 s.
  expectDamping([](SilRig& r) {
    pmg::MujocoBackend* sim = r.sim_;
    r.sil_->post([sim](pmg::HalBackend&) { sim->push(sim->pelvisBody(), Eigen::Vector3d(0.0, 800.0, 0.0), 0.25); });
  }, FaultCode::kFallTilt, -1, 750, /*gantry=*/false);
}

// The drivers are enabled by a request the backend repeats until each driver answers: enable
// frames lost because the robot (here pmg_sil's emulator) was not listening yet must not leave
// limp motors behind a supervisor that believes they hold their targets (pmg_calib_joints once
// captured a knee hanging at 0.01 rad while commanding 0.3 rad: its first cycles ran before pmg_sil
// had bound its ports).
TEST(SilFaults, EnableLostWhileTheRobotStartsIsRepeatedUntilAnswered) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  BusPlan plan = BusPlan::fromYaml(pmg::test::g1CanPlanPath());
  std::unique_ptr<CanTransport> imu;
  std::vector<std::unique_ptr<CanTransport>> transports;
  std::uint16_t base = 0;
  for (int attempt = 0;; ++attempt) {
    base = basePort(attempt + 7);
    try {
      transports = makeHostUdpTransports(plan, base, imu);
      break;
    } catch (const std::system_error&) {
      if (attempt >= 20) throw;
    }
  }
  CanBackendOptions co;
  co.lockstep = true;
  co.lockstep_timeout_s = 0.005;
  CanBackend can(plan, std::move(transports), std::move(imu), co);
  const int n = static_cast<int>(robot.numJoints());
  const int knee = 3;
  pmg::LowCommand cmd;
  cmd.num_motors = n;
  for (int j = 0; j < n; ++j) {
    const pmg::JointConfig& jc = robot.joints[static_cast<std::size_t>(j)];
    cmd.motors[static_cast<std::size_t>(j)] = pmg::MotorCommand{jc.default_position, 0.0, jc.kp, jc.kd, 0.0};
  }
  pmg::LowState st;
  // Nobody listens yet: the first enable requests are lost.
  for (int c = 0; c < 5; ++c) EXPECT_EQ(can.exchange(cmd, st), pmg::BackendStatus::kFault);
  // The robot comes up.
  pmg::MujocoBackendOptions mo;
  mo.gantry.enabled = true;
  auto sim = std::make_unique<pmg::MujocoBackend>(robot, mo);
  SilDriverEmulator sil(plan, std::move(sim), base);
  std::atomic<bool> stop{false};
  std::thread t([&] {
    while (!stop.load()) sil.runCycle(0.02);
  });
  // Bend the knee 0.3 rad beyond its default: after 1 s every driver must answer and the knee hold
  // the target (a limp knee hangs near 0 rad in the gantry).
  cmd.motors[knee].q = robot.joints[knee].default_position + 0.3;
  int ok = 0;
  for (int c = 0; c < 500; ++c) ok += can.exchange(cmd, st) == pmg::BackendStatus::kOk;
  stop = true;
  t.join();
  EXPECT_GT(ok, 400);
  ASSERT_TRUE(st.motors[knee].valid);
  EXPECT_NEAR(st.motors[knee].q, cmd.motors[knee].q, 0.05);
  EXPECT_GT(sil.counters().controls, 0u);
}
