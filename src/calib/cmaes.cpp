#include "pmg/calib/cmaes.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

namespace pmg::calib {

void CmaesOptions::validate() const {
  if (lambda != 0 && lambda < 2)
    throw std::invalid_argument(fmt::format("CmaesOptions.lambda = {}: expected 0 (default) or >= 2", lambda));
  if (!(sigma0 > 0.0 && sigma0 <= 1.0))
    throw std::invalid_argument(fmt::format("CmaesOptions.sigma0 = {}: expected in (0, 1] (unit box)", sigma0));
  if (max_evals < 2) throw std::invalid_argument(fmt::format("CmaesOptions.max_evals = {}: expected >= 2", max_evals));
  if (!(x_tol >= 0.0)) throw std::invalid_argument(fmt::format("CmaesOptions.x_tol = {}: expected >= 0", x_tol));
  if (!(f_tol >= 0.0)) throw std::invalid_argument(fmt::format("CmaesOptions.f_tol = {}: expected >= 0", f_tol));
  if (threads < 1) throw std::invalid_argument(fmt::format("CmaesOptions.threads = {}: expected >= 1", threads));
}

Cmaes::Cmaes(const Eigen::VectorXd& x0, const CmaesOptions& options)
    : opt_(options), rng_(options.seed), best_f_(std::numeric_limits<double>::infinity()) {
  opt_.validate();
  const int n = static_cast<int>(x0.size());
  if (n < 1) throw std::invalid_argument("Cmaes: x0 is empty: expected dimension n >= 1");
  for (int i = 0; i < n; ++i)
    if (!(x0[i] >= 0.0 && x0[i] <= 1.0))
      throw std::invalid_argument(fmt::format("Cmaes: x0[{}] = {}: expected in [0, 1] (unit box)", i, x0[i]));
  const double nd = n;
  // Defaults, table 1 / eqs. (48)-(58).
  lambda_ = opt_.lambda > 0 ? opt_.lambda : 4 + static_cast<int>(std::floor(3.0 * std::log(nd)));  // (48)
  if (lambda_ > opt_.max_evals)
    throw std::invalid_argument(
        fmt::format("CmaesOptions.max_evals = {}: expected >= lambda = {}", opt_.max_evals, lambda_));
  mu_ = lambda_ / 2;
  Eigen::VectorXd wp(lambda_);  // w'_i, eq. (49)
  for (int i = 0; i < lambda_; ++i) wp[i] = std::log((lambda_ + 1) / 2.0) - std::log(i + 1.0);
  const Eigen::VectorXd pos = wp.head(mu_), neg = wp.tail(lambda_ - mu_);
  mu_eff_ = pos.sum() * pos.sum() / pos.squaredNorm();                                       // (50)
  const double mu_eff_neg = neg.squaredNorm() > 0 ? neg.sum() * neg.sum() / neg.squaredNorm() : 0.0;  // (51)
  const double alpha_cov = 2.0;
  c_1_ = alpha_cov / ((nd + 1.3) * (nd + 1.3) + mu_eff_);                                   // (57)
  c_mu_ = std::min(1.0 - c_1_, alpha_cov * (mu_eff_ - 2.0 + 1.0 / mu_eff_) /
                                   ((nd + 2.0) * (nd + 2.0) + alpha_cov * mu_eff_ / 2.0));  // (58)
  c_mu_ = std::max(0.0, c_mu_);
  c_sigma_ = (mu_eff_ + 2.0) / (nd + mu_eff_ + 5.0);                                        // (55)
  d_sigma_ = 1.0 + 2.0 * std::max(0.0, std::sqrt((mu_eff_ - 1.0) / (nd + 1.0)) - 1.0) + c_sigma_;
  c_c_ = (4.0 + mu_eff_ / nd) / (nd + 4.0 + 2.0 * mu_eff_ / nd);                            // (56)
  // Negative weights, eq. (53): scaled by min(alpha_mu^-, alpha_mueff^-, alpha_posdef^-).
  const double inf = std::numeric_limits<double>::infinity();
  const double a_mu = c_mu_ > 0 ? 1.0 + c_1_ / c_mu_ : inf;
  const double a_mueff = 1.0 + 2.0 * mu_eff_neg / (mu_eff_ + 2.0);
  const double a_posdef = c_mu_ > 0 ? (1.0 - c_1_ - c_mu_) / (nd * c_mu_) : inf;
  const double a_neg = std::min({a_mu, a_mueff, a_posdef});
  w_.resize(lambda_);
  const double sum_pos = pos.sum(), sum_neg_abs = -neg.sum();
  for (int i = 0; i < lambda_; ++i) w_[i] = wp[i] >= 0 ? wp[i] / sum_pos : a_neg * wp[i] / sum_neg_abs;
  chi_n_ = std::sqrt(nd) * (1.0 - 1.0 / (4.0 * nd) + 1.0 / (21.0 * nd * nd));  // E|N(0, I)|

  mean_ = x0;
  sigma_ = opt_.sigma0;
  p_sigma_ = Eigen::VectorXd::Zero(n);
  p_c_ = Eigen::VectorXd::Zero(n);
  C_ = Eigen::MatrixXd::Identity(n, n);
  decompose();
  best_x_ = x0;
}

void Cmaes::decompose() {
  C_ = 0.5 * (C_ + C_.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(C_);
  B_ = es.eigenvectors();
  D_ = es.eigenvalues().cwiseMax(1e-300).cwiseSqrt();  // C = B diag(D^2) B^T
  C_inv_sqrt_ = B_ * D_.cwiseInverse().asDiagonal() * B_.transpose();
}

const std::vector<Eigen::VectorXd>& Cmaes::ask() {
  if (asked_) return eval_;
  const int n = dimension();
  raw_.assign(lambda_, Eigen::VectorXd(n));
  eval_.assign(lambda_, Eigen::VectorXd(n));
  Eigen::VectorXd z(n);
  for (int k = 0; k < lambda_; ++k) {
    for (int i = 0; i < n; ++i) z[i] = normal_(rng_);               // (38)
    raw_[k] = mean_ + sigma_ * (B_ * D_.asDiagonal() * z);           // (39)-(40)
    eval_[k] = raw_[k].cwiseMax(0.0).cwiseMin(1.0);                  // repair for evaluation
  }
  asked_ = true;
  return eval_;
}

void Cmaes::tell(const std::vector<double>& f_in) {
  if (!asked_) throw std::invalid_argument("Cmaes::tell: no ask() since the last tell()");
  if (static_cast<int>(f_in.size()) != lambda_)
    throw std::invalid_argument(fmt::format("Cmaes::tell: {} values: expected lambda = {}", f_in.size(), lambda_));
  asked_ = false;
  const int n = dimension();
  const double nd = n;
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> f(f_in);
  for (auto& v : f)
    if (!std::isfinite(v)) v = inf;
  evals_ += lambda_;
  for (int k = 0; k < lambda_; ++k)
    if (f[k] < best_f_) {
      best_f_ = f[k];
      best_x_ = eval_[k];
    }

  // Penalised ranking values of the repaired samples (box handling, see the header).
  std::vector<double> finite;
  for (double v : f)
    if (v < inf) finite.push_back(v);
  double w_pen = 0.0, f_range = inf;
  if (!finite.empty()) {
    std::sort(finite.begin(), finite.end());
    const auto q = [&](double p) {
      return finite[static_cast<std::size_t>(p * static_cast<double>(finite.size() - 1) + 0.5)];
    };
    w_pen = std::max(q(0.75) - q(0.25), 1e-12 * (1.0 + std::abs(q(0.5))));
    f_range = finite.back() - finite.front();
  }
  const double var_scale = sigma_ * sigma_ * C_.diagonal().mean();
  std::vector<double> ranked(lambda_);
  for (int k = 0; k < lambda_; ++k) ranked[k] = f[k] + w_pen * (raw_[k] - eval_[k]).squaredNorm() / var_scale;
  std::vector<int> order(lambda_);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return ranked[a] < ranked[b]; });

