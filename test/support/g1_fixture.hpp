#pragma once
// Paths of the shipped data the tests read, resolved against the repository root the test support
// target was compiled from (PMG_TEST_SOURCE_DIR), so tests do not depend on the working directory.
// The G1 fixture: the shipped Unitree G1 config files and a cached, loaded RobotConfig.
#include <string>

#include "pmg/common/robot_config.hpp"

namespace pmg::test {

/// Absolute path of the repository root (no trailing slash).
const std::string& sourceDir();
/// Absolute path of @p relative (a path from the repository root, e.g. "config/hal/g1_can.yaml").
std::string sourcePath(const std::string& relative);

std::string g1RobotConfigPath();          ///< config/robots/g1/g1.yaml
std::string g1RobotDir();                 ///< config/robots/g1
std::string g1UrdfPath();                 ///< config/robots/g1/g1_29dof_rev_1_0.urdf
std::string g1ClipDir();                  ///< config/clips/g1
std::string g1ClipPath(const std::string& name);  ///< config/clips/g1/<name>.yaml
std::string g1SilControllerConfigPath();  ///< config/controller/g1_sil.yaml
std::string g1GcoOptionsPath();           ///< config/gco/g1.yaml
std::string g1CanPlanPath();              ///< config/hal/g1_can.yaml
std::string g1ZeroProtocolPath();         ///< config/calib/zero_poses_g1.yaml
std::string policyTestDataDir();          ///< test/data/policy/ (with the trailing slash)

/// The shipped G1 robot config, loaded once per test process.
const RobotConfig& g1Robot();

/// Text of the shipped G1 robot config with its model paths (urdf:, mjcf:) made absolute, so that
/// a modified copy written to a TempDir loads like the original.
std::string g1RobotConfigText();

/// Whole contents of a file (throws std::runtime_error naming the path if it cannot be read).
std::string readTextFile(const std::string& path);

}  // namespace pmg::test
