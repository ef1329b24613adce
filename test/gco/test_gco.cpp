// GCO behaviour on synthetic G1 templates with a known kinematic error (PMG eqs. 13-19).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "gco_test_util.hpp"
#include "pmg/common/config_error.hpp"

namespace pmg::gco {
namespace {

using test::g1Legs;
using test::runGait;

SyntheticGait gaitWith(SyntheticGaitOptions o) {
  LegKinematics kin(g1Legs());
  return makeSyntheticGait(kin, o);
}

TEST(SyntheticGait, TemplateStanceFeetSlideByTheSetAmountWithoutGco) {
  // The harness itself: with the reported (wrong) base velocity each stance slides by
  // |v_error| * T_stance; with the true velocity, by nothing.
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;  // template reports 0.3 m/s for a 0.4 m/s gait
  const SyntheticGait g = gaitWith(o);
  EXPECT_LT(g.ik_max_error, 1e-6);
  GcoOptions off;
  off.enabled = false;
  const auto rr = runGait(g, off, 3);
  const double expected = 0.1 * o.duty * o.period;  // 48 mm
  EXPECT_NEAR(rr.without_gco.mean_slip_per_stance, expected, 1.5e-3);
  EXPECT_NEAR(rr.without_gco.mean_stance_speed, 0.1, 2e-3);
  EXPECT_GE(rr.without_gco.stances, 4);
  // Disabled GCO publishes the template unchanged.
  EXPECT_DOUBLE_EQ(rr.last.u_opt.v_x, 0.3);
  EXPECT_EQ(rr.last.status, GcoStatus::kDisabled);
  // The consistency metric sees the true velocity.
  EXPECT_NEAR(rr.without_gco.mean_implied_v_x, 0.4, 2e-3);

  SyntheticGaitOptions exact = o;
  exact.v_x_error = 0.0;
  const auto rr0 = runGait(gaitWith(exact), off, 3);
  EXPECT_LT(rr0.without_gco.max_slip_per_stance, 0.5e-3);
}

TEST(Gco, RemovesForwardSlideAndRecoversTheTrueBaseVelocity) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  const auto rr = runGait(gaitWith(o), GcoOptions{}, 4);
  EXPECT_GT(rr.without_gco.mean_slip_per_stance, 0.04);
  EXPECT_LT(rr.with_gco.max_slip_per_stance, 1e-3);  // issue target: < 1 mm per stance
  EXPECT_NEAR(rr.last.u_opt.v_x, 0.4, 1e-3);         // recovers the true velocity
  EXPECT_NEAR(rr.last.u_opt.v_y, 0.0, 1e-3);
  EXPECT_NEAR(rr.last.delta(0), 0.1, 1e-3);
  EXPECT_EQ(rr.counters.solver_failures, 0u);
  EXPECT_EQ(rr.last.status, GcoStatus::kOk);
}

TEST(Gco, RemovesLateralTurningSlideAndFloat) {
  SyntheticGaitOptions o;
  o.v_x = 0.25;
  o.v_y = 0.1;
  o.yaw_rate = 0.4;
  o.v_y_error = 0.08;
  o.yaw_rate_error = -0.2;
  o.height_error = 0.015;  // template pelvis 15 mm too high: stance feet float by 15 mm
  const auto rr = runGait(gaitWith(o), GcoOptions{}, 4);
  EXPECT_GT(rr.without_gco.mean_slip_per_stance, 0.02);
  EXPECT_NEAR(rr.without_gco.mean_height_error, 0.015, 1e-4);
  EXPECT_LT(rr.with_gco.max_slip_per_stance, 1e-3);
  EXPECT_LT(rr.with_gco.max_height_error, 0.1e-3);
  EXPECT_NEAR(rr.last.u_opt.v_y, 0.1, 2e-3);
  EXPECT_NEAR(rr.last.u_opt.yaw_rate, 0.4, 5e-3);
  EXPECT_NEAR(rr.last.u_opt.height, o.base_height, 1e-4);
  EXPECT_LT(rr.with_gco.mean_stance_speed, 0.05 * rr.without_gco.mean_stance_speed);
}

TEST(Gco, PitchedPelvisKeepsStanceFootOnTheGround) {
  // A bent posture tilts the pelvis: eq. 13 with R_HB = Ry(pitch). The sole of the stance foot
  // must stay on the ground and at rest (output of the solve), whatever the pitch.
  SyntheticGaitOptions o;
  o.v_x_error = 0.05;
  const SyntheticGait g = gaitWith(o);
  Gco gco(g1Legs(), GcoOptions{});
  for (int rep = 0; rep < 2; ++rep) {
    for (const GcoInput& tick : g.ticks) {
      GcoInput in = tick;
      in.base_pitch = 0.15;
      in.command.pitch = 0.3;
      GcoResult res;
      ASSERT_EQ(gco.solve(in, &res), GcoStatus::kOk);
      EXPECT_DOUBLE_EQ(res.u_opt.pitch, 0.3);  // pitch passes through (eq. 19)
      const bool single = in.contact[0] != in.contact[1];
      if (rep == 1 && single && !res.jump_limited) {
        const std::size_t f = in.contact[0] ? 0 : 1;
        EXPECT_LT(std::abs(res.sole_height[f]), 1e-5);
        EXPECT_LT(res.v_WS_H[f].head<2>().norm(), 1e-4);
      }
    }
  }
}

TEST(Gco, CommandLimitsWinOverContact) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  GcoOptions opt;
  opt.limits.v_x_max = 0.35;  // the feet ask for 0.4 m/s
  const auto rr = runGait(gaitWith(o), opt, 3);
  EXPECT_LE(rr.last.u_opt.v_x, 0.35);
  EXPECT_GT(rr.last.u_opt.v_x, 0.34);
  // Slip is reduced but not removed: the remaining 0.05 m/s error (24 mm per stance if it were
  // all slide) is partly turned into foot yaw by Δω in single support.
  EXPECT_LT(rr.with_gco.mean_slip_per_stance, 0.6 * rr.without_gco.mean_slip_per_stance);
  EXPECT_GT(rr.with_gco.mean_slip_per_stance, 0.2 * rr.without_gco.mean_slip_per_stance);
}

