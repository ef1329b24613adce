// Clip validation (src/clips/clip_validation.cpp): the file reader and the generator refuse the
// same clips with the same message, and a robot config that does not match its URDF is named as
// the culprit instead of the clip file that exposed it.
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/clips/clip_validation.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace {

using namespace pmg;

/// The message of what @p f throws as a ClipFormatError, "" if it throws nothing.
std::string clipError(const std::function<void()>& f) {
  try {
    f();
  } catch (const ClipFormatError& e) {
    return e.what();
  }
  return "";
}

TEST(ClipValidation, TheGeneratorAndTheFileReaderRefuseTheSameClips) {
  const RobotConfig& robot = test::g1Robot();
  const GeneratorJointSpace js = generatorJointSpace(robot);
  const DynamicClip good = readDynamicClip(test::g1ClipPath("walk_forward"), robot);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::string, std::function<void(DynamicClip&)>>> cases = {
      {"qd: is 3x29", [](DynamicClip& c) { c.qd.conservativeResize(3, Eigen::NoChange); }},
      {"contact.left.sigma: = 0.7", [](DynamicClip& c) { c.contact[0].sigma = 0.7; }},
      {"contact.right.mu: = 1", [](DynamicClip& c) { c.contact[1].mu = 1.0; }},
      {"period: = 0", [](DynamicClip& c) { c.period = 0.0; }},
      {"period: = 11", [](DynamicClip& c) { c.period = 11.0; }},
      {"nominal_scale: = -1", [](DynamicClip& c) { c.nominal_scale = -1.0; }},
      {"direction: = 2", [](DynamicClip& c) { c.direction = 2; }},
      {"base_height[4]: = 0", [](DynamicClip& c) { c.base_height[4] = 0.0; }},
      {"q[2][5]: = 0.300000: expected within joint limits [-0.2618, 0.2618] of left_ankle_roll_joint",
       [](DynamicClip& c) { c.q(2, 5) = 0.3; }},
      {"v_base[1][2]: expected a finite number", [nan](DynamicClip& c) { c.v_base(1, 2) = nan; }},
      {"metadata.provenance: = 'made_up'", [](DynamicClip& c) { c.meta.provenance = "made_up"; }},
      {"metadata.frame_begin/frame_end: = 5/2", [](DynamicClip& c) { c.meta.frame_begin = 5, c.meta.frame_end = 2; }},
      {"joint_names[3]: = 'left_knee_jnt': expected 'left_knee_joint'",
       [](DynamicClip& c) { c.meta.joint_names[3] = "left_knee_jnt"; }},
  };
  for (const auto& [expected, mutate] : cases) {
    SCOPED_TRACE(expected);
    DynamicClip bad = good;
    mutate(bad);
    const std::string from_file = clipError([&] { validateClip(bad, robot, "walk.yaml"); });
    EXPECT_EQ(from_file.rfind("walk.yaml: " + expected, 0), 0u) << from_file;
    ClipLibrary lib;
    lib.dynamic_clips.push_back(bad);
    const std::string from_generator = clipError([&] { GeneratorModel model(lib, js); });
    EXPECT_EQ(from_generator.rfind("clip 'walk_forward': " + expected, 0), 0u) << from_generator;
    // Same text after the source.
    EXPECT_EQ(from_file.substr(from_file.find(": ") + 2), from_generator.substr(from_generator.find(": ") + 2));
  }
  const StaticClip squat = readStaticClip(test::g1ClipPath("squat"), robot);
  StaticClip bad = squat;
  bad.values[3] = bad.values[2];
  EXPECT_EQ(clipError([&] { validateClip(bad, robot, "squat.yaml"); }).rfind("squat.yaml: values[3]: ", 0), 0u);
  ClipLibrary lib;
  lib.static_clips.push_back(bad);
  EXPECT_EQ(clipError([&] { GeneratorModel model(lib, js); }).rfind("static clip 'squat': values[3]: ", 0), 0u);
  bad = squat;
  bad.neutral = 2.0;
  EXPECT_EQ(clipError([&] { validateClip(bad, robot, "squat.yaml"); }).rfind("squat.yaml: neutral: = 2: expected within", 0),
            0u);
}

TEST(ClipValidation, JointNamesAreRequiredInFilesAndOptionalInMemory) {
  const RobotConfig& robot = test::g1Robot();
  DynamicClip c = readDynamicClip(test::g1ClipPath("walk_forward"), robot);
  c.meta.joint_names.clear();
  EXPECT_EQ(clipError([&] { validateClip(c, robot, "w.yaml"); }),
            "w.yaml: joint_names: has 0 names: expected 29 (joints of robot config " + robot.source_file + ")");
  ClipValidationOptions in_memory;
  in_memory.require_joint_names = false;
  EXPECT_EQ(clipError([&] { validateClip(c, robot, "w", in_memory); }), "");
  in_memory.limit_tolerance = -1.0;
  EXPECT_NE(clipError([&] { validateClip(c, robot, "w", in_memory); }).find("limit_tolerance"), std::string::npos);
}

// Issue 11: "a joint missing from the URDF is blamed on a clip file". A robot config whose joint is
// not in its URDF made every clip file fail with "joint_names[3]: = 'left_knee_joint': expected
// 'left_knee_jointx'", although the clip is right and the config is wrong.
TEST(ClipValidation, AJointMissingFromTheUrdfIsBlamedOnTheRobotConfig) {
  RobotConfig robot = test::g1Robot();
  const int knee = robot.jointIndex("left_knee_joint");
  ASSERT_GE(knee, 0);
  robot.joints[static_cast<std::size_t>(knee)].name = "left_knee_jointx";
  robot.joints[static_cast<std::size_t>(robot.jointIndex("right_knee_joint"))].mirror = "left_knee_jointx";
  const std::string clip_file = test::g1ClipPath("walk_forward");
  for (const auto& read : std::vector<std::function<void()>>{
           [&] { readDynamicClip(clip_file, robot); }, [&] { loadClipLibrary(test::g1ClipDir(), robot); }}) {
    try {
      read();
      FAIL() << "accepted a robot config whose joint is not in the URDF";
    } catch (const ClipFormatError& e) {
      FAIL() << "blamed on the clip: " << e.what();
    } catch (const ConfigError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(robot.source_file + ": joint 'left_knee_jointx' is not a moving joint of URDF " + robot.urdf_path, 0),
                0u)
          << msg;
      EXPECT_NE(msg.find("the robot config does not match its URDF"), std::string::npos) << msg;
      EXPECT_NE(msg.find("is not at fault: its joint_names[3] = 'left_knee_joint'"), std::string::npos) << msg;
    }
  }
  // A clip that really names a joint the robot lacks is still the clip's error.
  const RobotConfig& good = test::g1Robot();
  DynamicClip c = readDynamicClip(clip_file, good);
  c.meta.joint_names[3] = "left_knee_jointx";
  EXPECT_EQ(clipError([&] { validateClip(c, good, "w.yaml"); }).rfind("w.yaml: joint_names[3]: = 'left_knee_jointx'", 0), 0u);
}

}  // namespace
