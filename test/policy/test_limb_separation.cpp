// LimbSeparation: actor joints take the actor's targets, all others the upper-body targets.
#include <vector>

#include <gtest/gtest.h>

#include "pmg/policy/limb_separation.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "test_policy_common.hpp"

namespace pmg::policy::test {
namespace {

void checkSplit(const std::string& file, std::size_t n_actor) {
  const PolicyRobotSpec spec = g1Spec();
  PolicyRunner runner(kDataDir + file, spec);
  ASSERT_FALSE(runner.contract().reference_pairs.empty()) << file;
  ASSERT_TRUE(runner.step(runner.contract().reference_pairs[0].obs.data()).ok());
  LimbSeparation split(runner.contract());
  ASSERT_EQ(split.numJoints(), 29u);
  JointCommand cmd;
  cmd.resize(split.numJoints());
  std::vector<double> upper_q(29), upper_qd(29);
  for (std::size_t j = 0; j < 29; ++j) {
    upper_q[j] = 10.0 + static_cast<double>(j);  // values an actor target can never equal
    upper_qd[j] = -static_cast<double>(j);
  }
  split.compose(runner.jointTargets(), upper_q.data(), upper_qd.data(), cmd);
  std::size_t actor = 0;
  for (std::size_t j = 0; j < 29; ++j) {
    const bool is_leg = j < 12, is_waist = j >= 12 && j < 15;
    const bool expect_actor = is_leg || (is_waist && n_actor == 15);
    EXPECT_EQ(split.isActorJoint(j), expect_actor) << spec.joint_names[j];
    if (expect_actor) {
      EXPECT_DOUBLE_EQ(cmd.q_des[j], runner.jointTargets()[actor]) << spec.joint_names[j];
      EXPECT_DOUBLE_EQ(cmd.qd_des[j], 0.0);
      ++actor;
    } else {
      EXPECT_DOUBLE_EQ(cmd.q_des[j], upper_q[j]) << spec.joint_names[j];
      EXPECT_DOUBLE_EQ(cmd.qd_des[j], upper_qd[j]);
    }
    EXPECT_DOUBLE_EQ(cmd.kp[j], spec.kp[j]);
    EXPECT_DOUBLE_EQ(cmd.kd[j], spec.kd[j]);
  }
  EXPECT_EQ(actor, n_actor);
}

TEST(LimbSeparation, LegsOnlyActor) { checkSplit("g1_legs_ok.onnx", 12); }
TEST(LimbSeparation, LegsAndWaistActor) { checkSplit("g1_legs_waist_hist3_ok.onnx", 15); }

TEST(LimbSeparation, NullVelocityTargetsMeanZero) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  LimbSeparation split(runner.contract());
  JointCommand cmd;
  cmd.resize(29);
  cmd.qd_des.assign(29, 7.0);
  const std::vector<double> upper_q(29, 0.1);
  split.compose(runner.jointTargets(), upper_q.data(), nullptr, cmd);
  for (double v : cmd.qd_des) EXPECT_EQ(v, 0.0);
}

}  // namespace
}  // namespace pmg::policy::test
