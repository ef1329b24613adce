// Files of the zero-point calibration. See include/pmg/calib/zero_io.hpp.
#include "pmg/calib/zero_io.hpp"

#include <cmath>
#include <algorithm>
#include <fstream>
#include <random>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

namespace pmg::calib {

std::vector<double> randomLegOffsets(const RobotConfig& robot, const gco::LegModel& model, unsigned seed,
                                     double max_offset) {
  std::vector<double> out(robot.numJoints(), 0.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-max_offset, max_offset);
  for (int i : zeroJointIndices(model, robot)) out[static_cast<std::size_t>(i)] = u(rng);
  return out;
}

std::vector<double> loadJointValues(const std::string& path, const RobotConfig& robot) {
  return loadZeroOffsetFile(path, robot);  // one reader for the robot config's `zero_offsets:` and this
}

void writeZeroResult(const std::string& path, const RobotConfig& robot, const gco::LegModel& model,
                     const ZeroEstimate& r, const ZeroCapture& cap, const ZeroEstimatorOptions& o) {
  const auto idx = zeroJointIndices(model, robot);
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "zero_offsets" << YAML::Comment("encoder reading - true joint angle [rad]; pmg_calib_zero")
    << YAML::Value << YAML::BeginMap;
  for (int j = 0; j < kZeroJoints; ++j)
    e << YAML::Key << robot.joints[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].name << YAML::Value
      << -r.z(j);
  e << YAML::EndMap;
  e << YAML::Key << "calibration" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "converged" << YAML::Value << r.converged;
  e << YAML::Key << "message" << YAML::Value << r.message;
  e << YAML::Key << "iterations" << YAML::Value << r.iterations;
  e << YAML::Key << "options" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "tau" << YAML::Value
    << o.tau << YAML::Key << "alpha" << YAML::Value << o.alpha << YAML::Key << "epsilon" << YAML::Value << o.epsilon
    << YAML::Key << "M" << YAML::Value << o.consecutive << YAML::Key << "max_iterations" << YAML::Value
    << o.max_iterations << YAML::EndMap;
  e << YAML::Key << "placement_right_sole_in_left" << YAML::Comment("x [m], y [m], yaw [rad]") << YAML::Value
    << YAML::Flow << std::vector<double>{r.placement.x(), r.placement.y(), r.placement.z()};
  e << YAML::Key << "capture_duration_s" << YAML::Value << cap.duration_s;
  e << YAML::Key << "home_drift_rad" << YAML::Value << cap.home_drift;
  e << YAML::Key << "poses" << YAML::Value << YAML::BeginSeq;
  for (std::size_t k = 0; k < cap.samples.size(); ++k) {
    const auto has = [&](const std::vector<int>& v) { return std::find(v.begin(), v.end(), static_cast<int>(k)) != v.end(); };
    const char* status = has(r.used) ? "used" : has(r.rejected_capture) ? "refused_at_capture" : "excluded_by_tau";
    e << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << cap.samples[k].name << YAML::Key
      << "status" << YAML::Value << status << YAML::Key << "imu_disagreement_rad" << YAML::Value
      << (k < r.imu_disagreement.size() ? r.imu_disagreement[k] : NAN) << YAML::Key << "closure_residual_m"
      << YAML::Value << (k < r.closure_residual.size() ? r.closure_residual[k] : NAN);
    if (!cap.samples[k].reason.empty()) e << YAML::Key << "reason" << YAML::Value << cap.samples[k].reason;
    e << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::EndMap << YAML::EndMap;
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  f << "# Leg zero offsets from pmg_calib_zero (docs/calibration.md, \"Zero-point calibration\").\n"
    << "# Use: robot config key `zero_offsets: <this file>` (applied by pmg::ZeroOffsetBackend).\n"
    << e.c_str() << "\n";
}

void writeZeroHistoryCsv(const std::string& path, const RobotConfig& robot, const gco::LegModel& model,
                         const ZeroEstimate& r) {
  const auto idx = zeroJointIndices(model, robot);
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  f << "iteration,step";
  for (int j = 0; j < kZeroJoints; ++j) f << "," << robot.joints[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].name;
  f << "\n";
  for (std::size_t it = 0; it < r.history.size(); ++it) {
    f << it + 1 << "," << r.step_history[it];
    for (int j = 0; j < kZeroJoints; ++j) f << "," << -r.history[it](j);
    f << "\n";
  }
}

}  // namespace pmg::calib
