// VR teleoperation through the product path (ControllerApp: shaper, generator, GCO, policy,
// supervisor, MuJoCo 2.2 SIL) with config/controller/g1_sil_teleop.yaml, the stream fed as the
// LCM receiver would: a headset walk makes the robot walk that way; a dropped stream stops the
// robot and its arms settle back onto the PMG reference; the tick allocates nothing.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace pmg {
namespace {

using teleop::ArmMode;
using teleop::kLeftHand;
using teleop::kRightHand;

ControllerConfig teleopConfig() {
  ControllerConfig c = loadControllerConfig(test::sourcePath("config/controller/g1_sil_teleop.yaml"));
  c.makeOffline();
  return c;
}

teleop::VrSample operatorAt(double x, double y, double z = 1.6, double yaw = 0.0) {
  teleop::VrSample s;
  s.head_position = {x, y, z};
  s.head_quat = {std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)};
  s.hand_valid = {true, true};
  // Hands in front of the chest, relative to the head.
  s.hand_position = {{{x + 0.30, y + 0.20, z - 0.45}, {x + 0.30, y - 0.20, z - 0.45}}};
  return s;
}

// Drives the app in lockstep, tick by tick, with the VR stream as the LCM source writes it.
class Session {
 public:
  explicit Session(ControllerApp& app) : app_(app) {}
  void tick(const teleop::VrSample& vr, bool stream = true) {
    const double now = static_cast<double>(ticks_) * 0.01;
    if (stream) {
      sample_.vr = vr;
      sample_.vr_time = now;
    }
    app_.stepLockstep(sample_);
    ++ticks_;
    min_height_ = std::min(min_height_, base()[2]);
  }
  void run(const teleop::VrSample& vr, double seconds, bool stream = true) {
    for (int k = 0; k < static_cast<int>(std::lround(seconds / 0.01)); ++k) tick(vr, stream);
  }
  void pressA(teleop::VrSample vr) {
    vr.buttons[kRightHand] |= teleop::kVrButtonLower;
    run(vr, 0.05);
    vr.buttons[kRightHand] = 0;
    run(vr, 0.05);
  }
  std::array<double, 3> base() const { return app_.controller().lastState().base_position; }
  double minHeight() const { return min_height_; }

 private:
  ControllerApp& app_;
  CommandSample sample_;
  long ticks_ = 0;
  double min_height_ = 10.0;
};

TEST(TeleopSil, HeadsetWalkMovesTheRobotThatWay) {
  ControllerApp app(teleopConfig());
  ASSERT_NE(app.controller().teleop(), nullptr);
  Session s(app);
  s.run(operatorAt(0, 0), 1.0);  // stand up, engage the actor; teleop not engaged yet
  ASSERT_EQ(app.controller().mode(), Mode::kActive);
  s.pressA(operatorAt(0, 0));
  ASSERT_TRUE(app.controller().teleop()->status().engaged);
  // The operator steps 0.3 m forward and stays there: the robot walks forward.
  const auto p0 = s.base();
  s.run(operatorAt(0.30, 0.0), 4.0);
  const auto p1 = s.base();
  // Back to the origin (robot stops), then 0.25 m to the left: the robot walks left.
  s.run(operatorAt(0.0, 0.0), 2.0);
  const auto p2 = s.base();
  s.run(operatorAt(0.0, 0.25), 4.0);
  const auto p3 = s.base();
  std::printf("[ SIL ] headset +0.30 m x for 4 s: robot moved (%.2f, %.2f) m; headset +0.25 m y for 4 s: (%.2f, %.2f) m\n",
              p1[0] - p0[0], p1[1] - p0[1], p3[0] - p2[0], p3[1] - p2[1]);
  EXPECT_GT(p1[0] - p0[0], 0.6) << "forward";
  EXPECT_LT(std::fabs(p1[1] - p0[1]), 0.5 * (p1[0] - p0[0]));
  EXPECT_GT(p3[1] - p2[1], 0.25) << "left";
  EXPECT_LT(std::fabs(p3[0] - p2[0]), 0.6 * (p3[1] - p2[1]));
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
  EXPECT_GT(s.minHeight(), 0.6) << "the robot fell";
}

