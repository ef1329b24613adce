// Safety supervisor: every mode transition, every watchdog, the envelope clamps and fall detection,
// and "no allocation" in step().
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/safety/mode_requests.hpp"
#include "pmg/hal/safety/supervisor.hpp"

using namespace pmg::hal::safety;

namespace {

constexpr double kDt = 0.002;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

SafetyOptions twoJoints() {
  SafetyOptions o;
  o.joints = {JointLimits{-1.0, 2.0, 20.0, 50.0, 300.0, 10.0}, JointLimits{-0.5, 0.5, 30.0, 20.0, 100.0, 5.0}};
  o.stand_q = {0.8, 0.1};
  o.stand_kp = {100.0, 40.0};
  o.stand_kd = {3.0, 1.0};
  o.damping_kd = {4.0, 2.0};
  o.soft_stand_duration_s = 1.0;
  o.reset_min_damping_s = 0.5;
  return o;
}

// Drives a supervisor with healthy, fresh inputs; tests break one thing at a time.
struct Rig {
  SafetySupervisor sup;
  SafetyInput in;
  SafetyOutput out;
  double t = 0.0;
  int imu_counter = 0;
  explicit Rig(SafetyOptions o = twoJoints()) : sup(std::move(o)), in(sup.makeInput()), out(sup.makeOutput()) {
    in.q = {0.0, 0.0};
    in.base_height_m = 0.75;
  }
  // Fresh motors, a fresh noisy IMU and a fresh valid command unless told otherwise.
  void tick(ModeRequest r = ModeRequest::kNone, bool fresh_motors = true, bool fresh_imu = true,
            bool fresh_command = true) {
    t += kDt;
    in.now_s = t;
    in.request = r;
    if (fresh_motors)
      for (double& s : in.motor_stamp_s) s = t;
    if (fresh_imu) {
      in.imu.stamp_s = t;
      in.imu.omega_B[0] = 1e-3 * ((imu_counter++ % 7) - 3);  // sensor noise
    }
    if (fresh_command) {
      in.command_stamp_s = t;
      in.policy_stamp_s = t;
      in.policy_valid = true;
    }
    sup.step(in, out);
  }
  void ticks(int n) {
    for (int i = 0; i < n; ++i) tick();
  }
  void toActive() {
    in.q = {0.8, 0.1};  // already at the standing pose: the stand holds still
    tick(ModeRequest::kSoftStand);
    ASSERT_EQ(out.mode, Mode::kSoftStand);
    ticks(static_cast<int>(sup.options().soft_stand_duration_s / kDt) + 1);
    in.q = {0.8, 0.1};
    in.cmd_q = {0.8, 0.1};
    in.cmd_kp = {100.0, 40.0};
    in.cmd_kd = {3.0, 1.0};
    tick(ModeRequest::kActive);
    ASSERT_EQ(out.mode, Mode::kActive);
  }
};

}  // namespace

TEST(Supervisor, StartsPassiveWithZeroTorque) {
  Rig r;
  r.in.cmd_kp = {100, 100};
  r.in.cmd_tau = {5, 5};
  r.ticks(10);
  EXPECT_EQ(r.out.mode, Mode::kPassive);
  for (int j = 0; j < 2; ++j) {
    EXPECT_EQ(r.out.cmd_kp[j], 0.0);
    EXPECT_EQ(r.out.cmd_kd[j], 0.0);
    EXPECT_EQ(r.out.cmd_tau[j], 0.0);
  }
}

