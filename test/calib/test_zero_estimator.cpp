// Zero-point estimator (PMG eqs. 21-25) on synthetic kinematic data: exact recovery, observability of the
// shipped protocol, the tau gate, non-convergence reporting, option and protocol validation.
#include <cmath>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/calib/zero_calibration.hpp"
#include "pmg/common/robot_config.hpp"
#include "temp_dir.hpp"

namespace pmg::calib {
namespace {

class ZeroEstimatorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    robot_ = new RobotConfig(pmg::test::g1Robot());
    model_ = new std::shared_ptr<const gco::LegModel>(gco::LegModel::fromRobotConfig(*robot_));
    protocol_ = new ZeroProtocol(loadZeroProtocol(pmg::test::g1ZeroProtocolPath()));
  }
  static void TearDownTestSuite() {
    delete robot_;
    delete model_;
    delete protocol_;
  }
  static ZeroVector randomZ(unsigned seed, double max = 0.05) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-max, max);
    ZeroVector z;
    for (int j = 0; j < kZeroJoints; ++j) z(j) = u(rng);
    return z;
  }
  static RobotConfig* robot_;
  static std::shared_ptr<const gco::LegModel>* model_;
  static ZeroProtocol* protocol_;
};
RobotConfig* ZeroEstimatorTest::robot_ = nullptr;
std::shared_ptr<const gco::LegModel>* ZeroEstimatorTest::model_ = nullptr;
ZeroProtocol* ZeroEstimatorTest::protocol_ = nullptr;

TEST_F(ZeroEstimatorTest, RecoversOffsetsFromExactData) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const ZeroVector z_true = randomZ(seed);
    const auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
    ZeroEstimator est(*model_, {});
    const ZeroEstimate r = est.estimate(samples);
    EXPECT_TRUE(r.converged) << r.message;
    EXPECT_EQ(r.used.size(), samples.size());
    EXPECT_TRUE(r.rejected_tau.empty());
    EXPECT_LT((r.z - z_true).cwiseAbs().maxCoeff(), 1e-4) << "seed " << seed << "\nz    " << r.z.transpose()
                                                         << "\ntrue " << z_true.transpose();
    // The history starts far from the truth and ends at it.
    ASSERT_FALSE(r.history.empty());
    EXPECT_GT((r.history.front() - z_true).cwiseAbs().maxCoeff(), 1e-3);
  }
}

TEST_F(ZeroEstimatorTest, MedianNeedsFullCorrectionsPerPose) {
  // Eq. 23's median of the literal per-pose projections (each delta_k only in the 8-dim row space of its
  // pose) wanders off; the leave-one-out corrections converge like Gauss-Newton.
  const ZeroVector z_true = randomZ(1);
  const auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
  ZeroEstimatorOptions o;
  o.max_iterations = 150;
  o.per_pose = ZeroPerPose::kProjection;
  const ZeroEstimate proj = ZeroEstimator(*model_, o).estimate(samples);
  EXPECT_FALSE(proj.converged);
  EXPECT_GT((proj.z - z_true).cwiseAbs().maxCoeff(), 1e-2);
  o.per_pose = ZeroPerPose::kLeaveOneOut;
  const ZeroEstimate loo = ZeroEstimator(*model_, o).estimate(samples);
  EXPECT_TRUE(loo.converged) << loo.message;
  EXPECT_LE(loo.iterations, 20);
  EXPECT_LT((loo.z - z_true).cwiseAbs().maxCoeff(), 1e-5);
}

TEST_F(ZeroEstimatorTest, ShippedProtocolObservesAllOffsetsSquatsAloneDoNot) {
  const ZeroVector z_true = randomZ(7);
  const auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
  ZeroEstimator est(*model_, {});
  const Eigen::Vector3d p = est.placementOf(samples.front().readings + z_true);
  const ZeroObservability all = est.observability(samples, z_true, p);
  EXPECT_EQ(all.rank, kZeroJoints + 3);
  EXPECT_GT(all.singular_values(all.singular_values.size() - 1), 1e-3);

  ZeroProtocol squats = *protocol_;
  squats.poses.clear();
  for (const auto& pose : protocol_->poses)
    if (pose.rpy.isZero() && pose.dp.head<2>().isZero()) squats.poses.push_back(pose);
  ASSERT_GE(squats.poses.size(), 2u);
  const auto sq = synthesizeZeroSamples(*model_, *robot_, squats, z_true);
  const ZeroObservability o = est.observability(sq, z_true, p);
  EXPECT_LT(o.singular_values(o.singular_values.size() - 1), 1e-6 * o.singular_values(0));
  EXPECT_LT(o.rank, kZeroJoints + 3);
}

