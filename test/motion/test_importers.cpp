// Mocap importers: DeepMimic and BVH files parse into plausible keypoints, malformed files give
// errors naming file and line, and mirroring a human motion swaps sides.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/motion/amp_npz.hpp"
#include "pmg/motion/bvh.hpp"
#include "pmg/motion/deepmimic.hpp"
#include "temp_dir.hpp"

namespace {

using namespace pmg::motion;

/// Writes @p text to a per-process scratch folder (removed at exit) and returns the path.
std::string tempFile(const std::string& name, const std::string& text) {
  static const pmg::test::TempDir scratch("motion_importers");
  return scratch.write(name, text);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(Importers, DeepMimicWalkIsOneCycleAtThirtyHertz) {
  const DeepMimicMotion m = readDeepMimicMotion(pmg::test::sourcePath("data/motions/deepmimic/humanoid3d_walk.txt"));
  EXPECT_TRUE(m.loop_wrap);
  EXPECT_EQ(m.frames.size(), 39u);
  EXPECT_NEAR(m.fps, 30.0, 0.01);
  const HumanMotion h = deepMimicToHuman(m);
  EXPECT_NEAR(h.legLength(), 0.8314, 1e-3);  // skeleton constant
  // Walks ~1.2 m along +x (W) in the cycle, pelvis ~0.85 m above the ground.
  const double dx = h.frames.back().p_WK[0].x() - h.frames.front().p_WK[0].x();
  EXPECT_NEAR(dx, 1.24, 0.05);
  EXPECT_NEAR(h.frames[0].p_WK[0].z(), 0.85, 0.05);
  // Left is +y: the left hip is at larger y than the right one when facing +x.
  EXPECT_GT(h.frames[0].p_WK[static_cast<int>(Keypoint::kLeftHip)].y(), h.frames[0].p_WK[static_cast<int>(Keypoint::kRightHip)].y());
}

TEST(Importers, CmuBvhSquatGoesDownAndUp) {
  const BvhMotion b = readBvh(pmg::test::sourcePath("data/motions/cmu_bvh/cmu_115_07_squat_excerpt.bvh"));
  EXPECT_EQ(b.numFrames(), 125);
  EXPECT_EQ(b.num_channels, 96);
  const HumanMotion h = bvhToHuman(b, 0.056444);
  double lo = 1e9;
  for (const auto& f : h.frames) lo = std::min(lo, f.p_WK[0].z());
  // SOURCE.md: pelvis 1.02 m standing, 0.56 m at the bottom (ground at the feet).
  EXPECT_NEAR(h.frames.front().p_WK[0].z(), 1.02, 0.06);
  EXPECT_NEAR(lo, 0.56, 0.06);
}

TEST(Importers, AmpNpzWalk) {
  const auto arrays = readNpz(pmg::test::sourcePath("data/motions/isaaclab_amp/humanoid_walk.npz"));
  ASSERT_EQ(arrays.count("dof_positions"), 1u);
  EXPECT_EQ(arrays.at("dof_positions").shape, (std::vector<std::size_t>{154, 28}));
  EXPECT_EQ(arrays.at("dof_names").descr, "<U16");
  const HumanMotion h = ampNpzToHuman(pmg::test::sourcePath("data/motions/isaaclab_amp/humanoid_walk.npz"));
  EXPECT_EQ(h.numFrames(), 154);
  EXPECT_DOUBLE_EQ(h.fps, 60.0);
  // SOURCE.md: pelvis speed ~1.5 m/s.
  const Eigen::Vector3d d = h.frames.back().p_WK[0] - h.frames.front().p_WK[0];
  EXPECT_NEAR(d.head<2>().norm() / ((h.numFrames() - 1) / h.fps), 1.5, 0.2);
  // A file that is not a ZIP archive is rejected with its name.
  const std::string bad = tempFile("pmg_bad.npz", "not a zip");
  EXPECT_NE(errorOf([&] { readNpz(bad); }).find("pmg_bad.npz: not a ZIP/.npz archive"), std::string::npos);
}

TEST(Importers, MalformedFilesNameFileAndLine) {
  const std::string bvh = tempFile("pmg_bad.bvh",
                                   "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation "
                                   "Xrotation\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0 0 0 0\n0 0 0 0 0\n");
  const std::string e1 = errorOf([&] { readBvh(bvh); });
  EXPECT_NE(e1.find("pmg_bad.bvh:11: frame 1: 5 values: expected 6"), std::string::npos) << e1;
  const std::string bvh2 = tempFile("pmg_bad2.bvh", "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 1 Wrotation\n}\n");
  const std::string e2 = errorOf([&] { readBvh(bvh2); });
  EXPECT_NE(e2.find("pmg_bad2.bvh:5: channel 'Wrotation'"), std::string::npos) << e2;
  const std::string dm = tempFile("pmg_bad.txt", "{\"Loop\": \"wrap\",\n\"Frames\": [\n[0.1, 0, 0],\n[0.1, 0, 0]\n]}\n");
  const std::string e3 = errorOf([&] { readDeepMimicMotion(dm); });
  EXPECT_NE(e3.find("pmg_bad.txt:3: Frames[0]: expected a list of 44 numbers, got 3"), std::string::npos) << e3;
  EXPECT_NE(errorOf([&] { readBvh("/nonexistent.bvh"); }).find("/nonexistent.bvh: cannot open"), std::string::npos);
}

TEST(Importers, MirroredHumanMotionSwapsSides) {
  const HumanMotion h = deepMimicToHuman(readDeepMimicMotion(pmg::test::sourcePath("data/motions/deepmimic/humanoid3d_walk.txt")));
  const HumanMotion m = h.mirrored();
  const auto L = static_cast<std::size_t>(Keypoint::kLeftKnee), R = static_cast<std::size_t>(Keypoint::kRightKnee);
  for (std::size_t k = 0; k < h.frames.size(); k += 7) {
    EXPECT_NEAR(m.frames[k].p_WK[L].y(), -h.frames[k].p_WK[R].y(), 1e-12);
    EXPECT_NEAR(m.frames[k].p_WK[L].x(), h.frames[k].p_WK[R].x(), 1e-12);
  }
}

}  // namespace
