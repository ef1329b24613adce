// ObservationAssembler: scaling, clipping, history order and the non-finite guard.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "pmg/policy/observation.hpp"

namespace pmg::policy::test {
namespace {

ObservationLayout layout(int history) {
  ObservationLayout l;
  l.history_length = history;
  l.clip = 5.0f;
  l.terms.push_back({"base_ang_vel_B", 3, {0.25f, 0.25f, 0.25f}});
  l.terms.push_back({"command", 2, {2.0f, 0.5f}});
  return l;
}

TEST(ObservationAssembler, ScalesAndClips) {
  ObservationAssembler obs(layout(1));
  const int w = obs.termIndex("base_ang_vel_B");
  const int c = obs.termIndex("command");
  const double gyro[3] = {1.0, -2.0, 100.0};  // 100 * 0.25 = 25 -> clipped to 5
  const double cmd[2] = {0.5, -4.0};
  obs.setTerm(c, cmd);
  obs.setTerm(w, gyro);
  ASSERT_TRUE(obs.commit());
  ASSERT_EQ(obs.size(), 5);
  const float expected[5] = {0.25f, -0.5f, 5.0f, 1.0f, -2.0f};
  for (int i = 0; i < 5; ++i) EXPECT_FLOAT_EQ(obs.data()[i], expected[i]) << i;
}

TEST(ObservationAssembler, HistoryNewestFirstAndFilledOnFirstCommit) {
  ObservationAssembler obs(layout(3));
  const int w = obs.termIndex("base_ang_vel_B");
  const int c = obs.termIndex("command");
  auto push = [&](double v) {
    const double gyro[3] = {v, v, v};
    const double cmd[2] = {v, v};
    obs.setTerm(w, gyro);
    obs.setTerm(c, cmd);
    return obs.commit();
  };
  ASSERT_TRUE(push(4.0));  // all three frames = frame(4)
  for (int h = 0; h < 3; ++h) EXPECT_FLOAT_EQ(obs.data()[5 * h], 1.0f);
  ASSERT_TRUE(push(8.0));
  ASSERT_TRUE(push(12.0));
  // Newest first: frame(12), frame(8), frame(4); first value of each = v * 0.25.
  EXPECT_FLOAT_EQ(obs.data()[0], 3.0f);
  EXPECT_FLOAT_EQ(obs.data()[5], 2.0f);
  EXPECT_FLOAT_EQ(obs.data()[10], 1.0f);
  EXPECT_FLOAT_EQ(obs.data()[3], 5.0f);   // command[0] 12 * 2 = 24 -> clip 5
  EXPECT_FLOAT_EQ(obs.data()[14], -0.0f + 2.0f);  // command[1] of frame(4): 4 * 0.5
  obs.reset();
  ASSERT_TRUE(push(-4.0));
  for (int h = 0; h < 3; ++h) EXPECT_FLOAT_EQ(obs.data()[5 * h], -1.0f);
}

TEST(ObservationAssembler, NonFiniteFrameRejectedAndHistoryKept) {
  ObservationAssembler obs(layout(2));
  const int w = obs.termIndex("base_ang_vel_B");
  const int c = obs.termIndex("command");
  const double gyro[3] = {1.0, 1.0, 1.0};
  const double cmd[2] = {0.0, 0.0};
  obs.setTerm(w, gyro);
  obs.setTerm(c, cmd);
  ASSERT_TRUE(obs.commit());
  const double bad[3] = {1.0, std::numeric_limits<double>::quiet_NaN(), 1.0};
  obs.setTerm(w, bad);
  EXPECT_FALSE(obs.commit());
  for (int i = 0; i < obs.size(); ++i) EXPECT_TRUE(std::isfinite(obs.data()[i]));
  const double inf[2] = {std::numeric_limits<double>::infinity(), 0.0};
  obs.setTerm(w, gyro);
  obs.setTerm(c, inf);  // +inf * 2 clips to 5: finite, accepted as saturated
  EXPECT_TRUE(obs.commit());
  EXPECT_FLOAT_EQ(obs.data()[3], 5.0f);
}

TEST(ObservationAssembler, UnknownTermListsKnownOnes) {
  ObservationAssembler obs(layout(1));
  try {
    obs.termIndex("joint_vel");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("base_ang_vel_B, command"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg::policy::test
