// KDL leg chains of the G1: structure, symmetry and Jacobian vs. finite differences of FK.
#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "gco_test_util.hpp"
#include "pmg/common/robot_config.hpp"

namespace pmg::gco {
namespace {

TEST(LegModel, G1ChainsHaveTheSixLegJointsInOrder) {
  const auto legs = test::g1Legs();
  const std::array<std::string, kLegDofs> left{"left_hip_pitch_joint", "left_hip_roll_joint", "left_hip_yaw_joint",
                                               "left_knee_joint", "left_ankle_pitch_joint", "left_ankle_roll_joint"};
  EXPECT_EQ(legs->jointNames(Foot::kLeft), left);
  EXPECT_EQ(legs->jointNames(Foot::kRight)[3], "right_knee_joint");
  EXPECT_NEAR(legs->jointLimits(Foot::kLeft)[3].second, 2.8798, 1e-6);  // knee upper limit from the URDF
}

TEST(LegModel, MissingFileAndLinkNameTheProblem) {
  try {
    LegModel::fromUrdfFile(pmg::test::sourcePath("config/robots/g1/missing.urdf"));
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.urdf"), std::string::npos) << e.what();
  }
  LegModelOptions o;
  o.foot_links[1] = "no_such_link";
  try {
    LegModel::fromUrdfFile(test::kG1Urdf, o);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_link"), std::string::npos) << e.what();
  }
}

TEST(LegModel, FromRobotConfigMatchesTheUrdfChains) {
  const RobotConfig& cfg = pmg::test::g1Robot();
  const auto legs = LegModel::fromRobotConfig(cfg);
  const auto ref = test::g1Legs();
  LegKinematics a(legs), b(ref);
  LegVector q;
  q << -0.3, 0.1, -0.05, 0.7, -0.3, 0.05;
  for (Foot f : {Foot::kLeft, Foot::kRight}) {
    EXPECT_EQ(legs->jointNames(f), ref->jointNames(f));
    Eigen::Isometry3d Xa, Xb;
    ASSERT_TRUE(a.forward(f, q, &Xa));
    ASSERT_TRUE(b.forward(f, q, &Xb));
    EXPECT_LT((Xa.translation() - Xb.translation()).norm(), 1e-12);
  }
  const auto idx = legs->jointIndices(cfg.jointNames());
  EXPECT_EQ(idx[0][3], cfg.jointIndex("left_knee_joint"));
  EXPECT_EQ(idx[1][0], cfg.jointIndex("right_hip_pitch_joint"));
}

TEST(LegModel, JointIndicesFromRobotOrder) {
  const auto legs = test::g1Legs();
  std::vector<std::string> names{"waist_yaw_joint"};
  for (Foot f : {Foot::kRight, Foot::kLeft}) {
    for (const auto& n : legs->jointNames(f)) names.push_back(n);
  }
  const auto idx = legs->jointIndices(names);
  EXPECT_EQ(idx[0][0], 7);  // left_hip_pitch after waist + 6 right joints
  EXPECT_EQ(idx[1][5], 6);
  names.pop_back();
  EXPECT_THROW(legs->jointIndices(names), std::runtime_error);
}

TEST(LegKinematics, ZeroPoseSolesAreBelowTheHipsAndMirrored) {
  LegKinematics kin(test::g1Legs());
  FootKinematics l, r;
  ASSERT_TRUE(kin.compute(Foot::kLeft, LegVector::Zero(), LegVector::Zero(), &l));
  ASSERT_TRUE(kin.compute(Foot::kRight, LegVector::Zero(), LegVector::Zero(), &r));
  EXPECT_NEAR(l.p_BS_B.y(), -r.p_BS_B.y(), 1e-6);
  EXPECT_GT(l.p_BS_B.y(), 0.08);
  EXPECT_LT(l.p_BS_B.z(), -0.7);  // straight leg: sole ~0.75 m below the pelvis
  EXPECT_GT(l.p_BS_B.z(), -0.85);
}

TEST(LegKinematics, JacobianVelocityMatchesFiniteDifferenceOfForwardKinematics) {
  LegKinematics kin(test::g1Legs());
  LegVector q, qd;
  q << -0.4, 0.1, 0.05, 0.8, -0.35, 0.05;
  qd << 1.0, -0.5, 0.3, -2.0, 1.5, 0.4;
  for (Foot f : {Foot::kLeft, Foot::kRight}) {
    FootKinematics k;
    ASSERT_TRUE(kin.compute(f, q, qd, &k));
    const double h = 1e-6;
    Eigen::Isometry3d Xp, Xm;
    ASSERT_TRUE(kin.forward(f, q + h * qd, &Xp));
    ASSERT_TRUE(kin.forward(f, q - h * qd, &Xm));
    const Eigen::Vector3d v_fd = (Xp.translation() - Xm.translation()) / (2 * h);
    EXPECT_LT((v_fd - k.v_BS_B).norm(), 1e-6);
    const Eigen::AngleAxisd dR(Xp.linear() * Xm.linear().transpose());
    EXPECT_LT((dR.axis() * dR.angle() / (2 * h) - k.w_BF_B).norm(), 1e-5);
  }
}

TEST(LegKinematics, NonFiniteInputIsRejected) {
  LegKinematics kin(test::g1Legs());
  LegVector q = LegVector::Zero();
  q(2) = std::numeric_limits<double>::quiet_NaN();
  FootKinematics k;
  k.p_BS_B.setConstant(7.0);
  EXPECT_FALSE(kin.compute(Foot::kLeft, q, LegVector::Zero(), &k));
  EXPECT_EQ(k.p_BS_B.x(), 7.0);
}

TEST(LegKinematics, InverseKinematicsReachesAReachableSolePose) {
  LegKinematics kin(test::g1Legs());
  LegVector q_true;
  q_true << -0.3, 0.05, 0.1, 0.6, -0.3, 0.02;
  Eigen::Isometry3d X;
  ASSERT_TRUE(kin.forward(Foot::kRight, q_true, &X));
  LegVector q;
  LegVector seed;
  seed << -0.1, 0.0, 0.0, 0.3, -0.2, 0.0;  // standing pose: IK is local
  const double err = kin.inverse(Foot::kRight, X, seed, &q);
  EXPECT_LT(err, 1e-6);
}

}  // namespace
}  // namespace pmg::gco
