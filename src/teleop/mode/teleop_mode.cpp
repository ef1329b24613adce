#include "pmg/teleop/teleop_mode.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "pmg/common/config_error.hpp"

namespace pmg::teleop {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Quaternion (w, x, y, z) → rotation matrix.
Eigen::Matrix3d rotation(const std::array<double, 4>& q) noexcept {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

// Yaw of a rotation (z up): heading of its x axis in the horizontal plane [rad].
double yawOf(const std::array<double, 4>& q) noexcept {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

// Pitch of a rotation's x axis below the horizontal (looking down is positive) [rad].
double pitchDownOf(const std::array<double, 4>& q) noexcept {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return std::asin(std::clamp(2.0 * (w * y - x * z), -1.0, 1.0));
}

double wrapAngle(double a) noexcept { return std::remainder(a, 2.0 * kPi); }

// Dead band: 0 inside ±band, continuous outside.
double shrink(double v, double band) noexcept {
  if (v > band) return v - band;
  if (v < -band) return v + band;
  return 0.0;
}

Eigen::Matrix3d yawRotation(double yaw) noexcept { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

bool inRange(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

}  // namespace

std::vector<std::pair<std::string, HandOrientation>> yamlEnumNames(HandOrientation) {
  return {{"relative", HandOrientation::kRelative}, {"absolute", HandOrientation::kAbsolute}};
}

const char* toString(ArmMode m) noexcept {
  switch (m) {
    case ArmMode::kPmg: return "pmg";
    case ArmMode::kFollowing: return "following";
    case ArmMode::kHolding: return "holding";
    case ArmMode::kReturning: return "returning";
  }
  return "?";
}

std::string TeleopConfig::validate() const {
  if (!inRange(stale_timeout_s, 0.02, 2.0)) return "teleop.stale_timeout_s: expected 0.02..2 s";
  if (!inRange(arm_hold_s, 0.0, 10.0)) return "teleop.arm_hold_s: expected 0..10 s";
  if (!inRange(arm_return_speed, 0.05, 6.0)) return "teleop.arm_return_speed: expected 0.05..6 rad/s";
  if (!inRange(position_deadband_m, 0.0, 0.5)) return "teleop.position_deadband_m: expected 0..0.5 m";
  if (!inRange(yaw_deadband_rad, 0.0, 1.0)) return "teleop.yaw_deadband_rad: expected 0..1 rad";
  for (double g : velocity_gain)
    if (!inRange(g, 0.0, 10.0)) return "teleop.velocity_gain: expected each 0..10 1/s";
  if (!inRange(height_deadband_m, 0.0, 0.5)) return "teleop.height_deadband_m: expected 0..0.5 m";
  if (!inRange(height_gain, 0.0, 3.0)) return "teleop.height_gain: expected 0..3";
  if (!inRange(pitch_deadband_rad, 0.0, 1.2)) return "teleop.pitch_deadband_rad: expected 0..1.2 rad";
  if (!inRange(pitch_gain, 0.0, 3.0)) return "teleop.pitch_gain: expected 0..3";
  if (!inRange(grip_threshold, 0.2, 0.95)) return "teleop.grip_threshold: expected 0.2..0.95";
  if (!inRange(arm_scale, 0.2, 2.0)) return "teleop.arm_scale: expected 0.2..2";
  for (double c : operator_shoulder_center_m)
    if (!inRange(c, -0.6, 0.6)) return "teleop.operator_shoulder_center_m: expected each within +-0.6 m";
  if (const std::string e = ik.validate(); !e.empty()) return "teleop.ik: " + e;
  return {};
}

TeleopMode::TeleopMode(const RobotConfig& robot, const TeleopConfig& config)
    : config_(config), ik_(std::make_unique<ArmIk>(robot, config.ik)) {
  for (int h = 0; h < 2; ++h) {
    // "Pointing forward": shoulder pitch −π/2 (the arm hangs along −z at zero), the rest zero,
    // within the joint limits.
    ArmJoints q{};
    q[0] = -kPi / 2;
    for (std::size_t k = 0; k < q.size(); ++k) q[k] = std::clamp(q[k], ik_->lower(h)[k], ik_->upper(h)[k]);
    r_fwd_[static_cast<std::size_t>(h)] = ik_->forwardKinematics(h, q).orientation.toRotationMatrix();
  }
  robot_shoulder_center_T_ = 0.5 * (ik_->shoulderPosition(0) + ik_->shoulderPosition(1));
  n_joints_ = static_cast<int>(robot.numJoints());
  for (int h = 0; h < 2; ++h)
    for (int j : ik_->jointIndices(h))
      if (j < 0 || j >= n_joints_)
        throw ConfigError(robot.source_file + ": arm joint index " + std::to_string(j) + " outside the robot's " +
                          std::to_string(n_joints_) + " joints");
  for (int h = 0; h < 2; ++h) {
    r_ctrl0_H_[static_cast<std::size_t>(h)].setIdentity();
    r_hand0_T_[static_cast<std::size_t>(h)] = ik_->forwardKinematics(h, ik_->nominal(h)).orientation.toRotationMatrix();
  }
  reset();
}

TeleopMode::~TeleopMode() = default;

void TeleopMode::reset() noexcept {
  const std::uint64_t engagements = status_.engagements, stale = status_.stale_events;
  status_ = TeleopStatus{};
  status_.engagements = engagements;
  status_.stale_events = stale;
  have_sample_ = false;
  button_prev_ = false;
  stale_since_ = -1.0;
  grip_held_ = {false, false};
}

ArmPose TeleopMode::armTarget(const VrSample& s, int hand) const noexcept {
  const auto h = static_cast<std::size_t>(hand);
  const Eigen::Matrix3d r_yaw_t = yawRotation(yawOf(s.head_quat)).transpose();
  const Eigen::Vector3d head(s.head_position[0], s.head_position[1], s.head_position[2]);
  const Eigen::Vector3d hand_v(s.hand_position[h][0], s.hand_position[h][1], s.hand_position[h][2]);
  const Eigen::Vector3d p_h = r_yaw_t * (hand_v - head);
  const Eigen::Vector3d c_h(config_.operator_shoulder_center_m[0], config_.operator_shoulder_center_m[1],
                            config_.operator_shoulder_center_m[2]);
  ArmPose target;
  target.position = robot_shoulder_center_T_ + config_.arm_scale * (p_h - c_h);
  const Eigen::Matrix3d r_ctrl_h = r_yaw_t * rotation(s.hand_quat[h]);
  target.orientation = config_.orientation == HandOrientation::kAbsolute
                           ? Eigen::Quaterniond(r_ctrl_h * r_fwd_[h]).normalized()
                           : Eigen::Quaterniond(r_ctrl_h * r_ctrl0_H_[h].transpose() * r_hand0_T_[h]).normalized();
  return target;
}

const TeleopStatus& TeleopMode::updateCommand(const CommandSample& input, double now, double standing_height) noexcept {
  status_.command_override = false;
  const bool fresh = config_.enabled && input.vr_time >= 0.0 && now - input.vr_time <= config_.stale_timeout_s;
  status_.stream_fresh = fresh;
  if (fresh) {
    last_ = input.vr;
    have_sample_ = true;
    // Engage / disengage on a press of the right controller's A button.
    const bool button = (last_.buttons[kRightHand] & kVrButtonLower) != 0;
    if (button && !button_prev_) {
      if (!status_.engaged) {
        status_.engaged = true;
        ++status_.engagements;
        origin_p_ = last_.head_position;
        origin_yaw_ = yawOf(last_.head_quat);
        stale_since_ = -1.0;
      } else {
        status_.engaged = false;
      }
    }
    button_prev_ = button;
  }
  if (!status_.engaged) return status_;

  Command& c = status_.command;
  if (!fresh) {
    // Stale stream: locomotion stops at once, posture holds; after arm_hold_s teleop lets go.
    if (stale_since_ < 0.0) {
      stale_since_ = now;
      ++status_.stale_events;
    }
    if (now - stale_since_ >= config_.arm_hold_s) {
      status_.engaged = false;
      return status_;
    }
    c.vx = c.vy = c.wz = 0.0;
    status_.command_override = true;
    return status_;
  }
  stale_since_ = -1.0;
  // Locomotion: the headset's displacement in O and its yaw relative to O.
  const Eigen::Vector3d d = yawRotation(origin_yaw_).transpose() *
                            Eigen::Vector3d(last_.head_position[0] - origin_p_[0], last_.head_position[1] - origin_p_[1], 0.0);
  const double r = std::hypot(d.x(), d.y());
  const double scale = r > config_.position_deadband_m ? (r - config_.position_deadband_m) / r : 0.0;
  c.vx = config_.velocity_gain[0] * scale * d.x();
  c.vy = config_.velocity_gain[1] * scale * d.y();
  c.wz = config_.velocity_gain[2] * shrink(wrapAngle(yawOf(last_.head_quat) - origin_yaw_), config_.yaw_deadband_rad);
  // Posture: headset height change → pelvis height; looking down → forward bend.
  const double dz = shrink(last_.head_position[2] - origin_p_[2], config_.height_deadband_m);
  c.height = dz != 0.0 ? std::optional<double>(standing_height + config_.height_gain * dz) : std::nullopt;
  c.pitch = config_.pitch_gain * shrink(pitchDownOf(last_.head_quat), config_.pitch_deadband_rad);
  c.roll = 0.0;
  status_.command_override = true;
  return status_;
}

void TeleopMode::applyArms(double* q_ref, double* qd_ref, int n, double dt) noexcept {
  if (n != n_joints_) return;  // not this robot's reference (never from the controller)
  const bool fresh = status_.stream_fresh && have_sample_;
  std::array<bool, 2> follow{};
  for (int h = 0; h < 2; ++h) {
    const auto hh = static_cast<std::size_t>(h);
    const auto& idx = ik_->jointIndices(h);  // within the robot's joints (checked at setup)
    // Deadman with hysteresis (only a fresh sample changes it).
    if (fresh) {
      const double g = last_.grip[hh];
      grip_held_[hh] = grip_held_[hh] ? g >= config_.grip_threshold - 0.1 : g >= config_.grip_threshold;
    }
    const bool want = status_.engaged && fresh && grip_held_[hh] && last_.hand_valid[hh];
    ArmMode& m = status_.arm[hh];
    const ArmMode before = m;
    switch (m) {
      case ArmMode::kPmg:
        if (want) {
          for (std::size_t k = 0; k < 7; ++k) q_arm_[hh][k] = q_ref[idx[k]];
          m = ArmMode::kFollowing;
        }
        break;
      case ArmMode::kFollowing:
        if (!want) m = status_.engaged ? ArmMode::kHolding : ArmMode::kReturning;
        break;
      case ArmMode::kHolding:
        if (want) m = ArmMode::kFollowing;
        else if (!status_.engaged) m = ArmMode::kReturning;
        break;
      case ArmMode::kReturning:
        if (want) m = ArmMode::kFollowing;
        break;
    }
    follow[hh] = m == ArmMode::kFollowing;
    if (follow[hh] && before != ArmMode::kFollowing) {
      // Grip pressed: the orientation reference (relative mapping) is the controller now and
      // the robot hand where the arm is now.
      r_ctrl0_H_[hh] = yawRotation(yawOf(last_.head_quat)).transpose() * rotation(last_.hand_quat[hh]);
      r_hand0_T_[hh] = ik_->forwardKinematics(h, q_arm_[hh]).orientation.toRotationMatrix();
    }
    if (follow[hh]) status_.target_T[hh] = armTarget(last_, h);
  }
  status_.ik_time_s = 0.0;
  if (follow[0] || follow[1]) {
    const auto t0 = std::chrono::steady_clock::now();
    ik_->solve(status_.target_T, follow, q_arm_, status_.ik);
    status_.ik_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  for (int h = 0; h < 2; ++h) {
    const auto hh = static_cast<std::size_t>(h);
    const auto& idx = ik_->jointIndices(h);
    ArmMode& m = status_.arm[hh];
    if (m == ArmMode::kReturning) {
      // Ramp to the PMG arm reference; hand back once there.
      const double step = config_.arm_return_speed * dt;
      double err = 0.0;
      for (std::size_t k = 0; k < 7; ++k) {
        const double target = q_ref[idx[k]];
        q_arm_[hh][k] += std::clamp(target - q_arm_[hh][k], -step, step);
        err = std::max(err, std::fabs(target - q_arm_[hh][k]));
      }
      if (err < 1e-4) m = ArmMode::kPmg;
    }
    if (m == ArmMode::kPmg) {
      for (std::size_t k = 0; k < 7; ++k) q_prev_out_[hh][k] = q_ref[idx[k]];
      continue;
    }
    for (std::size_t k = 0; k < 7; ++k) {
      const double q = q_arm_[hh][k];
      q_ref[idx[k]] = q;
      qd_ref[idx[k]] = m == ArmMode::kHolding || dt <= 0.0 ? 0.0 : (q - q_prev_out_[hh][k]) / dt;
      q_prev_out_[hh][k] = q;
    }
  }
}

}  // namespace pmg::teleop
