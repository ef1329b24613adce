// Posture templates on the robot with the feet flat (pmg::motion::PostureProbe): the measures of
// known postures, the squat's torso-pitch hold, and the synthesized lean. The shipped templates
// themselves: test_shipped_clips.cpp.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/clips/clip_validation.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/posture_synthesis.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

class PostureSynthesis : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new KinematicModel(pmg::test::g1Robot());
    probe_ = new PostureProbe(*model_);
  }
  static void TearDownTestSuite() {
    delete probe_;
    delete model_;
  }
  static KinematicModel* model_;
  static PostureProbe* probe_;
  const RobotConfig& robot_ = pmg::test::g1Robot();
};
KinematicModel* PostureSynthesis::model_ = nullptr;
PostureProbe* PostureSynthesis::probe_ = nullptr;

// The default pose stands level and upright and balanced; tilting both feet by the ankles tilts the
// pelvis (and the torso with it) the other way when the feet are put flat.
TEST_F(PostureSynthesis, MeasuresTheTiltTheFeetImply) {
  Eigen::VectorXd q = robot_.defaultPose();
  const FlatFootPosture stand = probe_->measure(q);
  EXPECT_NEAR(stand.pelvis_pitch, 0.0, 1e-9);
  EXPECT_NEAR(stand.pelvis_roll, 0.0, 1e-9);
  EXPECT_NEAR(stand.torso_pitch, 0.0, 1e-9);
  EXPECT_NEAR(stand.torso_roll, 0.0, 1e-9);
  EXPECT_NEAR(stand.foot_tilt, 0.0, 1e-9);
  EXPECT_GT(stand.pelvis_height, 0.7);
  EXPECT_LT(stand.pelvis_height, 0.8);
  EXPECT_GT(stand.com_margin, 0.03);
  EXPECT_NEAR(stand.p_WS[0].y(), -stand.p_WS[1].y(), 1e-9);
  // Both ankles pitched by +0.1 rad: the feet are flat only with the pelvis pitched by 0.1.
  for (const char* j : {"left_ankle_pitch_joint", "right_ankle_pitch_joint"}) q(robot_.jointIndex(j)) += 0.1;
  const FlatFootPosture tilted = probe_->measure(q);
  EXPECT_NEAR(std::abs(tilted.pelvis_pitch), 0.1, 1e-6);
  EXPECT_NEAR(tilted.torso_pitch, tilted.pelvis_pitch, 1e-9);  // waist straight
  EXPECT_NEAR(tilted.foot_tilt, 0.0, 1e-9);
  // Feet rolled the same way (ankle roll mirrored): the pelvis rolls.
  q = robot_.defaultPose();
  q(robot_.jointIndex("left_ankle_roll_joint")) = 0.05;
  q(robot_.jointIndex("right_ankle_roll_joint")) = 0.05;
  EXPECT_NEAR(std::abs(probe_->measure(q).pelvis_roll), 0.05, 2e-3);
  EXPECT_THROW(probe_->measure(Eigen::VectorXd::Zero(3)), std::invalid_argument);
}

// holdTorsoPitch sets the waist pitch so that every row's torso pitch (feet flat) is the neutral
// row's, whatever the legs make the pelvis do; other joints are left alone.
TEST_F(PostureSynthesis, HoldTorsoPitchCompensatesPelvisTiltAndWaist) {
  StaticClip s;
  s.name = "squat_like";
  s.axis = PostureAxis::kHeight;
  s.values = Eigen::Vector3d(0.6, 0.7, 0.76);
  s.neutral = 0.76;
  s.q = robot_.defaultPose().transpose().replicate(3, 1);
  const Eigen::Index wp = robot_.jointIndex("waist_pitch_joint");
  s.q(0, wp) = 0.4;  // the trunk leans forward 0.4 on the waist...
  for (const char* j : {"left_ankle_pitch_joint", "right_ankle_pitch_joint"}) s.q(0, robot_.jointIndex(j)) += 0.15;  // ...the pelvis tilts back 0.15
  s.q(1, wp) = -0.2;
  const StaticClip before = s;
  const double residual = holdTorsoPitch(s, *probe_);
  EXPECT_LT(residual, 1e-8);
  const double pitch0 = probe_->measure(s.q.row(2).transpose()).torso_pitch;
  for (Eigen::Index i = 0; i < 3; ++i) {
    EXPECT_NEAR(probe_->measure(s.q.row(i).transpose()).torso_pitch, pitch0, 1e-8) << "row " << i;
    for (Eigen::Index j = 0; j < s.q.cols(); ++j)
      if (j != wp) {
        EXPECT_EQ(s.q(i, j), before.q(i, j));
      }
  }
  EXPECT_NEAR(probe_->measure(before.q.row(0).transpose()).torso_pitch - pitch0, 0.25, 1e-3);  // the input did couple
  EXPECT_NEAR(std::abs(s.q(0, wp)), 0.15, 0.01);  // the waist now only undoes the pelvis tilt
  // A coupling the waist cannot undo (pelvis tilted past the waist limit) is reported, not hidden.
  StaticClip far = before;
  for (const char* j : {"left_ankle_pitch_joint", "right_ankle_pitch_joint"}) far.q(0, robot_.jointIndex(j)) = robot_.joints[static_cast<std::size_t>(robot_.jointIndex(j))].upper;
  for (const char* j : {"left_knee_joint", "right_knee_joint"}) far.q(0, robot_.jointIndex(j)) = 0.0;
  for (const char* j : {"left_hip_pitch_joint", "right_hip_pitch_joint"}) far.q(0, robot_.jointIndex(j)) = 0.5;
  EXPECT_GT(holdTorsoPitch(far, *probe_), 0.1);
}

