// Trustworthy verdicts of pmg::calib::calibrate_dynamics (issue 15): the held-out logs report and
// never choose (selection is K-fold cross-validation over the training logs), a cause is named
// only when its gain is significant against the logs' noise floor, a delay shorter than the
// driver / sample period is not a transport delay, and a commanded-vs-delivered torque ratio on
// torque-controlled data is named torque_constant (not absorbed by dry friction).
#include <cmath>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/calib/log_generator.hpp"

namespace pmg::calib {
namespace {

std::string named(const CalibrationReport& rep) {
  std::string s;
  for (const auto& k : rep.causes) s += k.name + " ";
  return s.empty() ? "none" : s;
}

bool is_named(const CalibrationReport& rep, const std::string& n) {
  for (const auto& k : rep.causes)
    if (k.name == n) return true;
  return false;
}

CalibrationOptions quick_options(std::vector<std::string> candidates) {
  CalibrationOptions opt;
  opt.threads = 2;
  opt.verbose = std::getenv("PMG_CALIB_VERBOSE") != nullptr;
  opt.candidates = std::move(candidates);
  return opt;
}

/// Two PD training logs and one held-out log of the reference rig (200 Hz, 6 s, 4096-count encoder
/// and 0.2 mrad noise), as in test_hidden_effects.cpp.
struct Logs {
  std::vector<BenchLog> train, heldout;
};
Logs pd_logs(const RigConfig& rig, const RigParams& truth, std::uint64_t seed) {
  Logs l;
  SyntheticLogOptions o;
  o.duration_s = 6.0;
  o.log_rate_hz = 200.0;
  o.seed = seed;
  o.kp_log = 4.0;
  o.kd_log = 0.08;
  l.train.push_back(generate_bench_log(rig, truth, o));
  o.trajectory = Trajectory::kStepsHolds;
  o.kp_log = 8.0;
  o.kd_log = 0.12;
  o.seed = seed + 1;
  l.train.push_back(generate_bench_log(rig, truth, o));
  o.trajectory = Trajectory::kChirp;
  o.kp_log = 6.0;
  o.kd_log = 0.1;
  o.seed = seed + 2;
  l.heldout.push_back(generate_bench_log(rig, truth, o));
  return l;
}

TEST(NoiseFloor, RecoversEncoderResolutionAndNoise) {
  const RigConfig rig = make_test_rig(0.002);
  const RigParams truth = make_rig_truth(rig, 1.1, 0.9, 0.005);
  SyntheticLogOptions o;
  o.duration_s = 6.0;
  o.noise_rad = 1e-3;
  o.quantum_rad = 0.0;
  const NoiseFloor white = estimate_noise_floor({generate_bench_log(rig, truth, o)});
  EXPECT_NEAR(white.hf_rad, 1e-3, 0.15e-3);  // smooth motion adds little at 200 Hz
  o.noise_rad = 0.0;
  o.quantum_rad = 2.0 * 3.14159265358979 / 4096.0;
  const NoiseFloor quant = estimate_noise_floor({generate_bench_log(rig, truth, o)});
  EXPECT_NEAR(quant.quantum_rad, o.quantum_rad, 1e-9);
  EXPECT_GT(quant.floor_rad, o.quantum_rad / std::sqrt(12.0) * 0.99);
  EXPECT_LT(quant.floor_rad, o.quantum_rad);
  EXPECT_THROW(estimate_noise_floor({}), std::invalid_argument);
}

// (a) Clean simulated logs: the whole catalogue is tested and nothing is named; the noise floor
// is reported and the baseline is already within the rule-3 room of it.
TEST(TrustworthyVerdicts, CleanDataNamesNothing) {
  const RigConfig rig = make_test_rig(0.002);
  const Logs logs = pd_logs(rig, make_rig_truth(rig, 1.1, 0.9, 0.005), 21);
  const CalibrationReport rep = calibrate_dynamics(rig, logs.train, logs.heldout, quick_options({}));
  EXPECT_TRUE(rep.causes.empty()) << "named on clean data: " << named(rep);
  EXPECT_GT(rep.noise.floor_rad, 3e-4);   // 4096 counts/rev (0.44 mrad RMS) + 0.2 mrad noise
  EXPECT_LT(rep.noise.floor_rad, 1.2e-3);
  EXPECT_EQ(rep.cv_folds, 2);
  EXPECT_EQ(rep.cv_fold_unit, "logs");
  EXPECT_LT(rep.baseline.cv_rmse_rad, 2e-3);
  for (const auto& c : rep.candidates) {
    EXPECT_FALSE(c.significant) << c.name << ": " << c.verdict;
    EXPECT_TRUE(std::isnan(c.fit.heldout_rmse_rad)) << c.name << ": held-out RMSE measured for a candidate";
  }
  const YAML::Node j = YAML::Load(report_to_json(rep));
  EXPECT_GT(j["noise_floor_rad"].as<double>(), 0.0);
  EXPECT_EQ(j["selection"]["method"].as<std::string>(), "kfold");
  EXPECT_EQ(j["baseline"]["selection"]["folds"].as<int>(), 2);
}

// (b) Torque-controlled logs whose motor delivers 0.8 of the commanded torque: torque_constant is
// named first and kt_scale recovered within 5 %; dry friction does not absorb the ratio.
TEST(TrustworthyVerdicts, TorqueConstantNamedOnTorqueControlledData) {
  const RigConfig rig = make_test_rig(0.002);
  RigParams truth = make_rig_truth(rig, 1.0, 1.0, 0.005);
  truth.act.kt_scale = 0.8;
  std::vector<BenchLog> train, held;
  SyntheticLogOptions o;
  o.duration_s = 6.0;
  o.log_rate_hz = 200.0;
  o.tau_ff_Nm = 0.3;  // 0.6 of the peak gravity torque
  for (int k = 0; k < 3; ++k) {
    o.trajectory = k == 0 ? Trajectory::kSines : k == 1 ? Trajectory::kStepsHolds : Trajectory::kChirp;
    o.seed = 40 + k;
    (k < 2 ? train : held).push_back(generate_bench_log(rig, truth, o));
  }
  ASSERT_EQ(train.front().kp.front(), 0.0);
  const CalibrationReport rep = calibrate_dynamics(
      rig, train, held, quick_options({"coulomb_friction", "viscous_friction", "torque_constant", "torque_saturation"}));
  ASSERT_FALSE(rep.causes.empty()) << "kt_scale 0.8 not named";
  EXPECT_EQ(rep.causes.front().name, "torque_constant") << "named: " << named(rep);
  EXPECT_NEAR(rep.extended.params.at("kt_scale"), 0.8, 0.04) << named(rep);
  EXPECT_FALSE(is_named(rep, "coulomb_friction")) << named(rep);
  EXPECT_LT(rep.extended.heldout_rmse_rad, 0.5 * rep.baseline.heldout_rmse_rad);
  // The identified model flows into an actuator block (robot config / SIL) and back.
  const ActuatorBlock b = actuator_block_from_params(rig, rep.extended.params);
  EXPECT_NEAR(b.params.kt_scale, rep.extended.params.at("kt_scale"), 1e-12);
  const ActuatorBlock back = parse_actuator_block(actuator_block_to_yaml(b), "kt test");
  EXPECT_NEAR(back.params.kt_scale, b.params.kt_scale, 1e-9);
}

// On PD-controlled data kt_scale is kp and kd scaled together: not fitted, verdict says why.
TEST(TrustworthyVerdicts, TorqueConstantNotFittedOnPdData) {
  const RigConfig rig = make_test_rig(0.002);
  const Logs logs = pd_logs(rig, make_rig_truth(rig, 1.1, 0.9, 0.005), 5);
  const CalibrationReport rep = calibrate_dynamics(rig, logs.train, logs.heldout, quick_options({"torque_constant"}));
  ASSERT_EQ(rep.candidates.size(), 1u);
  EXPECT_FALSE(rep.candidates[0].significant);
  EXPECT_NE(rep.candidates[0].verdict.find("feed-forward"), std::string::npos) << rep.candidates[0].verdict;
}

// (c) A 3 ms delay: longer than nothing, shorter than the 5 ms log period (and above the 2 ms
// driver period). It is not named a transport delay.
TEST(TrustworthyVerdicts, DelayBelowSamplePeriodNotNamed) {
  const RigConfig rig = make_test_rig(0.002);
  RigParams truth = make_rig_truth(rig, 1.1, 0.9, 0.005);
  truth.act.delay_s = 0.003;
  const Logs logs = pd_logs(rig, truth, 33);
  const CalibrationReport rep =
      calibrate_dynamics(rig, logs.train, logs.heldout, quick_options({"transport_delay", "viscous_friction"}));
  EXPECT_FALSE(is_named(rep, "transport_delay")) << "named: " << named(rep);
  for (const auto& c : rep.candidates) {
    if (c.name == "transport_delay") {
      EXPECT_FALSE(c.significant) << c.verdict;
    }
  }
}

// (d) The held-out logs report and do not choose: replacing the held-out log by a corrupted one
// (offset + noise + a different trajectory) leaves every selection number and parameter
// bit-identical, while the reported test RMSE changes.
TEST(TrustworthyVerdicts, SelectionUsesOnlyTrainingLogs) {
  const RigConfig rig = make_test_rig(0.002);
  RigParams truth = make_rig_truth(rig, 1.1, 0.9, 0.005);
  draw_hidden_effect("coulomb_friction", 12, rig, truth);
  const Logs logs = pd_logs(rig, truth, 12);
  std::vector<BenchLog> corrupted = logs.heldout;
  for (std::size_t i = 0; i < corrupted[0].size(); ++i) corrupted[0].q[i] += 0.05 + 0.01 * std::sin(0.37 * i);
  const auto opt = quick_options({"coulomb_friction", "zero_offset", "viscous_friction"});
  const CalibrationReport a = calibrate_dynamics(rig, logs.train, logs.heldout, opt);
  const CalibrationReport b = calibrate_dynamics(rig, logs.train, corrupted, opt);
  ASSERT_FALSE(a.causes.empty());
  EXPECT_EQ(a.causes.front().name, "coulomb_friction");
  EXPECT_EQ(named(a), named(b));
  EXPECT_EQ(a.extended.params, b.extended.params);
  EXPECT_EQ(a.baseline.params, b.baseline.params);
  EXPECT_EQ(a.baseline.cv_rmse_rad, b.baseline.cv_rmse_rad);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_EQ(a.candidates[i].fit.cv_rmse_rad, b.candidates[i].fit.cv_rmse_rad) << a.candidates[i].name;
    EXPECT_EQ(a.candidates[i].significant, b.candidates[i].significant) << a.candidates[i].name;
  }
  EXPECT_GT(b.extended.heldout_rmse_rad, a.extended.heldout_rmse_rad + 0.03);
  EXPECT_NE(b.baseline.heldout_rmse_rad, a.baseline.heldout_rmse_rad);
}

// With one training log the folds are contiguous time blocks of it.
TEST(TrustworthyVerdicts, OneTrainingLogFoldsAreTimeBlocks) {
  const RigConfig rig = make_test_rig(0.002);
  const Logs logs = pd_logs(rig, make_rig_truth(rig, 1.1, 0.9, 0.005), 8);
  auto opt = quick_options({"zero_offset"});
  opt.cv_folds = 3;
  const CalibrationReport rep = calibrate_dynamics(rig, {logs.train[0]}, logs.heldout, opt);
  EXPECT_EQ(rep.cv_folds, 3);
  EXPECT_EQ(rep.cv_fold_unit, "time_blocks");
  EXPECT_TRUE(std::isfinite(rep.baseline.cv_rmse_rad));
  EXPECT_TRUE(rep.causes.empty()) << named(rep);
  opt.cv_folds = 1;
  EXPECT_THROW(opt.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace pmg::calib
