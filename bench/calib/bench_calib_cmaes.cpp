// Wall time of a CMA-ES baseline fit (eta = [Kp, Kd, I]) with the population evaluated in 1 vs 2
// (or N) threads, one BenchSimulator (own mjData) per thread. Synthetic logs from the reference
// test rig (make_test_rig), truth off nominal (kp x1.1, kd x0.9, armature 0.005).
//   bench_calib_cmaes [--threads N] [--duration S] [--rate HZ] [--generations G] [--logs 1|2]
// Prints, for 1 and N threads:
//   1. the CMA-ES phase alone: G generations of cmaes_minimize_parallel on the training loss;
//   2. fit_baseline with --optimizer cmaes (CMA-ES on half of 400 evaluations + BOBYQA polish,
//      whose rollouts of the logs run in parallel) and with cmaes_pagmo (serial population, only
//      the logs in parallel: with one log it gains nothing from a second thread).
// and whether the 1- and N-thread results are bit-identical.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/calib/bench_sim.hpp"
#include "pmg/calib/cmaes.hpp"
#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/calib/log_generator.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
double cpu_since(std::clock_t c0) { return static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC; }
std::string load_average() {
  std::ifstream f("/proc/loadavg");
  double a = -1.0;
  f >> a;
  return a >= 0 ? fmt::format("{:.2f}", a) : std::string("n/a");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_calib_cmaes: wall time of a CMA-ES baseline fit with the population evaluated on 1 vs N "
               "threads, and whether the results are bit-identical"};
  int threads = 2, generations = 20, n_logs = 2;
  double duration = 25.0, rate = 500.0;
  app.add_option("--threads", threads, "N, the thread count compared with 1")->check(CLI::Range(2, 1024))
      ->capture_default_str();
  app.add_option("--duration", duration, "length of each training log [s]")->check(CLI::Range(2.001, 3600.0))
      ->capture_default_str();
  app.add_option("--rate", rate, "log rate [Hz]")->check(CLI::Range(10.0, 10000.0))->capture_default_str();
  app.add_option("--generations", generations, "CMA-ES generations of the phase-1 timing")
      ->check(CLI::Range(1, 100000))->capture_default_str();
  app.add_option("--logs", n_logs, "training logs (1 or 2)")->check(CLI::Range(1, 2))->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  using namespace pmg::calib;
  const RigConfig rig = make_test_rig(0.002);
  const RigParams truth = make_rig_truth(rig, 1.1, 0.9, 0.005);
  SyntheticLogOptions o;
  o.duration_s = duration;
  o.log_rate_hz = rate;
  o.kp_log = 4.0;
  o.kd_log = 0.08;
  o.trajectory = Trajectory::kStepsHolds;
  std::vector<BenchLog> train{generate_bench_log(rig, truth, o)};
  o.trajectory = Trajectory::kSines;
  o.seed = 2;
  if (n_logs == 2) train.push_back(generate_bench_log(rig, truth, o));
  fmt::print("CMA-ES baseline fit: {} training log(s) of {:.0f} s at {:.0f} Hz, physics step {} ms; "
             "{} hardware threads, load average {} (wall-time speed-up needs idle cores)\n",
             n_logs, duration, rate, rig.sim_dt_s * 1e3, std::thread::hardware_concurrency(), load_average());

  // 1. CMA-ES phase alone: the training loss of [kp_scale, kd_scale, armature] in the unit box
  // (log scale for the gains as in pmg_calib_dynamics), one simulator per worker.
  double wall1 = 0.0;
  Eigen::VectorXd x1;
  for (int nt : {1, threads}) {
    std::vector<std::unique_ptr<BenchSimulator>> sims;
    for (int w = 0; w < nt; ++w) sims.push_back(std::make_unique<BenchSimulator>(rig, false));
    const PointObjective loss = [&](const Eigen::VectorXd& u, int w) {
      RigParams p;
      p.kp_scale = std::exp(std::log(0.05) + u[0] * std::log(20.0 / 0.05));
      p.kd_scale = std::exp(std::log(0.01) + u[1] * std::log(50.0 / 0.01));
      p.armature_kgm2 = u[2] * 20.0 * rig.armature_kgm2;
      p.act.torque_limit_Nm = rig.torque_limit_Nm;
      p.act.rate_hz = rig.rate_hz;
      double sse = 0.0;
      for (const auto& l : train) sse += sims[static_cast<std::size_t>(w)]->rollout(l, p);  // logs serially
      return std::isfinite(sse) ? sse : 1e6;
    };
    CmaesOptions co;
    co.sigma0 = 0.25;
    co.threads = nt;
    co.x_tol = 0.0;
    co.f_tol = 0.0;
    Eigen::VectorXd x0(3);
    x0 << 0.5, 0.5, 0.05;
    co.max_evals = generations * Cmaes(x0, co).lambda();
    const auto t0 = Clock::now();
    const std::clock_t c0 = std::clock();
    const CmaesResult r = cmaes_minimize_parallel(loss, x0, co);
    const double wall = since(t0), cpu = cpu_since(c0);
    if (nt == 1) {
      wall1 = wall;
      x1 = r.x;
    }
    const std::string vs1 = nt == 1 ? ""
                                    : fmt::format(" (speed-up x{:.2f}, best point {} 1 thread)", wall1 / wall,
                                                  r.x == x1 ? "bit-identical to" : "DIFFERS from");
    fmt::print("  CMA-ES phase, {} generations x lambda {} = {} rollout sets, {} thread(s): "
               "wall {:.2f} s, CPU {:.2f} s{}\n",
               r.generations, co.max_evals / generations, r.evaluations, nt, wall, cpu, vs1);
  }

  // 2. The whole baseline fit as pmg_calib_dynamics runs it.
  for (const char* name : {"cmaes", "cmaes_pagmo"}) {
    double w1 = 0.0;
    FittedModel f1;
    for (int nt : {1, threads}) {
      CalibrationOptions opt;
      opt.optimizer = parse_optimizer(name);
      opt.threads = nt;
      const auto t0 = Clock::now();
      const std::clock_t c0 = std::clock();
      const FittedModel f = fit_baseline(rig, train, opt);
      const double wall = since(t0), cpu = cpu_since(c0);
      if (nt == 1) {
        w1 = wall;
        f1 = f;
      }
      const std::string vs1 = nt == 1 ? ""
                                      : fmt::format(" (speed-up x{:.2f}, {})", w1 / wall,
                                                    f.params == f1.params ? "identical fit" : "fit DIFFERS");
      fmt::print("  fit_baseline --optimizer {:<11} {} thread(s): wall {:.2f} s, CPU {:.2f} s, {} evals, "
                 "kp_scale {:.4f} kd_scale {:.4f} armature {:.5f}, RMSE {:.3g} rad{}\n",
                 name, nt, wall, cpu, f.evaluations, f.params.at("kp_scale"), f.params.at("kd_scale"),
                 f.params.at("armature"), f.train_rmse_rad, vs1);
    }
  }
  return 0;
}
