// PMG generator: each equation on hand-computed cases, convexity, continuity across φ = 1 → 0,
// negative commands (clips derived with pmg::clips), standing, posture offsets, clip validation,
// and no allocation per tick.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "pmg/generator/generator.hpp"
#include "synthetic_joint_space.hpp"

namespace pmg {
namespace {

constexpr int kJoints = test::kSyntheticJoints;
constexpr int kSamples = 8;

GeneratorJointSpace jointSpace() { return test::syntheticJointSpace(); }

// Clip whose joint j at sample k is offset + (k+1) * 0.01 * (j+1): distinct, easy to hand-compute.
DynamicClip makeClip(CommandAxis axis, double offset, double scale, double period, double mu_l, double mu_r) {
  DynamicClip c;
  c.name = "clip" + std::to_string(static_cast<int>(axis));
  c.axis = axis;
  c.nominal_scale = scale;
  c.period = period;
  c.q.resize(kSamples, kJoints);
  for (int k = 0; k < kSamples; ++k)
    for (int j = 0; j < kJoints; ++j) c.q(k, j) = offset + (k + 1) * 0.01 * (j + 1);
  c.qd = Eigen::MatrixXd::Zero(kSamples, kJoints);
  c.v_base = Eigen::MatrixXd::Zero(kSamples, 3);
  c.omega_base = Eigen::MatrixXd::Zero(kSamples, 3);
  c.v_base.col(static_cast<int>(axis) < 2 ? static_cast<int>(axis) : 0).setConstant(axis == CommandAxis::kYaw ? 0 : scale);
  if (axis == CommandAxis::kYaw) c.omega_base.col(2).setConstant(scale);
  c.base_height = Eigen::VectorXd::Constant(kSamples, 0.72);
  c.contact = {FootContact{mu_l, 0.3}, FootContact{mu_r, 0.3}};
  return c;
}

ClipLibrary library() {
  ClipLibrary lib;
  lib.dynamic_clips.push_back(makeClip(CommandAxis::kForward, 0.0, 1.0, 1.2, 0.25, 0.75));
  lib.dynamic_clips.push_back(makeClip(CommandAxis::kLateral, 0.5, 0.4, 1.0, 0.30, 0.80));
  lib.dynamic_clips.push_back(makeClip(CommandAxis::kYaw, -0.5, 0.8, 0.8, 0.20, 0.70));
  StaticClip squat;
  squat.name = "squat";
  squat.axis = PostureAxis::kHeight;
  squat.values = Eigen::Vector3d(0.45, 0.6, 0.75);
  squat.neutral = 0.75;
  squat.q.resize(3, kJoints);
  squat.q << 0.9, 0.9, 0.0, 1.0,  //
      0.5, 0.5, 0.0, 0.6,         //
      0.1, 0.1, 0.0, -0.2;
  lib.static_clips.push_back(squat);
  return lib;
}

// These tests check the paper's equations (eqs. 4–12): Blending::kPaper. The command-consistent
// blending (the default) is tested in test_consistent_blending.cpp.
GeneratorParams paper() {
  GeneratorParams p;
  p.blending = Blending::kPaper;
  return p;
}

std::shared_ptr<const GeneratorModel> model(GeneratorParams p = paper()) {
  return std::make_shared<const GeneratorModel>(library(), jointSpace(), p);
}

TEST(Generator, ZeroCommandIsExactlyTheStandingPose) {
  MotionGenerator gen(model());
  gen.step({}, {}, 0.01);
  const auto& out = gen.output();
  EXPECT_TRUE(out.q_ref.isApprox(jointSpace().q_stand, 1e-12));
  EXPECT_DOUBLE_EQ(out.standing_weight, 1.0);
  EXPECT_TRUE(out.in_contact[0] && out.in_contact[1]);
  EXPECT_NEAR(out.period, 1.2, 1e-12);  // T_stand = forward clip period
  EXPECT_NEAR(out.next_phase, 0.01 / 1.2, 1e-12);
  EXPECT_NEAR(out.base_height, 0.75, 1e-12);
}

TEST(Generator, Eq4AlphaAndEq6WeightsHandComputed) {
  GeneratorParams p = paper();
  p.epsilon = 0.1;
  MotionGenerator gen(model(p));
  gen.step({0.5, 0.2, 0.0}, {}, 0.01);
  const auto& out = gen.output();
  EXPECT_NEAR(out.alpha[0], 0.5 / 1.0, 1e-12);          // eq. 4
  EXPECT_NEAR(out.alpha[1], 0.2 / 0.4, 1e-12);
  EXPECT_NEAR(out.alpha[2], 0.0, 1e-12);
  EXPECT_NEAR(out.weight[0], 0.5 / (0.7 + 0.1), 1e-12);  // eq. 6
  EXPECT_NEAR(out.weight[1], 0.2 / (0.7 + 0.1), 1e-12);
  EXPECT_NEAR(out.standing_weight, 0.1 / 0.8, 1e-12);
  gen.step({3.0, 0.0, 0.0}, {}, 0.01);  // α saturates at 1 (and the command is clamped to 1.5)
  EXPECT_NEAR(gen.output().alpha[0], 1.0, 1e-12);
  EXPECT_EQ(gen.output().status, GeneratorStatus::kCommandClamped);
}

TEST(Generator, Eq5Eq7BlendAtASampleHandComputed) {
  GeneratorParams p = paper();
  p.epsilon = 0.1;
  MotionGenerator gen(model(p));
  gen.reset(2.0 / kSamples);  // exactly sample k = 2: q_D(k=2, j) = offset + 0.03 (j + 1)
  gen.step({0.5, 0.2, 0.0}, {}, 0.01);
  const auto& out = gen.output();
  const auto js = jointSpace();
  const double w0 = 0.5 / 0.8, w1 = 0.2 / 0.8, ws = 0.1 / 0.8, a0 = 0.5, a1 = 0.5;
  for (int j = 0; j < kJoints; ++j) {
    const double qf = 0.0 + 0.03 * (j + 1), ql = 0.5 + 0.03 * (j + 1);
    const double qt_f = a0 * qf + (1 - a0) * js.q_stand[j];  // eq. 5
    const double qt_l = a1 * ql + (1 - a1) * js.q_stand[j];
    const double expected = w0 * qt_f + w1 * qt_l + ws * js.q_stand[j];  // eq. 7 (+ standing weight)
    EXPECT_NEAR(out.q_dynamic[j], expected, 1e-12) << j;
    EXPECT_NEAR(out.q_ref[j], expected, 1e-12) << j;  // no posture command: q_s = 0 (eq. 10)
  }
}

TEST(Generator, PhaseInterpolatesLinearlyBetweenSamples) {
  MotionGenerator gen(model());
  gen.reset(2.25 / kSamples);
  gen.step({1.5, 0, 0}, {}, 0.01);  // w0 = 1.5/1.55, α = 1
  const double w0 = 1.5 / 1.55;
  const double q_clip = 0.75 * 0.03 + 0.25 * 0.04;  // joint 0 at samples 2 and 3
  EXPECT_NEAR(gen.output().q_dynamic[0], w0 * q_clip + (1 - w0) * 0.1, 1e-12);
}

TEST(Generator, Eq8Eq9ContactBlendHandComputed) {
  GeneratorParams p = paper();
  p.epsilon = 0.1;
  MotionGenerator gen(model(p));
  gen.step({0.5, 0.2, 0.0}, {}, 0.01);
  const auto& out = gen.output();
  const double w0 = 0.5 / 0.8, w1 = 0.2 / 0.8, ws = 0.1 / 0.8;
  EXPECT_NEAR(out.contact[0].mu, (w0 * 0.25 + w1 * 0.30) / (w0 + w1), 1e-12);
  EXPECT_NEAR(out.contact[1].mu, (w0 * 0.75 + w1 * 0.80) / (w0 + w1), 1e-12);
  EXPECT_NEAR(out.contact[0].sigma, (w0 + w1) * 0.3 + ws * 0.5, 1e-12);
  // φ = 0: left centre ≈ 0.264, σ ≈ 0.325 → in contact; right centre ≈ 0.764, distance 0.236 → in contact too.
  EXPECT_TRUE(out.in_contact[0]);
  EXPECT_TRUE(out.in_contact[1]);
  // φ = 0.62: left distance |0.62 − 0.264| = 0.356 > σ = 0.325 → swing; right distance 0.144 → stance.
  gen.reset(0.62);
  gen.step({0.5, 0.2, 0.0}, {}, 0.01);
  EXPECT_FALSE(gen.output().in_contact[0]);
  EXPECT_TRUE(gen.output().in_contact[1]);
}

TEST(Generator, Eq11Eq12PhaseAdvanceAndWrap) {
  GeneratorParams p = paper();
  p.epsilon = 0.1;
  MotionGenerator gen(model(p));
  gen.reset(0.995);
  gen.step({0.5, 0.2, 0.0}, {}, 0.01);
  const double T = (0.5 / 0.8) * 1.2 + (0.2 / 0.8) * 1.0 + (0.1 / 0.8) * 1.2;  // eq. 12
  EXPECT_NEAR(gen.output().period, T, 1e-12);
  EXPECT_NEAR(gen.output().next_phase, std::fmod(0.995 + 0.01 / T, 1.0), 1e-12);  // eq. 11 with wrap
  EXPECT_LT(gen.phase(), 0.01);
}

TEST(Generator, Eq10PostureOffsetFromStaticClip) {
  MotionGenerator gen(model());
  gen.step({}, {0.0, 0.0, 0.6}, 0.01);  // squat to 0.6 m: q_s = q(0.6) − q(0.75)
  const auto& out = gen.output();
  const Eigen::Vector4d expected_offset(0.4, 0.4, 0.0, 0.8);
  EXPECT_TRUE(out.q_posture.isApprox(expected_offset, 1e-12)) << out.q_posture.transpose();
  EXPECT_TRUE(out.q_ref.isApprox(jointSpace().q_stand + expected_offset, 1e-12));
  EXPECT_NEAR(out.beta[2], -0.5, 1e-12);  // halfway between neutral 0.75 and range end 0.45
  EXPECT_NEAR(out.base_height, 0.6, 1e-12);
  gen.step({}, {0.0, 0.0, 0.1}, 0.01);  // below the range: clamped to 0.45
  EXPECT_EQ(gen.output().status, GeneratorStatus::kCommandClamped);
  EXPECT_NEAR(gen.output().beta[2], -1.0, 1e-12);
}

TEST(Generator, ConvexityQdStaysInTheSpanOfTheTemplates) {
  auto m = model();
  MotionGenerator gen(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5), phase(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    gen.reset(phase(rng));
    gen.step({u(rng), 0.5 * u(rng), u(rng)}, {}, 0.01);
    for (int j = 0; j < kJoints; ++j) {
      double lo = jointSpace().q_stand[j], hi = lo;
      for (int a = 0; a < 3; ++a)
        for (int s : {1, -1}) {
          const DynamicClip* c = m->dynamicClip(static_cast<CommandAxis>(a), s);
          lo = std::min(lo, c->q.col(j).minCoeff());
          hi = std::max(hi, c->q.col(j).maxCoeff());
        }
      EXPECT_GE(gen.output().q_dynamic[j], lo - 1e-12);
      EXPECT_LE(gen.output().q_dynamic[j], hi + 1e-12);
    }
  }
}

TEST(Generator, ContinuousAcrossPhaseWrap) {
  MotionGenerator gen(model());
  const VelocityCommand u{0.8, 0.1, 0.3};
  gen.reset(1.0 - 1e-9);
  gen.step(u, {}, 1e-9);
  const Eigen::VectorXd before = gen.output().q_ref;
  gen.reset(0.0);
  gen.step(u, {}, 1e-9);
  EXPECT_LT((gen.output().q_ref - before).cwiseAbs().maxCoeff(), 1e-7);
  // And a full cycle of small steps never jumps more than the largest sample-to-sample change.
  gen.reset(0.9);
  Eigen::VectorXd prev = gen.output().q_ref;
  gen.step(u, {}, 0.001);
  prev = gen.output().q_ref;
  for (int i = 0; i < 2000; ++i) {
    gen.step(u, {}, 0.001);
    EXPECT_LT((gen.output().q_ref - prev).cwiseAbs().maxCoeff(), 0.02) << "tick " << i;
    prev = gen.output().q_ref;
  }
}

TEST(Generator, NegativeCommandsUseTimeReversedAndMirroredClips) {
  auto m = model();
  const DynamicClip* fwd = m->dynamicClip(CommandAxis::kForward, 1);
  const DynamicClip* back = m->dynamicClip(CommandAxis::kForward, -1);
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->meta.provenance, "mocap_time_reversed");
  EXPECT_EQ(back->direction, -1);
  // Reversed, then rotated so that φ = 0 is the left touchdown again: the forward clip's left
  // contact (μ 0.25, σ 0.3) reversed is μ 0.75, starting at 0.45 of the cycle = 3.6 → 4 samples.
  const Eigen::Index shift = 4;
  for (Eigen::Index k = 0; k < kSamples; ++k) {
    const Eigen::Index src = (kSamples - (k + shift) % kSamples) % kSamples;  // q_back(φ) = q_fwd(1 − φ − shift/N)
    EXPECT_TRUE(back->q.row(k).isApprox(fwd->q.row(src))) << k;
    EXPECT_NEAR(back->v_base(k, 0), -fwd->v_base(src, 0), 1e-12);
  }
  EXPECT_NEAR(back->contact[0].mu, 0.25, 1e-12);
  const DynamicClip* left = m->dynamicClip(CommandAxis::kLateral, 1);
  const DynamicClip* right = m->dynamicClip(CommandAxis::kLateral, -1);
  EXPECT_EQ(right->meta.provenance, "mocap_mirrored");
  EXPECT_EQ(right->direction, -1);
  // Mirrored, then rotated by 4 samples: the new left foot is the old right one (μ 0.8, σ 0.3).
  for (Eigen::Index k = 0; k < kSamples; ++k) {
    const Eigen::Index src = (k + 4) % kSamples;
    EXPECT_DOUBLE_EQ(right->q(k, 0), left->q(src, 1));   // left joint takes the right joint's motion
    EXPECT_DOUBLE_EQ(right->q(k, 2), -left->q(src, 2));  // yaw joint flips sign
  }
  EXPECT_NEAR(right->contact[0].mu, left->contact[1].mu - 0.5, 1e-12);
  MotionGenerator gen(m);
  gen.step({0, -0.3, 0}, {}, 0.01);
  EXPECT_GT(gen.output().weight[1], 0.0);
  EXPECT_LT(gen.output().v_base[1], 0.0);  // walking right
  gen.step({0, 0, -0.5}, {}, 0.01);
  EXPECT_LT(gen.output().yaw_rate, 0.0);  // turning clockwise
}

TEST(Generator, DerivedClipsKeepTheLeftTouchdownAtPhaseZero) {
  // All clips share one phase and are blended sample by sample, so a derived clip must start at
  // the left foot's touchdown like the real ones (within half a sample).
  auto m = model();
  for (const auto& [axis, dir] : {std::pair{CommandAxis::kForward, -1}, std::pair{CommandAxis::kLateral, -1},
                                  std::pair{CommandAxis::kYaw, -1}}) {
    const DynamicClip* c = m->dynamicClip(axis, dir);
    ASSERT_NE(c, nullptr);
    const double start = c->contact[0].mu - c->contact[0].sigma;
    EXPECT_LE(std::fabs(start - std::round(start)), 0.5 / kSamples + 1e-12) << c->name;
  }
}

TEST(Generator, NanCommandFallsBackToStandingAndIsReported) {
  MotionGenerator gen(model());
  EXPECT_EQ(gen.step({std::nan(""), 0, 0}, {}, 0.01), GeneratorStatus::kInvalidCommand);
  EXPECT_TRUE(gen.output().q_ref.isApprox(jointSpace().q_stand, 1e-12));
  EXPECT_TRUE(gen.output().q_ref.allFinite());
  EXPECT_EQ(gen.step({}, {}, -1.0), GeneratorStatus::kBadTimeStep);
}

TEST(Generator, ReferenceVelocityMatchesTheFiniteDifferenceOfQref) {
  MotionGenerator gen(model());
  const VelocityCommand u{0.7, 0.0, 0.2};
  const double dt = 1e-4;
  gen.reset(0.4);
  gen.step(u, {}, dt);
  const Eigen::VectorXd q0 = gen.output().q_ref, qd0 = gen.output().qd_ref;
  gen.step(u, {}, dt);
  const Eigen::VectorXd fd = (gen.output().q_ref - q0) / dt;
  EXPECT_LT((fd - qd0).cwiseAbs().maxCoeff(), 1e-6 + 0.02 * fd.cwiseAbs().maxCoeff());
}

// GeneratorParams::max_cadence_ratio outside [1, 2] is refused naming the field.
TEST(Generator, RejectsACadenceRatioOutsideItsRange) {
  for (double bad : {0.9, 2.5, std::nan("")}) {
    GeneratorParams p;
    p.max_cadence_ratio = bad;
    try {
      GeneratorModel m(library(), jointSpace(), p);
      ADD_FAILURE() << "max_cadence_ratio " << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("max_cadence_ratio"), std::string::npos) << e.what();
    }
  }
  GeneratorParams ok;
  ok.max_cadence_ratio = 1.0;
  EXPECT_NO_THROW(GeneratorModel(library(), jointSpace(), ok));
}

