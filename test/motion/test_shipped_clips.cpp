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
#include "pmg/motion/posture_synthesis.hpp"
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
    if (entry.path().filename() == pmg::kConsistencyMapFile) {  // not a clip (its header comment is not kept)
      EXPECT_FALSE(pmg::readConsistencyMap(path).empty());
      continue;
    }
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

// Pitch and height templates move both sides alike (each row is its own mirror image); the roll
// template leans the other way under the mirror (row of −ρ = mirror of row of +ρ).
TEST_F(ShippedClips, PostureTemplatesAreLeftRightSymmetric) {
  const pmg::ClipLibrary lib = pmg::loadClipLibrary(std::string(kClipDir), robot_);
  const std::vector<int> mirror = robot_.mirrorIndex();
  ASSERT_FALSE(lib.static_clips.empty());
  for (const auto& s : lib.static_clips) {
    SCOPED_TRACE(s.name);
    const Eigen::Index K = s.q.rows();
    for (Eigen::Index i = 0; i < K; ++i) {
      const Eigen::Index m = s.axis == pmg::PostureAxis::kRoll ? K - 1 - i : i;  // the mirrored row
      if (s.axis == pmg::PostureAxis::kRoll) {
        ASSERT_NEAR(s.values(m), -s.values(i), 1e-5) << "roll values are not symmetric about 0";
      }
      for (std::size_t j = 0; j < robot_.numJoints(); ++j) {
        const double mirrored = robot_.joints[j].mirror_sign * s.q(m, mirror[j]);
        EXPECT_NEAR(s.q(i, static_cast<Eigen::Index>(j)), mirrored, 2e-6) << robot_.joints[j].name << " row " << i;
      }
    }
  }
}

// The lean (roll) template, measured on the robot with both feet flat: torso_link roll rises
// monotonically through the values, equals them, and covers the envelope (±0.2 rad); the soles stay
// planted (sole-to-sole vector constant, both flat) and the centre of mass stays over the same point
// of the feet; torso pitch and pelvis height do not change.
TEST_F(ShippedClips, LeanRollsTheTorsoWithTheFeetPlanted) {
  const pmg::StaticClip lean = pmg::readStaticClip(pmg::test::g1ClipPath("lean"), robot_);
  ASSERT_EQ(lean.axis, pmg::PostureAxis::kRoll);
  EXPECT_LE(lean.values(0), -0.2);
  EXPECT_GE(lean.values(lean.values.size() - 1), 0.2);
  EXPECT_DOUBLE_EQ(lean.neutral, 0.0);
  const pmg::KinematicModel model(robot_);
  pmg::motion::PostureProbe probe(model);
  Eigen::Index neutral_row = 0;
  lean.values.cwiseAbs().minCoeff(&neutral_row);
  const pmg::motion::FlatFootPosture n = probe.measure(lean.q.row(neutral_row).transpose());
  const Eigen::Vector3d feet0 = n.p_WS[0] - n.p_WS[1];
  const Eigen::Vector2d com0 = (n.p_WC - 0.5 * (n.p_WS[0] + n.p_WS[1])).head<2>();
  double previous = -1e9;
  for (Eigen::Index i = 0; i < lean.q.rows(); ++i) {
    SCOPED_TRACE("row " + std::to_string(i));
    const pmg::motion::FlatFootPosture m = probe.measure(lean.q.row(i).transpose());
    EXPECT_GT(m.torso_roll, previous + 0.01);
    previous = m.torso_roll;
    EXPECT_NEAR(m.torso_roll, lean.values(i), 1e-3);
    EXPECT_LT(m.foot_tilt, 1e-3);
    EXPECT_LT((m.p_WS[0] - m.p_WS[1] - feet0).norm(), 0.003) << "the soles moved against each other";
    EXPECT_LT(((m.p_WC - 0.5 * (m.p_WS[0] + m.p_WS[1])).head<2>() - com0).norm(), 0.003) << "centre of mass moved over the feet";
    EXPECT_NEAR(m.torso_pitch, n.torso_pitch, 0.01);
    EXPECT_NEAR(m.pelvis_height, n.pelvis_height, 0.005);
    EXPECT_GT(m.com_margin, 0.02);
  }
}

// The height template does not couple pitch: with the feet flat, torso_link pitch stays within
// 0.03 rad of the neutral row's over the whole range (was up to 0.44 rad: the captured squat leans
// the trunk forward), and the robot stays statically balanced.
TEST_F(ShippedClips, SquatKeepsTheTorsoPitch) {
  const pmg::StaticClip squat = pmg::readStaticClip(pmg::test::g1ClipPath("squat"), robot_);
  ASSERT_EQ(squat.axis, pmg::PostureAxis::kHeight);
  const pmg::KinematicModel model(robot_);
  pmg::motion::PostureProbe probe(model);
  Eigen::Index neutral_row = 0;
  (squat.values.array() - squat.neutral).abs().minCoeff(&neutral_row);
  const double pitch0 = probe.measure(squat.q.row(neutral_row).transpose()).torso_pitch;
  EXPECT_LE(squat.values(0), 0.62) << "the squat must reach the envelope's lowest height";
  for (Eigen::Index i = 0; i < squat.q.rows(); ++i) {
    SCOPED_TRACE("value " + std::to_string(squat.values(i)));
    const pmg::motion::FlatFootPosture m = probe.measure(squat.q.row(i).transpose());
    EXPECT_NEAR(m.torso_pitch, pitch0, 0.03);
    EXPECT_NEAR(m.torso_roll, 0.0, 1e-6);
    EXPECT_GT(m.com_margin, 0.0) << "centre of mass outside the support polygon";
    EXPECT_NEAR(m.pelvis_height, squat.values(i), 0.015);
  }
}

// The turn template is a slow turn in place to the left: one closed cycle (sample N ≡ sample 0, the
// seam test above checks every clip), a real left turn of about a quarter turn per cycle at about
// 1 rad/s, little translation, and each foot takes exactly one step.
TEST_F(ShippedClips, TurnLeftIsAClosedTurnInPlace) {
  const pmg::DynamicClip turn = pmg::readDynamicClip(pmg::test::g1ClipPath("turn_left"), robot_);
  ASSERT_EQ(turn.axis, pmg::CommandAxis::kYaw);
  EXPECT_EQ(turn.direction, 1);
  EXPECT_GT(turn.omega_base.col(2).mean(), 0.0) << "turns left (counter-clockwise)";
  EXPECT_NEAR(turn.nominal_scale, 1.0, 0.2);                          // [rad/s]
  EXPECT_NEAR(turn.nominal_scale * turn.period, 1.6, 0.3);            // yaw per cycle [rad] (CMU 69_17: 93 deg)
  EXPECT_LT(turn.v_base.leftCols(2).colwise().mean().norm(), 0.1);   // in place [m/s]
  EXPECT_LE(seamResidual(turn.q, 0), 1e-3);
  EXPECT_LE(seamResidual(turn.v_base, 0), maxInteriorResidual(turn.v_base) + 1e-6);
  // One step per foot: one contact run each that is not the whole cycle.
  const pmg::KinematicModel model(robot_);
  const auto labels = pmg::motion::robotContactLabels(pmg::motion::clipSoleTracks(turn, model), pmg::motion::RobotContactOptions{});
  for (std::size_t f = 0; f < 2; ++f) {
    int liftoffs = 0;
    const std::size_t N = labels[f].size();
    for (std::size_t k = 0; k < N; ++k) liftoffs += labels[f][k] && !labels[f][(k + 1) % N];
    EXPECT_EQ(liftoffs, 1) << "foot " << f;
  }
}
