#include "pmg/controller/velocity_feedback.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

#include "pmg/common/config_error.hpp"

namespace pmg {

namespace {
/// R_WB of the IMU's orientation estimate, normalised; false when the IMU is invalid or its
/// quaternion is far from unit length. noexcept, no allocation.
bool imuRotation(const ImuState& imu, Eigen::Matrix3d* R_WB) noexcept {
  if (!imu.valid) return false;
  Eigen::Quaterniond q_WB(imu.quat_wxyz[0], imu.quat_wxyz[1], imu.quat_wxyz[2], imu.quat_wxyz[3]);
  const double norm = q_WB.norm();
  if (!(norm > 0.5 && norm < 1.5)) return false;
  q_WB.coeffs() /= norm;
  *R_WB = q_WB.toRotationMatrix();
  return true;
}

/// Rotation from the pelvis frame B to the heading frame H (W turned by the pelvis yaw).
Eigen::Matrix3d headingFromBody(const Eigen::Matrix3d& R_WB) noexcept {
  const double yaw = std::atan2(R_WB(1, 0), R_WB(0, 0));
  return Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_WB;
}

double tiltFromVertical(const Eigen::Matrix3d& R_WB) noexcept { return std::acos(std::clamp(R_WB(2, 2), -1.0, 1.0)); }

/// An axis's own gain at the (clamped) crouch @p c [m]: g⁺ + k⁺ c for a positive command, g⁻ + k⁻ c
/// for a negative one (CommandResponseModel).
double gainAtCrouch(const CommandResponseAxis& a, bool positive, double c) noexcept {
  return positive ? a.gain_positive + a.gain_positive_per_crouch * c : a.gain_negative + a.gain_negative_per_crouch * c;
}
}  // namespace

std::string CommandResponseModel::validate() const {
  static const char* kName[3] = {"vx", "vy", "wz"};
  for (std::size_t i = 0; i < 3; ++i) {
    const CommandResponseAxis& a = axes[i];
    const std::string at = std::string(kName[i]) + ".";
    if (!(a.gain_positive >= 0.3 && a.gain_positive <= 3.0)) return at + "gain_positive: expected 0.3..3";
    if (!(a.gain_negative >= 0.3 && a.gain_negative <= 3.0)) return at + "gain_negative: expected 0.3..3";
    for (std::size_t j = 0; j < 3; ++j) {
      const std::string idx = "[" + std::to_string(j) + "]";
      if (j == i) {
        if (a.gain_per_magnitude[j] != 0.0) return at + "gain_per_magnitude" + idx + ": expected 0 (the axis itself)";
        if (a.gain_per_command[j] != 0.0) return at + "gain_per_command" + idx + ": expected 0 (the axis itself)";
        if (a.drift[j] != 0.0) return at + "drift" + idx + ": expected 0 (the axis itself)";
        continue;
      }
      if (!(a.gain_per_magnitude[j] >= -3.0 && a.gain_per_magnitude[j] <= 3.0))
        return at + "gain_per_magnitude" + idx + ": expected -3..3";
      if (!(a.gain_per_command[j] >= -3.0 && a.gain_per_command[j] <= 3.0))
        return at + "gain_per_command" + idx + ": expected -3..3";
      if (!(a.drift[j] >= -1.0 && a.drift[j] <= 1.0)) return at + "drift" + idx + ": expected -1..1";
    }
    if (!(a.gain_positive_per_crouch >= -10.0 && a.gain_positive_per_crouch <= 10.0))
      return at + "gain_positive_per_crouch: expected -10..10 [1/m]";
    if (!(a.gain_negative_per_crouch >= -10.0 && a.gain_negative_per_crouch <= 10.0))
      return at + "gain_negative_per_crouch: expected -10..10 [1/m]";
    if (!(max_correction[i] >= 0.0 && max_correction[i] <= 1.0))
      return "max_correction[" + std::to_string(i) + "]: expected 0..1 (m/s, rad/s)";
  }
  if (!(combined_max_correction_ratio >= 0.0 && combined_max_correction_ratio <= 1.0))
    return "combined_max_correction_ratio: expected 0..1";
  for (std::size_t i = 0; i < 3; ++i)
    if (!(combined_full[i] > 0.0 && combined_full[i] <= 2.0))
      return "combined_full[" + std::to_string(i) + "]: expected (0, 2] (m/s, rad/s)";
  if (!(min_gain >= 0.3 && min_gain <= 1.0)) return "min_gain: expected 0.3..1";
  if (iterations < 1 || iterations > 50) return "iterations: expected 1..50";
  return {};
}

double CommandResponseModel::clampCrouch(double crouch_m) noexcept {
  return crouch_m > 0.0 ? std::min(crouch_m, 0.5) : 0.0;  // NaN fails the comparison: 0
}

std::array<double, 3> CommandResponseModel::achieved(const std::array<double, 3>& u, double crouch_m) const noexcept {
  const double c = clampCrouch(crouch_m);
  std::array<double, 3> v{};
  for (std::size_t i = 0; i < 3; ++i) {
    const CommandResponseAxis& a = axes[i];
    double gain = gainAtCrouch(a, u[i] >= 0.0, c);
    double drift = 0.0;
    for (std::size_t j = 0; j < 3; ++j) {
      if (j == i) continue;
      gain += a.gain_per_magnitude[j] * std::fabs(u[j]) + a.gain_per_command[j] * u[j];
      drift += a.drift[j] * u[j];
    }
    v[i] = gain * u[i] + drift;
  }
  return v;
}

double CommandResponseModel::combination(const std::array<double, 3>& u) const noexcept {
  double k = 1.0;
  for (std::size_t j = 0; j < 3; ++j) {
    const double a = std::fabs(u[j]) / combined_full[j];
    k *= a < 1.0 ? a : 1.0;  // NaN fails the comparison: counted as a full axis
  }
  return k;
}

std::array<double, 3> CommandResponseModel::invert(const std::array<double, 3>& u, double crouch_m) const noexcept {
  const double c = clampCrouch(crouch_m);
  const double shrink =
      combined_max_correction_ratio < 1.0 ? 1.0 - (1.0 - combined_max_correction_ratio) * combination(u) : 1.0;
  std::array<double, 3> bound{};
  for (std::size_t i = 0; i < 3; ++i) bound[i] = max_correction[i] * shrink;
  std::array<double, 3> x = u;
  for (int sweep = 0; sweep < iterations; ++sweep) {
    for (std::size_t i = 0; i < 3; ++i) {
      const CommandResponseAxis& a = axes[i];
      double r = u[i];
      double gain = 0.0;
      for (std::size_t j = 0; j < 3; ++j) {
        if (j == i) continue;
        r -= a.drift[j] * x[j];
        gain += a.gain_per_magnitude[j] * std::fabs(x[j]) + a.gain_per_command[j] * x[j];
      }
      gain += gainAtCrouch(a, r >= 0.0, c);
      x[i] = std::clamp(r / std::max(min_gain, gain), u[i] - bound[i], u[i] + bound[i]);
    }
  }
  return x;
}

std::string VelocityFeedbackConfig::validate() const {
  static const char* kAxis[3] = {"v_x", "v_y", "yaw rate"};
  for (std::size_t i = 0; i < 3; ++i)
    if (!(std::isfinite(ki[i]) && ki[i] >= 0.0 && ki[i] <= 20.0))
      return std::string("ki[") + std::to_string(i) + "] (" + kAxis[i] + "): expected 0..20 [1/s]";
  if (!(max_ratio >= 0.0 && max_ratio <= 2.0)) return "max_ratio: expected 0..2 (share of |u|)";
  for (std::size_t i = 0; i < 3; ++i)
    if (!(envelope_min[i] <= 0.0 && envelope_max[i] >= 0.0 && envelope_max[i] - envelope_min[i] > 0.0))
      return "envelope_min/envelope_max[" + std::to_string(i) + "]: expected min <= 0 <= max, min < max";
  for (std::size_t i = 0; i < 3; ++i)
    if (!(std::isfinite(small_command_bound[i]) && small_command_bound[i] >= 0.0 && small_command_bound[i] <= 0.5))
      return std::string("small_command_bound[") + std::to_string(i) + "] (" + kAxis[i] + "): expected 0..0.5 [m/s, rad/s]";
  for (std::size_t i = 0; i < 3; ++i)
    if (!(std::isfinite(max_velocity_headroom[i]) && max_velocity_headroom[i] >= 0.0 && max_velocity_headroom[i] <= 1.0))
      return std::string("max_velocity_headroom[") + std::to_string(i) + "] (" + kAxis[i] + "): expected 0..1 [m/s, rad/s]";
  if (!(stance_band_m > 0.0 && stance_band_m <= 0.1)) return "stance_band_m: expected (0, 0.1] m";
  if (!(odometry_time_s >= 0.0 && odometry_time_s <= 2.0)) return "odometry_time_s: expected 0..2 s";
  if (!(gate_mps > 0.0 && gate_mps <= 5.0)) return "gate_mps: expected (0, 5] m/s";
  if (!(max_rejected_s >= 0.0 && max_rejected_s <= 5.0)) return "max_rejected_s: expected 0..5 s";
  if (!(max_tilt_rad > 0.0 && max_tilt_rad <= 1.5)) return "max_tilt_rad: expected (0, 1.5] rad";
  if (!(decay_time_s > 0.0 && decay_time_s <= 5.0)) return "decay_time_s: expected (0, 5] s";
  if (!(feedforward_return_s >= 0.0 && feedforward_return_s <= 30.0))
    return "feedforward_return_s: expected 0 (decay_time_s) or (0, 30] s";
  if (!(settle_time_s >= 0.0 && settle_time_s <= 5.0)) return "settle_time_s: expected 0..5 s";
  if (!(steady_band >= 0.0 && steady_band <= 0.5)) return "steady_band: expected 0..0.5 (m/s, rad/s)";
  if (!(brake_ratio >= 0.0 && brake_ratio < 1.0)) return "brake_ratio: expected [0, 1)";
  if (!(brake_rate > 0.0 && brake_rate <= 10.0)) return "brake_rate: expected (0, 10] m/s^2";
  if (!(brake_decel > 0.0 && brake_decel <= std::min(5.0, brake_rate)))
    return "brake_decel: expected (0, min(5, brake_rate)] m/s^2";
  if (const std::string e = feedforward.validate(); !e.empty()) return "feedforward." + e;
  if (const std::string e = upset_guard.validate(); !e.empty()) return "upset_guard." + e;
  if (upset_guard.enabled && !enabled) return "upset_guard.enabled: needs velocity_feedback.enabled (the guard runs on its estimate)";
  return {};
}

std::string UpsetGuardConfig::validate() const {
  static const char* kAxis[3] = {"v_x [m/s]", "v_y [m/s]", "yaw rate [rad/s]"};
  for (std::size_t i = 0; i < 3; ++i)
    if (!(max_error[i] > 0.0 && max_error[i] <= 3.0))
      return "max_error[" + std::to_string(i) + "] (" + kAxis[i] + "): expected (0, 3]";
  if (!(trigger_s > 0.0 && trigger_s <= 5.0)) return "trigger_s: expected (0, 5] s";
  if (!(settle_velocity > 0.0 && settle_velocity <= 1.0)) return "settle_velocity: expected (0, 1] m/s";
  if (!(settle_s >= 0.0 && settle_s <= 10.0)) return "settle_s: expected [0, 10] s";
  if (!(rearm_band >= 0.0 && rearm_band <= 0.3)) return "rearm_band: expected [0, 0.3] (m/s, rad/s)";
  if (!(stance_band_m > 0.0 && stance_band_m <= 0.1)) return "stance_band_m: expected (0, 0.1] m";
  return {};
}

UpsetGuard::UpsetGuard(const UpsetGuardConfig& config) : config_(config) {
  if (const std::string e = config.validate(); !e.empty()) throw ConfigError("velocity_feedback.upset_guard." + e);
}

namespace {
VelocityFeedbackConfig guardEstimateConfig(const VelocityFeedbackConfig& feedback, const UpsetGuardConfig& guard) {
  VelocityFeedbackConfig c = feedback;
  c.stance_band_m = guard.stance_band_m;
  c.yaw_rate_gated = false;
  return c;
}
}  // namespace

UpsetGuard::UpsetGuard(const UpsetGuardConfig& config, std::shared_ptr<const gco::LegModel> legs,
                       const gco::LegJointIndex& leg_idx, const VelocityFeedbackConfig& feedback)
    : UpsetGuard(config) {
  estimator_ = std::make_unique<BaseVelocityEstimator>(std::move(legs), leg_idx, guardEstimateConfig(feedback, config));
}

UpsetGuard::~UpsetGuard() = default;

void UpsetGuard::reset() noexcept {
  off_s_ = {};
  settled_s_ = 0.0;
  latched_ = false;
  if (estimator_) estimator_->reset();
  est_ = BaseVelocityEstimate{};
}

bool UpsetGuard::update(const VelocityCommand& u, const VelocityCommand& target, const LowState& state,
                        double dt) noexcept {
  if (!config_.enabled || !estimator_) return false;
  est_ = estimator_->update(state, dt);
  return update(u, target, est_, dt);
}

bool UpsetGuard::update(const VelocityCommand& u, const VelocityCommand& target, const BaseVelocityEstimate& est,
                        double dt) noexcept {
  if (!config_.enabled) return false;
  const double v[3] = {est.v_x, est.v_y, est.yaw_rate};
  const bool valid = est.valid && std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
  if (!latched_) {
    if (!valid) return false;  // neither counts nor breaks a run
    const double cmd[3] = {u.vx, u.vy, u.wz};
    bool upset = false;
    for (std::size_t i = 0; i < 3; ++i) {
      off_s_[i] = std::fabs(cmd[i] - v[i]) > config_.max_error[i] ? off_s_[i] + dt : 0.0;
      upset = upset || off_s_[i] >= config_.trigger_s;
    }
    if (!upset) return false;
    latched_ = true;
    settled_s_ = 0.0;
    ++upsets_;
    return true;
  }
  if (valid) {
    const double s = config_.settle_velocity;
    settled_s_ = (std::fabs(v[0]) < s && std::fabs(v[1]) < s && std::fabs(v[2]) < 2.0 * s) ? settled_s_ + dt : 0.0;
  }
  const double b = config_.rearm_band;
  const bool neutral = std::fabs(target.vx) <= b && std::fabs(target.vy) <= b && std::fabs(target.wz) <= b;
  if (settled_s_ >= config_.settle_s && neutral) {
    reset();
    return false;
  }
  return true;
}

LegOdometry::LegOdometry(std::shared_ptr<const gco::LegModel> legs, const gco::LegJointIndex& leg_idx,
                         double stance_band_m)
    : kin_((legs ? legs : throw std::invalid_argument("LegOdometry: leg model is null"))),
      idx_(leg_idx),
      band_(stance_band_m) {}

LegOdometry::~LegOdometry() = default;

BaseVelocityEstimate LegOdometry::estimate(const LowState& state) noexcept {
  Eigen::Matrix3d R_WB;
  if (!imuRotation(state.imu, &R_WB)) return BaseVelocityEstimate{};
  return estimate(state, R_WB);
}

BaseVelocityEstimate LegOdometry::estimate(const LowState& state, const Eigen::Matrix3d& R_WB) noexcept {
  BaseVelocityEstimate out;
  const Eigen::Matrix3d R_HB = headingFromBody(R_WB);
  const Eigen::Vector3d w_B(state.imu.gyro[0], state.imu.gyro[1], state.imu.gyro[2]);
  const Eigen::Vector3d w_H = R_HB * w_B;
  if (!w_H.allFinite()) return out;

  std::array<Eigen::Vector3d, kNumFeet> v_f;
  std::array<double, kNumFeet> z_f{};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    gco::LegVector q, qd;
    for (int j = 0; j < gco::kLegDofs; ++j) {
      const int m = idx_[f][static_cast<std::size_t>(j)];
      if (m < 0 || m >= state.num_motors) return out;
      q[j] = state.motors[static_cast<std::size_t>(m)].q;
      qd[j] = state.motors[static_cast<std::size_t>(m)].qd;
    }
    gco::FootKinematics k;
    if (!kin_.compute(static_cast<Foot>(f), q, qd, &k)) return out;
    const Eigen::Vector3d r_H = R_HB * k.p_BS_B;
    z_f[f] = r_H.z();
    v_f[f] = -(w_H.cross(r_H) + R_HB * k.v_BS_B);
  }
  const double z_low = std::min(z_f[0], z_f[1]);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    out.foot_v_x[f] = v_f[f].x();
    out.foot_v_y[f] = v_f[f].y();
    if (z_f[f] - z_low > band_) continue;
    out.foot_in_stance[f] = true;
    sum += v_f[f];
    ++out.stance_feet;
  }
  sum /= out.stance_feet;  // at least the lower foot
  out.v_x = sum.x();
  out.v_y = sum.y();
  out.yaw_rate = w_H.z();
  out.valid = sum.allFinite() && std::isfinite(out.yaw_rate);
  return out;
}

