// The HAL's low-pass of the IMU's specific force before the loop (SafeBackendOptions::
// imu_acc_lowpass_s, timing.imu_acc_lowpass_s): the 100 Hz loop takes one HAL sample in five, so
// acceleration spikes phase-locked to the gait (foot impacts) alias into a bias of whatever
// integrates them (the base-velocity estimator). These tests build the product's HAL stack
// (makeHalStack) around a scripted backend and read it as the loop does.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/safety/safe_backend.hpp"

namespace {

constexpr double kPeriod = 0.002;  // 500 Hz HAL
constexpr int kCyclesPerTick = 5;  // 100 Hz loop

/// Motors answer at their default pose; the IMU reports x-acceleration spikes of ±spike m/s² on
/// fixed cycles of every 10 (the gait's impacts, phase-locked to the loop): +spike on cycle 0 and
/// −spike on cycle 3, so the true mean of acc_x is 0.
class SpikyImuBackend final : public pmg::HalBackend {
 public:
  SpikyImuBackend(const pmg::RobotConfig& robot, double spike) : robot_(robot), spike_(spike) {}
  const char* name() const noexcept override { return "spiky-imu"; }
  double cyclePeriod() const noexcept override { return kPeriod; }
  pmg::BackendStatus exchange(const pmg::LowCommand&, pmg::LowState& state) noexcept override {
    const int n = static_cast<int>(robot_.numJoints());
    state.num_motors = n;
    for (int i = 0; i < n; ++i) {
      auto& m = state.motors[static_cast<std::size_t>(i)];
      m.q = robot_.joints[static_cast<std::size_t>(i)].default_position;
      m.qd = 0.0;
      m.tau = 0.0;
      m.valid = true;
    }
    const int phase = static_cast<int>(cycle_ % 10);
    raw_x = phase == 0 ? spike_ : (phase == 3 ? -spike_ : 0.0);
    if (cycle_ == overload_cycle) raw_x = 400.0;  // beyond the supervisor's imu_acc_max (160)
    state.imu.quat_wxyz = {1.0, 0.0, 0.0, 0.0};
    state.imu.gyro = {1e-4 * static_cast<double>(cycle_ % 7), 0.0, 0.0};  // never frozen
    state.imu.acc = {raw_x, 0.0, 9.81};
    state.imu.valid = true;
    ++cycle_;
    return pmg::BackendStatus::kOk;
  }
  void resetCycle() noexcept { cycle_ = 0; }
  double raw_x = 0.0;
  long overload_cycle = -1;

 private:
  const pmg::RobotConfig& robot_;
  double spike_;
  long cycle_ = 0;
};

struct Samples {
  std::vector<double> loop_x;  ///< acc_x as the loop samples it (every 5th cycle)
  std::vector<double> all_x;   ///< acc_x handed up on every cycle
  std::vector<double> raw_x;   ///< what the backend reported
};

Samples run(double lowpass_s, int cycles) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  auto device = std::make_unique<SpikyImuBackend>(robot, 100.0);
  SpikyImuBackend* dev = device.get();
  pmg::HalStackConfig hs;
  hs.imu_acc_lowpass_s = lowpass_s;
  pmg::HalStack stack = pmg::makeHalStack(robot, hs, std::move(device));
  pmg::LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  pmg::LowState st;
  Samples r;
  for (int k = 0; k < cycles; ++k) {
    stack.backend->exchange(cmd, st);
    r.all_x.push_back(st.imu.acc[0]);
    r.raw_x.push_back(dev->raw_x);
    if (k % kCyclesPerTick == 0) r.loop_x.push_back(st.imu.acc[0]);
    EXPECT_DOUBLE_EQ(st.imu.acc[2], 9.81) << "a constant axis passes unchanged (unit DC gain), cycle " << k;
  }
  return r;
}

double mean(const std::vector<double>& v, std::size_t from = 0) {
  double s = 0.0;
  for (std::size_t i = from; i < v.size(); ++i) s += v[i];
  return s / static_cast<double>(v.size() - from);
}

TEST(ImuLowpass, OffHandsTheLoopTheRawSamples) {
  const Samples r = run(0.0, 200);
  for (std::size_t k = 0; k < r.all_x.size(); ++k) ASSERT_EQ(r.all_x[k], r.raw_x[k]) << "cycle " << k;
  // The aliasing this option exists for: the loop sees every +100 spike and no −100 one.
  EXPECT_NEAR(mean(r.loop_x), 50.0, 1e-9);
  EXPECT_NEAR(mean(r.raw_x), 0.0, 1e-9);
}

