#include "pmg/gco/gco.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <ceres/tiny_solver.h>

namespace pmg::gco {

namespace {

void requireRange(double value, double lo, double hi, const char* field) {
  if (!(value >= lo && value <= hi)) {
    throw std::invalid_argument(std::string("GcoOptions.") + field + " = " + std::to_string(value) +
                                ": expected a value in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
}

void requireOrdered(double lo, double hi, const char* field) {
  if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi)) {
    throw std::invalid_argument(std::string("GcoOptions.limits.") + field + ": expected finite min < max, got [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
}

constexpr int kNumResiduals = 20;
constexpr int kNumParameters = 4;
using Vec4 = Eigen::Matrix<double, kNumParameters, 1>;

/// Per-tick data of the least-squares problem (filled before each solve; x = 0 values).
struct TickProblem {
  std::array<Eigen::Vector3d, kNumFeet> r{};   ///< r_f = R_HB p_BS_B [m]
  std::array<Eigen::Vector3d, kNumFeet> v0{};  ///< sole velocity at x = 0 [m/s]
  std::array<double, kNumFeet> wz0{};          ///< foot yaw rate at x = 0 [rad/s]
  std::array<double, kNumFeet> z0{};           ///< sole height above ground at x = 0 [m]
  std::array<double, kNumFeet> s{};            ///< contact weights
  Vec4 x_prev = Vec4::Zero();                  ///< last tick's x
  Vec4 base = Vec4::Zero();                    ///< template (v_x, v_y, ω, h)
  Vec4 lo = Vec4::Zero(), hi = Vec4::Zero();   ///< command limits
  Vec4 w_prior = Vec4::Zero(), w_smooth = Vec4::Zero();
  double w_v = 1, w_yaw = 1, w_h = 1, w_limit = 1;
};

/// Residuals and analytic Jacobian of eqs. 16-18 (see gco.hpp), in ceres::TinySolver's interface.
struct GcoCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = kNumResiduals, NUM_PARAMETERS = kNumParameters };
  const TickProblem* p = nullptr;

  bool operator()(const double* x, double* res, double* jac) const {
    Eigen::Map<Eigen::Matrix<double, kNumResiduals, 1>> r(res);
    r.setZero();
    Eigen::Matrix<double, kNumResiduals, kNumParameters> J;
    J.setZero();
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      const int i = 4 * static_cast<int>(f);
      const double s = p->s[f];
      const Eigen::Vector3d& rf = p->r[f];
      r(i + 0) = s * p->w_v * (p->v0[f].x() + x[0] - x[2] * rf.y());
      r(i + 1) = s * p->w_v * (p->v0[f].y() + x[1] + x[2] * rf.x());
      r(i + 2) = s * p->w_yaw * (p->wz0[f] + x[2]);
      r(i + 3) = s * p->w_h * (p->z0[f] + x[3]);
      J(i + 0, 0) = s * p->w_v;
      J(i + 0, 2) = -s * p->w_v * rf.y();
      J(i + 1, 1) = s * p->w_v;
      J(i + 1, 2) = s * p->w_v * rf.x();
      J(i + 2, 2) = s * p->w_yaw;
      J(i + 3, 3) = s * p->w_h;
    }
    for (int j = 0; j < kNumParameters; ++j) {
      r(8 + j) = p->w_prior(j) * x[j];
      J(8 + j, j) = p->w_prior(j);
      r(12 + j) = p->w_smooth(j) * (x[j] - p->x_prev(j));
      J(12 + j, j) = p->w_smooth(j);
      const double u = p->base(j) + x[j];
      if (u >= p->hi(j)) {  // active at the bound itself, where the warm start is projected
        r(16 + j) = p->w_limit * (u - p->hi(j));
        J(16 + j, j) = p->w_limit;
      } else if (u <= p->lo(j)) {
        r(16 + j) = p->w_limit * (u - p->lo(j));
        J(16 + j, j) = p->w_limit;
      }
    }
    if (jac != nullptr) {
      Eigen::Map<Eigen::Matrix<double, kNumResiduals, kNumParameters>> J_out(jac);
      J_out = J;
    }
    return true;
  }
};

bool finite(const GcoInput& in) {
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (!in.q_leg[f].allFinite() || !in.qd_leg[f].allFinite()) return false;
  }
  return in.v_HB_H.allFinite() && in.w_HB_H.allFinite() && std::isfinite(in.base_height) &&
         std::isfinite(in.base_roll) && std::isfinite(in.base_pitch) && std::isfinite(in.command.pitch) &&
         std::isfinite(in.command.roll);
}

}  // namespace

