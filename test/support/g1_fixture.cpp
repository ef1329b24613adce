#include "g1_fixture.hpp"

#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#ifndef PMG_TEST_SOURCE_DIR
#error "PMG_TEST_SOURCE_DIR must be defined by the pmg_test_support target"
#endif

namespace pmg::test {

const std::string& sourceDir() {
  static const std::string dir = PMG_TEST_SOURCE_DIR;
  return dir;
}

std::string sourcePath(const std::string& relative) { return sourceDir() + "/" + relative; }

std::string g1RobotConfigPath() { return sourcePath("config/robots/g1/g1.yaml"); }
std::string g1RobotDir() { return sourcePath("config/robots/g1"); }
std::string g1UrdfPath() { return sourcePath("config/robots/g1/g1_29dof_rev_1_0.urdf"); }
std::string g1ClipDir() { return sourcePath("config/clips/g1"); }
std::string g1ClipPath(const std::string& name) { return g1ClipDir() + "/" + name + ".yaml"; }
std::string g1SilControllerConfigPath() { return sourcePath("config/controller/g1_sil.yaml"); }
std::string g1GcoOptionsPath() { return sourcePath("config/gco/g1.yaml"); }
std::string g1CanPlanPath() { return sourcePath("config/hal/g1_can.yaml"); }
std::string g1ZeroProtocolPath() { return sourcePath("config/calib/zero_poses_g1.yaml"); }
std::string policyTestDataDir() { return sourcePath("test/data/policy/"); }

const RobotConfig& g1Robot() {
  static const RobotConfig robot = loadRobotConfig(g1RobotConfigPath());
  return robot;
}

std::string g1RobotConfigText() {
  const std::string text = readTextFile(g1RobotConfigPath());
  const std::string dir = g1RobotDir() + "/";
  return std::regex_replace(text, std::regex(R"(^(\s*(urdf|mjcf):\s*)([^/\s#][^\s#]*))",
                                             std::regex::multiline),
                            "$1" + dir + "$3");
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace pmg::test