BaseVelocityEstimator::BaseVelocityEstimator(std::shared_ptr<const gco::LegModel> legs, const gco::LegJointIndex& leg_idx,
                                             const VelocityFeedbackConfig& config)
    : odometry_(std::move(legs), leg_idx, config.stance_band_m), config_(config) {}

void BaseVelocityEstimator::reset() noexcept {
  v_ = {0.0, 0.0, 0.0};
  initialized_ = false;
  rejected_run_ = 0;
  restarts_ = 0;
  tilt_ = 0.0;
  last_leg_ = BaseVelocityEstimate{};
}

double BaseVelocityEstimator::medianInnovation(std::size_t i, int n) noexcept {
  const auto count = static_cast<std::ptrdiff_t>(n);
  std::copy(innovations_[i].begin(), innovations_[i].begin() + count, scratch_.begin());
  auto mid = scratch_.begin() + count / 2;
  std::nth_element(scratch_.begin(), mid, scratch_.begin() + count);
  if (count % 2 == 1) return *mid;
  const double upper = *mid;
  const double lower = *std::max_element(scratch_.begin(), mid);  // the largest of the lower half
  return 0.5 * (lower + upper);
}

BaseVelocityEstimate BaseVelocityEstimator::update(const LowState& state, double dt) noexcept {
  Eigen::Matrix3d R_WB;
  const bool imu_ok = imuRotation(state.imu, &R_WB);  // once per tick, for the legs and the prediction
  last_leg_ = imu_ok ? odometry_.estimate(state, R_WB) : BaseVelocityEstimate{};
  BaseVelocityEstimate& leg = last_leg_;
  // Prediction from the IMU: the specific force rotated into W plus gravity is the acceleration of
  // the IMU; in the turning heading frame H, dv_H/dt = R_HW a_W - w_z e_z x v_H.
  const double a = config_.odometry_time_s > 0.0 ? std::min(1.0, dt / config_.odometry_time_s) : 1.0;
  if (initialized_ && imu_ok) {
    tilt_ = tiltFromVertical(R_WB);
    const Eigen::Matrix3d R_HB = headingFromBody(R_WB);
    const Eigen::Vector3d a_H =
        R_HB * Eigen::Vector3d(state.imu.acc[0], state.imu.acc[1], state.imu.acc[2]) - Eigen::Vector3d(0, 0, kGravity);
    const double wz = (R_HB * Eigen::Vector3d(state.imu.gyro[0], state.imu.gyro[1], state.imu.gyro[2])).z();
    const double vx = v_[0] + (a_H.x() + wz * v_[1]) * dt, vy = v_[1] + (a_H.y() - wz * v_[0]) * dt;
    if (std::isfinite(vx) && std::isfinite(vy)) {
      v_[0] = vx;
      v_[1] = vy;
    }
    // Ungated (yaw_rate_gated false): the gyro's yaw rate low-passed on every tick.
    if (!config_.yaw_rate_gated && std::isfinite(wz)) v_[2] += a * (wz - v_[2]);
  }
  // With stance_foot_nearest and both soles in the band, the foot whose sample lies nearer the
  // prediction is the measurement (a swing foot skimming the floor is not averaged in).
  if (config_.stance_foot_nearest && initialized_ && leg.valid && leg.stance_feet == 2) {
    const double d0 = std::hypot(leg.foot_v_x[0] - v_[0], leg.foot_v_y[0] - v_[1]);
    const double d1 = std::hypot(leg.foot_v_x[1] - v_[0], leg.foot_v_y[1] - v_[1]);
    const std::size_t f = d1 < d0 ? 1 : 0;
    if (std::isfinite(leg.foot_v_x[f]) && std::isfinite(leg.foot_v_y[f])) {
      leg.v_x = leg.foot_v_x[f];
      leg.v_y = leg.foot_v_y[f];
      leg.stance_feet = 1;
      leg.foot_in_stance[1 - f] = false;
    }
  }
  // Correction by leg odometry, gated: a measurement further than gate_mps from the prediction
  // (a swing foot taken for a stance foot at touchdown or lift-off, a slipping foot, a flight
  // phase) is rejected, unless the rejections have lasted max_rejected_s (then the estimate
  // restarts from it).
  if (leg.valid) {
    const double innovation = std::hypot(leg.v_x - v_[0], leg.v_y - v_[1]);
    // Rejected for max_rejected_s: the IMU-only prediction has drifted; restart from the legs.
    const bool restart = !initialized_ || static_cast<double>(rejected_run_) * dt >= config_.max_rejected_s;
    // With restart_median, the window's samples (the rejected ones and a restart's own) are kept for
    // the median a restart takes.
    if (config_.restart_median && initialized_ && (restart || innovation > config_.gate_mps)) {
      const int slot = rejected_run_ % kRestartWindow;
      innovations_[0][slot] = leg.v_x - v_[0];
      innovations_[1][slot] = leg.v_y - v_[1];
    }
    if (restart || innovation <= config_.gate_mps) {
      if (restart && initialized_ && config_.restart_median) {
        // From the prediction shifted by the median innovation of the window: a glitch among them (a
        // lifting foot counted in stance) does not become the estimate.
        const int n = std::min(rejected_run_ + 1, kRestartWindow);
        v_[0] += medianInnovation(0, n);
        v_[1] += medianInnovation(1, n);
      } else {
        v_[0] = restart ? leg.v_x : v_[0] + a * (leg.v_x - v_[0]);
        v_[1] = restart ? leg.v_y : v_[1] + a * (leg.v_y - v_[1]);
      }
      // Gated (yaw_rate_gated, the default): the yaw rate (the gyro's) moves with the accepted
      // samples only, held while the gate rejects and taken from one sample on a restart (with the
      // median too: the integral loop's yaw gain was chosen on that; with the median there as well
      // the grid lost 4 more segments).
      if (config_.yaw_rate_gated || !initialized_) v_[2] = restart ? leg.yaw_rate : v_[2] + a * (leg.yaw_rate - v_[2]);
      if (restart && initialized_) ++restarts_;
      initialized_ = true;
      rejected_run_ = 0;
      ++accepted_;
    } else {
      ++rejected_run_;
      ++rejected_;
    }
  }
  BaseVelocityEstimate out;
  out.valid = initialized_;
  out.stance_feet = leg.stance_feet;
  out.v_x = v_[0];
  out.v_y = v_[1];
  out.yaw_rate = v_[2];
  return out;
}

