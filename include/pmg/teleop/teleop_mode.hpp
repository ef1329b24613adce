#pragma once
/// @file teleop_mode.hpp
/// Teleoperation mode of the 100 Hz loop (issue 13, docs/teleop.md): the VR stream
/// (pmg::teleop::VrSample, from `pmg_vr_bridge` over LCM) drives the robot as in the PMG paper
/// (Fig. 1e): the headset commands locomotion and posture, the hand controllers command the arms
/// through inverse kinematics, and the policy keeps balancing the legs (limb separation).
///
/// Frames:
///  - V: the VR floor frame of the stream (x forward, y left, z up; vr_sample.hpp);
///  - O: the operator's origin frame, captured at engage time: V translated to the headset's
///    position and rotated by its yaw then (z stays vertical);
///  - H: the headset's current yaw frame (V rotated by the headset's current yaw, at its position);
///  - T: the robot's torso_link frame (x forward, y left, z up), the frame of the arm targets.
///
/// Mapping (all gains, dead bands and timeouts in TeleopConfig, the controller config's
/// `teleop:` block):
///  - engage/disengage: a press of the right controller's A button (kVrButtonLower) toggles;
///    engaging captures O. Only while the loop is active and the stream is fresh.
///  - locomotion: headset displacement d_O (x, y) beyond a radial dead band → v_x, v_y
///    [m/s] = gain · (|d| − dead band) · d/|d|; headset yaw relative to O beyond its dead band → ω.
///    The headset acts like a joystick that the operator steps onto.
///  - posture: headset height change beyond its dead band → pelvis height command (standing
///    height + gain · Δz); headset pitch (looking down is positive) beyond its dead band → torso
///    pitch (forward bend). Roll stays 0.
///  - arms: while a hand's grip is held (deadman, squeeze ≥ grip_threshold, hysteresis 0.1) its
///    controller pose relative to the headset, in H, is scaled to the robot's arm reach:
///    p_T = c_T + arm_scale · (p_H − c_H), with c_H the operator's shoulder centre relative to the
///    headset and c_T the robot's (the mid-point of the two shoulder joints in T). The
///    orientation, `orientation: relative` (default): the controller's rotation since the grip
///    was pressed, in H, is applied to the robot hand's orientation at that moment,
///    R_T = (R_H R_H0ᵀ) R_T0, so squeezing never twists the wrist and a Quest grip frame need not
///    match the robot hand's; `absolute`: R_T = R_H · R_fwd with R_fwd the robot hand's
///    orientation when the arm points forward (a controller pointing forward makes the hand point
///    forward). The arm's 7 joints come from pmg::teleop::ArmIk (KDL chains, hard joint limits,
///    capsules).
///  - deadman and watchdogs, per arm: released grip → the arm holds its last solution; a stale
///    stream (older than stale_timeout_s) → locomotion command zero at once, arms hold; after
///    arm_hold_s of staleness (or on disengage) the arms ramp to the PMG arm reference at
///    arm_return_speed and teleop disengages (re-engage with A). Arms are never left moving.
///  - continuity: the loop's ReferenceRateLimiter bounds every reference after this stage (the
///    same 6 rad/s as the rest of the controller), so engaging, disengaging or a jump of the
///    stream never jumps a joint reference.
/// update*() are noexcept and allocation-free (tested); construction allocates (setup).

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pmg/common/robot_config.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/teleop/arm_ik.hpp"
#include "pmg/teleop/vr_sample.hpp"

namespace pmg::teleop {

/// How the hand controllers' orientation maps onto the robot hands (file comment).
enum class HandOrientation : std::uint8_t { kRelative, kAbsolute };
std::vector<std::pair<std::string, HandOrientation>> yamlEnumNames(HandOrientation);

/// Parameters of the teleoperation mode (controller config `teleop:`; units in the names).
struct TeleopConfig {
  bool enabled = false;               ///< accept the VR stream at all
  double stale_timeout_s = 0.25;      ///< a VR sample older than this: stream stale [s]
  double arm_hold_s = 1.0;            ///< stale or disengaged: arms hold this long, then return [s]
  double arm_return_speed = 0.8;      ///< speed of the return to the PMG arm reference [rad/s]
  double position_deadband_m = 0.05;  ///< radial dead band of the headset displacement [m]
  double yaw_deadband_rad = 0.10;     ///< dead band of the headset yaw [rad]
  std::array<double, 3> velocity_gain{1.5, 1.5, 1.5};  ///< v_x, v_y per m [1/s]; ω per rad [1/s]
  double height_deadband_m = 0.03;    ///< dead band of the headset height change [m]
  double height_gain = 1.0;           ///< pelvis height change per headset height change [-]
  double pitch_deadband_rad = 0.25;   ///< dead band of the headset pitch (looking down) [rad]
  double pitch_gain = 0.8;            ///< torso pitch per headset pitch beyond the dead band [-]
  double grip_threshold = 0.6;        ///< squeeze that holds the deadman [0, 1]
  double arm_scale = 0.7;             ///< robot / operator arm-reach ratio [-]
  /// The operator's shoulder centre relative to the headset, frame H [m].
  std::array<double, 3> operator_shoulder_center_m{-0.08, 0.0, -0.25};
  HandOrientation orientation = HandOrientation::kRelative;  ///< hand orientation mapping
  ArmIkOptions ik;                    ///< the arm IK's tuning (arm_ik.hpp)

  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, "accept the VR teleoperation stream (PMG_VR_POSE)");
    a->Visit("stale_timeout_s", &stale_timeout_s, "VR sample age that makes the stream stale, 0.02..2 s");
    a->Visit("arm_hold_s", &arm_hold_s, "stale/disengaged: arms hold this long, 0..10 s");
    a->Visit("arm_return_speed", &arm_return_speed, "arm return speed to the PMG reference, 0.05..6 rad/s");
    a->Visit("position_deadband_m", &position_deadband_m, "headset displacement dead band, 0..0.5 m");
    a->Visit("yaw_deadband_rad", &yaw_deadband_rad, "headset yaw dead band, 0..1 rad");
    a->Visit("velocity_gain", &velocity_gain, "[v_x, v_y per m; yaw rate per rad], each 0..10 1/s");
    a->Visit("height_deadband_m", &height_deadband_m, "headset height dead band, 0..0.5 m");
    a->Visit("height_gain", &height_gain, "pelvis height per headset height, 0..3");
    a->Visit("pitch_deadband_rad", &pitch_deadband_rad, "headset pitch dead band, 0..1.2 rad");
    a->Visit("pitch_gain", &pitch_gain, "torso pitch per headset pitch, 0..3");
    a->Visit("grip_threshold", &grip_threshold, "deadman squeeze, 0.2..0.95");
    a->Visit("arm_scale", &arm_scale, "robot/operator arm reach, 0.2..2");
    a->Visit("operator_shoulder_center_m", &operator_shoulder_center_m,
             "operator's shoulder centre relative to the headset, headset yaw frame [m], each within +-0.6");
    a->Visit("orientation", &orientation, "hand orientation mapping: relative | absolute");
    a->Visit("ik", &ik, "arm IK tuning (include/pmg/teleop/arm_ik.hpp)");
  }
  /// Empty when valid, else "teleop.<field>: expected ...".
  std::string validate() const;
};

