#pragma once
/// @file config_error.hpp
/// pmg::ConfigError, the one exception type of every configuration loader (robot config, controller
/// config, bus plans, GCO options, clips, command scripts, calibration files, policy contracts).

#include <stdexcept>

namespace pmg {

/// Error raised by every configuration loader. what() names the file (and line where known), the key
/// and the expected range, e.g. "g1.yaml:27: joints[3] (left_knee_joint).kp = -1: expected 0..5000".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace pmg
