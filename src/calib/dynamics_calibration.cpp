#include "pmg/calib/dynamics_calibration.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <nlopt.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>

#include "pmg/calib/cmaes.hpp"

namespace pmg::calib {
namespace {

using ParamMap = std::map<std::string, double>;

struct Spec {
  std::string name;
  double lo = 0.0, hi = 1.0, init = 0.0;
  bool log = false;
};

double to_unit(const Spec& s, double v) {
  v = std::clamp(v, s.lo, s.hi);
  const double u = s.log ? (std::log(v) - std::log(s.lo)) / (std::log(s.hi) - std::log(s.lo)) : (v - s.lo) / (s.hi - s.lo);
  return std::clamp(u, 0.0, 1.0);
}
double from_unit(const Spec& s, double u) {
  u = std::clamp(u, 0.0, 1.0);
  return s.log ? std::exp(std::log(s.lo) + u * (std::log(s.hi) - std::log(s.lo))) : s.lo + u * (s.hi - s.lo);
}

const std::map<std::string, std::vector<std::string>>& param_table() {
  static const std::map<std::string, std::vector<std::string>> t = {
      {"coulomb_friction", {"fc_Nm"}},
      {"viscous_friction", {"fv_Nms_per_rad"}},
      {"stribeck_friction", {"fc_Nm", "fs_Nm", "vs_rad_per_s"}},
      {"load_dependent_friction", {"fc_Nm", "kl"}},
      {"backlash", {"gap_rad"}},
      {"transport_delay", {"delay_s"}},
      {"torque_constant", {"kt_scale"}},
      {"torque_saturation", {"tau_max_Nm"}},
      {"torque_speed_limit", {"tau_stall_Nm", "w_max_rad_per_s"}},
      {"zero_offset", {"offset_rad"}},
  };
  return t;
}

/// Characteristic magnitudes of the training data, used to scale parameter ranges.
struct Scales {
  double tau_peak = 1.0;  ///< max |baseline motor torque| on training logs [N·m]
  double w_peak = 1.0;    ///< max |measured velocity| on training logs [rad/s]
  double dt = 0.001;      ///< physics step [s]
};

Spec spec_for(const std::string& p, const RigConfig& rig, const Scales& sc) {
  const double tau_ref = std::max(sc.tau_peak, 0.05 * rig.gravity_torque_Nm());
  const double max_delay = std::min(0.1, (ActuatorState::kMaxDelaySteps - 2) * sc.dt);
  if (p == "kp_scale") return {p, 0.05, 20.0, 1.0, true};
  if (p == "kd_scale") return {p, 0.01, 50.0, 1.0, true};
  if (p == "armature") {
    const double hi = std::max(20.0 * rig.armature_kgm2, 2.0 * rig.link_inertia_about_axis());
    return {p, 0.0, hi, rig.armature_kgm2, false};
  }
  if (p == "fc_Nm") return {p, 0.0, tau_ref, 0.02 * tau_ref, false};
  if (p == "fs_Nm") return {p, 0.0, 1.5 * tau_ref, 0.05 * tau_ref, false};
  if (p == "vs_rad_per_s") return {p, 0.002, 2.0, 0.05, true};
  if (p == "kl") return {p, 0.0, 0.6, 0.02, false};
  if (p == "fv_Nms_per_rad") return {p, 0.0, 2.0 * tau_ref / sc.w_peak, 0.02 * tau_ref / sc.w_peak, false};
  if (p == "gap_rad") return {p, 0.0, 0.2, 0.005, false};
  if (p == "delay_s") return {p, 0.0, max_delay, 0.005, false};
  if (p == "tau_max_Nm") return {p, 0.05 * sc.tau_peak, 1.2 * sc.tau_peak, 1.1 * sc.tau_peak, false};
  if (p == "tau_stall_Nm") return {p, 0.1 * sc.tau_peak, 4.0 * sc.tau_peak, 2.0 * sc.tau_peak, true};
  if (p == "w_max_rad_per_s") return {p, 0.3 * sc.w_peak, 50.0 * sc.w_peak, 20.0 * sc.w_peak, true};
  if (p == "offset_rad") return {p, -0.2, 0.2, 0.0, false};
  if (p == "kt_scale") return {p, 0.2, 3.0, 1.0, true};
  throw std::invalid_argument("unknown calibration parameter '" + p + "'");
}

/// The value at which a catalogue entry's parameter has no effect (clamped into its range): zero for
/// friction, gap, delay and offset terms, 1 for kt_scale, the range's top for torque limits; the
/// Stribeck velocity has none (its start value).
double neutral_value(const Spec& s) {
  const std::string& p = s.name;
  double v = 0.0;
  if (p == "kt_scale") v = 1.0;
  else if (p == "tau_max_Nm" || p == "tau_stall_Nm" || p == "w_max_rad_per_s") v = s.hi;
  else if (p == "vs_rad_per_s") v = s.init;
  return std::clamp(v, s.lo, s.hi);
}

/// Coarse starting points for a candidate's parameters (the rest of the fit starts from the
/// baseline): the scan avoids BOBYQA starting in a flat region (e.g. a gap smaller than the motion).
std::vector<ParamMap> scan_grid(const std::string& c, const RigConfig& rig, const Scales& sc) {
  const double tau_ref = std::max(sc.tau_peak, 0.05 * rig.gravity_torque_Nm());
  std::vector<ParamMap> g;
  if (c == "coulomb_friction")
    for (double f : {0.01, 0.03, 0.08, 0.15, 0.3}) g.push_back({{"fc_Nm", f * tau_ref}});
  if (c == "viscous_friction")
    for (double f : {0.01, 0.05, 0.15, 0.4}) g.push_back({{"fv_Nms_per_rad", f * tau_ref / sc.w_peak}});
  if (c == "stribeck_friction")
    for (double f : {0.05, 0.12, 0.25})
      for (double vs : {0.03, 0.2}) g.push_back({{"fc_Nm", 0.5 * f * tau_ref}, {"fs_Nm", f * tau_ref}, {"vs_rad_per_s", vs}});
  if (c == "load_dependent_friction")
    for (double k : {0.02, 0.05, 0.1, 0.2, 0.4}) g.push_back({{"fc_Nm", 0.005 * tau_ref}, {"kl", k}});
  if (c == "backlash")
    for (double gap : {0.002, 0.005, 0.01, 0.02, 0.04, 0.08}) g.push_back({{"gap_rad", gap}});
  if (c == "transport_delay")
    for (double d : {0.002, 0.005, 0.01, 0.02, 0.04, 0.07})
      if (d < spec_for("delay_s", rig, sc).hi) g.push_back({{"delay_s", d}});
  if (c == "torque_saturation")
    for (double f : {0.3, 0.5, 0.7, 0.85, 1.0}) g.push_back({{"tau_max_Nm", f * sc.tau_peak}});
  if (c == "torque_speed_limit")
    for (double f : {0.7, 1.5})
      for (double w : {1.0, 2.0, 5.0}) g.push_back({{"tau_stall_Nm", f * sc.tau_peak}, {"w_max_rad_per_s", w * sc.w_peak}});
  if (c == "torque_constant")
    for (double k : {0.6, 0.75, 0.9, 1.1, 1.3}) g.push_back({{"kt_scale", k}});
  if (c == "zero_offset")
    for (double o : {-0.05, -0.02, -0.007, 0.007, 0.02, 0.05}) g.push_back({{"offset_rad", o}});
  return g;
}

double get(const ParamMap& m, const char* k, double dflt) {
  const auto it = m.find(k);
  return it == m.end() ? dflt : it->second;
}

/// One worker's simulators (plain and with backlash), created on first use.
class WorkerSims {
 public:
  explicit WorkerSims(const RigConfig& rig) : rig_(rig) {}
  BenchSimulator& get(bool backlash) {
    auto& p = backlash ? backlash_ : plain_;
    if (!p) p = std::make_unique<BenchSimulator>(rig_, backlash);
    return *p;
  }

