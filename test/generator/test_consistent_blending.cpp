// Command-consistent blending (GeneratorParams::blending = kConsistent, include/pmg/generator/
// generator.hpp): amplitudes from the clips' implied-motion tables on hand-computed cases, drift of
// one channel cancelled by another, continuity through sign changes, saturation, the consistency
// map's multilinear correction, table validation, and no allocation per tick.
#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "pmg/generator/generator.hpp"
#include "synthetic_joint_space.hpp"

namespace pmg {
namespace {

constexpr int kJoints = test::kSyntheticJoints;
constexpr int kSamples = 8;

GeneratorJointSpace jointSpace() { return test::syntheticJointSpace(); }

ImpliedMotionTable table(std::initializer_list<double> amplitudes, std::initializer_list<Eigen::Vector3d> rows) {
  ImpliedMotionTable t;
  t.amplitude.resize(static_cast<Eigen::Index>(amplitudes.size()));
  t.velocity.resize(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::Index i = 0;
  for (double a : amplitudes) t.amplitude[i++] = a;
  i = 0;
  for (const auto& r : rows) t.velocity.row(i++) = r.transpose();
  return t;
}

DynamicClip makeClip(CommandAxis axis, double offset, double scale, double period) {
  DynamicClip c;
  c.name = "clip" + std::to_string(static_cast<int>(axis));
  c.axis = axis;
  c.nominal_scale = scale;
  c.period = period;
  c.q.resize(kSamples, kJoints);
  for (int k = 0; k < kSamples; ++k)
    for (int j = 0; j < kJoints; ++j) c.q(k, j) = offset + 0.05 * std::sin(2 * M_PI * k / kSamples + j);
  c.qd = Eigen::MatrixXd::Zero(kSamples, kJoints);
  c.v_base = Eigen::MatrixXd::Zero(kSamples, 3);
  c.omega_base = Eigen::MatrixXd::Zero(kSamples, 3);
  c.base_height = Eigen::VectorXd::Constant(kSamples, 0.72);
  c.contact = {FootContact{0.25, 0.3}, FootContact{0.75, 0.3}};
  return c;
}

// Forward: nonlinear (0.5 m/s at e = 1, 0.9 at e = 2); lateral: 0.4 m/s left with a 0.1 m/s
// backward drift; yaw: 0.8 rad/s at e = 1, 1.5 at e = 2. All periods 1.2 s (T_u = 1.2 s).
ClipLibrary library() {
  ClipLibrary lib;
  DynamicClip fwd = makeClip(CommandAxis::kForward, 0.1, 0.5, 1.2);
  fwd.implied = table({0.0, 1.0, 2.0}, {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d(0.9, 0, 0)});
  DynamicClip lat = makeClip(CommandAxis::kLateral, 0.3, 0.4, 1.2);
  lat.implied = table({0.0, 1.0}, {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-0.1, 0.4, 0)});
  DynamicClip yaw = makeClip(CommandAxis::kYaw, -0.2, 0.8, 1.2);
  yaw.implied = table({0.0, 1.0, 2.0}, {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 0.8), Eigen::Vector3d(0, 0, 1.5)});
  lib.dynamic_clips = {fwd, lat, yaw};
  return lib;
}

std::shared_ptr<const GeneratorModel> model(const ClipLibrary& lib = library()) {
  return std::make_shared<const GeneratorModel>(lib, jointSpace(), GeneratorParams{});
}

// Σ_i D_i(e_i) along every axis, from the model's tables and the output's amplitudes.
Eigen::Vector3d displacement(const GeneratorModel& m, const GeneratorOutput& out) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < kNumCommandAxes; ++i) {
    if (out.amplitude[i] == 0.0) continue;
    const auto* t = m.displacementTable(static_cast<CommandAxis>(i), out.clip_direction[i]);
    EXPECT_NE(t, nullptr);
    const Eigen::Index K = t->amplitude.size();
    Eigen::Index k = 0;
    while (k + 2 < K && out.amplitude[i] > t->amplitude[k + 1]) ++k;
    const double f = (out.amplitude[i] - t->amplitude[k]) / (t->amplitude[k + 1] - t->amplitude[k]);
    d += ((1 - f) * t->displacement.row(k) + f * t->displacement.row(k + 1)).transpose();
  }
  return d;
}

TEST(ConsistentBlending, IsTheDefault) { EXPECT_EQ(GeneratorParams{}.blending, Blending::kConsistent); }

