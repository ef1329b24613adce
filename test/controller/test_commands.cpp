// The command vocabulary (commands.cpp): shaping (NaN, range, staleness, slew limits, the explicit
// "no height command"), the reference rate limiter, and the one command-script format.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

CommandSample velocity(double vx, double vy, double wz, double t) {
  CommandSample s;
  s.command.vx = vx;
  s.command.vy = vy;
  s.command.wz = wz;
  s.velocity_time = t;
  return s;
}

/// The envelope tests' limits: standing at 0.78 m, |v| at most (1.0, 0.4, 0.8), the rest default.
CommandLimits envelopeLimits() {
  CommandLimits limits;
  limits.standing_height = 0.78;
  limits.max_velocity = {1.0, 0.4, 0.8};
  return limits;
}

/// Drives a CommandShaper at 100 Hz with one held velocity command and a posture set per call,
/// recording the largest per-tick step of the shaped velocity on each axis.
struct HeldCommandRun {
  CommandShaper& shaper;
  CommandSample sample;
  double dt = 0.01, t = 0.0;
  double largest[3] = {0, 0, 0};
  VelocityCommand prev{};
  HeldCommandRun(CommandShaper& sh, double vx, double vy, double wz) : shaper(sh), sample(velocity(vx, vy, wz, 0.0)) {
    prev = shaper.velocity();
  }
  void operator()(double pitch, std::optional<double> height, double seconds) {
    for (int k = 0; k < static_cast<int>(seconds / dt); ++k, t += dt) {
      sample.command.pitch = pitch;
      sample.command.height = height;
      sample.posture_time = sample.velocity_time = t;
      shaper.update(sample, t, dt);
      const VelocityCommand& v = shaper.velocity();
      largest[0] = std::max(largest[0], std::fabs(v.vx - prev.vx));
      largest[1] = std::max(largest[1], std::fabs(v.vy - prev.vy));
      largest[2] = std::max(largest[2], std::fabs(v.wz - prev.wz));
      prev = v;
    }
  }
  /// Every axis' largest step within its slew limit (max_acceleration × dt).
  void expectWithinSlew(const CommandLimits& limits) const {
    for (std::size_t i = 0; i < 3; ++i) EXPECT_LE(largest[i], limits.max_acceleration[i] * dt + 1e-12) << "axis " << i;
  }
};

TEST(CommandShaper, SlewLimitsTheVelocityStep) {
  CommandShaper shaper(CommandLimits{});
  CommandSample s = velocity(1.0, 0.0, 1.0, 0.0);
  shaper.update(s, 0.0, 0.01);
  EXPECT_NEAR(shaper.velocity().vx, 0.01, 1e-12);  // 1 m/s^2 * 10 ms
  EXPECT_NEAR(shaper.velocity().wz, 0.02, 1e-12);  // 2 rad/s^2 * 10 ms
  for (int k = 1; k < 200; ++k) {
    s.velocity_time = k * 0.01;
    shaper.update(s, k * 0.01, 0.01);
  }
  EXPECT_NEAR(shaper.velocity().vx, 1.0, 1e-12);
  EXPECT_FALSE(shaper.stale());
}

TEST(CommandShaper, StaleCommandRampsToZero) {
  CommandLimits limits;
  limits.timeout = 0.2;
  CommandShaper shaper(limits);
  CommandSample s = velocity(0.5, 0.0, 0.0, 0.0);
  for (int k = 0; k < 100; ++k) {
    s.velocity_time = k * 0.01;
    shaper.update(s, k * 0.01, 0.01);
  }
  ASSERT_NEAR(shaper.velocity().vx, 0.5, 1e-12);
  double now = 0.99;
  for (int k = 0; k < 25; ++k) shaper.update(s, now += 0.01, 0.01);  // no fresh sample
  EXPECT_TRUE(shaper.stale());
  EXPECT_LT(shaper.velocity().vx, 0.5);
  for (int k = 0; k < 100; ++k) shaper.update(s, now += 0.01, 0.01);
  EXPECT_NEAR(shaper.velocity().vx, 0.0, 1e-12);
  EXPECT_GT(shaper.counters().stale_ticks, 100u);
}

