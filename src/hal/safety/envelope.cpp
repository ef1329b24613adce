#include "pmg/hal/safety/envelope.hpp"

#include <algorithm>
#include <cmath>

namespace pmg::hal::safety {

double predictedTorque(const JointSetpoint& sp, double q, double qd) noexcept {
  return sp.kp * (sp.q - q) + sp.kd * (sp.qd - qd) + sp.tau_ff;
}

namespace {
bool clampTo(double& x, double lo, double hi) noexcept {
  if (x < lo) {
    x = lo;
    return true;
  }
  if (x > hi) {
    x = hi;
    return true;
  }
  return false;
}
}  // namespace

std::uint8_t clampSetpoint(const JointLimits& L, double q, double qd, JointSetpoint& sp) noexcept {
  std::uint8_t bits = 0;
  if (!std::isfinite(q) || !std::isfinite(qd)) {
    // Without a measurement no PD term can be bounded: command zero torque.
    sp = JointSetpoint{};
    sp.q = std::isfinite(q) ? q : 0.0;
    return kClampNonFinite;
  }
  if (!std::isfinite(sp.q)) { sp.q = q; bits |= kClampNonFinite; }
  if (!std::isfinite(sp.qd)) { sp.qd = 0.0; bits |= kClampNonFinite; }
  if (!std::isfinite(sp.kp)) { sp.kp = 0.0; bits |= kClampNonFinite; }
  if (!std::isfinite(sp.kd)) { sp.kd = 0.0; bits |= kClampNonFinite; }
  if (!std::isfinite(sp.tau_ff)) { sp.tau_ff = 0.0; bits |= kClampNonFinite; }
  if (clampTo(sp.kp, 0.0, L.kp_max) | clampTo(sp.kd, 0.0, L.kd_max)) bits |= kClampGain;
  if (clampTo(sp.q, L.q_min, L.q_max)) bits |= kClampPosition;
  if (clampTo(sp.qd, -L.qd_max, L.qd_max)) bits |= kClampVelocity;
  bool torque = clampTo(sp.tau_ff, -L.tau_max, L.tau_max);
  // Damping + feed-forward part first, then the stiffness part gets what is left.
  const double e = sp.kd * (sp.qd - qd) + sp.tau_ff;
  const double e_c = std::clamp(e, -L.tau_max, L.tau_max);
  if (e_c != e) {
    torque = true;
    if (sp.kd > 0.0) sp.qd = qd + (e_c - sp.tau_ff) / sp.kd;
  }
  const double e2 = sp.kd * (sp.qd - qd) + sp.tau_ff;
  const double p = sp.kp * (sp.q - q);
  const double p_c = std::clamp(p, -L.tau_max - e2, L.tau_max - e2);
  if (p_c != p) {
    torque = true;
    if (sp.kp > 0.0) sp.q = q + p_c / sp.kp;
  }
  if (torque) bits |= kClampTorque;
  return bits;
}

std::uint8_t slewLimit(double q_prev, double tau_prev, double max_dq, double max_dtau, JointSetpoint& sp) noexcept {
  bool c = false;
  if (std::isfinite(q_prev)) c |= clampTo(sp.q, q_prev - max_dq, q_prev + max_dq);
  if (std::isfinite(tau_prev)) c |= clampTo(sp.tau_ff, tau_prev - max_dtau, tau_prev + max_dtau);
  return c ? kClampSlew : 0;
}

double baseTilt(const double qv[4]) noexcept {
  const double w = qv[0], x = qv[1], y = qv[2], z = qv[3];
  const double n2 = w * w + x * x + y * y + z * z;
  if (!std::isfinite(n2) || n2 <= 1e-12) return std::nan("");
  // R_WB(2,2) for a (possibly non-unit) quaternion.
  const double r22 = 1.0 - 2.0 * (x * x + y * y) / n2;
  return std::acos(std::clamp(r22, -1.0, 1.0));
}

}  // namespace pmg::hal::safety
