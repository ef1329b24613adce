// Command validation and shaping (NaN, range, staleness, slew limits) and command scripts.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "pmg/common/robot_config.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"

namespace pmg {
namespace {

TEST(CommandShaper, SlewLimitsTheVelocityStep) {
  CommandShaper shaper(CommandLimits{});
  CommandSample s;
  s.velocity = {1.0, 0.0, 1.0};
  s.velocity_time = 0.0;
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
  CommandSample s;
  s.velocity = {0.5, 0.0, 0.0};
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
  CommandSample s;
  s.velocity = {0.3, 0.0, 0.0};
  s.velocity_time = 0.0;
  for (int k = 0; k < 50; ++k) shaper.update(s, 0.01 * k, 0.01);
  s.velocity = {NAN, 0.0, 0.0};
  s.velocity_time = 0.5;
  shaper.update(s, 0.5, 0.01);
  EXPECT_EQ(shaper.counters().rejected_nan, 1u);
  EXPECT_NEAR(shaper.velocity().vx, 0.3, 1e-12);
  s.velocity = {0.0, 0.0, -7.0};
  s.posture = {2.0, 0.0, 0.5};
  s.velocity_time = s.posture_time = 0.51;
  for (int k = 0; k < 400; ++k) {
    s.velocity_time = s.posture_time = 0.51 + 0.01 * k;
    shaper.update(s, s.velocity_time, 0.01);
  }
  EXPECT_NEAR(shaper.velocity().wz, -1.0, 1e-12);  // clamped to max_velocity
  EXPECT_NEAR(shaper.posture().pitch, 0.6, 1e-12);  // clamped to posture_max
  EXPECT_GE(shaper.counters().clamped, 1u);
}

TEST(CommandScript, LoadsTheDemoAndRejectsBadSegments) {
  const CommandScript demo = loadCommandScript("config/commands/demo.yaml");
  EXPECT_GE(demo.segments.size(), 4u);
  EXPECT_NEAR(demo.at(0.0).velocity.vx, 0.0, 1e-12);
  EXPECT_NEAR(demo.at(3.0).velocity.vx, 0.5, 1e-12);
  EXPECT_NEAR(demo.at(1e6).velocity.vx, demo.segments.back().velocity.vx, 1e-12);
  const std::string bad = (std::filesystem::temp_directory_path() / "pmg_bad_script.yaml").string();
  std::ofstream(bad) << "segments:\n  - {duration: 1.0}\n  - {duration: -2, vx: 0.1}\n";
  try {
    loadCommandScript(bad);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("segments[1].duration"), std::string::npos) << e.what();
  }
  std::ofstream(bad) << "segments:\n  - {duration: 1.0, vx: fast}\n";
  EXPECT_THROW(loadCommandScript(bad), ConfigError);
}

TEST(ControllerConfig, ShippedConfigLoadsAndBadValuesAreNamed) {
  const ControllerConfig c = loadControllerConfig("config/controller/g1_sil.yaml");
  EXPECT_EQ(c.cyclesPerTick(), 5);
  EXPECT_TRUE(c.mujoco.gantry.enabled);
  const std::string bad = "config/controller/.test_bad.yaml";
  std::ifstream in("config/controller/g1_sil.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("hal_rate_hz: 500"), 16, "hal_rate_hz: 250");
  std::ofstream(bad) << text;
  try {
    loadControllerConfig(bad);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("timing.hal_rate_hz"), std::string::npos) << e.what();
  }
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace pmg