TEST(ImuLowpass, TheLoopsSamplesLoseThePhaseLockedBias) {
  const Samples r = run(0.005, 2000);
  // After the start-up transient (10 time constants) the loop's mean lies within a fifth of the raw
  // sampling's bias of the true mean (8.6 of 50 m/s^2 here, a first order at 2.5 cycles), and the
  // mean over all cycles is kept (unit DC gain).
  const std::size_t skip = 10;  // loop ticks = 0.1 s
  const double bias = std::fabs(mean(r.loop_x, skip));
  EXPECT_LT(bias, 0.2 * 50.0) << "the loop's sampled mean of acc_x [m/s^2]; raw: 50";
  EXPECT_NEAR(mean(r.all_x, 50), mean(r.raw_x, 50), 0.5);
  // A step response of the first order: 63 % of a step after one time constant. Measured on the
  // first samples: it starts from the first sample (100 on cycle 0), then decays towards 0.
  EXPECT_DOUBLE_EQ(r.all_x[0], 100.0);
  EXPECT_NEAR(r.all_x[1], 100.0 * (1.0 - kPeriod / (0.005 + kPeriod)), 1e-9);
}

TEST(ImuLowpass, TheSupervisorStillSeesTheRawSpike) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  auto device = std::make_unique<SpikyImuBackend>(robot, 10.0);
  SpikyImuBackend* dev = device.get();
  pmg::HalStackConfig hs;
  hs.imu_acc_lowpass_s = 0.05;
  hs.soft_stand_duration_s = 0.1;
  pmg::HalStack stack = pmg::makeHalStack(robot, hs, std::move(device));
  pmg::engageActive(stack, robot, 2.0);
  pmg::LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  for (std::size_t i = 0; i < robot.numJoints(); ++i) {
    cmd.motors[i] = {robot.joints[i].default_position, 0.0, robot.joints[i].kp, robot.joints[i].kd, 0.0};
  }
  pmg::LowState st;
  pmg::hal::safety::SafetyStatus status;
  for (int k = 0; k < 20; ++k) {
    ++cmd.sequence;
    stack.backend->exchange(cmd, st);
  }
  ASSERT_TRUE(stack.safety->status(status));
  ASSERT_EQ(status.mode, pmg::hal::safety::Mode::kActive);
  dev->overload_cycle = 0;  // the next cycle: 400 m/s^2
  dev->resetCycle();
  double loop_x = 0.0;
  for (int k = 0; k < 5; ++k) {
    ++cmd.sequence;
    stack.backend->exchange(cmd, st);
    if (k == 0) loop_x = st.imu.acc[0];
  }
  EXPECT_LT(std::fabs(loop_x), 160.0) << "the loop's value is smoothed";
  ASSERT_TRUE(stack.safety->status(status));
  EXPECT_EQ(status.fault.code, pmg::hal::safety::FaultCode::kImuInvalid)
      << "a 400 m/s^2 sample is beyond imu_acc_max for the supervisor, which sees the raw IMU";
  EXPECT_NEAR(status.fault.value, std::hypot(400.0, 9.81), 1e-9);
}

TEST(ImuLowpass, TheHalCycleWithTheLowpassDoesNotAllocate) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  pmg::HalStackConfig hs;
  hs.imu_acc_lowpass_s = 0.005;
  pmg::HalStack stack = pmg::makeHalStack(robot, hs, std::make_unique<SpikyImuBackend>(robot, 100.0));
  pmg::LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  pmg::LowState st;
  stack.backend->exchange(cmd, st);  // first cycle outside the count
  EXPECT_EQ(pmg::test::allocationsDuring([&] {
              for (int k = 0; k < 500; ++k) stack.backend->exchange(cmd, st);
            }),
            0u);
}

TEST(ImuLowpass, ATimeConstantOutsideItsRangeIsRefused) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  for (double bad : {0.001, 0.2, -0.01, std::nan("")}) {
    pmg::HalStackConfig hs;
    hs.imu_acc_lowpass_s = bad;
    try {
      pmg::makeHalStack(robot, hs, std::make_unique<SpikyImuBackend>(robot, 1.0));
      ADD_FAILURE() << "accepted imu_acc_lowpass_s " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("timing.imu_acc_lowpass_s"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
