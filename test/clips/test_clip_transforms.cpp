// Clip transforms (src/clips/clip_transforms.cpp): the mirror map agrees with the G1's URDF
// geometry, mirroring and time reversal follow their documented rules and keep φ = 0 at the left
// touchdown, phase rotation keeps the motion, and the generator derives exactly the clip that
// pmg_make_clips shipped (one mirror rule).
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/clips/clip_transforms.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace {

using namespace pmg;

/// Start of the left foot's contact interval, wrapped to (−0.5, 0.5].
double leftTouchdown(const DynamicClip& c) {
  const double start = c.contact[0].mu - c.contact[0].sigma;
  return start - std::round(start);
}

// The mirror map (mirror, mirror_sign of the robot config) is the reflection of the robot in its
// sagittal plane: for any q, the right foot and hand with M q are the mirror images (y → −y) of
// the left ones with q, in position and orientation. This checks every leg, waist and arm joint's
// sign against the URDF's joint axes.
TEST(ClipTransforms, MirrorMapIsTheSagittalReflectionOfTheUrdf) {
  const RobotConfig& robot = test::g1Robot();
  const GeneratorJointSpace js = generatorJointSpace(robot);
  const KinematicModel model(robot);
  const Eigen::Matrix3d S = Eigen::Vector3d(1, -1, 1).asDiagonal();
  std::mt19937 rng(7);
  for (const auto& [left_tip, right_tip] :
       {std::pair<std::string, std::string>{"left_ankle_roll_link", "right_ankle_roll_link"},
        std::pair<std::string, std::string>{"left_wrist_yaw_link", "right_wrist_yaw_link"}}) {
    const LimbChain left = model.chain(robot.base_link, left_tip), right = model.chain(robot.base_link, right_tip);
    ChainFkWorkspace fk_left(left), fk_right(right);
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd q(static_cast<Eigen::Index>(robot.numJoints()));
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      for (Eigen::Index j = 0; j < q.size(); ++j) q[j] = u(rng);
      const Eigen::VectorXd qm = mirrorJoints(q.transpose(), js).transpose();
      Eigen::Isometry3d X_l, X_r;
      ASSERT_TRUE(fk_left.tipPose(q, X_l));
      ASSERT_TRUE(fk_right.tipPose(qm, X_r));
      // 0.1 mm: the exported URDF's left and right link origins differ by up to 1e-5 m (rounding);
      // a wrong sign moves the tip by centimetres to decimetres.
      EXPECT_LT((X_r.translation() - S * X_l.translation()).norm(), 1e-4) << left_tip << " trial " << trial;
      EXPECT_LT((X_r.linear() - S * X_l.linear() * S).norm(), 1e-9) << left_tip << " trial " << trial;
    }
  }
}