VelocityFeedback::VelocityFeedback(const VelocityFeedbackConfig& config, std::shared_ptr<const gco::LegModel> legs,
                                   const gco::LegJointIndex& leg_idx, const std::array<double, 3>& max_velocity)
    : config_(config), estimator_(std::move(legs), leg_idx, config), max_velocity_(max_velocity) {
  if (const std::string e = config_.validate(); !e.empty()) throw ConfigError("velocity_feedback: " + e);
}

void VelocityFeedback::reset() noexcept {
  c_ = {0.0, 0.0, 0.0};
  u_ff_ = {0.0, 0.0, 0.0};
  u_anchor_ = {0.0, 0.0, 0.0};
  steady_ = {0.0, 0.0, 0.0};
  brake_ = {0.0, 0.0};
  ff_share_ = 1.0;
  u_fb_prev_ = VelocityCommand{};
  estimator_.reset();
  est_ = BaseVelocityEstimate{};
}

const VelocityCommand& VelocityFeedback::update(const VelocityCommand& u, const LowState& state, double dt) noexcept {
  if (!config_.enabled) {
    u_fb_ = u;
    return u_fb_;
  }
  const BaseVelocityEstimate est = estimator_.update(state, dt);
  return correct(u, est, dt, estimator_.rejecting(), estimator_.tilt() > config_.max_tilt_rad);
}