  // Selection and recombination, eqs. (41)-(42), c_m = 1.
  std::vector<Eigen::VectorXd> y(lambda_);
  for (int i = 0; i < lambda_; ++i) y[i] = (raw_[order[i]] - mean_) / sigma_;  // y_{i:lambda}
  Eigen::VectorXd y_w = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < mu_; ++i) y_w += w_[i] * y[i];
  mean_ += sigma_ * y_w;

  // Step-size path, eq. (43).
  p_sigma_ = (1.0 - c_sigma_) * p_sigma_ + std::sqrt(c_sigma_ * (2.0 - c_sigma_) * mu_eff_) * (C_inv_sqrt_ * y_w);
  // Stall indicator h_sigma and covariance path, eq. (45).
  const double ps_norm = p_sigma_.norm();
  const double hs_lhs = ps_norm / std::sqrt(1.0 - std::pow(1.0 - c_sigma_, 2.0 * (gen_ + 1)));
  const bool h_sigma = hs_lhs < (1.4 + 2.0 / (nd + 1.0)) * chi_n_;
  p_c_ = (1.0 - c_c_) * p_c_ + (h_sigma ? std::sqrt(c_c_ * (2.0 - c_c_) * mu_eff_) : 0.0) * y_w;
  // Covariance update, eqs. (46)-(47).
  const double delta_h = (h_sigma ? 0.0 : 1.0) * c_c_ * (2.0 - c_c_);
  Eigen::MatrixXd rank_mu = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < lambda_; ++i) {
    double wo = w_[i];
    if (wo < 0) wo *= nd / std::max((C_inv_sqrt_ * y[i]).squaredNorm(), 1e-300);  // (46)
    rank_mu += wo * y[i] * y[i].transpose();
  }
  C_ = (1.0 + c_1_ * delta_h - c_1_ - c_mu_ * w_.sum()) * C_ + c_1_ * p_c_ * p_c_.transpose() + c_mu_ * rank_mu;
  // Step size, eq. (44); the exponent is capped at 1 (at most a factor e per generation), a guard
  // against a sigma blow-up after a long first step.
  sigma_ *= std::exp(std::min(1.0, (c_sigma_ / d_sigma_) * (ps_norm / chi_n_ - 1.0)));
  decompose();
  ++gen_;

  // Stop criteria.
  double gen_best = inf;
  for (double v : f) gen_best = std::min(gen_best, v);
  best_history_.push_back(gen_best);
  const std::size_t hist = 10 + static_cast<std::size_t>(std::ceil(30.0 * nd / lambda_));
  if (best_history_.size() > hist) best_history_.erase(best_history_.begin());
  const double max_sd = sigma_ * C_.diagonal().cwiseSqrt().maxCoeff();
  if (max_sd < opt_.x_tol && sigma_ * p_c_.cwiseAbs().maxCoeff() < opt_.x_tol) {
    stop_reason_ = "x_tol";
  } else if (best_history_.size() == hist && f_range < opt_.f_tol) {
    const auto [lo, hi] = std::minmax_element(best_history_.begin(), best_history_.end());
    if (*hi - *lo < opt_.f_tol) stop_reason_ = "f_tol";
  }
  if (stop_reason_.empty() && D_.maxCoeff() * D_.maxCoeff() > 1e14 * D_.minCoeff() * D_.minCoeff())
    stop_reason_ = "condition";
}

