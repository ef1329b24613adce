// The scripted VR operator (vr_script.hpp): keyframes interpolate and hold, buttons and grips hold
// per step, a dropped stream sends nothing, the shipped script loads, bad scripts are named errors.
#include <cmath>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/teleop/vr_script.hpp"
#include "temp_dir.hpp"

namespace pmg::teleop {
namespace {

TEST(VrScript, KeyframesInterpolateButtonsHoldAndTheStreamDrops) {
  test::TempDir dir;
  const std::string path = dir.write("s.yaml", R"(rate_hz: 50
steps:
  - {t: 0.0, head: [0, 0, 1.6], yaw: 0.0, left_hand: [0.1, 0.3, -0.7], right_hand: [0.1, -0.3, -0.7]}
  - {t: 1.0, buttons_right: [lower], grip: [1, 0]}
  - {t: 2.0, head: [0.4, 0, 1.6], yaw: 0.5}
  - {t: 3.0, stream: false}
)");
  const VrScript s = loadVrScript(path);
  EXPECT_DOUBLE_EQ(s.end(), 4.0);
  VrSample v;
  ASSERT_TRUE(s.sample(0.5, 1, v));
  EXPECT_EQ(v.buttons[kRightHand], 0u);
  EXPECT_NEAR(v.head_position[0], 0.0, 1e-12);  // the head moves only during the step before its keyframe
  ASSERT_TRUE(s.sample(1.5, 2, v));
  EXPECT_EQ(v.buttons[kRightHand], static_cast<std::uint32_t>(kVrButtonLower));
  EXPECT_EQ(v.grip[kLeftHand], 1.0);
  EXPECT_EQ(v.grip[kRightHand], 0.0);
  EXPECT_NEAR(v.head_position[0], 0.2, 1e-12);  // halfway between the keyframes at 1.0 and 2.0 s
  ASSERT_TRUE(s.sample(2.5, 3, v));
  EXPECT_NEAR(v.head_position[0], 0.4, 1e-12);
  EXPECT_EQ(v.grip[kLeftHand], 0.0) << "grips hold only during their step";
  // Yaw 0.5 rad: the hands turn with the head, around it.
  const double yaw = std::atan2(2 * (v.head_quat[0] * v.head_quat[3] + v.head_quat[1] * v.head_quat[2]),
                                1 - 2 * (v.head_quat[2] * v.head_quat[2] + v.head_quat[3] * v.head_quat[3]));
  EXPECT_NEAR(yaw, 0.5, 1e-9);
  const double dx = v.hand_position[kLeftHand][0] - v.head_position[0], dy = v.hand_position[kLeftHand][1] - v.head_position[1];
  EXPECT_NEAR(dx, 0.1 * std::cos(0.5) - 0.3 * std::sin(0.5), 1e-9);
  EXPECT_NEAR(dy, 0.1 * std::sin(0.5) + 0.3 * std::cos(0.5), 1e-9);
  for (const auto& q : {v.head_quat, v.hand_quat[0], v.hand_quat[1]})
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-12);
  EXPECT_FALSE(s.sample(3.5, 4, v)) << "stream: false sends nothing";
}

TEST(VrScript, TheShippedWalkScriptLoads) {
  const VrScript s = loadVrScript(test::sourcePath("config/teleop/vr_walk_script.yaml"));
  EXPECT_GT(s.steps.size(), 5u);
  VrSample v;
  EXPECT_TRUE(s.sample(0.0, 0, v));
  EXPECT_FALSE(s.sample(s.end() - 0.1, 1, v)) << "the script ends with the stream dropped";
}

TEST(VrScript, BadScriptsAreNamedErrors) {
  test::TempDir dir;
  const auto expectError = [&](const std::string& text, const std::string& what) {
    const std::string path = dir.write("bad.yaml", text);
    try {
      (void)loadVrScript(path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectError("steps:\n  - {t: 0.0, heed: [0, 0, 1.6]}\n", "heed");
  expectError("steps:\n  - {t: 1.0}\n  - {t: 0.5}\n", "strictly increasing");
  expectError("steps:\n  - {t: 0.0, grip: [2, 0]}\n", "grip");
  expectError("steps:\n  - {t: 0.0, buttons_right: [trigger]}\n", "trigger");
  expectError("rate_hz: 0\nsteps:\n  - {t: 0.0}\n", "rate_hz");
  expectError("steps:\n  - {t: 0.0, left_hand: [3, 0, 0]}\n", "1.5 m");
  expectError("steps: []\n", "steps");
}

}  // namespace
}  // namespace pmg::teleop
