// Stride adaptation of the reference (stride_adaptation.hpp) on the shipped G1 clips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "g1_fixture.hpp"
#include "g1_reference_fixture.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/foot_slip.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg::gco {
namespace {

using Fixture = test::G1Reference;

constexpr double kStand = 0.78;  // standing pelvis height of the G1 [m]

using Schedule = std::vector<std::pair<VelocityCommand, PostureCommand>>;

struct RunResult {
  FootSlipStats plain, adapted;        // soles metered under the commanded base motion
  double max_added_step = 0.0;         // largest per-tick change of q_adapted − q_generator [rad]
  double max_qd_mismatch = 0.0;        // added q̇ against the finite difference of the added q [rad/s]
  double max_generator_step = 0.0;     // largest per-tick change of the generator's own q_ref [rad]
  double max_added = 0.0;              // largest |q_adapted − q_generator| [rad]
  double max_non_leg_change = 0.0;     // largest change of a joint outside the leg chains [rad]
  std::vector<std::array<Eigen::Vector3d, 2>> liftoff, touchdown;  // offsets at each foot's switches
  std::vector<std::array<int, 2>> switch_foot;
  StrideAdaptationCounters counters;   // of the whole run
  double planted_travel = 0.0;         // adapted soles' horizontal travel in W while in contact, both feet [m]
  double planted_max_speed = 0.0;      // its largest per-tick speed [m/s]
};

// Horizontal travel in W of the soles while in contact (both feet summed) in a FootSlipMeter trace,
// and the largest per-tick speed: what a planted foot would have to slide.
void plantedTravel(const std::vector<FootSlipSample>& trace, double dt, double* travel, double* max_speed) {
  *travel = 0.0;
  *max_speed = 0.0;
  for (std::size_t k = 1; k < trace.size(); ++k)
    for (std::size_t f = 0; f < 2; ++f)
      if (trace[k].contact[f] && trace[k - 1].contact[f]) {
        const double d = (trace[k].p_WS[f] - trace[k - 1].p_WS[f]).head<2>().norm();
        *travel += d;
        *max_speed = std::max(*max_speed, d / dt);
      }
}

// The pipe with the stride adaptation next to a plain generator on the same commands (each step
// ramped over 0.5 s, as the controller's shaper does); both references are metered by FootSlipMeter
// with the pelvis moved by the command itself (v_x, v_y, ω, the template height).
RunResult run(const Fixture& fx, const Schedule& schedule, int ticks_each, double lead = 0.5, int skip = 100,
              double sole_half_length = StrideAdaptationOptions{}.sole_half_length, bool standing_hold = true) {
  GcoOptions o;
  o.stride_adaptation.enabled = true;
  o.stride_adaptation.standing_hold = standing_hold;
  o.stride_adaptation.touchdown_lead = lead;
  o.stride_adaptation.sole_half_length = sole_half_length;
  GeneratorWithGco pipe(fx.model, fx.legs, o);
  MotionGenerator plain(fx.model);
  FootSlipMeter meter_plain(fx.legs, o.dt), meter_adapted(fx.legs, o.dt);
  GcoInput in_plain;
  RunResult r;
  Eigen::VectorXd prev_added, prev_gen;
  std::vector<bool> is_leg(fx.model->jointSpace().joint_names.size(), false);
  for (const auto& foot : fx.idx)
    for (int j : foot) is_leg[static_cast<std::size_t>(j)] = true;
  std::array<bool, 2> last_contact{true, true};
  std::array<Eigen::Vector3d, 2> last_offset{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  VelocityCommand ud0;
  PostureCommand us0{0.0, 0.0, kStand};
  int tick = 0;
  for (const auto& [ud1, us1] : schedule) {
    for (int k = 0; k < ticks_each; ++k, ++tick) {
      VelocityCommand ud;
      PostureCommand us;
      test::rampedCommand(ud0, us0, ud1, us1, k, &ud, &us);
      pipe.step(ud, us, o.dt);
      plain.step(ud, us, o.dt);
      const GeneratorOutput& ad = pipe.generatorOutput();
      const GeneratorOutput& gen = plain.output();
      const Eigen::VectorXd added = ad.q_ref - gen.q_ref;
      for (Eigen::Index j = 0; j < added.size(); ++j)
        if (!is_leg[static_cast<std::size_t>(j)]) r.max_non_leg_change = std::max(r.max_non_leg_change, std::abs(added(j)));
      r.max_added = std::max(r.max_added, added.cwiseAbs().maxCoeff());
      if (prev_added.size() > 0) {
        const Eigen::VectorXd step = added - prev_added;
        r.max_added_step = std::max(r.max_added_step, step.cwiseAbs().maxCoeff());
        r.max_qd_mismatch = std::max(r.max_qd_mismatch, ((ad.qd_ref - gen.qd_ref) - step / o.dt).cwiseAbs().maxCoeff());
        r.max_generator_step = std::max(r.max_generator_step, (gen.q_ref - prev_gen).cwiseAbs().maxCoeff());
      }
      prev_added = added;
      prev_gen = gen.q_ref;
      BaseCommand base;
      base.v_x = ud.vx;
      base.v_y = ud.vy;
      base.yaw_rate = ud.wz;
      base.height = gen.base_height;
      fillFromGenerator(gen, fx.idx, ud, us, &in_plain);
      if (tick >= skip) {
        meter_plain.add(in_plain, base);
        meter_adapted.add(pipe.gcoInput(), base);
      }
      const StrideAdaptation& sa = pipe.strideAdaptation();
      for (std::size_t f = 0; f < 2; ++f) {
        // The offset a foot lifts off with (its last stance tick) and lands with (its last swing tick).
        if (tick >= skip && last_contact[f] != ad.in_contact[f]) {
          (ad.in_contact[f] ? r.touchdown : r.liftoff).push_back(last_offset);
          r.switch_foot.push_back({static_cast<int>(f), ad.in_contact[f] ? 1 : 0});
        }
        last_contact[f] = ad.in_contact[f];
      }
      last_offset = {sa.offset(Foot::kLeft), sa.offset(Foot::kRight)};
    }
    ud0 = ud1;
    us0 = us1;
  }
  r.counters = pipe.strideAdaptation().counters();
  plantedTravel(meter_adapted.trace(), o.dt, &r.planted_travel, &r.planted_max_speed);
  r.plain = meter_plain.stats();
  r.adapted = meter_adapted.stats();
  return r;
}

// Walking straight, sideways and turning: in single support the stance sole of the adapted
// reference stays where it is in the world while the pelvis moves by the command (metered
// independently of the adaptation by FootSlipMeter, at the sole point S, so S is the held point here:
// sole_half_length 0): its slip per stance is below 2 mm against 40-50 mm for the generator's own
// reference. (FootSlipMeter's speeds come from q̇, whose analytic value leads the tick's finite
// difference by half a tick; they fall by more than 5 times.) A crouched combined command the captured
// clips carry with their stance foot lifted 3 cm and more inside its window: the bounds act (counted),
// and the slip still halves. Only the leg joints change.
TEST(StrideAdaptation, StanceSolesStillUnderTheCommand) {
  const Fixture fx;
  for (const VelocityCommand u : {VelocityCommand{0.5, 0.0, 0.0}, VelocityCommand{0.0, 0.3, 0.0}, VelocityCommand{-0.3, 0.0, 0.5}}) {
    SCOPED_TRACE("command " + std::to_string(u.vx) + " " + std::to_string(u.vy) + " " + std::to_string(u.wz));
    const RunResult r = run(fx, {{u, PostureCommand{0.0, 0.0, kStand}}}, 400, 0.5, 100, 0.0);
    ASSERT_GT(r.adapted.stances, 2);
    EXPECT_GT(r.plain.mean_slip_per_stance, 0.03);
    EXPECT_LT(r.adapted.mean_slip_per_stance, 0.002);
    EXPECT_LT(r.adapted.mean_single_support_speed, 0.2 * r.plain.mean_single_support_speed);
    EXPECT_EQ(r.counters.speed_limited + r.counters.offset_limited + r.counters.failures, 0u);
    EXPECT_EQ(r.max_non_leg_change, 0.0);
  }
  const RunResult r = run(fx, {{VelocityCommand{0.5, 0.3, 0.5}, PostureCommand{0.0, 0.0, 0.66}}}, 400, 0.5, 100, 0.0);
  EXPECT_GT(r.counters.offset_limited, 0u);
  EXPECT_LT(r.adapted.mean_slip_per_stance, 0.5 * r.plain.mean_slip_per_stance);
  EXPECT_EQ(r.max_non_leg_change, 0.0);
}

// Standing, with posture commands (squat, bend, lean) and no velocity: nothing to adapt, the
// reference is the generator's to the bit.
TEST(StrideAdaptation, StandingInAPostureIsLeftAsItIs) {
  const Fixture fx;
  const RunResult r = run(fx,
                    {{VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}},
                     {VelocityCommand{}, PostureCommand{0.3, 0.0, kStand}},
                     {VelocityCommand{}, PostureCommand{0.0, 0.15, kStand}},
                     {VelocityCommand{}, PostureCommand{0.0, 0.0, 0.62}}},
                    150, 0.5, 0);
  EXPECT_LT(r.max_added, 1e-12);
}

// Stopping from a walk (backward 0.5 m/s, side-step 0.3 m/s, forward 0.5 m/s, each ramped to 0 over
// 0.5 s): once the generator stands, both feet are planted. With standing_hold the adapted reference
// keeps them where its last steps put them: the soles, metered from the stop command on, move less
// than a third as far as with the offsets decaying (standing_hold false, before 2026-12-04, which
// slid the planted feet back under the hips), and under 2 cm in total.
TEST(StrideAdaptation, StoppingLeavesThePlantedFeetWhereTheyLanded) {
  const Fixture fx;
  for (const VelocityCommand u : {VelocityCommand{-0.5, 0.0, 0.0}, VelocityCommand{0.0, 0.3, 0.0}, VelocityCommand{0.5, 0.0, 0.0}}) {
    SCOPED_TRACE("command " + std::to_string(u.vx) + " " + std::to_string(u.vy) + " " + std::to_string(u.wz));
    const Schedule walk_then_stop{{u, PostureCommand{0.0, 0.0, kStand}}, {VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}}};
    double slide[2];
    for (int hold = 0; hold < 2; ++hold) {
      const RunResult r = run(fx, walk_then_stop, 400, 0.5, 400, StrideAdaptationOptions{}.sole_half_length, hold == 1);
      slide[hold] = r.planted_travel;
      std::printf("standing_hold %d: planted soles moved %.1f mm after the stop command (largest %.0f mm/s)\n", hold,
                  1e3 * r.planted_travel, 1e3 * r.planted_max_speed);
      EXPECT_EQ(r.max_non_leg_change, 0.0);
    }
    EXPECT_LT(slide[1], slide[0] / 3.0);
    EXPECT_LT(slide[1], 0.02);
  }
}

