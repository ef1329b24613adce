#pragma once
/// @file contract.hpp
/// The policy contract: what an exported actor (ONNX) assumes about the robot and the controller.
///
/// The contract travels inside the ONNX model as YAML text under the custom metadata key
/// `pmg.contract` (ONNX `metadata_props`). training/pmg_train/contract.py writes it;
/// docs/policy.md documents every field. At load, pmg::policy::PolicyRunner parses it
/// (parseContract) and compares it with the robot configuration (checkContract); any mismatch
/// throws ContractError naming the file and the field, so a wrong policy never starts.
///
/// Units: SI. Angles [rad], gains kp [N*m/rad], kd [N*m*s/rad], periods [s]. Joint vectors are
/// in the robot's joint order (`joint_names`) unless a field says "actuated order" (the order of
/// `actuated_joints`, which is also the order of the actor's output).

#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmg {
struct RobotConfig;  // include/pmg/common/robot_config.hpp
}

namespace pmg::policy {

/// Contract format version this code reads (`version` field).
inline constexpr int kContractVersion = 1;
/// ONNX metadata key that holds the contract YAML.
inline constexpr const char* kContractMetadataKey = "pmg.contract";

/// Thrown at load time (never in the loop) when a contract is malformed or does not match the
/// robot. what() = "<source>: <field>: <problem>"; field() returns the field path alone,
/// e.g. "kp[3] (left_knee_joint)".
class ContractError : public std::runtime_error {
 public:
  ContractError(const std::string& source, const std::string& field, const std::string& problem);
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

/// One term of an observation frame. The controller supplies `size` raw values in SI units;
/// the network sees raw * scale (element-wise), then clipped to ±ObservationLayout::clip.
struct ObservationTerm {
  std::string name;          ///< e.g. "base_ang_vel_B", "joint_pos_rel" (docs/policy.md lists them)
  int size = 0;              ///< number of values (> 0)
  std::vector<float> scale;  ///< (size x 1) multiplier per value (a scalar in YAML is broadcast)
};

/// Layout of the actor input: history_length frames of the concatenated terms.
struct ObservationLayout {
  std::vector<ObservationTerm> terms;  ///< in frame order
  int history_length = 1;              ///< frames stacked, newest first (>= 1)
  float clip = 100.0f;                 ///< |scaled value| limit (> 0)
  /// Values per frame (sum of term sizes).
  int frameSize() const noexcept;
  /// Actor input size = frameSize() * history_length.
  int size() const noexcept;
};

/// Actor output -> joint position targets: q_des[i] = offset[i] + scale[i] * clamp(a[i], ±clip).
struct ActionSpec {
  std::vector<double> scale;   ///< (n_act x 1) [rad per unit action], actuated order
  std::vector<double> offset;  ///< (n_act x 1) [rad], actuated order (usually the default pose)
  float clip = 10.0f;         ///< |a| limit before scaling [unitless] (> 0)
};

/// A stored observation -> raw actor output pair that the runner re-computes at load.
struct ReferencePair {
  std::vector<float> obs;     ///< (ObservationLayout::size() x 1), already scaled
  std::vector<float> action;  ///< (n_act x 1), raw network output (before clip/scale)
};

/// The parsed contract (immutable after load).
struct PolicyContract {
  int version = 0;
  std::string robot;                         ///< robot model name, informative
  std::vector<std::string> joint_names;      ///< (nj) robot joint order the policy was trained with
  std::vector<std::string> actuated_joints;  ///< (n_act) joints the actor commands, action order
  bool controls_waist = false;               ///< actor commands the waist joints too
  double control_period = 0.0;               ///< actor step period [s]
  std::vector<double> default_pose;          ///< (nj) [rad]
  std::vector<double> kp;                    ///< (nj) joint PD stiffness [N*m/rad]
  std::vector<double> kd;                    ///< (nj) joint PD damping [N*m*s/rad]
  ActionSpec action;
  ObservationLayout observation;
  /// PMG/GCO settings as flat key -> scalar text (e.g. enabled: "true", gco: "false",
  /// gait_period: "0.8"), compared with what the controller runs (checkContract).
  std::map<std::string, std::string> pmg;
  std::vector<ReferencePair> reference_pairs;  ///< at least one
};

/// Parses and structurally validates a contract (sizes consistent with each other, finite
/// numbers, positive periods/clips/sizes, no duplicate names).
/// @param yaml_text the `pmg.contract` metadata value
/// @param source    name used in error messages (the ONNX file path)
/// @throws ContractError naming the offending field
PolicyContract parseContract(const std::string& yaml_text, const std::string& source);

/// What the runner needs to know about the robot and the controller to accept a policy.
/// Filled from the robot configuration (pmg::RobotConfig, config/robots/<robot>/<robot>.yaml) by
/// makePolicyRobotSpec, plus the controller's period and PMG/GCO settings.
struct PolicyRobotSpec {
  std::string name;                      ///< robot model name (informative)
  std::vector<std::string> joint_names;  ///< (nj) robot joint order
  std::vector<double> default_pose;      ///< (nj) [rad]
  std::vector<double> kp;                ///< (nj) [N*m/rad]
  std::vector<double> kd;                ///< (nj) [N*m*s/rad]
  std::vector<std::string> leg_joints;   ///< joints the actor must command (lower body)
  std::vector<std::string> waist_joints; ///< joints the actor commands iff controls_waist
  double control_period = 0.01;          ///< controller loop period [s] (100 Hz)
  /// PMG/GCO settings the controller runs with; every key must be present in the contract's
  /// `pmg` map with an equal value (numbers within 1e-9 relative, text exactly).
  std::map<std::string, std::string> pmg;
};

/// Fills a spec from the robot configuration: joint order, default pose, kp, kd. Leg joints =
/// names containing "hip", "knee" or "ankle"; waist joints = names starting with "waist".
/// @param control_period controller loop period [s], > 0. pmg settings are left empty.
/// @throws std::invalid_argument if control_period is not > 0.
PolicyRobotSpec makePolicyRobotSpec(const RobotConfig& robot, double control_period);

/// loadRobotConfig(robot_yaml_path) (validated, throws pmg::ConfigError naming file and key)
/// followed by makePolicyRobotSpec.
PolicyRobotSpec loadPolicyRobotSpec(const std::string& robot_yaml_path, double control_period);

/// Compares a contract with the robot/controller. Numbers must match to 1e-9 relative
/// (they are copied, not re-derived); joint order exactly.
/// @throws ContractError naming the first mismatching field, both values and the joint.
void checkContract(const PolicyContract& contract, const PolicyRobotSpec& robot,
                   const std::string& source);

}  // namespace pmg::policy