TEST(CommandShaper, NanIsRejectedOutOfRangeIsClamped) {
  CommandShaper shaper(CommandLimits{});
  CommandSample s = velocity(0.3, 0.0, 0.0, 0.0);
  for (int k = 0; k < 50; ++k) shaper.update(s, 0.01 * k, 0.01);
  s.command.vx = std::nan("");
  s.velocity_time = 0.5;
  shaper.update(s, 0.5, 0.01);
  EXPECT_EQ(shaper.counters().rejected_nan, 1u);
  EXPECT_NEAR(shaper.velocity().vx, 0.3, 1e-12);
  s.command = Command{0.0, 0.0, -7.0, 2.0, 0.0, 0.5};
  for (int k = 0; k < 400; ++k) {
    s.velocity_time = s.posture_time = 0.51 + 0.01 * k;
    shaper.update(s, s.velocity_time, 0.01);
  }
  EXPECT_NEAR(shaper.velocity().wz, -1.0, 1e-12);   // clamped to max_velocity
  EXPECT_NEAR(shaper.posture().pitch, 0.6, 1e-12);  // clamped to pitch_range
  EXPECT_NEAR(shaper.posture().height, 0.5, 1e-12);
  EXPECT_GE(shaper.counters().clamped, 1u);
  s.command.height = std::numeric_limits<double>::infinity();
  s.posture_time = 10.0;
  shaper.update(s, 10.0, 0.01);
  EXPECT_EQ(shaper.counters().rejected_nan, 2u) << "an infinite height is rejected like NaN";
}

// Defect 2 of issue 11: "none" -> 0.45 m used to jump in one tick. Now "none" is the standing
// height and every transition slews at height_rate.
TEST(CommandShaper, HeightNoneToValueAndBackIsSlewed) {
  CommandLimits limits;
  limits.standing_height = 0.78;
  CommandShaper shaper(limits);
  EXPECT_DOUBLE_EQ(shaper.posture().height, 0.78) << "starts at the standing height";
  CommandSample s;
  const double dt = 0.01, max_step = limits.height_rate * dt;
  double prev = shaper.posture().height, t = 0, largest = 0;
  const auto run = [&](std::optional<double> h, double seconds) {
    for (int k = 0; k < static_cast<int>(seconds / dt); ++k, t += dt) {
      s.command.height = h;
      s.posture_time = s.velocity_time = t;
      shaper.update(s, t, dt);
      largest = std::max(largest, std::fabs(shaper.posture().height - prev));
      prev = shaper.posture().height;
    }
  };
  run(std::nullopt, 0.5);
  run(0.45, 0.1);
  EXPECT_NEAR(shaper.posture().height, 0.78 - 10 * max_step, 1e-9) << "slewing down, not jumped";
  run(0.45, 3.0);
  EXPECT_NEAR(shaper.posture().height, 0.45, 1e-12);
  run(std::nullopt, 0.1);
  EXPECT_NEAR(shaper.posture().height, 0.45 + 10 * max_step, 1e-9) << "back to standing, slewed";
  run(std::nullopt, 3.0);
  EXPECT_NEAR(shaper.posture().height, 0.78, 1e-12);
  EXPECT_LE(largest, max_step + 1e-12);
}