// The synthesized lean: values strictly increasing, symmetric, neutral 0 at the default pose; soles
// planted and flat; a valid static clip declared as synthesized.
TEST_F(PostureSynthesis, SynthesizedLeanMeetsItsTargets) {
  LeanOptions opt;
  opt.max_roll = 0.2;
  opt.samples_per_side = 2;
  const LeanSynthesis lean = synthesizeLean(*probe_, opt);
  const StaticClip& c = lean.clip;
  ASSERT_EQ(c.values.size(), 5);
  EXPECT_EQ(c.axis, PostureAxis::kRoll);
  EXPECT_EQ(c.neutral, 0.0);
  EXPECT_EQ(c.values(2), 0.0);
  EXPECT_TRUE(c.q.row(2).isApprox(robot_.defaultPose().transpose()));
  for (Eigen::Index i = 0; i < 5; ++i) {
    EXPECT_NEAR(c.values(i), 0.1 * static_cast<double>(i - 2), 1e-4) << i;
    EXPECT_NEAR(c.values(i), -c.values(4 - i), 1e-9) << i;
  }
  EXPECT_LT(lean.max_foot_error, 1e-4);
  EXPECT_LT(lean.max_foot_tilt, 1e-4);
  EXPECT_LT(lean.max_com_shift, 1e-4);
  EXPECT_LT(lean.max_pitch_change, 1e-3);
  EXPECT_GT(lean.min_com_margin, 0.02);
  // The waist does the roll and the legs shift the pelvis (hip roll), arms untouched.
  const Eigen::VectorXd d = (c.q.row(4) - c.q.row(2)).transpose();
  EXPECT_NEAR(d(robot_.jointIndex("waist_roll_joint")), 0.2, 0.05);
  EXPECT_GT(std::abs(d(robot_.jointIndex("left_hip_roll_joint"))), 0.005);
  EXPECT_EQ(d(robot_.jointIndex("left_shoulder_pitch_joint")), 0.0);
  EXPECT_EQ(c.meta.provenance, "synthesized");
  EXPECT_NO_THROW(validateClip(c, robot_, "lean"));
  LeanOptions bad;
  bad.max_roll = 0.6;
  EXPECT_THROW(synthesizeLean(*probe_, bad), std::invalid_argument);
}

TEST_F(PostureSynthesis, HoldJointsAtNeutralFreezesColumns) {
  StaticClip s;
  s.name = "squat_like";
  s.values = Eigen::Vector2d(0.6, 0.76);
  s.neutral = 0.76;
  s.q = Eigen::MatrixXd::Random(2, static_cast<Eigen::Index>(robot_.numJoints()));
  const StaticClip before = s;
  const int shoulder = robot_.jointIndex("left_shoulder_pitch_joint");
  holdJointsAtNeutral(s, {shoulder});
  EXPECT_EQ(s.q(0, shoulder), before.q(1, shoulder));
  EXPECT_EQ(s.q.row(1), before.q.row(1));
  EXPECT_EQ(s.q(0, 0), before.q(0, 0));
  EXPECT_THROW(holdJointsAtNeutral(s, {99}), std::invalid_argument);
}

}  // namespace