// Command steps (standing -> fast side-step -> bent backward turn -> crouched fast diagonal ->
// standing), ramped as the shaper does: the added leg offset changes per tick by at most
// max_correction_rate * dt, less than the generator's own reference does, and the added q̇ is
// its time derivative.
TEST(StrideAdaptation, ContinuousThroughContactSwitchesAndCommandSteps) {
  const Fixture fx;
  const RunResult r = run(fx,
                    {{VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}},
                     {VelocityCommand{0.0, 0.4, 0.0}, PostureCommand{0.0, 0.0, kStand}},
                     {VelocityCommand{-0.5, 0.0, -0.8}, PostureCommand{0.3, 0.0, kStand}},
                     {VelocityCommand{1.0, -0.4, 0.8}, PostureCommand{0.0, 0.0, 0.62}},
                     {VelocityCommand{}, PostureCommand{0.0, 0.0, kStand}}},
                    150, 0.5, 0);
  const double bound = StrideAdaptationOptions{}.max_correction_rate * 0.01;
  EXPECT_GT(r.max_added_step, 0.0);
  EXPECT_LE(r.max_added_step, bound + 1e-12);
  EXPECT_LT(r.max_added_step, 0.5 * r.max_generator_step);
  EXPECT_LT(r.max_qd_mismatch, 1e-9);
  EXPECT_LE(r.max_added, StrideAdaptationOptions{}.max_correction + 1e-12);
}

