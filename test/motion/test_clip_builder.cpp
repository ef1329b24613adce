// Clip building: contact segmentation on a motion with known contacts, gait-cycle cutting, the
// contact model {μ, σ}, periodic helpers, and mirroring.
#include <cmath>

#include <gtest/gtest.h>

#include "pmg/common/robot_config.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/motion/clip_io.hpp"

namespace {

using namespace pmg;
using namespace pmg::motion;

/// A motion at 100 Hz with a 1 s gait cycle: left foot on the ground for φ ∈ [0, 0.6), right foot
/// for φ ∈ [0.5, 1.1); swing feet rise 5 cm; the base walks forward at 0.4 m/s.
RobotMotion knownContactMotion(const RobotConfig& robot, int frames) {
  RobotMotion m;
  m.fps = 100.0;
  m.q = robot.defaultPose().transpose().replicate(frames, 1);
  m.p_WB.setZero(frames, 3);
  m.R_WB.assign(static_cast<std::size_t>(frames), Eigen::Quaterniond::Identity());
  for (auto& p : m.p_WS) p.setZero(frames, 3);
  for (int k = 0; k < frames; ++k) {
    const double phi = std::fmod(k / m.fps, 1.0);
    m.p_WB(k, 0) = 0.4 * k / m.fps;
    m.p_WB(k, 2) = 0.75;
    m.q(k, 3) = 0.3 + 0.2 * std::sin(2 * M_PI * phi);  // left knee
    const bool left = phi < 0.6, right = phi >= 0.5 || phi < 0.1;
    m.p_WS[0](k, 2) = left ? 0.0 : 0.05 * std::sin(M_PI * (phi - 0.6) / 0.4);
    m.p_WS[1](k, 2) = right ? 0.0 : 0.05 * std::sin(M_PI * (phi - 0.1) / 0.4);
  }
  return m;
}

TEST(ClipBuilder, ContactSegmentationOnKnownContacts) {
  const RobotConfig robot = loadRobotConfig("config/robots/g1/g1.yaml");
  const RobotMotion m = knownContactMotion(robot, 300);
  ContactOptions opt;
  opt.height_threshold = 0.005;
  const ContactSequence c = detectContacts(m, opt);
  // Touchdowns of the left foot at φ = 0 → frames 100 and 200; liftoffs at φ ≈ 0.6.
  const std::vector<int> td = findContactEvents(c, Foot::kLeft, ContactEvent::kTouchdown, 0, 250);
  ASSERT_EQ(td.size(), 2u);
  EXPECT_NEAR(td[0], 100, 1);
  EXPECT_NEAR(td[1], 200, 1);
  const CycleWindow w = findGaitCycle(c, Foot::kLeft, ContactEvent::kTouchdown, 0, 250);
  EXPECT_EQ(w.end - w.begin, 100);
  DynamicClipOptions o;
  o.name = "walk_forward";
  o.num_samples = 50;
  const DynamicClip clip = buildDynamicClip(m, c, w, robot, o);
  EXPECT_NEAR(clip.period, 1.0, 1e-9);
  EXPECT_NEAR(clip.nominal_scale, 0.4, 1e-6);
  EXPECT_EQ(clip.direction, 1);
  // Left contact φ ∈ [0, 0.6): μ ≈ 0.3, σ ≈ 0.3; right φ ∈ [0.5, 1.1): μ ≈ 0.8, σ ≈ 0.3.
  EXPECT_NEAR(clip.contact[0].mu, 0.3, 0.02);
  EXPECT_NEAR(clip.contact[0].sigma, 0.3, 0.02);
  EXPECT_NEAR(clip.contact[1].mu, 0.8, 0.02);
  EXPECT_NEAR(clip.contact[1].sigma, 0.3, 0.02);
  // q̇ of the knee: d/dt 0.2 sin(2πt) = 0.4π cos(2πt), smoothed slightly.
  EXPECT_NEAR(clip.qd.col(3).maxCoeff(), 0.4 * M_PI, 0.1);
  EXPECT_NO_THROW(validateClip(clip, robot, "known"));
}

TEST(ClipBuilder, ContactModelOfCircularRuns) {
  std::vector<bool> f(10, false);
  for (int k : {8, 9, 0, 1}) f[static_cast<std::size_t>(k)] = true;  // wraps around φ = 0
  const FootContact c = contactModel(f);
  EXPECT_NEAR(c.mu, 0.95, 1e-9);
  EXPECT_NEAR(c.sigma, 0.2, 1e-9);
  EXPECT_NEAR(contactModel(std::vector<bool>(10, true)).sigma, 0.5, 1e-12);
  EXPECT_NEAR(contactModel(std::vector<bool>(10, false)).sigma, 0.0, 1e-12);
}

TEST(ClipBuilder, PeriodicHelpers) {
  const int M = 40;
  Eigen::MatrixXd x(M, 1);
  for (int k = 0; k < M; ++k) x(k, 0) = std::sin(2 * M_PI * k / M);
  const Eigen::MatrixXd y = resamplePeriodic(x, 64);
  for (int k = 0; k < 64; ++k) EXPECT_NEAR(y(k, 0), std::sin(2 * M_PI * k / 64.0), 2e-4);
  const Eigen::MatrixXd d = periodicDerivative(y, 2.0);  // period 2 s: d/dt = π cos
  for (int k = 0; k < 64; ++k) EXPECT_NEAR(d(k, 0), M_PI * std::cos(2 * M_PI * k / 64.0), 1e-2);  // O(h²) central difference
  const Eigen::MatrixXd s = circularGaussianSmooth(x, 1.0);
  EXPECT_NEAR(s.mean(), x.mean(), 1e-12);  // smoothing keeps the cycle mean
  EXPECT_LT(s.cwiseAbs().maxCoeff(), 1.0);
}

TEST(ClipBuilder, MirrorSwapsSidesAndIsAnInvolution) {
  const RobotConfig robot = loadRobotConfig("config/robots/g1/g1.yaml");
  const DynamicClip lat = readDynamicClip("config/clips/g1/walk_lateral_left.yaml", robot);
  const DynamicClip m = mirrorClip(lat, robot, "walk_lateral_right");
  EXPECT_EQ(m.direction, -lat.direction);
  EXPECT_EQ(m.meta.provenance, "mocap_mirrored");
  EXPECT_NEAR(m.v_base.col(1).mean(), -lat.v_base.col(1).mean(), 1e-12);
  EXPECT_NEAR(m.contact[0].sigma, lat.contact[1].sigma, 1e-12);
  // Left hip roll of the mirror = −(right hip roll of the source), up to the phase rotation.
  const int l = robot.jointIndex("left_hip_roll_joint"), r = robot.jointIndex("right_hip_roll_joint");
  EXPECT_NEAR(m.q.col(l).mean(), -lat.q.col(r).mean(), 1e-9);
  EXPECT_NO_THROW(validateClip(m, robot, "mirror"));
  const DynamicClip back = mirrorClip(m, robot, lat.name);
  EXPECT_EQ(back.direction, lat.direction);
  // Mirroring twice gives the source back up to a phase rotation: same per-joint means and ranges.
  EXPECT_LT((back.q.colwise().mean() - lat.q.colwise().mean()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((back.q.colwise().maxCoeff() - lat.q.colwise().maxCoeff()).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
