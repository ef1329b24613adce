#include "pmg/gco/sole_levelling.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pmg::gco {

namespace {
constexpr int kAnklePitch = kLegDofs - 2;  // chain order: hip pitch, roll, yaw, knee, ankle pitch, ankle roll
constexpr int kAnkleRoll = kLegDofs - 1;
}  // namespace

void SoleLevellingOptions::validate() const {
  const auto fail = [](const std::string& field, const std::string& range, double v) {
    throw std::invalid_argument("gco.sole_levelling." + field + " = " + std::to_string(v) + ": expected " + range);
  };
  if (!(edge_fraction > 0.0 && edge_fraction <= 1.0)) fail("edge_fraction", "(0, 1]", edge_fraction);
  if (iterations < 1 || iterations > 10) fail("iterations", "1..10", iterations);
  if (!(max_correction > 0.0 && max_correction <= 1.0)) fail("max_correction", "(0, 1] rad", max_correction);
}

SoleLevelling::SoleLevelling(std::shared_ptr<const LegModel> legs, const SoleLevellingOptions& options,
                             const LegJointIndex& leg_idx)
    : legs_(std::move(legs)), options_(options), leg_idx_(leg_idx), kin_(legs_) {
  options_.validate();
}

bool SoleLevelling::solveFoot(std::size_t f, const LegVector& q_target, const LegVector& q) noexcept {
  const Foot foot = static_cast<Foot>(f);
  Eigen::Matrix3d R;
  Eigen::Matrix<double, 3, kLegDofs> Jw;
  if (!kin_.orientation(foot, q_target, &R, &Jw)) return false;
  const Eigen::Vector3d n_target = R.col(2);
  const auto& lim = legs_->jointLimits(foot);
  Eigen::Vector2d delta = Eigen::Vector2d::Zero();
  LegVector qc = q;
  for (int it = 0; it < options_.iterations; ++it) {
    qc(kAnklePitch) = q(kAnklePitch) + delta(0);
    qc(kAnkleRoll) = q(kAnkleRoll) + delta(1);
    if (!kin_.orientation(foot, qc, &R, &Jw)) return false;
    const Eigen::Vector3d n = R.col(2);
    Eigen::Matrix<double, 3, 2> J;
    J.col(0) = Jw.col(kAnklePitch).cross(n);
    J.col(1) = Jw.col(kAnkleRoll).cross(n);
    const Eigen::Matrix2d H = J.transpose() * J + 1e-9 * Eigen::Matrix2d::Identity();
    delta -= H.ldlt().solve(J.transpose() * (n - n_target));
    for (int k = 0; k < 2; ++k) {
      const int j = k == 0 ? kAnklePitch : kAnkleRoll;
      const double lo = std::max(-options_.max_correction, lim[j].first - q(j));
      const double hi = std::min(options_.max_correction, lim[j].second - q(j));
      delta(k) = lo <= hi ? std::clamp(delta(k), lo, hi) : 0.0;
    }
  }
  delta_[f] = delta;
  return true;
}

double SoleLevelling::weightAt(const FootContact& contact, double phase, double edge_fraction) noexcept {
  const auto wrap = [](double x) { return x - std::floor(x); };
  const double d0 = std::abs(wrap(phase) - wrap(contact.mu));
  const double d = std::min(d0, 1.0 - d0);
  const double ramp = edge_fraction * contact.sigma;
  if (!(ramp > 0.0)) return 0.0;
  return std::clamp((contact.sigma - d) / ramp, 0.0, 1.0);
}

bool SoleLevelling::apply(const Eigen::VectorXd& q_stand, const Eigen::VectorXd& q_posture, double phase,
                          const std::array<FootContact, kNumFeet>& contact, double dt, Eigen::VectorXd* q_ref,
                          Eigen::VectorXd* qd_ref) noexcept {
  for (std::size_t f = 0; f < kNumFeet; ++f) weight_[f] = weightAt(contact[f], phase, options_.edge_fraction);
  const bool first = !started_;
  started_ = true;
  if (!options_.enabled || q_ref == nullptr || qd_ref == nullptr || !(dt > 0.0)) return false;
  bool ok = true;
  for (std::size_t f = 0; f < kNumFeet && ok; ++f) {
    if (weight_[f] == 0.0) {  // swing (or a window's edge): nothing is applied, nothing to solve
      delta_[f].setZero();
      continue;
    }
    LegVector q, q_target;
    for (int j = 0; j < kLegDofs; ++j) {
      const int k = leg_idx_[f][j];
      q(j) = (*q_ref)(k);
      q_target(j) = q_stand(k) + q_posture(k);
    }
    ok = solveFoot(f, q_target, q);
  }
  if (!ok) return false;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const Eigen::Vector2d applied = weight_[f] * delta_[f];
    const Eigen::Vector2d rate_added = first ? Eigen::Vector2d::Zero() : Eigen::Vector2d((applied - applied_[f]) / dt);
    const int kp = leg_idx_[f][kAnklePitch], kr = leg_idx_[f][kAnkleRoll];
    (*q_ref)(kp) += applied(0);
    (*q_ref)(kr) += applied(1);
    (*qd_ref)(kp) += rate_added(0);
    (*qd_ref)(kr) += rate_added(1);
    applied_[f] = applied;
  }
  return true;
}

}  // namespace pmg::gco
