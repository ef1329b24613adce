// Reference settings beyond the paper on the shipped G1 clips: stance sole levelling
// (sole_levelling.hpp) and upright walking (GeneratorParams::upright_walking).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "g1_fixture.hpp"
#include "g1_reference_fixture.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg::gco {
namespace {

constexpr double kStand = 0.78;  // standing pelvis height of the G1 [m]

using Fixture = test::G1Reference;

LegVector legOf(const Eigen::VectorXd& q, const LegJointIndex& idx, std::size_t f) {
  LegVector v;
  for (int j = 0; j < kLegDofs; ++j) v(j) = q(idx[f][j]);
  return v;
}

// Sole normal of foot f for the full joint vector q, pelvis frame B (independent of SoleLevelling).
Eigen::Vector3d soleNormal(LegKinematics& kin, const Fixture& fx, const Eigen::VectorXd& q, std::size_t f) {
  Eigen::Isometry3d X;
  EXPECT_TRUE(kin.forward(static_cast<Foot>(f), legOf(q, fx.idx, f), &X));
  return X.linear().col(2);
}

double angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

struct LevelRun {
  double max_tilt_stance_before = 0.0;  // worst stance-sole tilt against the posture's sole, generator
  double max_tilt_stance_after = 0.0;   // the same, levelled reference, at full weight
  double max_non_ankle_change = 0.0;    // |levelled − generator| over the non-ankle joints [rad]
  double max_swing_change = 0.0;        // |levelled − generator| on a foot at weight 0 [rad]
  double max_extra_step = 0.0;          // largest per-tick change of the added ankle offset [rad]
  double max_qd_mismatch = 0.0;         // added q̇ vs the finite difference of the added q [rad/s]
  double max_generator_step = 0.0;      // largest per-tick change of the generator's own q_ref [rad]
};

// Runs the pipe with levelling next to a plain generator on the same commands.
LevelRun run(const Fixture& fx, const std::vector<std::pair<VelocityCommand, PostureCommand>>& schedule, int ticks_each) {
  GcoOptions o;
  o.sole_levelling.enabled = true;
  GeneratorWithGco pipe(fx.model, fx.legs, o);
  MotionGenerator plain(fx.model);
  LegKinematics kin(fx.legs);
  const Eigen::VectorXd& q_stand = fx.model->jointSpace().q_stand;
  LevelRun r;
  Eigen::VectorXd prev_added, prev_gen;
  VelocityCommand ud0;
  PostureCommand us0{0.0, 0.0, kStand};
  for (const auto& [ud1, us1] : schedule) {
    for (int k = 0; k < ticks_each; ++k) {
      VelocityCommand ud;
      PostureCommand us;
      test::rampedCommand(ud0, us0, ud1, us1, k, &ud, &us);
      pipe.step(ud, us, o.dt);
      plain.step(ud, us, o.dt);
      const GeneratorOutput& lev = pipe.generatorOutput();
      const GeneratorOutput& gen = plain.output();
      const Eigen::VectorXd added = lev.q_ref - gen.q_ref;
      const Eigen::VectorXd added_qd = lev.qd_ref - gen.qd_ref;
      const Eigen::VectorXd q_post = q_stand + gen.q_posture;
      for (std::size_t f = 0; f < kNumFeet; ++f) {
        const SoleLevelling& sl = pipe.soleLevelling();
        for (int j = 0; j < kLegDofs - 2; ++j) {
          r.max_non_ankle_change = std::max(r.max_non_ankle_change, std::abs(added(fx.idx[f][j])));
        }
        const double w = sl.weight(static_cast<Foot>(f));
        if (w == 0.0) {
          for (int j = 0; j < kLegDofs; ++j) r.max_swing_change = std::max(r.max_swing_change, std::abs(added(fx.idx[f][j])));
        }
        if (w == 1.0 && gen.in_contact[f]) {
          const Eigen::Vector3d n_post = soleNormal(kin, fx, q_post, f);
          r.max_tilt_stance_before = std::max(r.max_tilt_stance_before, angle(soleNormal(kin, fx, gen.q_ref, f), n_post));
          r.max_tilt_stance_after = std::max(r.max_tilt_stance_after, angle(soleNormal(kin, fx, lev.q_ref, f), n_post));
        }
      }
      if (prev_added.size() > 0) {
        const Eigen::VectorXd step = added - prev_added;
        r.max_extra_step = std::max(r.max_extra_step, step.cwiseAbs().maxCoeff());
        r.max_qd_mismatch = std::max(r.max_qd_mismatch, (added_qd - step / o.dt).cwiseAbs().maxCoeff());
      }
      prev_added = added;
      const Eigen::VectorXd gen_step = gen.q_ref - (prev_gen.size() ? prev_gen : gen.q_ref);
      r.max_generator_step = std::max(r.max_generator_step, gen_step.cwiseAbs().maxCoeff());
      prev_gen = gen.q_ref;
    }
    ud0 = ud1;
    us0 = us1;
  }
  return r;
}

// The generator tilts the stance soles of a side-step and of backward walking (docs/policy.md:
// +0.11..+0.23 rad of torso pitch on flat soles); levelled, the stance soles lie parallel to the
// posture's (here: standing) soles, only the ankle joints move, and the swing leg is the generator's.
TEST(SoleLevelling, StanceSolesParallelToThePostureSolesOnlyAnklesChange) {
  const Fixture fx;
  for (const VelocityCommand u : {VelocityCommand{0.0, 0.4, 0.0}, VelocityCommand{-0.5, 0.0, 0.5},
                                  VelocityCommand{0.5, 0.3, 0.5}}) {
    SCOPED_TRACE("command " + std::to_string(u.vx) + " " + std::to_string(u.vy) + " " + std::to_string(u.wz));
    const LevelRun r = run(fx, {{u, PostureCommand{0.0, 0.0, kStand}}}, 400);
    EXPECT_GT(r.max_tilt_stance_before, 0.05);  // the effect is there
    EXPECT_LT(r.max_tilt_stance_after, 1e-4);   // and gone at full weight
    EXPECT_EQ(r.max_non_ankle_change, 0.0);
    EXPECT_EQ(r.max_swing_change, 0.0);
  }
}

// With a posture commanded the target is the posture's own sole, so a bend or a squat is kept.
TEST(SoleLevelling, StandingInAPostureIsLeftAsItIs) {
  const Fixture fx;
  for (const PostureCommand s : {PostureCommand{0.3, 0.0, kStand}, PostureCommand{0.0, 0.15, kStand},
                                 PostureCommand{0.0, 0.0, 0.62}}) {
    const LevelRun r = run(fx, {{VelocityCommand{}, s}}, 200);
    EXPECT_LT(r.max_tilt_stance_before, 1e-3);
    EXPECT_LT(r.max_tilt_stance_after, 1e-4);
    EXPECT_EQ(r.max_non_ankle_change, 0.0);
  }
}

// Command steps (standing -> fast side-step -> bent backward turn -> crouched fast diagonal ->
// standing), ramped as the shaper does: the added ankle offset changes per tick by less than the
// generator's own reference does (continuous), and the added q̇ is its time derivative.
TEST(SoleLevelling, ContinuousThroughContactSwitchesAndCommandSteps) {
  const Fixture fx;
  const LevelRun r = run(fx,
                    {{VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}},
                     {VelocityCommand{0.0, 0.4, 0.0}, PostureCommand{0.0, 0.0, kStand}},
                     {VelocityCommand{-0.5, 0.0, -0.8}, PostureCommand{0.3, 0.0, kStand}},
                     {VelocityCommand{1.0, -0.4, 0.8}, PostureCommand{0.0, 0.0, 0.62}},
                     {VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}}},
                    150);
  EXPECT_GT(r.max_extra_step, 0.0);
  EXPECT_LT(r.max_extra_step, 0.5 * r.max_generator_step);
  EXPECT_LT(r.max_extra_step, 0.03);  // 3 rad/s
  EXPECT_LT(r.max_qd_mismatch, 1e-9);
}