TEST(ConsistentBlending, SingleAxisAmplitudeInvertsTheTableHandComputed) {
  auto m = model();
  MotionGenerator gen(m);
  gen.reset(0.0);
  gen.step({0.6, 0.0, 0.0}, {}, 0.01);
  const auto& out = gen.output();
  // T_u = 1.2 s (every period 1.2): displacement 0.6 * 1.2 = 0.72 m per cycle; the table gives
  // 0.6 m at e = 1 and 1.08 m at e = 2, so e = 1 + 0.12 / 0.48 = 1.25.
  EXPECT_NEAR(out.period, 1.2, 1e-12);
  EXPECT_NEAR(out.amplitude[0], 1.25, 1e-12);
  EXPECT_NEAR(out.alpha[0], 1.25, 1e-12);
  EXPECT_EQ(out.amplitude_saturated, 0);
  // q_d = q_stand + e (q_D(φ = 0) − q_stand).
  const auto& js = jointSpace();
  const DynamicClip* fwd = m->dynamicClip(CommandAxis::kForward, 1);
  for (int j = 0; j < kJoints; ++j)
    EXPECT_NEAR(out.q_dynamic[j], js.q_stand[j] + 1.25 * (fwd->q(0, j) - js.q_stand[j]), 1e-12) << j;
  // The paper's blending dilutes the same command: α = 0.6 / 0.5 → 1, w = 0.6 / 0.65.
  GeneratorParams paper;
  paper.blending = Blending::kPaper;
  MotionGenerator gp(std::make_shared<const GeneratorModel>(library(), jointSpace(), paper));
  gp.step({0.6, 0.0, 0.0}, {}, 0.01);
  EXPECT_NEAR(gp.output().amplitude[0], 0.6 / 0.65, 1e-12);
}

TEST(ConsistentBlending, AnotherChannelCancelsTheLateralClipsBackwardDrift) {
  auto m = model();
  MotionGenerator gen(m);
  gen.step({0.0, 0.3, 0.0}, {}, 0.01);
  const auto& out = gen.output();
  // The lateral clip drifts backward (−0.1 per 0.4 left): the forward clip plays to cancel it,
  // although v_x is not commanded.
  EXPECT_EQ(out.clip_direction[0], 1);
  EXPECT_GT(out.amplitude[0], 0.1);
  EXPECT_DOUBLE_EQ(out.weight[0], 0.0);  // the weights (period, contacts) still follow eq. 6
  const Eigen::Vector3d d = displacement(*m, out);
  EXPECT_NEAR(d.x(), 0.0, 1e-9);
  EXPECT_NEAR(d.y(), 0.3 * out.period, 1e-9);
  EXPECT_NEAR(d.z(), 0.0, 1e-12);
}

TEST(ConsistentBlending, CombinedCommandIsCarriedOnEveryAxis) {
  auto m = model();
  MotionGenerator gen(m);
  for (const VelocityCommand& u : {VelocityCommand{0.5, 0.3, 0.5}, VelocityCommand{-0.3, -0.2, 0.4},
                                   VelocityCommand{0.2, 0.0, -0.6}}) {
    gen.step(u, {}, 0.01);
    const Eigen::Vector3d d = displacement(*m, gen.output()) / gen.output().period;
    EXPECT_NEAR(d.x(), u.vx, 1e-6);
    EXPECT_NEAR(d.y(), u.vy, 1e-6);
    EXPECT_NEAR(d.z(), u.wz, 1e-6);
  }
}

TEST(ConsistentBlending, ReferenceIsContinuousThroughSignChanges) {
  MotionGenerator gen(model());
  double worst = 0.0;
  Eigen::VectorXd prev;
  for (int k = -2000; k <= 2000; ++k) {
    const double x = 1e-4 * k;  // v_x and ω cross zero while v_y drifts the forward channel
    gen.reset(0.3);
    gen.step({x, 0.3, -x}, {}, 0.01);
    if (prev.size() > 0) worst = std::max(worst, (gen.output().q_ref - prev).cwiseAbs().maxCoeff());
    prev = gen.output().q_ref;
  }
  EXPECT_LT(worst, 2e-4);  // |Δq| per 1e-4 m/s of command: Lipschitz, no jump
}

TEST(ConsistentBlending, AmplitudeSaturatesAtTheTablesEndAndSaysSo) {
  MotionGenerator gen(model());
  gen.step({1.4, 0.0, 0.0}, {}, 0.01);
  EXPECT_DOUBLE_EQ(gen.output().amplitude[0], 2.0);
  EXPECT_EQ(gen.output().amplitude_saturated, 1);
}

TEST(ConsistentBlending, ClipWithoutTableGetsTheLinearFallback) {
  ClipLibrary lib = library();
  lib.dynamic_clips[0].implied = {};
  MotionGenerator gen(model(lib));
  gen.step({0.25, 0.0, 0.0}, {}, 0.01);
  EXPECT_NEAR(gen.output().amplitude[0], 0.5, 1e-12);  // x̄ = 0.5 m/s at e = 1
}

