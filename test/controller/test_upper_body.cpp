// pmg::UpperBodyCompensation (include/pmg/controller/upper_body.hpp): the gravity torques equal the
// gradient of the robot's potential energy (an independent computation: finite differences of
// sum m_i g z_i over MuJoCo's body centres of mass), for the base upright and tilted through the
// IMU; apply() writes only the configured joints' tau_ff, damps, clamps and allocates nothing; the
// config refuses the actor's joints, unknown joints, duplicates and values out of range.
#include <cmath>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "temp_dir.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/controller/upper_body.hpp"
#include "pmg/policy/contract.hpp"

namespace pmg {
namespace {

std::vector<std::string> legs() { return policy::makePolicyRobotSpec(test::g1Robot(), 0.01).leg_joints; }

UpperBodyConfig waistAndLeftArm() {
  UpperBodyConfig c;
  c.enabled = true;
  c.joints = {"waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint", "left_shoulder_pitch_joint", "left_elbow_joint"};
  c.max_torque = 300.0;
  c.ramp_s = 0.0;
  return c;
}

// A bent, turned pose with the arms forward (the box carrier's), base orientation q_wb.
LowState pose(const RobotConfig& robot, const std::array<double, 4>& q_wb) {
  LowState s;
  s.num_motors = static_cast<int>(robot.numJoints());
  for (int i = 0; i < s.num_motors; ++i) s.motors[static_cast<std::size_t>(i)].q = robot.joints[static_cast<std::size_t>(i)].default_position;
  const auto set = [&](const char* name, double q) { s.motors[static_cast<std::size_t>(robot.jointIndex(name))].q = q; };
  set("waist_pitch_joint", 0.35);
  set("waist_roll_joint", -0.1);
  set("waist_yaw_joint", 0.2);
  set("left_shoulder_pitch_joint", -0.9);
  set("right_shoulder_pitch_joint", -0.7);
  set("left_elbow_joint", 0.3);
  set("right_elbow_joint", 0.5);
  s.imu.quat_wxyz = q_wb;  // the G1's IMU site sits on the pelvis without a turn
  s.imu.valid = true;
  return s;
}

// Potential energy sum m_i g z_i [J] of the robot in MuJoCo's model at joint positions q (robot
// order) and base orientation q_wb.
double potential(const mjModel* m, mjData* d, const RobotConfig& robot, const LowState& s) {
  mj_resetData(m, d);
  int free_q = -1;
  for (int k = 0; k < m->njnt && free_q < 0; ++k)
    if (m->jnt_type[k] == mjJNT_FREE) free_q = m->jnt_qposadr[k];
  for (int a = 0; a < 4; ++a) d->qpos[free_q + 3 + a] = s.imu.quat_wxyz[static_cast<std::size_t>(a)];
  for (std::size_t i = 0; i < robot.numJoints(); ++i)
    d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, robot.joints[i].name.c_str())]] = s.motors[i].q;
  mj_kinematics(m, d);
  double v = 0.0;
  for (int b = 1; b < m->nbody; ++b) v += m->body_mass[b] * -m->opt.gravity[2] * d->xipos[3 * b + 2];
  return v;
}

void expectGravityIsThePotentialsGradient(const std::array<double, 4>& q_wb) {
  const RobotConfig& robot = test::g1Robot();
  UpperBodyCompensation ub(robot, waistAndLeftArm(), legs());
  const LowState s = pose(robot, q_wb);
  const std::vector<double> g = ub.gravity(s);
  MjModelPtr m = loadMujocoModel(robot.mjcf_path);
  MjDataPtr d(mj_makeData(m.get()));
  const double h = 1e-6;
  double largest = 0.0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    const auto j = static_cast<std::size_t>(ub.jointIndices()[k]);
    LowState plus = s, minus = s;
    plus.motors[j].q += h;
    minus.motors[j].q -= h;
    const double dv = (potential(m.get(), d.get(), robot, plus) - potential(m.get(), d.get(), robot, minus)) / (2 * h);
    EXPECT_NEAR(g[k], dv, 1e-4 + 1e-4 * std::fabs(dv)) << ub.config().joints[k];
    largest = std::max(largest, std::fabs(dv));
  }
  // Not a trivial pose: the waist pitch holds the bent upper body with the arms forward.
  EXPECT_GT(largest, 5.0);
}

TEST(UpperBody, GravityIsThePotentialEnergysGradientUpright) { expectGravityIsThePotentialsGradient({1, 0, 0, 0}); }

