// Zero-point estimator (PMG eqs. 21-25) on the KDL leg chains. See include/pmg/calib/zero_calibration.hpp.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <ceres/tiny_solver.h>
#include <fmt/format.h>

#include "pmg/calib/zero_calibration.hpp"

namespace pmg::calib {
namespace {

using pmg::Foot;
using gco::LegVector;
using Vec8 = Eigen::Matrix<double, 8, 1>;

gco::LegVector leg(const ZeroVector& q, int f) { return q.segment<gco::kLegDofs>(gco::kLegDofs * f); }

Eigen::Matrix3d rotZ(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

void require(bool ok, const std::string& field, double value, const std::string& range) {
  if (!ok) throw std::invalid_argument(fmt::format("ZeroEstimatorOptions.{} = {}: expected {}", field, value, range));
}

double median(std::vector<double>& v) {
  const std::size_t n = v.size();
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
  const double hi = v[n / 2];
  if (n % 2 == 1) return hi;
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2));
  return 0.5 * (lo + hi);
}

}  // namespace

void ZeroEstimatorOptions::validate() const {
  require(std::isfinite(tau) && tau > 0.0 && tau <= 1.0, "tau", tau, "in (0, 1] rad");
  require(std::isfinite(alpha) && alpha > 0.0 && alpha <= 1.0, "alpha", alpha, "in (0, 1]");
  require(std::isfinite(epsilon) && epsilon > 0.0 && epsilon <= 0.1, "epsilon", epsilon, "in (0, 0.1] rad");
  require(consecutive >= 1 && consecutive <= 1000, "consecutive", consecutive, "an integer in [1, 1000] (M)");
  require(max_iterations >= 1 && max_iterations <= 1000000, "max_iterations", max_iterations, "in [1, 1e6]");
  require(min_poses >= 2 && min_poses <= 1000, "min_poses", min_poses, "in [2, 1000]");
  require(std::isfinite(constraint_weight) && constraint_weight >= 1e2 && constraint_weight <= 1e12,
          "constraint_weight", constraint_weight, "in [1e2, 1e12]");
  const double orth = (R_BI * R_BI.transpose() - Eigen::Matrix3d::Identity()).norm();
  require(R_BI.allFinite() && orth < 1e-6 && R_BI.determinant() > 0.0, "R_BI", orth,
          "a rotation matrix (|R R^T - I| < 1e-6, det +1)");
}

ZeroEstimator::ZeroEstimator(std::shared_ptr<const gco::LegModel> model, ZeroEstimatorOptions options)
    : model_(std::move(model)), options_(std::move(options)) {
  if (!model_) throw std::invalid_argument("ZeroEstimator: LegModel must not be null");
  options_.validate();
  kin_ = std::make_unique<gco::LegKinematics>(model_);
}

ZeroEstimator::~ZeroEstimator() = default;

Vec8 ZeroEstimator::constraint(const ZeroVector& q, const Eigen::Vector3d& p, const Eigen::Vector3d& up_I) {
  Eigen::Isometry3d X_BL, X_BR;
  Vec8 c = Vec8::Constant(std::numeric_limits<double>::quiet_NaN());
  if (!kin_->forward(Foot::kLeft, leg(q, 0), &X_BL) || !kin_->forward(Foot::kRight, leg(q, 1), &X_BR)) return c;
  const Eigen::Isometry3d X_WB = X_BL.inverse();
  const Eigen::Isometry3d X_WR = X_WB * X_BR;
  const Eigen::Matrix3d R_WR_nom = rotZ(p.z());
  c.segment<3>(0) = X_WR.translation() - Eigen::Vector3d(p.x(), p.y(), 0.0);
  const Eigen::AngleAxisd e(R_WR_nom.transpose() * X_WR.linear());
  c.segment<3>(3) = e.angle() * e.axis();
  const Eigen::Vector3d up_W = X_WB.linear() * options_.R_BI * up_I;
  c.segment<2>(6) = up_W.head<2>();
  return c;
}

