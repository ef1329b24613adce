// The shipped G1 clip set (config/clips/g1/): loads and validates, stays within joint limits,
// is continuous across the cycle boundary φ = 1 → 0, re-writes byte-identically, has contact labels
// where the played clip's soles are down and do not slide against each other, and symmetric
// posture templates.
#include <algorithm>
#include <cmath>
#include <vector>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {

const std::string kRobot = pmg::test::g1RobotConfigPath();
const std::string kClipDir = pmg::test::g1ClipDir();

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

class ShippedClips : public ::testing::Test {
 protected:
  void SetUp() override { robot_ = pmg::loadRobotConfig(kRobot); }
  pmg::RobotConfig robot_;
};

TEST_F(ShippedClips, LibraryLoadsWithTheFoundationTemplates) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  bool forward = false, yaw_left = false;
  for (const auto& c : lib.dynamic_clips) {
    forward |= c.axis == pmg::CommandAxis::kForward && c.direction == 1;
    yaw_left |= c.axis == pmg::CommandAxis::kYaw && c.direction == 1;
  }
  EXPECT_TRUE(forward) << "walk_forward missing";
  EXPECT_TRUE(yaw_left) << "turn_left missing";
}

TEST_F(ShippedClips, WithinJointLimitsAndPlausible) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  ASSERT_FALSE(lib.dynamic_clips.empty());  // the loop below must check something
  for (const auto& c : lib.dynamic_clips) {
    SCOPED_TRACE(c.name);
    for (Eigen::Index k = 0; k < c.q.rows(); ++k)
      for (std::size_t j = 0; j < robot_.numJoints(); ++j) {
        const auto& jc = robot_.joints[j];
        EXPECT_GE(c.q(k, static_cast<Eigen::Index>(j)), jc.lower - 1e-6) << jc.name << " at sample " << k;
        EXPECT_LE(c.q(k, static_cast<Eigen::Index>(j)), jc.upper + 1e-6) << jc.name << " at sample " << k;
      }
    // A gait cycle of a human-sized motion: 0.4 s < T < 2 s, pelvis at 0.5..0.9 m, each foot in
    // contact for part of the cycle but not never.
    EXPECT_GT(c.period, 0.4);
    EXPECT_LT(c.period, 2.0);
    EXPECT_GT(c.base_height.minCoeff(), 0.5);
    EXPECT_LT(c.base_height.maxCoeff(), 0.9);
    for (const auto& fc : c.contact) EXPECT_GT(fc.sigma, 0.1);
    // The mean realised command equals the declared nominal scale (x̄ is the cycle mean).
    const double mean = c.axis == pmg::CommandAxis::kForward ? c.v_base.col(0).mean()
                        : c.axis == pmg::CommandAxis::kLateral ? c.v_base.col(1).mean()
                                                                : c.omega_base.col(2).mean();
    EXPECT_NEAR(c.direction * mean, c.nominal_scale, 0.1 * c.nominal_scale);
    // A closed cycle returns to the same pelvis height, roll and pitch.
    EXPECT_NEAR(c.v_base.col(2).mean(), 0.0, 1e-5);
    EXPECT_NEAR(c.omega_base.col(0).mean(), 0.0, 1e-5);
    EXPECT_NEAR(c.omega_base.col(1).mean(), 0.0, 1e-5);
  }
}

/// Seam residual of periodic samples x (N rows) at row k: distance of x[k] from the cubic through
/// its two neighbours on each side, (−x[k−2] + 4x[k−1] + 4x[k+1] − x[k+2]) / 6 (max over columns).
/// Smooth data gives O(h⁴) (≈1e-4 rad here); a jump J at row k gives ≈ J.
double seamResidual(const Eigen::MatrixXd& x, Eigen::Index k) {
  const Eigen::Index N = x.rows();
  auto row = [&](Eigen::Index i) { return x.row(((i % N) + N) % N); };
  return (row(k) - (-row(k - 2) + 4.0 * row(k - 1) + 4.0 * row(k + 1) - row(k + 2)) / 6.0).cwiseAbs().maxCoeff();
}

double maxInteriorResidual(const Eigen::MatrixXd& x) {
  double m = 0.0;
  for (Eigen::Index k = 1; k < x.rows(); ++k) m = std::max(m, seamResidual(x, k));
  return m;
}