// The crouched velocity envelope (CommandLimits::crouched_height): standing, a fast arc passes;
// crouched to crouched_height, it is slowed along its direction until Σ|u_i|/m_i = 1 and counted;
// crouching while the arc is held never steps the velocity faster than the slew limits.
TEST(CommandShaper, CrouchedEnvelopeSlowsACombinedCommandAlongItsDirection) {
  CommandLimits limits = envelopeLimits();
  limits.crouched_height = 0.62;
  limits.crouched_max_velocity = {0.3, 0.3, 0.6};
  CommandShaper shaper(limits);
  HeldCommandRun hold(shaper, 0.6, 0.2, 0.4);
  const auto run = [&](std::optional<double> h, double seconds) { hold(0.0, h, seconds); };
  run(std::nullopt, 2.0);
  EXPECT_NEAR(shaper.velocity().vx, 0.6, 1e-12) << "standing: the arc passes unchanged";
  EXPECT_NEAR(shaper.velocity().wz, 0.4, 1e-12);
  EXPECT_EQ(shaper.counters().crouch_limited_ticks, 0u);
  run(0.62, 3.0);
  ASSERT_NEAR(shaper.posture().height, 0.62, 1e-12);
  const VelocityCommand v = shaper.velocity();
  const double l1 = std::fabs(v.vx) / 0.3 + std::fabs(v.vy) / 0.3 + std::fabs(v.wz) / 0.6;
  EXPECT_NEAR(l1, 1.0, 1e-9) << "on the crouched envelope's boundary";
  EXPECT_NEAR(v.vy / v.vx, 0.2 / 0.6, 1e-9) << "the direction is kept";
  EXPECT_NEAR(v.wz / v.vx, 0.4 / 0.6, 1e-9);
  EXPECT_GT(shaper.counters().crouch_limited_ticks, 0u);
  EXPECT_EQ(shaper.counters().clamped, 0u) << "inside max_velocity: not a clamp";
  hold.expectWithinSlew(limits);
  run(std::nullopt, 3.0);
  EXPECT_NEAR(shaper.velocity().vx, 0.6, 1e-12) << "standing up gives the command back";

  // Off (crouched_height 0, the default): crouched to 0.62 m the arc passes.
  CommandLimits off = limits;
  off.crouched_height = 0.0;
  CommandShaper plain(off);
  HeldCommandRun(plain, 0.6, 0.2, 0.4)(0.0, 0.62, 4.0);
  EXPECT_NEAR(plain.velocity().vx, 0.6, 1e-12);

  // Per axis (crouched_per_axis): each axis alone against its limit, so the arc (0.6, 0.2, 0.4)
  // at 0.62 m is slowed by v_x alone (0.6 / 0.3 = 2) to (0.3, 0.1, 0.2), where the L1 rule gave a
  // sum of 1; half crouched (0.70 m) the limits and the rule are halfway; with the crouched limits
  // at the box (max_velocity) nothing inside the box is slowed, however crouched, while the crouch
  // fraction (the braking weight) still follows the height.
  CommandLimits per_axis = limits;
  per_axis.crouched_per_axis = true;
  CommandShaper axes(per_axis);
  HeldCommandRun arc(axes, 0.6, 0.2, 0.4);
  arc(0.0, 0.62, 4.0);
  EXPECT_NEAR(axes.velocity().vx, 0.3, 1e-9);
  EXPECT_NEAR(axes.velocity().vy, 0.1, 1e-9);
  EXPECT_NEAR(axes.velocity().wz, 0.2, 1e-9);
  EXPECT_GT(axes.counters().crouch_limited_ticks, 0u);
  arc(0.0, 0.70, 3.0);
  ASSERT_NEAR(axes.crouchFraction(), 0.5, 1e-9);
  // s = 0.5 * max(0.6/1, 0.2/0.4, 0.4/0.8) + 0.5 * max(0.6/0.65, 0.2/0.35, 0.4/0.7) with M = (1, 0.4, 0.8)
  const double M[3] = {limits.max_velocity[0], limits.max_velocity[1], limits.max_velocity[2]};
  const double m[3] = {0.5 * (M[0] + 0.3), 0.5 * (M[1] + 0.3), 0.5 * (M[2] + 0.6)};
  const double s_half = 0.5 * std::max({0.6 / M[0], 0.2 / M[1], 0.4 / M[2]}) + 0.5 * std::max({0.6 / m[0], 0.2 / m[1], 0.4 / m[2]});
  EXPECT_NEAR(axes.velocity().vx, s_half > 1.0 ? 0.6 / s_half : 0.6, 1e-9);
  arc.expectWithinSlew(per_axis);
  CommandLimits open = per_axis;
  open.crouched_max_velocity = limits.max_velocity;
  CommandShaper box(open);
  HeldCommandRun(box, 0.9, 0.3, 0.6)(0.0, 0.62, 4.0);
  EXPECT_NEAR(box.velocity().vx, 0.9, 1e-12) << "inside the box: not slowed";
  EXPECT_NEAR(box.velocity().vy, 0.3, 1e-12);
  EXPECT_EQ(box.counters().crouch_limited_ticks, 0u);
  EXPECT_NEAR(box.crouchFraction(), 1.0, 1e-12);
}

