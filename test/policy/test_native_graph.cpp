// NativeGraph / PolicyBackend::kNative: the allocation-free evaluator reproduces ONNX Runtime and
// the stored reference actions on every committed model, and refuses graphs it cannot run.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pmg/policy/native_graph.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "test_policy_common.hpp"

namespace pmg::policy::test {
namespace {

PolicyRunnerOptions nativeOptions() {
  PolicyRunnerOptions o;
  o.backend = PolicyBackend::kNative;
  return o;
}

class NativeModels : public ::testing::TestWithParam<std::string> {};

TEST_P(NativeModels, MatchesOnnxRuntimeAndReferences) {
  PolicyRobotSpec spec = g1Spec();
  const std::string path = GetParam();
  if (path.find("/config/policies/") != std::string::npos) spec.pmg = {{"enabled", "true"}, {"gco", "true"}};
  PolicyRunner ort(path, spec);
  PolicyRunner native(path, spec, nativeOptions());
  // Reference pairs plus perturbed inputs (not stored anywhere): both engines agree.
  ASSERT_FALSE(ort.contract().reference_pairs.empty()) << path << " has no reference pairs to compare on";
  std::vector<float> obs;
  int k = 0;
  for (const auto& ref : ort.contract().reference_pairs) {
    for (int variant = 0; variant < 3; ++variant) {
      obs = ref.obs;
      for (std::size_t i = 0; i < obs.size(); ++i) obs[i] += 0.1f * static_cast<float>(variant) * std::sin(0.7f * static_cast<float>(i + k));
      ++k;
      ASSERT_TRUE(ort.step(obs.data()).ok());
      ASSERT_TRUE(native.step(obs.data()).ok());
      for (int i = 0; i < ort.actionSize(); ++i) EXPECT_NEAR(native.action()[i], ort.action()[i], 2e-6f) << path << " action " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Committed, NativeModels,
                         ::testing::Values(kDataDir + "g1_legs_ok.onnx", kDataDir + "g1_legs_waist_hist3_ok.onnx",
                                           kDataDir + "g1_legs_512_256_128.onnx", pmg::test::sourcePath("config/policies/g1_pmg_policy.onnx")));

TEST(NativeGraph, NanOutputDetected) {
  PolicyRunner runner(kDataDir + "nan_output.onnx", g1Spec(), nativeOptions());
  ASSERT_FALSE(runner.contract().reference_pairs.empty());
  std::vector<float> obs = runner.contract().reference_pairs[0].obs;
  ASSERT_TRUE(runner.step(obs.data()).ok());
  obs[0] = -1.0f;  // sqrt(obs[0]) -> NaN
  EXPECT_EQ(runner.step(obs.data()).code, PolicyStepCode::kNonFiniteAction);
  EXPECT_EQ(runner.counters().nonfinite_action, 1u);
}

TEST(NativeGraph, UnsupportedOpRefusedByNameButOnnxRuntimeRunsIt) {
  EXPECT_NO_THROW(PolicyRunner(kDataDir + "softplus_ok_for_ort.onnx", g1Spec()));
  try {
    PolicyRunner runner(kDataDir + "softplus_ok_for_ort.onnx", g1Spec(), nativeOptions());
    FAIL() << "native backend accepted Softplus";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Softplus"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("softplus_ok_for_ort.onnx"), std::string::npos) << e.what();
  }
}

TEST(NativeGraph, UnknownOutputRefused) {
  EXPECT_THROW(NativeGraph(kDataDir + "g1_legs_ok.onnx", "obs", "no_such_value", 62), std::runtime_error);
}

}  // namespace
}  // namespace pmg::policy::test