 private:
  RigConfig rig_;
  std::unique_ptr<BenchSimulator> plain_, backlash_;
};

/// Rows of one log that count in a loss: [lo, hi) or, with `outside`, every row but those. The
/// whole log is always rolled out (open loop from its first row); only the counting differs.
struct Piece {
  const BenchLog* log = nullptr;
  std::size_t lo = 0, hi = 0;
  bool outside = false;
  bool whole() const { return !outside && lo == 0 && hi >= log->size(); }
  std::size_t rows() const { return outside ? log->size() - (hi - lo) : hi - lo; }
};

std::vector<Piece> whole_logs(const std::vector<const BenchLog*>& logs) {
  std::vector<Piece> v;
  for (const auto* l : logs) v.push_back(Piece{l, 0, l->size(), false});
  return v;
}

double piece_sse(BenchSimulator& sim, const Piece& p, const RigParams& rp) {
  if (p.whole()) return sim.rollout(*p.log, rp);
  thread_local RolloutTrace tr;
  const double full = sim.rollout(*p.log, rp, &tr);
  if (!std::isfinite(full)) return full;
  double s = 0.0;
  for (std::size_t i = 0; i < p.log->size(); ++i) {
    if (((i >= p.lo) && (i < p.hi)) == p.outside) continue;
    const double e = tr.q[i] - p.log->q[i];
    s += e * e;
  }
  return s;
}

/// Mean squared error over pieces of logs (rollouts spread over the workers, one thread each).
double mse(const RigConfig& rig, const std::vector<Piece>& pieces, const ParamMap& params,
           std::vector<WorkerSims*>& workers) {
  const RigParams rp = rig_params_from(rig, params);
  const bool backlash = params.count("gap_rad") > 0;
  std::size_t rows = 0;
  for (const auto& p : pieces) rows += p.rows();
  std::vector<double> sse(pieces.size(), 0.0);
  const std::size_t nw = std::min(workers.size(), pieces.size());
  auto run = [&](std::size_t w, std::size_t stride) {
    for (std::size_t i = w; i < pieces.size(); i += stride) sse[i] = piece_sse(workers[w]->get(backlash), pieces[i], rp);
  };
  if (nw <= 1) {
    run(0, 1);
  } else {
    std::vector<std::thread> th;
    for (std::size_t w = 1; w < nw; ++w) th.emplace_back(run, w, nw);
    run(0, nw);
    for (auto& t : th) t.join();
  }
  double total = 0.0;
  for (double s : sse) total += s;
  return std::isfinite(total) && rows > 0 ? total / static_cast<double>(rows) : 1e6;
}

/// Mean squared error over whole logs.
double mse(const RigConfig& rig, const std::vector<const BenchLog*>& logs, const ParamMap& params,
           std::vector<WorkerSims*>& workers) {
  return mse(rig, whole_logs(logs), params, workers);
}

/// K-fold partition of the training logs: fold k trains on train[k] and is scored on test[k].
struct Folds {
  std::vector<std::vector<Piece>> train, test;
  std::string unit;  ///< "logs" | "time_blocks"
  int k() const { return static_cast<int>(test.size()); }
};

Folds make_folds(const std::vector<const BenchLog*>& tr, int k_max) {
  Folds f;
  if (tr.size() >= 2) {
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(k_max), tr.size());
    f.unit = "logs";
    f.train.resize(k);
    f.test.resize(k);
    for (std::size_t i = 0; i < tr.size(); ++i)
      for (std::size_t j = 0; j < k; ++j) (j == i % k ? f.test : f.train)[j].push_back(Piece{tr[i], 0, tr[i]->size(), false});
  } else {
    const BenchLog* l = tr.front();
    const std::size_t n = l->size();
    const std::size_t k = std::max<std::size_t>(2, std::min<std::size_t>(static_cast<std::size_t>(k_max), n / 20));
    if (n < 40) throw std::invalid_argument(fmt::format("calibrate_dynamics: training log '{}' has {} rows; cross-validation "
                                                        "over time blocks needs >= 40", l->name, n));
    f.unit = "time_blocks";
    for (std::size_t j = 0; j < k; ++j) {
      const std::size_t lo = j * n / k, hi = (j + 1) * n / k;
      f.test.push_back({Piece{l, lo, hi, false}});
      f.train.push_back({Piece{l, lo, hi, true}});
    }
  }
  return f;
}

struct FitOutcome {
  ParamMap params;
  double mse = std::numeric_limits<double>::infinity();
  int evals = 0;
};

using Objective = std::function<double(const ParamMap&)>;
/// Objective evaluated on one worker's private simulators (worker in [0, threads)).
using WorkerObjective = std::function<double(const ParamMap&, int worker)>;

/// pagmo user-defined problem on the unit box.
struct PagmoProblem {
  const std::function<double(const std::vector<double>&)>* f = nullptr;
  std::size_t n = 1;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const { return {(*f)(x)}; }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {pagmo::vector_double(n, 0.0), pagmo::vector_double(n, 1.0)};
  }
};

/// Minimises `obj` over `specs` (other parameters fixed in `fixed`), starting from the specs' init.
/// With Optimizer::kCmaes and a `wobj`, each generation is evaluated with wobj on `threads` workers
/// concurrently (results recorded in candidate order, so the outcome does not depend on threads).
FitOutcome fit(const std::vector<Spec>& specs, const ParamMap& fixed, const Objective& obj, Optimizer opt,
               int max_evals, unsigned seed, const WorkerObjective* wobj = nullptr, int threads = 1) {
  const std::size_t n = specs.size();
  FitOutcome best;
  best.params = fixed;
  auto to_map = [&](const std::vector<double>& u) {
    ParamMap m = fixed;
    for (std::size_t i = 0; i < n; ++i) m[specs[i].name] = from_unit(specs[i], u[i]);
    return m;
  };
  auto record = [&](ParamMap&& m, double v) {
    ++best.evals;
    if (v < best.mse) {
      best.mse = v;
      best.params = std::move(m);
    }
  };
  std::function<double(const std::vector<double>&)> f = [&](const std::vector<double>& u) {
    ParamMap m = to_map(u);
    const double v = obj(m);
    record(std::move(m), v);
    return v;
  };
  std::vector<double> u0(n);
  for (std::size_t i = 0; i < n; ++i) u0[i] = to_unit(specs[i], specs[i].init);
  f(u0);
  int left = max_evals - 1;
  if (opt == Optimizer::kCmaes && left > 20) {
    CmaesOptions co;
    co.sigma0 = 0.25;
    co.max_evals = left / 2;
    co.seed = seed;
    co.x_tol = 1e-6;   // unit box; BOBYQA polishes below that
    co.f_tol = 1e-14;  // rad^2, far below encoder resolution
    co.threads = std::max(1, threads);
    const Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(u0.data(), static_cast<Eigen::Index>(n));
    auto to_map_e = [&](const Eigen::VectorXd& x) {
      return to_map(std::vector<double>(x.data(), x.data() + x.size()));
    };
    cmaes_minimize(
        [&](const std::vector<Eigen::VectorXd>& X) {
          std::vector<double> fx;
          if (wobj)
            fx = evaluate_parallel(
                X, [&](const Eigen::VectorXd& x, int w) { return (*wobj)(to_map_e(x), w); }, co.threads);
          else
            for (const auto& x : X) fx.push_back(obj(to_map_e(x)));
          for (std::size_t k = 0; k < X.size(); ++k) record(to_map_e(X[k]), fx[k]);  // candidate order
          return fx;
        },
        x0, co);
    left = max_evals - best.evals;
  } else if (opt == Optimizer::kCmaesPagmo && left > 20) {
    PagmoProblem pp{&f, n};
    pagmo::problem prob{pp};
    const unsigned pop_size = 4 + static_cast<unsigned>(3.0 * std::log(static_cast<double>(n))) + 4;
    const unsigned gens = static_cast<unsigned>(std::max(1, (left / 2) / static_cast<int>(pop_size)));
    pagmo::population pop{prob, pop_size, seed};
    pagmo::cmaes algo{gens, -1, -1, -1, -1, 0.25, 1e-10, 1e-8, false, true, seed};
    pop = algo.evolve(pop);
    left = max_evals - best.evals;
  } else if (opt == Optimizer::kCrs2 && left > 20) {
    nlopt::opt g(nlopt::GN_CRS2_LM, static_cast<unsigned>(n));
    nlopt::srand(seed);
    g.set_lower_bounds(std::vector<double>(n, 0.0));
    g.set_upper_bounds(std::vector<double>(n, 1.0));
    g.set_maxeval(left / 2);
    g.set_min_objective([](const std::vector<double>& x, std::vector<double>&, void* d) {
      return (*static_cast<std::function<double(const std::vector<double>&)>*>(d))(x);
    }, &f);
    std::vector<double> x = u0;
    double fx = 0.0;
    try {
      g.optimize(x, fx);
    } catch (const std::exception&) {
      // NLopt reports round-off / forced stops as exceptions; the best point is kept in `best`.
    }
    left = max_evals - best.evals;
  }
  if (left > static_cast<int>(2 * n + 2)) {
    for (std::size_t i = 0; i < n; ++i) u0[i] = to_unit(specs[i], best.params.at(specs[i].name));
    nlopt::opt local(nlopt::LN_BOBYQA, static_cast<unsigned>(n));
    local.set_lower_bounds(std::vector<double>(n, 0.0));
    local.set_upper_bounds(std::vector<double>(n, 1.0));
    local.set_maxeval(left);
    local.set_xtol_rel(1e-5);
    local.set_ftol_rel(1e-9);
    std::vector<double> step(n);
    for (std::size_t i = 0; i < n; ++i) {
      // ~15 % of the current value (log-scaled parameters) or of the distance to the lower bound,
      // at least 2 % of the range: coarse enough to leave flat spots, fine enough for 20 evals.
      const Spec& sp = specs[i];
      const double v = from_unit(sp, u0[i]);
      double st = sp.log ? std::log(1.15) / (std::log(sp.hi) - std::log(sp.lo)) : 0.15 * (v - sp.lo) / (sp.hi - sp.lo);
      st = std::max(st, 0.02);
      step[i] = std::min(st, 0.45);
    }
    local.set_initial_step(step);
    local.set_min_objective([](const std::vector<double>& x, std::vector<double>&, void* d) {
      return (*static_cast<std::function<double(const std::vector<double>&)>*>(d))(x);
    }, &f);
    double fx = 0.0;
    try {
      local.optimize(u0, fx);
    } catch (const std::exception&) {
      // Round-off stop: the best point seen is in `best`.
    }
  }
  return best;
}

