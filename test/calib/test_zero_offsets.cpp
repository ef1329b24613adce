// Calibrated zero offsets in the robot config (`zero_offsets:`) and their application around a HAL
// backend (pmg::ZeroOffsetBackend): parsing, errors naming file and joint, and the SIL with hidden
// encoder offsets reporting true angles once the matching offsets are configured.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/zero_offset_backend.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

/// Copy of the G1 config (absolute model paths) with @p extra appended, in @p dir.
std::string configWith(const test::TempDir& dir, const std::string& extra, const std::string& name) {
  return dir.write(name + ".yaml", test::g1RobotConfigText() + "\n" + extra);
}

TEST(ZeroOffsets, RobotConfigReadsMapAndResultFile) {
  const test::TempDir dir;
  const RobotConfig plain = loadRobotConfig(test::g1RobotConfigPath());
  EXPECT_EQ(plain.zeroOffsets().cwiseAbs().maxCoeff(), 0.0);
  const RobotConfig c =
      loadRobotConfig(configWith(dir, "zero_offsets: {left_knee_joint: 0.021, right_hip_roll_joint: -0.013}\n", "zmap"));
  EXPECT_DOUBLE_EQ(c.joints[static_cast<std::size_t>(c.jointIndex("left_knee_joint"))].zero_offset, 0.021);
  EXPECT_DOUBLE_EQ(c.zeroOffsets()(c.jointIndex("right_hip_roll_joint")), -0.013);
  EXPECT_EQ(c.zeroOffsets()(c.jointIndex("left_knee_joint") + 1), 0.0);
  // The --out file of pmg_calib_zero, by path relative to the config.
  dir.write("zres.yaml", "zero_offsets:\n  left_ankle_pitch_joint: 0.0042\ncalibration: {converged: true}\n");
  const RobotConfig f = loadRobotConfig(configWith(dir, "zero_offsets: zres.yaml\n", "zfile"));
  EXPECT_DOUBLE_EQ(f.zeroOffsets()(f.jointIndex("left_ankle_pitch_joint")), 0.0042);
}

TEST(ZeroOffsets, BadEntriesNameFileAndJoint) {
  const test::TempDir dir;
  const auto expectError = [&dir](const std::string& extra, const std::string& name, const std::string& needle) {
    try {
      loadRobotConfig(configWith(dir, extra, name));
      FAIL() << "expected ConfigError for " << extra;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expectError("zero_offsets: {left_elbow_jint: 0.01}\n", "zbad1",
              "zero_offsets: 'left_elbow_jint' is not a joint of");
  expectError("zero_offsets: {left_elbow_jint: 0.01}\n", "zbad1b", "(did you mean 'left_elbow_joint'?)");
  expectError("zero_offsets: {left_knee_joint: 0.9}\n", "zbad2", "|offset| <= 0.5 rad");
  expectError("zero_offsets: {left_knee_joint: abc}\n", "zbad3",
              "zero_offsets.left_knee_joint: expected a finite number, got 'abc'");
  expectError("zero_offsets: {left_knee_joint: .nan}\n", "zbad3b",
              "zero_offsets.left_knee_joint: expected a finite number, got '.nan'");
  expectError("zero_offsets: missing_file.yaml\n", "zbad4", "missing_file.yaml: cannot open file");
  // A pmg_calib_zero result file with a misspelt key.
  dir.write("ztypo.yaml", "zero_offsets:\n  left_knee_joint: 0.01\ncalibraton: {converged: true}\n");
  expectError("zero_offsets: ztypo.yaml\n", "zbad5", "ztypo.yaml:3: unknown key 'calibraton' at the top level (did you mean 'calibration'?)");
}

TEST(ZeroOffsets, BackendReportsTrueAnglesAndHoldsTrueTargets) {
  const RobotConfig& robot = test::g1Robot();
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  Eigen::VectorXd hidden = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < 12; ++i) hidden(i) = 0.04 * std::sin(1.7 * static_cast<double>(i) + 0.3);
  MujocoBackendOptions bo;  // in the gantry
  bo.encoder_offsets.assign(hidden.data(), hidden.data() + n);
  auto sim = std::make_unique<MujocoBackend>(robot, bo);
  MujocoBackend* raw = sim.get();
  ZeroOffsetBackend backend(std::move(sim), hidden);
  LowCommand cmd;
  LowState st;
  cmd.num_motors = static_cast<int>(n);
  const Eigen::VectorXd q0 = robot.defaultPose(), kp = robot.kp(), kd = robot.kd();
  for (Eigen::Index i = 0; i < n; ++i) cmd.motors[static_cast<std::size_t>(i)] = {q0(i), 0.0, kp(i), kd(i), 0.0};
  for (int c = 0; c < 500; ++c) ASSERT_EQ(backend.exchange(cmd, st), BackendStatus::kOk);
  // Reference: the same commands on a robot without hidden offsets and without the wrapper.
  MujocoBackend ref(robot, MujocoBackendOptions{});
  LowState st_ref;
  for (int c = 0; c < 500; ++c) ASSERT_EQ(ref.exchange(cmd, st_ref), BackendStatus::kOk);
  // Same physics (targets held in true angles), same reported angles (true ones, not true + hidden).
  for (int i = 0; i < raw->model()->nq; ++i) EXPECT_NEAR(raw->data()->qpos[i], ref.data()->qpos[i], 1e-9) << "qpos " << i;
  for (Eigen::Index i = 0; i < n; ++i)
    EXPECT_NEAR(st.motors[static_cast<std::size_t>(i)].q, st_ref.motors[static_cast<std::size_t>(i)].q, 1e-9)
        << robot.joints[static_cast<std::size_t>(i)].name << " hidden offset " << hidden(i);
  // Without the wrapper the hidden offsets show in the readings.
  EXPECT_GT(std::abs(hidden(3)), 0.01);
  EXPECT_THROW(ZeroOffsetBackend(nullptr, hidden), std::invalid_argument);
}

}  // namespace
}  // namespace pmg