const VelocityCommand& VelocityFeedback::correct(const VelocityCommand& u, const BaseVelocityEstimate& est,
                                                 double dt, bool hold, bool decay) noexcept {
  u_fb_ = u;
  est_ = est;
  if (decay) {
    ++decayed_ticks_;
  } else if (hold) {
    ++held_ticks_;
  }
  const double keep = decay ? std::max(0.0, 1.0 - dt / config_.decay_time_s) : 1.0;
  const std::array<double, 3> u_user{u.vx, u.vy, u.wz};
  u_ff_ = config_.feedforward.enabled ? config_.feedforward.invert(u_user, crouch_m_) : u_user;
  if (config_.decay_feedforward) {
    // The feed-forward's share decays while tilted and returns over feedforward_return_s (continuous).
    const double back_s = config_.feedforward_return_s > 0.0 ? config_.feedforward_return_s : config_.decay_time_s;
    ff_share_ = decay ? ff_share_ * keep : std::min(1.0, ff_share_ + dt / back_s);
    for (std::size_t i = 0; i < 3; ++i) u_ff_[i] = u_user[i] + ff_share_ * (u_ff_[i] - u_user[i]);
  }
  for (std::size_t i = 0; i < 3; ++i) {
    // The limits: the envelope and ±max_velocity, which opens beyond max_velocity only as far as the
    // command comes within max_velocity_headroom of it (continuous in u; unchanged below that).
    const double ceiling = std::max(max_velocity_[i], std::fabs(u[i]) + config_.max_velocity_headroom[i]);
    const double lo = std::max(config_.envelope_min[i], -ceiling);
    const double hi = std::min(config_.envelope_max[i], ceiling);
    // The feed-forward stays inside the limits (a command already beyond them is passed on).
    u_ff_[i] = std::clamp(u_ff_[i], std::min(lo, u[i]), std::max(hi, u[i]));
    const double bound = std::max(config_.max_ratio * std::fabs(u[i]),
                                  std::min(std::fabs(u[i]), config_.small_command_bound[i]));
    double c = c_[i] * keep;
    if (std::fabs(u[i] - u_anchor_[i]) > std::max(config_.steady_band, 0.05 * std::fabs(u_anchor_[i]))) {
      u_anchor_[i] = u[i];  // the command moved: it settles again from here
      steady_[i] = 0.0;
    } else {
      steady_[i] += dt;
    }
    const bool settled = steady_[i] >= config_.settle_time_s - 1e-9;
    if (est_.valid && !hold && !decay && settled) c += config_.ki[i] * (u[i] - estimate(i)) * dt;
    c = std::clamp(c, -bound, bound);
    // Anti-windup: the correction never holds more than the limits let through.
    const double limited = std::clamp(u_ff_[i] + c, std::min(lo, u_ff_[i]), std::max(hi, u_ff_[i]));
    c_[i] = limited - u_ff_[i];
  }
  const VelocityCommand previous = u_fb_prev_;
  u_fb_.vx = u_ff_[0] + c_[0];
  u_fb_.vy = u_ff_[1] + c_[1];
  u_fb_.wz = u_ff_[2] + c_[2];
  if (config_.brake_ratio > 0.0) {
    // Braking floor (VelocityFeedbackConfig::brake_ratio), per linear axis, as a magnitude f >= 0
    // along its direction s: the floor's direction is kept until it is back at zero.
    bool raised = false;
    double* out[2] = {&u_fb_.vx, &u_fb_.vy};
    const double prev_out[2] = {previous.vx, previous.vy};
    const double ratio = config_.brake_ratio * (config_.brake_crouch_scaled ? brake_weight_ : 1.0);
    for (std::size_t i = 0; i < 2; ++i) {
      const double v = estimate(i);
      const double s = brake_[i] != 0.0 ? (brake_[i] > 0.0 ? 1.0 : -1.0) : (v >= 0.0 ? 1.0 : -1.0);
      const double f = std::fabs(brake_[i]);
      const bool active = est_.valid && !decay && s * *out[i] >= 0.0;
      const double want = active ? std::max(0.0, ratio * s * v) : 0.0;
      const double cap = std::max(0.0, s * prev_out[i] - config_.brake_decel * dt);
      const double step = config_.brake_rate * dt;
      const double f_new = std::clamp(std::min(want, cap), std::max(0.0, f - step), f + step);
      brake_[i] = s * f_new;
      if (f_new > 0.0 && s * *out[i] < f_new) {
        *out[i] = s * f_new;
        raised = true;
      }
    }
    if (raised) ++braking_ticks_;
  }
  u_fb_prev_ = u_fb_;
  return u_fb_;
}