/// Baseline fit eta = [Kp, Kd, I] on the training logs. BOBYQA / CRS2 / pagmo evaluate one point
/// at a time with the logs' rollouts spread over the workers; CMA-ES spreads each generation's
/// candidates over the workers instead, and each candidate's logs run serially on its worker (one
/// level of parallelism, no oversubscription).
FitOutcome run_baseline_fit(const RigConfig& rig, const std::vector<const BenchLog*>& tr,
                            const std::vector<Spec>& specs, const CalibrationOptions& options,
                            std::vector<WorkerSims*>& workers) {
  Objective train_obj = [&](const ParamMap& m) { return mse(rig, tr, m, workers); };
  {
    ParamMap nominal;
    for (const auto& sp : specs) nominal[sp.name] = sp.init;
    const double v = train_obj(nominal);
    if (!std::isfinite(v) || v >= 1e6)
      throw std::runtime_error(
          "calibrate_dynamics: the rig simulation diverges at the nominal parameters; check the rig file");
  }
  WorkerObjective per_worker = [&](const ParamMap& m, int w) {
    std::vector<WorkerSims*> one{workers.at(static_cast<std::size_t>(w))};
    return mse(rig, tr, m, one);
  };
  return fit(specs, {}, train_obj, options.optimizer, options.max_evals_baseline, options.seed, &per_worker,
             static_cast<int>(workers.size()));
}

const char* optimizer_name(Optimizer o) {
  switch (o) {
    case Optimizer::kBobyqa: return "bobyqa";
    case Optimizer::kCrs2: return "crs2";
    case Optimizer::kCmaes: return "cmaes";
    case Optimizer::kCmaesPagmo: return "cmaes_pagmo";
  }
  return "?";
}

std::vector<double> measured_velocity(const BenchLog& log) {
  if (log.has_dq()) return log.dq;
  std::vector<double> v(log.size(), 0.0);
  for (std::size_t i = 1; i + 1 < log.size(); ++i) v[i] = (log.q[i + 1] - log.q[i - 1]) / (log.t[i + 1] - log.t[i - 1]);
  if (log.size() > 2) {
    v[0] = v[1];
    v.back() = v[log.size() - 2];
  }
  return v;
}

std::string json_num(double v) {
  if (!std::isfinite(v)) return "null";
  return fmt::format("{:.6g}", v);
}

std::string json_params(const ParamMap& m) {
  std::string s = "{";
  bool first = true;
  for (const auto& [k, v] : m) {
    s += fmt::format("{}\"{}\": {}", first ? "" : ", ", k, json_num(v));
    first = false;
  }
  return s + "}";
}

/// Adds the output-only keys kp [N·m/rad] and kd [N·m·s/rad] (rig nominal x fitted scale) and, for
/// logs with gain columns, kp_per_log_unit / kd_per_log_unit.
void add_si_gains(const RigConfig& rig, bool gain_columns, ParamMap& p) {
  const double ks = get(p, "kp_scale", 1.0), ds = get(p, "kd_scale", 1.0);
  p["kp"] = ks * rig.kp_Nm_per_rad;
  p["kd"] = ds * rig.kd_Nms_per_rad;
  if (!p.count("armature")) p["armature"] = rig.armature_kgm2;
  if (gain_columns) {
    p["kp_per_log_unit"] = ks * rig.log_gain_to_SI;
    p["kd_per_log_unit"] = ds * rig.log_gain_to_SI;
  }
}

}  // namespace

Optimizer parse_optimizer(const std::string& name) {
  if (name == "bobyqa") return Optimizer::kBobyqa;
  if (name == "crs2") return Optimizer::kCrs2;
  if (name == "cmaes") return Optimizer::kCmaes;
  if (name == "cmaes_pagmo") return Optimizer::kCmaesPagmo;
  throw std::invalid_argument("--optimizer = '" + name + "': expected bobyqa, crs2, cmaes or cmaes_pagmo");
}

const std::vector<std::string>& catalogue_names() {
  static const std::vector<std::string> names = {
      "coulomb_friction", "viscous_friction", "stribeck_friction", "load_dependent_friction", "backlash",
      "transport_delay",  "torque_constant",  "torque_saturation", "torque_speed_limit", "zero_offset"};
  return names;
}

const std::vector<std::string>& catalogue_params(const std::string& name) {
  const auto it = param_table().find(name);
  if (it == param_table().end()) throw std::invalid_argument("unknown catalogue entry '" + name + "'");
  return it->second;
}

std::string nested_entry(const std::string& name) {
  if (name == "stribeck_friction" || name == "load_dependent_friction") return "coulomb_friction";
  if (name == "torque_speed_limit") return "torque_saturation";
  return "";
}

void CalibrationOptions::validate() const {
  if (threads < 0) throw std::invalid_argument(fmt::format("CalibrationOptions.threads = {}: expected >= 0", threads));
  if (!(min_gain_per_param > 0.0 && min_gain_per_param < 0.5))
    throw std::invalid_argument(
        fmt::format("CalibrationOptions.min_gain_per_param = {}: expected in (0, 0.5)", min_gain_per_param));
  if (max_evals_baseline < 10)
    throw std::invalid_argument(fmt::format("CalibrationOptions.max_evals_baseline = {}: expected >= 10", max_evals_baseline));
  if (max_evals_candidate < 10)
    throw std::invalid_argument(fmt::format("CalibrationOptions.max_evals_candidate = {}: expected >= 10", max_evals_candidate));
  if (profile_evals < 4)
    throw std::invalid_argument(fmt::format("CalibrationOptions.profile_evals = {}: expected >= 4", profile_evals));
  if (!(noise_z > 0.0 && std::isfinite(noise_z)))
    throw std::invalid_argument(fmt::format("CalibrationOptions.noise_z = {}: expected > 0", noise_z));
  if (!(min_rmse_over_floor >= 1.0 && std::isfinite(min_rmse_over_floor)))
    throw std::invalid_argument(
        fmt::format("CalibrationOptions.min_rmse_over_floor = {}: expected >= 1", min_rmse_over_floor));
  if (cv_folds < 2 || cv_folds > 20)
    throw std::invalid_argument(fmt::format("CalibrationOptions.cv_folds = {}: expected in [2, 20]", cv_folds));
  if (cv_evals < 20)
    throw std::invalid_argument(fmt::format("CalibrationOptions.cv_evals = {}: expected >= 20", cv_evals));
  for (const auto& c : candidates) catalogue_params(c);
}