Eigen::Vector3d ZeroEstimator::placementOf(const ZeroVector& q) {
  Eigen::Isometry3d X_BL, X_BR;
  if (!kin_->forward(Foot::kLeft, leg(q, 0), &X_BL) || !kin_->forward(Foot::kRight, leg(q, 1), &X_BR))
    throw std::invalid_argument("ZeroEstimator::placementOf: forward kinematics failed (non-finite joints)");
  const Eigen::Isometry3d X_LR = X_BL.inverse() * X_BR;
  const Eigen::Vector3d x_axis = X_LR.linear().col(0);
  return {X_LR.translation().x(), X_LR.translation().y(), std::atan2(x_axis.y(), x_axis.x())};
}

double ZeroEstimator::imuDisagreement(const ZeroVector& q, const Eigen::Vector3d& p, const Eigen::Vector3d& up_I) {
  Eigen::Isometry3d X_BL, X_BR;
  if (!kin_->forward(Foot::kLeft, leg(q, 0), &X_BL) || !kin_->forward(Foot::kRight, leg(q, 1), &X_BR))
    return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d up_B = (options_.R_BI * up_I).normalized();
  // Pelvis orientation implied by each leg with its sole flat on the floor: R_WB = R_WS R_BS^T.
  const Eigen::Vector3d up_left = X_BL.linear().transpose() * up_B;
  const Eigen::Vector3d up_right = rotZ(p.z()) * X_BR.linear().transpose() * up_B;
  const auto tilt = [](const Eigen::Vector3d& u) { return std::atan2(u.head<2>().norm(), u.z()); };
  return std::max(tilt(up_left), tilt(up_right));
}

namespace {

using PoseJacobian = Eigen::Matrix<double, 8, kZeroJoints + 3>;

/// Central-difference Jacobian of one pose's constraint c(q, p) w.r.t. (z, p) (columns: the 12
/// joint offsets, then the right-sole placement x, y, yaw), step 1e-6.
template <typename Constraint>
PoseJacobian poseJacobian(const Constraint& c, const ZeroVector& q, const Eigen::Vector3d& p) {
  constexpr double h = 1e-6;
  PoseJacobian J;
  for (int j = 0; j < kZeroJoints + 3; ++j) {
    ZeroVector qp = q, qm = q;
    Eigen::Vector3d pp = p, pm = p;
    if (j < kZeroJoints) {
      qp(j) += h;
      qm(j) -= h;
    } else {
      pp(j - kZeroJoints) += h;
      pm(j - kZeroJoints) -= h;
    }
    J.col(j) = (c(qp, pp) - c(qm, pm)) / (2.0 * h);
  }
  return J;
}

/// Per-pose solve in ceres::TinySolver's interface: x = (Δq (12), Δp (3)) around (q0, p0).
/// Residuals: Δq (12), Δp (3), sqrt(w_c) c(q0 + Δq, p0 + Δp) (8); c's Jacobian by central differences.
struct PoseCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = kZeroJoints + 3 + 8, NUM_PARAMETERS = kZeroJoints + 3 };
  ZeroEstimator* est = nullptr;
  ZeroVector q0 = ZeroVector::Zero();
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d up_I = Eigen::Vector3d::UnitZ();
  double sw = 1e3;

  Vec8 c(const Eigen::Matrix<double, NUM_PARAMETERS, 1>& x) const {
    return est->constraint(q0 + x.head<kZeroJoints>(), p0 + x.tail<3>(), up_I);
  }
  bool operator()(const double* xp, double* res, double* jac) const {
    const Eigen::Map<const Eigen::Matrix<double, NUM_PARAMETERS, 1>> x(xp);
    Eigen::Map<Eigen::Matrix<double, NUM_RESIDUALS, 1>> r(res);
    r.head<NUM_PARAMETERS>() = x;
    const Vec8 c0 = c(x);
    if (!c0.allFinite()) return false;
    r.tail<8>() = sw * c0;
    if (jac != nullptr) {
      Eigen::Map<Eigen::Matrix<double, NUM_RESIDUALS, NUM_PARAMETERS>> J(jac);
      J.setZero();
      J.topRows<NUM_PARAMETERS>().setIdentity();
      constexpr double h = 1e-6;
      for (int j = 0; j < NUM_PARAMETERS; ++j) {
        Eigen::Matrix<double, NUM_PARAMETERS, 1> xp1 = x, xm1 = x;
        xp1(j) += h;
        xm1(j) -= h;
        J.block<8, 1>(NUM_PARAMETERS, j) = sw * (c(xp1) - c(xm1)) / (2.0 * h);
      }
    }
    return true;
  }
};

}  // namespace