TEST_F(ZeroEstimatorTest, NaiveSimulationAtReadingsPlusZCarriesNoInformation) {
  // The ill-posed reading of eq. 22: a model driven to r + z reproduces r + z, delta = 0, z never moves.
  const ZeroVector z_true = randomZ(11);
  const auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
  ZeroEstimator est(*model_, {});
  // With the constraints of the pose (feet planted, IMU tilt) the per-pose solve moves away from r + z ...
  Eigen::Vector3d pk;
  const Eigen::Vector3d p = est.placementOf(samples[3].readings);
  const ZeroVector q_sim = est.solvePose(samples[3].readings, p, samples[3].up_I, &pk);
  EXPECT_GT((q_sim - samples[3].readings).cwiseAbs().maxCoeff(), 1e-3);
  // ... and at the true offsets the constraints hold and delta vanishes.
  const ZeroVector q_true = samples[3].readings + z_true;
  const Eigen::Vector3d p_true = est.placementOf(q_true);
  EXPECT_LT(est.constraint(q_true, p_true, samples[3].up_I).norm(), 1e-6);  // synthetic IK tolerance
  EXPECT_LT((est.solvePose(q_true, p_true, samples[3].up_I, &pk) - q_true).norm(), 1e-6);
}

TEST_F(ZeroEstimatorTest, TauGateExcludesCorruptedPose) {
  const ZeroVector z_true = randomZ(5);
  auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
  const int bad = 6;
  // The robot rocked onto a foot edge: the IMU says 0.06 rad more roll than the planted-feet model allows.
  samples[bad].up_I = Eigen::AngleAxisd(0.06, Eigen::Vector3d::UnitX()) * samples[bad].up_I;
  ZeroEstimatorOptions o;
  o.tau = 0.005;
  ZeroEstimator est(*model_, o);
  const ZeroEstimate r = est.estimate(samples);
  EXPECT_TRUE(r.converged) << r.message;
  ASSERT_EQ(r.rejected_tau.size(), 1u) << r.message;
  EXPECT_EQ(r.rejected_tau.front(), bad);
  EXPECT_GT(r.imu_disagreement[bad], o.tau);
  EXPECT_LT((r.z - z_true).cwiseAbs().maxCoeff(), 1e-4);
  // Without the gate (tau large) the corrupted pose stays in and biases the estimate.
  o.tau = 1.0;
  ZeroEstimator loose(*model_, o);
  const ZeroEstimate r2 = loose.estimate(samples);
  EXPECT_TRUE(r2.rejected_tau.empty());
  EXPECT_GT((r2.z - z_true).cwiseAbs().maxCoeff(), (r.z - z_true).cwiseAbs().maxCoeff());
}

TEST_F(ZeroEstimatorTest, CaptureRefusedSamplesAreNotUsed) {
  const ZeroVector z_true = randomZ(9);
  auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, z_true);
  samples[2].valid = false;
  samples[2].readings.setConstant(0.3);  // garbage that must not matter
  ZeroEstimator est(*model_, {});
  const ZeroEstimate r = est.estimate(samples);
  ASSERT_EQ(r.rejected_capture.size(), 1u);
  EXPECT_EQ(r.rejected_capture.front(), 2);
  EXPECT_LT((r.z - z_true).cwiseAbs().maxCoeff(), 1e-4);
}