RigParams rig_params_from(const RigConfig& rig, const std::map<std::string, double>& p) {
  RigParams r;
  r.kp_scale = get(p, "kp_scale", 1.0);
  r.kd_scale = get(p, "kd_scale", 1.0);
  r.armature_kgm2 = get(p, "armature", rig.armature_kgm2);
  ActuatorParams& a = r.act;
  a.rate_hz = rig.rate_hz;
  a.torque_limit_Nm = get(p, "tau_max_Nm", rig.torque_limit_Nm);
  a.tau_stall_Nm = get(p, "tau_stall_Nm", 0.0);
  a.w_max_rad_per_s = get(p, "w_max_rad_per_s", 0.0);
  a.fc_Nm = get(p, "fc_Nm", 0.0);
  a.fs_Nm = get(p, "fs_Nm", 0.0);
  a.vs_rad_per_s = get(p, "vs_rad_per_s", 0.1);
  a.kl = get(p, "kl", 0.0);
  a.fv_Nms_per_rad = get(p, "fv_Nms_per_rad", 0.0);
  a.delay_s = get(p, "delay_s", 0.0);
  a.kt_scale = get(p, "kt_scale", 1.0);
  a.offset_rad = get(p, "offset_rad", 0.0);
  a.backlash_gap_rad = get(p, "gap_rad", 0.0);
  return r;
}

FittedModel fit_baseline(const RigConfig& rig, const std::vector<BenchLog>& train, const CalibrationOptions& options) {
  options.validate();
  rig.validate();
  if (train.empty()) throw std::invalid_argument("fit_baseline: at least one training log is required (--train)");
  const int nthreads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<const BenchLog*> tr;
  for (const auto& l : train) tr.push_back(&l);
  std::vector<std::unique_ptr<WorkerSims>> sims_owned;
  std::vector<WorkerSims*> workers;
  for (int i = 0; i < nthreads; ++i) {
    sims_owned.push_back(std::make_unique<WorkerSims>(rig));
    workers.push_back(sims_owned.back().get());
  }
  Scales sc;
  sc.dt = rig.sim_dt_s;
  std::vector<Spec> specs;
  for (const char* p : {"kp_scale", "kd_scale", "armature"}) specs.push_back(spec_for(p, rig, sc));
  const FitOutcome fo = run_baseline_fit(rig, tr, specs, options, workers);
  FittedModel m;
  m.params = fo.params;
  m.train_rmse_rad = std::sqrt(fo.mse);
  m.evaluations = fo.evals;
  return m;
}

namespace {

NoiseFloor noise_floor_of(const std::vector<const BenchLog*>& logs) {
  NoiseFloor nf;
  double q_min = std::numeric_limits<double>::infinity();
  std::vector<double> abs_r;
  std::size_t rows = 0;
  for (const auto* l : logs) {
    const auto& q = l->q;
    rows += q.size();
    for (std::size_t i = 1; i < q.size(); ++i) {
      const double d = std::abs(q[i] - q[i - 1]);
      if (d > 1e-9) q_min = std::min(q_min, d);
    }
    // 5-point local quadratic (Savitzky-Golay) smoothing; residual of the centre sample, taken
    // where the joint moves slowest (lowest quarter of |q[i+1] - q[i-1]| in this log): errors
    // that grow with speed (sampling-time jitter, unresolved fast transients) stay out. For white
    // noise the residual (symmetric weights) and the speed (antisymmetric) are independent.
    std::vector<std::pair<double, double>> rv;  // (speed, |residual|)
    for (std::size_t i = 2; i + 2 < q.size(); ++i) {
      const double sm = (-3.0 * q[i - 2] + 12.0 * q[i - 1] + 17.0 * q[i] + 12.0 * q[i + 1] - 3.0 * q[i + 2]) / 35.0;
      rv.emplace_back(std::abs(q[i + 1] - q[i - 1]), std::abs(q[i] - sm));
    }
    if (rv.empty()) continue;
    const std::size_t quarter = std::max<std::size_t>(1, rv.size() / 4);
    std::nth_element(rv.begin(), rv.begin() + static_cast<long>(quarter - 1), rv.end());
    for (std::size_t i = 0; i < quarter; ++i) abs_r.push_back(rv[i].second);
  }
  nf.quantum_rad = std::isfinite(q_min) ? q_min : 0.0;
  // Robust scale (1.4826 x median |r|). White noise of std s leaves a residual of variance
  // s^2 (1 - 17/35) after this smoother.
  double med = 0.0;
  if (!abs_r.empty()) {
    std::nth_element(abs_r.begin(), abs_r.begin() + static_cast<long>(abs_r.size() / 2), abs_r.end());
    med = abs_r[abs_r.size() / 2];
  }
  nf.hf_rad = 1.4826 * med / std::sqrt(18.0 / 35.0);
  nf.floor_rad = std::sqrt(nf.hf_rad * nf.hf_rad + nf.quantum_rad * nf.quantum_rad / 12.0);
  nf.samples = rows;
  nf.effective_samples = static_cast<double>(std::max<std::size_t>(rows, 1));
  return nf;
}

/// The significance rule of CalibrationOptions::min_gain_per_param (rules 1-5).
struct Rule {
  double thr = 0.03, z = 3.0, room = 2.0;
  double floor = 0.0, neff = 1.0, min_delay = 0.0;

