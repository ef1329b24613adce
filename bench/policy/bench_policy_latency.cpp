// Latency of the policy tick: PolicyRunner::step with each backend (ONNX Runtime with 1 thread,
// and the allocation-free native evaluator) for the given actors (default: the shipped policy of
// pmg's data directory), plus observation assembly and limb separation. Prints p50 / p99 / max per
// call in microseconds over N calls after warm-up:
//   build/bin/bench_policy_latency [--iterations 20000] [--model test/data/policy/g1_legs_512_256_128.onnx ...]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/policy/limb_separation.hpp"
#include "pmg/policy/observation.hpp"
#include "pmg/policy/policy_runner.hpp"

namespace {

using Clock = std::chrono::steady_clock;

void report(const char* what, std::vector<double>& us) {
  std::sort(us.begin(), us.end());
  const auto at = [&](double q) { return us[static_cast<std::size_t>(q * static_cast<double>(us.size() - 1))]; };
  std::printf("%-44s n=%zu  p50 %8.2f us  p99 %8.2f us  max %8.2f us\n", what, us.size(), at(0.5), at(0.99), us.back());
}

void benchModel(const std::string& path, const pmg::policy::PolicyRobotSpec& spec, int n, bool native) {
  using namespace pmg::policy;
  PolicyRunnerOptions opt;
  opt.backend = native ? PolicyBackend::kNative : PolicyBackend::kOnnxRuntime;
  PolicyRunner runner(path, spec, opt);
  ObservationAssembler obs(runner.contract().observation);
  LimbSeparation split(runner.contract());
  JointCommand cmd;
  cmd.resize(split.numJoints());
  std::vector<double> raw(256, 0.0), upper(split.numJoints(), 0.0);
  std::vector<double> t_step, t_tick;
  t_step.reserve(static_cast<std::size_t>(n));
  t_tick.reserve(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = 0.001 * static_cast<double>((k + static_cast<int>(i)) % 100);
    const auto t0 = Clock::now();
    for (int i = 0; i < static_cast<int>(runner.contract().observation.terms.size()); ++i) obs.setTerm(i, raw.data());
    obs.commit();
    const auto t1 = Clock::now();
    runner.step(obs.data());
    const auto t2 = Clock::now();
    split.compose(runner.jointTargets(), upper.data(), nullptr, cmd);
    const auto t3 = Clock::now();
    t_step.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
    t_tick.push_back(std::chrono::duration<double, std::micro>(t3 - t0).count());
  }
  std::printf("%s: obs %d, actions %d, backend %s\n", path.c_str(), runner.observationSize(), runner.actionSize(),
              native ? "native" : "ONNX Runtime");
  report("  PolicyRunner::step", t_step);
  report("  full tick (assemble + step + compose)", t_tick);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Policy tick latency (p50/p99/max)"};
  int n = 20000;
  std::string robot = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::vector<std::string> models = {pmg::resolveData("config/policies/g1_pmg_policy.onnx").string()};
  app.add_option("--iterations", n, "timed calls per model")->check(CLI::Range(100, 10000000));
  app.add_option("--robot", robot, "robot config YAML")->capture_default_str();
  app.add_option("--model", models, "ONNX actors (contract must match the robot config; default: the shipped policy; "
                                    "the test models are test/data/policy/g1_legs_*.onnx)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    auto spec = pmg::policy::loadPolicyRobotSpec(robot, 0.01);
    for (const auto& m : models) {
      benchModel(m, spec, n, false);
      benchModel(m, spec, n, true);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