TEST_F(ZeroEstimatorTest, NonConvergenceIsReported) {
  const auto samples = synthesizeZeroSamples(*model_, *robot_, *protocol_, randomZ(3));
  ZeroEstimatorOptions o;
  o.max_iterations = 4;  // M = 5 consecutive small steps cannot happen in 4 iterations
  o.consecutive = 5;
  ZeroEstimator est(*model_, o);
  const ZeroEstimate r = est.estimate(samples);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 4);
  EXPECT_NE(r.message.find("not converged"), std::string::npos) << r.message;
  // Too few usable poses is an error naming min_poses.
  std::vector<ZeroSample> few(samples.begin(), samples.begin() + 2);
  ZeroEstimator est2(*model_, {});
  try {
    est2.estimate(few);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_poses"), std::string::npos) << e.what();
  }
}

TEST_F(ZeroEstimatorTest, BadOptionsNameTheField) {
  const auto expectField = [&](ZeroEstimatorOptions o, const std::string& field) {
    try {
      ZeroEstimator est(*model_, o);
      FAIL() << "expected an error for " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("ZeroEstimatorOptions." + field), std::string::npos) << e.what();
    }
  };
  ZeroEstimatorOptions o;
  o.tau = 0.0;
  expectField(o, "tau");
  o = {};
  o.alpha = 1.5;
  expectField(o, "alpha");
  o = {};
  o.epsilon = -1e-6;
  expectField(o, "epsilon");
  o = {};
  o.consecutive = 0;
  expectField(o, "consecutive");
  o = {};
  o.max_iterations = 0;
  expectField(o, "max_iterations");
  o = {};
  o.R_BI(0, 0) = 2.0;
  expectField(o, "R_BI");
  EXPECT_THROW(ZeroEstimator(nullptr, {}), std::invalid_argument);
}

TEST_F(ZeroEstimatorTest, BadProtocolNamesFileAndField) {
  const pmg::test::TempDir path_dir;
  const std::string path = path_dir.file("bad_zero_protocol.yaml");
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  move_s: 0.05\n  poses:\n    - {name: a, dp: [0, 0, -0.05]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find(path), std::string::npos) << w;
    EXPECT_NE(w.find("zero_calibration.move_s"), std::string::npos) << w;
    EXPECT_NE(w.find("[0.2, 30]"), std::string::npos) << w;
  }
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  poses:\n    - {name: far, dp: [0, 0.5, 0]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("poses[0] (far).dp"), std::string::npos) << e.what();
  }
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  flatten_feet: maybe\n  poses:\n    - {name: a, dp: [0, 0, -0.05]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("zero_calibration.flatten_feet: expected true or false"), std::string::npos)
        << e.what();
  }
  // A typo is an error naming the file, line, key and the nearest valid key.
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  hold: 2.0\n  poses:\n    - {name: a, dp: [0, 0, -0.05]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":2: unknown key 'hold' in 'zero_calibration' (did you mean 'hold_s'?)");
  }
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  poses:\n    - {name: a, dp: [0, 0, -0.05], rp: [0, 0.1, 0]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              path + ":3: unknown key 'rp' in 'zero_calibration.poses[0]' (did you mean 'rpy'?)");
  }
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  poses:\n    - {name: a, dp: [0, 0, .inf]}\n";
  }
  try {
    loadZeroProtocol(path);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              path + ":3: zero_calibration.poses[0].dp[2]: expected a finite number, got '.inf'");
  }
}

// The switches the SIL acceptance relies on: absent = the conservative defaults, the shipped protocol sets
// both (docs/calibration.md: start from the current stance, plan with the home feet as the model sees them).
TEST_F(ZeroEstimatorTest, ProtocolSwitchesParse) {
  EXPECT_TRUE(protocol_->start_from_current);
  EXPECT_FALSE(protocol_->flatten_feet);
  const pmg::test::TempDir path_dir;
  const std::string path = path_dir.file("zero_protocol_defaults.yaml");
  {
    std::ofstream f(path);
    f << "zero_calibration:\n  poses:\n    - {name: a, dp: [0, 0, -0.05]}\n";
  }
  const ZeroProtocol d = loadZeroProtocol(path);
  EXPECT_FALSE(d.start_from_current);
  EXPECT_TRUE(d.flatten_feet);
}

}  // namespace
}  // namespace pmg::calib
