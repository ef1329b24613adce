// Clip building: contact segmentation on a motion with known contacts, gait-cycle cutting, the
// contact model {μ, σ}, periodic helpers, robot-sole contact labels and the posture templates
// (symmetrised, leg directions kept). Mirror and phase rotation: test/clips/test_clip_transforms.cpp.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/motion/clip_builder.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/clips/clip_transforms.hpp"
#include "pmg/generator/robot_joint_space.hpp"

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
  const RobotConfig& robot = pmg::test::g1Robot();
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

}  // namespace

namespace {

using namespace pmg;
using namespace pmg::motion;

ClipSoleTracks tracksOf(const std::vector<double>& hl, const std::vector<double>& hr, const std::vector<double>& rel) {
  ClipSoleTracks t;
  const auto N = static_cast<Eigen::Index>(hl.size());
  t.height.resize(N, 2);
  t.speed.setZero(N, 2);
  t.relative_speed.resize(N);
  for (Eigen::Index k = 0; k < N; ++k) {
    t.height(k, 0) = hl[static_cast<std::size_t>(k)];
    t.height(k, 1) = hr[static_cast<std::size_t>(k)];
    t.relative_speed(k) = rel[static_cast<std::size_t>(k)];
  }
  return t;
}

std::string labels(const std::vector<bool>& v) {
  std::string s;
  for (bool b : v) s += b ? '1' : '0';
  return s;
}

}  // namespace