TEST(TeleopSil, DroppedStreamStopsTheRobotAndItsArmsSettle) {
  ControllerApp app(teleopConfig());
  const ControllerConfig& config = app.config();
  Session s(app);
  s.run(operatorAt(0, 0), 1.0);
  s.pressA(operatorAt(0, 0));
  // Walk forward with both grips held and both hands forward at chest height, as when carrying
  // (the teleop policy was trained with such arm motion; docs/teleop.md, "Limits").
  const teleop::TeleopMode& tm = *app.controller().teleop();
  teleop::VrSample vr = operatorAt(0.3, 0.0);
  vr.grip = {1.0, 1.0};
  vr.hand_position = {{{0.3 + 0.45, 0.20, 1.6 - 0.45}, {0.3 + 0.45, -0.20, 1.6 - 0.45}}};
  s.run(vr, 1.5);
  ASSERT_EQ(tm.status().arm[kLeftHand], ArmMode::kFollowing);
  ASSERT_EQ(tm.status().arm[kRightHand], ArmMode::kFollowing);
  // Measure the tick's allocations while the arms follow.
  {
    test::AllocationGuard guard(test::AllocationScope::kThisThread);
    s.run(vr, 0.5);
    EXPECT_EQ(guard.count(), 0u) << "the teleop tick allocated";
  }
  // The stream drops.
  const auto before = s.base();
  // Zero within the stale timeout (0.25 s) plus the shaper's deceleration (0.375 m/s at 1 m/s²).
  s.run(vr, 0.7, false);
  EXPECT_EQ(app.controller().commands().vector()[0], 0.0) << "velocity command not zero 0.7 s after the drop";
  s.run(vr, 3.0, false);
  const auto p_a = s.base();
  s.run(vr, 1.0, false);
  const auto p_b = s.base();
  EXPECT_FALSE(tm.status().engaged);
  EXPECT_EQ(tm.status().arm[kLeftHand], ArmMode::kPmg);
  EXPECT_EQ(tm.status().arm[kRightHand], ArmMode::kPmg);
  EXPECT_LT(std::hypot(p_b[0] - p_a[0], p_b[1] - p_a[1]), 0.06) << "the robot still walks 3.5 s after the drop";
  // The arms settled: references on PMG's, joints at rest near them.
  const LowState& st = app.controller().lastState();
  for (int h = 0; h < 2; ++h) {
    for (int j : tm.ik().jointIndices(h)) {
      const auto k = static_cast<std::size_t>(j);
      EXPECT_LT(std::fabs(st.motors[k].qd), 0.3) << config.robot.joints[k].name;
      EXPECT_LT(std::fabs(st.motors[k].q - app.controller().reference()[k]), 0.1) << config.robot.joints[k].name;
    }
  }
  const std::string summary = app.finish().text();
  EXPECT_NE(summary.find("VR teleop: engaged 1 times; stream went stale while engaged 1 times"), std::string::npos) << summary;
  std::printf("[ SIL ] stream dropped: robot moved %.2f m before stopping\n", std::hypot(p_a[0] - before[0], p_a[1] - before[1]));
  EXPECT_EQ(app.controller().fault(), FaultCode::kNone);
  EXPECT_GT(s.minHeight(), 0.6) << "the robot fell";
}