TEST(ClipTransforms, MirrorSwapsSidesAndIsAnInvolution) {
  const RobotConfig& robot = test::g1Robot();
  const DynamicClip lat = readDynamicClip(test::g1ClipPath("walk_lateral_left"), robot);
  const DynamicClip m = mirrorClip(lat, robot, "walk_lateral_right");
  EXPECT_EQ(m.name, "walk_lateral_right");
  EXPECT_EQ(m.direction, -lat.direction);
  EXPECT_EQ(m.meta.provenance, "mocap_mirrored");
  EXPECT_NEAR(m.v_base.col(1).mean(), -lat.v_base.col(1).mean(), 1e-12);
  EXPECT_NEAR(m.omega_base.col(2).mean(), -lat.omega_base.col(2).mean(), 1e-12);
  EXPECT_NEAR(m.omega_base.col(1).mean(), lat.omega_base.col(1).mean(), 1e-12);  // pitch rate kept
  EXPECT_DOUBLE_EQ(m.contact[0].sigma, lat.contact[1].sigma);  // feet swapped
  EXPECT_DOUBLE_EQ(m.contact[1].sigma, lat.contact[0].sigma);
  EXPECT_LE(std::fabs(leftTouchdown(m)), 0.5 / static_cast<double>(m.numSamples()) + 1e-12);
  // Left knee of the mirror = right knee of the original, at the rotated phase.
  const int lk = robot.jointIndex("left_knee_joint"), rk = robot.jointIndex("right_knee_joint");
  const Eigen::Index N = lat.q.rows();
  const double start = lat.contact[1].mu - lat.contact[1].sigma;
  const Eigen::Index shift = std::lround((start - std::floor(start)) * static_cast<double>(N)) % N;
  const int lr = robot.jointIndex("left_hip_roll_joint"), rr = robot.jointIndex("right_hip_roll_joint");
  for (Eigen::Index k = 0; k < N; ++k) {
    EXPECT_DOUBLE_EQ(m.q(k, lk), lat.q((k + shift) % N, rk));
    EXPECT_DOUBLE_EQ(m.q(k, lr), -lat.q((k + shift) % N, rr));  // roll changes sign
  }
  EXPECT_NO_THROW(validateClip(m, robot, "mirror"));
  // Mirroring twice gives the clip back (for a clip aligned on its left touchdown, contacts away from
  // half-sample ties: the shipped clips' contact intervals start half-way between samples).
  DynamicClip aligned = lat;
  aligned.contact = {FootContact{0.25, 0.25}, FootContact{0.75, 0.2}};
  const DynamicClip back = mirrorClip(mirrorClip(aligned, robot, "m"), robot, lat.name);
  EXPECT_EQ(back.direction, lat.direction);
  EXPECT_LT((back.q - lat.q).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((back.v_base - lat.v_base).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((back.omega_base - lat.omega_base).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(back.contact[0].mu, 0.25, 1e-12);
  EXPECT_NEAR(back.contact[1].sigma, 0.2, 1e-12);
  // A forward clip mirrored still walks forward; a synthesized clip stays declared as synthesized.
  DynamicClip fwd = readDynamicClip(test::g1ClipPath("walk_forward"), robot);
  fwd.meta.provenance = "synthesized";
  const DynamicClip fm = mirrorClip(fwd, robot, "walk_forward_mirrored");
  EXPECT_EQ(fm.direction, fwd.direction);
  EXPECT_EQ(fm.meta.provenance, "synthesized");
  DynamicClip wrong = lat;
  wrong.q.conservativeResize(Eigen::NoChange, 5);
  EXPECT_THROW(mirrorClip(wrong, robot, "x"), std::invalid_argument);
}

TEST(ClipTransforms, TimeReversalPlaysTheClipBackwardsFromTheLeftTouchdown) {
  const RobotConfig& robot = test::g1Robot();
  const DynamicClip fwd = readDynamicClip(test::g1ClipPath("walk_forward"), robot);
  const DynamicClip r = timeReverseClip(fwd, "walk_forward_reversed");
  const Eigen::Index N = fwd.q.rows();
  EXPECT_EQ(r.name, "walk_forward_reversed");
  EXPECT_EQ(r.direction, -fwd.direction);
  EXPECT_EQ(r.meta.provenance, "mocap_time_reversed");
  EXPECT_LE(std::fabs(leftTouchdown(r)), 0.5 / static_cast<double>(N) + 1e-12);
  // Reversed, the left foot's contact ends where it started: (1 − μ) − σ, rounded to a sample.
  const double start = (1.0 - fwd.contact[0].mu) - fwd.contact[0].sigma;
  const Eigen::Index shift = std::lround((start - std::floor(start)) * static_cast<double>(N)) % N;
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::Index src = (N - (k + shift) % N) % N;  // q'(φ) = q(1 − φ − shift / N)
    EXPECT_EQ(r.q.row(k), fwd.q.row(src)) << k;
    EXPECT_EQ(r.qd.row(k), -fwd.qd.row(src)) << k;
    EXPECT_EQ(r.v_base.row(k), -fwd.v_base.row(src)) << k;
    EXPECT_EQ(r.omega_base.row(k), -fwd.omega_base.row(src)) << k;
    EXPECT_EQ(r.base_height[k], fwd.base_height[src]) << k;
  }
  for (std::size_t f = 0; f < kNumFeet; ++f) EXPECT_DOUBLE_EQ(r.contact[f].sigma, fwd.contact[f].sigma);
  EXPECT_NEAR(r.v_base.col(0).mean(), -fwd.v_base.col(0).mean(), 1e-12);  // walks backward
}

TEST(ClipTransforms, RotateClipPhaseKeepsTheMotion) {
  const RobotConfig& robot = test::g1Robot();
  const DynamicClip c = readDynamicClip(test::g1ClipPath("walk_forward"), robot);
  DynamicClip r = c;
  const Eigen::Index N = c.q.rows();
  rotateClipPhase(r, 5);
  EXPECT_EQ(r.q.row(0), c.q.row(5));
  EXPECT_EQ(r.qd.row(N - 1), c.qd.row(4));
  EXPECT_EQ(r.base_height(0), c.base_height(5));
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    double expected = c.contact[f].mu - 5.0 / static_cast<double>(N);
    expected -= std::floor(expected);
    EXPECT_NEAR(r.contact[f].mu, expected, 1e-12);
    EXPECT_DOUBLE_EQ(r.contact[f].sigma, c.contact[f].sigma);
  }
  rotateClipPhase(r, N - 5);  // back to the original
  EXPECT_EQ(r.q, c.q);
  rotateClipPhase(r, -3);  // negative shifts wrap
  EXPECT_EQ(r.q.row(3), c.q.row(0));
  // Aligning an aligned clip changes nothing.
  DynamicClip a = c;
  EXPECT_EQ(alignPhaseOnLeftTouchdown(a), 0);
  EXPECT_EQ(a.q, c.q);
}

/// Largest difference between the samples of two clips, @p b rotated by @p shift samples.
double maxDifference(const DynamicClip& a, DynamicClip b, Eigen::Index shift) {
  rotateClipPhase(b, shift);
  double d = 0.0;
  for (const auto& [x, y] : {std::pair{&a.q, &b.q}, std::pair{&a.qd, &b.qd}, std::pair{&a.v_base, &b.v_base},
                             std::pair{&a.omega_base, &b.omega_base}})
    d = std::max(d, (*x - *y).cwiseAbs().maxCoeff());
  for (std::size_t f = 0; f < kNumFeet; ++f)
    d = std::max({d, std::fabs(a.contact[f].mu - b.contact[f].mu), std::fabs(a.contact[f].sigma - b.contact[f].sigma)});
  return d;
}

// One mirror rule: a generator whose library lacks walk_lateral_right and turn_right derives them
// with the rule that made the shipped files, so it plays the shipped clips (to the 1e-6 text
// rounding). The one latitude: the shipped contact intervals start half-way between two samples,
// and the 6-decimal rounding of μ and σ may tip the rounding of that half sample, i.e. the derived
// clip may start one sample earlier or later than the file.
TEST(ClipTransforms, GeneratorDerivesTheShippedMirroredClips) {
  const RobotConfig& robot = test::g1Robot();
  const ClipLibrary shipped = loadClipLibrary(test::g1ClipDir(), robot);
  ClipLibrary lib = shipped;
  lib.dynamic_clips.clear();
  for (const DynamicClip& c : shipped.dynamic_clips)
    if (c.name != "walk_lateral_right" && c.name != "turn_right") lib.dynamic_clips.push_back(c);
  ASSERT_EQ(lib.dynamic_clips.size(), shipped.dynamic_clips.size() - 2);
  const GeneratorModel model(lib, generatorJointSpace(robot));
  for (const char* name : {"walk_lateral_right", "turn_right"}) {
    SCOPED_TRACE(name);
    const DynamicClip file = readDynamicClip(test::g1ClipPath(name), robot);
    const DynamicClip* derived = model.dynamicClip(file.axis, file.direction);
    ASSERT_NE(derived, nullptr);
    EXPECT_EQ(derived->meta.provenance, "mocap_mirrored");
    EXPECT_EQ(derived->name.find("_mirrored"), derived->name.size() - 9);
    const Eigen::Index N = file.q.rows();
    double best = maxDifference(*derived, file, 0);
    for (const Eigen::Index shift : {Eigen::Index{1}, N - 1}) best = std::min(best, maxDifference(*derived, file, shift));
    EXPECT_LT(best, 1.5e-6);
    // The generator's former rule (mirror without the phase alignment) is far from the shipped clip.
    const DynamicClip* source = model.dynamicClip(file.axis, -file.direction);
    const Eigen::MatrixXd unaligned_q = mirrorJoints(source->q, generatorJointSpace(robot));
    EXPECT_GT((unaligned_q - file.q).cwiseAbs().maxCoeff(), 0.05);
  }
}

}  // namespace