TEST(SoleLevelling, OptionsNameTheFieldAndYamlReadsTheSubMap) {
  SoleLevellingOptions o;
  o.edge_fraction = 0.0;
  try {
    o.validate();
    FAIL() << "expected a throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("gco.sole_levelling.edge_fraction"), std::string::npos) << e.what();
  }
  o = {};
  o.iterations = 0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  const GcoOptions y = parseGcoOptionsYaml("gco:\n  sole_levelling: {enabled: true, edge_fraction: 0.25}\n", "t.yaml");
  EXPECT_TRUE(y.sole_levelling.enabled);
  EXPECT_DOUBLE_EQ(y.sole_levelling.edge_fraction, 0.25);
  EXPECT_ANY_THROW(parseGcoOptionsYaml("gco:\n  sole_levelling: {enabled: true, ramp: 0.2}\n", "t.yaml"));
}

// GeneratorParams::upright_walking: the walking clips' waist pitch/roll are shifted so that their
// cycle mean is the standing pose's. Measured on the shipped clips: a side-step at 0.4 m/s leans
// the waist forward by ~0.24 rad on average (0.28 in diag_turn); upright, < 0.01 rad; the legs are
// untouched.
TEST(UprightWalking, RemovesTheWaistLeanAndLeavesTheLegs) {
  const Fixture fx;
  GeneratorParams up;
  up.upright_walking = true;
  auto upright = std::make_shared<const GeneratorModel>(loadClipLibrary(pmg::test::g1ClipDir(), fx.robot),
                                                        pmg::generatorJointSpace(fx.robot), up);
  const auto& names = fx.model->jointSpace().joint_names;
  const auto wp = std::find(names.begin(), names.end(), "waist_pitch_joint") - names.begin();
  const double q0 = fx.model->jointSpace().q_stand[wp];
  for (const VelocityCommand u : {VelocityCommand{0.0, 0.4, 0.0}, VelocityCommand{-0.5, 0.0, 0.0},
                                  VelocityCommand{0.5, 0.3, 0.5}}) {
    MotionGenerator a(fx.model), b(upright);
    double lean_clip = 0.0, lean_upright = 0.0, legs = 0.0;
    const int n = 600;
    for (int k = 0; k < n; ++k) {
      a.step(u, {0.0, 0.0, kStand}, 0.01);
      b.step(u, {0.0, 0.0, kStand}, 0.01);
      lean_clip += (a.output().q_ref[wp] - q0) / n;
      lean_upright += (b.output().q_ref[wp] - q0) / n;
      for (std::size_t f = 0; f < kNumFeet; ++f)
        for (int j = 0; j < kLegDofs; ++j)
          legs = std::max(legs, std::abs(a.output().q_ref[fx.idx[f][j]] - b.output().q_ref[fx.idx[f][j]]));
    }
    SCOPED_TRACE("command " + std::to_string(u.vx) + " " + std::to_string(u.vy) + " " + std::to_string(u.wz));
    EXPECT_GT(lean_clip, 0.1);
    EXPECT_LT(std::abs(lean_upright), 0.02);
    EXPECT_EQ(legs, 0.0);
  }
}

}  // namespace
}  // namespace pmg::gco