TEST(UpperBody, GravityIsThePotentialEnergysGradientWithTheBaseTilted) {
  // Pelvis pitched 0.3 rad forward and rolled 0.1 rad (the IMU's quaternion, world <- IMU).
  const double p = 0.15, r = 0.05;
  const std::array<double, 4> qp{std::cos(p), 0, std::sin(p), 0}, qr{std::cos(r), std::sin(r), 0, 0};
  const std::array<double, 4> q{qp[0] * qr[0], qp[0] * qr[1], qp[2] * qr[0], -qp[2] * qr[1]};  // qp * qr
  expectGravityIsThePotentialsGradient(q);
  // And the tilt matters: the same joints, upright, need other torques.
  const RobotConfig& robot = test::g1Robot();
  UpperBodyCompensation ub(robot, waistAndLeftArm(), legs());
  const std::vector<double> tilted = ub.gravity(pose(robot, q));
  const std::vector<double> upright = ub.gravity(pose(robot, {1, 0, 0, 0}));
  EXPECT_GT(std::fabs(tilted[2] - upright[2]), 1.0);  // waist pitch [N m]
}

TEST(UpperBody, ApplyWritesOnlyItsJointsDampsAndClamps) {
  const RobotConfig& robot = test::g1Robot();
  UpperBodyConfig c = waistAndLeftArm();
  c.damping = 5.0;
  c.gravity_scale = 0.5;
  c.max_torque = 300.0;
  c.ramp_s = 0.0;
  UpperBodyCompensation ub(robot, c, legs());
  LowState s = pose(robot, {1, 0, 0, 0});
  const int pitch = robot.jointIndex("waist_pitch_joint");
  s.motors[static_cast<std::size_t>(pitch)].qd = 0.4;
  s.motors[static_cast<std::size_t>(robot.jointIndex("waist_roll_joint"))].qd = std::nan("");
  LowCommand cmd;
  cmd.num_motors = s.num_motors;
  for (auto& mc : cmd.motors) mc.tau_ff = 7.0;
  const std::vector<double> g = ub.gravity(s);
  ub.apply(s, cmd, 0.01);
  EXPECT_NEAR(cmd.motors[static_cast<std::size_t>(pitch)].tau_ff, 0.5 * g[2] - 5.0 * 0.4, 1e-12);
  EXPECT_NEAR(cmd.motors[static_cast<std::size_t>(robot.jointIndex("waist_roll_joint"))].tau_ff, 0.5 * g[1], 1e-12)
      << "a non-finite velocity is not damped";
  for (int i = 0; i < cmd.num_motors; ++i) {
    bool mine = false;
    for (const int j : ub.jointIndices()) mine = mine || j == i;
    if (!mine) {
      EXPECT_EQ(cmd.motors[static_cast<std::size_t>(i)].tau_ff, 7.0) << robot.joints[static_cast<std::size_t>(i)].name;
    }
  }
  // Clamped to max_torque, and to the joint's torque limit.
  c.max_torque = 1.0;
  UpperBodyCompensation small(robot, c, legs());
  s.motors[static_cast<std::size_t>(pitch)].qd = 100.0;
  small.apply(s, cmd, 0.01);
  EXPECT_DOUBLE_EQ(cmd.motors[static_cast<std::size_t>(pitch)].tau_ff, -1.0);
  c.max_torque = 300.0;
  c.damping = 50.0;
  UpperBodyCompensation big(robot, c, legs());
  big.apply(s, cmd, 0.01);
  EXPECT_DOUBLE_EQ(cmd.motors[static_cast<std::size_t>(pitch)].tau_ff, -robot.joints[static_cast<std::size_t>(pitch)].torque_limit);
}