// The generator refuses a clip by the clip library's one validation (pmg::validateClip).
std::string modelError(const ClipLibrary& lib) {
  try {
    GeneratorModel m(lib, jointSpace());
  } catch (const ClipFormatError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Generator, RejectsInconsistentClips) {
  ClipLibrary lib = library();
  lib.dynamic_clips[0].qd.resize(3, kJoints);
  EXPECT_EQ(modelError(lib), "clip 'clip0': qd: is 3x4: expected 8x4 (same shape as q)");
  lib = library();
  lib.dynamic_clips[1].contact[0].sigma = 0.7;
  EXPECT_EQ(modelError(lib), "clip 'clip1': contact.left.sigma: = 0.7: expected in [0, 0.5] (phase units)");
  lib = library();
  lib.dynamic_clips.push_back(lib.dynamic_clips[0]);
  EXPECT_NE(modelError(lib).find("duplicates clip 'clip0'"), std::string::npos);
  lib = library();
  lib.dynamic_clips[2].q(3, 1) = 3.5;  // beyond the limit 3
  EXPECT_EQ(modelError(lib), "clip 'clip2': q[3][1]: = 3.500000: expected within joint limits [-3, 3] of r");
  lib = library();
  lib.static_clips[0].meta.joint_names = {"r", "l", "yaw", "pitch"};  // names are optional in memory, but checked
  EXPECT_EQ(modelError(lib), "static clip 'squat': joint_names[0]: = 'r': expected 'l' (joint order of the joint space)");
  lib = library();
  lib.dynamic_clips[0].period = 12.0;
  EXPECT_EQ(modelError(lib), "clip 'clip0': period: = 12: expected T in (0, 10) [s]");
}

TEST(Generator, StepDoesNotAllocate) {
  MotionGenerator gen(model());
  gen.step({0.3, 0.1, 0.2}, {0.1, 0.0, 0.6}, 0.01);  // warm
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (int i = 0; i < 1000; ++i) gen.step({0.3 + 1e-3 * i, -0.1, 0.2}, {0.0, 0.0, 0.6}, 0.01);
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace pmg
