// Robot config loading and validation: the shipped G1 config is valid and agrees with the URDF;
// every class of bad input is refused with an error naming file, key and expected range.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

const std::string kConfig = test::g1RobotConfigPath();

TEST(RobotConfig, ShippedG1ConfigLoadsWith29Joints) {
  const RobotConfig c = loadRobotConfig(kConfig);
  EXPECT_EQ(c.numJoints(), 29u);
  EXPECT_EQ(c.joints.front().name, "left_hip_pitch_joint");
  EXPECT_EQ(c.joints.back().name, "right_wrist_yaw_joint");
  EXPECT_EQ(c.mirrorIndex()[0], 6);  // left hip pitch <-> right hip pitch
}

TEST(RobotConfig, LimitsMatchTheUrdf) {
  const RobotConfig c = loadRobotConfig(kConfig);
  const auto urdf = urdf::parseURDFFile(c.urdf_path);
  ASSERT_TRUE(urdf);
  for (const auto& j : c.joints) {
    const auto uj = urdf->getJoint(j.name);
    ASSERT_TRUE(uj) << j.name;
    ASSERT_TRUE(uj->limits) << j.name;
    EXPECT_NEAR(j.lower, uj->limits->lower, 1e-5) << j.name;
    EXPECT_NEAR(j.upper, uj->limits->upper, 1e-5) << j.name;
    EXPECT_NEAR(j.torque_limit, uj->limits->effort, 1e-9) << j.name;
    EXPECT_NEAR(j.velocity_limit, uj->limits->velocity, 1e-9) << j.name;
  }
}

struct BadCase {
  const char* name;
  const char* pattern;      // regex applied to the shipped text
  const char* replacement;
  const char* expected;     // substring of the error message
};

class RobotConfigRejects : public ::testing::TestWithParam<BadCase> {};