TEST(Gco, ContactSwitchAndPhaseWrapStayWithinTheJumpBound) {
  // Flight phases (duty < 0.5): GCO decays toward the template in flight and snaps back at
  // touchdown, the largest switch there is. The published u' never jumps by more than max_jump.
  SyntheticGaitOptions o;
  o.duty = 0.4;
  o.v_x = 0.6;
  o.stance_x = 0.0;
  o.v_x_error = -0.3;
  o.height_error = 0.02;
  const SyntheticGait g = gaitWith(o);
  GcoOptions opt;
  const auto rr = runGait(g, opt, 5);
  EXPECT_LE(rr.max_jump_v, opt.max_jump_velocity + 1e-12);
  EXPECT_LE(rr.max_jump_w, opt.max_jump_yaw_rate + 1e-12);
  EXPECT_LE(rr.max_jump_h, opt.max_jump_height + 1e-12);
  // Slip still mostly removed despite the bound.
  EXPECT_LT(rr.with_gco.mean_slip_per_stance, 0.2 * rr.without_gco.mean_slip_per_stance);
  // Without the bound the raw solution does jump more at the switches: the bound is active.
  GcoOptions loose = opt;
  loose.max_jump_velocity = 10.0;
  loose.max_jump_height = 1.0;
  const auto raw = runGait(g, loose, 5);
  EXPECT_GT(raw.max_jump_v, opt.max_jump_velocity);
  EXPECT_GT(rr.counters.jump_limited, 0u);
}

TEST(Gco, PeriodicTemplateWithoutSwitchConflictsDoesNotHitTheBound) {
  // Walking with double support and a consistent template error: contact switches and the
  // φ wrap change u' by less than 1 mm/s and 0.1 mm (the solution is the same on both feet).
  SyntheticGaitOptions o;
  o.v_x_error = 0.08;
  o.height_error = -0.01;
  const SyntheticGait g = gaitWith(o);
  Gco gco(g1Legs(), GcoOptions{});
  GcoResult res, prev;
  for (int c = 0; c < 4; ++c) {
    for (std::size_t k = 0; k < g.ticks.size(); ++k) {
      gco.solve(g.ticks[k], &res);
      if (c > 0) {
        EXPECT_LT(std::abs(res.u_opt.v_x - prev.u_opt.v_x), 1e-3) << "cycle " << c << " tick " << k;
        EXPECT_LT(std::abs(res.u_opt.height - prev.u_opt.height), 1e-4) << "cycle " << c << " tick " << k;
      }
      prev = res;
    }
  }
  EXPECT_EQ(gco.counters().jump_limited, 0u);
}