// The bent velocity envelope (CommandLimits::bent_pitch): upright and leaning back a fast walk
// passes; bending to bent_pitch while it is held slows it along its direction to bent_max_velocity,
// per axis, counted, never faster than the slew limits; half bent the limit is halfway; straightening
// gives the command back; crouched too, the tighter envelope wins; off, nothing is limited.
TEST(CommandShaper, BentEnvelopeSlowsAFastWalkWhileTheTorsoIsBent) {
  CommandLimits limits = envelopeLimits();
  limits.bent_pitch = 0.4;
  limits.bent_max_velocity = {0.6, 0.4, 0.8};
  CommandShaper shaper(limits);
  HeldCommandRun run(shaper, 1.0, 0.0, 0.4);
  run(0.0, std::nullopt, 2.0);
  EXPECT_NEAR(shaper.velocity().vx, 1.0, 1e-12) << "upright: the walk passes unchanged";
  run(-0.1, std::nullopt, 2.0);
  EXPECT_NEAR(shaper.velocity().vx, 1.0, 1e-12) << "leaning back: not limited";
  EXPECT_EQ(shaper.counters().bent_limited_ticks, 0u);
  run(0.4, std::nullopt, 3.0);
  ASSERT_NEAR(shaper.posture().pitch, 0.4, 1e-12);
  EXPECT_NEAR(shaper.velocity().vx, 0.6, 1e-9) << "bent: v_x at bent_max_velocity";
  EXPECT_NEAR(shaper.velocity().wz / shaper.velocity().vx, 0.4, 1e-9) << "the direction is kept";
  EXPECT_GT(shaper.counters().bent_limited_ticks, 0u);
  EXPECT_EQ(shaper.counters().crouch_limited_ticks, 0u);
  EXPECT_EQ(shaper.counters().clamped, 0u) << "inside max_velocity: not a clamp";
  run(0.2, std::nullopt, 3.0);
  EXPECT_NEAR(shaper.velocity().vx, 0.8, 1e-9) << "half bent: the limit is halfway";
  run(0.0, std::nullopt, 3.0);
  EXPECT_NEAR(shaper.velocity().vx, 1.0, 1e-12) << "straightening gives the command back";
  run.expectWithinSlew(limits);

  // Bent and crouched: the tighter of the two envelopes holds.
  CommandLimits both = limits;
  both.crouched_height = 0.62;
  both.crouched_max_velocity = {0.3, 0.3, 0.6};
  CommandShaper crouched(both);
  HeldCommandRun(crouched, 1.0, 0.0, 0.0)(0.4, 0.62, 6.0);
  EXPECT_NEAR(crouched.velocity().vx, 0.3, 1e-9) << "the crouched envelope is the tighter";
  EXPECT_GT(crouched.counters().crouch_limited_ticks, 0u);

  // Off (bent_pitch 0, the default): bent 0.4 rad the walk passes.
  CommandLimits off = limits;
  off.bent_pitch = 0.0;
  CommandShaper plain(off);
  HeldCommandRun(plain, 1.0, 0.0, 0.0)(0.4, std::nullopt, 4.0);
  EXPECT_NEAR(plain.velocity().vx, 1.0, 1e-12);
  EXPECT_EQ(plain.counters().bent_limited_ticks, 0u);
}

