#pragma once
/// @file reality.hpp
/// A "reality" for the SIL robot: the hidden truth that the calibration tools must find (issue 15,
/// docs/calibration.md "A real robot with a hidden truth"). `pmg_sil --reality REALITY.yaml` plays
/// the real robot with these effects; the tools reach it only through the motor bus, never through
/// this file. `pmg_reality_draw` writes random plausible ones.
///
/// File format (every key optional; unknown keys, unknown joints and unknown links are errors;
/// SI units):
/// ```yaml
/// joints:                # per joint: an actuator block (the robot config's `actuator:` format,
///   left_knee_joint: {fc_Nm: 1.2, delay_s: 0.006}          # pmg/calib/actuator_yaml.hpp)
///   right_hip_pitch_joint: {kp_scale: 0.85, armature_kgm2: 0.03}
/// zero_offsets: {left_ankle_pitch_joint: 0.03}   # encoder reading - true angle [rad], |x| <= 0.5
/// links: {torso_link: {mass_scale: 1.08}}         # model errors: body mass (and inertia) x scale
/// ```
/// Setup code: allocates and throws pmg::ConfigError naming the file, key and expected range.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg::hal {

/// A model error of one body of the MJCF.
struct LinkError {
  double mass_scale = 1.0;  ///< body mass and rotational inertia are multiplied by this, in [0.5, 2]
  template <class A>
  void Serialize(A* a) {
    a->Visit("mass_scale", &mass_scale, "body mass (and inertia) x scale, 0.5..2");
  }
  std::string validate() const;  ///< "" or "mass_scale = x: expected 0.5..2"
};

/// The hidden truth of one SIL robot.
struct Reality {
  std::map<std::string, calib::ActuatorBlock> joints;  ///< joint name -> its true actuator
  std::map<std::string, double> zero_offsets;          ///< joint name -> encoder reading - true angle [rad]
  std::map<std::string, LinkError> links;              ///< MJCF body name -> model error
  std::string source;                                  ///< the file it was read from ("" if drawn)

  template <class A>
  void Serialize(A* a) {
    a->Visit("joints", &joints, "{joint: actuator block} (docs/calibration.md)");
    a->Visit("zero_offsets", &zero_offsets, "{joint: encoder reading - true angle [rad]}");
    a->Visit("links", &links, "{body: {mass_scale}}");
  }
  /// Joints with an actuator block or a non-zero zero offset, in the robot config's order.
  std::vector<std::string> affectedJoints(const RobotConfig& robot) const;
};

/// Reads and checks a reality file against @p robot: joint names must be the robot's (an unknown
/// one is named with the nearest), every actuator block valid (ActuatorBlock::validate; backlash is
/// refused, the G1 SIL has no rotor bodies), |zero offset| <= 0.5 rad, mass scales in [0.5, 2].
/// Link names are checked against the MJCF when applied (MujocoBackend).
/// @throws pmg::ConfigError "<file>: <key path>: <problem>".
Reality loadReality(const std::string& path, const RobotConfig& robot);

/// Applies @p reality to a SIL: each joint's actuator block replaces the robot config's
/// (`robot->joints[i].actuator_yaml`), the zero offsets become the backend's hidden encoder
/// offsets (added to any already there), the link errors its body mass scales.
void applyReality(const Reality& reality, RobotConfig* robot, MujocoBackendOptions* options);

/// What pmg_reality_draw may draw. Effects per affected joint: exactly one of the catalogue
/// entries below (so that "the effect named first" is well defined), magnitude uniform in its range.
/// The ranges (docs/calibration.md, "Drawn realities") come from the real actuator logs, scaled to
/// the G1 leg motors (torque limits 50-139 N m), and from the catalogue's identifiability:
///  - coulomb_friction fc_Nm in [1.0, 3.0] N m: the real logs identify 0.43-0.63 N m on 6-9 N m
///    motors (AK80-6, STS3250), 5-10 % of peak; 1-3 N m is 1-6 % of the G1 legs' peaks;
///  - viscous_friction fv_Nms_per_rad in [0.5, 2.0] N m s/rad (0.3-1.3 x the legs' PD kd);
///  - transport_delay delay_s in [0.004, 0.012] s (2-6 driver periods of 2 ms: a delay shorter
///    than the driver period is not a transport delay);
///  - armature armature_kgm2 in [0.02, 0.05] kg m^2 (the SIL's nominal is 0.01: the G1's reflected
///    rotor inertias are 0.01-0.04);
///  - pd_gain kp_scale in [0.75, 0.88] or [1.12, 1.25] (firmware gain errors of 12-25 %).
/// Zero offsets: 2-4 leg joints (independent of the effects), |offset| in [0.01, 0.05] rad, random
/// sign. Links (when enabled): torso_link mass_scale in [0.95, 1.10] with probability 1/2.
struct RealityDrawOptions {
  int joints = 0;       ///< affected leg joints (effects), 0 = draw 4..6; at most 12
  int zero_offsets = -1;  ///< leg joints with a zero offset, -1 = draw 2..4; at most 12
  bool links = true;    ///< may draw a torso mass error
};
/// The catalogue entries a drawn reality uses (RealityDrawOptions), in draw order.
const std::vector<std::string>& drawableEffects();
/// The catalogue entry of a drawn joint's block ("coulomb_friction", ..., "pd_gain"), "" if none
/// of them (used by tests to compare with what a calibration names).
std::string drawnEffectName(const calib::ActuatorBlock& block);

/// Draws a random plausible reality for the 12 leg joints of @p robot (the first 12 joints, the
/// G1's legs), deterministic in @p seed. @throws ConfigError if the options are out of range.
Reality drawReality(const RobotConfig& robot, std::uint64_t seed, const RealityDrawOptions& options = {});

/// Writes @p reality as a reality file, preceded by @p comment lines (prefixed with "# ").
/// @throws pmg::ConfigError if the file cannot be written.
void writeReality(const std::string& path, const Reality& reality, const std::string& comment);

}  // namespace pmg::hal