TEST_P(RobotConfigRejects, NamesFileKeyAndRange) {
  const BadCase& bad = GetParam();
  // A modified copy of the shipped config (model paths made absolute) in a per-test folder.
  const std::string text = std::regex_replace(test::g1RobotConfigText(), std::regex(bad.pattern), bad.replacement,
                                              std::regex_constants::format_first_only);
  const test::TempDir dir;
  const std::string path = dir.write(std::string(bad.name) + ".yaml", text);
  try {
    loadRobotConfig(path);
    FAIL() << "accepted a config with " << bad.name;
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(bad.expected), std::string::npos) << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(
    BadInputs, RobotConfigRejects,
    ::testing::Values(BadCase{"negative_kp", "kp: 150", "kp: -3", "joints[0] (left_hip_pitch_joint).kp"},
                      BadCase{"limits_swapped", "lower: -2.5307, upper: 2.8798", "lower: 2.9, upper: 2.8798",
                              "expected lower < upper"},
                      BadCase{"default_outside", "default: 0.3", "default: 9", "left_knee_joint).default"},
                      BadCase{"bad_bus", "bus: can0", "bus: [can0]", "joints[0].bus: expected a string, got a list"},
                      BadCase{"bad_motor_id", "motor_id: 1,", "motor_id: 300,",
                              "(left_hip_pitch_joint).motor_id = 300: expected 1..254"},
                      BadCase{"duplicate_motor", "motor_id: 2,", "motor_id: 1,", "duplicate id on bus can0"},
                      BadCase{"broken_mirror", "mirror: right_hip_roll_joint", "mirror: right_knee_joint",
                              "expected a pairwise map"},
                      BadCase{"missing_key", "torque_limit: 88, ", "",
                              "joints[0]: missing required key 'torque_limit'"},
                      BadCase{"not_a_number", "kd: 4,", "kd: fast,",
                              "joints[0].kd: expected a finite number, got 'fast'"},
                      BadCase{"infinite_limit", "velocity_limit: 32", "velocity_limit: .inf",
                              "joints[0].velocity_limit: expected a finite number, got '.inf'"},
                      BadCase{"typo_in_joint", "mirror_sign: -1\\}", "mirror_sigm: -1}",
                              "unknown key 'mirror_sigm' in 'joints[1]' (did you mean 'mirror_sign'?)"},
                      BadCase{"typo_in_robot", "standing_base_height:", "standing_base_heigth:",
                              "unknown key 'standing_base_heigth' in 'robot' (did you mean 'standing_base_height'?)"},
                      BadCase{"typo_at_top", "joints:", "zero_offset: {}\njoints:",
                              "unknown key 'zero_offset' at the top level (did you mean 'zero_offsets'?)"},
                      BadCase{"unknown_zero_joint", "joints:", "zero_offsets: {left_kne_joint: 0.1}\njoints:",
                              "zero_offsets: 'left_kne_joint' is not a joint of"},
                      BadCase{"zero_offset_too_big", "joints:", "zero_offsets: {left_knee_joint: 0.7}\njoints:",
                              "zero_offsets.left_knee_joint: expected |offset| <= 0.5 rad, got 0.7"},
                      BadCase{"missing_urdf", "urdf: \\S*g1_29dof_rev_1_0.urdf", "urdf: nope.urdf", "robot.urdf"},
                      BadCase{"syntax", "joints:", "joints: [", "YAML syntax error"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

// A typo names the file and the line of the misspelt key, the key and the nearest valid key.
TEST(RobotConfig, TypoNamesFileLineKeyAndNearestKey) {
  std::string text = test::g1RobotConfigText();
  const std::size_t at = text.find("  imu_site:");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 11, "  imu_sites:");
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
  const test::TempDir dir;
  const std::string path = dir.write("typo.yaml", text);
  try {
    loadRobotConfig(path);
    FAIL() << "accepted a typo";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":" + std::to_string(line) +
                                         ": unknown key 'imu_sites' in 'robot' (did you mean 'imu_site'?)");
  }
}

TEST(RobotConfig, BusesAndMotorIdsAreNamed) {
  const RobotConfig c = loadRobotConfig(kConfig);
  EXPECT_EQ(c.joints[0].bus, "can0");
  EXPECT_EQ(c.joints[0].motor_id, 1);
  EXPECT_EQ(c.joints[6].bus, "can1");  // right hip pitch: first motor of the second leg bus
  EXPECT_EQ(c.joints[6].motor_id, 1);
}

// `actuator_uncertainty:` (pmg_calib_joints): read per joint, only for parameters the joint's block
// names, finite and >= 0; anything else is refused naming the file, the joint and the key.
TEST(RobotConfig, ActuatorUncertaintyBelongsToTheBlocksParameters) {
  auto withKnee = [](const std::string& extra) {
    return std::regex_replace(test::g1RobotConfigText(), std::regex("(mirror: right_knee_joint, mirror_sign: 1)\\}"),
                              "$1" + extra + "}", std::regex_constants::format_first_only);
  };
  const test::TempDir dir;
  const RobotConfig c = loadRobotConfig(
      dir.write("ok.yaml", withKnee(", actuator: {fc_Nm: 2.0, delay_s: 0.004}, actuator_uncertainty: {fc_Nm: 0.05, delay_s: 0.0002}")));
  const std::map<std::string, double> want{{"delay_s", 0.0002}, {"fc_Nm", 0.05}};
  EXPECT_EQ(c.joints[3].actuator_uncertainty, want);
  EXPECT_TRUE(c.joints[4].actuator_uncertainty.empty());
  const struct {
    const char* name;
    std::string extra;
    std::string message;
  } bad[] = {
      {"not_in_block", ", actuator: {fc_Nm: 2.0}, actuator_uncertainty: {fv_Nms_per_rad: 0.1}",
       "'fv_Nms_per_rad': not a parameter the joint's `actuator:` block names (expected one of its keys, e.g. 'fc_Nm')"},
      {"no_block", ", actuator_uncertainty: {fc_Nm: 0.1}", "(the joint has no actuator block)"},
      {"negative", ", actuator: {fc_Nm: 2.0}, actuator_uncertainty: {fc_Nm: -0.1}", "expected a finite value >= 0"},
  };
  for (const auto& b : bad) {
    const std::string path = dir.write(std::string(b.name) + ".yaml", withKnee(b.extra));
    try {
      loadRobotConfig(path);
      ADD_FAILURE() << b.name << ": accepted";
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find("actuator_uncertainty"), std::string::npos) << what;
      EXPECT_NE(what.find(b.message), std::string::npos) << b.name << ": " << what;
    }
  }
}

}  // namespace
}  // namespace pmg
