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
///   kt_scale: 1.0              # delivered torque / commanded torque (torque constant)
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
#include "pmg/common/yaml_archive.hpp"

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

  /// Fields for pmg::yaml (yaml_archive.hpp): the keys of the block format above.
  template <class A>
  void Serialize(A* a) {
    a->Visit("armature_kgm2", &armature_kgm2, "rotor inertia at the joint [kg m^2]");
    a->Visit("kp_scale", &kp_scale, "multiplies the PD stiffness");
    a->Visit("kd_scale", &kd_scale, "multiplies the PD damping");
    a->Visit("rate_hz", &params.rate_hz, "driver PD rate [Hz] (0 = every physics step)");
    a->Visit("delay_s", &params.delay_s, "command transport delay [s]");
    a->Visit("kt_scale", &params.kt_scale, "delivered / commanded torque (torque constant)");
    a->Visit("offset_rad", &params.offset_rad, "encoder reading - true angle [rad]");
    a->Visit("torque_limit_Nm", &params.torque_limit_Nm, "torque saturation [N m] (.inf = none)",
             yaml::kAllowNonFinite);
    a->Visit("tau_stall_Nm", &params.tau_stall_Nm, "torque-speed envelope [N m] (0 = off)");
    a->Visit("w_max_rad_per_s", &params.w_max_rad_per_s, "no-load speed [rad/s]");
    a->Visit("fc_Nm", &params.fc_Nm, "Coulomb friction [N m]");
    a->Visit("fs_Nm", &params.fs_Nm, "break-away torque [N m] (0 = fc_Nm)");
    a->Visit("vs_rad_per_s", &params.vs_rad_per_s, "Stribeck velocity [rad/s]");
    a->Visit("kl", &params.kl, "load-dependent friction coefficient");
    a->Visit("fv_Nms_per_rad", &params.fv_Nms_per_rad, "viscous friction [N m s/rad]");
    a->Visit("backlash_gap_rad", &params.backlash_gap_rad, "dead-zone width [rad]");
  }
};

/// Parses the map under an `actuator:` key (pass the map itself) with pmg::yaml. `where` names the
/// file/section for error messages (the node's own line numbers are not used: it may come from
/// re-parsed text). Unknown keys are an error naming the nearest valid key (typos must not silently
/// disable an effect); non-finite numbers are refused except torque_limit_Nm: .inf.
/// @throws pmg::ConfigError.
ActuatorBlock parse_actuator_block(const YAML::Node& map, const std::string& where);
/// The block as a YAML map (only non-default effects, plus rate and limit).
YAML::Node actuator_block_to_yaml(const ActuatorBlock& block);

/// Reads `path` and parses its top-level `actuator:` map (the only key). @throws pmg::ConfigError
/// naming the file and line.
ActuatorBlock load_actuator_file(const std::string& path);
/// Writes `{actuator: block}` to `path`, preceded by `comment` lines (prefixed with "# ").
void write_actuator_file(const std::string& path, const ActuatorBlock& block, const std::string& comment);

/// Converts a calibration report parameter map (FittedModel::params keys) into a block, with the
/// rig's driver rate and torque limit where the map has none.
ActuatorBlock actuator_block_from_params(const RigConfig& rig, const std::map<std::string, double>& params);

}  // namespace pmg::calib
