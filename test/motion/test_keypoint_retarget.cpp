// Optimisation-based retargeting recovers the joint angles of a synthetic motion generated from
// the robot's own forward kinematics (scale 1, targets = robot keypoints): |q − q_true| ≤ 0.01 rad
// on every observable joint (all but the wrists, which no keypoint sees).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/keypoint_retarget.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

TEST(KeypointRetarget, RecoversJointAnglesOfASyntheticRobotMotion) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const KinematicModel model(robot);
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  Eigen::VectorXd q0 = robot.defaultPose();
  q0(robot.jointIndex("left_elbow_joint")) = 0.5;
  q0(robot.jointIndex("right_elbow_joint")) = 0.5;
  // A smooth 1 s motion at 30 fps: every non-wrist joint oscillates about the default pose with
  // its own amplitude (0.1..0.35 rad) and phase; the base walks forward, sways and yaws. The
  // elbows stay bent by more than 0.8 rad (G1 elbow q = π/2 is a straight arm, where shoulder yaw
  // cannot be seen from keypoint positions).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> amp(0.1, 0.35), phase(0.0, 2 * M_PI);
  Eigen::VectorXd a(n), ph(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    a(j) = robot.joints[static_cast<std::size_t>(j)].name.find("wrist") == std::string::npos ? amp(rng) : 0.0;
    ph(j) = phase(rng);
  }
  const int F = 30;
  HumanMotion human;
  human.format = "synthetic";
  human.fps = 30.0;
  human.ankle_height = 0.0174;
  std::vector<Eigen::VectorXd> q_true;
  const Eigen::VectorXd lo = robot.lowerLimits(), hi = robot.upperLimits();
  for (int k = 0; k < F; ++k) {
    const double t = k / human.fps;
    Eigen::VectorXd q(n);
    for (Eigen::Index j = 0; j < n; ++j) q(j) = std::min(hi(j) - 0.02, std::max(lo(j) + 0.02, q0(j) + a(j) * std::sin(2 * M_PI * t + ph(j))));
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.linear() = (Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.05 * std::sin(6 * t), Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
    X_WB.translation() = Eigen::Vector3d(0.5 * t, 0.02 * std::sin(6 * t), 1.0);  // high: no ground contact
    human.frames.push_back(robotKeypoints(model, X_WB, q));
    q_true.push_back(q);
  }
  KeypointRetargetOptions opt;
  opt.scale = 1.0;
  opt.segment_directions = false;
  opt.contact_height = 1e-3;  // feet are in the air: no contact constraints
  const RetargetResult res = retargetKeypoints(human, model, opt);
  double worst = 0.0;
  std::string worst_joint;
  for (int k = 0; k < F; ++k)
    for (Eigen::Index j = 0; j < n; ++j) {
      const double e = std::abs(res.motion.q(k, j) - q_true[static_cast<std::size_t>(k)](j));
      if (e > worst) {
        worst = e;
        worst_joint = robot.joints[static_cast<std::size_t>(j)].name + " frame " + std::to_string(k);
      }
    }
  EXPECT_LE(worst, 0.01) << "worst joint " << worst_joint;
  const RetargetStats st = retargetStats(res, robot, 0, F);
  EXPECT_LT(st.keypoint_error_max, 0.005);
  EXPECT_EQ(st.joint_limit_violations, 0);
}


/// A G1 standing still in its default pose, as a "human" motion of @p frames at 30 fps (robot
/// keypoints, feet flat on the ground).
HumanMotion standingRobot(const KinematicModel& model, int frames) {
  HumanMotion human;
  human.format = "synthetic";
  human.fps = 30.0;
  human.ankle_height = 0.0174;  // ankle roll link origin above the sole
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = Eigen::Vector3d(0, 0, 0.7666);  // soles on z = 0
  for (int k = 0; k < frames; ++k) human.frames.push_back(robotKeypoints(model, X_WB, model.config().defaultPose()));
  return human;
}