const VelocityCommand& VelocityFeedback::scaleDown(double scale, bool keep_yaw) noexcept {
  if (!(scale > 1.0)) return u_fb_;
  u_fb_ = {u_fb_.vx / scale, u_fb_.vy / scale, keep_yaw ? u_fb_.wz : u_fb_.wz / scale};
  for (std::size_t i = 0; i < 3; ++i) c_[i] = u_fb_[i] - u_ff_[i];
  u_fb_prev_ = u_fb_;
  ++envelope_ticks_;
  return u_fb_;
}

std::string PostureFeedbackConfig::validate() const {
  for (std::size_t i = 0; i < 2; ++i)
    if (!(std::isfinite(ki[i]) && ki[i] >= 0.0 && ki[i] <= 20.0))
      return std::string("ki[") + std::to_string(i) + "] (" + (i == 0 ? "pitch" : "roll") + "): expected 0..20 [1/s]";
  if (!(max_correction_rad >= 0.0 && max_correction_rad <= 0.3)) return "max_correction_rad: expected 0..0.3 rad";
  if (!(filter_time_s >= 0.0 && filter_time_s <= 2.0)) return "filter_time_s: expected 0..2 s";
  if (!(max_tilt_rad > 0.0 && max_tilt_rad <= 1.5)) return "max_tilt_rad: expected (0, 1.5] rad";
  if (!(decay_time_s > 0.0 && decay_time_s <= 5.0)) return "decay_time_s: expected (0, 5] s";
  if (!(still_velocity >= 0.0 && still_velocity <= 1.0)) return "still_velocity: expected 0..1 m/s";
  if (!(still_measured_velocity >= 0.0 && still_measured_velocity <= 2.0))
    return "still_measured_velocity: expected 0..2 m/s";
  if (!(settle_s >= 0.0 && settle_s <= 5.0)) return "settle_s: expected 0..5 s";
  if (!(stop_settle_s >= 0.0 && stop_settle_s <= 5.0)) return "stop_settle_s: expected 0..5 s";
  for (std::size_t i = 0; i < 2; ++i)
    if (!(std::isfinite(walking_ki[i]) && walking_ki[i] >= 0.0 && walking_ki[i] <= 5.0))
      return std::string("walking_ki[") + std::to_string(i) + "] (" + (i == 0 ? "pitch" : "roll") + "): expected 0..5 [1/s]";
  if (!(walking_max_correction_rad >= 0.0 && walking_max_correction_rad <= 0.3))
    return "walking_max_correction_rad: expected 0..0.3 rad";
  if (!(walking_filter_time_s >= 0.0 && walking_filter_time_s <= 5.0)) return "walking_filter_time_s: expected 0..5 s";
  if (!(walking_settle_s >= 0.0 && walking_settle_s <= 5.0)) return "walking_settle_s: expected 0..5 s";
  if (!(walking_velocity_settle_s >= 0.0 && walking_velocity_settle_s <= 5.0))
    return "walking_velocity_settle_s: expected 0..5 s";
  if (!(walking_min_command_rad >= 0.0 && walking_min_command_rad <= 0.5)) return "walking_min_command_rad: expected 0..0.5 rad";
  if (!(walking_deadband_rad >= 0.0 && walking_deadband_rad <= 0.3)) return "walking_deadband_rad: expected 0..0.3 rad";
  if (!(walking_crouch_m >= 0.0 && walking_crouch_m <= 0.2)) return "walking_crouch_m: expected 0..0.2 m";
  for (std::size_t i = 0; i < 2; ++i)
    if (!(std::isfinite(envelope_min[i]) && std::isfinite(envelope_max[i]) && envelope_min[i] <= 0.0 &&
          envelope_max[i] >= 0.0 && envelope_min[i] >= -1.5 && envelope_max[i] <= 1.5))
      return std::string("envelope_min/envelope_max[") + std::to_string(i) + "] (" + (i == 0 ? "pitch" : "roll") +
             "): expected -1.5 <= min <= 0 <= max <= 1.5 rad";
  if (!(std::isfinite(height_ki) && height_ki >= 0.0 && height_ki <= 20.0)) return "height_ki: expected 0..20 [1/s]";
  if (!(max_height_correction_m >= 0.0 && max_height_correction_m <= 0.1))
    return "max_height_correction_m: expected 0..0.1 m";
  if (!(height_settle_s >= 0.0 && height_settle_s <= 5.0)) return "height_settle_s: expected 0..5 s";
  if (!(std::isfinite(walking_height_ki) && walking_height_ki >= 0.0 && walking_height_ki <= 5.0))
    return "walking_height_ki: expected 0..5 [1/s]";
  if (!(walking_max_height_correction_m >= 0.0 && walking_max_height_correction_m <= 0.1))
    return "walking_max_height_correction_m: expected 0..0.1 m";
  if (!(walking_below_floor_m >= 0.0 && walking_below_floor_m <= 0.05))
    return "walking_below_floor_m: expected 0..0.05 m";
  return {};
}