TEST(Gco, FlightDecaysTowardTheTemplate) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  const SyntheticGait g = gaitWith(o);
  Gco gco(g1Legs(), GcoOptions{});
  GcoResult res;
  GcoInput in = g.ticks[0];
  ASSERT_TRUE(in.contact[0] || in.contact[1]);
  gco.solve(in, &res);
  const double d0 = res.delta(0);
  EXPECT_NEAR(d0, 0.1, 2e-3);
  in.contact = {false, false};
  gco.solve(in, &res);
  // One flight tick: x ← x · w_s² / (w_s² + w_p²) = 0.96 x with the default weights.
  EXPECT_NEAR(res.delta(0), d0 * 0.0025 / 0.0026, 1e-6);
}

TEST(Gco, SolverFailureFallsBackToLastGoodSolutionAndCounts) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  const SyntheticGait g = gaitWith(o);
  GcoOptions opt;
  Gco gco(g1Legs(), opt);
  GcoResult good;
  ASSERT_EQ(gco.solve(g.ticks[0], &good), GcoStatus::kOk);
  // A solver that may take only one step and tolerates no gradient must report failure.
  GcoOptions strict = opt;
  strict.max_iterations = 1;
  strict.failure_gradient_norm = 0.0;
  strict.newton_polish_iterations = 0;  // the polish alone would already reach the minimiser
  Gco bad(g1Legs(), strict);
  GcoResult res;
  EXPECT_EQ(bad.solve(g.ticks[0], &res), GcoStatus::kSolverFailure);
  EXPECT_EQ(bad.counters().solver_failures, 1u);
  EXPECT_DOUBLE_EQ(res.delta(0), 0.0);  // no good solution yet: x = 0, u' = template
  EXPECT_DOUBLE_EQ(res.u_opt.v_x, g.ticks[0].v_HB_H.x());
}

TEST(Gco, NonFiniteInputReusesTheLastGoodCommand) {
  SyntheticGaitOptions o;
  o.v_x_error = -0.1;
  const SyntheticGait g = gaitWith(o);
  Gco gco(g1Legs(), GcoOptions{});
  GcoResult good, res;
  gco.solve(g.ticks[0], &good);
  GcoInput in = g.ticks[1];
  in.qd_leg[1](3) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(gco.solve(in, &res), GcoStatus::kInvalidInput);
  EXPECT_DOUBLE_EQ(res.u_opt.v_x, good.u_opt.v_x);
  EXPECT_DOUBLE_EQ(res.u_opt.height, good.u_opt.height);
  EXPECT_EQ(gco.counters().invalid_inputs, 1u);
  in = g.ticks[1];
  in.base_height = std::nan("");
  EXPECT_EQ(gco.solve(in, &res), GcoStatus::kInvalidInput);
  EXPECT_EQ(gco.counters().invalid_inputs, 2u);
}

TEST(Gco, FillLegStateMapsRobotOrder) {
  const auto legs = g1Legs();
  std::vector<std::string> names{"waist_yaw_joint"};
  for (Foot f : {Foot::kLeft, Foot::kRight}) {
    for (const auto& n : legs->jointNames(f)) names.push_back(n);
  }
  const auto idx = legs->jointIndices(names);
  Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(13, 0.0, 1.2), qd = -q;
  GcoInput in;
  fillLegState(idx, q, qd, &in);
  EXPECT_DOUBLE_EQ(in.q_leg[0](0), q(1));
  EXPECT_DOUBLE_EQ(in.q_leg[1](5), q(12));
  EXPECT_DOUBLE_EQ(in.qd_leg[1](0), qd(7));
}

TEST(GcoOptions, ValidateNamesTheField) {
  GcoOptions o;
  o.w_foot_velocity = -1.0;
  try {
    o.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("w_foot_velocity"), std::string::npos) << e.what();
  }
  o = GcoOptions{};
  o.limits.height_min = 0.9;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  EXPECT_THROW(Gco(g1Legs(), o), std::invalid_argument);
}