void GcoOptions::validate() const {
  requireRange(dt, 1e-4, 0.1, "dt");
  requireRange(ground_height, -10.0, 10.0, "ground_height");
  requireRange(w_foot_velocity, 1e-6, 1e6, "w_foot_velocity");
  requireRange(w_foot_yaw_rate, 0.0, 1e6, "w_foot_yaw_rate");
  requireRange(w_foot_height, 1e-6, 1e6, "w_foot_height");
  requireRange(w_prior_velocity, 1e-9, 1e6, "w_prior_velocity");
  requireRange(w_prior_yaw_rate, 1e-9, 1e6, "w_prior_yaw_rate");
  requireRange(w_prior_height, 1e-9, 1e6, "w_prior_height");
  requireRange(w_smooth_velocity, 0.0, 1e6, "w_smooth_velocity");
  requireRange(w_smooth_yaw_rate, 0.0, 1e6, "w_smooth_yaw_rate");
  requireRange(w_smooth_height, 0.0, 1e6, "w_smooth_height");
  requireRange(w_limit, 0.0, 1e9, "w_limit");
  requireOrdered(limits.v_x_min, limits.v_x_max, "v_x_min/v_x_max");
  requireOrdered(limits.v_y_min, limits.v_y_max, "v_y_min/v_y_max");
  requireOrdered(limits.yaw_rate_min, limits.yaw_rate_max, "yaw_rate_min/yaw_rate_max");
  requireOrdered(limits.height_min, limits.height_max, "height_min/height_max");
  requireRange(contact_ramp_time, 0.0, 1.0, "contact_ramp_time");
  requireRange(max_jump_velocity, 1e-6, 10.0, "max_jump_velocity");
  requireRange(max_jump_yaw_rate, 1e-6, 10.0, "max_jump_yaw_rate");
  requireRange(max_jump_height, 1e-6, 1.0, "max_jump_height");
  requireRange(max_iterations, 1, 100, "max_iterations");
  requireRange(newton_polish_iterations, 0, 20, "newton_polish_iterations");
  requireRange(failure_gradient_norm, 0.0, 1e6, "failure_gradient_norm");
  sole_levelling.validate();
  stride_adaptation.validate();
}

