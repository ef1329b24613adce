// Allocation accounting of the per-tick path: the test-support allocation guard, in its
// process-wide mode, is switched on around ObservationAssembler::setTerm/commit,
// PolicyRunner::step and LimbSeparation::compose. It sees every operator new in the process,
// ONNX Runtime's included (it links the same libstdc++).
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "pmg/policy/limb_separation.hpp"
#include "pmg/policy/observation.hpp"
#include "pmg/policy/onnx_session.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "test_policy_common.hpp"

namespace pmg::policy::test {
namespace {

// Counts every thread's operator new calls (ONNX Runtime may allocate on its own threads).
struct Counting {
  pmg::test::AllocationGuard guard{pmg::test::AllocationScope::kProcess};
  long count() const { return static_cast<long>(guard.count()); }
};

TEST(PolicyAllocation, CounterSeesAllocations) {
  // The counter itself works (otherwise the zero below would prove nothing).
  Counting c;
  auto* v = new std::vector<double>(100);
  const long n = c.count();
  delete v;
  EXPECT_GE(n, 2);
}

// pmg's own per-tick code (observation assembly, runner bookkeeping and guards, limb
// separation) allocates nothing. A non-finite observation makes step() return before ONNX
// Runtime is called, so this measures the runner alone.
TEST(PolicyAllocation, OwnTickCodeIsAllocationFree) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  ObservationAssembler obs(runner.contract().observation);
  LimbSeparation split(runner.contract());
  JointCommand cmd;
  cmd.resize(split.numJoints());
  std::vector<int> idx;
  for (const auto& t : runner.contract().observation.terms) idx.push_back(obs.termIndex(t.name));
  std::vector<double> raw(64, 0.1), upper_q(29, 0.0);
  std::vector<float> nan_obs(static_cast<std::size_t>(runner.observationSize()), std::nanf(""));
  long allocations = 0;
  {
    Counting c;
    for (int tick = 0; tick < 200; ++tick) {
      for (double& r : raw) r = 0.01 * tick;
      for (int i : idx) obs.setTerm(i, raw.data());
      ASSERT_TRUE(obs.commit());
      ASSERT_EQ(runner.step(nan_obs.data()).code, PolicyStepCode::kNonFiniteObservation);
      split.compose(runner.jointTargets(), upper_q.data(), nullptr, cmd);
    }
    allocations = c.count();
  }
  EXPECT_EQ(allocations, 0) << "operator new calls in 200 ticks of pmg code";
}

// ONNX Runtime 1.24's Run allocates a small, constant number of objects per call (its execution
// frame bookkeeping; the tensors themselves are the bound, preallocated buffers). This test
// pins that: the count per bare OnnxSession::run() is the same on every call (no growth), and
// a full tick (assembly + PolicyRunner::step + composition) allocates exactly that many and
// not one more. docs/policy.md discusses what this means for the real-time loop.
TEST(PolicyAllocation, FullTickAllocatesOnlyWhatOnnxRuntimeRunDoes) {
  PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", g1Spec());
  OnnxSession bare(kDataDir + "g1_legs_ok.onnx");
  std::vector<float> in(static_cast<std::size_t>(runner.observationSize()), 0.1f);
  std::vector<float> out(static_cast<std::size_t>(runner.actionSize()), 0.0f);
  bare.bindInput(bare.inputs()[0].name, in.data(), {1, runner.observationSize()});
  bare.bindOutput(bare.outputs()[0].name, out.data(), {1, runner.actionSize()});
  for (int w = 0; w < 5; ++w) ASSERT_TRUE(bare.run());
  std::vector<long> per_run;
  for (int k = 0; k < 50; ++k) {
    Counting c;
    ASSERT_TRUE(bare.run());
    per_run.push_back(c.count());
  }
  for (long n : per_run) ASSERT_EQ(n, per_run.front()) << "ONNX Runtime allocations per run vary";
  const long ort_per_run = per_run.front();
  RecordProperty("onnxruntime_allocations_per_run", static_cast<int>(ort_per_run));
  std::printf("ONNX Runtime operator-new calls per Run: %ld\n", ort_per_run);

  ObservationAssembler obs(runner.contract().observation);
  LimbSeparation split(runner.contract());
  JointCommand cmd;
  cmd.resize(split.numJoints());
  std::vector<double> raw(64, 0.0), upper_q(29, 0.0);
  long allocations = 0;
  constexpr int kTicks = 200;
  {
    Counting c;
    for (int tick = 0; tick < kTicks; ++tick) {
      for (double& r : raw) r = 0.01 * tick;
      for (int i = 0; i < static_cast<int>(runner.contract().observation.terms.size()); ++i) obs.setTerm(i, raw.data());
      ASSERT_TRUE(obs.commit());
      ASSERT_TRUE(runner.step(obs.data()).ok());
      split.compose(runner.jointTargets(), upper_q.data(), nullptr, cmd);
    }
    allocations = c.count();
  }
  EXPECT_EQ(allocations, kTicks * ort_per_run) << "pmg code added allocations on top of ONNX Runtime's";
  EXPECT_EQ(runner.counters().steps, static_cast<std::uint64_t>(kTicks));
}

// With the native backend the whole tick, inference included, allocates nothing.
TEST(PolicyAllocation, NativeBackendTickIsAllocationFree) {
  PolicyRunnerOptions opt;
  opt.backend = PolicyBackend::kNative;
  PolicyRunner runner(kDataDir + "g1_legs_512_256_128.onnx", g1Spec(), opt);
  ObservationAssembler obs(runner.contract().observation);
  LimbSeparation split(runner.contract());
  JointCommand cmd;
  cmd.resize(split.numJoints());
  std::vector<double> raw(64, 0.0), upper_q(29, 0.0);
  long allocations = 0;
  {
    Counting c;
    for (int tick = 0; tick < 200; ++tick) {
      for (double& r : raw) r = 0.01 * tick;
      for (int i = 0; i < static_cast<int>(runner.contract().observation.terms.size()); ++i) obs.setTerm(i, raw.data());
      ASSERT_TRUE(obs.commit());
      ASSERT_TRUE(runner.step(obs.data()).ok());
      split.compose(runner.jointTargets(), upper_q.data(), nullptr, cmd);
    }
    allocations = c.count();
  }
  EXPECT_EQ(allocations, 0) << "operator new calls in 200 ticks with the native backend";
  EXPECT_EQ(runner.counters().steps, 200u);
}

}  // namespace
}  // namespace pmg::policy::test