// crouchFraction(): how crouched the shaped posture is, the braking floor's weight
// (velocity_feedback.brake_crouch_scaled). 0 at the standing height however bent or leaning back,
// 1 at or below crouched_height, in between along the slewed height, so it moves by at most the
// height slew's share per tick.
TEST(CommandShaper, CrouchFractionFollowsTheShapedHeightAndNotTheBend) {
  CommandLimits limits = envelopeLimits();
  limits.crouched_height = 0.62;
  limits.bent_pitch = 0.4;
  CommandShaper shaper(limits);
  HeldCommandRun run(shaper, 0.0, 0.0, 0.0);
  run(0.0, std::nullopt, 1.0);
  EXPECT_EQ(shaper.crouchFraction(), 0.0) << "upright at the standing height";
  run(0.4, std::nullopt, 2.0);
  ASSERT_NEAR(shaper.posture().pitch, 0.4, 1e-12);
  EXPECT_EQ(shaper.crouchFraction(), 0.0) << "bent at the standing height";
  run(-0.1, std::nullopt, 2.0);
  EXPECT_EQ(shaper.crouchFraction(), 0.0) << "leaning back";
  run(0.3, 0.70, 3.0);
  ASSERT_NEAR(shaper.posture().height, 0.70, 1e-12);
  EXPECT_NEAR(shaper.crouchFraction(), 0.5, 1e-9) << "crouched halfway: 0.08 of 0.16 m";
  // From there to a deep crouch and back up: per tick at most the height slew's share.
  double prev = shaper.crouchFraction(), largest = 0.0;
  for (const double height : {0.55, 0.78}) {
    for (int k = 0; k < 200; ++k) {
      run(0.0, height, 0.01);
      largest = std::max(largest, std::fabs(shaper.crouchFraction() - prev));
      prev = shaper.crouchFraction();
      EXPECT_GE(prev, 0.0);
      EXPECT_LE(prev, 1.0);
    }
    if (height < 0.6) {
      EXPECT_EQ(shaper.crouchFraction(), 1.0) << "below crouched_height";
    }
  }
  EXPECT_EQ(shaper.crouchFraction(), 0.0) << "standing height again";
  EXPECT_LE(largest, limits.height_rate * 0.01 / 0.16 + 1e-12);
  EXPECT_GT(largest, 0.0);

  // The crouched envelope off (the default): 0 however deep.
  CommandShaper plain(envelopeLimits());
  HeldCommandRun(plain, 0.0, 0.0, 0.0)(0.4, 0.55, 4.0);
  EXPECT_EQ(plain.crouchFraction(), 0.0);
}

TEST(CommandLimits, ValidateNamesTheField) {
  CommandLimits l;
  EXPECT_EQ(l.validate(), "");
  l.max_velocity[1] = std::numeric_limits<double>::infinity();
  EXPECT_NE(l.validate().find("commands.max_velocity"), std::string::npos);
  l = CommandLimits{};
  l.height_range = {0.9, 1.0};
  EXPECT_NE(l.validate().find("standing height"), std::string::npos);
  l = CommandLimits{};
  l.max_reference_speed = 0;
  EXPECT_NE(l.validate().find("max_reference_speed"), std::string::npos);
  l = CommandLimits{};
  l.crouched_height = 0.8;  // above the standing height
  EXPECT_NE(l.validate().find("commands.crouched_height"), std::string::npos);
  l = CommandLimits{};
  l.crouched_height = 0.62;
  l.crouched_max_velocity = {1.5, 0.3, 0.6};  // beyond max_velocity
  EXPECT_NE(l.validate().find("commands.crouched_max_velocity"), std::string::npos);
  // Each value set alone on default limits is refused with the field's name.
  const auto rejects = [](double CommandLimits::*field, std::initializer_list<double> values, const char* name) {
    for (double v : values) {
      CommandLimits bad;
      bad.*field = v;
      EXPECT_NE(bad.validate().find(name), std::string::npos) << name << " = " << v;
    }
  };
  rejects(&CommandLimits::bent_pitch, {-0.1, 0.7, std::nan("")}, "commands.bent_pitch:");  // negative, beyond pitch_range, NaN
  rejects(&CommandLimits::walking_min_height, {0.3, 0.8, std::nan(""), -0.1},  // below height_range, above standing, NaN, negative
          "commands.walking_min_height:");
  l = CommandLimits{};
  l.bent_pitch = 0.4;
  EXPECT_EQ(l.validate(), "");
  l.bent_max_velocity = {1.2, 0.4, 0.8};  // beyond max_velocity
  EXPECT_NE(l.validate().find("commands.bent_max_velocity"), std::string::npos);
  l.bent_max_velocity = {0.0, 0.4, 0.8};
  EXPECT_NE(l.validate().find("commands.bent_max_velocity"), std::string::npos);
  l = CommandLimits{};
  l.walking_min_height = 0.66;
  EXPECT_EQ(l.validate(), "");
  l.walking_min_height_hold_s = 11.0;
  EXPECT_NE(l.validate().find("commands.walking_min_height_hold_s"), std::string::npos);
}

// The walking height floor (CommandLimits::walking_min_height): crouched to 0.62 m the robot walks at
// the floor, stands at the floor for the hold after the stop, then crouches to 0.62 m; a height above
// the floor and a crouch without walking pass; the shaped height never steps.
TEST(CommandShaper, WalkingHeightFloorRaisesACrouchedWalkAndHoldsAfterTheStop) {
  CommandLimits limits;
  limits.walking_min_height = 0.66;
  limits.walking_min_height_hold_s = 1.5;
  CommandShaper shaper(limits);
  const double dt = 0.01, step = limits.height_rate * dt;
  double t = 0.0, prev_h = shaper.posture().height, largest_step = 0.0;
  CommandSample s;
  const auto run = [&](double vx, std::optional<double> h, double seconds) {
    for (int k = 0; k < static_cast<int>(std::lround(seconds / dt)); ++k, t += dt) {
      s.command.vx = vx;
      s.command.height = h;
      s.posture_time = s.velocity_time = t;
      shaper.update(s, t, dt);
      largest_step = std::max(largest_step, std::fabs(shaper.posture().height - prev_h));
      prev_h = shaper.posture().height;
    }
  };
  run(0.0, 0.62, 3.0);  // a crouch without walking: as deep as commanded
  EXPECT_NEAR(shaper.posture().height, 0.62, 1e-12);
  EXPECT_EQ(shaper.counters().height_floor_ticks, 0u);
  run(0.3, 0.62, 3.0);  // walking crouched: raised to the floor
  EXPECT_NEAR(shaper.posture().height, 0.66, 1e-12);
  EXPECT_NEAR(shaper.velocity().vx, 0.3, 1e-12);
  EXPECT_GT(shaper.counters().height_floor_ticks, 0u);
  // Stop: the velocity slews to zero in 0.3 s; the floor holds 1.5 s after that. The shaper's tick
  // runs on the 100 Hz loop: with the floor acting it allocates nothing.
  double lowest_in_hold = 1.0;
  const double stop_t = t;
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    while (t < stop_t + 0.3 + 1.5 - 0.05) {
      run(0.0, 0.62, dt);
      lowest_in_hold = std::min(lowest_in_hold, shaper.posture().height);
    }
    allocations = guard.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_NEAR(shaper.velocity().vx, 0.0, 1e-12);
  EXPECT_NEAR(lowest_in_hold, 0.66, 1e-12) << "held at the floor after the stop";
  run(0.0, 0.62, 1.0);
  EXPECT_NEAR(shaper.posture().height, 0.62, 1e-12) << "then crouched as commanded";
  run(0.5, 0.70, 3.0);  // above the floor: unchanged
  EXPECT_NEAR(shaper.posture().height, 0.70, 1e-12);
  EXPECT_LE(largest_step, step + 1e-12) << "the shaped height never steps";
}

TEST(ReferenceRateLimiter, BoundsEveryJointsStep) {
  ReferenceRateLimiter limiter(6.0);
  double q[3] = {0.0, 1.0, -1.0};
  limiter.reset(q, 3);
  double next[3] = {0.5, 1.01, -2.0};
  EXPECT_TRUE(limiter.apply(next, 3, 0.01));
  EXPECT_NEAR(next[0], 0.06, 1e-12);
  EXPECT_NEAR(next[1], 1.01, 1e-12) << "a small step passes unchanged";
  EXPECT_NEAR(next[2], -1.06, 1e-12);
  double same[3] = {0.06, 1.01, -1.06};
  EXPECT_FALSE(limiter.apply(same, 3, 0.01));
  EXPECT_EQ(limiter.limitedTicks(), 1u);
}

// ------------------------------------------------------------------------------------ scripts

TEST(CommandScript, LoadsBothPlacementsOfTheOneFormat) {
  const CommandScript demo = loadCommandScript(test::sourcePath("config/commands/demo.yaml"));
  ASSERT_GE(demo.segments.size(), 4u);
  EXPECT_NEAR(demo.at(0.0).vx, 0.0, 1e-12);
  EXPECT_NEAR(demo.at(3.0).vx, 0.5, 1e-12);
  EXPECT_FALSE(demo.at(3.0).height.has_value()) << "no height in the file: no height command";
  EXPECT_NEAR(demo.at(1e6).vx, demo.segments.back().command.vx, 1e-12);
  EXPECT_EQ(demo.segments[1].name, "forward");

  const CommandScript eval = loadCommandScript(test::sourcePath("config/policies/eval_commands.yaml"));
  EXPECT_NEAR(eval.duration(), 48.0, 1e-12);
  EXPECT_NEAR(eval.ramp, 0.5, 1e-12);
  EXPECT_EQ(eval.segments[1].name, "forward");
  EXPECT_NEAR(eval.segments[1].start, 3.0, 1e-12);
  EXPECT_NEAR(eval.at(3.25).vx, 0.25, 1e-12) << "ramped over 0.5 s";
  ASSERT_TRUE(eval.at(35.0).height.has_value());
  EXPECT_NEAR(*eval.at(35.0).height, 0.66, 1e-12);
}

std::string loadError(const std::string& text) {
  test::TempDir dir;
  const std::string path = dir.write("script.yaml", text);
  try {
    loadCommandScript(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(CommandScript, BadScriptsAreNamedErrors) {
  EXPECT_NE(loadError("segments:\n  - {duration: 1.0}\n  - {duration: -2, vx: 0.1}\n").find("segments[1]"),
            std::string::npos);
  const std::string typo = loadError("segments:\n  - {duration: 1.0, vxx: 0.5}\n");
  EXPECT_NE(typo.find("script.yaml:2"), std::string::npos) << typo;
  EXPECT_NE(typo.find("'vxx'"), std::string::npos) << typo;
  EXPECT_NE(typo.find("did you mean 'vx'"), std::string::npos) << typo;
  EXPECT_NE(loadError("segments:\n  - {duration: 1.0, vx: fast}\n").find("vx"), std::string::npos);
  EXPECT_NE(loadError("segments:\n  - {duration: 1.0, vx: .inf}\n").find("vx"), std::string::npos);
  EXPECT_NE(loadError("segments:\n  - {t: 0, vx: 0.1}\n  - {duration: 2}\n").find("segments[1]"), std::string::npos)
      << "placements are not mixed";
  EXPECT_NE(loadError("segments:\n  - {t: 0}\n  - {t: 5}\n").find("duration"), std::string::npos);
  EXPECT_NE(loadError("segments:\n  - {duration: 1, mode: flying}\n").find("mode"), std::string::npos);
  EXPECT_NE(loadError("segments: []\n").find("segments"), std::string::npos);
  EXPECT_NE(loadError("").find("script.yaml"), std::string::npos);
}

TEST(CommandScript, ModeRequestsByName) {
  test::TempDir dir;
  const std::string path = dir.write("modes.yaml", "segments:\n  - {duration: 1, mode: soft_stand}\n  - {duration: 1, mode: damping}\n"
                                                   "  - {duration: 1, mode: reset}\n  - {duration: 1}\n");
  const CommandScript s = loadCommandScript(path);
  EXPECT_EQ(s.segments[0].mode, ModeRequest::kSoftStand);
  EXPECT_EQ(s.segments[1].mode, ModeRequest::kDamping);
  EXPECT_EQ(s.segments[2].mode, ModeRequest::kReset);
  EXPECT_EQ(s.segments[3].mode, ModeRequest::kNone);
}

}  // namespace
}  // namespace pmg

namespace pmg {
namespace {

// The crouched calibration sweeps of the command-response feed-forward (config/policies/response_sweep_7
// and _8, written by scripts/make_response_sweep.py --height-range) draw each walk inside the crouched
// velocity envelope of the product config they were drawn for (wh6g's, the default until 2026-12-06, whose
// L1 envelope slows crouched walks; the default's per-axis box slows none) at its own height: played through
// that config's shaper, no tick is slowed by the envelope (the fit would otherwise read the shaper's scaling
// as the robot's response), every walk reaches its height before the window the summary averages over (the
// last 60 %), and the sweeps do crouch (heights 0.66-0.78 m) and walk backward.
TEST(CommandShaper, CrouchedResponseSweepsStayInsideTheProductConfigsCrouchedEnvelope) {
  const ControllerConfig config = loadControllerConfig(test::sourcePath("config/controller/g1_sil_policy_wh6g.yaml"));
  ASSERT_GT(config.commands.crouched_height, 0.0);
  for (const char* file : {"config/policies/response_sweep_7.yaml", "config/policies/response_sweep_8.yaml"}) {
    const CommandScript script = loadCommandScript(test::sourcePath(file));
    CommandShaper shaper(config.commands);
    const double dt = 0.01;
    double lowest = 1.0;
    int backward_crouched = 0, walks = 0;
    std::size_t segment = 0;
    for (double t = 0.0; t < script.duration(); t += dt) {
      CommandSample s;
      s.command = script.at(t);
      s.velocity_time = s.posture_time = t;
      shaper.update(s, t, dt);
      const std::size_t k = script.segmentIndex(t);
      const CommandSegment& g = script.segments[k];
      const bool walking = std::fabs(g.command.vx) + std::fabs(g.command.vy) + std::fabs(g.command.wz) > 0.0;
      if (walking && t >= g.start + 0.4 * g.duration) {
        ASSERT_TRUE(g.command.height.has_value()) << file << " " << g.name;
        EXPECT_NEAR(shaper.posture().height, std::max(*g.command.height, config.commands.walking_min_height), 1e-9)
            << file << " " << g.name << ": the walk's height is reached before its window";
        if (k != segment) {
          ++walks;
          lowest = std::min(lowest, shaper.posture().height);
          if (g.command.vx <= -0.2 && shaper.posture().height < config.commands.standing_height - 0.03) ++backward_crouched;
        }
        segment = k;
      }
    }
    EXPECT_EQ(shaper.counters().crouch_limited_ticks, 0u) << file << ": a walk outside the crouched envelope";
    EXPECT_EQ(shaper.counters().clamped, 0u) << file;
    EXPECT_EQ(walks, 72) << file;
    EXPECT_LT(lowest, 0.68) << file << ": the sweep crouches";
    EXPECT_GE(backward_crouched, 3) << file << ": backward walks crouched (the gains per crouch' evidence)";
  }
}

}  // namespace
}  // namespace pmg
