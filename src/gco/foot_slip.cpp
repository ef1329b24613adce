#include "pmg/gco/foot_slip.hpp"

#include <cmath>
#include <stdexcept>

namespace pmg::gco {

FootSlipMeter::FootSlipMeter(std::shared_ptr<const LegModel> model, double dt, double ground_height)
    : model_(model), kin_(model), dt_(dt), ground_height_(ground_height) {
  if (!(dt > 0.0)) throw std::invalid_argument("FootSlipMeter: dt must be > 0");
}

namespace {
Eigen::Matrix3d rotationHB(double roll, double pitch) {
  const double cr = std::cos(roll), sr = std::sin(roll), cp = std::cos(pitch), sp = std::sin(pitch);
  Eigen::Matrix3d R_HB;
  R_HB << cp, sp * sr, sp * cr, 0.0, cr, -sr, -sp, cp * sr, cp * cr;
  return R_HB;
}
}  // namespace

ImpliedBaseVelocity stanceImpliedVelocity(LegKinematics& kin, const GcoInput& in) noexcept {
  ImpliedBaseVelocity out;
  const Eigen::Matrix3d R_HB = rotationHB(in.base_roll, in.base_pitch);
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (!in.contact[f]) continue;
    FootKinematics k;
    if (!kin.compute(static_cast<Foot>(f), in.q_leg[f], in.qd_leg[f], &k)) return ImpliedBaseVelocity{};
    const Eigen::Vector3d r = R_HB * k.p_BS_B;
    const double w = -(R_HB * k.w_BF_B).z();
    const Eigen::Vector3d v_rel = Eigen::Vector3d(0.0, 0.0, w).cross(r) + R_HB * k.v_BS_B;
    out.v_x -= v_rel.x();
    out.v_y -= v_rel.y();
    out.yaw_rate += w;
    ++out.stance_feet;
  }
  if (out.stance_feet == 0) return out;
  out.v_x /= out.stance_feet;
  out.v_y /= out.stance_feet;
  out.yaw_rate /= out.stance_feet;
  out.valid = true;
  return out;
}

void FootSlipMeter::reset() {
  p_WB_.setZero();
  yaw_ = 0.0;
  trace_.clear();
  implied_v_.clear();
  commanded_v_.clear();
  implied_w_.clear();
}

void FootSlipMeter::add(const GcoInput& in, const BaseCommand& base) {
  FootSlipSample s;
  s.t = static_cast<double>(trace_.size()) * dt_;
  p_WB_.z() = base.height;
  s.p_WB = p_WB_;
  s.yaw = yaw_;
  const Eigen::Matrix3d R_HB = rotationHB(in.base_roll, in.base_pitch);
  const Eigen::Matrix3d R_WH = Eigen::AngleAxisd(yaw_, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d v_base(base.v_x, base.v_y, 0.0);
  const Eigen::Vector3d w_base(in.w_HB_H.x(), in.w_HB_H.y(), base.yaw_rate);
  Eigen::Vector2d implied_sum = Eigen::Vector2d::Zero();
  int implied_n = 0;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    FootKinematics k;
    if (!kin_.compute(static_cast<Foot>(f), in.q_leg[f], in.qd_leg[f], &k)) {
      throw std::runtime_error("FootSlipMeter::add: non-finite leg state at sample " + std::to_string(trace_.size()));
    }
    const Eigen::Vector3d r = R_HB * k.p_BS_B;
    s.p_WS[f] = p_WB_ + R_WH * r;
    const Eigen::Vector3d v_rel = w_base.cross(r) + R_HB * k.v_BS_B;
    s.v_WS_H[f] = v_base + v_rel;
    s.contact[f] = in.contact[f];
    if (in.contact[f]) {
      implied_sum += -v_rel.head<2>();
      ++implied_n;
    }
  }
  if (implied_n > 0) {
    implied_v_.push_back(implied_sum / implied_n);
    commanded_v_.emplace_back(in.command.v_x, in.command.v_y);
    const ImpliedBaseVelocity iv = stanceImpliedVelocity(kin_, in);
    implied_w_.push_back(iv.valid ? iv.yaw_rate : 0.0);
  }
  trace_.push_back(s);
  // Midpoint-rule integration of the pelvis pose in W.
  const double yaw_mid = yaw_ + 0.5 * base.yaw_rate * dt_;
  p_WB_.head<2>() += Eigen::Rotation2Dd(yaw_mid) * Eigen::Vector2d(base.v_x, base.v_y) * dt_;
  yaw_ += base.yaw_rate * dt_;
}

FootSlipStats FootSlipMeter::stats() const {
  FootSlipStats st;
  double speed_sum = 0.0, height_sum = 0.0, slip_sum = 0.0;
  double ss_sum = 0.0, ds_sum = 0.0;
  int ss_n = 0, ds_n = 0;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    // Find complete stances: touchdown (false -> true) ... lift-off (true -> false).
    std::size_t k = 1;
    while (k < trace_.size()) {
      if (trace_[k].contact[f] && !trace_[k - 1].contact[f]) {
        const std::size_t begin = k;
        std::size_t end = k;
        while (end < trace_.size() && trace_[end].contact[f]) ++end;
        if (end >= trace_.size()) break;  // stance not finished inside the record
        const Eigen::Vector2d p0 = trace_[begin].p_WS[f].head<2>();
        double slip = 0.0;
        for (std::size_t i = begin; i < end; ++i) {
          const FootSlipSample& s = trace_[i];
          slip = std::max(slip, (s.p_WS[f].head<2>() - p0).norm());
          const double speed = s.v_WS_H[f].head<2>().norm();
          const double herr = std::abs(s.p_WS[f].z() - ground_height_);
          speed_sum += speed;
          if (s.contact[1 - f]) {
            ds_sum += speed;
            ++ds_n;
          } else {
            ss_sum += speed;
            ++ss_n;
          }
          height_sum += herr;
          st.max_stance_speed = std::max(st.max_stance_speed, speed);
          st.max_height_error = std::max(st.max_height_error, herr);
          ++st.stance_ticks;
        }
        slip_sum += slip;
        st.max_slip_per_stance = std::max(st.max_slip_per_stance, slip);
        ++st.stances;
        k = end;
      } else {
        ++k;
      }
    }
  }
  if (st.stance_ticks > 0) {
    st.mean_stance_speed = speed_sum / st.stance_ticks;
    st.mean_height_error = height_sum / st.stance_ticks;
  }
  if (st.stances > 0) st.mean_slip_per_stance = slip_sum / st.stances;
  if (ss_n > 0) st.mean_single_support_speed = ss_sum / ss_n;
  if (ds_n > 0) st.mean_double_support_speed = ds_sum / ds_n;
  if (!implied_v_.empty()) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double err = 0.0;
    for (std::size_t i = 0; i < implied_v_.size(); ++i) {
      sum += implied_v_[i];
      err += (implied_v_[i] - commanded_v_[i]).norm();
    }
    st.mean_implied_v_x = sum.x() / implied_v_.size();
    st.mean_implied_v_y = sum.y() / implied_v_.size();
    st.mean_implied_velocity_error = err / implied_v_.size();
    double w_sum = 0.0;
    for (double w : implied_w_) w_sum += w;
    st.mean_implied_yaw_rate = w_sum / static_cast<double>(implied_w_.size());
  }
  return st;
}

}  // namespace pmg::gco