TEST(UpperBody, FadesInAfterResetSoThatEngagingNeverStepsATorque) {
  const RobotConfig& robot = test::g1Robot();
  UpperBodyConfig c = waistAndLeftArm();
  c.ramp_s = 0.5;
  UpperBodyCompensation ub(robot, c, legs());
  const LowState s = pose(robot, {1, 0, 0, 0});
  const int pitch = robot.jointIndex("waist_pitch_joint");
  const double full = UpperBodyCompensation(robot, waistAndLeftArm(), legs()).gravity(s)[2];
  ASSERT_GT(std::fabs(full), 5.0);
  LowCommand cmd;
  cmd.num_motors = s.num_motors;
  ub.reset();
  double prev = 0.0, largest_step = 0.0;
  for (int k = 1; k <= 60; ++k) {
    ub.apply(s, cmd, 0.01);
    const double tau = cmd.motors[static_cast<std::size_t>(pitch)].tau_ff;
    if (k == 1) {
      EXPECT_NEAR(tau, full * 0.01 / 0.5, 1e-9) << "the first tick after reset";
    }
    if (k == 25) {
      EXPECT_NEAR(tau, full * 0.5, 1e-9) << "half way";
    }
    largest_step = std::max(largest_step, std::fabs(tau - prev));
    prev = tau;
  }
  EXPECT_NEAR(prev, full, 1e-9) << "faded in after ramp_s";
  EXPECT_LE(largest_step, std::fabs(full) * 0.01 / 0.5 + 1e-9);
  ub.reset();  // entering active again starts from zero
  ub.apply(s, cmd, 0.01);
  EXPECT_NEAR(cmd.motors[static_cast<std::size_t>(pitch)].tau_ff, full * 0.01 / 0.5, 1e-9);
}

TEST(UpperBody, ApplyAllocatesNothing) {
  const RobotConfig& robot = test::g1Robot();
  UpperBodyCompensation ub(robot, waistAndLeftArm(), legs());
  LowState s = pose(robot, {1, 0, 0, 0});
  LowCommand cmd;
  cmd.num_motors = s.num_motors;
  ub.apply(s, cmd, 0.01);
  test::AllocationGuard guard;
  for (int k = 0; k < 100; ++k) {
    s.motors[14].q = 0.3 + 0.001 * k;
    ub.apply(s, cmd, 0.01);
  }
  EXPECT_EQ(guard.count(), 0u);
}

TEST(UpperBody, RefusesTheActorsJointsUnknownJointsAndDuplicates) {
  const RobotConfig& robot = test::g1Robot();
  const auto refused = [&](std::vector<std::string> joints, const std::string& what) {
    UpperBodyConfig c;
    c.enabled = true;
    c.joints = std::move(joints);
    try {
      UpperBodyCompensation ub(robot, c, legs());
      ADD_FAILURE() << "accepted; expected: " << what;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused({"waist_pitch_joint", "left_knee_joint"}, "upper_body.joints[1] = 'left_knee_joint': a joint the actor commands");
  refused({"waist_pich_joint"}, "upper_body.joints[0] = 'waist_pich_joint': not a joint");
  refused({"waist_pitch_joint", "waist_pitch_joint"}, "upper_body.joints[1] = 'waist_pitch_joint': listed twice");
}

TEST(UpperBody, ConfigNamesTheFieldAndRange) {
  UpperBodyConfig c;
  EXPECT_EQ(c.validate(), "");
  c.damping = -1;
  EXPECT_NE(c.validate().find("upper_body.damping = -1: expected 0..50"), std::string::npos) << c.validate();
  c = UpperBodyConfig{};
  c.gravity_scale = std::nan("");
  EXPECT_NE(c.validate().find("upper_body.gravity_scale"), std::string::npos);
  c = UpperBodyConfig{};
  c.max_torque = 0.0;
  EXPECT_NE(c.validate().find("upper_body.max_torque"), std::string::npos);
  c = UpperBodyConfig{};
  c.ramp_s = 11.0;
  EXPECT_NE(c.validate().find("upper_body.ramp_s = 11: expected 0..10 s"), std::string::npos) << c.validate();
  c = UpperBodyConfig{};
  c.enabled = true;
  c.joints.clear();
  EXPECT_NE(c.validate().find("upper_body.joints"), std::string::npos);
}

TEST(UpperBody, ControllerConfigRefusesUnknownKeys) {
  std::string text = test::readTextFile(test::sourcePath("config/controller/g1_sil_teleop.yaml"));
  // Its relative paths made absolute, so that a copy loads from a temporary folder.
  for (std::size_t at = text.find("../"); at != std::string::npos; at = text.find("../", at))
    text.replace(at, 3, test::sourcePath("config") + "/");
  const auto at = text.find("upper_body:");
  ASSERT_NE(at, std::string::npos) << "the teleop config has an upper_body: section";
  std::string bad = text;
  bad.insert(text.find('\n', at) + 1, "  dampin: 3.0\n");
  test::TempDir dir;
  const std::string path = dir.write("g1_sil_teleop.yaml", bad);
  try {
    loadControllerConfig(path);
    ADD_FAILURE() << "an unknown key was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("dampin"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg
