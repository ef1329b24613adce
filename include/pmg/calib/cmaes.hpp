#pragma once
/// @file cmaes.hpp
/// (mu/mu_w, lambda)-CMA-ES with an ask/tell interface and batch evaluation, so that the lambda
/// candidates of one generation can be evaluated concurrently (issue 6: the population's bench-rig
/// rollouts run in parallel threads, one MuJoCo mjData per worker).
///
/// Source: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772 (2016). Equation
/// numbers below are those of its algorithm summary and default-parameter table (v1, 2016):
///   sampling           z_k ~ N(0, I), y_k = B D z_k, x_k = m + sigma y_k          (38)-(40)
///   recombination      <y>_w = sum_{i<=mu} w_i y_{i:lambda}, m <- m + c_m sigma <y>_w (41)-(42)
///   step-size control  p_sigma (43), sigma <- sigma exp(c_sigma/d_sigma (|p_sigma|/E|N(0,I)| - 1)) (44),
///                      exponent capped at 1 (one generation grows sigma by at most e)
///   covariance         p_c (45) with the stall indicator h_sigma, negative-weight rescaling w_i° (46),
///                      C <- (1 + c_1 delta(h_sigma) - c_1 - c_mu sum_j w_j) C + c_1 p_c p_c^T
///                           + c_mu sum_i w_i° y_{i:lambda} y_{i:lambda}^T                (47)
///   defaults           lambda = 4 + floor(3 ln n) (48), w'_i = ln((lambda+1)/2) - ln i (49),
///                      mu_eff (50)-(51), alpha weights of the negative part (53), c_m = 1 (54),
///                      c_sigma, d_sigma (55), c_c (56), c_1 (57), c_mu (58).
///
/// Search space: the unit box [0, 1]^n (callers map their parameters into it, linearly or in log
/// scale). Box handling (documented choice): repair by projection plus a quadratic penalty, after
/// the boundary handling of Hansen et al., "A method for handling uncertainty in evolutionary
/// optimization ...", IEEE TEC 13(1), 2009, simplified to one penalty weight: a
/// sample x_k outside the box is *evaluated* at its projection x~_k = clip(x_k, 0, 1) (ask()
/// returns x~_k), it is *ranked* by
///   f(x~_k) + w_pen |x_k - x~_k|^2 / (sigma^2 mean(diag C)),
/// w_pen = inter-quartile range of the generation's finite f values (at least 1e-12 (1 + |median|)),
/// and the *unrepaired* x_k enters the update (38)-(47) (the update sees the sampled points, not
/// the repaired ones). The reported best point is always inside the box (best f over all evaluated x~_k).
///
/// Determinism: all random numbers are drawn in ask() (std::mt19937_64 seeded with
/// CmaesOptions::seed) before any evaluation, and tell() takes the values by candidate index, so
/// the run does not depend on the order or the thread in which the candidates are evaluated:
/// same seed -> bit-identical result with 1 or N threads (given a deterministic objective).
///
/// All coordinates are dimensionless (unit box). Setup/offline code: allocates, throws
/// std::invalid_argument on bad input.

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace pmg::calib {

struct CmaesOptions {
  int lambda = 0;          ///< population size lambda >= 2; 0 = default 4 + floor(3 ln n), eq. (48)
  double sigma0 = 0.3;     ///< initial step size sigma^(0) in unit-box coordinates, in (0, 1]
  int max_evals = 1000;    ///< cmaes_minimize* budget: no generation is started that would exceed it; >= lambda
  double x_tol = 1e-11;    ///< stop ("x_tol") when sigma max_i sqrt(C_ii) and sigma max_i |p_c,i| < x_tol; >= 0
  double f_tol = 1e-12;    ///< stop ("f_tol") when the f range of the last generation and of the
                           ///< best values of the last 10 + ceil(30 n / lambda) generations < f_tol; >= 0
  std::uint64_t seed = 1;  ///< random seed (sampling only)
  int threads = 1;         ///< worker threads of cmaes_minimize_parallel, >= 1
  /// Throws std::invalid_argument naming the field (CmaesOptions.<field> = value: expected ...).
  void validate() const;
};

/// Ask/tell CMA-ES on the unit box [0, 1]^n. Usage: loop { X = ask(); f_k = f(X[k]); tell(f); }
/// until done().
class Cmaes {
 public:
  /// @param x0 initial mean m^(0), shape n >= 1, every entry in [0, 1].
  /// @throws std::invalid_argument on bad options or x0 outside the box / non-finite.
  Cmaes(const Eigen::VectorXd& x0, const CmaesOptions& options);

  int dimension() const { return static_cast<int>(mean_.size()); }
  int lambda() const { return lambda_; }
  int mu() const { return mu_; }
  double mu_eff() const { return mu_eff_; }

  /// Samples the generation's lambda candidates, eqs. (38)-(40), and returns their evaluation
  /// points (the samples projected onto the box, each of shape n, in [0, 1]). Calling ask() twice
  /// without tell() returns the same points.
  const std::vector<Eigen::VectorXd>& ask();
  /// Takes f[k] = objective at ask()[k] (size lambda; NaN and +-inf are ranked last) and updates
  /// m, p_sigma, p_c, C, sigma, eqs. (41)-(47). @throws std::invalid_argument on a size mismatch
  /// or without a preceding ask().
  void tell(const std::vector<double>& f);

  /// True once a stop criterion holds ("x_tol", "f_tol", "condition": cond(C) > 1e14).
  bool done() const { return !stop_reason_.empty(); }
  const std::string& stop_reason() const { return stop_reason_; }

  const Eigen::VectorXd& best_x() const { return best_x_; }  ///< best evaluated point (in the box)
  double best_f() const { return best_f_; }                  ///< its value (+inf before the first tell)
  int evaluations() const { return evals_; }
  int generation() const { return gen_; }
  double sigma() const { return sigma_; }
  const Eigen::VectorXd& mean() const { return mean_; }
  const Eigen::MatrixXd& covariance() const { return C_; }

 private:
  void decompose();

  CmaesOptions opt_;
  int lambda_ = 0, mu_ = 0;
  Eigen::VectorXd w_;  ///< recombination weights w_1..w_lambda (positive then negative), eq. (53)
  double mu_eff_ = 0, c_sigma_ = 0, d_sigma_ = 0, c_c_ = 0, c_1_ = 0, c_mu_ = 0, chi_n_ = 0;
  Eigen::VectorXd mean_, p_sigma_, p_c_, D_;
  Eigen::MatrixXd C_, B_, C_inv_sqrt_;
  double sigma_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::vector<Eigen::VectorXd> raw_, eval_;
  bool asked_ = false;
  int evals_ = 0, gen_ = 0;
  Eigen::VectorXd best_x_;
  double best_f_;
  std::vector<double> best_history_;
  std::string stop_reason_;
};

/// Evaluates a whole generation: returns f(points[k]) for every k, in index order.
using BatchObjective = std::function<std::vector<double>(const std::vector<Eigen::VectorXd>& points)>;
/// One point on one worker: `worker` in [0, threads) identifies the calling thread's private
/// resources (e.g. its own MuJoCo mjData); calls with different workers run concurrently.
using PointObjective = std::function<double(const Eigen::VectorXd& x, int worker)>;

/// Evaluates f at every point on `threads` threads (min(threads, points) are used; the calling
/// thread is worker 0), candidates handed out dynamically, results stored by index. If calls
/// throw, the exception of the lowest failing index is rethrown after all threads joined.
/// @throws std::invalid_argument if threads < 1.
std::vector<double> evaluate_parallel(const std::vector<Eigen::VectorXd>& points, const PointObjective& f, int threads);

struct CmaesResult {
  Eigen::VectorXd x;            ///< best evaluated point, in [0, 1]^n
  double f = 0.0;               ///< f(x)
  int evaluations = 0;
  int generations = 0;
  std::string stop_reason;      ///< "x_tol" | "f_tol" | "condition" | "max_evals"
};

/// Runs generations until a stop criterion or the budget options.max_evals. `f` receives each
/// generation's lambda points at once (options.threads is not used here).
CmaesResult cmaes_minimize(const BatchObjective& f, const Eigen::VectorXd& x0, const CmaesOptions& options);
/// Same, evaluating each generation with evaluate_parallel(points, f, options.threads).
CmaesResult cmaes_minimize_parallel(const PointObjective& f, const Eigen::VectorXd& x0, const CmaesOptions& options);

}  // namespace pmg::calib
