// Baseline calibration with --optimizer cmaes (population evaluated in parallel workers) on 6 s
// synthetic bench logs: recovers kp/kd/armature, and gives the same fit with 1 and 2 threads.
#include <cmath>
#include <cstdlib>
#include <vector>

#include <gtest/gtest.h>

#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/calib/log_generator.hpp"

namespace pmg::calib {
namespace {

/// Truth well off the rig's nominal values (kp x1.3, kd x0.8, armature 0.006 vs 0.004).
RigParams truth_of(const RigConfig& rig) {
  return make_rig_truth(rig, 1.3, 0.8, 0.006);
}

std::vector<BenchLog> short_logs(const RigConfig& rig, std::uint64_t seed) {
  std::vector<BenchLog> logs;
  SyntheticLogOptions o;
  o.duration_s = 6.0;
  o.log_rate_hz = 200.0;
  o.seed = seed;
  o.trajectory = Trajectory::kSines;
  o.kp_log = 4.0;
  o.kd_log = 0.08;
  logs.push_back(generate_bench_log(rig, truth_of(rig), o));
  o.trajectory = Trajectory::kStepsHolds;
  o.kp_log = 8.0;
  o.kd_log = 0.12;
  o.seed = seed + 1;
  logs.push_back(generate_bench_log(rig, truth_of(rig), o));
  return logs;
}

void expect_truth(const std::map<std::string, double>& p) {
  EXPECT_NEAR(p.at("kp_scale"), 1.3, 0.03 * 1.3);
  EXPECT_NEAR(p.at("kd_scale"), 0.8, 0.10 * 0.8);
  EXPECT_NEAR(p.at("armature"), 0.006, 0.10 * 0.006);
}

TEST(CmaesCalibration, BaselineRecoveredAndThreadCountIndependent) {
  const RigConfig rig = make_test_rig(0.002);
  const auto logs = short_logs(rig, 21);
  CalibrationOptions opt;
  opt.optimizer = parse_optimizer("cmaes");
  opt.max_evals_baseline = 300;
  opt.threads = 1;
  const FittedModel f1 = fit_baseline(rig, logs, opt);
  opt.threads = 2;
  const FittedModel f2 = fit_baseline(rig, logs, opt);
  expect_truth(f2.params);
  EXPECT_LT(f2.train_rmse_rad, 2e-3);  // encoder resolution 1.5 mrad, noise 0.2 mrad
  EXPECT_GT(f2.evaluations, 100);      // CMA-ES ran on half the budget, then the polish
  EXPECT_LE(f2.evaluations, opt.max_evals_baseline);
  // Bit-identical: the generation's candidates are sampled before evaluation, gathered by index.
  for (const char* k : {"kp_scale", "kd_scale", "armature"}) EXPECT_EQ(f1.params.at(k), f2.params.at(k)) << k;
  EXPECT_EQ(f1.train_rmse_rad, f2.train_rmse_rad);
  EXPECT_EQ(f1.evaluations, f2.evaluations);
}

TEST(CmaesCalibration, PagmoCrossCheckAgrees) {
  const RigConfig rig = make_test_rig(0.002);
  const auto logs = short_logs(rig, 21);
  CalibrationOptions opt;
  opt.optimizer = parse_optimizer("cmaes_pagmo");
  opt.max_evals_baseline = 300;
  opt.threads = 2;
  const FittedModel f = fit_baseline(rig, logs, opt);
  expect_truth(f.params);
}

TEST(CmaesCalibration, FullCalibrationWithCmaes) {
  // calibrate_dynamics with the cmaes optimiser on clean data: one candidate tested, nothing named,
  // the baseline recovered; the report names the optimiser.
  const RigConfig rig = make_test_rig(0.002);
  const auto train = short_logs(rig, 31);
  SyntheticLogOptions o;
  o.duration_s = 6.0;
  o.trajectory = Trajectory::kChirp;
  o.kp_log = 6.0;
  o.kd_log = 0.1;
  o.seed = 40;
  const std::vector<BenchLog> held{generate_bench_log(rig, truth_of(rig), o)};
  CalibrationOptions opt;
  opt.optimizer = parse_optimizer("cmaes");
  opt.max_evals_baseline = 300;
  opt.max_evals_candidate = 60;
  opt.threads = 2;
  opt.candidates = {"coulomb_friction"};
  opt.verbose = std::getenv("PMG_CALIB_VERBOSE") != nullptr;
  const CalibrationReport rep = calibrate_dynamics(rig, train, held, opt);
  EXPECT_EQ(rep.optimizer, "cmaes");
  expect_truth(rep.baseline.params);
  EXPECT_LT(rep.baseline.heldout_rmse_rad, 3e-3);
  EXPECT_TRUE(rep.causes.empty());
}

TEST(CmaesCalibration, OptimizerNames) {
  EXPECT_EQ(parse_optimizer("cmaes"), Optimizer::kCmaes);
  EXPECT_EQ(parse_optimizer("cmaes_pagmo"), Optimizer::kCmaesPagmo);
  EXPECT_THROW(parse_optimizer("cma"), std::invalid_argument);
}

}  // namespace
}  // namespace pmg::calib