TEST(ClipBuilder, RobotContactLabelsFollowTheDocumentedRules) {
  RobotContactOptions opt;  // enter 5 mm, exit 10 mm; relative speed enter 0.2, exit 0.3 m/s
  // Left foot on the ground; the right foot comes down (8 mm: above enter, no touchdown), reaches
  // 2 mm while sliding at 0.5 m/s against the left (no double support), slows to 0.25 (still no
  // touchdown: enter needs < 0.2), then 0.1 (touchdown). Relative speed then grows to 0.35 >= exit:
  // the older stance (left) lifts off although it is still low; back at 4 mm it does not touch down
  // again while it slides at 0.5 m/s against the right foot.
  const std::vector<double> hl{0, 0, 0, 0, 0, 0.004, 0.02, 0.05, 0.02, 0.004};
  const std::vector<double> hr{0.05, 0.008, 0.002, 0.002, 0.0, 0.0, 0.0, 0.0, 0.0, 0.003};
  const std::vector<double> rel{1.0, 0.6, 0.5, 0.25, 0.1, 0.35, 0.9, 1.2, 0.9, 0.5};
  const auto c = robotContactLabels(tracksOf(hl, hr, rel), opt);
  EXPECT_EQ(labels(c[0]), "1111100000");
  EXPECT_EQ(labels(c[1]), "0000111111");
  // Hysteresis on height: a foot in contact stays up to exit_height; a foot in swing needs enter_height.
  const std::vector<double> hl2{0, 0.007, 0.009, 0.011, 0.007, 0.004, 0, 0, 0, 0};
  const std::vector<double> hr2{0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const std::vector<double> rel2(10, 0.0);
  const auto c2 = robotContactLabels(tracksOf(hl2, hr2, rel2), opt);
  EXPECT_EQ(labels(c2[0]), "1110011111");
  EXPECT_EQ(labels(c2[1]), "1111111111");
  // Periodic: rotating the input rotates the labels.
  std::vector<double> hl3(hl), hr3(hr), rel3(rel);
  std::rotate(hl3.begin(), hl3.begin() + 3, hl3.end());
  std::rotate(hr3.begin(), hr3.begin() + 3, hr3.end());
  std::rotate(rel3.begin(), rel3.begin() + 3, rel3.end());
  const auto c3 = robotContactLabels(tracksOf(hl3, hr3, rel3), opt);
  std::string l0 = labels(c[0]);
  std::rotate(l0.begin(), l0.begin() + 3, l0.end());
  EXPECT_EQ(labels(c3[0]), l0);
  // Options are validated with the field named.
  RobotContactOptions bad;
  bad.exit_height = 0.001;
  try {
    robotContactLabels(tracksOf(hl, hr, rel), bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exit_height"), std::string::npos) << e.what();
  }
  ClipSoleTracks mismatched = tracksOf({0, 0}, {0, 0}, {0, 0});
  mismatched.relative_speed.resize(1);
  EXPECT_THROW(robotContactLabels(mismatched, opt), std::invalid_argument);
}

TEST(ClipBuilder, SymmetrizedStaticClipIsMirrorInvariant) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const std::vector<int> mirror = robot.mirrorIndex();
  StaticClip s;
  s.name = "lopsided";
  s.values = Eigen::VectorXd::LinSpaced(3, 0.5, 0.7);
  s.q = Eigen::MatrixXd::Zero(3, static_cast<Eigen::Index>(robot.numJoints()));
  for (Eigen::Index j = 0; j < s.q.cols(); ++j) s.q.col(j) = Eigen::Vector3d(0.1, 0.2, 0.3) * static_cast<double>(j % 7 - 3);
  const StaticClip before = s;
  symmetrizeStaticClip(s, robot);
  double change = 0.0;
  for (Eigen::Index j = 0; j < s.q.cols(); ++j) {
    const double sign = robot.joints[static_cast<std::size_t>(j)].mirror_sign;
    const Eigen::Index m = mirror[static_cast<std::size_t>(j)];
    EXPECT_TRUE(s.q.col(j).isApprox(sign * s.q.col(m), 1e-15) || s.q.col(j).norm() < 1e-15) << robot.joints[static_cast<std::size_t>(j)].name;
    EXPECT_TRUE(s.q.col(j).isApprox(0.5 * (before.q.col(j) + sign * before.q.col(m)), 1e-15) || s.q.col(j).norm() < 1e-15);
    change += (s.q.col(j) - before.q.col(j)).norm();
  }
  EXPECT_GT(change, 0.1);  // the lopsided input did change
  const StaticClip once = s;
  symmetrizeStaticClip(s, robot);  // idempotent
  EXPECT_TRUE(s.q.isApprox(once.q, 1e-15));
  EXPECT_EQ(s.values, before.values);
  StaticClip wrong = before;
  wrong.q.resize(3, 5);
  EXPECT_THROW(symmetrizeStaticClip(wrong, robot), std::invalid_argument);
}

// symmetrizeGaitClip on the shipped forward walk (a single capture whose left and right steps differ):
// afterwards every quantity half a cycle on is the mirror image of the one now, the change is half the
// capture's asymmetry, the mean forward speed is kept, and a second pass changes nothing.
TEST(ClipBuilder, SymmetrizedGaitStepsAlikeOnBothFeet) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const GeneratorJointSpace joints = generatorJointSpace(robot);
  const DynamicClip before = readDynamicClip(pmg::test::g1ClipDir() + "/walk_forward.yaml", robot);
  const Eigen::Index N = before.q.rows(), h = N / 2;
  ASSERT_EQ(N % 2, 0);
  auto half_on = [&](const Eigen::MatrixXd& x) {
    Eigen::MatrixXd y(x.rows(), x.cols());
    for (Eigen::Index k = 0; k < N; ++k) y.row(k) = x.row((k + h) % N);
    return y;
  };
  const Eigen::Vector3d s_v(1.0, -1.0, 1.0), s_w(-1.0, 1.0, -1.0);
  // How far the capture is from symmetric: q(k + h) against M q(k), over all joints and samples.
  const double asym_before = (mirrorJoints(half_on(before.q), joints) - before.q).norm();
  EXPECT_GT(asym_before / std::sqrt(static_cast<double>(before.q.size())), 0.01);  // > 0.01 rad RMS: a real asymmetry
  DynamicClip clip = before;
  symmetrizeGaitClip(clip, robot);
  EXPECT_LT((half_on(clip.q) - mirrorJoints(clip.q, joints)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((half_on(clip.qd) - mirrorJoints(clip.qd, joints)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((half_on(clip.v_base) - clip.v_base * s_v.asDiagonal()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((half_on(clip.omega_base) - clip.omega_base * s_w.asDiagonal()).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd hgt = clip.base_height;
  EXPECT_LT((half_on(hgt) - hgt).cwiseAbs().maxCoeff(), 1e-12);
  // The change is half the asymmetry (the clip moves halfway to its mirror image), not more.
  EXPECT_NEAR((clip.q - before.q).norm(), 0.5 * asym_before, 1e-9);
  EXPECT_NEAR(clip.v_base.col(0).mean(), before.v_base.col(0).mean(), 1e-12);  // nominal speed kept
  EXPECT_NEAR(clip.v_base.col(1).mean(), 0.0, 1e-12);                         // no net side drift
  EXPECT_NEAR(clip.omega_base.col(2).mean(), 0.0, 1e-12);                     // nor turn
  // Contacts: the right foot's interval is the left's, half a cycle on; the width the mean of both.
  EXPECT_NEAR(clip.contact[0].sigma, 0.5 * (before.contact[0].sigma + before.contact[1].sigma), 1e-12);
  EXPECT_NEAR(clip.contact[1].sigma, clip.contact[0].sigma, 1e-12);
  double dmu = clip.contact[1].mu - clip.contact[0].mu;
  dmu -= std::floor(dmu);
  EXPECT_NEAR(dmu, 0.5, 1e-12);
  EXPECT_NEAR(clip.contact[0].mu, 0.5 * (before.contact[0].mu + before.contact[1].mu - 0.5), 1e-9);  // no wrap here
  EXPECT_TRUE(clip.implied.empty());
  const DynamicClip once = clip;
  symmetrizeGaitClip(clip, robot);  // idempotent
  EXPECT_TRUE(clip.q.isApprox(once.q, 1e-14));
  EXPECT_NEAR(clip.contact[0].mu, once.contact[0].mu, 1e-12);
  // Refused: a side-step (not its own mirror image), an odd sample count, a wrong joint count.
  DynamicClip lateral = before;
  lateral.axis = CommandAxis::kLateral;
  EXPECT_THROW(symmetrizeGaitClip(lateral, robot), std::invalid_argument);
  DynamicClip odd = before;
  odd.q.conservativeResize(N - 1, Eigen::NoChange);
  odd.qd.conservativeResize(N - 1, Eigen::NoChange);
  try {
    symmetrizeGaitClip(odd, robot);
    ADD_FAILURE() << "an odd sample count was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("walk_forward"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("even"), std::string::npos) << e.what();
  }
  DynamicClip wrong = before;
  wrong.q.resize(N, 5);
  EXPECT_THROW(symmetrizeGaitClip(wrong, robot), std::invalid_argument);
}

TEST(ClipBuilder, KeepLegDirectionsShortensWithoutTurningTheLegs) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const KinematicModel model(robot);
  const std::vector<std::string> names = robot.jointNames();
  auto idx = [&](const char* j) { return static_cast<Eigen::Index>(std::find(names.begin(), names.end(), j) - names.begin()); };
  StaticClip s;
  s.name = "squat_like";
  s.axis = PostureAxis::kHeight;
  s.values = Eigen::Vector2d(0.6, 0.75);
  s.neutral = 0.75;
  s.q = robot.defaultPose().transpose().replicate(2, 1);
  // Row 0: knees bent and both legs turned forward about the hips (hip pitch −0.3 on top of the
  // knee compensation), as a squat that pushes the hips back.
  for (const char* side : {"left_", "right_"}) {
    s.q(0, idx((std::string(side) + "knee_joint").c_str())) += 0.6;
    s.q(0, idx((std::string(side) + "hip_pitch_joint").c_str())) += -0.3 - 0.3;
    s.q(0, idx((std::string(side) + "ankle_pitch_joint").c_str())) += -0.3;
  }
  const StaticClip before = s;
  keepLegDirections(s, model);
  const LimbChain legs[2] = {model.leftLeg(), model.rightLeg()};
  for (int f = 0; f < 2; ++f) {
    ChainFkWorkspace ws(legs[f]);
    auto angle = [&](const Eigen::RowVectorXd& row) {
      const Eigen::VectorXd q = row.transpose();
      Eigen::Isometry3d X_BH, X_BF;
      EXPECT_TRUE(ws.segmentPose(q, 0, X_BH) && ws.tipPose(q, X_BF));
      const Eigen::Vector3d v = X_BF.translation() - X_BH.translation();
      return std::atan2(-v.x(), -v.z());
    };
    const std::string side = f == 0 ? "left_" : "right_";
    const Eigen::Index hip = idx((side + "hip_pitch_joint").c_str()), ankle = idx((side + "ankle_pitch_joint").c_str()),
                       knee = idx((side + "knee_joint").c_str());
    EXPECT_GT(std::abs(angle(before.q.row(0)) - angle(before.q.row(1))), 0.2);  // the input turned the leg
    EXPECT_NEAR(angle(s.q.row(0)), angle(s.q.row(1)), 1e-9);                     // the output does not
    EXPECT_EQ(s.q(0, knee), before.q(0, knee));                                  // leg length change kept
    EXPECT_NEAR(s.q(0, hip) + s.q(0, ankle), before.q(0, hip) + before.q(0, ankle), 1e-12);  // sole pitch kept
  }
  EXPECT_EQ(s.q.row(1), before.q.row(1));  // the neutral row is the reference
  StaticClip wrong = before;
  wrong.q.resize(2, 3);
  EXPECT_THROW(keepLegDirections(wrong, model), std::invalid_argument);
}

// raiseWalkingHeight on the shipped side-step (its pelvis 24 mm below the standing pose's): both
// soles move down together by the per-sample raise, keeping their place and orientation in the
// pelvis frame; the knees keep their bound and the joints their limits; the raise is smooth in phase.
TEST(ClipBuilder, RaiseWalkingHeightLengthensBothLegsAlikeAndKeepsTheFeetInPlace) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const KinematicModel model(robot);
  const DynamicClip before = readDynamicClip(pmg::test::g1ClipDir() + "/walk_lateral_left.yaml", robot);
  DynamicClip clip = before;
  WalkingHeightOptions opt;
  opt.min_knee = 0.05;
  const WalkingHeightReport rep = raiseWalkingHeight(clip, model, robot.defaultPose(), opt);
  EXPECT_GT(rep.standing_height - rep.mean_height_before, 0.015);  // the capture walks low
  EXPECT_NEAR(rep.target_raise, rep.standing_height - rep.mean_height_before, 1e-12);
  EXPECT_GT(rep.mean_height_after - rep.mean_height_before, 0.008);
  EXPECT_LE(rep.mean_height_after, rep.standing_height + 1e-9);

  const std::vector<std::string> names = robot.jointNames();
  auto idx = [&](const std::string& j) { return static_cast<Eigen::Index>(std::find(names.begin(), names.end(), j) - names.begin()); };
  Eigen::Vector3d p_FS = Eigen::Vector3d::Zero();
  for (const auto& s : g1SolePoints_F()) p_FS += 0.25 * s;
  const LimbChain legs[2] = {model.leftLeg(), model.rightLeg()};
  ChainFkWorkspace ws[2] = {ChainFkWorkspace(legs[0]), ChainFkWorkspace(legs[1])};
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  const Eigen::Index N = clip.q.rows();
  Eigen::VectorXd d(N);
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::VectorXd q0 = before.q.row(k).transpose(), q1 = clip.q.row(k).transpose();
    double dz[2];
    for (int f = 0; f < 2; ++f) {
      Eigen::Isometry3d X0, X1;
      ASSERT_TRUE(ws[f].tipPose(q0, X0) && ws[f].tipPose(q1, X1));
      const Eigen::Vector3d p0 = X0 * p_FS, p1 = X1 * p_FS;
      EXPECT_NEAR(p1.x(), p0.x(), 1e-6) << "sample " << k;  // the sole keeps its place
      EXPECT_NEAR(p1.y(), p0.y(), 1e-6) << "sample " << k;
      EXPECT_TRUE(X1.linear().isApprox(X0.linear(), 1e-6)) << "sample " << k;  // and its orientation
      dz[f] = p0.z() - p1.z();
      const std::string side = f == 0 ? "left_" : "right_";
      const Eigen::Index knee = idx(side + "knee_joint");
      EXPECT_GE(q1(knee), std::min(opt.min_knee, q0(knee)) - 1e-9) << "sample " << k;
      for (const std::string j : {"hip_pitch_joint", "hip_roll_joint", "hip_yaw_joint", "knee_joint", "ankle_pitch_joint", "ankle_roll_joint"}) {
        EXPECT_GE(q1(idx(side + j)), lower(idx(side + j)));
        EXPECT_LE(q1(idx(side + j)), upper(idx(side + j)));
      }
    }
    EXPECT_NEAR(dz[0], dz[1], 1e-6) << "sample " << k;  // relative sole heights (contacts) unchanged
    d(k) = dz[0];
    EXPECT_GE(d(k), -1e-9);
    EXPECT_LE(d(k), rep.target_raise + 1e-9);
    EXPECT_NEAR(clip.base_height(k) - before.base_height(k), d(k), 1e-6);
    // Only the legs change.
    for (Eigen::Index j = 0; j < q0.size(); ++j) {
      const std::string& n = names[static_cast<std::size_t>(j)];
      if (n.find("hip_") == std::string::npos && n.find("knee") == std::string::npos && n.find("ankle_") == std::string::npos) {
        EXPECT_EQ(q1(j), q0(j)) << n;
      }
    }
  }
  EXPECT_NEAR(d.minCoeff(), rep.min_raise, 1e-6);
  // Smooth in phase: unsmoothed, the knee-limited raise jumps by up to 6 mm from one sample to the next.
  for (Eigen::Index k = 0; k < N; ++k) EXPECT_LT(std::abs(d((k + 1) % N) - d(k)), 0.004) << "sample " << k;
  EXPECT_TRUE(clip.qd.isApprox(periodicDerivative(clip.q, clip.period)));
  EXPECT_EQ(clip.contact[0].mu, before.contact[0].mu);

  DynamicClip same = before;
  WalkingHeightOptions off;
  off.fraction = 0.0;
  raiseWalkingHeight(same, model, robot.defaultPose(), off);
  EXPECT_EQ(same.q, before.q);
  for (auto bad : {WalkingHeightOptions{1.5, 0.15, 2.0}, WalkingHeightOptions{1.0, -0.1, 2.0}, WalkingHeightOptions{1.0, 0.15, 11.0}}) {
    DynamicClip c = before;
    EXPECT_THROW(raiseWalkingHeight(c, model, robot.defaultPose(), bad), std::invalid_argument);
  }
  DynamicClip c = before;
  EXPECT_THROW(raiseWalkingHeight(c, model, Eigen::VectorXd::Zero(3), opt), std::invalid_argument);
}

// Cycle closing in swing (CycleClosing::kInSwing): a one-shot motion whose last stance differs from
// its first. A leg joint that drifts is corrected only while its foot is in swing, so the closed
// clip moves that joint exactly as the capture did during the foot's stances (no sliding added in
// double support); other joints keep the linear ramp; both close (row M ≡ row 0).
TEST(ClipBuilder, ClosingInSwingCorrectsALegOnlyWhileItsFootIsUp) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const KinematicModel model(robot);
  const int M = 40;
  RobotMotion m;
  m.fps = 40.0;
  m.q = robot.defaultPose().transpose().replicate(M + 1, 1);
  m.p_WB.setZero(M + 1, 3);
  m.p_WB.col(2).setConstant(0.75);
  m.R_WB.resize(M + 1);
  ContactSequence c(static_cast<std::size_t>(M + 1), {true, true});
  const Eigen::Index hip_yaw = robot.jointIndex("left_hip_yaw_joint"), waist = robot.jointIndex("waist_yaw_joint");
  for (int k = 0; k <= M; ++k) {
    // Turning left, slowing down: the yaw rate drifts too (closed in single support only).
    m.R_WB[static_cast<std::size_t>(k)] = Eigen::Quaterniond(Eigen::AngleAxisd(0.04 * k - 0.0002 * k * k, Eigen::Vector3d::UnitZ()));
    m.q(k, hip_yaw) = 0.002 * k;  // drifts 0.08 rad over the cycle, in stance and in swing
    m.q(k, waist) = 0.001 * k;
    c[static_cast<std::size_t>(k)][0] = !(k >= 10 && k < 20);  // left swing [10, 20)
    c[static_cast<std::size_t>(k)][1] = !(k >= 25 && k < 35);  // right swing [25, 35)
  }
  DynamicClipOptions o;
  o.name = "turn_like";
  o.axis = CommandAxis::kYaw;
  o.num_samples = M;  // resampling at the source samples: the identity
  o.smoothing_sigma = 0.0;
  o.align_on_left_touchdown = false;
  o.closing = CycleClosing::kInSwing;
  o.leg_joints = {model.leftLeg().joint_index, model.rightLeg().joint_index};
  const DynamicClip clip = buildDynamicClip(m, c, CycleWindow{0, M}, robot, o);
  const double yaw_rate_step = -0.0004 * m.fps;  // [rad/s per sample] of the captured ω_z
  for (int k = 0; k + 1 < M; ++k) {
    const double step = clip.q(k + 1, hip_yaw) - clip.q(k, hip_yaw);
    if (k + 1 < 10 || k >= 20) {
      EXPECT_NEAR(step, 0.002, 1e-12) << "left stance, sample " << k;  // as captured
    }
    EXPECT_NEAR(clip.q(k + 1, waist) - clip.q(k, waist), 0.001 - 0.04 / M, 1e-12);               // linear ramp
    const bool double_support = k < 10 || (k >= 20 && k < 25) || k >= 35;
    if (double_support && k > 0) {  // (sample 0's rate is a one-sided difference)
      EXPECT_NEAR(clip.omega_base(k + 1, 2) - clip.omega_base(k, 2), yaw_rate_step, 1e-9) << "double support, sample " << k;
    }
  }
  // Closed: the step across the seam (row M−1 → row 0) continues the motion.
  EXPECT_NEAR(clip.q(0, hip_yaw) - clip.q(M - 1, hip_yaw), 0.002, 1e-12);  // the seam lies in the left stance
  EXPECT_NEAR(clip.q(0, waist) - clip.q(M - 1, waist), 0.001 - 0.04 / M, 1e-12);
  // The linear ramp would have moved the hip yaw in stance too.
  o.closing = CycleClosing::kLinearRamp;
  const DynamicClip linear = buildDynamicClip(m, c, CycleWindow{0, M}, robot, o);
  EXPECT_NEAR(linear.q(5, hip_yaw) - linear.q(4, hip_yaw), 0.0, 1e-12);
  // Options: both legs named, no joint in both.
  o.closing = CycleClosing::kInSwing;
  o.leg_joints[1].clear();
  EXPECT_THROW(buildDynamicClip(m, c, CycleWindow{0, M}, robot, o), std::invalid_argument);
  o.leg_joints[1] = o.leg_joints[0];
  EXPECT_THROW(buildDynamicClip(m, c, CycleWindow{0, M}, robot, o), std::invalid_argument);
}