/// Where an arm's reference comes from.
enum class ArmMode : std::uint8_t {
  kPmg = 0,     ///< the PMG generator's arm reference (teleop not in control of this arm)
  kFollowing,   ///< IK of the hand controller (grip held)
  kHolding,     ///< the last solution (grip released, or stream stale)
  kReturning,   ///< ramping to the PMG arm reference
};
const char* toString(ArmMode m) noexcept;

/// What the teleop stage decided this tick.
struct TeleopStatus {
  bool engaged = false;        ///< the headset drives locomotion/posture
  bool stream_fresh = false;   ///< a VR sample younger than stale_timeout_s
  bool command_override = false;  ///< `command` replaces the other sources this tick
  Command command;             ///< the headset's command (heading frame; see file comment)
  std::array<ArmMode, 2> arm{ArmMode::kPmg, ArmMode::kPmg};
  std::array<ArmIkResult, 2> ik{};   ///< of the arms that followed this tick
  std::array<ArmPose, 2> target_T{};  ///< arm targets (frame T) of the arms that followed
  double ik_time_s = 0.0;      ///< wall time of this tick's IK solve (both arms) [s]
  std::uint64_t engagements = 0;      ///< engage events so far
  std::uint64_t stale_events = 0;     ///< fresh → stale transitions while engaged
};

class TeleopMode {
 public:
  /// Setup: builds the arm IK from @p robot with config.ik (throws ConfigError on a bad robot
  /// model); @p config must be valid (validate()).
  TeleopMode(const RobotConfig& robot, const TeleopConfig& config);
  ~TeleopMode();
  TeleopMode(const TeleopMode&) = delete;
  TeleopMode& operator=(const TeleopMode&) = delete;

  /// Forgets engagement and arm states (every arm back to kPmg); call when the loop leaves or
  /// enters kActive.
  void reset() noexcept;

  /// Step 1 of a tick, before the generator: reads the newest VR sample of @p input (received at
  /// input.vr_time, controller clock) at controller time @p now [s]; @p standing_height [m] is
  /// the "no height command" height. Returns the status; when status.command_override the loop
  /// uses status.command instead of the other sources' command.
  const TeleopStatus& updateCommand(const CommandSample& input, double now, double standing_height) noexcept;

  /// Step 2, after the generator: overrides the arm joints of @p q_ref / @p qd_ref (robot joint
  /// order, n entries; the PMG reference in, the reference to send out) for every arm that teleop
  /// controls, solving the IK for the arms that follow. @p dt [s] is the tick period. @p n must be
  /// the robot's joint count (else nothing is changed).
  void applyArms(double* q_ref, double* qd_ref, int n, double dt) noexcept;

  const TeleopStatus& status() const noexcept { return status_; }
  const TeleopConfig& config() const noexcept { return config_; }
  const ArmIk& ik() const noexcept { return *ik_; }
  /// The arm target of hand @p hand from VR sample @p s (frame T, before workspace clamping),
  /// with the orientation mapping of the config (relative: against the grip-press reference).
  ArmPose armTarget(const VrSample& s, int hand) const noexcept;

 private:
  TeleopConfig config_;
  std::unique_ptr<ArmIk> ik_;
  TeleopStatus status_;
  VrSample last_{};
  bool have_sample_ = false;
  bool button_prev_ = false;
  double stale_since_ = -1.0;
  // origin O
  std::array<double, 3> origin_p_{};
  double origin_yaw_ = 0.0;
  // arms
  std::array<bool, 2> grip_held_{};
  std::array<ArmJoints, 2> q_arm_{};
  std::array<ArmJoints, 2> q_prev_out_{};
  std::array<Eigen::Matrix3d, 2> r_fwd_;
  std::array<Eigen::Matrix3d, 2> r_ctrl0_H_;   // relative orientation: controller in H at grip press
  std::array<Eigen::Matrix3d, 2> r_hand0_T_;   // ... and the robot hand in T then
  Eigen::Vector3d robot_shoulder_center_T_ = Eigen::Vector3d::Zero();
  int n_joints_ = 0;
};

}  // namespace pmg::teleop