TEST(ConsistentBlending, ConsistencyMapCorrectionIsMultilinear) {
  ClipLibrary lib = library();
  ConsistencyMap& c = lib.consistency;
  c.grid[0] = Eigen::Vector2d(-1.0, 1.0);
  c.grid[1] = Eigen::Vector2d(-0.5, 0.5);
  c.grid[2] = Eigen::VectorXd::Constant(1, 0.0);
  c.grid[3] = Eigen::VectorXd::Constant(1, 0.75);
  c.grid[4] = Eigen::VectorXd::Constant(1, 0.0);
  c.delta.resize(4, 3);  // rows (vx, vy): (-1,-0.5), (-1,0.5), (1,-0.5), (1,0.5); Δv_x = 0.1 vx + 0.2 vy
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const double vx = c.grid[0][i], vy = c.grid[1][j];
      c.delta.row(2 * i + j) << 0.1 * vx + 0.2 * vy, 0.0, 0.05;
    }
  auto m = model(lib);
  MotionGenerator gen(m);
  gen.step({0.4, -0.2, 0.0}, {}, 0.01);
  EXPECT_NEAR(gen.output().command_correction[0], 0.1 * 0.4 + 0.2 * -0.2, 1e-12);
  EXPECT_NEAR(gen.output().command_correction[2], 0.05, 1e-12);
  const Eigen::Vector3d d = displacement(*m, gen.output()) / gen.output().period;
  EXPECT_NEAR(d.x(), 0.4 + 0.0, 1e-6);  // u + Δu is what the tables carry
  EXPECT_NEAR(d.z(), 0.05, 1e-6);
  // Outside the grid the inputs are clamped: vx = 3 reads the vx = 1 edge.
  gen.step({3.0, 0.5, 0.0}, {}, 0.01);
  EXPECT_NEAR(gen.output().command_correction[0], 0.1 * 1.0 + 0.2 * 0.5, 1e-12);
  // The paper's blending ignores the map.
  GeneratorParams paper;
  paper.blending = Blending::kPaper;
  MotionGenerator gp(std::make_shared<const GeneratorModel>(lib, jointSpace(), paper));
  gp.step({0.4, -0.2, 0.0}, {}, 0.01);
  EXPECT_EQ(gp.output().command_correction[0], 0.0);
}

std::string modelError(const ClipLibrary& lib) {
  try {
    GeneratorModel m(lib, jointSpace());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(ConsistentBlending, ConsistencyMapInterpolatesThePitchCommand) {
  ClipLibrary lib = library();
  ConsistencyMap& c = lib.consistency;
  c.grid[0] = c.grid[1] = c.grid[2] = Eigen::VectorXd::Constant(1, 0.0);
  c.grid[3] = Eigen::VectorXd::Constant(1, 0.75);
  c.grid[4] = Eigen::Vector2d(0.0, 0.4);      // pitch [rad]
  c.delta.resize(2, 3);
  c.delta << 0.0, 0.02, 0.0,   // pitch 0
      0.0, 0.10, -0.08;        // pitch 0.4
  MotionGenerator gen(model(lib));
  gen.step({0.3, 0.0, 0.2}, {0.1, 0.0, 0.0}, 0.01);  // a quarter of the way: Δv_y 0.04, Δω -0.02
  EXPECT_NEAR(gen.output().command_correction[1], 0.04, 1e-12);
  EXPECT_NEAR(gen.output().command_correction[2], -0.02, 1e-12);
  gen.step({0.3, 0.0, 0.2}, {0.9, 0.0, 0.0}, 0.01);  // beyond the grid: its end
  EXPECT_NEAR(gen.output().command_correction[1], 0.10, 1e-12);
}

TEST(ConsistentBlending, RejectsTablesItCannotInvert) {
  ClipLibrary lib = library();
  lib.dynamic_clips[0].implied.velocity(2, 0) = 0.4;  // forward no longer grows with the amplitude
  EXPECT_NE(modelError(lib).find("implied_motion.velocity[2][0]"), std::string::npos) << modelError(lib);
  lib = library();
  lib.dynamic_clips[2].implied.amplitude[0] = 0.1;
  EXPECT_NE(modelError(lib).find("implied_motion.amplitude[0]"), std::string::npos) << modelError(lib);
  lib = library();
  lib.consistency.grid[0] = Eigen::Vector2d(0.0, 1.0);
  lib.consistency.grid[1] = lib.consistency.grid[2] = lib.consistency.grid[3] = lib.consistency.grid[4] =
      Eigen::VectorXd::Constant(1, 0.0);
  lib.consistency.delta.setZero(3, 3);  // 2 grid points, 3 rows
  EXPECT_NE(modelError(lib).find("consistency.delta"), std::string::npos) << modelError(lib);
}

TEST(ConsistentBlending, StepDoesNotAllocate) {
  ClipLibrary lib = library();
  lib.consistency.grid[0] = Eigen::Vector2d(-1.0, 1.0);
  lib.consistency.grid[1] = lib.consistency.grid[2] = lib.consistency.grid[3] = lib.consistency.grid[4] =
      Eigen::VectorXd::Constant(1, 0.0);
  lib.consistency.delta = Eigen::MatrixXd::Constant(2, 3, 0.01);
  MotionGenerator gen(model(lib));
  gen.step({0.3, 0.1, 0.2}, {}, 0.01);
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (int i = 0; i < 1000; ++i) gen.step({0.3 - 1e-3 * i, 0.2, -0.4 + 1e-3 * i}, {}, 0.01);
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace pmg