  /// True if `new_cv` (a model with `extra` more parameters than the reference, `params` its
  /// fitted values, `entry` the catalogue entry that was added) is significant against `ref_cv`.
  /// `why` receives the verdict text.
  bool test(const FittedModel& ref, const FittedModel& cand, std::size_t extra, const std::string& entry,
            std::string& why) const {
    const double ref_cv = ref.cv_rmse_rad, new_cv = cand.cv_rmse_rad;
    const ParamMap& params = cand.params;
    const double gain = 1.0 - new_cv / ref_cv;
    const double need_gain = thr * static_cast<double>(extra);
    const double drop = ref_cv - new_cv;
    const double need_drop = z * floor / std::sqrt(neff);
    std::vector<std::string> fails;
    if (!(gain > need_gain))
      fails.push_back(fmt::format("CV gain {:.3f} <= {:.3f} required for {} parameter(s)", gain, need_gain, extra));
    if (!(drop > need_drop))
      fails.push_back(fmt::format("CV RMSE drop {:.3g} rad <= {:.3g} rad = {} x noise floor {:.3g} rad / sqrt({:.0f} effective "
                                  "samples)", drop, need_drop, z, floor, neff));
    if (!(ref_cv > room * floor))
      fails.push_back(fmt::format("reference CV RMSE {:.3g} rad <= {} x noise floor {:.3g} rad (explained to the noise)", ref_cv,
                                  room, floor));
    {
      const std::size_t k = std::min(ref.cv_fold_mse.size(), cand.cv_fold_mse.size());
      std::size_t better = 0;
      for (std::size_t f = 0; f < k; ++f) better += cand.cv_fold_mse[f] < ref.cv_fold_mse[f] ? 1 : 0;
      const std::size_t need = (3 * k + 3) / 4;  // ceil(3K/4)
      if (better < need)
        fails.push_back(fmt::format("lower test error in only {} of {} folds (needs {})", better, k, need));
    }
    if (entry == "transport_delay") {
      const double d = get(params, "delay_s", 0.0);
      if (!(d >= min_delay))
        fails.push_back(fmt::format("delay {:.4g} s < {:.4g} s (driver / sample period): not a transport delay", d, min_delay));
    }
    if (fails.empty()) {
      why = fmt::format("CV gain {:.3f} > {:.3f} for {} parameter(s); CV RMSE drop {:.3g} rad > {:.3g} rad (noise); reference "
                        "{:.3g} rad > {} x floor", gain, need_gain, extra, drop, need_drop, ref_cv, room);
      return true;
    }
    why.clear();
    for (const auto& f : fails) why += (why.empty() ? "" : "; ") + f;
    return false;
  }
};

/// K-fold CV RMSE of the model with free parameters `names`: per fold, BOBYQA (options.cv_evals)
/// warm-started from `full` (the fit on all training logs) on the fold's training pieces, scored on
/// its test pieces. Folds are spread over `workers` (one fold per worker at a time).
double cv_rmse(const RigConfig& rig, const Folds& folds, const ParamMap& full, const std::vector<std::string>& names,
               const Scales& sc, const CalibrationOptions& o, std::vector<WorkerSims*>& workers, int* evals,
               std::vector<double>* fold_mse) {
  const std::size_t k = folds.test.size();
  std::vector<double> sse(k, 0.0);
  std::vector<std::size_t> rows(k, 0);
  std::vector<int> ev(k, 0);
  std::atomic<std::size_t> next{0};
  auto work = [&](WorkerSims* ws) {
    std::vector<WorkerSims*> mine{ws};
    for (std::size_t f = next++; f < k; f = next++) {
      Objective obj = [&](const ParamMap& m) { return mse(rig, folds.train[f], m, mine); };
      std::vector<Spec> specs;
      for (const auto& p : names) {
        Spec s = spec_for(p, rig, sc);
        s.init = full.at(p);
        specs.push_back(s);
      }
      const FitOutcome fo = fit(specs, {}, obj, Optimizer::kBobyqa, o.cv_evals, o.seed);
      ev[f] = fo.evals;
      for (const auto& p : folds.test[f]) rows[f] += p.rows();
      const double m = mse(rig, folds.test[f], fo.params, mine);
      sse[f] = m >= 1e6 ? std::numeric_limits<double>::infinity() : m * static_cast<double>(rows[f]);
    }
  };
  {
    std::vector<std::thread> th;
    const std::size_t nw = std::min(workers.size(), k);
    for (std::size_t w = 1; w < nw; ++w) th.emplace_back(work, workers[w]);
    work(workers[0]);
    for (auto& t : th) t.join();
  }
  double s = 0.0;
  std::size_t r = 0;
  if (fold_mse) fold_mse->assign(k, 0.0);
  for (std::size_t f = 0; f < k; ++f) {
    s += sse[f];
    r += rows[f];
    if (evals) *evals += ev[f];
    if (fold_mse) (*fold_mse)[f] = sse[f] / static_cast<double>(std::max<std::size_t>(rows[f], 1));
  }
  return std::sqrt(s / static_cast<double>(std::max<std::size_t>(r, 1)));
}

std::vector<std::string> model_names(const std::vector<std::string>& base, const std::vector<std::string>& causes) {
  std::set<std::string> n(base.begin(), base.end());
  for (const auto& c : causes)
    for (const auto& p : catalogue_params(c)) n.insert(p);
  return {n.begin(), n.end()};
}

}  // namespace

NoiseFloor estimate_noise_floor(const std::vector<BenchLog>& logs) {
  if (logs.empty()) throw std::invalid_argument("estimate_noise_floor: no logs");
  std::vector<const BenchLog*> p;
  for (const auto& l : logs) p.push_back(&l);
  return noise_floor_of(p);
}

