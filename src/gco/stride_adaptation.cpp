#include "pmg/gco/stride_adaptation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <Eigen/LU>

namespace pmg::gco {

namespace {

constexpr double kUnreachedPosition = 0.002;  // [m]
constexpr double kUnreachedAngle = 0.01;      // [rad]

double smoothstep(double x) noexcept {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// Scales v down to norm `bound`; returns true when it did.
template <class V>
bool boundNorm(V* v, double bound) noexcept {
  const double n = v->norm();
  if (n <= bound) return false;
  *v *= bound / n;
  return true;
}

double yawOf(const Eigen::Matrix3d& R) noexcept { return std::atan2(R(1, 0), R(0, 0)); }

bool boundAbs(double* x, double bound) noexcept {
  if (std::abs(*x) <= bound) return false;
  *x = std::copysign(bound, *x);
  return true;
}

}  // namespace

void StrideAdaptationOptions::validate() const {
  const auto fail = [](const std::string& field, const std::string& range, double v) {
    throw std::invalid_argument("gco.stride_adaptation." + field + " = " + std::to_string(v) + ": expected " + range);
  };
  if (!(touchdown_lead >= 0.0 && touchdown_lead < 1.0)) fail("touchdown_lead", "[0, 1)", touchdown_lead);
  if (!(return_fraction > 0.0 && return_fraction <= 1.0)) fail("return_fraction", "(0, 1]", return_fraction);
  if (!(standing_time_constant > 0.0 && standing_time_constant <= 10.0)) {
    fail("standing_time_constant", "(0, 10] s", standing_time_constant);
  }
  if (!(max_offset > 0.0 && max_offset <= 0.3)) fail("max_offset", "(0, 0.3] m", max_offset);
  if (!(max_offset_height > 0.0 && max_offset_height <= 0.3)) fail("max_offset_height", "(0, 0.3] m", max_offset_height);
  if (!(max_offset_yaw > 0.0 && max_offset_yaw <= 1.0)) fail("max_offset_yaw", "(0, 1] rad", max_offset_yaw);
  if (!(max_offset_speed > 0.0 && max_offset_speed <= 5.0)) fail("max_offset_speed", "(0, 5] m/s", max_offset_speed);
  if (!(max_offset_yaw_rate > 0.0 && max_offset_yaw_rate <= 10.0)) {
    fail("max_offset_yaw_rate", "(0, 10] rad/s", max_offset_yaw_rate);
  }
  if (iterations < 1 || iterations > 10) fail("iterations", "1..10", iterations);
  if (!(max_correction > 0.0 && max_correction <= 1.5)) fail("max_correction", "(0, 1.5] rad", max_correction);
  if (!(damping >= 0.0 && damping <= 1.0)) fail("damping", "[0, 1]", damping);
  if (!(stepping_margin > 0.0 && stepping_margin <= 0.5)) fail("stepping_margin", "(0, 0.5]", stepping_margin);
  if (!(height_weight > 0.0 && height_weight <= 1.0)) fail("height_weight", "(0, 1]", height_weight);
  if (!(sole_half_length >= 0.0 && sole_half_length <= 0.2)) fail("sole_half_length", "[0, 0.2] m", sole_half_length);
  if (!(rolling_slope > 0.0 && rolling_slope <= 1.0)) fail("rolling_slope", "(0, 1]", rolling_slope);
  if (!(max_correction_rate > 0.0 && max_correction_rate <= 100.0)) {
    fail("max_correction_rate", "(0, 100] rad/s", max_correction_rate);
  }
}

StrideAdaptation::StrideAdaptation(std::shared_ptr<const LegModel> legs, const StrideAdaptationOptions& options,
                                   const LegJointIndex& leg_idx)
    : legs_(std::move(legs)), options_(options), leg_idx_(leg_idx), kin_(legs_) {
  options_.validate();
}

void StrideAdaptation::reset() noexcept {
  started_ = false;
  counters_ = StrideAdaptationCounters{};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    offset_[f].setZero();
    liftoff_offset_[f].setZero();
    yaw_offset_[f] = liftoff_yaw_[f] = 0.0;
    delta_[f].setZero();
    applied_[f].setZero();
    residual_[f].setZero();
    last_contact_[f] = true;
  }
}

double StrideAdaptation::swingProgress(const FootContact& contact, double phase) noexcept {
  const double sigma = contact.sigma;
  if (!(sigma < 0.5)) return 0.0;
  const double s = phase - contact.mu - std::floor(phase - contact.mu);  // φ − μ in [0, 1)
  if (s < sigma || s > 1.0 - sigma) return 0.0;                           // stance
  return std::clamp((s - sigma) / (1.0 - 2.0 * sigma), 0.0, 1.0);
}

bool StrideAdaptation::solveFoot(std::size_t f, const LegVector& q_ref, const Eigen::Isometry3d& X_target,
                                 double dt) noexcept {
  const Foot foot = static_cast<Foot>(f);
  const auto& lim = legs_->jointLimits(foot);
  LegVector delta = delta_[f];
  Eigen::Isometry3d X;
  Eigen::Matrix<double, 6, kLegDofs> J;
  Eigen::Matrix<double, 6, 1> err;
  const auto poseError = [&]() {  // of the pose X
    err.head<3>() = X_target.translation() - X.translation();
    const Eigen::AngleAxisd aa(X_target.linear() * X.linear().transpose());
    err.tail<3>() = aa.angle() * aa.axis();
  };
  const double wz = options_.height_weight;
  const double max_step = options_.max_correction_rate * dt;
  const LegVector& last = applied_[f];
  for (int it = 0; it < options_.iterations; ++it) {
    if (!kin_.jacobian(foot, q_ref + delta, &X, &J)) return false;
    poseError();
    err(2) *= wz;  // the sole's height gives way first where the pose is out of reach
    J.row(2) *= wz;
    // Levenberg-Marquardt with the error-dependent damping of Sugihara (2011): |err|² + damping, so
    // that an out-of-reach target (a straight stance knee) gives a short step, not a large one.
    const Eigen::Matrix<double, kLegDofs, kLegDofs> H =
        J.transpose() * J + (err.squaredNorm() + options_.damping) * Eigen::Matrix<double, kLegDofs, kLegDofs>::Identity();
    delta += H.partialPivLu().solve(J.transpose() * err);
    for (int j = 0; j < kLegDofs; ++j) {
      const double lo = std::max({-options_.max_correction, lim[j].first - q_ref(j), last(j) - max_step});
      const double hi = std::min({options_.max_correction, lim[j].second - q_ref(j), last(j) + max_step});
      delta(j) = lo <= hi ? std::clamp(delta(j), lo, hi) : std::clamp(0.0, last(j) - max_step, last(j) + max_step);
    }
  }
  if (!kin_.forward(foot, q_ref + delta, &X)) return false;  // the pose error left, for `unreached`
  poseError();
  delta_[f] = delta;
  residual_[f] = Eigen::Vector2d(err.head<3>().norm(), err.tail<3>().norm());
  return true;
}

bool StrideAdaptation::apply(const StrideAdaptationInput& in, double dt, Eigen::VectorXd* q_ref,
                             Eigen::VectorXd* qd_ref) noexcept {
  if (!options_.enabled || q_ref == nullptr || qd_ref == nullptr || !(dt > 0.0)) return false;
  ++counters_.ticks;
  const bool first = !started_;
  // On a failure the last tick's correction is held (the reference gets no jump) and the state too.
  const auto hold = [&]() {
    ++counters_.failures;
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      delta_[f] = applied_[f];
      for (int j = 0; j < kLegDofs; ++j) (*q_ref)(leg_idx_[f][j]) += applied_[f](j);
    }
    return false;
  };
  if (!std::isfinite(in.phase) || !std::isfinite(in.base_height) ||
      !in.v_H.allFinite() || !std::isfinite(in.yaw_rate)) {
    return hold();
  }
  const double height_rate = first ? 0.0 : (in.base_height - last_height_) / dt;
  const double tau = options_.standing_time_constant;