// touchdown_lead λ: the swing foot lands ahead of the clip's placement by λ times the offset it
// lifted off with (0: on the clip's placement), which centres the stance under the hip and makes the
// offset at lift-off smaller.
TEST(StrideAdaptation, SwingFootLandsAheadByTheLeadTimesTheLastDrift) {
  const Fixture fx;
  const Schedule walk{{VelocityCommand{0.5, 0.3, 0.5}, PostureCommand{0.0, 0.0, 0.66}}};
  double lo_norm[2] = {0.0, 0.0};
  for (const double lead : {0.0, 0.5}) {
    SCOPED_TRACE("lead " + std::to_string(lead));
    const RunResult r = run(fx, walk, 600, lead, 200);
    // Pair each touchdown with the same foot's last lift-off.
    std::array<Eigen::Vector3d, 2> last_lo{Eigen::Vector3d::Constant(NAN), Eigen::Vector3d::Constant(NAN)};
    int pairs = 0;
    std::size_t i_lo = 0, i_td = 0;
    double lo_sum = 0.0;
    int lo_n = 0;
    for (const auto& [f, td] : r.switch_foot) {
      const std::size_t ff = static_cast<std::size_t>(f);
      if (!td) {
        last_lo[ff] = r.liftoff[i_lo++][ff];
        lo_sum += last_lo[ff].head<2>().norm();
        ++lo_n;
        continue;
      }
      const Eigen::Vector3d e_td = r.touchdown[i_td++][ff];
      if (!last_lo[ff].allFinite()) continue;
      const Eigen::Vector2d expected = -lead * last_lo[ff].head<2>();
      EXPECT_LT((e_td.head<2>() - expected).norm(), 0.002) << "foot " << f << " lift-off " << last_lo[ff].transpose()
                                                            << " touchdown " << e_td.transpose();
      ++pairs;
    }
    EXPECT_GE(pairs, 4);
    ASSERT_GT(lo_n, 0);
    lo_norm[lead > 0.0 ? 1 : 0] = lo_sum / lo_n;
  }
  EXPECT_GT(lo_norm[0], 0.01);  // the drift is there
  EXPECT_LT(lo_norm[1], lo_norm[0]);
}

