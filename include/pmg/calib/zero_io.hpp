#pragma once
/// @file zero_io.hpp
/// Files of the zero-point calibration (pmg_calib_zero): injected offsets, the result YAML, the
/// convergence history. Offsets in files are encoder zero offsets, reading − true angle [rad]
/// (= −z of pmg::calib::ZeroEstimate), keyed by the robot config's joint names.

#include <string>
#include <vector>

#include "pmg/calib/zero_calibration.hpp"
#include "pmg/common/robot_config.hpp"

namespace pmg::calib {

/// Uniform random offsets in [−max_offset, max_offset] on the 12 leg joints (std::mt19937 with @p seed),
/// zero elsewhere; robot joint order (n). For SIL tests and demos.
std::vector<double> randomLegOffsets(const RobotConfig& robot, const gco::LegModel& model, unsigned seed,
                                     double max_offset);

/// Reads `{joint_name: value, ...}` (or a pmg_calib_zero result file with a top-level `zero_offsets:`
/// map) into a robot-order vector (n, zeros for joints not named); = pmg::loadZeroOffsetFile().
/// @throws ConfigError naming the file, line and the unknown joint (with the nearest joint name) or
/// key, or the non-finite / |value| > 0.5 rad entry.
std::vector<double> loadJointValues(const std::string& path, const RobotConfig& robot);

/// Writes the result: `zero_offsets: {joint: offset}` (the form loadJointValues and the robot config's
/// optional `zero_offsets:` key read) plus a `calibration:` block (converged, iterations, options, poses used /
/// refused / excluded, per-pose IMU disagreement). @throws std::runtime_error if the file cannot be written.
void writeZeroResult(const std::string& path, const RobotConfig& robot, const gco::LegModel& model,
                     const ZeroEstimate& result, const ZeroCapture& capture, const ZeroEstimatorOptions& options);

/// Convergence history CSV: `iteration,step,<joint offsets...>` (offset = −z per iteration).
void writeZeroHistoryCsv(const std::string& path, const RobotConfig& robot, const gco::LegModel& model,
                         const ZeroEstimate& result);

}  // namespace pmg::calib