// Continuity across φ = 1 → 0 (row N−1 → row 0): the position jump is at most 1e-3 rad, and the
// joint and base velocities are no rougher at the seam than anywhere inside the cycle.
TEST_F(ShippedClips, ContinuousAcrossTheCycleBoundary) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  ASSERT_FALSE(lib.dynamic_clips.empty());
  for (const auto& c : lib.dynamic_clips) {
    SCOPED_TRACE(c.name);
    EXPECT_LE(seamResidual(c.q, 0), 1e-3) << "position jump across phi = 1 -> 0 [rad]";
    EXPECT_LE(seamResidual(c.qd, 0), maxInteriorResidual(c.qd) + 1e-6) << "joint velocity step at the seam";
    EXPECT_LE(seamResidual(c.v_base, 0), maxInteriorResidual(c.v_base) + 1e-6) << "base velocity step at the seam";
    EXPECT_LE(seamResidual(c.omega_base, 0), maxInteriorResidual(c.omega_base) + 1e-6) << "base angular velocity step at the seam";
  }
}

// The seam measure does detect a jump: a 0.01 rad step in one joint at φ = 0 is flagged.
TEST_F(ShippedClips, SeamMeasureDetectsAJump) {
  const pmg::DynamicClip c = pmg::readDynamicClip(std::string(kClipDir) + "/walk_forward.yaml", robot_);
  Eigen::MatrixXd q = c.q;
  ASSERT_LE(seamResidual(q, 0), 1e-3);
  for (Eigen::Index k = 0; k < q.rows() / 2; ++k) q(k, 3) += 0.01;  // left knee offset over half the cycle
  EXPECT_GT(seamResidual(q, 0), 4e-3);
}

TEST_F(ShippedClips, RewriteIsByteIdentical) {
  for (const auto& entry : std::filesystem::directory_iterator(kClipDir)) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string path = entry.path().string();
    SCOPED_TRACE(path);
    const std::string text = slurp(path);
    if (pmg::readClipKind(path) == pmg::ClipKind::kDynamic)
      EXPECT_EQ(pmg::clipToYaml(pmg::readDynamicClip(path, robot_)), text);
    else
      EXPECT_EQ(pmg::clipToYaml(pmg::readStaticClip(path, robot_)), text);
  }
}

}  // namespace

// The contact schedule {μ, σ} of every dynamic clip, played as the generator plays it (level
// pelvis), marks soles that are on the ground, and double support only where the two soles do not
// slide against each other (docs/motion.md, "Contact labels of the clips"). With the human labels
// (clips up to commit 484c9a4) the played walk_forward sole touched down 17-30 mm up.
TEST_F(ShippedClips, ContactScheduleMatchesTheRobotSoles) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  const pmg::KinematicModel model(robot_);
  const pmg::motion::RobotContactOptions opt;
  ASSERT_FALSE(lib.dynamic_clips.empty());  // the loop below must check something
  for (const auto& c : lib.dynamic_clips) {
    SCOPED_TRACE(c.name);
    const pmg::motion::ClipSoleTracks t = pmg::motion::clipSoleTracks(c, model);
    const Eigen::Index N = c.q.rows();
    int double_support = 0;
    for (Eigen::Index k = 0; k < N; ++k) {
      const double phi = static_cast<double>(k) / static_cast<double>(N);
      bool in[2];
      for (std::size_t f = 0; f < 2; ++f) {
        const double d = std::abs(phi - c.contact[f].mu), dist = std::min(d, 1.0 - d);
        in[f] = dist < c.contact[f].sigma - 1e-9;
        if (in[f]) {
          EXPECT_LT(t.height(k, static_cast<Eigen::Index>(f)), opt.exit_height) << "foot " << f << " sample " << k;
        }
      }
      if (in[0] && in[1]) {
        ++double_support;
        EXPECT_LT(t.relative_speed(k), opt.exit_relative_speed) << "sample " << k;
      }
    }
    EXPECT_LT(double_support, N / 2);
  }
}

TEST_F(ShippedClips, PostureTemplatesAreLeftRightSymmetric) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  const std::vector<int> mirror = robot_.mirrorIndex();
  ASSERT_FALSE(lib.static_clips.empty());
  for (const auto& s : lib.static_clips) {
    SCOPED_TRACE(s.name);
    for (Eigen::Index i = 0; i < s.q.rows(); ++i)
      for (std::size_t j = 0; j < robot_.numJoints(); ++j) {
        const double mirrored = robot_.joints[j].mirror_sign * s.q(i, mirror[j]);
        EXPECT_NEAR(s.q(i, static_cast<Eigen::Index>(j)), mirrored, 2e-6) << robot_.joints[j].name << " row " << i;
      }
  }
}