// The defaults (sole levelling and stride adaptation off) leave the generator's output to the bit.
TEST(StrideAdaptation, DisabledLeavesTheGeneratorOutput) {
  const Fixture fx;
  GeneratorWithGco pipe(fx.model, fx.legs, GcoOptions{});
  MotionGenerator plain(fx.model);
  for (int k = 0; k < 200; ++k) {
    pipe.step({0.5, 0.3, 0.5}, {}, 0.01);
    plain.step({0.5, 0.3, 0.5}, {}, 0.01);
    ASSERT_EQ((pipe.generatorOutput().q_ref - plain.output().q_ref).cwiseAbs().maxCoeff(), 0.0);
  }
  EXPECT_FALSE(pipe.strideAdaptation().enabled());
  EXPECT_FALSE(pipe.soleLevelling().enabled());
}

// A non-finite command: the last tick's correction is held (no jump in the reference), the state
// is kept, and the failure is counted.
TEST(StrideAdaptation, BadInputHoldsTheLastCorrection) {
  const Fixture fx;
  StrideAdaptationOptions so;
  so.enabled = true;
  StrideAdaptation sa(fx.legs, so, fx.idx);
  MotionGenerator gen(fx.model);
  StrideAdaptationInput in;
  Eigen::VectorXd q, qd;
  for (int k = 0; k < 150; ++k) {
    gen.step({0.5, 0.0, 0.5}, {}, 0.01);
    const GeneratorOutput& g = gen.output();
    in.phase = g.phase;
    in.contact = g.contact;
    in.in_contact = g.in_contact;
    in.base_height = g.base_height;
    in.v_H = {0.5, 0.0};
    in.yaw_rate = 0.5;
    q = g.q_ref;
    qd = g.qd_ref;
    ASSERT_TRUE(sa.apply(in, 0.01, &q, &qd));
  }
  const LegVector held = sa.correction(Foot::kLeft);
  ASSERT_GT(held.norm(), 1e-3);
  const Eigen::Vector3d e = sa.offset(Foot::kLeft);
  in.yaw_rate = NAN;
  q = gen.output().q_ref;
  qd = gen.output().qd_ref;
  EXPECT_FALSE(sa.apply(in, 0.01, &q, &qd));
  for (int j = 0; j < kLegDofs; ++j) EXPECT_NEAR(q(fx.idx[0][j]) - gen.output().q_ref(fx.idx[0][j]), held(j), 1e-12);
  EXPECT_EQ((qd - gen.output().qd_ref).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(sa.offset(Foot::kLeft), e);
  EXPECT_EQ(sa.counters().failures, 1u);
}

TEST(StrideAdaptation, OptionsNameTheFieldAndYamlReadsTheSubMap) {
  StrideAdaptationOptions o;
  o.touchdown_lead = 1.0;
  try {
    o.validate();
    FAIL() << "expected a throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("gco.stride_adaptation.touchdown_lead"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("[0, 1)"), std::string::npos) << e.what();
  }
  o = {};
  o.max_correction_rate = 0.0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o = {};
  o.iterations = 11;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  const GcoOptions y =
      parseGcoOptionsYaml("gco:\n  stride_adaptation: {enabled: true, touchdown_lead: 0.25}\n", "t.yaml");
  EXPECT_TRUE(y.stride_adaptation.enabled);
  EXPECT_DOUBLE_EQ(y.stride_adaptation.touchdown_lead, 0.25);
  EXPECT_ANY_THROW(parseGcoOptionsYaml("gco:\n  stride_adaptation: {enabled: true, lead: 0.2}\n", "t.yaml"));
  EXPECT_ANY_THROW(parseGcoOptionsYaml("gco:\n  stride_adaptation: {return_fraction: 0}\n", "t.yaml"));
}

}  // namespace
}  // namespace pmg::gco