CalibrationReport calibrate_dynamics(const RigConfig& rig, const std::vector<BenchLog>& train,
                                     const std::vector<BenchLog>& heldout, const CalibrationOptions& options) {
  options.validate();
  rig.validate();
  if (train.empty()) throw std::invalid_argument("calibrate_dynamics: at least one training log is required (--train)");
  if (heldout.empty()) throw std::invalid_argument("calibrate_dynamics: at least one held-out log is required (--heldout)");
  const auto t_start = std::chrono::steady_clock::now();
  const int nthreads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  auto log_msg = [&](const std::string& s) {
    if (options.verbose) fmt::print(stderr, "[calib] {}\n", s);
  };

  std::vector<const BenchLog*> tr, ho;
  for (const auto& l : train) tr.push_back(&l);
  for (const auto& l : heldout) ho.push_back(&l);

  std::vector<std::unique_ptr<WorkerSims>> sims_owned;
  for (int i = 0; i < nthreads; ++i) sims_owned.push_back(std::make_unique<WorkerSims>(rig));
  std::vector<WorkerSims*> all_workers;
  for (auto& s : sims_owned) all_workers.push_back(s.get());

  CalibrationReport rep;
  rep.optimizer = optimizer_name(options.optimizer);
  for (const auto& l : train) rep.train_logs.push_back(l.name);
  for (const auto& l : heldout) rep.heldout_logs.push_back(l.name);
  const Folds folds = make_folds(tr, options.cv_folds);
  rep.cv_folds = folds.k();
  rep.cv_fold_unit = folds.unit;

  // ---- Baseline eta = [Kp, Kd, I], its CV RMSE ----------------------------------------------
  // Everything up to the final report uses the training logs only.
  Scales sc;
  sc.dt = rig.sim_dt_s;
  const std::vector<std::string> base_names = {"kp_scale", "kd_scale", "armature"};
  std::vector<Spec> base_specs;
  for (const auto& p : base_names) base_specs.push_back(spec_for(p, rig, sc));
  FitOutcome base = run_baseline_fit(rig, tr, base_specs, options, all_workers);
  rep.baseline.params = base.params;
  rep.baseline.train_rmse_rad = std::sqrt(base.mse);
  rep.baseline.evaluations = base.evals;
  rep.baseline.cv_rmse_rad = cv_rmse(rig, folds, base.params, base_names, sc, options, all_workers, &rep.baseline.evaluations,
                                     &rep.baseline.cv_fold_mse);
  log_msg(fmt::format("baseline: kp_scale {:.4g} kd_scale {:.4g} armature {:.4g}; train RMSE {:.4g} rad, {}-fold CV ({}) {:.4g} rad "
                      "({} evals)", base.params["kp_scale"], base.params["kd_scale"], base.params["armature"],
                      rep.baseline.train_rmse_rad, folds.k(), folds.unit, rep.baseline.cv_rmse_rad, rep.baseline.evaluations));

  // Scales from the fitted baseline; noise floor and effective samples from its training residual.
  rep.noise = noise_floor_of(tr);
  {
    RolloutTrace trace;
    const RigParams rp = rig_params_from(rig, base.params);
    sc.tau_peak = 1e-6;
    sc.w_peak = 1e-3;
    double num = 0.0, den = 0.0;
    for (const auto* l : tr) {
      all_workers[0]->get(false).rollout(*l, rp, &trace);
      for (double x : trace.tau_motor) sc.tau_peak = std::max(sc.tau_peak, std::abs(x));
      for (double x : measured_velocity(*l)) sc.w_peak = std::max(sc.w_peak, std::abs(x));
      double mean = 0.0;
      for (std::size_t i = 0; i < l->size(); ++i) mean += trace.q[i] - l->q[i];
      mean /= static_cast<double>(std::max<std::size_t>(l->size(), 1));
      for (std::size_t i = 0; i < l->size(); ++i) {
        const double e = trace.q[i] - l->q[i] - mean;
        den += e * e;
        if (i > 0) num += e * (trace.q[i - 1] - l->q[i - 1] - mean);
      }
    }
    const double rho = den > 0.0 ? std::clamp(num / den, 0.0, 0.999999) : 0.0;
    const double n = static_cast<double>(rep.noise.samples);
    rep.noise.effective_samples = std::clamp(n * (1.0 - rho) / (1.0 + rho), 1.0, std::max(n, 1.0));
  }
  Rule rule;
  rule.thr = options.min_gain_per_param;
  rule.z = options.noise_z;
  rule.room = options.min_rmse_over_floor;
  rule.floor = rep.noise.floor_rad;
  rule.neff = rep.noise.effective_samples;
  {
    std::vector<double> dts;
    for (const auto* l : tr)
      for (std::size_t i = 1; i < l->size(); ++i) dts.push_back(l->t[i] - l->t[i - 1]);
    double med = 0.0;
    if (!dts.empty()) {
      std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
      med = dts[dts.size() / 2];
    }
    rule.min_delay = std::max(1.0 / rig.rate_hz, med);
  }
  log_msg(fmt::format("noise floor {:.3g} rad (quantum {:.3g} rad, high-frequency {:.3g} rad), {:.0f} effective of {} samples; "
                      "minimum transport delay {:.4g} s", rep.noise.floor_rad, rep.noise.quantum_rad, rep.noise.hf_rad,
                      rep.noise.effective_samples, rep.noise.samples, rule.min_delay));
  bool has_tau_ff = false;
  for (const auto* l : tr)
    for (double x : l->tau_ff) has_tau_ff = has_tau_ff || x != 0.0;

  // ---- Candidates (one worker each, in parallel): fit on all training logs, then K-fold CV ----
  std::vector<std::string> cands = options.candidates.empty() ? catalogue_names() : options.candidates;
  rep.candidates.resize(cands.size());
  std::vector<char> fitted(cands.size(), 0);
  std::atomic<std::size_t> next{0};
  std::mutex err_mutex;
  std::string first_error;
  auto run_candidate = [&](WorkerSims* ws, std::size_t ci) {
    const std::string& c = cands[ci];
    CandidateResult r;
    r.name = c;
    r.reference_cv_rmse_rad = rep.baseline.cv_rmse_rad;
    if (c == "torque_constant" && !has_tau_ff) {
      r.verdict = "not fitted: no training log carries a feed-forward torque (on PD data kt_scale is kp and kd scaled "
                  "together, which the baseline fits)";
      r.fit.params = base.params;
      rep.candidates[ci] = r;
      return;
    }
    std::vector<WorkerSims*> mine{ws};
    Objective obj = [&](const ParamMap& m) { return mse(rig, tr, m, mine); };
    // Profile scan: at each grid point of the new parameters, the baseline parameters are
    // re-fitted briefly with the new ones held fixed (effects such as backlash or load-dependent
    // friction trade off against the gains along curved valleys that a local method started from
    // the plain baseline does not follow). BOBYQA from the two best points.
    std::vector<std::pair<double, ParamMap>> scanned;
    std::vector<Spec> base_only;
    for (const auto& p : base_names) base_only.push_back(spec_for(p, rig, sc));
    for (const ParamMap& g : scan_grid(c, rig, sc)) {
      ParamMap fixed = g;
      std::vector<Spec> bs = base_only;
      for (auto& sp : bs) sp.init = base.params.at(sp.name);
      if (const auto it = g.find("kl"); it != g.end()) {
        // While the motor drives the motion, load-dependent friction removes kl |tau|: the same
        // response needs gains / (1 - kl). Start on that ridge.
        bs[0].init = std::min(bs[0].init / (1.0 - it->second), bs[0].hi);
        bs[1].init = std::min(bs[1].init / (1.0 - it->second), bs[1].hi);
      }
      FitOutcome pf = fit(bs, fixed, obj, Optimizer::kBobyqa, options.profile_evals, options.seed);
      scanned.emplace_back(pf.mse, pf.params);
    }
    std::sort(scanned.begin(), scanned.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const std::size_t n_starts = std::min<std::size_t>(2, scanned.size());
    FitOutcome fo;
    int evals = static_cast<int>(scanned.size()) * options.profile_evals;
    for (std::size_t st = 0; st < n_starts; ++st) {
      const ParamMap& start = scanned[st].second;
      std::vector<Spec> specs;
      for (const auto& p : base_names) {
        Spec s = spec_for(p, rig, sc);
        s.init = start.at(p);
        specs.push_back(s);
      }
      for (const auto& p : catalogue_params(c)) {
        Spec s = spec_for(p, rig, sc);
        s.init = get(start, p.c_str(), s.init);
        specs.push_back(s);
      }
      FitOutcome f1 = fit(specs, {}, obj, Optimizer::kBobyqa, options.max_evals_candidate / static_cast<int>(n_starts),
                          options.seed);
      evals += f1.evals;
      if (f1.mse < fo.mse) fo = f1;
    }
    r.fit.params = fo.params;
    r.fit.train_rmse_rad = std::sqrt(fo.mse);
    r.fit.cv_rmse_rad =
        cv_rmse(rig, folds, fo.params, model_names(base_names, {c}), sc, options, mine, &evals, &r.fit.cv_fold_mse);
    r.fit.evaluations = evals;
    for (const auto& p : catalogue_params(c)) r.params[p] = fo.params.at(p);
    r.gain = 1.0 - r.fit.cv_rmse_rad / rep.baseline.cv_rmse_rad;
    rep.candidates[ci] = r;
    fitted[ci] = 1;
    log_msg(fmt::format("{:<24} CV RMSE {:.4g} rad  CV gain {:+.3f}  {}", c, r.fit.cv_rmse_rad, r.gain, json_params(r.params)));
  };
  {
    std::vector<std::thread> th;
    const int nw = std::min<int>(nthreads, static_cast<int>(cands.size()));
    for (int w = 0; w < nw; ++w)
      th.emplace_back([&, w] {
        for (std::size_t ci = next++; ci < cands.size(); ci = next++) {
          try {
            run_candidate(all_workers[w], ci);
          } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(err_mutex);
            if (first_error.empty()) first_error = cands[ci] + ": " + e.what();
          }
        }
      });
    for (auto& t : th) t.join();
    if (!first_error.empty()) throw std::runtime_error("calibrate_dynamics: candidate fit failed: " + first_error);
  }

  // ---- Name: the significance rule against the baseline's CV RMSE, nesting ------------------
  auto find = [&](const std::string& n) -> CandidateResult* {
    for (std::size_t i = 0; i < rep.candidates.size(); ++i)
      if (rep.candidates[i].name == n && fitted[i]) return &rep.candidates[i];
    return nullptr;
  };
  for (std::size_t i = 0; i < rep.candidates.size(); ++i) {
    if (!fitted[i]) continue;
    auto& r = rep.candidates[i];
    r.significant = rule.test(rep.baseline, r.fit, catalogue_params(r.name).size(), r.name, r.verdict);
  }
  for (auto& big : rep.candidates) {
    const std::string small_name = nested_entry(big.name);
    CandidateResult* small = small_name.empty() ? nullptr : find(small_name);
    if (!small || !big.significant) continue;
    const std::size_t extra = catalogue_params(big.name).size() - catalogue_params(small_name).size();
    std::string why;
    if (rule.test(small->fit, big.fit, extra, big.name, why)) {
      if (small->significant) {
        small->significant = false;
        small->verdict += fmt::format("; superseded by {} (nests it, beats it in cross-validation)", big.name);
      }
    } else if (small->significant) {
      big.significant = false;
      big.verdict += fmt::format("; does not beat the nested {} clearly (CV RMSE {:.4g} vs {:.4g}: {})", small_name,
                                 big.fit.cv_rmse_rad, small->fit.cv_rmse_rad, why);
    }
  }
  std::vector<const CandidateResult*> pool;
  for (const auto& r : rep.candidates)
    if (r.significant) pool.push_back(&r);
  std::sort(pool.begin(), pool.end(), [](const auto* a, const auto* b) { return a->gain > b->gain; });

  // ---- Extend: forward selection on CV RMSE. The best single cause first; then, in parallel,
  // each other individually significant entry is fitted together with the causes chosen so far,
  // cross-validated, and the best one joins if it passes the rule against the current model. ----
  rep.extended = rep.baseline;
  if (!pool.empty()) {
    rep.extended = pool.front()->fit;
    rep.extended_causes.push_back(pool.front()->name);
    rep.causes.push_back(*pool.front());
    std::vector<const CandidateResult*> remaining(pool.begin() + 1, pool.end());
    while (!remaining.empty()) {
      struct Trial {
        FitOutcome fo;
        double cv = std::numeric_limits<double>::infinity();
        std::vector<double> fold_mse;
        std::size_t added = 0;
      };
      std::vector<Trial> trials(remaining.size());
      std::atomic<std::size_t> nxt{0};
      auto work = [&](WorkerSims* ws) {
        std::vector<WorkerSims*> mine{ws};
        Objective obj = [&](const ParamMap& m) { return mse(rig, tr, m, mine); };
        for (std::size_t k = nxt++; k < remaining.size(); k = nxt++) {
          const CandidateResult& cause = *remaining[k];
          const std::vector<std::string> before = model_names(base_names, rep.extended_causes);
          std::vector<std::string> with = rep.extended_causes;
          with.push_back(cause.name);
          const std::vector<std::string> names = model_names(base_names, with);
          trials[k].added = names.size() - before.size();
          if (trials[k].added == 0) continue;
          // Two starts: the current model with the new entry's parameters at the entry's own fit,
          // and the current model with the entry switched off (its neutral values: the joint fit
          // then starts at the current model's training error and cannot end above it). The entry's
          // own fit may have absorbed what the chosen causes explain (a viscous term fitted alone
          // carries the Coulomb friction too), so either start can be the better one; the lower
          // training error is kept (training data only: CV scores the result).
          FitOutcome best_fit;
          for (const bool neutral : {false, true}) {
            std::vector<Spec> specs;
            for (const auto& p : names) {
              Spec sp = spec_for(p, rig, sc);
              sp.init = rep.extended.params.count(p) ? rep.extended.params.at(p)
                        : neutral                    ? neutral_value(sp)
                                                     : cause.fit.params.at(p);
              specs.push_back(sp);
            }
            FitOutcome fo = fit(specs, {}, obj, Optimizer::kBobyqa, options.max_evals_candidate, options.seed);
            const int evals = best_fit.evals + fo.evals;
            if (fo.mse < best_fit.mse) best_fit = std::move(fo);
            best_fit.evals = evals;
          }
          trials[k].fo = std::move(best_fit);
          trials[k].cv =
              cv_rmse(rig, folds, trials[k].fo.params, names, sc, options, mine, &trials[k].fo.evals, &trials[k].fold_mse);
        }
      };
      {
        std::vector<std::thread> th;
        const std::size_t nw = std::min<std::size_t>(all_workers.size(), remaining.size());
        for (std::size_t w = 1; w < nw; ++w) th.emplace_back(work, all_workers[w]);
        work(all_workers[0]);
        for (auto& t : th) t.join();
      }
      std::size_t best = 0;
      for (std::size_t k = 1; k < trials.size(); ++k)
        if (trials[k].cv < trials[best].cv) best = k;
      const Trial& bt = trials[best];
      std::string why;
      FittedModel trial_model;
      trial_model.params = bt.fo.params;
      trial_model.cv_rmse_rad = bt.cv;
      trial_model.cv_fold_mse = bt.fold_mse;
      const bool accept = bt.added > 0 && rule.test(rep.extended, trial_model, bt.added, remaining[best]->name, why);
      log_msg(fmt::format("extend with {}: CV RMSE {:.4g} (current {:.4g}) -> {} ({})", remaining[best]->name, bt.cv,
                          rep.extended.cv_rmse_rad, accept ? "accepted" : "rejected", why));
      if (!accept) break;
      CandidateResult joined = *remaining[best];
      joined.reference_cv_rmse_rad = rep.extended.cv_rmse_rad;
      joined.gain = 1.0 - bt.cv / rep.extended.cv_rmse_rad;
      joined.verdict = "joined the model: " + why;
      rep.extended.params = bt.fo.params;
      rep.extended.train_rmse_rad = std::sqrt(bt.fo.mse);
      rep.extended.cv_rmse_rad = bt.cv;
      rep.extended.cv_fold_mse = bt.fold_mse;
      rep.extended.evaluations = bt.fo.evals;
      joined.fit = rep.extended;
      for (const auto& p : catalogue_params(joined.name)) joined.params[p] = rep.extended.params.at(p);
      rep.extended_causes.push_back(joined.name);
      rep.causes.push_back(joined);
      remaining.erase(remaining.begin() + static_cast<long>(best));
    }
  }
  // Verdicts of individually significant entries that did not join the joint model.
  for (auto& r : rep.candidates) {
    if (!r.significant) continue;
    if (std::find(rep.extended_causes.begin(), rep.extended_causes.end(), r.name) == rep.extended_causes.end()) {
      r.significant = false;
      r.verdict += "; adds nothing significant once the chosen causes are in the model";
    }
  }

  // ---- Report: held-out (test) RMSE, once, for the baseline and the chosen model (chain) ------
  rep.baseline.heldout_rmse_rad = std::sqrt(mse(rig, ho, rep.baseline.params, all_workers));
  for (auto& c : rep.causes) c.fit.heldout_rmse_rad = std::sqrt(mse(rig, ho, c.fit.params, all_workers));
  rep.extended.heldout_rmse_rad = rep.causes.empty() ? rep.baseline.heldout_rmse_rad : rep.causes.back().fit.heldout_rmse_rad;
  log_msg(fmt::format("held-out RMSE: baseline {:.4g} rad, extended {:.4g} rad", rep.baseline.heldout_rmse_rad,
                      rep.extended.heldout_rmse_rad));

  // ---- Show: where the baseline residuals concentrate (held-out) ----------------------------
  {
    const char* names[] = {"all", "velocity_reversal", "high_torque", "steady_hold", "fast_move"};
    std::vector<double> n_in(5, 0), se_b(5, 0), se_e(5, 0);
    double n_total = 0;
    RolloutTrace tb, te;
    const RigParams rb = rig_params_from(rig, rep.baseline.params);
    const RigParams re = rig_params_from(rig, rep.extended.params);
    const bool ext_backlash = rep.extended.params.count("gap_rad") > 0;
    for (const auto* l : ho) {
      all_workers[0]->get(false).rollout(*l, rb, &tb);
      all_workers[0]->get(ext_backlash).rollout(*l, re, &te);
      const std::vector<double> v = measured_velocity(*l);
      double vmax = 1e-9, tmax = 1e-9, cmax = 1e-9;
      std::vector<double> vcmd(l->size(), 0.0);
      for (std::size_t i = 1; i < l->size(); ++i) vcmd[i] = (l->q_cmd[i] - l->q_cmd[i - 1]) / (l->t[i] - l->t[i - 1]);
      for (std::size_t i = 0; i < l->size(); ++i) {
        vmax = std::max(vmax, std::abs(v[i]));
        tmax = std::max(tmax, std::abs(tb.tau_motor[i]));
        cmax = std::max(cmax, std::abs(vcmd[i]));
      }
      // Velocity reversals: +-50 ms around a sign change of the measured velocity between
      // motions faster than 10 % of the peak.
      std::vector<char> rev(l->size(), 0);
      std::size_t last_fast = 0;
      bool have_fast = false;
      for (std::size_t i = 0; i < l->size(); ++i) {
        if (std::abs(v[i]) > 0.1 * vmax) {
          if (have_fast && (v[i] > 0) != (v[last_fast] > 0) && l->t[i] - l->t[last_fast] < 0.5) {
            const double tc = 0.5 * (l->t[i] + l->t[last_fast]);
            for (std::size_t k = last_fast; k > 0 && l->t[k] > tc - 0.05 - (l->t[i] - l->t[last_fast]); --k) rev[k] = 1;
            for (std::size_t k = last_fast; k < l->size() && l->t[k] < tc + 0.05 + (l->t[i] - l->t[last_fast]); ++k) rev[k] = 1;
          }
          last_fast = i;
          have_fast = true;
        }
      }
      for (std::size_t i = 0; i < l->size(); ++i) {
        const double eb = tb.q[i] - l->q[i], ee = te.q[i] - l->q[i];
        const bool in[5] = {true, rev[i] != 0, std::abs(tb.tau_motor[i]) >= 0.7 * tmax,
                            std::abs(vcmd[i]) < 0.02 * cmax && std::abs(v[i]) < 0.05 * vmax,
                            std::abs(v[i]) >= 0.5 * vmax};
        for (int r = 0; r < 5; ++r)
          if (in[r]) {
            n_in[r] += 1;
            se_b[r] += eb * eb;
            se_e[r] += ee * ee;
          }
        n_total += 1;
      }
    }
    for (int r = 0; r < 5; ++r) {
      RegionResidual rr;
      rr.name = names[r];
      rr.fraction_of_samples = n_in[r] / std::max(1.0, n_total);
      rr.baseline_rmse_rad = n_in[r] > 0 ? std::sqrt(se_b[r] / n_in[r]) : 0.0;
      rr.extended_rmse_rad = n_in[r] > 0 ? std::sqrt(se_e[r] / n_in[r]) : 0.0;
      rep.regions.push_back(rr);
    }
  }
  bool gain_columns = false;
  for (const auto* l : tr) gain_columns = gain_columns || l->has_kp() || l->has_kd();
  add_si_gains(rig, gain_columns, rep.baseline.params);
  add_si_gains(rig, gain_columns, rep.extended.params);
  for (auto& c : rep.candidates) add_si_gains(rig, gain_columns, c.fit.params);
  for (auto& c : rep.causes) add_si_gains(rig, gain_columns, c.fit.params);
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return rep;
}