std::vector<double> evaluate_parallel(const std::vector<Eigen::VectorXd>& points, const PointObjective& f,
                                      int threads) {
  if (threads < 1) throw std::invalid_argument(fmt::format("evaluate_parallel: threads = {}: expected >= 1", threads));
  std::vector<double> out(points.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::exception_ptr> errors(points.size());
  std::atomic<std::size_t> next{0};
  auto work = [&](int worker) {
    for (std::size_t k = next++; k < points.size(); k = next++) {
      try {
        out[k] = f(points[k], worker);
      } catch (...) {
        errors[k] = std::current_exception();
      }
    }
  };
  const int nw = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(threads), points.size()));
  std::vector<std::thread> th;
  for (int w = 1; w < nw; ++w) th.emplace_back(work, w);
  work(0);
  for (auto& t : th) t.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  return out;
}

CmaesResult cmaes_minimize(const BatchObjective& f, const Eigen::VectorXd& x0, const CmaesOptions& options) {
  Cmaes es(x0, options);
  while (!es.done() && es.evaluations() + es.lambda() <= options.max_evals) {
    const std::vector<Eigen::VectorXd>& X = es.ask();
    std::vector<double> fx = f(X);
    if (fx.size() != X.size())
      throw std::invalid_argument(
          fmt::format("cmaes_minimize: the batch objective returned {} values for {} points", fx.size(), X.size()));
    es.tell(fx);
  }
  CmaesResult r;
  r.x = es.best_x();
  r.f = es.best_f();
  r.evaluations = es.evaluations();
  r.generations = es.generation();
  r.stop_reason = es.done() ? es.stop_reason() : "max_evals";
  return r;
}

CmaesResult cmaes_minimize_parallel(const PointObjective& f, const Eigen::VectorXd& x0, const CmaesOptions& options) {
  options.validate();
  const int threads = options.threads;
  return cmaes_minimize([&](const std::vector<Eigen::VectorXd>& X) { return evaluate_parallel(X, f, threads); }, x0,
                        options);
}

}  // namespace pmg::calib
