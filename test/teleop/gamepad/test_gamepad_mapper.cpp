// GamepadMapper (src/teleop/gamepad/gamepad_mapper.cpp), its config and the virtual-controller
// script: pure logic, no SDL. Time is simulated (50 Hz updates), so every expected value is exact.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/teleop/gamepad.hpp"
#include "pmg/teleop/gamepad_script.hpp"

namespace pmg::teleop {
namespace {

using ::testing::HasSubstr;
constexpr double kDt = 0.02;

std::uint32_t bits(std::initializer_list<GamepadControl> cs) {
  std::uint32_t b = 0;
  for (auto c : cs) b |= controlBit(c);
  return b;
}

/// Drives a mapper with states at 50 Hz on a simulated clock.
struct Driver {
  explicit Driver(const GamepadConfig& c = GamepadConfig{}) : mapper(c) {}
  GamepadMapper mapper;
  GamepadState s = [] {
    GamepadState x;
    x.attached = true;
    return x;
  }();
  double now = 10.0;
  std::vector<ModeRequest> requests;
  /// One update with the current state stamped now (fresh), then the clock advances.
  const GamepadOutput& step(bool stamp = true) {
    if (stamp) s.time = now;
    const GamepadOutput& o = mapper.update(s, now);
    if (o.mode != ModeRequest::kNone) requests.push_back(o.mode);
    now += kDt;
    return o;
  }
  const GamepadOutput& run(int n, bool stamp = true) {
    for (int i = 0; i < n - 1; ++i) step(stamp);
    return step(stamp);
  }
  void press(std::initializer_list<GamepadControl> cs) {
    s.buttons = 0;
    s.left_trigger = s.right_trigger = 0.0;
    for (auto c : cs) {
      if (c == GamepadControl::kLeftTrigger)
        s.left_trigger = 1.0;
      else if (c == GamepadControl::kRightTrigger)
        s.right_trigger = 1.0;
      else
        s.buttons |= controlBit(c);
    }
  }
  void release() { press({}); }
  std::size_t count(ModeRequest m) const {
    std::size_t n = 0;
    for (auto r : requests) n += r == m;
    return n;
  }
};

/// A config without slew (one update reaches any target), to test the static shaping.
GamepadConfig noSlew() {
  GamepadConfig c;
  for (GamepadAxisConfig* a : {&c.sticks.vx, &c.sticks.vy, &c.sticks.wz}) a->accel = a->decel = 100.0;
  return c;
}

// Reference of the documented curve: dead zone, rescale, (1 − e)·u + e·u³, × max.
double expected(const GamepadAxisConfig& a, double x) {
  if (std::fabs(x) <= a.dead_zone) return 0.0;
  const double u = (std::fabs(x) - a.dead_zone) / (1.0 - a.dead_zone);
  return std::copysign(((1.0 - a.expo) * u + a.expo * u * u * u) * a.max, x);
}

// ------------------------------------------------------------------------------------------------
TEST(GamepadMapper, DeadZoneGivesExactlyZeroAndJustOutsideMoves) {
  Driver d(noSlew());
  d.step();  // connect with centred sticks
  const double dz = d.mapper.config().sticks.vx.dead_zone;
  d.s.left_y = -dz;  // on the edge: still inside
  d.s.left_x = 0.9 * dz;
  d.s.right_x = -0.5 * dz;
  const GamepadOutput& o = d.step();
  EXPECT_EQ(o.vx, 0.0);
  EXPECT_EQ(o.vy, 0.0);
  EXPECT_EQ(o.wz, 0.0);
  d.s.left_y = -(dz + 0.01);
  EXPECT_GT(d.step().vx, 0.0);
}

TEST(GamepadMapper, ExpoCurveAndScalingFollowTheConfig) {
  GamepadConfig c = noSlew();
  c.sticks.vx.expo = 0.5;
  c.sticks.vy.expo = 0.0;  // linear
  Driver d(c);
  d.step();
  for (double x : {0.15, 0.3, 0.55, 0.8, 1.0}) {
    d.s.left_y = -x;
    d.s.left_x = -x;
    d.s.right_x = x;
    const GamepadOutput& o = d.step();
    EXPECT_NEAR(o.vx, expected(c.sticks.vx, x), 1e-12) << x;
    EXPECT_NEAR(o.vy, expected(c.sticks.vy, x), 1e-12) << x;
    EXPECT_NEAR(o.wz, expected(c.sticks.wz, -x), 1e-12) << x;
  }
  // Full deflection gives exactly the configured maximum; expo bends the curve below linear.
  EXPECT_DOUBLE_EQ(d.mapper.output().vx, c.sticks.vx.max);
  d.s.left_y = d.s.left_x = -0.55;
  d.step();
  EXPECT_LT(d.mapper.output().vx / c.sticks.vx.max, d.mapper.output().vy / c.sticks.vy.max);
}

TEST(GamepadMapper, SignConventionsOfTheHeadingFrame) {
  Driver d(noSlew());
  d.step();
  d.s.left_y = -1.0;  // stick up
  EXPECT_GT(d.step().vx, 0.0);
  d.s.left_y = 0.0;
  d.s.left_x = -1.0;  // stick left → +vy (left positive)
  d.run(3);
  EXPECT_GT(d.mapper.output().vy, 0.0);
  EXPECT_EQ(d.mapper.output().vx, 0.0);
  d.s.left_x = 0.0;
  d.s.right_x = -1.0;  // right stick left → +wz (counter-clockwise)
  d.run(3);
  EXPECT_GT(d.mapper.output().wz, 0.0);
  d.s.right_x = 1.0;
  d.run(3);
  EXPECT_LT(d.mapper.output().wz, 0.0);
}

TEST(GamepadMapper, SlewLimitsAccelerationAndDecelerationAndEndsExactlyAtZero) {
  GamepadConfig c;
  c.sticks.vx = {0.1, 0.0, 0.6, 1.0, 2.0};
  Driver d(c);
  d.step();
  d.s.left_y = -1.0;  // full forward: target 0.6 m/s at 1 m/s² → 0.02 m/s per update
  double prev = 0.0;
  int updates = 0;
  while (d.mapper.output().vx < 0.6 && updates < 100) {
    const double v = d.step().vx;
    EXPECT_NEAR(v - prev, std::min(0.02, 0.6 - prev), 1e-12);
    prev = v;
    ++updates;
  }
  EXPECT_NEAR(updates, 30, 1);  // 0.6 / 0.02 (the simulated clock's steps are 0.02 ± 1 ulp-scale)
  EXPECT_EQ(d.mapper.output().vx, 0.6);
  d.s.left_y = 0.0;  // release: 2 m/s² → 0.04 per update, lands exactly on 0
  updates = 0;
  while (d.mapper.output().vx > 0.0 && updates < 100) {
    const double v = d.step().vx;
    EXPECT_NEAR(prev - v, std::min(0.04, prev), 1e-12);
    prev = v;
    ++updates;
  }
  EXPECT_NEAR(updates, 15, 1);
  EXPECT_EQ(d.mapper.output().vx, 0.0);  // exactly, not 1e-17
}

TEST(GamepadMapper, ReleasedSticksGiveExactlyZeroOnEveryAxis) {
  Driver d;
  d.step();
  const double pattern[][3] = {{-0.7, 0.3, 0.9}, {0.4, -0.95, -0.2}, {-1.0, 1.0, 0.33}, {0.12, -0.5, -1.0}};
  for (const auto& p : pattern) {
    d.s.left_y = p[0];
    d.s.left_x = p[1];
    d.s.right_x = p[2];
    d.run(17);
  }
  d.s.left_y = d.s.left_x = d.s.right_x = 0.0;
  const GamepadOutput& o = d.run(100);  // 2 s: more than any decel ramp
  EXPECT_EQ(o.vx, 0.0);
  EXPECT_EQ(o.vy, 0.0);
  EXPECT_EQ(o.wz, 0.0);
  // A stick resting inside the dead zone (a worn controller) is released too.
  d.s.left_y = 0.05;
  d.s.right_x = -0.08;
  EXPECT_EQ(d.run(5).vx, 0.0);
  EXPECT_EQ(d.mapper.output().wz, 0.0);
}

TEST(GamepadMapper, PostureStepsHoldsAndStaysInItsRanges) {
  Driver d;
  const GamepadPostureConfig& p = d.mapper.config().posture;
  d.step();
  EXPECT_FALSE(d.mapper.output().height.has_value());  // no height command until the operator asks
  d.press({GamepadControl::kDpadDown});
  d.step();
  ASSERT_TRUE(d.mapper.output().height.has_value());
  EXPECT_NEAR(*d.mapper.output().height, p.standing_height - p.height_step, 1e-12);  // one step per press
  d.run(10);  // held 0.2 s < hold_delay: no further change
  EXPECT_NEAR(*d.mapper.output().height, p.standing_height - p.height_step, 1e-12);
  d.run(30);  // held 0.8 s in all: rate × (0.8 − 0.4) s more (± one update)
  EXPECT_NEAR(*d.mapper.output().height, p.standing_height - p.height_step - p.height_rate * 0.4,
              p.height_rate * kDt + 1e-9);
  d.run(500);  // 10 s: bounded
  EXPECT_DOUBLE_EQ(*d.mapper.output().height, p.height_range[0]);
  d.release();
  d.step();
  for (int i = 0; i < 40; ++i) {  // 40 presses up: bounded above
    d.press({GamepadControl::kDpadUp});
    d.step();
    d.release();
    d.step();
  }
  EXPECT_DOUBLE_EQ(*d.mapper.output().height, p.height_range[1]);

  // Pitch: the pitch layer (RT) turns d-pad up/down into pitch; the height stays.
  const double h = *d.mapper.output().height;
  d.press({GamepadControl::kRightTrigger, GamepadControl::kDpadUp});
  d.step();
  EXPECT_NEAR(d.mapper.output().pitch, p.pitch_step, 1e-12);
  EXPECT_EQ(*d.mapper.output().height, h);
  d.run(300);
  EXPECT_DOUBLE_EQ(d.mapper.output().pitch, p.pitch_range[1]);
  // Roll: right = lean right = +roll, left = −roll.
  d.press({GamepadControl::kDpadRight});
  d.step();
  EXPECT_NEAR(d.mapper.output().roll, p.roll_step, 1e-12);
  d.release();
  d.step();
  d.press({GamepadControl::kDpadLeft});
  d.run(300);
  EXPECT_DOUBLE_EQ(d.mapper.output().roll, p.roll_range[0]);
  // Neutral posture: RT + Y.
  d.press({GamepadControl::kRightTrigger, GamepadControl::kY});
  d.step();
  EXPECT_EQ(d.mapper.output().pitch, 0.0);
  EXPECT_EQ(d.mapper.output().roll, 0.0);
  EXPECT_FALSE(d.mapper.output().height.has_value());
  // The posture ranges of the default config lie inside the controller's command limits.
  const CommandLimits limits;
  EXPECT_GE(p.height_range[0], limits.height_range[0]);
  EXPECT_LE(p.height_range[1], limits.height_range[1]);
  EXPECT_GE(p.pitch_range[0], limits.pitch_range[0]);
  EXPECT_LE(p.pitch_range[1], limits.pitch_range[1]);
  EXPECT_GE(p.roll_range[0], limits.roll_range[0]);
  EXPECT_LE(p.roll_range[1], limits.roll_range[1]);
  EXPECT_TRUE(d.requests.empty());  // posture never requests a mode
}

TEST(GamepadMapper, ModeLayerKeepsTheDpadOffThePosture) {
  Driver d;
  d.step();
  d.press({GamepadControl::kLeftTrigger});
  d.step();
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kDpadUp});  // stand, not height
  d.run(50);
  EXPECT_FALSE(d.mapper.output().height.has_value());
  EXPECT_EQ(d.count(ModeRequest::kSoftStand), 1u);
}

TEST(GamepadMapper, ModeRequestsOnPressEdgesOnly) {
  Driver d;
  d.step();
  struct Case {
    std::initializer_list<GamepadControl> controls;
    ModeRequest expected;
  };
  const Case cases[] = {
      {{GamepadControl::kLeftTrigger, GamepadControl::kDpadUp}, ModeRequest::kSoftStand},
      {{GamepadControl::kRightShoulder, GamepadControl::kX}, ModeRequest::kActive},
      {{GamepadControl::kBack}, ModeRequest::kDamping},
      {{GamepadControl::kLeftTrigger, GamepadControl::kStart}, ModeRequest::kReset},
  };
  for (const Case& c : cases) {
    d.requests.clear();
    d.press(c.controls);
    d.run(25);  // held for half a second: one request
    d.release();
    d.run(5);
    d.press(c.controls);  // pressed again: a second one
    d.run(3);
    d.release();
    d.step();
    ASSERT_EQ(d.requests.size(), 2u) << static_cast<int>(c.expected);
    EXPECT_EQ(d.requests[0], c.expected);
    EXPECT_EQ(d.requests[1], c.expected);
  }
  // Half a chord does nothing; the chord's second button completes the edge.
  d.requests.clear();
  d.press({GamepadControl::kX});
  d.run(5);
  d.press({GamepadControl::kX, GamepadControl::kRightShoulder});
  d.step();
  EXPECT_EQ(d.requests, std::vector<ModeRequest>{ModeRequest::kActive});
  // A trigger below the threshold is not pressed.
  d.release();
  d.step();
  d.requests.clear();
  d.s.left_trigger = 0.3;
  d.s.buttons = bits({GamepadControl::kDpadUp});
  d.run(5);
  EXPECT_TRUE(d.requests.empty());
  EXPECT_EQ(d.mapper.counters().mode_requests, 9u);
}

TEST(GamepadMapper, ButtonsHeldWhileConnectingRequestNothing) {
  Driver d;
  d.press({GamepadControl::kRightShoulder, GamepadControl::kX});
  d.run(10);
  EXPECT_TRUE(d.requests.empty());
  d.release();
  d.step();
  d.press({GamepadControl::kRightShoulder, GamepadControl::kX});
  d.step();
  EXPECT_EQ(d.requests, std::vector<ModeRequest>{ModeRequest::kActive});
}

TEST(GamepadMapper, EstopChordLatchesUntilReleasedAndReset) {
  Driver d;
  d.step();
  d.s.left_y = -1.0;
  d.run(40);
  ASSERT_GT(d.mapper.output().vx, 0.5);
  d.requests.clear();
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kB});  // stick still full forward
  const GamepadOutput& o = d.step();
  EXPECT_EQ(o.mode, ModeRequest::kDamping);
  EXPECT_TRUE(o.estop_latched);
  EXPECT_EQ(o.vx, 0.0);  // at once, no deceleration ramp
  // Held for 2 s: the damping request repeats every estop_repeat (0.5 s), nothing else gets through.
  d.run(100);
  EXPECT_EQ(d.count(ModeRequest::kDamping), 1u + 3u);  // t = 0, 0.5, 1.0, 1.5 (2.0 is the next update)
  EXPECT_EQ(d.mapper.output().vx, 0.0);
  // Released: still latched; walk and stand are ignored.
  d.press({GamepadControl::kRightShoulder, GamepadControl::kX});
  d.step();
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kDpadUp});
  d.step();
  EXPECT_TRUE(d.mapper.output().estop_latched);
  EXPECT_EQ(d.count(ModeRequest::kActive), 0u);
  EXPECT_EQ(d.count(ModeRequest::kSoftStand), 0u);
  EXPECT_EQ(d.mapper.output().vx, 0.0);
  // Reset while the chord is still held does not re-arm.
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kB, GamepadControl::kStart});
  d.step();
  EXPECT_TRUE(d.mapper.output().estop_latched);
  EXPECT_EQ(d.count(ModeRequest::kReset), 0u);
  // Chord released, then LT + Start: kReset, re-armed.
  d.press({GamepadControl::kLeftTrigger});
  d.step();
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kStart});
  EXPECT_EQ(d.step().mode, ModeRequest::kReset);
  EXPECT_FALSE(d.mapper.output().estop_latched);
  // The stick is still at full forward: nothing moves until it has been centred.
  d.release();
  d.run(10);
  EXPECT_EQ(d.mapper.output().vx, 0.0);
  EXPECT_TRUE(d.mapper.output().waiting_for_centre);
  d.s.left_y = 0.0;
  d.step();
  EXPECT_FALSE(d.mapper.output().waiting_for_centre);
  d.s.left_y = -1.0;
  d.run(5);
  EXPECT_GT(d.mapper.output().vx, 0.0);
  EXPECT_EQ(d.mapper.counters().estops, 1u);
  // Walk works again.
  d.press({GamepadControl::kRightShoulder, GamepadControl::kX});
  d.step();
  EXPECT_EQ(d.count(ModeRequest::kActive), 1u);
}

TEST(GamepadMapper, EstopChordHeldWhileConnectingLatchesAtOnce) {
  Driver d;
  d.press({GamepadControl::kLeftTrigger, GamepadControl::kB});
  EXPECT_EQ(d.step().mode, ModeRequest::kDamping);
  EXPECT_TRUE(d.mapper.output().estop_latched);
}

TEST(GamepadMapper, DetachedControllerZeroesAtOnceThenOneDampingAfterTheTimeout) {
  Driver d;
  d.step();
  d.s.left_y = -1.0;
  d.s.right_x = 1.0;
  d.run(50);
  ASSERT_GT(d.mapper.output().vx, 0.5);
  d.requests.clear();
  d.s.attached = false;  // unplugged (sticks were held)
  const double lost_at = d.now;
  const GamepadOutput& o = d.step();
  EXPECT_EQ(o.link, GamepadLink::kLost);
  EXPECT_EQ(o.vx, 0.0);
  EXPECT_EQ(o.wz, 0.0);
  double damping_at = -1.0;
  for (int i = 0; i < 250; ++i) {  // 5 s unplugged
    const double t = d.now;
    if (d.step().mode == ModeRequest::kDamping && damping_at < 0) damping_at = t;
  }
  EXPECT_EQ(d.requests, std::vector<ModeRequest>{ModeRequest::kDamping});  // exactly one
  EXPECT_NEAR(damping_at - lost_at, d.mapper.config().link.damping_timeout, kDt + 1e-9);
  EXPECT_GE(damping_at - lost_at, d.mapper.config().link.damping_timeout - 1e-9);
  EXPECT_EQ(d.mapper.counters().losses, 1u);
  EXPECT_EQ(d.mapper.counters().loss_dampings, 1u);
  // Plugged in again with the stick still held: link ok, velocity waits for the sticks to centre.
  d.s.attached = true;
  d.run(10);
  EXPECT_EQ(d.mapper.output().link, GamepadLink::kOk);
  EXPECT_EQ(d.mapper.output().vx, 0.0);
  d.s.left_y = d.s.right_x = 0.0;
  d.step();
  d.s.left_y = -1.0;
  d.run(5);
  EXPECT_GT(d.mapper.output().vx, 0.0);
  // A second loss gets its own (single) damping request.
  d.s.attached = false;
  d.run(100);
  EXPECT_EQ(d.count(ModeRequest::kDamping), 2u);
}

TEST(GamepadMapper, StaleStateIsALossAfterTheStaleTimeout) {
  Driver d;
  d.step();
  d.s.left_y = -1.0;
  d.run(50);
  const double last = d.now - kDt;  // the reader stops delivering: state time frozen
  d.requests.clear();
  double zero_at = -1.0, damping_at = -1.0;
  for (int i = 0; i < 150; ++i) {
    const double t = d.now;
    const GamepadOutput& o = d.step(false);
    if (o.vx == 0.0 && zero_at < 0) zero_at = t;
    if (o.mode == ModeRequest::kDamping) damping_at = t;
  }
  const GamepadLinkConfig& l = d.mapper.config().link;
  EXPECT_GT(zero_at - last, l.stale_timeout);               // moving while the state is fresh ...
  EXPECT_LE(zero_at - last, l.stale_timeout + kDt + 1e-9);  // ... and zero at once after
  EXPECT_NEAR(damping_at - zero_at, l.damping_timeout, kDt + 1e-9);
  EXPECT_EQ(d.requests.size(), 1u);
}

TEST(GamepadMapper, NoDampingWhenNoControllerWasEverConnected) {
  Driver d;
  d.s.attached = false;
  d.run(200);
  EXPECT_TRUE(d.requests.empty());
  EXPECT_EQ(d.mapper.output().link, GamepadLink::kNone);
  GamepadConfig c;
  c.link.damping_on_loss = false;  // and the switch turns loss damping off
  Driver e(c);
  e.step();
  e.s.attached = false;
  e.run(200);
  EXPECT_TRUE(e.requests.empty());
  EXPECT_EQ(e.mapper.output().link, GamepadLink::kLost);
}

TEST(GamepadMapper, NonFiniteStateCountsAsLost) {
  Driver d;
  d.step();
  d.s.left_y = -1.0;
  d.run(20);
  d.s.left_x = std::nan("");
  const GamepadOutput& o = d.step();
  EXPECT_EQ(o.link, GamepadLink::kLost);
  EXPECT_EQ(o.vx, 0.0);
  EXPECT_EQ(d.mapper.counters().invalid_states, 1u);
}

TEST(GamepadMapper, UpdateAllocatesNothing) {
  Driver d;
  d.step();
  const std::initializer_list<GamepadControl> chords[] = {{GamepadControl::kLeftTrigger, GamepadControl::kDpadUp},
                                                          {GamepadControl::kRightShoulder, GamepadControl::kX},
                                                          {GamepadControl::kDpadDown},
                                                          {GamepadControl::kRightTrigger, GamepadControl::kDpadUp},
                                                          {GamepadControl::kLeftTrigger, GamepadControl::kB},
                                                          {GamepadControl::kLeftTrigger, GamepadControl::kStart}};
  test::AllocationGuard guard;
  for (int i = 0; i < 3000; ++i) {
    d.s.left_y = std::sin(0.01 * i);
    d.s.left_x = std::cos(0.013 * i);
    d.s.right_x = std::sin(0.007 * i);
    if (i % 40 == 0) d.press(chords[(i / 40) % 6]);
    if (i % 40 == 20) d.release();
    d.s.attached = (i / 500) % 2 == 0 || i % 500 < 100;
    d.mapper.update(d.s, d.now);
    d.s.time = d.now;
    d.now += kDt;
  }
  EXPECT_EQ(guard.count(), 0u);
  EXPECT_GT(d.mapper.counters().mode_requests, 10u);
  EXPECT_GT(d.mapper.counters().losses, 1u);
}

// ------------------------------------------------------------------------------------------------
TEST(GamepadConfig, ShippedConfigLoadsAndLiesInsideTheCommandLimits) {
  const GamepadConfig c = loadGamepadConfig(test::sourcePath("config/teleop/gamepad.yaml"));
  const CommandLimits limits;
  EXPECT_LE(c.sticks.vx.max, limits.max_velocity[0]);
  EXPECT_LE(c.sticks.vy.max, limits.max_velocity[1]);
  EXPECT_LE(c.sticks.wz.max, limits.max_velocity[2]);
  EXPECT_EQ(c.buttons.estop, (std::vector<GamepadControl>{GamepadControl::kLeftTrigger, GamepadControl::kB}));
  EXPECT_EQ(c.buttons.walk, (std::vector<GamepadControl>{GamepadControl::kRightShoulder, GamepadControl::kX}));
  EXPECT_EQ(c.link.stale_timeout, 0.5);
  EXPECT_NO_THROW(GamepadMapper{c});
  // ... and inside the default policy config's posture limits, which keep the actor within what it was
  // trained on (height from 0.59 m: docs/controller.md "Squats and bends beyond the trained range"), so that the
  // whole d-pad travel is something the robot does.
  const ControllerConfig policy = loadControllerConfig(test::sourcePath("config/controller/g1_sil_policy.yaml"));
  EXPECT_GE(c.posture.height_range[0], policy.commands.height_range[0]);
  EXPECT_LE(c.posture.height_range[1], policy.commands.height_range[1]);
  EXPECT_GE(c.posture.pitch_range[0], policy.commands.pitch_range[0]);
  EXPECT_LE(c.posture.pitch_range[1], policy.commands.pitch_range[1]);
  EXPECT_GE(c.posture.roll_range[0], policy.commands.roll_range[0]);
  EXPECT_LE(c.posture.roll_range[1], policy.commands.roll_range[1]);
}

struct BadConfig {
  const char* name;
  const char* yaml;
  std::vector<const char*> expect;  // substrings of the error
};

TEST(GamepadConfig, BadConfigsAreRejectedNamingTheFieldAndRange) {
  const BadConfig cases[] = {
      {"unknown key",
       "sticks:\n  vx: {dead_zone: 0.1}\n  vz: {max: 0.3}\n",
       {"bad.yaml:3", "unknown key 'vz'", "did you mean"}},
      {"misspelt section", "postur:\n  height_step: 0.01\n", {"bad.yaml:1", "unknown key 'postur'", "posture"}},
      {"vx above the command limit",
       "sticks:\n  vx: {max: 1.5}\n",
       {"bad.yaml:", "sticks", "vx.max = 1.5", "(0, 1]", "CommandLimits"}},
      {"vy above the command limit", "sticks:\n  vy: {max: 0.6}\n", {"vy.max = 0.6", "(0, 0.5]"}},
      {"dead zone", "sticks:\n  wz: {dead_zone: 0.7}\n", {"sticks.wz", "dead_zone = 0.7", "0..0.5"}},
      {"negative accel", "sticks:\n  vx: {accel: -1}\n", {"accel = -1", "(0, 100]"}},
      {"expo", "sticks:\n  vx: {expo: 2}\n", {"expo = 2", "0..1"}},
      {"not a number", "sticks:\n  vx: {max: fast}\n", {"bad.yaml:2", "sticks.vx.max", "number"}},
      {"infinite", "sticks:\n  vx: {max: .inf}\n", {"sticks.vx.max", "finite"}},
      {"height range outside the limits",
       "posture:\n  height_range: [0.3, 0.8]\n",
       {"posture", "height_range = [0.3, 0.8]", "[0.45, 0.85]", "CommandLimits::height_range"}},
      {"height range without the standing height", "posture:\n  height_range: [0.5, 0.7]\n", {"must contain 0.76"}},
      {"pitch range", "posture:\n  pitch_range: [0.1, 0.5]\n", {"pitch_range", "must contain 0"}},
      {"roll range order", "posture:\n  roll_range: [0.2, -0.2]\n", {"roll_range", "min <= max"}},
      {"step", "posture:\n  height_step: 0.5\n", {"height_step = 0.5", "0..0.2"}},
      {"unknown control",
       "buttons:\n  walk: [rb, x]\n",
       {"bad.yaml:2", "buttons.walk[0]", "'rightshoulder'", "got 'rb'"}},
      {"one-button e-stop", "buttons:\n  estop: [b]\n", {"buttons", "estop: expected exactly 2"}},
      {"three-button chord", "buttons:\n  stand: [lefttrigger, dpup, a]\n", {"stand: expected 1 or 2"}},
      {"binding inside another", "buttons:\n  damping: [b]\n", {"damping is contained in estop"}},
      {"same binding twice", "buttons:\n  walk: [lefttrigger, dpup]\n", {"is the same binding as"}},
      {"layer on the d-pad", "buttons:\n  pitch_layer: dpup\n", {"pitch_layer = dpup"}},
      {"trigger threshold", "buttons:\n  trigger_threshold: 1.0\n", {"trigger_threshold = 1", "0.05..0.95"}},
      {"stale timeout", "link:\n  stale_timeout: 0\n", {"link", "stale_timeout = 0", "0.05..5 s"}},
      {"damping timeout", "link:\n  damping_timeout: -1\n", {"damping_timeout = -1"}},
  };
  for (const BadConfig& c : cases) {
    try {
      parseGamepadConfig(c.yaml, "bad.yaml");
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const ConfigError& e) {
      for (const char* s : c.expect) EXPECT_THAT(e.what(), HasSubstr(s)) << c.name;
    }
  }
  // A config built in code is checked by the mapper the same way.
  GamepadConfig c;
  c.sticks.wz.max = 3.0;
  try {
    GamepadMapper m(c);
    ADD_FAILURE() << "accepted wz.max = 3";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("sticks: wz.max = 3"));
  }
}

// ------------------------------------------------------------------------------------------------
TEST(GamepadScript, ParsesStepsAndTheirStates) {
  const GamepadScript s = parseGamepadScript(
      "duration: 4\n"
      "steps:\n"
      "  - {t: 0.0}\n"
      "  - {t: 0.5, name: stand, buttons: [lefttrigger, dpup]}\n"
      "  - {t: 1.5, left_y: -0.8, right_x: 0.25}\n"
      "  - {t: 3.0, attached: false}\n");
  ASSERT_EQ(s.steps.size(), 4u);
  EXPECT_EQ(s.end(), 4.0);
  EXPECT_EQ(s.stepIndex(0.49), 0u);
  EXPECT_EQ(s.stepIndex(0.5), 1u);
  EXPECT_EQ(s.stepIndex(2.9), 2u);
  EXPECT_EQ(s.stepIndex(10.0), 3u);
  const GamepadState st = s.steps[1].state();
  EXPECT_EQ(st.left_trigger, 1.0);
  EXPECT_EQ(st.buttons, bits({GamepadControl::kDpadUp}));
  EXPECT_EQ(s.steps[2].state().left_y, -0.8);
  EXPECT_FALSE(s.steps[3].state().attached);
  EXPECT_EQ(parseGamepadScript("steps:\n  - {t: 0.0}\n  - {t: 2.0}\n").end(), 3.0);
  EXPECT_NO_THROW(loadGamepadScript(test::sourcePath("config/teleop/gamepad_demo_script.yaml")));
}

TEST(GamepadScript, BadScriptsAreRejected) {
  const BadConfig cases[] = {
      {"time going back", "steps:\n  - {t: 1.0}\n  - {t: 0.5}\n", {"steps[1].t = 0.5", "expected > 1"}},
      {"axis out of range", "steps:\n  - {t: 0, left_y: -2}\n", {"bad.yaml:2", "steps[0]", "left_y = -2", "-1..1"}},
      {"trigger out of range", "steps:\n  - {t: 0, left_trigger: 1.5}\n", {"left_trigger = 1.5"}},
      {"missing t", "steps:\n  - {left_y: 0.5}\n", {"missing required key 't'"}},
      {"unknown key", "steps:\n  - {t: 0, lefty: 0.5}\n", {"unknown key 'lefty'", "left_y"}},
      {"no steps", "steps: []\n", {"at least one step"}},
      {"duration before the last step", "duration: 1\nsteps:\n  - {t: 0}\n  - {t: 2}\n", {"duration = 1"}},
  };
  for (const BadConfig& c : cases) {
    try {
      parseGamepadScript(c.yaml, "bad.yaml");
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const ConfigError& e) {
      for (const char* s : c.expect) EXPECT_THAT(e.what(), HasSubstr(s)) << c.name;
    }
  }
}

}  // namespace
}  // namespace pmg::teleop