namespace {
LimbChain torsoChain(const PostureFeedbackConfig& config, const RobotConfig& robot) {
  if (const std::string e = config.validate(); !e.empty()) throw ConfigError("posture_feedback: " + e);
  return KinematicModel(robot).chain(robot.base_link, "torso_link");
}
}  // namespace

PostureFeedback::PostureFeedback(const PostureFeedbackConfig& config, const RobotConfig& robot,
                                 const std::array<double, 2>& pitch_range, const std::array<double, 2>& roll_range,
                                 const std::array<double, 2>& height_range, double standing_height,
                                 std::shared_ptr<const gco::LegModel> legs, const gco::LegJointIndex& leg_idx,
                                 double walking_min_height)
    : config_(config),
      torso_(torsoChain(config, robot)),
      fk_(torso_),
      q_(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(robot.numJoints()))),
      pitch_range_(pitch_range),
      roll_range_(roll_range),
      height_range_(height_range),
      standing_height_(standing_height),
      walking_min_height_(walking_min_height),
      leg_idx_(leg_idx) {
  if (config_.height_ki > 0.0 || config_.walking_height_ki > 0.0) {
    const char* key = config_.height_ki > 0.0 ? "height_ki" : "walking_height_ki";
    if (!legs)
      throw ConfigError(std::string("posture_feedback.") + key + ": the height feedback needs the robot's leg chains");
    if (!(height_range_[0] > 0.0 && height_range_[0] <= height_range_[1] && standing_height_ >= height_range_[0]))
      throw ConfigError(std::string("posture_feedback.") + key + ": the height feedback needs a height range containing the standing "
                        "height (got [" + std::to_string(height_range_[0]) + ", " + std::to_string(height_range_[1]) +
                        "] m, standing " + std::to_string(standing_height_) + " m)");
    legs_ = std::make_unique<gco::LegKinematics>(std::move(legs));
  }
  if (config_.walking_crouch_m > 0.0 && !(standing_height_ > 0.0))
    throw ConfigError("posture_feedback.walking_crouch_m: the crouched-walk feedback needs the standing height (got " +
                      std::to_string(standing_height_) + " m)");
}

PostureFeedback::~PostureFeedback() = default;

void PostureFeedback::reset() noexcept {
  c_ = {0.0, 0.0};
  p_hat_ = {0.0, 0.0};
  p_walk_hat_ = {0.0, 0.0};
  c_stand_ = {0.0, 0.0};
  c_walk_ = {0.0, 0.0};
  p_settled_ = {0.0, 0.0};
  p_steady_s_ = {0.0, 0.0};
  still_s_ = 0.0;
  v_settled_ = {0.0, 0.0, 0.0};
  v_steady_s_ = 0.0;
  have_ = false;
  c_h_ = h_hat_ = 0.0;
  c_hw_ = c_h_applied_ = h_walking_s_ = 0.0;
  have_h_ = false;
  h_settled_ = h_steady_s_ = 0.0;
}

bool PostureFeedback::pelvisHeight(const LowState& state, double* height) noexcept {
  Eigen::Matrix3d R_WB;
  if (!legs_ || !imuRotation(state.imu, &R_WB)) return false;
  double z_low = 0.0;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    gco::LegVector q;
    for (int j = 0; j < gco::kLegDofs; ++j) {
      const int m = leg_idx_[f][static_cast<std::size_t>(j)];
      if (m < 0 || m >= state.num_motors) return false;
      q[j] = state.motors[static_cast<std::size_t>(m)].q;
    }
    Eigen::Isometry3d X_BS;
    if (!legs_->forward(static_cast<Foot>(f), q, &X_BS)) return false;
    const double z = (R_WB * X_BS.translation()).z();  // sole below the pelvis origin, W axes
    z_low = f == 0 ? z : std::min(z_low, z);
  }
  *height = -z_low;
  return std::isfinite(*height);
}

bool PostureFeedback::torsoAttitude(const LowState& state, double* pitch, double* roll, double* pelvis_tilt) noexcept {
  Eigen::Matrix3d R_WB;
  if (state.num_motors != q_.size() || !imuRotation(state.imu, &R_WB)) return false;
  for (Eigen::Index i = 0; i < q_.size(); ++i) q_[i] = state.motors[static_cast<std::size_t>(i)].q;
  Eigen::Isometry3d X_BT;
  if (!q_.allFinite() || !fk_.tipPose(q_, X_BT)) return false;
  const Eigen::Matrix3d R = R_WB * X_BT.linear();
  *pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  *roll = std::atan2(R(2, 1), R(2, 2));
  *pelvis_tilt = tiltFromVertical(R_WB);
  return std::isfinite(*pitch) && std::isfinite(*roll);
}