std::string report_to_json(const CalibrationReport& r) {
  auto sel = [&](const FittedModel& m, double ref) {
    const double cv = m.cv_rmse_rad;
    std::string t = fmt::format("{{\"method\": \"kfold\", \"folds\": {}, \"fold_unit\": \"{}\", \"cv_rmse_rad\": {}", r.cv_folds,
                                r.cv_fold_unit, json_num(cv));
    if (!m.cv_fold_mse.empty()) {
      t += ", \"fold_rmse_rad\": [";
      for (std::size_t f = 0; f < m.cv_fold_mse.size(); ++f) t += fmt::format("{}{}", f ? ", " : "", json_num(std::sqrt(m.cv_fold_mse[f])));
      t += "]";
    }
    if (std::isfinite(ref))
      t += fmt::format(", \"reference_cv_rmse_rad\": {}, \"cv_gain\": {}", json_num(ref), json_num(1.0 - cv / ref));
    return t + "}";
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::string s = "{\n";
  s += fmt::format("  \"baseline\": {{\"params\": {}, \"train_rmse_rad\": {}, \"heldout_rmse_rad\": {}, \"selection\": {}}},\n",
                   json_params(r.baseline.params), json_num(r.baseline.train_rmse_rad), json_num(r.baseline.heldout_rmse_rad),
                   sel(r.baseline, nan));
  s += "  \"causes\": [";
  for (std::size_t i = 0; i < r.causes.size(); ++i) {
    const auto& c = r.causes[i];
    s += fmt::format("{}\n    {{\"name\": \"{}\", \"params\": {}, \"heldout_rmse_rad\": {}, \"gain\": {}, \"train_rmse_rad\": {}, "
                     "\"selection\": {}, \"verdict\": \"{}\"}}",
                     i ? "," : "", c.name, json_params(c.params), json_num(c.fit.heldout_rmse_rad), json_num(c.gain),
                     json_num(c.fit.train_rmse_rad), sel(c.fit, c.reference_cv_rmse_rad), c.verdict);
  }
  s += r.causes.empty() ? "],\n" : "\n  ],\n";
  s += fmt::format("  \"extended\": {{\"params\": {}, \"causes\": [", json_params(r.extended.params));
  for (std::size_t i = 0; i < r.extended_causes.size(); ++i) s += fmt::format("{}\"{}\"", i ? ", " : "", r.extended_causes[i]);
  s += fmt::format("], \"train_rmse_rad\": {}, \"heldout_rmse_rad\": {}, \"gain\": {}, \"selection\": {}}},\n",
                   json_num(r.extended.train_rmse_rad), json_num(r.extended.heldout_rmse_rad),
                   json_num(1.0 - r.extended.heldout_rmse_rad / r.baseline.heldout_rmse_rad),
                   sel(r.extended, r.baseline.cv_rmse_rad));
  s += "  \"candidates\": [";
  for (std::size_t i = 0; i < r.candidates.size(); ++i) {
    const auto& c = r.candidates[i];
    s += fmt::format("{}\n    {{\"name\": \"{}\", \"params\": {}, \"heldout_rmse_rad\": {}, \"train_rmse_rad\": {}, \"gain\": {}, "
                     "\"significant\": {}, \"verdict\": \"{}\", \"evaluations\": {}, \"selection\": {}}}",
                     i ? "," : "", c.name, json_params(c.params), json_num(c.fit.heldout_rmse_rad), json_num(c.fit.train_rmse_rad),
                     json_num(c.gain), c.significant ? "true" : "false", c.verdict, c.fit.evaluations,
                     sel(c.fit, c.reference_cv_rmse_rad));
  }
  s += "\n  ],\n  \"residual_regions\": [";
  for (std::size_t i = 0; i < r.regions.size(); ++i) {
    const auto& g = r.regions[i];
    s += fmt::format("{}\n    {{\"region\": \"{}\", \"fraction_of_samples\": {}, \"baseline_rmse_rad\": {}, \"extended_rmse_rad\": {}}}",
                     i ? "," : "", g.name, json_num(g.fraction_of_samples), json_num(g.baseline_rmse_rad),
                     json_num(g.extended_rmse_rad));
  }
  s += "\n  ],\n  \"train_logs\": [";
  for (std::size_t i = 0; i < r.train_logs.size(); ++i) s += fmt::format("{}\"{}\"", i ? ", " : "", r.train_logs[i]);
  s += "],\n  \"heldout_logs\": [";
  for (std::size_t i = 0; i < r.heldout_logs.size(); ++i) s += fmt::format("{}\"{}\"", i ? ", " : "", r.heldout_logs[i]);
  s += fmt::format("],\n  \"noise_floor_rad\": {},\n  \"noise\": {{\"quantum_rad\": {}, \"hf_rad\": {}, \"floor_rad\": {}, "
                   "\"effective_samples\": {}, \"samples\": {}}},\n",
                   json_num(r.noise.floor_rad), json_num(r.noise.quantum_rad), json_num(r.noise.hf_rad),
                   json_num(r.noise.floor_rad), json_num(r.noise.effective_samples), r.noise.samples);
  s += fmt::format("  \"selection\": {{\"method\": \"kfold\", \"folds\": {}, \"fold_unit\": \"{}\", \"data\": \"training logs only\"}},\n",
                   r.cv_folds, r.cv_fold_unit);
  s += fmt::format("  \"optimizer\": \"{}\",\n  \"wall_time_s\": {}\n}}\n", r.optimizer, json_num(r.wall_time_s));
  return s;
}

void write_trace_csv(const RigConfig& rig, const std::vector<BenchLog>& heldout, const CalibrationReport& report,
                     const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write trace CSV");
  out << "log,t,q_cmd,q_measured,q_baseline,q_extended\n";
  BenchSimulator plain(rig, false);
  const bool ext_backlash = report.extended.params.count("gap_rad") > 0;
  BenchSimulator ext(rig, ext_backlash);
  RolloutTrace tb, te;
  for (std::size_t k = 0; k < heldout.size(); ++k) {
    const auto& l = heldout[k];
    plain.rollout(l, rig_params_from(rig, report.baseline.params), &tb);
    ext.rollout(l, rig_params_from(rig, report.extended.params), &te);
    for (std::size_t i = 0; i < l.size(); ++i)
      out << fmt::format("{},{:.6f},{:.6g},{:.6g},{:.6g},{:.6g}\n", k, l.t[i], l.q_cmd[i], l.q[i], tb.q[i], te.q[i]);
  }
}

}  // namespace pmg::calib
