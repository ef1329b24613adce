// Tests of pmg::teleop::ArmIk (include/pmg/teleop/arm_ik.hpp) on the shipped G1 model: setup and
// errors, FK → IK round trips, the FK pose stream, joint limits, workspace clamp, continuity,
// capsule collisions, invalid targets and allocation-free solving.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "arm_ik_streams.hpp"
#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/yaml_archive.hpp"
#include "pmg/teleop/arm_ik.hpp"
#include "temp_dir.hpp"

namespace pmg::teleop {
namespace {

using Q2 = std::array<ArmJoints, 2>;
using R2 = std::array<ArmIkResult, 2>;
using T2 = std::array<ArmPose, 2>;

double rotationError(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

/// The off-line solver: no continuity bound, a large iteration budget (solving "from scratch").
ArmIkOptions globalOptions(int restarts) {
  ArmIkOptions o;
  o.max_joint_step = 10.0;
  o.max_iterations = 300;
  o.max_restarts = restarts;
  o.stop_when_stalled = false;
  return o;
}

class ArmIkTest : public ::testing::Test {
 protected:
  static ArmIk& ik() {
    static ArmIk solver(test::g1Robot());
    return solver;
  }
  static ArmIk& globalIk(int restarts) {
    static ArmIk single(test::g1Robot(), globalOptions(0));
    static ArmIk with_restarts(test::g1Robot(), globalOptions(5));
    return restarts == 0 ? single : with_restarts;
  }
  static Q2 nominal() { return {ik().nominal(0), ik().nominal(1)}; }

  /// True if both hands of q lie inside the workspace shell the IK clamps targets to.
  static bool insideWorkspace(const Q2& q) {
    const double m = ik().options().workspace_margin;
    for (int h = 0; h < 2; ++h) {
      const double r = (ik().forwardKinematics(h, q[h]).position - ik().shoulderPosition(h)).norm();
      if (r > ik().reach(h) * (1.0 - m) || r < ik().minReach(h) * (1.0 + m)) return false;
    }
    return true;
  }
  /// Uniform random configuration of both arms within the limits whose capsules are at least
  /// `clearance` apart (rejection sampling), optionally with both hands inside the workspace shell.
  static Q2 randomFreeConfig(std::mt19937& rng, double clearance, bool in_workspace = false) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (;;) {
      Q2 q;
      for (int h = 0; h < 2; ++h) {
        for (int j = 0; j < kArmDofs; ++j) {
          q[h][j] = ik().lower(h)[j] + (ik().upper(h)[j] - ik().lower(h)[j]) * u(rng);
        }
      }
      if (ik().minCapsuleDistance(q) >= clearance && (!in_workspace || insideWorkspace(q))) return q;
    }
  }
  static void expectWithinLimits(const ArmIk& s, const Q2& q) {
    for (int h = 0; h < 2; ++h) {
      for (int j = 0; j < kArmDofs; ++j) {
        EXPECT_GE(q[h][j], s.lower(h)[j]) << "hand " << h << " joint " << j;
        EXPECT_LE(q[h][j], s.upper(h)[j]) << "hand " << h << " joint " << j;
      }
    }
  }
};

TEST_F(ArmIkTest, SetupMapsBothChainsOntoTheRobotConfig) {
  const RobotConfig& robot = test::g1Robot();
  const std::array<std::string, 2> side{"left_", "right_"};
  const std::array<std::string, kArmDofs> names{"shoulder_pitch_joint", "shoulder_roll_joint", "shoulder_yaw_joint",
                                                "elbow_joint",          "wrist_roll_joint",    "wrist_pitch_joint",
                                                "wrist_yaw_joint"};
  for (int h = 0; h < 2; ++h) {
    for (int j = 0; j < kArmDofs; ++j) {
      const int k = ik().jointIndices(h)[j];
      ASSERT_GE(k, 0);
      EXPECT_EQ(robot.joints[k].name, side[h] + names[j]);
      EXPECT_EQ(ik().nominal(h)[j], robot.joints[k].default_position);
      EXPECT_EQ(ik().lower(h)[j], robot.joints[k].lower);
      EXPECT_EQ(ik().upper(h)[j], robot.joints[k].upper);
    }
    // Shoulder beside the upper torso; the G1 arm is about half a metre long.
    const Eigen::Vector3d s = ik().shoulderPosition(h);
    EXPECT_NEAR(std::abs(s.y()), 0.13, 0.02);
    EXPECT_GT(s.y() * (h == 0 ? 1 : -1), 0.0);
    EXPECT_NEAR(s.z(), 0.255, 0.02);
    EXPECT_GT(ik().reach(h), 0.40);
    EXPECT_LT(ik().reach(h), 0.60);
    EXPECT_GT(ik().minReach(h), 0.05);
    EXPECT_LT(ik().minReach(h), 0.5 * ik().reach(h));
  }
  EXPECT_NEAR(ik().reach(0), ik().reach(1), 1e-3);  // mirrored arms
  // The nominal pose is collision-free.
  EXPECT_GT(ik().minCapsuleDistance(nominal()), 0.0);
}

TEST_F(ArmIkTest, ForwardKinematicsAgreesWithTheRobotKinematicModel) {
  const KinematicModel model(test::g1Robot());
  std::mt19937 rng(3);
  for (int h = 0; h < 2; ++h) {
    const LimbChain limb = model.chain("torso_link", h == 0 ? "left_rubber_hand" : "right_rubber_hand");
    ChainFkWorkspace fk(limb);
    for (int i = 0; i < 20; ++i) {
      const Q2 q = randomFreeConfig(rng, -1.0);
      Eigen::VectorXd full = test::g1Robot().defaultPose();
      for (int j = 0; j < kArmDofs; ++j) full[ik().jointIndices(h)[j]] = q[h][j];
      Eigen::Isometry3d X;
      ASSERT_TRUE(fk.tipPose(full, X));
      const ArmPose p = ik().forwardKinematics(h, q[h]);
      EXPECT_LT((p.position - X.translation()).norm(), 1e-12);
      EXPECT_LT(rotationError(p.orientation, Eigen::Quaterniond(X.linear())), 1e-9);
    }
  }
}

TEST_F(ArmIkTest, JacobianAgreesWithKdlsJacobianSolver) {
  const KinematicModel model(test::g1Robot());
  std::mt19937 rng(4);
  for (int h = 0; h < 2; ++h) {
    const LimbChain limb = model.chain("torso_link", h == 0 ? "left_rubber_hand" : "right_rubber_hand");
    KDL::ChainJntToJacSolver solver(limb.chain);
    KDL::JntArray q_kdl(kArmDofs);
    KDL::Jacobian J_kdl(kArmDofs);
    for (int i = 0; i < 20; ++i) {
      const Q2 q = randomFreeConfig(rng, -1.0);
      for (int j = 0; j < kArmDofs; ++j) q_kdl(j) = q[h][j];
      ASSERT_GE(solver.JntToJac(q_kdl, J_kdl), 0);
      const Eigen::Matrix<double, 6, kArmDofs> J = ik().jacobian(h, q[h]);
      EXPECT_LT((J - J_kdl.data).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
  EXPECT_TRUE(ik().jacobian(0, {std::nan(""), 0, 0, 0, 0, 0, 0}).hasNaN());
}

TEST_F(ArmIkTest, OptionsLoadFromYamlStrictly) {
  test::TempDir dir;
  const ArmIkOptions o = yaml::loadYamlFile<ArmIkOptions>(
      dir.write("ik.yaml", "max_iterations: 12\nmax_joint_step: 0.05\navoid_collisions: false\n"));
  EXPECT_EQ(o.max_iterations, 12);
  EXPECT_EQ(o.max_joint_step, 0.05);
  EXPECT_FALSE(o.avoid_collisions);
  EXPECT_EQ(o.damping, ArmIkOptions{}.damping);
  try {
    (void)yaml::loadYamlFile<ArmIkOptions>(dir.write("typo.yaml", "max_joint_stp: 0.05\n"));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("typo.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_joint_step"), std::string::npos) << e.what();
  }
  try {
    (void)yaml::loadYamlFile<ArmIkOptions>(dir.write("range.yaml", "collision_margin: 0.5\n"));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("collision_margin"), std::string::npos) << e.what();
  }
}

TEST_F(ArmIkTest, MissingHandLinkIsAConfigErrorNamingTheUrdf) {
  test::TempDir dir;
  std::string urdf = test::readTextFile(test::g1UrdfPath());
  for (std::size_t at = urdf.find("right_rubber_hand"); at != std::string::npos; at = urdf.find("right_rubber_hand")) {
    urdf.replace(at, 17, "right_other_glove");
  }
  RobotConfig robot = test::g1Robot();
  robot.urdf_path = dir.write("g1_no_hand.urdf", urdf);
  try {
    ArmIk bad(robot);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("g1_no_hand.urdf"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("right_rubber_hand"), std::string::npos) << e.what();
  }
}

TEST_F(ArmIkTest, InvalidOptionsNameTheField) {
  ArmIkOptions o;
  o.max_joint_step = -1.0;
  EXPECT_NE(o.validate().find("max_joint_step"), std::string::npos);
  EXPECT_THROW(ArmIk(test::g1Robot(), o), std::invalid_argument);
  o = ArmIkOptions{};
  o.collision_activation = o.collision_margin;
  EXPECT_NE(o.validate().find("collision_activation"), std::string::npos);
  o = ArmIkOptions{};
  o.damping = std::nan("");
  EXPECT_NE(o.validate().find("damping"), std::string::npos);
  EXPECT_EQ(ArmIkOptions{}.validate(), "");
}

TEST(SegmentDistance, KnownCases) {
  double s = -1, t = -1;
  // Crossing perpendicular segments 0.3 apart.
  EXPECT_NEAR(segmentSegmentDistance({-1, 0, 0}, {1, 0, 0}, {0, -1, 0.3}, {0, 1, 0.3}, &s, &t), 0.3, 1e-12);
  EXPECT_NEAR(s, 0.5, 1e-12);
  EXPECT_NEAR(t, 0.5, 1e-12);
  // Parallel, overlapping.
  EXPECT_NEAR(segmentSegmentDistance({0, 0, 0}, {1, 0, 0}, {0.5, 0.2, 0}, {2, 0.2, 0}, &s, &t), 0.2, 1e-12);
  // End points closest.
  EXPECT_NEAR(segmentSegmentDistance({0, 0, 0}, {1, 0, 0}, {2, 1, 0}, {3, 1, 0}, &s, &t), std::sqrt(2.0), 1e-12);
  EXPECT_EQ(s, 1.0);
  EXPECT_EQ(t, 0.0);
  // Point against segment, both degenerate.
  EXPECT_NEAR(segmentSegmentDistance({0.5, 1, 0}, {0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, &s, &t), 1.0, 1e-12);
  EXPECT_NEAR(t, 0.5, 1e-12);
  EXPECT_NEAR(segmentSegmentDistance({0, 0, 1}, {0, 0, 1}, {0, 0, 0}, {0, 0, 0}, &s, &t), 1.0, 1e-12);
  // Brute force on random segments.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p0(u(rng), u(rng), u(rng)), p1(u(rng), u(rng), u(rng));
    const Eigen::Vector3d q0(u(rng), u(rng), u(rng)), q1(u(rng), u(rng), u(rng));
    double best = 1e9;
    for (int a = 0; a <= 200; ++a) {
      for (int b = 0; b <= 200; ++b) {
        best = std::min(best, ((p0 + (p1 - p0) * a / 200.0) - (q0 + (q1 - q0) * b / 200.0)).norm());
      }
    }
    const double d = segmentSegmentDistance(p0, p1, q0, q1, &s, &t);
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GT(d, best - 1e-2);
  }
}

/// FK → target → IK round trips. Samples: both arms uniform within the limits, capsules at least
/// collision_margin apart (what the IK keeps), hands inside the workspace shell. Success = position
/// error ≤ 1 mm and orientation error ≤ 0.01 rad. Three solvers:
///   0: from the nominal pose, one descent (300 iterations, no continuity bound);
///   1: the same with up to 5 restarts (ArmIkOptions::max_restarts, off-line use);
///   2: the 100 Hz configuration (defaults: 8 iterations, 0.06 rad per joint) seeded within 0.05 rad
///      of the sampled configuration (the previous tick's solution).
TEST_F(ArmIkTest, RoundTripFromNominalAndFromANearbySeed) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> perturb(-0.05, 0.05);
  constexpr int kSamples = 300;
  const double margin = ik().options().collision_margin;
  std::array<int, 3> ok{};
  std::array<double, 3> iterations_sum{};
  std::array<std::vector<double>, 3> ep_all, eo_all;
  int iterations_nearby_max = 0;
  int arms = 0;
  for (int i = 0; i < kSamples; ++i) {
    const Q2 q_true = randomFreeConfig(rng, margin, true);
    const T2 targets{ik().forwardKinematics(0, q_true[0]), ik().forwardKinematics(1, q_true[1])};
    for (int mode = 0; mode < 3; ++mode) {
      Q2 q = nominal();
      R2 r;
      if (mode < 2) {
        globalIk(mode).solve(targets, {true, true}, q, r);
      } else {
        for (int h = 0; h < 2; ++h) {
          for (int j = 0; j < kArmDofs; ++j) {
            q[h][j] = std::clamp(q_true[h][j] + perturb(rng), ik().lower(h)[j], ik().upper(h)[j]);
          }
        }
        ik().solve(targets, {true, true}, q, r);
      }
      expectWithinLimits(ik(), q);
      for (int h = 0; h < 2; ++h) {
        const ArmPose p = ik().forwardKinematics(h, q[h]);
        const double ep = (p.position - targets[h].position).norm();
        const double eo = rotationError(p.orientation, targets[h].orientation);
        // The result reports the error it achieved, and "converged" means within the tolerances.
        EXPECT_NEAR(r[h].position_error_m, ep, 1e-9);
        EXPECT_NEAR(r[h].orientation_error_rad, eo, 1e-6);
        EXPECT_FALSE(r[h].workspace_clamped);
        const ArmIkOptions& o = mode < 2 ? globalIk(mode).options() : ik().options();
        EXPECT_EQ(r[h].status == ArmIkStatus::kConverged, ep <= o.position_tolerance && eo <= o.orientation_tolerance);
        ok[mode] += ep <= 1e-3 && eo <= 0.01;
        iterations_sum[mode] += r[h].iterations;
        ep_all[mode].push_back(ep);
        eo_all[mode].push_back(eo);
        if (mode == 2) iterations_nearby_max = std::max(iterations_nearby_max, r[h].iterations);
      }
    }
    arms += 2;
  }
  auto quantile = [](std::vector<double> v, double p) {
    const auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  };
  const std::array<const char*, 3> name{"from nominal, one descent", "from nominal, <= 5 restarts",
                                        "100 Hz options, seed within 0.05 rad"};
  for (int mode = 0; mode < 3; ++mode) {
    std::printf(
        "round trip %-38s: %5.1f %% of %d arms within 1 mm / 0.01 rad; median %.2g m %.2g rad, "
        "p95 %.2g m %.2g rad; mean %.1f iterations\n",
        name[mode], 100.0 * ok[mode] / arms, arms, quantile(ep_all[mode], 0.5), quantile(eo_all[mode], 0.5),
        quantile(ep_all[mode], 0.95), quantile(eo_all[mode], 0.95), iterations_sum[mode] / arms);
  }
  std::printf("round trip nearby seed: at most %d of %d iterations\n", iterations_nearby_max,
              ik().options().max_iterations);
  EXPECT_GE(ok[0], 0.70 * arms);  // one local descent from nominal: joint limits leave local minima
  EXPECT_GE(ok[1], 0.95 * arms);
  EXPECT_GE(ok[2], 0.98 * arms);
}

/// The known-answer case: a pose stream generated from the robot's own forward kinematics
/// of a smooth arm trajectory q_a(t) (100 Hz, 20 s), solved at the 100 Hz settings with the previous
/// solution as the seed. The G1 arm has 7 joints for a 6-D pose, so a pose fixes the joints only up
/// to the elbow swivel; the IK resolves it by the null-space pull toward the nominal pose. The known
/// answer is therefore q*(t): the configuration with q_a(t)'s hand pose at which that pull is
/// stationary, found independently (ik_streams::resolveRedundancy: numerical Jacobian, SVD). The IK
/// must reproduce the poses and q*(t); the distance to q_a(t) itself (all along the swivel) is printed.
TEST_F(ArmIkTest, TracksAPoseStreamFromTheRobotsOwnForwardKinematics) {
  ArmIk solver(test::g1Robot());
  constexpr double kDt = 0.01;
  constexpr int kTicks = 2000;
  double ep_max = 0, eo_max = 0, joint_max = 0, joint_sq = 0, raw_max = 0, d_min = 1e9;
  int within = 0, counted = 0;
  Q2 q;
  for (int k = 0; k < kTicks; ++k) {
    const Q2 q_a = ik_streams::smoothArmTrajectory(solver, k * kDt);
    Q2 q_star;
    for (int h = 0; h < 2; ++h) ASSERT_TRUE(ik_streams::resolveRedundancy(solver, h, q_a[h], &q_star[h])) << k;
    if (k == 0) q = q_star;
    d_min = std::min(d_min, solver.minCapsuleDistance(q_a));
    const T2 targets = ik_streams::armPoses(solver, q_a);
    R2 r;
    solver.solve(targets, {true, true}, q, r);
    for (int h = 0; h < 2; ++h) {
      ep_max = std::max(ep_max, r[h].position_error_m);
      eo_max = std::max(eo_max, r[h].orientation_error_rad);
      within += r[h].position_error_m <= 1e-3 && r[h].orientation_error_rad <= 0.01;
      EXPECT_FALSE(r[h].workspace_clamped);
      for (int j = 0; j < kArmDofs; ++j) {
        const double e = std::abs(q[h][j] - q_star[h][j]);
        joint_max = std::max(joint_max, e);
        joint_sq += e * e;
        ++counted;
        raw_max = std::max(raw_max, std::abs(q[h][j] - q_a[h][j]));
      }
    }
  }
  const double joint_rms = std::sqrt(joint_sq / counted);
  std::printf(
      "FK stream (%d ticks, both arms): pose error max %.3g m, %.3g rad (%.1f %% of arm-ticks within 1 mm / "
      "0.01 rad); joints vs the known answer q*: max %.3g rad, RMS %.3g rad; vs the generating trajectory "
      "(differs by the elbow swivel): max %.3g rad; clearance >= %.3f m\n",
      kTicks, ep_max, eo_max, 100.0 * within / (2.0 * kTicks), joint_max, joint_rms, raw_max, d_min);
  EXPECT_GE(d_min, solver.options().collision_margin);  // the stream keeps the IK's margin
  EXPECT_EQ(within, 2 * kTicks);
  EXPECT_LE(ep_max, 1e-3);
  EXPECT_LE(eo_max, 0.01);
  EXPECT_LE(joint_max, 0.02);   // measured 0.011 rad (null-space lag while the swivel moves)
  EXPECT_LE(joint_rms, 0.004);  // measured 0.0019 rad
}

TEST_F(ArmIkTest, FarTargetsAreClampedFlaggedAndNeverLeaveTheJointLimits) {
  ArmIk solver(test::g1Robot());
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  Q2 q = nominal();
  for (int k = 0; k < 300; ++k) {
    T2 targets;
    for (int h = 0; h < 2; ++h) {
      const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      const double dist = k < 100 ? 1.5 : (k < 200 ? 1e3 : 1.05 * solver.reach(h));
      targets[h].position = solver.shoulderPosition(h) + dist * dir;
      targets[h].orientation = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    }
    R2 r;
    solver.solve(targets, {true, true}, q, r);
    expectWithinLimits(solver, q);
    for (int h = 0; h < 2; ++h) {
      EXPECT_EQ(r[h].status, ArmIkStatus::kUnreachableClamped);
      EXPECT_TRUE(r[h].workspace_clamped);
      EXPECT_GT(r[h].clamp_distance_m, 0.0);
      // The clamped target lies on the shell: reach (1 − margin) from the shoulder.
      const double r_out = solver.reach(h) * (1.0 - solver.options().workspace_margin);
      EXPECT_NEAR((targets[h].position - solver.shoulderPosition(h)).norm() - r[h].clamp_distance_m, r_out, 1e-9);
      EXPECT_GE(r[h].min_capsule_distance_m, 0.5 * solver.options().collision_margin - 1e-9);
    }
  }
  // A reachable pose just inside the shell (the arm forward, the elbow as straight as the shell allows,
  // from the robot's FK) is reached from the nominal pose without a singular blow-up and not flagged.
  Q2 goal = nominal();
  for (int h = 0; h < 2; ++h) {
    goal[h][0] = -0.8;
    const double shell = solver.reach(h) * (1.0 - solver.options().workspace_margin);
    for (double elbow = 1.57; elbow > 0.0; elbow -= 0.005) {
      goal[h][3] = elbow;
      if ((solver.forwardKinematics(h, goal[h]).position - solver.shoulderPosition(h)).norm() < shell - 1e-3) break;
    }
  }
  const T2 t2 = ik_streams::armPoses(solver, goal);
  Q2 q2 = nominal();
  R2 r2;
  for (int k = 0; k < 300; ++k) {
    solver.solve(t2, {true, true}, q2, r2);
    expectWithinLimits(solver, q2);
  }
  for (int h = 0; h < 2; ++h) {
    EXPECT_FALSE(r2[h].workspace_clamped);
    EXPECT_EQ(r2[h].status, ArmIkStatus::kConverged) << "hand " << h;
    EXPECT_NEAR(q2[h][3], goal[h][3], 0.02) << "hand " << h;  // the elbow as straight as the goal's
  }
}

TEST_F(ArmIkTest, ATargetJumpGivesABoundedJointStepPerSolve) {
  ArmIk solver(test::g1Robot());
  std::mt19937 rng(11);
  const double step = solver.options().max_joint_step;
  int reached = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Q2 q = nominal();
    const Q2 q_goal = ik_streams::randomReachableConfig(solver, rng, solver.options().collision_margin);
    const T2 targets = ik_streams::armPoses(solver, q_goal);
    R2 r;
    double largest = 0.0;
    int ticks = 0;
    for (; ticks < 300; ++ticks) {
      const Q2 before = q;
      solver.solve(targets, {true, true}, q, r);
      for (int h = 0; h < 2; ++h) {
        for (int j = 0; j < kArmDofs; ++j) largest = std::max(largest, std::abs(q[h][j] - before[h][j]));
      }
      if (r[0].status == ArmIkStatus::kConverged && r[1].status == ArmIkStatus::kConverged) break;
    }
    EXPECT_LE(largest, step + 1e-12);
    EXPECT_GT(largest, 0.5 * step);  // it moves as fast as allowed toward a far target
    reached += ticks < 300;
  }
  // Walking to a far target tick by tick is a local descent: most, not all, get there (see the round
  // trip's "one descent" rate).
  EXPECT_GE(reached, 6);
}

TEST_F(ArmIkTest, TargetsInsideTheTorsoOrAtTheOtherHandStayCollisionFree) {
  ArmIk solver(test::g1Robot());
  const double floor = 0.5 * solver.options().collision_margin;
  // Left hand into the chest, right hand into the belly and then into the head.
  {
    Q2 q = nominal();
    T2 targets = ik_streams::armPoses(solver, q);
    targets[0].position = Eigen::Vector3d(0.02, 0.0, 0.15);
    targets[1].position = Eigen::Vector3d(0.0, 0.0, 0.05);
    bool flagged = false;
    for (int k = 0; k < 300; ++k) {
      if (k == 150) targets[1].position = Eigen::Vector3d(0.0, 0.0, 0.40);
      R2 r;
      solver.solve(targets, {true, true}, q, r);
      ASSERT_GE(solver.minCapsuleDistance(q), floor - 1e-9) << "tick " << k;
      for (int h = 0; h < 2; ++h) EXPECT_GE(r[h].min_capsule_distance_m, floor - 1e-9);
      flagged = flagged || (r[0].collision_limited && r[1].collision_limited);
      expectWithinLimits(solver, q);
    }
    EXPECT_TRUE(flagged);
    // The hands end near the body surface, not far away: the IK still pursues the targets.
    std::array<double, 2> d{};
    solver.minCapsuleDistance(q, &d);
    EXPECT_LT(d[0], solver.options().collision_activation);
    EXPECT_LT(d[1], solver.options().collision_activation);
  }
  // Left hand to where the right hand is (right arm held: inactive), then both hands to one point.
  {
    Q2 q = nominal();
    Q2 q_right_forward = q;
    q_right_forward[1] = {-1.0, -0.1, 0.0, 0.3, 0.0, 0.0, 0.0};  // right hand forward at chest height
    q[1] = q_right_forward[1];
    ASSERT_GT(solver.minCapsuleDistance(q), solver.options().collision_margin);
    T2 targets = ik_streams::armPoses(solver, q);
    targets[0] = solver.forwardKinematics(1, q[1]);
    bool flagged = false;
    for (int k = 0; k < 200; ++k) {
      R2 r;
      const ArmJoints right_before = q[1];
      solver.solve(targets, {true, false}, q, r);
      EXPECT_EQ(q[1], right_before);  // inactive arm unchanged
      EXPECT_EQ(r[1].status, ArmIkStatus::kInactive);
      ASSERT_GE(solver.minCapsuleDistance(q), floor - 1e-9) << "tick " << k;
      flagged = flagged || r[0].collision_limited;
    }
    EXPECT_TRUE(flagged);
    // Both active, both targets the midpoint between the hands.
    const Eigen::Vector3d mid =
        0.5 * (solver.forwardKinematics(0, q[0]).position + solver.forwardKinematics(1, q[1]).position);
    targets[0].position = mid;
    targets[1].position = mid;
    for (int k = 0; k < 200; ++k) {
      R2 r;
      solver.solve(targets, {true, true}, q, r);
      ASSERT_GE(solver.minCapsuleDistance(q), floor - 1e-9) << "tick " << k;
      expectWithinLimits(solver, q);
    }
  }
}

TEST_F(ArmIkTest, InvalidTargetsLeaveQUnchanged) {
  ArmIk solver(test::g1Robot());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::mt19937 rng(5);
  const Q2 q0 = ik_streams::randomReachableConfig(solver, rng, 0.02);
  const T2 good = ik_streams::armPoses(solver, ik_streams::randomReachableConfig(solver, rng, 0.02));
  std::vector<T2> bad;
  for (int h = 0; h < 2; ++h) {
    T2 t = good;
    t[h].position.x() = nan;
    bad.push_back(t);
    t = good;
    t[h].position.z() = inf;
    bad.push_back(t);
    t = good;
    t[h].orientation = Eigen::Quaterniond(nan, 0, 0, 1);
    bad.push_back(t);
    t = good;
    t[h].orientation = Eigen::Quaterniond(2, 0, 0, 0);  // not a unit quaternion
    bad.push_back(t);
    t = good;
    t[h].orientation = Eigen::Quaterniond(0, 0, 0, 0);
    bad.push_back(t);
  }
  for (std::size_t i = 0; i < bad.size(); ++i) {
    const int h = static_cast<int>(i) / 5;
    Q2 q = q0;
    R2 r;
    solver.solve(bad[i], {true, true}, q, r);
    EXPECT_EQ(r[h].status, ArmIkStatus::kInvalidTarget) << "case " << i;
    EXPECT_EQ(q[h], q0[h]) << "case " << i;
    EXPECT_NE(r[1 - h].status, ArmIkStatus::kInvalidTarget) << "case " << i;  // the other arm is solved
  }
  // A slightly non-unit quaternion (within the tolerance) is normalised and accepted.
  {
    T2 t = good;
    t[0].orientation.coeffs() *= 1.01;
    Q2 q = q0;
    R2 r;
    solver.solve(t, {true, true}, q, r);
    EXPECT_NE(r[0].status, ArmIkStatus::kInvalidTarget);
  }
  // A non-finite seed: nominal, flagged.
  {
    Q2 q = q0;
    q[1][3] = nan;
    R2 r;
    solver.solve(good, {true, true}, q, r);
    EXPECT_EQ(r[1].status, ArmIkStatus::kInvalidTarget);
    EXPECT_EQ(q[1], solver.nominal(1));
  }
  // A seed outside the limits comes back inside them (inactive arm: only the clamp).
  {
    Q2 q = q0;
    q[0][0] = 10.0;
    q[1][6] = -10.0;
    R2 r;
    solver.solve(good, {false, false}, q, r);
    EXPECT_EQ(q[0][0], solver.upper(0)[0]);
    EXPECT_EQ(q[1][6], solver.lower(1)[6]);
    EXPECT_EQ(r[0].status, ArmIkStatus::kInactive);
  }
  EXPECT_STREQ(toString(ArmIkStatus::kInvalidTarget), "invalid_target");
}

TEST_F(ArmIkTest, SolveAllocatesNothing) {
  ArmIk solver(test::g1Robot());
  ArmIkOptions restart_options;
  restart_options.max_restarts = 3;
  ArmIk restart_solver(test::g1Robot(), restart_options);
  std::mt19937 rng(9);
  // Inputs prepared outside the guard: smooth stream, jumps, far, inside the torso, NaN.
  std::vector<T2> stream;
  for (int k = 0; k < 100; ++k)
    stream.push_back(ik_streams::armPoses(solver, ik_streams::smoothArmTrajectory(solver, 0.01 * k)));
  for (int k = 0; k < 20; ++k) {
    stream.push_back(ik_streams::armPoses(solver, ik_streams::randomReachableConfig(solver, rng, 0.01)));
  }
  T2 far = stream.front();
  far[0].position = Eigen::Vector3d(5, 5, 5);
  stream.push_back(far);
  T2 inside = stream.front();
  inside[0].position = Eigen::Vector3d(0.02, 0.0, 0.15);
  inside[1].position = Eigen::Vector3d(0.02, 0.0, 0.15);
  for (int k = 0; k < 20; ++k) stream.push_back(inside);
  T2 invalid = stream.front();
  invalid[1].position.x() = std::numeric_limits<double>::quiet_NaN();
  stream.push_back(invalid);
  Q2 q = ik_streams::smoothArmTrajectory(solver, 0.0);
  Q2 q_restart = q;
  R2 r;
  std::array<double, 2> per_hand{};
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (std::size_t k = 0; k < stream.size(); ++k) {
      const T2& t = stream[k];
      solver.solve(t, {true, true}, q, r);
      restart_solver.solve(t, {true, k % 3 != 0}, q_restart, r);
      (void)solver.forwardKinematics(0, q[0]);
      (void)solver.minCapsuleDistance(q, &per_hand);
    }
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace pmg::teleop