const char* toString(GcoStatus status) noexcept {
  switch (status) {
    case GcoStatus::kOk: return "ok";
    case GcoStatus::kDisabled: return "disabled";
    case GcoStatus::kSolverFailure: return "solver_failure";
    case GcoStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

void fillLegState(const LegJointIndex& leg_idx, const Eigen::Ref<const Eigen::VectorXd>& q,
                  const Eigen::Ref<const Eigen::VectorXd>& qd, GcoInput* in) noexcept {
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    for (int j = 0; j < kLegDofs; ++j) {
      in->q_leg[f](j) = q(leg_idx[f][j]);
      in->qd_leg[f](j) = qd(leg_idx[f][j]);
    }
  }
}

struct Gco::Impl {
  explicit Impl(std::shared_ptr<const LegModel> model) : kin(std::move(model)) {}
  LegKinematics kin;
  TickProblem problem;
  GcoCost cost;
  ceres::TinySolver<GcoCost> solver;
  std::array<FootKinematics, kNumFeet> feet{};
  Vec4 x = Vec4::Zero();              ///< last published x (smoothness reference)
  Vec4 x_iter = Vec4::Zero();         ///< last solver iterate (warm start, also after a failure)
  Vec4 x_good = Vec4::Zero();         ///< last good solver solution
  Vec4 u_prev = Vec4::Zero();         ///< last published (v'_x, v'_y, ω', h')
  BaseCommand u_good;                 ///< last published u' (for invalid input)
  std::array<double, kNumFeet> s{0.0, 0.0};
  bool have_prev = false;
};

Gco::Gco(std::shared_ptr<const LegModel> model, const GcoOptions& options) : model_(std::move(model)), options_(options) {
  if (!model_) throw std::invalid_argument("Gco: LegModel must not be null");
  options_.validate();
  impl_ = std::make_unique<Impl>(model_);
  impl_->cost.p = &impl_->problem;
  auto& so = impl_->solver.options;
  so.max_num_iterations = options_.max_iterations + 1;  // TinySolver counts the initial evaluation
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  so.function_tolerance = 1e-14;
  so.cost_threshold = 1e-16;
  TickProblem& p = impl_->problem;
  p.w_v = options_.w_foot_velocity;
  p.w_yaw = options_.w_foot_yaw_rate;
  p.w_h = options_.w_foot_height;
  p.w_limit = options_.w_limit;
  p.w_prior << options_.w_prior_velocity, options_.w_prior_velocity, options_.w_prior_yaw_rate, options_.w_prior_height;
  p.w_smooth << options_.w_smooth_velocity, options_.w_smooth_velocity, options_.w_smooth_yaw_rate,
      options_.w_smooth_height;
  const CommandLimits& l = options_.limits;
  p.lo << l.v_x_min, l.v_y_min, l.yaw_rate_min, l.height_min;
  p.hi << l.v_x_max, l.v_y_max, l.yaw_rate_max, l.height_max;
}

Gco::~Gco() = default;

void Gco::reset() noexcept {
  impl_->x.setZero();
  impl_->x_iter.setZero();
  impl_->x_good.setZero();
  impl_->u_prev.setZero();
  impl_->s = {0.0, 0.0};
  impl_->have_prev = false;
  counters_ = GcoCounters{};
}

void Gco::setEnabled(bool enabled) noexcept {
  options_.enabled = enabled;
  reset();
}

GcoStatus Gco::solve(const GcoInput& in, GcoResult* out) noexcept {
  Impl& m = *impl_;
  TickProblem& p = m.problem;
  ++counters_.ticks;
  out->jump_limited = false;
  out->iterations = 0;
  out->initial_cost = 0.0;
  out->final_cost = 0.0;

  // Kinematics (eqs. 13-14) of both feet; invalid input -> last good u'.
  bool ok = finite(in);
  for (std::size_t f = 0; ok && f < kNumFeet; ++f) {
    ok = m.kin.compute(static_cast<Foot>(f), in.q_leg[f], in.qd_leg[f], &m.feet[f]);
  }
  if (!ok) {
    ++counters_.invalid_inputs;
    out->u_opt = m.u_good;
    out->delta = m.x;
    out->status = GcoStatus::kInvalidInput;
    return out->status;
  }

  // Contact weights s_f.
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (!in.contact[f]) {
      m.s[f] = 0.0;
    } else if (!m.have_prev || options_.contact_ramp_time <= 0.0) {
      m.s[f] = 1.0;
    } else {
      m.s[f] = std::min(1.0, m.s[f] + options_.dt / options_.contact_ramp_time);
    }
  }

  // Problem data at x = 0.
  const double cr = std::cos(in.base_roll), sr = std::sin(in.base_roll);
  const double cp = std::cos(in.base_pitch), sp = std::sin(in.base_pitch);
  Eigen::Matrix3d R_HB;  // Ry(pitch) * Rx(roll)
  R_HB << cp, sp * sr, sp * cr, 0.0, cr, -sr, -sp, cp * sr, cp * cr;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const FootKinematics& k = m.feet[f];
    p.r[f] = R_HB * k.p_BS_B;
    p.v0[f] = in.v_HB_H + in.w_HB_H.cross(p.r[f]) + R_HB * k.v_BS_B;
    p.wz0[f] = in.w_HB_H.z() + (R_HB * k.w_BF_B).z();
    p.z0[f] = in.base_height + p.r[f].z() - options_.ground_height;
    p.s[f] = m.s[f];
  }
  p.base << in.v_HB_H.x(), in.v_HB_H.y(), in.w_HB_H.z(), in.base_height;
  p.x_prev = m.x;

  GcoStatus status = GcoStatus::kDisabled;
  Vec4 x = Vec4::Zero();
  if (options_.enabled) {
    // Warm start: last iterate, projected into the command limits, then polished by Newton steps
    // on the active hinge set. Every residual is affine in x (the hinges piecewise affine), so each
    // step lands on the exact minimiser of the current piece; a few steps settle the active set.
    // Without it, Levenberg-Marquardt zig-zags across a hinge kink (curvature jumps by w_limit²)
    // and hit the iteration cap on ~3 % of the ticks of a limit-clamping schedule. The same
    // active-set solve is the training-side port (training/pmg_train/gco.py).
    x = (p.base + m.x_iter).cwiseMax(p.lo).cwiseMin(p.hi) - p.base;
    {
      Eigen::Matrix<double, kNumResiduals, 1> r;
      Eigen::Matrix<double, kNumResiduals, kNumParameters> J;
      for (int it = 0; it < options_.newton_polish_iterations; ++it) {
        m.cost(x.data(), r.data(), J.data());
        const Vec4 step = (J.transpose() * J).ldlt().solve(J.transpose() * r);
        if (!step.allFinite()) break;
        x -= step;
        if (step.cwiseAbs().maxCoeff() < 1e-13) break;
      }
    }
    const auto& summary = m.solver.Solve(m.cost, &x);
    if (x.allFinite()) m.x_iter = x;
    out->iterations = summary.iterations;
    out->initial_cost = summary.initial_cost;
    out->final_cost = summary.final_cost;
    const bool failed = !x.allFinite() || !std::isfinite(summary.final_cost) ||
                        (summary.status == ceres::TinySolver<GcoCost>::HIT_MAX_ITERATIONS &&
                         summary.gradient_max_norm > options_.failure_gradient_norm);
    if (failed) {
      ++counters_.solver_failures;
      x = m.x_good;
      status = GcoStatus::kSolverFailure;
    } else {
      m.x_good = x;
      status = GcoStatus::kOk;
    }
  }

  // u' = template + x, clamped to the limits and to the per-tick jump bound.
  Vec4 u = p.base + x;
  if (options_.enabled) {
    const Vec4 u_lim = u.cwiseMax(p.lo).cwiseMin(p.hi);
    if ((u_lim - u).cwiseAbs().maxCoeff() > 0.0) ++counters_.limit_clamped;
    u = u_lim;
    if (m.have_prev) {
      const Vec4 jump(options_.max_jump_velocity, options_.max_jump_velocity, options_.max_jump_yaw_rate,
                      options_.max_jump_height);
      const Vec4 u_j = u.cwiseMax(m.u_prev - jump).cwiseMin(m.u_prev + jump);
      if ((u_j - u).cwiseAbs().maxCoeff() > 0.0) {
        out->jump_limited = true;
        ++counters_.jump_limited;
      }
      u = u_j;
    }
    x = u - p.base;
  }
  m.x = x;
  m.u_prev = u;
  m.have_prev = true;

  out->delta = x;
  out->u_opt.v_x = u(0);
  out->u_opt.v_y = u(1);
  out->u_opt.yaw_rate = u(2);
  out->u_opt.height = u(3);
  out->u_opt.pitch = in.command.pitch;
  out->u_opt.roll = in.command.roll;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    out->contact_weight[f] = p.s[f];
    out->v_WS_H[f] = p.v0[f] + Eigen::Vector3d(x(0) - x(2) * p.r[f].y(), x(1) + x(2) * p.r[f].x(), 0.0);
    out->sole_height[f] = p.z0[f] + x(3);
  }
  m.u_good = out->u_opt;
  out->status = status;
  return status;
}

}  // namespace pmg::gco