const PostureCommand& PostureFeedback::update(const PostureCommand& u, const VelocityCommand& v,
                                              const LowState& state, double dt, const BaseVelocityEstimate* v_est,
                                              bool upset) noexcept {
  u_fb_ = u;
  if (!config_.enabled) return u_fb_;
  double pitch = 0.0, roll = 0.0, tilt = 0.0;
  const bool ok = torsoAttitude(state, &pitch, &roll, &tilt);
  if (ok) {
    const double a = config_.filter_time_s > 0.0 ? std::min(1.0, dt / config_.filter_time_s) : 1.0;
    p_hat_[0] = have_ ? p_hat_[0] + a * (pitch - p_hat_[0]) : pitch;
    p_hat_[1] = have_ ? p_hat_[1] + a * (roll - p_hat_[1]) : roll;
    const double aw = config_.walking_filter_time_s > 0.0 ? std::min(1.0, dt / config_.walking_filter_time_s) : 1.0;
    p_walk_hat_[0] = have_ ? p_walk_hat_[0] + aw * (pitch - p_walk_hat_[0]) : pitch;
    p_walk_hat_[1] = have_ ? p_walk_hat_[1] + aw * (roll - p_walk_hat_[1]) : roll;
    have_ = true;
  }
  const bool still = std::fabs(v.vx) < config_.still_velocity && std::fabs(v.vy) < config_.still_velocity &&
                     std::fabs(v.wz) < 2.0 * config_.still_velocity;
  // How long the velocity command has been still (stop_settle_s): the robot's transient after a stop
  // is not integrated.
  still_s_ = still ? still_s_ + dt : 0.0;
  const bool stop_settled = still_s_ >= config_.stop_settle_s - 1e-9;
  // How long the shaped velocity command has stayed where it settled (walking_velocity_settle_s): the
  // torso's swing as a walk starts or its command changes is not integrated by the walking integrators.
  constexpr double kVelocitySettleBand = 0.05;  // [m/s], [rad/s]
  const double v_now[3] = {v.vx, v.vy, v.wz};
  bool v_moved = false;
  for (std::size_t k = 0; k < 3; ++k) v_moved = v_moved || std::fabs(v_now[k] - v_settled_[k]) > kVelocitySettleBand;
  if (v_moved) {
    for (std::size_t k = 0; k < 3; ++k) v_settled_[k] = v_now[k];
    v_steady_s_ = 0.0;
  } else {
    v_steady_s_ += dt;
  }
  const bool walk_settled = v_steady_s_ >= config_.walking_velocity_settle_s - 1e-9;
  // Told to stand but still moving (still_measured_velocity): the standing correction is held.
  const bool moving = config_.still_measured_velocity > 0.0 && v_est && v_est->valid &&
                      (std::fabs(v_est->v_x) >= config_.still_measured_velocity ||
                       std::fabs(v_est->v_y) >= config_.still_measured_velocity);
  // Upset and going upright: every correction decays, as when tilted.
  const bool tilted = (ok && tilt > config_.max_tilt_rad) || upset;
  const bool hold_stand = still && moving && !tilted;  // the standing correction neither integrates nor decays
  const bool decay = !still || tilted;
  const double decay_keep = std::max(0.0, 1.0 - dt / config_.decay_time_s);
  const double keep = decay ? decay_keep : 1.0;
  const double cmd[2] = {u.pitch, u.roll};
  // Crouched (walking_crouch_m): an upright crouched walk's lean is fed back whole.
  const bool crouched = config_.walking_crouch_m > 0.0 && standing_height_ > 0.0 && u.height > 0.0 &&
                        u.height <= standing_height_ - config_.walking_crouch_m;
  const std::array<double, 2>* range[2] = {&pitch_range_, &roll_range_};
  // [rad] the few hundredths a torso sways standing or walking are not a sign (walking_crouch_release,
  // overshoot_release)
  constexpr double kReleaseBand = 0.02;
  for (std::size_t i = 0; i < 2; ++i) {
    if (std::fabs(cmd[i] - p_settled_[i]) > 0.01) {
      p_settled_[i] = cmd[i];
      p_steady_s_[i] = 0.0;
    } else {
      p_steady_s_[i] += dt;
    }
    // Walking (walking_ki > 0): integrate on the gait-averaged attitude once the posture command is
    // steady, within the walking bound; decay when the robot is told to stand or tilts, so that a
    // lean built against a side-step's sway is not held into the stop.
    // Below walking_min_command_rad (an upright walk), with a dead band: only the error beyond it.
    // A crouched walk with an upright command (walking_crouch_m) counts as commanded.
    const bool upright_crouch = crouched && std::fabs(cmd[i]) < config_.walking_min_command_rad;
    const bool commanded = std::fabs(cmd[i]) >= config_.walking_min_command_rad || upright_crouch;
    const bool walking = !still && !tilted && config_.walking_ki[i] > 0.0 && (commanded || config_.walking_deadband_rad > 0.0);
    // Standing: integrate on the fast low-pass while still, decay otherwise; walking crouched with an
    // upright command, what the still crouch needed is held (the torso leans back crouched whether
    // it walks or not), and the walking integrator adds what the gait needs on top. A commanded bend
    // is not held (held, a 0.4 rad bend walked crouched at 0.66 m fell at the stop).
    double cs = hold_stand ? c_stand_[i] : c_stand_[i] * keep;
    const double e = cmd[i] - p_walk_hat_[i];
    if (walking && upright_crouch) {
      // Held within the walking bound; what lies beyond it decays. With walking_crouch_release, a
      // held correction that pushes the gait-averaged torso further from the command (e of the
      // other sign, beyond kReleaseBand) decays whole: that actor leans one way standing crouched
      // and the other walking.
      const double wm = config_.walking_max_correction_rad;
      const double mag = std::fabs(c_stand_[i]);
      const bool opposed = config_.walking_crouch_release && have_ && e * std::copysign(1.0, c_stand_[i]) < -kReleaseBand;
      cs = opposed ? c_stand_[i] * decay_keep
                   : std::copysign(mag > wm ? wm + (mag - wm) * decay_keep : mag, c_stand_[i]);
    }
    // Standing with overshoot_release: a correction that pushes the torso further past the command
    // (beyond kReleaseBand on its other side) decays as well.
    if (config_.overshoot_release && have_ && ok && !decay &&
        (cmd[i] - p_hat_[i]) * std::copysign(1.0, cs) < -kReleaseBand)
      cs *= decay_keep;
    // Standing, only once the posture command has settled (settle_s) and the velocity command has
    // been still for stop_settle_s: neither the torso's lag behind a posture ramp nor its swing after
    // a stop is integrated, and meanwhile the correction is held.
    if (have_ && ok && !decay && !hold_stand && stop_settled && p_steady_s_[i] >= config_.settle_s)
      cs += config_.ki[i] * (cmd[i] - p_hat_[i]) * dt;
    cs = std::clamp(cs, -config_.max_correction_rad, config_.max_correction_rad);
    // Inside the dead band the correction decays as at a stop, so that what one gait needed is not
    // carried into the next (held, a crouched walk's correction overshot the crouched turn after it).
    const double band = commanded ? 0.0 : config_.walking_deadband_rad;
    const bool inside = !commanded && std::fabs(e) <= band;
    double cw = walking && !inside ? c_walk_[i] : c_walk_[i] * decay_keep;
    if (walking && !inside && have_ && ok && p_steady_s_[i] >= config_.walking_settle_s && walk_settled)
      cw = std::clamp(cw + config_.walking_ki[i] * (e - std::copysign(band, e)) * dt, -config_.walking_max_correction_rad,
                      config_.walking_max_correction_rad);
    const double c = std::clamp(cs + cw, -config_.max_correction_rad, config_.max_correction_rad);
    // Within the command's range, and not pushed beyond envelope_min/max by the correction.
    const double lo = std::max((*range[i])[0], std::min(cmd[i], config_.envelope_min[i]));
    const double hi = std::min((*range[i])[1], std::max(cmd[i], config_.envelope_max[i]));
    const double limited = std::clamp(cmd[i] + c, std::min(lo, hi), hi);
    c_[i] = limited - cmd[i];
    // Anti-windup: what the bounds cut comes off the integrator that is acting.
    const double cut = cs + cw - c_[i];
    if (walking) cw -= cut;
    else cs -= cut;
    c_stand_[i] = cs;
    c_walk_[i] = cw;
  }
  u_fb_.pitch = u.pitch + c_[0];
  u_fb_.roll = u.roll + c_[1];
  if (legs_) {
    double h = 0.0;
    const bool h_ok = pelvisHeight(state, &h);
    if (h_ok) {
      const double a = config_.filter_time_s > 0.0 ? std::min(1.0, dt / config_.filter_time_s) : 1.0;
      h_hat_ = have_h_ ? h_hat_ + a * (h - h_hat_) : h;
      have_h_ = true;
    }
    if (std::fabs(u.height - h_settled_) > 0.005) {
      h_settled_ = u.height;
      h_steady_s_ = 0.0;
    } else {
      h_steady_s_ += dt;
    }
    const bool steady = h_steady_s_ >= config_.height_settle_s;
    double c = c_h_ * keep;
    if (have_h_ && h_ok && !decay && steady && u.height > 0.0) c += config_.height_ki * (u.height - h_hat_) * dt;
    c = std::clamp(c, -config_.max_height_correction_m, config_.max_height_correction_m);
    const double upper = std::max(u.height, std::min(height_range_[1], standing_height_));
    if (config_.walking_height_ki == 0.0) {
      // The standing integrator alone, computed as before the walking one existed (the seed-replay
      // SIL tests pin its trajectories to the last bit).
      c_h_ = u.height > 0.0 ? std::clamp(u.height + c, height_range_[0], upper) - u.height : 0.0;
      c_h_applied_ = c_h_;
    } else {
      // Walking: the second integrator, on the same low-pass (the integrator averages the gait's
      // bob), once the robot has walked walking_settle_s at a steady height command; it decays when
      // told to stand or tilted.
      const bool walking_h = !still && !tilted;
      h_walking_s_ = walking_h ? h_walking_s_ + dt : 0.0;
      double cw = walking_h ? c_hw_ : c_hw_ * decay_keep;
      if (walking_h && have_h_ && h_ok && steady && h_walking_s_ >= config_.walking_settle_s && u.height > 0.0)
        cw += config_.walking_height_ki * (u.height - h_hat_) * dt;
      cw = std::clamp(cw, -config_.walking_max_height_correction_m, config_.walking_max_height_correction_m);
      // The walking correction never lowers the command more than walking_below_floor_m (0: not at
      // all) below the walking floor (a command already below it, as the floor's hold ends, is the
      // reference for that margin, not lowered further). The margin holds while the correction
      // decays too, so the stop lifts the command back at the decay's pace, not in one tick.
      double lower = height_range_[0];
      if (walking_min_height_ > 0.0 && (walking_h || cw != 0.0))
        lower = std::max(lower, std::min(u.height, walking_min_height_) - config_.walking_below_floor_m);
      const double want = u.height + c + cw;
      const double got = std::clamp(want, lower, upper);
      const bool bound = u.height > 0.0 && got != want;
      const double target = u.height > 0.0 ? (bound ? got - u.height : c + cw) : 0.0;
      // Anti-windup: what the bounds cut comes off the integrator that is acting.
      const double cut = bound ? c + cw - target : 0.0;
      // The applied correction moves towards its target at kWalkingHeightCorrectionRate at most: the floor's
      // bound takes effect in one tick as a walk starts and would cancel a lowering standing correction (up to
      // max_height_correction_m) at once, a step in the height reference (docs/controller.md "Walking height
      // correction").
      const double step = kWalkingHeightCorrectionRate * dt;
      c_h_applied_ = u.height > 0.0 ? c_h_applied_ + std::clamp(target - c_h_applied_, -step, step) : 0.0;
      // Decaying, what is cut comes off the walking correction first (as far as it reduces it).
      const double from_walk =
          walking_h ? cut : (cut * cw > 0.0 ? std::copysign(std::min(std::fabs(cut), std::fabs(cw)), cw) : 0.0);
      cw -= from_walk;
      c -= cut - from_walk;
      c_h_ = u.height > 0.0 ? c : 0.0;
      c_hw_ = u.height > 0.0 ? cw : 0.0;
    }
    u_fb_.height = u.height + c_h_applied_;
  }
  return u_fb_;
}

}  // namespace pmg
