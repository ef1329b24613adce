#include "pmg/gco/synthetic_gait.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pmg::gco {

namespace {

void requireRange(double value, double lo, double hi, const char* field) {
  if (!(value >= lo && value <= hi)) {
    throw std::invalid_argument(std::string("SyntheticGaitOptions.") + field + " = " + std::to_string(value) +
                                ": expected a value in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
}

Eigen::Matrix2d rot2(double a) {
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return R;
}

/// Pelvis displacement in the mid-stance heading frame after time τ at constant (v, ω):
/// ∫_0^τ Rz(ω s) v ds.
Eigen::Vector2d baseDisplacement(const Eigen::Vector2d& v, double w, double tau) {
  if (std::abs(w) < 1e-12) return v * tau;
  const double a = w * tau;
  Eigen::Matrix2d I;
  I << std::sin(a), -2.0 * std::sin(a / 2) * std::sin(a / 2), 2.0 * std::sin(a / 2) * std::sin(a / 2), std::sin(a);
  return I * v / w;
}

/// Wrapped phase difference φ − μ in [−0.5, 0.5).
double phaseDiff(double phi, double mu) {
  double d = phi - mu;
  d -= std::floor(d + 0.5);
  return d;
}

struct SolePose {
  Eigen::Vector3d p_HS;  ///< sole in H [m]
  double yaw;            ///< sole yaw in H [rad]
};

/// Sole pose of one foot at time t of the true gait (see the header).
SolePose solePose(const SyntheticGaitOptions& o, double mu, double side_y, double t) {
  const Eigen::Vector2d v(o.v_x, o.v_y);
  const double w = o.yaw_rate;
  const double T = o.period;
  const double Ts = o.duty * T;
  const Eigen::Vector2d p_nom(o.stance_x, side_y);
  const double phi = t / T - std::floor(t / T);
  const double tau = phaseDiff(phi, mu) * T;  // time since mid-stance, [−T/2, T/2)
  // Stance: world-fixed point seen from the moving, turning heading frame.
  auto stance = [&](double ts) {
    SolePose s;
    const Eigen::Vector2d p = rot2(-w * ts) * (p_nom - baseDisplacement(v, w, ts));
    s.p_HS = Eigen::Vector3d(p.x(), p.y(), 0.0);
    s.yaw = -w * ts;
    return s;
  };
  auto stanceVel = [&](double ts) {  // d/dt of stance position in H: −v − ω ẑ × p
    const SolePose s = stance(ts);
    return Eigen::Vector2d(-v.x() + w * s.p_HS.y(), -v.y() - w * s.p_HS.x());
  };
  if (std::abs(tau) <= Ts / 2) return stance(tau);
  // Swing from lift-off (τ = Ts/2) to the next touchdown (τ = T − Ts/2 ≡ −Ts/2): cubic Hermite
  // in xy and yaw with the stance velocities at both ends; height 16 s² (1 − s)² step_height.
  const double Tsw = T - Ts;
  const double ts = tau > 0 ? tau - Ts / 2 : tau + T - Ts / 2;
  const double s = ts / Tsw;
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
  const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
  const SolePose lo = stance(Ts / 2), td = stance(-Ts / 2);
  const Eigen::Vector2d vlo = stanceVel(Ts / 2), vtd = stanceVel(-Ts / 2);
  const Eigen::Vector2d pxy = h00 * lo.p_HS.head<2>() + h10 * Tsw * vlo + h01 * td.p_HS.head<2>() + h11 * Tsw * vtd;
  SolePose out;
  out.p_HS = Eigen::Vector3d(pxy.x(), pxy.y(), 16.0 * s * s * (1 - s) * (1 - s) * o.step_height);
  out.yaw = h00 * lo.yaw + h10 * Tsw * (-w) + h01 * td.yaw + h11 * Tsw * (-w);
  return out;
}

}  // namespace

void SyntheticGaitOptions::validate() const {
  requireRange(v_x, -1.5, 1.5, "v_x");
  requireRange(v_y, -1.0, 1.0, "v_y");
  requireRange(yaw_rate, -2.0, 2.0, "yaw_rate");
  requireRange(base_height, 0.4, 0.82, "base_height");
  requireRange(period, 0.2, 3.0, "period");
  requireRange(duty, 0.3, 0.9, "duty");
  requireRange(step_height, 0.0, 0.2, "step_height");
  requireRange(stance_width, 0.1, 0.5, "stance_width");
  requireRange(stance_x, -0.3, 0.3, "stance_x");
  requireRange(dt, 1e-3, 0.05, "dt");
  requireRange(mu_left, 0.0, 1.0, "mu_left");
  requireRange(mu_right, 0.0, 1.0, "mu_right");
  const double n = period / dt;
  if (std::abs(n - std::round(n)) > 1e-9) {
    throw std::invalid_argument("SyntheticGaitOptions.period / dt = " + std::to_string(n) + ": expected an integer");
  }
}

SyntheticGait makeSyntheticGait(LegKinematics& kin, const SyntheticGaitOptions& o) {
  o.validate();
  SyntheticGait g;
  g.options = o;
  const int N = static_cast<int>(std::lround(o.period / o.dt));
  // Seed pose: slightly bent knees (the G1 default standing pose).
  LegVector seed;
  seed << -0.1, 0.0, 0.0, 0.3, -0.2, 0.0;
  std::array<LegVector, kNumFeet> q_warm{seed, seed};
  const std::array<double, kNumFeet> mu{o.mu_left, o.mu_right};
  const std::array<double, kNumFeet> side{o.stance_width / 2, -o.stance_width / 2};
  const double sigma = o.duty / 2;
  const double h_fd = 1e-6;  // central-difference step of the sole target [s]

  auto target = [&](std::size_t f, double t) {
    const SolePose sp = solePose(o, mu[f], side[f], t);
    Eigen::Isometry3d X_BS = Eigen::Isometry3d::Identity();
    X_BS.linear() = Eigen::AngleAxisd(sp.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X_BS.translation() = sp.p_HS - Eigen::Vector3d(0, 0, o.base_height);
    return X_BS;
  };
  auto solve = [&](std::size_t f, double t, LegVector* q) {
    const double err = kin.inverse(static_cast<Foot>(f), target(f, t), q_warm[f], q);
    g.ik_max_error = std::max(g.ik_max_error, err);
    if (!(err < 1e-6)) {
      throw std::runtime_error("makeSyntheticGait: IK failed for foot " + std::to_string(f) + " at t = " +
                               std::to_string(t) + " s (error " + std::to_string(err) +
                               "); the sole target is out of reach (check base_height, stance_width, v, period)");
    }
  };
  // q̇ = J(q)^-1 [ṗ_BS; ω_BF]: the sole target's twist relative to the pelvis (central difference
  // of the analytic target, ±h_fd), mapped through the leg Jacobian (built column by column).
  auto velocity = [&](std::size_t f, double t, const LegVector& q) {
    const Eigen::Isometry3d Xp = target(f, t + h_fd), Xm = target(f, t - h_fd);
    Eigen::Matrix<double, 6, 1> twist;
    twist.head<3>() = (Xp.translation() - Xm.translation()) / (2 * h_fd);
    const Eigen::AngleAxisd dR(Xp.linear() * Xm.linear().transpose());
    twist.tail<3>() = dR.axis() * dR.angle() / (2 * h_fd);
    Eigen::Matrix<double, 6, 6> J;
    for (int j = 0; j < kLegDofs; ++j) {
      FootKinematics k;
      kin.compute(static_cast<Foot>(f), q, LegVector::Unit(j), &k);
      J.col(j) << k.v_BS_B, k.w_BF_B;
    }
    return LegVector(J.partialPivLu().solve(twist));
  };

  // Run through the cycle twice so the warm start of the first sample comes from the previous cycle.
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 0; k < N; ++k) {
      const double t = k * o.dt;
      GcoInput in;
      for (std::size_t f = 0; f < kNumFeet; ++f) {
        LegVector q;
        solve(f, t, &q);
        q_warm[f] = q;
        in.q_leg[f] = q;
        in.qd_leg[f] = velocity(f, t, q);
        in.contact[f] = std::abs(phaseDiff(static_cast<double>(k) / N, mu[f])) * o.period <= sigma * o.period + 1e-12;
      }
      in.v_HB_H = Eigen::Vector3d(o.v_x + o.v_x_error, o.v_y + o.v_y_error, 0.0);
      in.w_HB_H = Eigen::Vector3d(0.0, 0.0, o.yaw_rate + o.yaw_rate_error);
      in.base_height = o.base_height + o.height_error;
      in.command.v_x = o.v_x;
      in.command.v_y = o.v_y;
      in.command.yaw_rate = o.yaw_rate;
      in.command.height = o.base_height;
      if (pass == 1) {
        g.phase.push_back(static_cast<double>(k) / N);
        g.ticks.push_back(in);
      }
    }
  }
  return g;
}

}  // namespace pmg::gco
