#pragma once
/// @file robot_config.hpp
/// The robot configuration: the single source of truth for joint order, joint limits, default
/// standing pose, motor-level PD gains, torque limits and the motor-to-bus mapping.
/// Loaded from YAML (e.g. config/robots/g1/g1.yaml) and validated once at start-up (setup code:
/// allocates, throws pmg::ConfigError). The loop only reads the resulting immutable struct.

#include <cstddef>
#include <stdexcept>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pmg/common/config_error.hpp"

namespace pmg {

/// One actuated joint (= one motor). Units: rad, rad/s, N·m, N·m/rad, N·m·s/rad.
struct JointConfig {
  std::string name;            ///< joint name as in URDF/MJCF, e.g. "left_knee_joint"
  double lower = 0.0;          ///< position lower limit [rad]
  double upper = 0.0;          ///< position upper limit [rad], > lower
  double velocity_limit = 0;   ///< |q̇| limit [rad/s], > 0
  double torque_limit = 0;     ///< |τ| limit at the joint [N·m], > 0
  double kp = 0.0;             ///< motor-level PD stiffness [N·m/rad], ≥ 0
  double kd = 0.0;             ///< motor-level PD damping [N·m·s/rad], ≥ 0
  double default_position = 0; ///< default standing pose [rad], within [lower, upper]
  std::string bus;             ///< name of the motor bus (CAN interface), e.g. "can0"; the bus plans
                               ///< (config/hal/*.yaml) must agree (pmg::hal::bus::checkPlanAgainstRobot)
  int motor_id = 0;            ///< id of the motor driver on its bus, 1..254 (MIT-mode CAN)
  std::string mirror;          ///< name of the left/right mirror joint (itself for sagittal joints)
  int mirror_sign = 1;         ///< q_mirror = mirror_sign · q (±1)
  /// Identified actuator model of this joint (pmg_calib_dynamics output, docs/calibration.md) as
  /// the YAML text of its `actuator:` map, or "" for the ideal motor. In the file either an inline
  /// map (`actuator: {fc_Nm: 0.3, delay_s: 0.002}`) or the path of an actuator file (`actuator:
  /// calib/left_knee.actuator.yaml`, relative to the robot config). Parsed and validated by the
  /// simulator that applies it (pmg::MujocoBackend, pmg::calib::parse_actuator_block).
  std::string actuator_yaml;
  std::string actuator_source;  ///< where the block came from (file and key), for error messages
  /// How well calibration determined the block's parameters: {actuator key: uncertainty}, in the
  /// key's own unit, >= 0, only for keys the block names (pmg_calib_joints writes it, from the spread
  /// of its cross-validation fits; training sizes its domain randomisation from it). Optional key
  /// `actuator_uncertainty:` beside `actuator:`; empty when absent. Not used by the simulator.
  std::map<std::string, double> actuator_uncertainty;
  /// Encoder zero offset [rad] = encoder reading − true joint angle, |offset| ≤ 0.5 (pmg_calib_zero,
  /// docs/calibration.md). From the optional top-level `zero_offsets:` key: a map {joint_name: offset} or
  /// the path of a file with such a map under `zero_offsets:` (the `--out` file of pmg_calib_zero),
  /// relative to the robot config. 0 when absent. Applied by pmg::ZeroOffsetBackend (reading − offset,
  /// command + offset) around any HAL backend.
  double zero_offset = 0.0;
};

/// The whole robot configuration. Paths are absolute after loading.
struct RobotConfig {
  std::string source_file;     ///< the YAML file this was loaded from
  std::string name;            ///< robot model name
  std::string urdf_path;       ///< absolute path of the URDF (kinematics, KDL)
  std::string mjcf_path;       ///< absolute path of the MJCF (simulation, MuJoCo)
  std::string base_link;       ///< floating-base link, e.g. "pelvis"
  std::string left_foot_link;  ///< e.g. "left_ankle_roll_link"
  std::string right_foot_link; ///< e.g. "right_ankle_roll_link"
  std::string imu_site;        ///< MJCF site of the IMU, e.g. "imu_in_pelvis"
  double standing_base_height = 0.78;  ///< pelvis height above the ground in the default pose [m]
  std::vector<JointConfig> joints;     ///< in motor/joint order (= MJCF joint order)

  std::size_t numJoints() const { return joints.size(); }
  /// Index of a joint by name, or -1.
  int jointIndex(const std::string& joint_name) const;
  /// Default standing pose, (n) [rad].
  Eigen::VectorXd defaultPose() const;
  /// Per-joint vectors (n): lower/upper limits [rad], kp [N·m/rad], kd [N·m·s/rad], torque limit [N·m].
  Eigen::VectorXd lowerLimits() const;
  Eigen::VectorXd upperLimits() const;
  Eigen::VectorXd kp() const;
  Eigen::VectorXd kd() const;
  Eigen::VectorXd torqueLimits() const;
  /// Mirror map: index of each joint's mirror partner (n) and its sign (n).
  std::vector<int> mirrorIndex() const;
  /// Joint names in order.
  std::vector<std::string> jointNames() const;
  /// Encoder zero offsets (n) [rad] (JointConfig::zero_offset).
  Eigen::VectorXd zeroOffsets() const;
  /// The pmg::yaml validate() convention: "" if valid, else what is wrong, naming the key and the
  /// expected range, e.g. "joints[3] (left_knee_joint).kp = -1: expected 0..5000 N*m/rad".
  std::string validate() const;
};

/// Loads and validates a robot config YAML file (read with pmg::yaml, yaml_archive.hpp). Relative
/// model paths are resolved against the file's folder. @throws ConfigError naming the file, line, key
/// and expected range on any problem (unknown key, with the nearest valid key; missing key; wrong
/// type; non-finite number; limits out of order; default pose outside limits; negative gains;
/// duplicate joint; mirror map not an involution; duplicate motor id on a bus; model file missing).
RobotConfig loadRobotConfig(const std::string& yaml_path);

/// The text of @p robot's config file (robot.source_file) with its `urdf:` and `mjcf:` values
/// replaced by robot.urdf_path / robot.mjcf_path (absolute after loading), so that a copy written
/// elsewhere, edited or pointing at another model file (a composed scene), loads like the original.
/// @throws ConfigError if the file cannot be read.
std::string robotConfigTextWithModelPaths(const RobotConfig& robot);

/// Validates an already-filled config. @throws ConfigError "<source_file>: <config.validate()>".
void validate(const RobotConfig& config);

/// Reads a file of encoder zero offsets into robot joint order (n; 0 for joints not named): either a
/// bare map {joint_name: offset_rad} or a pmg_calib_zero result (`zero_offsets: {...}` plus its
/// `calibration`, `poses`, ... keys). Every offset finite with |offset| <= 0.5 rad.
/// @throws ConfigError naming the file, line and key (an unknown joint with the nearest joint name).
std::vector<double> loadZeroOffsetFile(const std::string& path, const RobotConfig& robot);

}  // namespace pmg
