// PolicyRunner: loads the committed test models through ONNX Runtime and checks its outputs
// against an independent float32 NumPy forward pass (the reference pairs) and its guards.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "test_policy_common.hpp"

namespace pmg::policy::test {
namespace {

TEST(PolicyRunner, ReproducesReferencePairs) {
  PolicyRunnerOptions opt;
  opt.warmup_runs = 3;
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec(), opt);
  ASSERT_EQ(runner.observationSize(), 3 + 3 + 6 + 12 * 4 + 2);
  ASSERT_EQ(runner.actionSize(), 12);
  EXPECT_LT(runner.referenceMaxAbsError(), 1e-5f);
  for (const auto& ref : runner.contract().reference_pairs) {
    ASSERT_TRUE(runner.step(ref.obs.data()).ok());
    for (int i = 0; i < runner.actionSize(); ++i) {
      EXPECT_NEAR(runner.action()[i], ref.action[static_cast<std::size_t>(i)], 1e-5f) << "action " << i;
    }
  }
  EXPECT_EQ(runner.counters().steps, runner.contract().reference_pairs.size());
  EXPECT_EQ(runner.counters().held, 0u);
}

TEST(PolicyRunner, TargetsAreOffsetPlusScaledClippedAction) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  const auto& c = runner.contract();
  // Before the first step the targets are the offset (= default pose of the legs).
  for (int i = 0; i < runner.actionSize(); ++i) EXPECT_DOUBLE_EQ(runner.jointTargets()[i], c.action.offset[static_cast<std::size_t>(i)]);
  EXPECT_DOUBLE_EQ(runner.jointTargets()[3], 0.3);  // left knee default
  // A large input drives tanh units to saturation; whatever the action, targets follow the law.
  std::vector<float> obs(static_cast<std::size_t>(runner.observationSize()), 50.0f);
  ASSERT_TRUE(runner.step(obs.data()).ok());
  for (int i = 0; i < runner.actionSize(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double a = std::clamp(runner.action()[i], -c.action.clip, c.action.clip);
    EXPECT_NEAR(runner.jointTargets()[i], c.action.offset[k] + c.action.scale[k] * a, 1e-9);
  }
}

TEST(PolicyRunner, NonFiniteObservationHoldsLastAction) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  const auto& ref = runner.contract().reference_pairs[0];
  ASSERT_TRUE(runner.step(ref.obs.data()).ok());
  const std::vector<double> before(runner.jointTargets(), runner.jointTargets() + runner.actionSize());
  std::vector<float> bad = runner.contract().reference_pairs[1].obs;
  bad[7] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(runner.step(bad.data()).code, PolicyStepCode::kNonFiniteObservation);
  bad[7] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(runner.step(bad.data()).code, PolicyStepCode::kNonFiniteObservation);
  for (int i = 0; i < runner.actionSize(); ++i) EXPECT_EQ(runner.jointTargets()[i], before[static_cast<std::size_t>(i)]);
  EXPECT_EQ(runner.counters().nonfinite_observation, 2u);
  EXPECT_EQ(runner.counters().held, 2u);
}