TEST(Supervisor, PassiveToSoftStandNeedsHealthyInputs) {
  Rig r;
  r.tick(ModeRequest::kSoftStand, /*fresh_motors=*/false);
  r.tick(ModeRequest::kSoftStand, false);
  for (int i = 0; i < 10; ++i) r.tick(ModeRequest::kNone, false);  // motors time out (never replied)
  r.tick(ModeRequest::kSoftStand, false);
  EXPECT_EQ(r.out.mode, Mode::kPassive) << "stale motors must refuse soft stand";
  EXPECT_EQ(r.out.refused_requests, 3u);
  Rig imu;
  imu.in.imu.stamp_s = -1.0;
  imu.tick(ModeRequest::kSoftStand, true, /*fresh_imu=*/false);
  EXPECT_EQ(imu.out.mode, Mode::kPassive) << "stale IMU must refuse soft stand";
  Rig ok;
  ok.tick(ModeRequest::kSoftStand);
  EXPECT_EQ(ok.out.mode, Mode::kSoftStand);
  EXPECT_TRUE(ok.out.mode_changed);
}

TEST(Supervisor, SoftStandInterpolatesFromMeasuredPose) {
  SafetyOptions o = twoJoints();
  o.joints[0].tau_max = o.joints[1].tau_max = 1000.0;  // keep the torque bound out of this test
  Rig r(o);
  r.in.q = {-0.2, 0.3};
  r.tick(ModeRequest::kSoftStand);
  EXPECT_NEAR(r.out.cmd_q[0], -0.2, 1e-12);
  EXPECT_NEAR(r.out.cmd_q[1], 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(r.out.cmd_kp[0], 100.0);
  EXPECT_DOUBLE_EQ(r.out.cmd_kd[1], 1.0);
  r.ticks(250);  // t = 0.5 s: smoothstep(0.5) = 0.5
  EXPECT_NEAR(r.out.stand_progress, 0.5, 1e-9);
  EXPECT_NEAR(r.out.cmd_q[0], -0.2 + 0.5 * (0.8 + 0.2), 1e-9);
  EXPECT_GT(r.out.cmd_qd[0], 0.0);
  EXPECT_LT(r.out.cmd_qd[1], 0.0);
  // Peak velocity of the quintic at mid-way: 1.875 * distance / T.
  EXPECT_NEAR(r.out.cmd_qd[0], 1.875 * 1.0 / 1.0, 1e-9);
  r.ticks(300);
  EXPECT_NEAR(r.out.cmd_q[0], 0.8, 1e-12);
  EXPECT_NEAR(r.out.cmd_q[1], 0.1, 1e-12);
  EXPECT_EQ(r.out.cmd_qd[0], 0.0);
  EXPECT_EQ(r.out.stand_progress, 1.0);
}

TEST(Supervisor, SoftStandToActiveOnlyWhenStandDoneAndCommandFresh) {
  Rig r;
  r.tick(ModeRequest::kSoftStand);
  r.ticks(100);
  r.tick(ModeRequest::kActive);
  EXPECT_EQ(r.out.mode, Mode::kSoftStand) << "stand not complete";
  r.ticks(500);
  r.in.policy_valid = false;
  r.t += kDt;
  r.in.now_s = r.t;
  r.in.request = ModeRequest::kActive;
  for (double& s : r.in.motor_stamp_s) s = r.t;
  r.in.imu.stamp_s = r.t;
  r.sup.step(r.in, r.out);
  EXPECT_EQ(r.out.mode, Mode::kSoftStand) << "invalid policy output";
  r.tick(ModeRequest::kNone, true, true, false);
  for (int i = 0; i < 30; ++i) r.tick(ModeRequest::kNone, true, true, false);
  r.tick(ModeRequest::kActive, true, true, false);
  EXPECT_EQ(r.out.mode, Mode::kSoftStand) << "stale command stream";
  EXPECT_EQ(r.out.refused_requests, 3u);
  r.tick(ModeRequest::kActive);
  EXPECT_EQ(r.out.mode, Mode::kActive);
}

TEST(Supervisor, ActiveToSoftStandAndSoftStandToPassive) {
  Rig r;
  r.toActive();
  r.in.cmd_q = {0.7, 0.15};
  r.tick();
  const double last_sent = r.out.cmd_q[0];
  r.in.q = {0.5, -0.2};  // tracking error: measured differs from commanded
  r.tick(ModeRequest::kSoftStand);
  EXPECT_EQ(r.out.mode, Mode::kSoftStand);
  EXPECT_NEAR(r.out.cmd_q[0], last_sent, 1e-12)
      << "from active the blend starts at the last command (continuous reference), not the measured pose";
  r.tick(ModeRequest::kPassive);
  EXPECT_EQ(r.out.mode, Mode::kPassive);
  EXPECT_EQ(r.out.cmd_kp[0], 0.0);
}

TEST(Supervisor, SoftStandFromPassiveStartsAtTheMeasuredPose) {
  Rig r;
  r.in.q = {0.5, -0.2};
  r.tick(ModeRequest::kSoftStand);
  ASSERT_EQ(r.out.mode, Mode::kSoftStand);
  EXPECT_NEAR(r.out.cmd_q[0], 0.5, 1e-12);
}

TEST(Supervisor, ActiveToPassiveIsRefused) {
  Rig r;
  r.toActive();
  r.tick(ModeRequest::kPassive);
  EXPECT_EQ(r.out.mode, Mode::kActive);
  EXPECT_EQ(r.out.refused_requests, 1u);
}

TEST(Supervisor, EstopFromEveryModeLatchesDamping) {
  for (int from = 0; from < 3; ++from) {
    Rig r;
    if (from == 1) r.tick(ModeRequest::kSoftStand);
    if (from == 2) r.toActive();
    r.in.qd = {1.0, -2.0};
    r.tick(ModeRequest::kDamping);
    ASSERT_EQ(r.out.mode, Mode::kDamping) << "from mode " << from;
    EXPECT_EQ(r.out.fault.code, FaultCode::kEstop);
    EXPECT_EQ(r.out.fault_counts[static_cast<int>(FaultCode::kEstop)], 1u);
    EXPECT_EQ(r.out.cmd_kp[0], 0.0);
    EXPECT_EQ(r.out.cmd_qd[0], 0.0);
    EXPECT_EQ(r.out.cmd_tau[0], 0.0);
    EXPECT_DOUBLE_EQ(r.out.cmd_kd[0], 4.0);
    EXPECT_DOUBLE_EQ(r.out.cmd_kd[1], 2.0);
    // Latched: nothing but a reset leaves damping, even with everything healthy again.
    r.tick(ModeRequest::kSoftStand);
    r.tick(ModeRequest::kActive);
    r.ticks(100);
    EXPECT_EQ(r.out.mode, Mode::kDamping);
    EXPECT_EQ(r.out.fault.code, FaultCode::kEstop) << "the cause stays recorded";
  }
}

TEST(Supervisor, ResetFromDampingNeedsTimeAndStillness) {
  Rig r;
  r.toActive();
  r.tick(ModeRequest::kDamping);
  r.tick(ModeRequest::kReset);
  EXPECT_EQ(r.out.mode, Mode::kDamping) << "too early";
  r.ticks(300);
  r.tick(ModeRequest::kPassive);
  EXPECT_EQ(r.out.mode, Mode::kDamping) << "passive is not reset: only kReset clears the latch";
  r.in.qd = {0.0, 1.0};
  r.tick(ModeRequest::kReset);
  EXPECT_EQ(r.out.mode, Mode::kDamping) << "still moving";
  r.in.qd = {0.0, 0.1};
  r.tick(ModeRequest::kReset);
  EXPECT_EQ(r.out.mode, Mode::kPassive);
  EXPECT_EQ(r.out.fault.code, FaultCode::kNone);
  r.tick(ModeRequest::kSoftStand);
  EXPECT_EQ(r.out.mode, Mode::kSoftStand) << "a new cycle can start after reset";
}

namespace {
// Run `breakit` on an active rig and count ticks until damping; check the recorded cause.
void expectDampingWithin(FaultCode code, int index, int max_ticks,
                         const std::function<void(Rig&)>& breakit, bool fresh_motors = true,
                         bool fresh_imu = true, bool fresh_command = true) {
  Rig r;
  r.toActive();
  breakit(r);
  int n = 0;
  while (r.out.mode != Mode::kDamping && n < 1000) {
    r.tick(ModeRequest::kNone, fresh_motors, fresh_imu, fresh_command);
    ++n;
  }
  EXPECT_EQ(r.out.mode, Mode::kDamping) << toString(code);
  EXPECT_LE(n, max_ticks) << toString(code);
  EXPECT_EQ(r.out.fault.code, code) << toString(r.out.fault.code) << " instead of " << toString(code);
  EXPECT_EQ(r.out.fault.index, index) << toString(code);
  EXPECT_EQ(r.out.fault_counts[static_cast<int>(code)], 1u);
  for (int j = 0; j < 2; ++j) EXPECT_EQ(r.out.cmd_kp[j], 0.0);
}
}  // namespace

TEST(Supervisor, EachWatchdogSendsActiveToDamping) {
  const WatchdogOptions w;
  const int cmd_ticks = static_cast<int>(w.command_timeout_s / kDt) + 1;
  const int motor_ticks = static_cast<int>(w.motor_timeout_s / kDt) + 1;
  expectDampingWithin(FaultCode::kCommandStale, -1, cmd_ticks, [](Rig&) {}, true, true, false);
  expectDampingWithin(FaultCode::kCommandInvalid, 1, 1, [](Rig& r) { r.in.cmd_tau[1] = kNaN; });
  expectDampingWithin(FaultCode::kPolicyInvalid, -1, 1, [](Rig& r) {
    r.tick();
    r.in.policy_valid = false;
    r.t += kDt;
    r.in.now_s = r.t;
    r.in.command_stamp_s = r.t;
    for (double& s : r.in.motor_stamp_s) s = r.t;
    r.in.imu.stamp_s = r.t;
    r.sup.step(r.in, r.out);
  });
  expectDampingWithin(FaultCode::kMotorStale, 1, motor_ticks, [](Rig& r) {
    // Motor 1 stops replying: its stamp no longer advances while motor 0's does.
    for (int i = 0; i < 20 && r.out.mode != Mode::kDamping; ++i) {
      const double last1 = r.in.motor_stamp_s[1];
      r.tick();
      r.in.motor_stamp_s[1] = last1;
      r.sup.step(r.in, r.out);
    }
  });
  expectDampingWithin(FaultCode::kMotorInvalid, 0, 1, [](Rig& r) { r.in.tau[0] = kNaN; });
  expectDampingWithin(FaultCode::kImuStale, -1, static_cast<int>(w.imu_timeout_s / kDt) + 1, [](Rig&) {},
                      true, false, true);
  expectDampingWithin(FaultCode::kImuInvalid, -1, 1, [](Rig& r) { r.in.imu.quat_WB[0] = 0.5; });
  expectDampingWithin(FaultCode::kImuInvalid, -1, 1, [](Rig& r) { r.in.imu.acc_B[2] = 400.0; });
  expectDampingWithin(FaultCode::kImuInvalid, -1, 1, [](Rig& r) { r.in.imu.omega_B[1] = kNaN; });
}

TEST(Supervisor, FrozenImuIsDetected) {
  Rig r;
  r.toActive();
  // The IMU keeps publishing (fresh stamps) but the values stop changing.
  int n = 0;
  while (r.out.mode == Mode::kActive && n < 500) {
    r.t += kDt;
    r.in.now_s = r.t;
    for (double& s : r.in.motor_stamp_s) s = r.t;
    r.in.imu.stamp_s = r.t;
    r.in.command_stamp_s = r.in.policy_stamp_s = r.t;
    r.sup.step(r.in, r.out);
    ++n;
  }
  EXPECT_EQ(r.out.fault.code, FaultCode::kImuFrozen);
  EXPECT_EQ(n, WatchdogOptions{}.imu_frozen_samples);
}

TEST(Supervisor, EnvelopeFaultsAndFallLatchDamping) {
  const EnvelopeOptions e;
  expectDampingWithin(FaultCode::kJointPosition, 1, 1, [&](Rig& r) { r.in.q[1] = 0.5 + e.q_fault_margin + 0.01; });
  expectDampingWithin(FaultCode::kJointVelocity, 0, 1, [&](Rig& r) { r.in.qd[0] = -20.0 * e.qd_fault_factor - 1; });
  expectDampingWithin(FaultCode::kJointTorque, 1, 1, [&](Rig& r) { r.in.tau[1] = 20.0 * e.tau_fault_factor + 1; });
  expectDampingWithin(FaultCode::kFallTilt, -1, 1, [&](Rig& r) {
    const double a = 0.5 * (e.max_tilt_rad + 0.05);  // rotation about x by max_tilt + 0.05 rad
    r.in.imu.quat_WB[0] = std::cos(a);
    r.in.imu.quat_WB[1] = std::sin(a);
  });
  expectDampingWithin(FaultCode::kFallHeight, -1, 1, [&](Rig& r) { r.in.base_height_m = e.min_base_height_m - 0.01; });
  // Unknown height (NaN) does not trip the height check.
  Rig r;
  r.toActive();
  r.in.base_height_m = kNaN;
  r.ticks(10);
  EXPECT_EQ(r.out.mode, Mode::kActive);
  // Tilt just below the threshold is fine.
  const double a = 0.5 * (e.max_tilt_rad - 0.05);
  r.in.imu.quat_WB[0] = std::cos(a);
  r.in.imu.quat_WB[1] = std::sin(a);
  r.ticks(10);
  EXPECT_EQ(r.out.mode, Mode::kActive);
}

TEST(Supervisor, FaultsInSoftStandToo) {
  Rig r;
  r.tick(ModeRequest::kSoftStand);
  r.in.imu.stamp_s = r.t;
  for (int i = 0; i < 20 && r.out.mode == Mode::kSoftStand; ++i) r.tick(ModeRequest::kNone, true, false);
  EXPECT_EQ(r.out.mode, Mode::kDamping);
  EXPECT_EQ(r.out.fault.code, FaultCode::kImuStale);
}

TEST(Supervisor, WatchdogsDoNotActInPassive) {
  Rig r;
  for (int i = 0; i < 50; ++i) r.tick(ModeRequest::kNone, false, false, false);
  EXPECT_EQ(r.out.mode, Mode::kPassive);
  EXPECT_EQ(r.out.fault.code, FaultCode::kNone);
}

TEST(Supervisor, ActiveCommandIsClampedAndSlewLimited) {
  SafetyOptions o = twoJoints();
  o.envelope.q_rate_max = 20.0;  // rad/s: 0.04 rad a cycle
  Rig r(o);
  r.toActive();
  const double dq = 20.0 * kDt;
  const std::uint64_t slewed = r.out.slew_clamped_joint_ticks;
  r.in.cmd_q = {1.8, 0.1};  // a 1 rad step on joint 0
  r.tick();
  EXPECT_NEAR(r.out.cmd_q[0], 0.8 + dq, 1e-12);
  EXPECT_TRUE(r.out.clamp_bits[0] & kClampSlew);
  EXPECT_EQ(r.out.slew_clamped_joint_ticks, slewed + 1) << "counted, joint 0 only";
  r.ticks(200);
  EXPECT_NEAR(r.out.cmd_q[0], 0.8 + 50.0 / 100.0, 1e-9) << "torque bound: kp (q - q_meas) <= tau_max";
  EXPECT_TRUE(r.out.clamp_bits[0] & kClampTorque);
  r.in.cmd_q = {5.0, 0.1};
  r.in.q = {1.9, 0.1};
  r.ticks(200);
  EXPECT_LE(r.out.cmd_q[0], 2.0) << "position limit";
}

// The default slew (600 rad/s, 1.2 rad a 2 ms cycle) lets a policy's position target step through
// within the cycle, as in training (an actor steps a leg target by up to 1.15 rad a tick); a larger
// step is spread over cycles and counted.
TEST(Supervisor, DefaultSlewPassesAPolicyStepAndSpreadsALargerOne) {
  SafetyOptions o = twoJoints();
  o.joints[0].tau_max = 1e4;  // no torque bound in the way
  Rig r(o);
  r.toActive();
  const double q0 = r.out.cmd_q[0];
  const double dq = EnvelopeOptions{}.q_rate_max * kDt;
  ASSERT_GE(dq, 1.15) << "the shipped actor's largest leg-target step a tick must pass in one cycle";
  const std::uint64_t slewed = r.out.slew_clamped_joint_ticks;
  r.in.cmd_q = {q0 + 1.0, 0.1};
  r.tick();
  EXPECT_NEAR(r.out.cmd_q[0], q0 + 1.0, 1e-12);
  EXPECT_FALSE(r.out.clamp_bits[0] & kClampSlew);
  EXPECT_EQ(r.out.slew_clamped_joint_ticks, slewed);
  r.in.cmd_q = {q0 + 1.0 - 3.0, 0.1};  // 3 rad back: more than one cycle's slew
  r.in.q = {q0 + 1.0, 0.1};
  r.tick();
  EXPECT_NEAR(r.out.cmd_q[0], std::max(q0 + 1.0 - dq, -2.0), 1e-12);
  EXPECT_TRUE(r.out.clamp_bits[0] & kClampSlew);
  EXPECT_EQ(r.out.slew_clamped_joint_ticks, slewed + 1);
}

TEST(Supervisor, RandomCommandsNeverExceedTorqueLimits) {
  Rig r;
  r.toActive();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    for (int j = 0; j < 2; ++j) {
      r.in.cmd_q[j] = 5 * u(rng);
      r.in.cmd_qd[j] = 100 * u(rng);
      r.in.cmd_kp[j] = 500 * u(rng);
      r.in.cmd_kd[j] = 20 * u(rng);
      r.in.cmd_tau[j] = 200 * u(rng);
      r.in.q[j] = 0.3 * u(rng);
      r.in.qd[j] = 10 * u(rng);
    }
    r.tick();
    ASSERT_EQ(r.out.mode, Mode::kActive);
    for (int j = 0; j < 2; ++j) {
      const JointLimits& L = r.sup.options().joints[j];
      JointSetpoint sp{r.out.cmd_q[j], r.out.cmd_qd[j], r.out.cmd_kp[j], r.out.cmd_kd[j], r.out.cmd_tau[j]};
      ASSERT_LE(std::fabs(predictedTorque(sp, r.in.q[j], r.in.qd[j])), L.tau_max + 1e-9);
      ASSERT_GE(sp.kp, 0.0);
      ASSERT_LE(sp.kp, L.kp_max);
      ASSERT_LE(sp.kd, L.kd_max);
      ASSERT_LE(std::fabs(sp.qd), L.qd_max + 1e-9);
    }
  }
}

