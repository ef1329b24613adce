#pragma once
// Upper-body gravity compensation and damping (beyond the paper; docs/controller.md "Upper-body
// gravity compensation").
//
// The actor commands the legs only; the waist and the arms are joint PD loops on their references
// (PMG's, or the teleop arm IK's), with the gains of the robot config (the G1's waist pitch: kp 80
// N m/rad, kd 3 N m s/rad). Crouched and bent with both arms forward and loaded, the upper body's
// weight bends the waist pitch 0.2 rad beyond its reference, onto its 0.52 rad stop, and the loop
// (damping ratio about 0.2 with the upper body's inertia) swings ±0.05-0.1 rad at the gait's
// frequency while the robot stands up or walks with a box (docs/teleop.md, "The waist under a
// load"). This stage adds a feed-forward torque to each configured joint:
//
//   tau_ff_j = gravity_scale * g_j(q, R_WB) - damping * qd_j,   clamped to ±min(max_torque, torque limit)
//
// g_j is the joint's generalised gravity force (MuJoCo's mj_rne with zero velocity and zero
// acceleration on the robot's own MJCF): the torque that holds everything beyond joint j against
// gravity in the measured configuration, with the floating base's orientation from the IMU. The
// joint PD law of the motor driver then only corrects the remaining error
// (tau = kp (q_ref - q) + kd (qd_ref - qd) + tau_ff, include/pmg/hal/bus/motor_protocol.hpp).
// Loads the model does not know (a carried box) are not compensated.
//
// Off unless a controller config enables it (`upper_body:`). The teleoperation config does, with an
// actor trained with the same feed-forward in its environment (pmg-train --upper-body-ff; its
// contract's pmg.upper_body_ff must match `enabled`, or the controller refuses the actor). Under an
// actor trained without it, it held the waist but carried no more boxes (docs/controller.md). The
// legs are refused: their torque belongs to the actor's contract.
//
// Real-time: apply() is noexcept and allocation-free (MuJoCo's kinematics and RNE work in the
// preallocated mjData). Setup allocates and throws.
#include <array>
#include <string>
#include <vector>

#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/types.hpp"

namespace pmg {

/// `upper_body:` of a controller config.
struct UpperBodyConfig {
  bool enabled = false;
  /// Joints that get the feed-forward, robot joint names; not leg joints (the actor's), no duplicates.
  std::vector<std::string> joints{"waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint"};
  /// Share of the model's gravity torque fed forward, [0, 1.5].
  double gravity_scale = 1.0;
  /// Extra viscous damping through the feed-forward [N m s/rad], [0, 50], on top of the robot
  /// config's kd (computed at the loop rate and held by the HAL between ticks).
  double damping = 0.0;
  /// Bound on |tau_ff| [N m], (0, 300]; each joint's torque_limit bounds it too.
  double max_torque = 40.0;
  /// After reset() (the loop entering active) the feed-forward fades in linearly over this long
  /// [s], [0, 10], so that engaging never steps a joint's torque; 0: at once.
  double ramp_s = 1.0;
  /// "" if valid, else "upper_body.<field> = <value>: expected <range>".
  std::string validate() const;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, "feed the upper body's gravity torque forward (docs/controller.md)");
    a->Visit("joints", &joints, "joints that get the feed-forward (not the actor's legs)");
    a->Visit("gravity_scale", &gravity_scale, "share of the model's gravity torque, 0..1.5");
    a->Visit("damping", &damping, "extra viscous damping through the feed-forward, 0..50 N*m*s/rad");
    a->Visit("max_torque", &max_torque, "bound on |tau_ff|, (0, 300] N*m");
    a->Visit("ramp_s", &ramp_s, "fade-in after the loop enters active, 0..10 s");
  }
};

/// The feed-forward stage (see the file comment). One per controller.
class UpperBodyCompensation {
 public:
  /// Setup: compiles @p robot's MJCF (robot.mjcf_path), maps config.joints to it and finds the
  /// IMU site on the floating base. @p leg_joints are refused. @throws ConfigError naming
  /// `upper_body.joints[i]` (unknown joint, leg joint, duplicate), or the MJCF (no free joint, IMU
  /// site not on the floating base). @p config must be valid (validate()).
  UpperBodyCompensation(const RobotConfig& robot, const UpperBodyConfig& config,
                        const std::vector<std::string>& leg_joints);
  ~UpperBodyCompensation();
  UpperBodyCompensation(const UpperBodyCompensation&) = delete;
  UpperBodyCompensation& operator=(const UpperBodyCompensation&) = delete;

  /// Gravity torques g_j [N m] of the configured joints (config order) for the measured joint
  /// positions state.motors[i].q (robot joint order) and base orientation state.imu.quat_wxyz
  /// (world <- IMU). Without a valid IMU the base is taken upright. noexcept, allocation-free.
  const std::vector<double>& gravity(const LowState& state) noexcept;

  /// Starts the fade-in (config.ramp_s): call when the loop enters active.
  void reset() noexcept { elapsed_s_ = 0.0; }

  /// Writes tau_ff (file comment), times the fade-in min(1, time since reset() / ramp_s), into
  /// @p command's motors of the configured joints (overwriting their tau_ff); @p dt [s] is the
  /// tick period. noexcept, allocation-free.
  void apply(const LowState& state, LowCommand& command, double dt) noexcept;

  const UpperBodyConfig& config() const noexcept { return config_; }
  /// Robot joint index of each configured joint.
  const std::vector<int>& jointIndices() const noexcept { return joint_index_; }
  /// The last tau_ff written per configured joint [N m].
  const std::vector<double>& lastFeedForward() const noexcept { return tau_ff_; }

 private:
  UpperBodyConfig config_;
  MjModelPtr model_;
  MjDataPtr data_;
  std::vector<int> qpos_adr_;    // per robot joint
  std::vector<int> joint_index_; // per configured joint: robot joint index
  std::vector<int> dof_adr_;     // per configured joint
  std::vector<double> limit_;    // per configured joint: min(max_torque, torque_limit)
  std::vector<double> gravity_;  // per configured joint
  std::vector<double> tau_ff_;   // per configured joint
  std::vector<mjtNum> rne_;      // nv
  int base_qpos_ = 0;
  double elapsed_s_ = 0.0;  // since reset()
  std::array<mjtNum, 4> q_site_inv_{1, 0, 0, 0};  // IMU site orientation in the base frame, inverted
};

}  // namespace pmg
