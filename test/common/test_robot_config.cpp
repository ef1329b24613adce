// Robot config loading and validation: the shipped G1 config is valid and agrees with the URDF;
// every class of bad input is refused with an error naming file, key and expected range.
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "pmg/common/robot_config.hpp"

namespace pmg {
namespace {

const char* kConfig = "config/robots/g1/g1.yaml";

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Writes a modified copy of the shipped config next to it (so relative model paths resolve).
std::string writeVariant(const std::string& text, const std::string& name) {
  const std::string path = "config/robots/g1/.test_" + name + ".yaml";
  std::ofstream(path) << text;
  return path;
}

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
  const std::string text =
      std::regex_replace(readFile(kConfig), std::regex(bad.pattern), bad.replacement, std::regex_constants::format_first_only);
  const std::string path = writeVariant(text, bad.name);
  try {
    loadRobotConfig(path);
    FAIL() << "accepted a config with " << bad.name;
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(bad.expected), std::string::npos) << msg;
  }
  std::filesystem::remove(path);
}

INSTANTIATE_TEST_SUITE_P(
    BadInputs, RobotConfigRejects,
    ::testing::Values(BadCase{"negative_kp", "kp: 150", "kp: -3", "joints[0] (left_hip_pitch_joint).kp"},
                      BadCase{"limits_swapped", "lower: -2.5307, upper: 2.8798", "lower: 2.9, upper: 2.8798",
                              "expected lower < upper"},
                      BadCase{"default_outside", "default: 0.3", "default: 9", "left_knee_joint).default"},
                      BadCase{"bad_bus", "bus: 0", "bus: 17", ".bus"},
                      BadCase{"duplicate_motor", "motor_id: 2,", "motor_id: 1,", "duplicate id on bus 0"},
                      BadCase{"broken_mirror", "mirror: right_hip_roll_joint", "mirror: right_knee_joint",
                              "expected a pairwise map"},
                      BadCase{"missing_key", "torque_limit: 88, ", "", "joints[0].torque_limit: missing"},
                      BadCase{"not_a_number", "kd: 4,", "kd: fast,", "joints[0].kd: cannot read"},
                      BadCase{"missing_urdf", "urdf: g1_29dof_rev_1_0.urdf", "urdf: nope.urdf", "robot.urdf"},
                      BadCase{"syntax", "joints:", "joints: [", "YAML syntax error"}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace pmg
