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

}  // namespace
