// The task judges (issue 14) on synthetic object trajectories in the shipped scenes: each success
// criterion of the paper's Table III passes where it holds and each failure class is named where it
// does not.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/hal/task_judge.hpp"

namespace pmg {
namespace {

TaskObjectSample sample(double t, double x, double y, double z, double vz = 0.0, double roll = 0.0) {
  TaskObjectSample s;
  s.t = t;
  s.state.p_W = {x, y, z};
  s.state.v_W = {0.0, 0.0, vz};
  s.state.q_W = Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  return s;
}

// The towel slides along the table (top at 0.76 m, 1.8 m long) from y0 to y1 in 10 s.
std::vector<TaskObjectSample> slide(double y0, double y1, double z = 0.763) {
  std::vector<TaskObjectSample> v;
  for (int k = 0; k <= 100; ++k) v.push_back(sample(0.1 * k, 0.6, y0 + (y1 - y0) * k / 100.0, z));
  return v;
}

TEST(TaskJudge, WipeNeedsMoreThanOneMetreOnTheTop) {
  const TaskScene scene = loadTaskScene(test::sourcePath("config/tasks/wipe_scene.yaml"));
  TaskVerdict v = judgeWipe(scene, "towel", slide(-0.45, 0.65), false);
  EXPECT_TRUE(v.success) << v.detail;
  EXPECT_NEAR(v.measure, 1.10, 0.011);
  v = judgeWipe(scene, "towel", slide(-0.45, 0.45), false);
  EXPECT_EQ(v.failure, "too_short") << v.detail;
  v = judgeWipe(scene, "towel", slide(-0.30, 0.95), false);  // past the top's end at 0.9 m
  EXPECT_EQ(v.failure, "left_the_table") << v.detail;
  v = judgeWipe(scene, "towel", slide(-0.45, 0.65), true);
  EXPECT_EQ(v.failure, "loss_of_balance");
  auto fell = slide(-0.45, 0.65);
  fell[50].state.p_W.z() = 0.3;  // knocked off the table, then (in the data) back
  EXPECT_EQ(judgeWipe(scene, "towel", fell, false).failure, "left_the_table");
  // Back and forth counts (0 -> 0.6 -> 0: 1.2 m of wiping); resting jitter of +-4 mm (under the 1 cm step) does not.
  auto wipe = slide(0.0, 0.6);
  for (const auto& s : slide(0.6, 0.0)) wipe.push_back(sample(10.0 + s.t, s.state.p_W.x(), s.state.p_W.y(), s.state.p_W.z()));
  v = judgeWipe(scene, "towel", wipe, false);
  EXPECT_TRUE(v.success) << v.detail;
  EXPECT_NEAR(v.measure, 1.2, 0.02);
  std::vector<TaskObjectSample> jitter;
  for (int k = 0; k < 1000; ++k) jitter.push_back(sample(0.01 * k, 0.6, 0.2 + ((k % 2) ? 0.004 : -0.004), 0.763));
  v = judgeWipe(scene, "towel", jitter, false);
  EXPECT_EQ(v.failure, "too_short");
  EXPECT_LT(v.measure, 0.02);
  EXPECT_THROW(judgeWipe(scene, "cloth", fell, false), std::invalid_argument);
  EXPECT_THROW(judgeWipe(scene, "towel", {}, false), std::invalid_argument);
}

// The box (0.20 m tall) from the pick table (top 0.50 m at (0.55, 0)) to the place table (top 0.76 m
// at (0.55, 0.75)): lifted to `peak` (its bottom above the pick top), carried, set down at `end`.
std::vector<TaskObjectSample> carry(double peak, Eigen::Vector3d end, double end_roll = 0.0, double v_end = 0.0) {
  std::vector<TaskObjectSample> v;
  const Eigen::Vector3d start(0.50, 0.0, 0.60);
  const Eigen::Vector3d top(0.50, 0.0, 0.50 + peak + 0.10);
  for (int k = 0; k <= 20; ++k) {  // up
    const Eigen::Vector3d p = start + (top - start) * k / 20.0;
    v.push_back(sample(0.1 * k, p.x(), p.y(), p.z()));
  }
  for (int k = 1; k <= 30; ++k) {  // across and down
    const Eigen::Vector3d p = top + (end - top) * k / 30.0;
    v.push_back(sample(2.0 + 0.1 * k, p.x(), p.y(), p.z(), -0.2, k == 30 ? end_roll : 0.0));
  }
  v.back().state.v_W.z() = -v_end;
  return v;
}

TEST(TaskJudge, BoxIsLiftedCarriedAndPlacedWithoutDropping) {
  const TaskScene scene = loadTaskScene(test::sourcePath("config/tasks/box_scene.yaml"));
  const Eigen::Vector3d placed(0.55, 0.72, 0.76 + 0.10);
  TaskVerdict v = judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed), false);
  EXPECT_TRUE(v.success) << v.detail;
  EXPECT_NEAR(v.measure, 0.30, 1e-9);
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.10, placed), false).failure, "not_lifted");
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, {0.55, 0.20, 0.86}), false).failure,
            "not_carried");
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed + Eigen::Vector3d(0, 0, 0.05)), false)
                .failure,
            "not_placed");  // still held 5 cm above the top
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed, 0.0, 0.1), false).failure,
            "not_placed");  // still moving
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed, 0.5), false).failure, "tipped");
  // Still in the hands when the trial ends, hanging turned: not placed (not tipped: it was never set down).
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed + Eigen::Vector3d(0, 0, 0.08), 0.5, 0.3),
                     false)
                .failure,
            "not_placed");
  auto dropped = carry(0.30, placed);
  dropped[35].state.v_W.z() = -1.5;  // let go above the table
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", dropped, false).failure, "dropped");
  EXPECT_EQ(judgeBox(scene, "box", "pick_table", "place_table", carry(0.30, placed), true).failure, "loss_of_balance");
  EXPECT_THROW(judgeBox(scene, "box", "pick_table", "shelf", dropped, false), std::invalid_argument);
}

}  // namespace
}  // namespace pmg