ZeroVector ZeroEstimator::solvePose(const ZeroVector& q0, const Eigen::Vector3d& p0, const Eigen::Vector3d& up_I,
                                    Eigen::Vector3d* p_out) {
  PoseCost cost;
  cost.est = this;
  cost.q0 = q0;
  cost.p0 = p0;
  cost.up_I = up_I;
  cost.sw = std::sqrt(options_.constraint_weight);
  ceres::TinySolver<PoseCost> solver;
  solver.options.max_num_iterations = 50;
  solver.options.gradient_tolerance = 1e-14;
  solver.options.parameter_tolerance = 1e-14;
  solver.options.function_tolerance = 1e-16;
  Eigen::Matrix<double, PoseCost::NUM_PARAMETERS, 1> x = Eigen::Matrix<double, PoseCost::NUM_PARAMETERS, 1>::Zero();
  solver.Solve(cost, &x);
  if (p_out != nullptr) *p_out = p0 + x.tail<3>();
  return q0 + x.head<kZeroJoints>();
}

ZeroObservability ZeroEstimator::observability(const std::vector<ZeroSample>& samples, const ZeroVector& z,
                                               const Eigen::Vector3d& p) {
  std::vector<const ZeroSample*> use;
  for (const auto& s : samples)
    if (s.valid) use.push_back(&s);
  Eigen::MatrixXd J(8 * static_cast<Eigen::Index>(use.size()), kZeroJoints + 3);
  for (std::size_t k = 0; k < use.size(); ++k) {
    const Eigen::Vector3d& up = use[k]->up_I;
    J.block<8, kZeroJoints + 3>(8 * static_cast<Eigen::Index>(k), 0) =
        poseJacobian([&](const ZeroVector& q, const Eigen::Vector3d& pl) { return constraint(q, pl, up); },
                     use[k]->readings + z, p);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
  ZeroObservability o;
  o.singular_values = svd.singularValues();
  const double smax = o.singular_values.size() > 0 ? o.singular_values(0) : 0.0;
  for (Eigen::Index i = 0; i < o.singular_values.size(); ++i)
    if (o.singular_values(i) > 1e-6 * smax) ++o.rank;
  if (svd.matrixV().cols() > 0) o.weakest_direction = svd.matrixV().col(svd.matrixV().cols() - 1);
  return o;
}

ZeroEstimate ZeroEstimator::estimate(const std::vector<ZeroSample>& samples, const ZeroVector& z0,
                                     const std::function<void(int, const ZeroVector&, double, int)>& progress) {
  ZeroEstimate out;
  const int n = static_cast<int>(samples.size());
  std::vector<bool> active(static_cast<std::size_t>(n), false);
  int first = -1;
  for (int k = 0; k < n; ++k) {
    const ZeroSample& s = samples[static_cast<std::size_t>(k)];
    const bool ok = s.valid && s.readings.allFinite() && s.up_I.allFinite() && s.up_I.norm() > 0.5;
    active[static_cast<std::size_t>(k)] = ok;
    if (!ok) out.rejected_capture.push_back(k);
    if (ok && first < 0) first = k;
  }
  const auto count_active = [&] { return static_cast<int>(std::count(active.begin(), active.end(), true)); };
  if (count_active() < options_.min_poses)
    throw std::invalid_argument(fmt::format("ZeroEstimator: {} usable poses of {}, need at least min_poses = {}",
                                            count_active(), n, options_.min_poses));
  ZeroVector z = z0;
  Eigen::Vector3d p = placementOf(samples[static_cast<std::size_t>(first)].readings + z);
  int below = 0;
  std::vector<ZeroVector> dq(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> dp(static_cast<std::size_t>(n));
  std::vector<double> col;
  for (int it = 1; it <= options_.max_iterations; ++it) {
    // Eq. 22: per-pose deviation delta_k of the model configuration from r_k + z.
    if (options_.per_pose == ZeroPerPose::kProjection) {
      for (int k = 0; k < n; ++k) {
        if (!active[static_cast<std::size_t>(k)]) continue;
        const ZeroSample& s = samples[static_cast<std::size_t>(k)];
        const ZeroVector q0 = s.readings + z;
        Eigen::Vector3d pk;
        dq[static_cast<std::size_t>(k)] = solvePose(q0, p, s.up_I, &pk) - q0;
        dp[static_cast<std::size_t>(k)] = pk - p;
      }
    } else {
      // Pose k's share of the Gauss-Newton step of the pose set, times the number of poses:
      // delta_k = -K H^-1 J_k^T c_k, H = sum_j J_j^T J_j (so that mean_k delta_k is the GN step).
      std::vector<Eigen::Matrix<double, 8, kZeroJoints + 3>> Jk(static_cast<std::size_t>(n));
      std::vector<Vec8> ck(static_cast<std::size_t>(n));
      Eigen::Matrix<double, kZeroJoints + 3, kZeroJoints + 3> H = Eigen::Matrix<double, kZeroJoints + 3, kZeroJoints + 3>::Zero();
      for (int k = 0; k < n; ++k) {
        if (!active[static_cast<std::size_t>(k)]) continue;
        const ZeroSample& s = samples[static_cast<std::size_t>(k)];
        const ZeroVector q = s.readings + z;
        ck[static_cast<std::size_t>(k)] = constraint(q, p, s.up_I);
        Jk[static_cast<std::size_t>(k)] =
            poseJacobian([&](const ZeroVector& qq, const Eigen::Vector3d& pl) { return constraint(qq, pl, s.up_I); }, q, p);
        H += Jk[static_cast<std::size_t>(k)].transpose() * Jk[static_cast<std::size_t>(k)];
      }
      H.diagonal().array() += 1e-12 * H.diagonal().maxCoeff();
      using Mat15 = Eigen::Matrix<double, kZeroJoints + 3, kZeroJoints + 3>;
      using Vec15 = Eigen::Matrix<double, kZeroJoints + 3, 1>;
      Vec15 g = Vec15::Zero();
      for (int k = 0; k < n; ++k)
        if (active[static_cast<std::size_t>(k)]) g += Jk[static_cast<std::size_t>(k)].transpose() * ck[static_cast<std::size_t>(k)];
      const Eigen::LDLT<Mat15> ldlt(H);
      const double K = count_active();
      for (int k = 0; k < n; ++k) {
        if (!active[static_cast<std::size_t>(k)]) continue;
        const auto& J = Jk[static_cast<std::size_t>(k)];
        const Vec8& c = ck[static_cast<std::size_t>(k)];
        Vec15 d;
        if (options_.per_pose == ZeroPerPose::kGaussNewtonShare) {
          d = -K * ldlt.solve(J.transpose() * c);
        } else {  // kLeaveOneOut
          const Mat15 Hk = H - J.transpose() * J;
          d = -Eigen::LDLT<Mat15>(Hk).solve(g - J.transpose() * c);
        }
        dq[static_cast<std::size_t>(k)] = d.template head<kZeroJoints>();
        dp[static_cast<std::size_t>(k)] = d.template tail<3>();
      }
    }
    // Eq. 23: median over the used poses, per joint (and per placement coordinate).
    ZeroVector delta;
    Eigen::Vector3d delta_p;
    for (int j = 0; j < kZeroJoints + 3; ++j) {
      col.clear();
      for (int k = 0; k < n; ++k)
        if (active[static_cast<std::size_t>(k)])
          col.push_back(j < kZeroJoints ? dq[static_cast<std::size_t>(k)](j)
                                        : dp[static_cast<std::size_t>(k)](j - kZeroJoints));
      double m = 0.0;
      if (options_.combine == ZeroCombine::kMedian) {
        m = median(col);
      } else {
        for (double v : col) m += v / static_cast<double>(col.size());
      }
      (j < kZeroJoints ? delta(j) : delta_p(j - kZeroJoints)) = m;
    }
    // Eq. 24: update.
    z += options_.alpha * delta;
    p += options_.alpha * delta_p;
    const double step = (options_.alpha * delta).cwiseAbs().maxCoeff();
    out.history.push_back(z);
    out.step_history.push_back(step);
    out.iterations = it;
    if (progress) progress(it, z, step, count_active());
    // Eq. 25: convergence over M consecutive iterations.
    below = step < options_.epsilon ? below + 1 : 0;
    if (below >= options_.consecutive) {
      // Eq. 21 gate: poses whose model still disagrees with their IMU by more than tau.
      std::vector<int> newly;
      for (int k = 0; k < n; ++k) {
        if (!active[static_cast<std::size_t>(k)]) continue;
        const ZeroSample& s = samples[static_cast<std::size_t>(k)];
        if (imuDisagreement(s.readings + z, p, s.up_I) > options_.tau) newly.push_back(k);
      }
      if (newly.empty()) {
        out.converged = true;
        break;
      }
      // Exclude the worst offender only: a pose that disagrees because of another's corruption can recover.
      int worst = newly.front();
      double worst_e = -1.0;
      for (int k : newly) {
        const ZeroSample& s = samples[static_cast<std::size_t>(k)];
        const double e = imuDisagreement(s.readings + z, p, s.up_I);
        if (e > worst_e) {
          worst_e = e;
          worst = k;
        }
      }
      active[static_cast<std::size_t>(worst)] = false;
      out.rejected_tau.push_back(worst);
      below = 0;
      if (count_active() < options_.min_poses) {
        out.message = fmt::format("tau gate left {} poses, fewer than min_poses = {}", count_active(),
                                  options_.min_poses);
        break;
      }
    }
  }
  out.z = z;
  out.placement = p;
  for (int k = 0; k < n; ++k) {
    const ZeroSample& s = samples[static_cast<std::size_t>(k)];
    if (active[static_cast<std::size_t>(k)]) out.used.push_back(k);
    const ZeroVector q = s.readings + z;
    out.imu_disagreement.push_back(s.readings.allFinite() ? imuDisagreement(q, p, s.up_I)
                                                          : std::numeric_limits<double>::quiet_NaN());
    out.closure_residual.push_back(s.readings.allFinite() ? constraint(q, p, s.up_I).head<3>().norm()
                                                          : std::numeric_limits<double>::quiet_NaN());
  }
  if (out.converged) {
    out.message = fmt::format("converged after {} iterations ({} poses used, {} refused at capture, {} excluded by tau)",
                              out.iterations, out.used.size(), out.rejected_capture.size(), out.rejected_tau.size());
  } else if (out.message.empty()) {
    out.message = fmt::format("not converged: |alpha delta| < epsilon = {} not held for M = {} iterations within "
                              "max_iterations = {} (last step {:.3g} rad)",
                              options_.epsilon, options_.consecutive, options_.max_iterations,
                              out.step_history.empty() ? 0.0 : out.step_history.back());
  }
  return out;
}

}  // namespace pmg::calib
