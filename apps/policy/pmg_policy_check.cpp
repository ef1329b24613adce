// pmg_policy_check: loads an exported actor exactly as the controller would (contract check
// against the robot config, reference pairs, warm-up) and prints its contract.
//   pmg_policy_check --model config/policies/g1_pmg_policy.onnx
//       [--robot config/robots/g1/g1.yaml] [--period 0.01] [--pmg gco=false --pmg enabled=true]
// Exit code 0 if the controller would start with this policy, 1 otherwise (the error names
// the file and the field).
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/policy/policy_runner.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Check an ONNX actor's pmg.contract against a robot config"};
  std::string model, robot = pmg::resolveData("config/robots/g1/g1.yaml").string();
  double period = 0.01;
  std::vector<std::string> pmg;
  app.add_option("--model", model, "ONNX actor with pmg.contract metadata")->required();
  app.add_option("--robot", robot, "robot config YAML (joint order, default pose, PD gains)")->capture_default_str();
  app.add_option("--period", period, "controller loop period [s]")->check(CLI::PositiveNumber);
  app.add_option("--pmg", pmg, "PMG/GCO setting the controller runs with, key=value (repeatable)");
  CLI11_PARSE(app, argc, argv);
  try {
    auto spec = pmg::policy::loadPolicyRobotSpec(robot, period);
    for (const auto& kv : pmg) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) throw std::invalid_argument("--pmg '" + kv + "': expected key=value");
      spec.pmg[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    pmg::policy::PolicyRunner runner(model, spec);
    const auto& c = runner.contract();
    std::printf("OK %s\n  robot %s, %zu joints, actor commands %zu (%s), period %.4f s\n", model.c_str(), c.robot.c_str(),
                c.joint_names.size(), c.actuated_joints.size(), c.controls_waist ? "legs + waist" : "legs",
                c.control_period);
    std::printf("  observation %d values = %d frame(s) x %d:", runner.observationSize(), c.observation.history_length,
                c.observation.frameSize());
    for (const auto& t : c.observation.terms) std::printf(" %s[%d]", t.name.c_str(), t.size);
    std::printf("\n  pmg:");
    for (const auto& [k, v] : c.pmg) std::printf(" %s=%s", k.c_str(), v.c_str());
    std::printf("\n  %zu reference pairs reproduced, max |action error| %.3g\n", c.reference_pairs.size(),
                static_cast<double>(runner.referenceMaxAbsError()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "REFUSED: %s\n", e.what());
    return 1;
  }
  return 0;
}