TEST(PolicyRunner, NanActionHoldsLastActionAndRecovers) {
  // nan_output.onnx adds 0*sqrt(obs[0]): NaN actions whenever obs[0] < 0.
  PolicyRunner runner(kDataDir + "nan_output.onnx", g1Spec());
  const auto& ref = runner.contract().reference_pairs[0];
  ASSERT_TRUE(runner.step(ref.obs.data()).ok());
  const std::vector<double> before(runner.jointTargets(), runner.jointTargets() + runner.actionSize());
  std::vector<float> obs = ref.obs;
  obs[0] = -0.5f;
  EXPECT_EQ(runner.step(obs.data()).code, PolicyStepCode::kNonFiniteAction);
  for (int i = 0; i < runner.actionSize(); ++i) {
    EXPECT_TRUE(std::isfinite(runner.jointTargets()[i]));
    EXPECT_EQ(runner.jointTargets()[i], before[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(runner.counters().nonfinite_action, 1u);
  const auto& ref1 = runner.contract().reference_pairs[1];
  ASSERT_TRUE(runner.step(ref1.obs.data()).ok());
  EXPECT_NEAR(runner.action()[0], ref1.action[0], 1e-5f);
}

TEST(PolicyRunner, ResetActionReturnsToOffset) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  ASSERT_TRUE(runner.step(runner.contract().reference_pairs[0].obs.data()).ok());
  runner.resetAction();
  for (int i = 0; i < runner.actionSize(); ++i) {
    EXPECT_EQ(runner.action()[i], 0.0f);
    EXPECT_DOUBLE_EQ(runner.jointTargets()[i], runner.contract().action.offset[static_cast<std::size_t>(i)]);
  }
}

TEST(PolicyRunner, WaistAndHistoryModel) {
  PolicyRunner runner(kDataDir + "g1_legs_waist_hist3_ok.onnx", g1Spec());
  EXPECT_TRUE(runner.contract().controls_waist);
  EXPECT_EQ(runner.contract().observation.history_length, 3);
  EXPECT_EQ(runner.actionSize(), 15);
  EXPECT_EQ(runner.observationSize(), 3 * (3 + 3 + 6 + 15 * 4 + 2));
  for (const auto& ref : runner.contract().reference_pairs) {
    ASSERT_TRUE(runner.step(ref.obs.data()).ok());
    for (int i = 0; i < runner.actionSize(); ++i) EXPECT_NEAR(runner.action()[i], ref.action[static_cast<std::size_t>(i)], 1e-5f);
  }
}

TEST(PolicyRunner, MissingFileNamesPath) {
  try {
    PolicyRunner runner(kDataDir + "does_not_exist.onnx", g1Spec());
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.onnx"), std::string::npos) << e.what();
  }
}

TEST(PolicyRunner, InvalidOptionsRefused) {
  PolicyRunnerOptions opt;
  opt.reference_atol = 0.0f;
  std::string msg;
  EXPECT_FALSE(opt.validate(&msg));
  EXPECT_NE(msg.find("reference_atol"), std::string::npos);
  EXPECT_THROW(PolicyRunner(kDataDir + "g1_legs_ok.onnx", g1Spec(), opt), std::invalid_argument);
}

TEST(PolicyRunner, TighterToleranceThanFloatNoiseStillPasses) {
  // The NumPy float32 reference and ORT agree far below the default tolerance; a 100x tighter
  // tolerance still accepts the model, while bad_reference (1e-2 off) is refused by default.
  PolicyRunnerOptions opt;
  opt.reference_atol = 1e-6f;
  opt.reference_rtol = 1e-5f;
  EXPECT_NO_THROW(PolicyRunner(kDataDir + "g1_legs_ok.onnx", g1Spec(), opt));
}

// The shipped, trained policy must stay consistent with the robot config (joint order, default
// pose, PD gains, 100 Hz period): a change to config/robots/g1/g1.yaml that breaks it fails here,
// which means the policy has to be retrained or re-exported.
TEST(PolicyRunner, ShippedPolicyMatchesRobotConfig) {
  PolicyRobotSpec spec = loadPolicyRobotSpec(pmg::test::g1RobotConfigPath(), 0.01);
  spec.pmg = {{"enabled", "true"}, {"gco", "true"}, {"mode", "pmg"}};  // full PMG (GCO)
  PolicyRunner runner(pmg::test::sourcePath("config/policies/g1_pmg_policy.onnx"), spec);
  EXPECT_EQ(runner.actionSize(), 12);
  EXPECT_EQ(runner.observationSize(), 62);
  EXPECT_LT(runner.referenceMaxAbsError(), 1e-5f);
  // Standing observation at the default pose: finite actions within the tanh range.
  std::vector<float> obs(62, 0.0f);
  obs[5] = -1.0f;                      // projected gravity: upright
  obs[11] = 0.78f;                     // command height [m] x scale 1
  obs[61] = 1.0f;                      // cos(2*pi*phase) at phase 0
  ASSERT_TRUE(runner.step(obs.data()).ok());
  for (int i = 0; i < 12; ++i) {
    EXPECT_TRUE(std::isfinite(runner.action()[i]));
    EXPECT_LE(std::abs(runner.action()[i]), 1.0f);
  }
}

}  // namespace
}  // namespace pmg::policy::test
