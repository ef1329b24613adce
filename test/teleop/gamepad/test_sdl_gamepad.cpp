// SdlGamepad through SDL's virtual game controller (SDL_JoystickAttachVirtualEx, type
// SDL_JOYSTICK_TYPE_GAMECONTROLLER): values set on the virtual device come back through the
// GameController API, hot plug is followed, and an unplugged controller stops the mapper's output.
// No hardware and no display needed. The reader only opens controllers named "pmg test pad", so a
// real controller plugged into the test machine does not disturb the test.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pmg/teleop/gamepad.hpp"
#include "pmg/teleop/gamepad_sdl.hpp"

namespace pmg::teleop {
namespace {

constexpr const char* kName = "pmg test pad";
constexpr double kLsb = 1.0 / 32767.0;  // one step of SDL's Sint16

TEST(SdlGamepad, ReadsAxesTriggersAndButtonsOfAVirtualController) {
  SdlVirtualGamepad pad(kName);
  SdlGamepad reader(kName);
  GamepadState s = reader.poll(1.0);
  ASSERT_TRUE(s.attached) << "the virtual controller was not opened";
  EXPECT_TRUE(reader.connected());
  EXPECT_EQ(reader.name(), kName);
  EXPECT_EQ(reader.instanceId(), pad.instanceId());
  EXPECT_EQ(s.time, 1.0);
  // Freshly attached: centred sticks, released triggers (not the half-pressed raw 0).
  EXPECT_EQ(s.left_x, 0.0);
  EXPECT_EQ(s.left_trigger, 0.0);
  EXPECT_EQ(s.right_trigger, 0.0);
  EXPECT_EQ(s.buttons, 0u);

  GamepadState in;
  in.left_x = 0.25;
  in.left_y = -0.75;  // up
  in.right_x = 0.5;
  in.right_y = -1.0;
  in.left_trigger = 1.0;
  in.right_trigger = 0.6;
  in.buttons =
      controlBit(GamepadControl::kB) | controlBit(GamepadControl::kDpadUp) | controlBit(GamepadControl::kStart);
  pad.set(in);
  s = reader.poll(2.0);
  ASSERT_TRUE(s.attached);
  EXPECT_NEAR(s.left_x, in.left_x, kLsb);
  EXPECT_NEAR(s.left_y, in.left_y, kLsb);
  EXPECT_NEAR(s.right_x, in.right_x, kLsb);
  EXPECT_NEAR(s.right_y, in.right_y, kLsb);
  EXPECT_EQ(s.left_trigger, 1.0);
  EXPECT_NEAR(s.right_trigger, in.right_trigger, 2 * kLsb);  // the trigger mapping halves the resolution
  EXPECT_EQ(s.buttons, in.buttons);
  // Full deflection both ways stays inside [-1, 1].
  in.left_x = -1.0;
  in.left_y = 1.0;
  pad.set(in);
  s = reader.poll(3.0);
  EXPECT_EQ(s.left_x, -1.0);
  EXPECT_EQ(s.left_y, 1.0);
}

TEST(SdlGamepad, EveryButtonArrivesOnItsOwnBit) {
  SdlVirtualGamepad pad(kName);
  SdlGamepad reader(kName);
  ASSERT_TRUE(reader.poll(0.0).attached);
  // SDL 2.26 maps every button of a virtual controller except the touchpad (its generated mapping
  // ends at paddle4), so the touchpad is not testable here.
  for (int b = 0; b < static_cast<int>(GamepadControl::kTouchpad); ++b) {
    GamepadState in;
    in.buttons = 1u << b;
    pad.set(in);
    EXPECT_EQ(reader.poll(0.0).buttons, in.buttons) << toString(static_cast<GamepadControl>(b));
  }
}

TEST(SdlGamepad, FollowsHotPlugAndTheMapperStopsOnUnplug) {
  SdlGamepad reader(kName);
  EXPECT_FALSE(reader.poll(0.0).attached);  // nothing plugged in yet
  auto pad = std::make_unique<SdlVirtualGamepad>(kName);
  GamepadMapper mapper{GamepadConfig{}};
  double now = 0.0;
  GamepadState in;
  pad->set(in);
  for (int i = 0; i < 5; ++i, now += 0.02) mapper.update(reader.poll(now), now);  // connect, centred
  ASSERT_EQ(mapper.output().link, GamepadLink::kOk);
  EXPECT_EQ(reader.connects(), 1u);
  in.left_y = -1.0;  // full forward
  pad->set(in);
  for (int i = 0; i < 50; ++i, now += 0.02) mapper.update(reader.poll(now), now);
  ASSERT_GT(mapper.output().vx, 0.3);

  pad->detach();  // unplugged: SDL_CONTROLLERDEVICEREMOVED
  const GamepadState s = reader.poll(now);
  EXPECT_FALSE(s.attached);
  EXPECT_FALSE(reader.connected());
  EXPECT_EQ(reader.disconnects(), 1u);
  const GamepadOutput& o = mapper.update(s, now);
  EXPECT_EQ(o.link, GamepadLink::kLost);
  EXPECT_EQ(o.vx, 0.0);
  int dampings = 0;
  for (int i = 0; i < 100; ++i) {
    now += 0.02;
    dampings += mapper.update(reader.poll(now), now).mode == ModeRequest::kDamping;
  }
  EXPECT_EQ(dampings, 1);

  pad->attach();  // plugged in again: SDL_CONTROLLERDEVICEADDED
  pad->set(in);   // stick still held
  now += 0.02;
  EXPECT_TRUE(reader.poll(now).attached);
  EXPECT_EQ(reader.connects(), 2u);
  EXPECT_EQ(mapper.update(reader.poll(now), now).vx, 0.0);  // waits for the sticks to centre
  EXPECT_TRUE(mapper.output().waiting_for_centre);

  pad.reset();  // the device object goes away entirely
  EXPECT_FALSE(reader.poll(now).attached);
}

TEST(SdlGamepad, NameFilterIgnoresOtherControllers) {
  SdlVirtualGamepad other("some other pad");
  SdlGamepad reader(kName);
  EXPECT_FALSE(reader.poll(0.0).attached);
  SdlVirtualGamepad mine(kName);
  EXPECT_TRUE(reader.poll(0.0).attached);
  EXPECT_EQ(reader.instanceId(), mine.instanceId());
}

}  // namespace
}  // namespace pmg::teleop