TEST(GcoOptions, YamlReadsFieldsAndRejectsUnknownKeys) {
  const GcoOptions o = parseGcoOptionsYaml(
      "gco:\n  enabled: false\n  w_foot_height: 3.5\n  max_iterations: 7\n  limits: {v_x_max: 1.2}\n", "mem.yaml");
  EXPECT_FALSE(o.enabled);
  EXPECT_DOUBLE_EQ(o.w_foot_height, 3.5);
  EXPECT_EQ(o.max_iterations, 7);
  EXPECT_DOUBLE_EQ(o.limits.v_x_max, 1.2);
  EXPECT_DOUBLE_EQ(o.limits.v_x_min, GcoOptions{}.limits.v_x_min);
  try {
    parseGcoOptionsYaml("w_foot_hieght: 1\n", "cfg/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "cfg/gco.yaml:1: unknown key 'w_foot_hieght' at the top level (did you mean 'w_foot_height'?)");
  }
  try {
    parseGcoOptionsYaml("gco:\n  dt: 0.01\n  limits: {v_x_max: 1.2, heigth_max: 0.8}\n", "cfg/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_STREQ(e.what(), "cfg/gco.yaml:3: unknown key 'heigth_max' in 'gco.limits' (did you mean 'height_max'?)");
  }
  try {
    parseGcoOptionsYaml("gco: {dt: 0.01}\ngcoo: {}\n", "cfg/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_STREQ(e.what(), "cfg/gco.yaml:2: unknown key 'gcoo' at the top level (did you mean 'gco'?)");
  }
  try {
    parseGcoOptionsYaml("dt: 5\n", "cfg/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("cfg/gco.yaml:1: ", 0), 0u) << msg;
    EXPECT_NE(msg.find("dt"), std::string::npos) << msg;
  }
  try {
    parseGcoOptionsYaml("max_jump_height: .inf\n", "cfg/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_STREQ(e.what(), "cfg/gco.yaml:1: max_jump_height: expected a finite number, got '.inf'");
  }
  EXPECT_THROW(parseGcoOptionsYaml("enabled: maybe\n", "x.yaml"), pmg::ConfigError);
  try {
    loadGcoOptionsFile("no/such/gco.yaml");
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_STREQ(e.what(), "no/such/gco.yaml: cannot open file");
  }
}

/// The ```yaml block that starts with "gco:" in docs/gco.md.
std::string docsYamlBlock() {
  std::ifstream f(pmg::test::sourcePath("docs/gco.md"));
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string doc = ss.str();
  const std::string open = "```yaml\ngco:";
  const std::size_t a = doc.find(open);
  if (a == std::string::npos) return {};
  const std::size_t b = doc.find("```", a + open.size());
  return doc.substr(a + 8, b - a - 8);
}

TEST(GcoOptions, ShippedYamlAndDocsMatchTheDefaults) {
  const GcoOptions d;
  const std::string docs_yaml = docsYamlBlock();
  ASSERT_FALSE(docs_yaml.empty()) << "docs/gco.md has no ```yaml gco: block";
  for (int source = 0; source < 2; ++source) {
    const GcoOptions o = source == 0 ? loadGcoOptionsFile(pmg::test::g1GcoOptionsPath())
                                     : parseGcoOptionsYaml(docs_yaml, "docs/gco.md");
    SCOPED_TRACE(source == 0 ? "config/gco/g1.yaml" : "docs/gco.md");
    EXPECT_EQ(o.enabled, d.enabled);
    EXPECT_DOUBLE_EQ(o.dt, d.dt);
    EXPECT_DOUBLE_EQ(o.w_foot_velocity, d.w_foot_velocity);
    EXPECT_DOUBLE_EQ(o.w_foot_yaw_rate, d.w_foot_yaw_rate);
    EXPECT_DOUBLE_EQ(o.w_foot_height, d.w_foot_height);
    EXPECT_DOUBLE_EQ(o.w_prior_velocity, d.w_prior_velocity);
    EXPECT_DOUBLE_EQ(o.w_prior_yaw_rate, d.w_prior_yaw_rate);
    EXPECT_DOUBLE_EQ(o.w_prior_height, d.w_prior_height);
    EXPECT_DOUBLE_EQ(o.w_smooth_velocity, d.w_smooth_velocity);
    EXPECT_DOUBLE_EQ(o.w_smooth_yaw_rate, d.w_smooth_yaw_rate);
    EXPECT_DOUBLE_EQ(o.w_smooth_height, d.w_smooth_height);
    EXPECT_DOUBLE_EQ(o.w_limit, d.w_limit);
    EXPECT_DOUBLE_EQ(o.contact_ramp_time, d.contact_ramp_time);
    EXPECT_DOUBLE_EQ(o.max_jump_velocity, d.max_jump_velocity);
    EXPECT_DOUBLE_EQ(o.max_jump_yaw_rate, d.max_jump_yaw_rate);
    EXPECT_DOUBLE_EQ(o.max_jump_height, d.max_jump_height);
    EXPECT_EQ(o.max_iterations, d.max_iterations);
    EXPECT_EQ(o.newton_polish_iterations, d.newton_polish_iterations);
    EXPECT_DOUBLE_EQ(o.failure_gradient_norm, d.failure_gradient_norm);
    EXPECT_DOUBLE_EQ(o.limits.v_x_min, d.limits.v_x_min);
    EXPECT_DOUBLE_EQ(o.limits.v_x_max, d.limits.v_x_max);
    EXPECT_DOUBLE_EQ(o.limits.v_y_min, d.limits.v_y_min);
    EXPECT_DOUBLE_EQ(o.limits.v_y_max, d.limits.v_y_max);
    EXPECT_DOUBLE_EQ(o.limits.yaw_rate_min, d.limits.yaw_rate_min);
    EXPECT_DOUBLE_EQ(o.limits.yaw_rate_max, d.limits.yaw_rate_max);
    EXPECT_DOUBLE_EQ(o.limits.height_min, d.limits.height_min);
    EXPECT_DOUBLE_EQ(o.limits.height_max, d.limits.height_max);
    EXPECT_EQ(o.sole_levelling.enabled, d.sole_levelling.enabled);
    EXPECT_DOUBLE_EQ(o.sole_levelling.edge_fraction, d.sole_levelling.edge_fraction);
    EXPECT_EQ(o.sole_levelling.iterations, d.sole_levelling.iterations);
    EXPECT_DOUBLE_EQ(o.sole_levelling.max_correction, d.sole_levelling.max_correction);
    const StrideAdaptationOptions &sa = o.stride_adaptation, &sd = d.stride_adaptation;
    EXPECT_EQ(sa.enabled, sd.enabled);
    EXPECT_DOUBLE_EQ(sa.touchdown_lead, sd.touchdown_lead);
    EXPECT_DOUBLE_EQ(sa.return_fraction, sd.return_fraction);
    EXPECT_DOUBLE_EQ(sa.standing_time_constant, sd.standing_time_constant);
    EXPECT_DOUBLE_EQ(sa.max_offset, sd.max_offset);
    EXPECT_DOUBLE_EQ(sa.stepping_margin, sd.stepping_margin);
    EXPECT_DOUBLE_EQ(sa.max_offset_height, sd.max_offset_height);
    EXPECT_DOUBLE_EQ(sa.max_offset_yaw, sd.max_offset_yaw);
    EXPECT_DOUBLE_EQ(sa.max_offset_speed, sd.max_offset_speed);
    EXPECT_DOUBLE_EQ(sa.max_offset_yaw_rate, sd.max_offset_yaw_rate);
    EXPECT_EQ(sa.iterations, sd.iterations);
    EXPECT_DOUBLE_EQ(sa.max_correction, sd.max_correction);
    EXPECT_DOUBLE_EQ(sa.damping, sd.damping);
    EXPECT_DOUBLE_EQ(sa.height_weight, sd.height_weight);
    EXPECT_DOUBLE_EQ(sa.max_correction_rate, sd.max_correction_rate);
    EXPECT_DOUBLE_EQ(sa.sole_half_length, sd.sole_half_length);
    EXPECT_DOUBLE_EQ(sa.rolling_slope, sd.rolling_slope);
  }
}

}  // namespace
}  // namespace pmg::gco