TEST(Supervisor, ClampHandlesNonFiniteMeasurement) {
  JointLimits L;
  JointSetpoint sp{0.5, 0.0, 100.0, 2.0, 1.0};
  EXPECT_EQ(clampSetpoint(L, kNaN, 0.0, sp), kClampNonFinite);
  EXPECT_EQ(sp.kp, 0.0);
  EXPECT_EQ(sp.kd, 0.0);
  EXPECT_EQ(sp.tau_ff, 0.0);
  EXPECT_TRUE(std::isfinite(sp.q));
  double unit[4] = {1, 0, 0, 0};
  EXPECT_NEAR(baseTilt(unit), 0.0, 1e-12);
  double upside_down[4] = {0, 1, 0, 0};
  EXPECT_NEAR(baseTilt(upside_down), M_PI, 1e-12);
  double zero[4] = {0, 0, 0, 0};
  EXPECT_TRUE(std::isnan(baseTilt(zero)));
}

TEST(Supervisor, StepDoesNotAllocate) {
  Rig r;
  long allocs = 0;
  {
    pmg::test::AllocationGuard scope;
    r.tick(ModeRequest::kSoftStand);
    r.ticks(600);
    r.in.q = {0.8, 0.1};
    r.tick(ModeRequest::kActive);
    r.ticks(50);
    r.tick(ModeRequest::kDamping);
    r.ticks(300);
    r.in.qd = {0, 0};
    r.tick(ModeRequest::kReset);
    allocs = static_cast<long>(scope.count());
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_EQ(r.out.mode, Mode::kPassive);
}

TEST(Supervisor, OptionsValidationNamesTheField) {
  SafetyOptions o = twoJoints();
  o.stand_q[1] = 3.0;
  try {
    SafetySupervisor s(o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stand_q[1]"), std::string::npos) << e.what();
  }
  o = twoJoints();
  o.damping_kd.pop_back();
  EXPECT_NE(o.validate().find("damping_kd: expected 2 values"), std::string::npos);
  o = twoJoints();
  o.envelope.max_tilt_rad = 4.0;
  EXPECT_NE(o.validate().find("max_tilt_rad"), std::string::npos);
}

TEST(Supervisor, OptionsFromG1RobotConfig) {
  const pmg::RobotConfig robot = pmg::loadRobotConfig(pmg::test::g1RobotConfigPath());
  SafetyOptions o = SafetyOptions::fromRobot(robot);
  EXPECT_EQ(o.joints.size(), 29u);
  EXPECT_EQ(o.validate(), "");
  SafetySupervisor s(o);
  EXPECT_EQ(s.numJoints(), 29u);
  EXPECT_DOUBLE_EQ(o.joints[3].tau_max, 139.0);  // left knee
}

TEST(ModeRequests, WireCodesMatchTheLcmTypeAndUnknownCodesAreRejected) {
  // pmg_lcm::mode_command_t: 0 passive, 1 soft stand, 2 active, 3 damping (e-stop), 4 reset.
  ModeRequest r = ModeRequest::kNone;
  ASSERT_TRUE(pmg::modeRequestFromWire(0, r));
  EXPECT_EQ(r, ModeRequest::kPassive);
  ASSERT_TRUE(pmg::modeRequestFromWire(2, r));
  EXPECT_EQ(r, ModeRequest::kActive);
  ASSERT_TRUE(pmg::modeRequestFromWire(3, r));
  EXPECT_EQ(r, ModeRequest::kDamping);
  ASSERT_TRUE(pmg::modeRequestFromWire(4, r));
  EXPECT_EQ(r, ModeRequest::kReset);
  for (int bad : {5, 7, 99, -1, -5, 127, -128}) {
    r = ModeRequest::kNone;
    EXPECT_FALSE(pmg::modeRequestFromWire(bad, r)) << bad;
    EXPECT_EQ(r, ModeRequest::kNone) << "a rejected code leaves the output unchanged";
  }
  EXPECT_STREQ(pmg::toString(Mode::kDamping), "damping");
  EXPECT_STREQ(pmg::toString(FaultCode::kFallHeight), "fall: base height");
  ModeRequestMailbox box;
  EXPECT_EQ(box.take(), ModeRequest::kNone);
  box.post(ModeRequest::kSoftStand);
  box.post(ModeRequest::kActive);
  EXPECT_EQ(box.take(), ModeRequest::kActive) << "latest wins";
  EXPECT_EQ(box.take(), ModeRequest::kNone);
  box.post(ModeRequest::kDamping);
  box.post(ModeRequest::kActive);
  EXPECT_EQ(box.take(), ModeRequest::kDamping) << "a pending e-stop is never overwritten";
}

TEST(Supervisor, BackendFaultLatchesDampingWhileTorqueIsApplied) {
  Rig r;
  r.in.backend_fault = true;
  r.tick();
  EXPECT_EQ(r.out.mode, Mode::kPassive) << "no torque applied in passive: nothing to stop";
  r.in.backend_fault = false;
  r.toActive();
  r.in.backend_fault = true;
  r.tick();
  EXPECT_EQ(r.out.mode, Mode::kDamping);
  EXPECT_EQ(r.out.fault.code, FaultCode::kBackend);
}