// Crouched 0.18 m and bent (looking down 0.70 rad: torso pitch 0.36 rad) with both hands forward
// and low, as the box operator grips: the upper body's weight bends the waist pitch beyond its
// reference. The teleop config's upper_body feed-forward (include/pmg/controller/upper_body.hpp)
// takes that error out. Without it, the actor before (g1_table2_baseline.onnx, trained without the
// feed-forward: the shipped one is refused there, TeleopSil.TheShippedActorNeedsTheFeedForward).
// Returns the waist pitch error q - q_ref [rad] over the last 2 s of 4 s: mean, and the largest
// measured waist pitch.
struct WaistPitch {
  double mean_error = 0.0, max_q = -10.0, min_height = 10.0;
};
WaistPitch crouchedWithArmsForward(bool upper_body) {
  ControllerConfig c = teleopConfig();
  EXPECT_EQ(c.upper_body.joints.size(), 3u) << "the teleop config's upper_body: the three waist joints";
  EXPECT_TRUE(c.upper_body.enabled) << "the teleop config ships the feed-forward on";
  c.upper_body.enabled = upper_body;
  if (!upper_body) c.policy_file = test::sourcePath("config/policies/g1_table2_baseline.onnx");
  ControllerApp app(c);
  EXPECT_EQ(app.controller().upperBody() != nullptr, upper_body);
  Session s(app);
  s.run(operatorAt(0, 0), 1.0);
  s.pressA(operatorAt(0, 0));
  // As the box operator does: the hands forward first, then crouch and bend in place.
  teleop::VrSample vr = operatorAt(0, 0);
  vr.grip = {1.0, 1.0};
  vr.hand_position = {{{0.40, 0.18, 1.6 - 0.45}, {0.40, -0.18, 1.6 - 0.45}}};
  s.run(vr, 1.5);
  const double head_z = 1.6 - 0.18, look_down = 0.70;
  vr = operatorAt(0, 0, head_z);
  vr.head_quat = {std::cos(look_down / 2), 0, std::sin(look_down / 2), 0};
  vr.grip = {1.0, 1.0};
  vr.hand_position = {{{0.40, 0.18, head_z - 0.45}, {0.40, -0.18, head_z - 0.45}}};
  s.run(vr, 3.0);
  const int pitch = c.robot.jointIndex("waist_pitch_joint");
  WaistPitch w;
  int n = 0;
  for (int k = 0; k < 200; ++k) {
    s.tick(vr);
    const double q = app.controller().lastState().motors[static_cast<std::size_t>(pitch)].q;
    w.mean_error += q - app.controller().reference()[static_cast<std::size_t>(pitch)];
    w.max_q = std::max(w.max_q, q);
    ++n;
  }
  w.mean_error /= n;
  w.min_height = s.minHeight();
  EXPECT_EQ(app.controller().mode(), Mode::kActive);
  return w;
}

TEST(TeleopSil, UpperBodyFeedForwardHoldsTheWaistUnderTheArms) {
  const WaistPitch off = crouchedWithArmsForward(false);
  const WaistPitch on = crouchedWithArmsForward(true);
  std::printf("waist pitch error (q - q_ref), crouched and bent, arms forward: off %.3f rad (largest q %.3f), on %.3f rad (largest q %.3f)\n",
              off.mean_error, off.max_q, on.mean_error, on.max_q);
  EXPECT_GT(off.mean_error, 0.08) << "without the feed-forward the waist should sag (the case this stage is for)";
  EXPECT_LT(std::fabs(on.mean_error), 0.03);
  EXPECT_LT(on.max_q, off.max_q - 0.05);
  EXPECT_GT(on.min_height, 0.5) << "the robot fell";
  EXPECT_GT(off.min_height, 0.5) << "the robot fell";
}

// The shipped teleop actor was trained with the waist feed-forward (its contract's pmg.upper_body_ff):
// the controller refuses to run it without, naming the key.
TEST(TeleopSil, TheShippedActorNeedsTheFeedForward) {
  ControllerConfig c = teleopConfig();
  c.upper_body.enabled = false;
  try {
    ControllerApp app(c);
    FAIL() << "ran the actor trained with the waist feed-forward without it";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("pmg.upper_body_ff"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg
