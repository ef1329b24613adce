// The shipped G1 clip set (config/clips/g1/): loads and validates, stays within joint limits,
// is continuous across the cycle boundary φ = 1 → 0, and re-writes byte-identically.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "pmg/common/robot_config.hpp"
#include "pmg/motion/clip_io.hpp"

namespace {

const char* kRobot = "config/robots/g1/g1.yaml";
const char* kClipDir = "config/clips/g1";

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
  }
}

// Continuity across φ = 1 → 0: the stored q̇ must integrate (trapezoid rule over one phase step)
// from the last sample to the first within 1e-3 rad, exactly as between any two neighbours, and
// the velocity step across the boundary must be no larger than the largest interior step.
TEST_F(ShippedClips, ContinuousAcrossTheCycleBoundary) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  ASSERT_FALSE(lib.dynamic_clips.empty());
  for (const auto& c : lib.dynamic_clips) {
    SCOPED_TRACE(c.name);
    const Eigen::Index N = c.q.rows();
    const double h = c.period / static_cast<double>(N);
    auto jump = [&](Eigen::Index a, Eigen::Index b) {
      return ((c.q.row(b) - c.q.row(a)) - 0.5 * h * (c.qd.row(a) + c.qd.row(b))).cwiseAbs().maxCoeff();
    };
    EXPECT_LE(jump(N - 1, 0), 1e-3) << "position jump across phi = 1 -> 0";
    double max_interior_dqd = 0.0;
    for (Eigen::Index k = 0; k + 1 < N; ++k) max_interior_dqd = std::max(max_interior_dqd, (c.qd.row(k + 1) - c.qd.row(k)).cwiseAbs().maxCoeff());
    EXPECT_LE((c.qd.row(0) - c.qd.row(N - 1)).cwiseAbs().maxCoeff(), max_interior_dqd) << "velocity step across the boundary";
    for (int axis = 0; axis < 3; ++axis) {
      double max_interior = 0.0;
      for (Eigen::Index k = 0; k + 1 < N; ++k) max_interior = std::max(max_interior, std::abs(c.v_base(k + 1, axis) - c.v_base(k, axis)));
      EXPECT_LE(std::abs(c.v_base(0, axis) - c.v_base(N - 1, axis)), max_interior + 1e-6) << "v_base axis " << axis;
    }
  }
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