// Hand-set contact spans replace the detected labels over their frames; a span outside the motion,
// empty, or with clearance on a contact span is refused with the span named.
TEST(KeypointRetarget, ContactOverridesReplaceTheDetectedLabels) {
  const KinematicModel model(pmg::test::g1Robot());
  const HumanMotion human = standingRobot(model, 10);
  KeypointRetargetOptions opt;
  const ContactSequence detected = detectHumanContacts(human, opt);
  for (const auto& c : detected) ASSERT_TRUE(c[0] && c[1]);  // standing: both feet down
  ContactOverride o;
  o.foot = Foot::kLeft;
  o.begin = 2;
  o.end = 5;
  o.contact = false;
  o.clearance = 0.03;
  opt.contact_overrides.push_back(o);
  const ContactSequence c = detectHumanContacts(human, opt);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(c[static_cast<std::size_t>(k)][0], k < 2 || k >= 5) << k;
    EXPECT_TRUE(c[static_cast<std::size_t>(k)][1]) << k;
  }
  auto refused = [&](const ContactOverride& bad, const char* what) {
    KeypointRetargetOptions b;
    b.contact_overrides = {o, bad};
    try {
      detectHumanContacts(human, b);
      ADD_FAILURE() << "expected std::invalid_argument for " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("contact_overrides[1]"), std::string::npos) << e.what();
    }
  };
  ContactOverride bad = o;
  bad.end = 11;
  refused(bad, "a span past the end");
  bad = o;
  bad.begin = bad.end;
  refused(bad, "an empty span");
  bad = o;
  bad.contact = true;
  refused(bad, "clearance on a contact span");
}

// A forced swing raises the foot by the clearance, and swing_blend makes the swing start at the
// stance it leaves and end at the one it reaches, instead of the foot snapping to the first swing
// target (here the foot is moved 5 cm forward for the swing and the stance after it).
TEST(KeypointRetarget, ForcedSwingWithClearanceAndBlendedEnds) {
  const KinematicModel model(pmg::test::g1Robot());
  HumanMotion human = standingRobot(model, 12);
  for (int k = 4; k < 12; ++k)
    for (Keypoint kp : {Keypoint::kLeftAnkle, Keypoint::kLeftToe}) human.frames[static_cast<std::size_t>(k)].p_WK[static_cast<std::size_t>(kp)].x() += 0.05;
  KeypointRetargetOptions opt;
  opt.scale = 1.0;
  opt.segment_directions = false;
  opt.level_pelvis = true;
  ContactOverride o;
  o.foot = Foot::kLeft;
  o.begin = 4;
  o.end = 7;
  o.contact = false;
  o.clearance = 0.04;
  opt.contact_overrides.push_back(o);
  const auto ankleTarget = [](const RetargetResult& r, int k) { return r.targets[static_cast<std::size_t>(k)][static_cast<std::size_t>(Keypoint::kLeftAnkle)]; };
  const RetargetResult sharp = retargetKeypoints(human, model, opt);
  opt.swing_blend = 0.1;  // 3 frames at 30 fps
  const RetargetResult blended = retargetKeypoints(human, model, opt);
  const double x_before = ankleTarget(sharp, 0).x(), x_after = ankleTarget(sharp, 11).x();
  ASSERT_NEAR(x_after - x_before, 0.05, 1e-9);
  EXPECT_NEAR(ankleTarget(sharp, 4).x(), x_after, 1e-9);               // snaps forward at lift-off
  EXPECT_LT(ankleTarget(blended, 4).x() - x_before, 0.5 * 0.05);        // leaves from the stance
  EXPECT_NEAR(ankleTarget(blended, 6).x(), x_after, 0.3 * 0.05);        // arrives at the next one
  // Clearance: sin(π (k − begin + ½) / 3) · 0.04 above the standing ankle target, at mid swing 0.04.
  EXPECT_NEAR(ankleTarget(sharp, 5).z() - ankleTarget(sharp, 0).z(), 0.04, 1e-9);
  // The robot foot follows: its sole leaves the ground in the swing and is back on it after.
  EXPECT_GT(blended.motion.p_WS[0](5, 2), 0.02);
  EXPECT_LT(std::abs(blended.motion.p_WS[0](10, 2)), 0.003);
}

}  // namespace