  std::array<LegVector, kNumFeet> q_leg;
  std::array<Eigen::Isometry3d, kNumFeet> poses;
  std::array<Eigen::Isometry3d, kNumFeet> targets;
  std::array<Eigen::Vector3d, kNumFeet> offset = offset_, liftoff = liftoff_offset_;
  std::array<double, kNumFeet> yaw = yaw_offset_, liftoff_yaw = liftoff_yaw_;
  std::uint64_t speed_limited = 0, offset_limited = 0;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    for (int j = 0; j < kLegDofs; ++j) q_leg[f](j) = (*q_ref)(leg_idx_[f][j]);
    Eigen::Isometry3d& X = poses[f];
    if (!kin_.forward(static_cast<Foot>(f), q_leg[f], &X)) return hold();
    const Eigen::Isometry3d& X_prev = first ? X : last_pose_[f];
    Eigen::Vector3d rate;
    double yaw_rate;
    if (in.in_contact[f]) {
      // Stepping share s_f: 1 while the foot's contact window leaves room for a swing, 0 standing.
      const double walking = std::clamp((0.5 - in.contact[f].sigma) / options_.stepping_margin, 0.0, 1.0);
      // The point the foot rolls on (sole frame): the heel when the toe is up, the toe when it is
      // down (toe-off), moving continuously through the sole's centre S while the sole is level.
      const double toe_down = -X.linear()(2, 0);  // −(sole x axis)_z: > 0 when the toe is lower
      const Eigen::Vector3d c_S(options_.sole_half_length * std::clamp(toe_down / options_.rolling_slope, -1.0, 1.0), 0, 0);
      // The reference's own motion of that point since the last tick (positions, so the held point
      // does not drift by the integration of velocities), and the motion that keeps it still.
      const Eigen::Vector3d p = X * c_S + offset[f];
      const Eigen::Vector3d moved = X * c_S - X_prev * c_S;
      const Eigen::Vector3d still(-in.v_H.x() + in.yaw_rate * p.y(), -in.v_H.y() - in.yaw_rate * p.x(), -height_rate);
      const double d_yaw_ref = std::remainder(yawOf(X.linear()) - yawOf(X_prev.linear()), 2.0 * M_PI);
      // Standing: with standing_hold only the height part decays (the feet stay where they landed).
      const Eigen::Vector3d standing_decay =
          options_.standing_hold ? Eigen::Vector3d(0.0, 0.0, offset[f].z()) : offset[f];
      const double standing_yaw_decay = options_.standing_hold ? 0.0 : yaw[f];
      rate = walking * (still - moved / dt) - (1.0 - walking) * standing_decay / tau;
      yaw_rate = walking * (-in.yaw_rate - d_yaw_ref / dt) - (1.0 - walking) * standing_yaw_decay / tau;
    } else {
      if (last_contact_[f] || first) {  // lift-off
        liftoff[f] = offset[f];
        liftoff_yaw[f] = yaw[f];
      }
      const double lead = options_.touchdown_lead;
      const Eigen::Vector3d touchdown(-lead * liftoff[f].x(), -lead * liftoff[f].y(), 0.0);
      const double a = smoothstep(swingProgress(in.contact[f], in.phase) / options_.return_fraction);
      const Eigen::Vector3d target = liftoff[f] + a * (touchdown - liftoff[f]);
      const double target_yaw = liftoff_yaw[f] + a * (-lead * liftoff_yaw[f] - liftoff_yaw[f]);
      rate = (target - offset[f]) / dt;
      yaw_rate = (target_yaw - yaw[f]) / dt;
    }
    const bool s1 = boundNorm(&rate, options_.max_offset_speed);
    const bool s2 = boundAbs(&yaw_rate, options_.max_offset_yaw_rate);
    speed_limited += (s1 || s2) ? 1 : 0;
    offset[f] += rate * dt;
    yaw[f] += yaw_rate * dt;
    const bool o0 = boundAbs(&offset[f].z(), options_.max_offset_height);
    const bool o1 = boundNorm(&offset[f], options_.max_offset) || o0;
    const bool o2 = boundAbs(&yaw[f], options_.max_offset_yaw);
    offset_limited += (o1 || o2) ? 1 : 0;
    targets[f].translation() = X.translation() + offset[f];
    targets[f].linear() = Eigen::AngleAxisd(yaw[f], Eigen::Vector3d::UnitZ()).toRotationMatrix() * X.linear();
  }
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (!solveFoot(f, q_leg[f], targets[f], first ? 1e9 : dt)) return hold();
  }
  // Commit: state, counters, and the reference.
  started_ = true;
  last_height_ = in.base_height;
  counters_.speed_limited += speed_limited;
  counters_.offset_limited += offset_limited;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    offset_[f] = offset[f];
    yaw_offset_[f] = yaw[f];
    liftoff_offset_[f] = liftoff[f];
    liftoff_yaw_[f] = liftoff_yaw[f];
    last_contact_[f] = in.in_contact[f];
    last_pose_[f] = poses[f];
    if (residual_[f](0) > kUnreachedPosition || residual_[f](1) > kUnreachedAngle) ++counters_.unreached;
    const LegVector rate_added = first ? LegVector::Zero() : LegVector((delta_[f] - applied_[f]) / dt);
    for (int j = 0; j < kLegDofs; ++j) {
      (*q_ref)(leg_idx_[f][j]) += delta_[f](j);
      (*qd_ref)(leg_idx_[f][j]) += rate_added(j);
    }
    applied_[f] = delta_[f];
  }
  return true;
}

}  // namespace pmg::gco
