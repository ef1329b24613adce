// ActuatorModel: stiction, Stribeck, load-dependent friction, delay line, limits, driver rate,
// zero offset; and that step() does not allocate.
#include <cmath>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "pmg/calib/actuator_model.hpp"

namespace pmg::calib {
namespace {

JointSample joint(double q, double dq, double inertia, double tau_other, double dt = 0.001) {
  JointSample j;
  j.q_rad = q;
  j.dq_rad_per_s = dq;
  j.inertia_kgm2 = inertia;
  j.tau_other_Nm = tau_other;
  j.dt_s = dt;
  return j;
}

MotorCommand torque(double tau) {
  MotorCommand c;
  c.tau_ff_Nm = tau;
  return c;
}

TEST(ActuatorModel, StictionHoldsBelowBreakawayAndSlipsAbove) {
  ActuatorParams p;
  p.fc_Nm = 0.2;
  p.validate();
  ActuatorState s;
  // At rest, 0.15 N·m of drive: friction cancels it exactly (joint stays stuck).
  auto o = ActuatorModel::step(p, s, torque(0.15), joint(0, 0, 0.01, 0.0));
  EXPECT_TRUE(o.stuck);
  EXPECT_NEAR(o.tau_applied_Nm, 0.0, 1e-12);
  // 0.25 N·m exceeds the break-away: it slips and kinetic friction (0.2) opposes the motion.
  s.reset();
  o = ActuatorModel::step(p, s, torque(0.25), joint(0, 0, 0.01, 0.0));
  EXPECT_FALSE(o.stuck);
  EXPECT_NEAR(o.tau_applied_Nm, 0.05, 1e-12);
  // Moving fast: kinetic friction opposes the velocity.
  s.reset();
  o = ActuatorModel::step(p, s, torque(0.0), joint(0, 2.0, 0.01, 0.0));
  EXPECT_NEAR(o.tau_friction_Nm, -0.2, 1e-12);
  // Slow enough to be stopped within the step: it is stopped exactly (no chattering).
  s.reset();
  o = ActuatorModel::step(p, s, torque(0.0), joint(0, 0.01, 0.01, 0.0));
  EXPECT_TRUE(o.stuck);
  EXPECT_NEAR(o.tau_applied_Nm, -0.01 * 0.01 / 0.001, 1e-12);  // v+ = v + dt/I tau = 0
}

TEST(ActuatorModel, StribeckBreakawayAboveKinetic) {
  ActuatorParams p;
  p.fc_Nm = 0.1;
  p.fs_Nm = 0.3;
  p.vs_rad_per_s = 0.05;
  p.validate();
  EXPECT_DOUBLE_EQ(ActuatorModel::static_friction(p, 0.0), 0.3);
  EXPECT_NEAR(ActuatorModel::kinetic_friction(p, 1.0, 0.0), 0.1, 1e-9);
  EXPECT_NEAR(ActuatorModel::kinetic_friction(p, 0.05, 0.0), 0.1 + 0.2 * std::exp(-1.0), 1e-12);
  ActuatorState s;
  EXPECT_TRUE(ActuatorModel::step(p, s, torque(0.25), joint(0, 0, 0.01, 0.0)).stuck);
  s.reset();
  EXPECT_FALSE(ActuatorModel::step(p, s, torque(0.35), joint(0, 0, 0.01, 0.0)).stuck);
}

TEST(ActuatorModel, LoadDependentFrictionGrowsWithMotorTorque) {
  ActuatorParams p;
  p.fc_Nm = 0.05;
  p.kl = 0.2;
  p.validate();
  EXPECT_NEAR(ActuatorModel::static_friction(p, 1.0), 0.25, 1e-12);
  ActuatorState s;
  // 1 N·m motor torque against a 0.8 N·m load: net 0.2 < 0.25 break-away -> stuck.
  EXPECT_TRUE(ActuatorModel::step(p, s, torque(1.0), joint(0, 0, 0.01, -0.8)).stuck);
  s.reset();
  // Without the load term the same situation slips.
  p.kl = 0.0;
  EXPECT_FALSE(ActuatorModel::step(p, s, torque(1.0), joint(0, 0, 0.01, -0.8)).stuck);
}

TEST(ActuatorModel, TransportDelayShiftsTheCommandByDelaySteps) {
  ActuatorParams p;
  p.delay_s = 0.005;  // 5 steps of 1 ms
  p.validate();
  ActuatorState s;
  for (int k = 0; k < 20; ++k) {
    const auto o = ActuatorModel::step(p, s, torque(static_cast<double>(k)), joint(0, 0, 0.0, 0.0));
    EXPECT_NEAR(o.tau_motor_Nm, std::max(0, k - 5), 1e-12) << "step " << k;
  }
  // Fractional delay interpolates linearly (continuous in delay_s).
  p.delay_s = 0.0025;
  s.reset();
  double last = 0.0;
  for (int k = 0; k < 10; ++k) last = ActuatorModel::step(p, s, torque(static_cast<double>(k)), joint(0, 0, 0, 0)).tau_motor_Nm;
  EXPECT_NEAR(last, 9 - 2.5, 1e-12);
}

TEST(ActuatorModel, SaturationAndTorqueSpeedEnvelope) {
  ActuatorParams p;
  p.torque_limit_Nm = 2.0;
  p.tau_stall_Nm = 3.0;
  p.w_max_rad_per_s = 10.0;
  p.validate();
  EXPECT_DOUBLE_EQ(ActuatorModel::limit_torque(p, 5.0, 0.0), 2.0);   // saturation
  EXPECT_DOUBLE_EQ(ActuatorModel::limit_torque(p, 5.0, 5.0), 1.5);   // 3 (1 - 5/10)
  EXPECT_DOUBLE_EQ(ActuatorModel::limit_torque(p, -5.0, 5.0), -2.0); // braking side: -3 (1 + 0.5) clipped by 2
  EXPECT_DOUBLE_EQ(ActuatorModel::limit_torque(p, 1.0, -8.0), 1.0);
  EXPECT_DOUBLE_EQ(ActuatorModel::limit_torque(p, -5.0, -8.0), -0.6); // -3 (1 - 0.8)
}

TEST(ActuatorModel, PdOnOffsetEncoderAtDriverRate) {
  ActuatorParams p;
  p.offset_rad = 0.01;
  p.rate_hz = 250.0;  // every 4th step of 1 ms
  p.validate();
  ActuatorState s;
  MotorCommand c;
  c.q_des_rad = 0.1;
  c.kp_Nm_per_rad = 10.0;
  c.kd_Nms_per_rad = 0.5;
  // Encoder reads q + offset = 0.01: tau = 10 (0.1 - 0.01) - 0.5 * 0.2 = 0.8.
  EXPECT_NEAR(ActuatorModel::step(p, s, c, joint(0.0, 0.2, 0, 0)).tau_motor_Nm, 0.8, 1e-12);
  // Held for the next 3 steps although the state changed, recomputed on the 4th.
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(ActuatorModel::step(p, s, c, joint(0.05, 0.0, 0, 0)).tau_motor_Nm, 0.8, 1e-12);
  EXPECT_NEAR(ActuatorModel::step(p, s, c, joint(0.05, 0.0, 0, 0)).tau_motor_Nm, 10.0 * (0.1 - 0.06), 1e-12);
  c.enabled = false;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(ActuatorModel::step(p, s, c, joint(0.05, 0.0, 0, 0)).tau_motor_Nm, 0.0);
}

TEST(ActuatorModel, ValidateNamesTheField) {
  ActuatorParams p;
  p.kl = 2.0;
  try {
    p.validate();
    FAIL() << "kl = 2 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kl"), std::string::npos);
  }
}

TEST(ActuatorModel, StepDoesNotAllocate) {
  ActuatorParams p;
  p.fc_Nm = 0.1;
  p.fs_Nm = 0.2;
  p.kl = 0.1;
  p.delay_s = 0.003;
  p.tau_stall_Nm = 2.0;
  p.w_max_rad_per_s = 20.0;
  auto s = std::make_unique<ActuatorState>();
  MotorCommand c;
  c.kp_Nm_per_rad = 5.0;
  double sum = 0.0;
  std::size_t allocations = 0;
  {
    pmg::test::AllocationGuard guard;
    for (int k = 0; k < 1000; ++k) {
      c.q_des_rad = std::sin(0.01 * k);
      sum += ActuatorModel::step(p, *s, c, joint(0.0, 0.1, 0.01, -0.05)).tau_applied_Nm;
    }
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace pmg::calib
