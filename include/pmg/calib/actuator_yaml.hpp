#pragma once
/// @file actuator_yaml.hpp
/// YAML reader/writer for an `actuator:` block, so that parameters identified by
/// pmg_calib_dynamics can be written into a robot config and applied by a simulator through
/// ActuatorModel. Setup code: allocates and throws std::runtime_error naming the file/key/range.
///
/// Block format (all keys optional; absent = effect off / rig default; SI units):
/// ```yaml
/// actuator:
///   armature_kgm2: 0.01        # rotor inertia at the joint (simulator's joint armature)
///   kp_scale: 1.0              # multiplies the configured PD stiffness (firmware gain scale)
///   kd_scale: 1.0              # multiplies the configured PD damping
///   rate_hz: 500               # driver PD update rate (0 = every physics step)
///   delay_s: 0.002             # transport delay of the command
///   offset_rad: 0.0            # encoder reading - true angle
///   torque_limit_Nm: 25.0      # torque saturation (.inf = none)
///   tau_stall_Nm: 0.0          # torque-speed envelope (0 = off)
///   w_max_rad_per_s: 0.0
///   fc_Nm: 0.1                 # Coulomb (kinetic) friction
///   fs_Nm: 0.0                 # break-away torque (0 = fc_Nm)
///   vs_rad_per_s: 0.1          # Stribeck velocity
///   kl: 0.0                    # load-dependent friction coefficient
///   fv_Nms_per_rad: 0.0        # viscous friction
///   backlash_gap_rad: 0.0      # dead-zone width between rotor and link
/// ```

#include <map>
#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

#include "pmg/calib/actuator_model.hpp"
#include "pmg/calib/bench_log.hpp"

namespace pmg::calib {

/// An actuator block: the ActuatorModel parameters plus what belongs to the simulator's joint
/// (armature) or to the driver configuration (gain scales).
struct ActuatorBlock {
  ActuatorParams params;
  std::optional<double> armature_kgm2;  ///< [kg·m²], >= 0 when set
  double kp_scale = 1.0;                ///< > 0
  double kd_scale = 1.0;                ///< > 0
  /// Throws std::runtime_error "<where>: actuator.<key> = <v>: expected <range>".
  void validate(const std::string& where) const;
};

/// Parses the map under an `actuator:` key (pass the map itself). `where` names the file/section
/// for error messages. Unknown keys are an error (typos must not silently disable an effect).
ActuatorBlock parse_actuator_block(const YAML::Node& map, const std::string& where);
/// The block as a YAML map (only non-default effects, plus rate and limit).
YAML::Node actuator_block_to_yaml(const ActuatorBlock& block);

/// Reads `path` and parses its top-level `actuator:` map.
ActuatorBlock load_actuator_file(const std::string& path);
/// Writes `{actuator: block}` to `path`, preceded by `comment` lines (prefixed with "# ").
void write_actuator_file(const std::string& path, const ActuatorBlock& block, const std::string& comment);

/// Converts a calibration report parameter map (FittedModel::params keys) into a block, with the
/// rig's driver rate and torque limit where the map has none.
ActuatorBlock actuator_block_from_params(const RigConfig& rig, const std::map<std::string, double>& params);

}  // namespace pmg::calib
