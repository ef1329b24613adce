#pragma once
// Shared fixtures for test/policy: the G1 robot spec and the committed test models
// (test/data/policy/make_test_models.py writes them), by absolute path (test support).
#include <string>

#include "g1_fixture.hpp"
#include "pmg/policy/contract.hpp"

namespace pmg::policy::test {

inline const std::string kDataDir = pmg::test::policyTestDataDir();

/// Robot spec from the lead's robot config, with the settings the test models were written for.
inline PolicyRobotSpec g1Spec() {
  PolicyRobotSpec s = loadPolicyRobotSpec(pmg::test::g1RobotConfigPath(), 0.01);
  s.pmg = {{"enabled", "true"}, {"gco", "false"}, {"gait_period", "0.8"}};
  return s;
}

}  // namespace pmg::policy::test
