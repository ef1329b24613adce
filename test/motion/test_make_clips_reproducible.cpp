// pmg_make_clips is reproducible: two runs give byte-identical files, and they match the shipped
// set in config/clips/g1 (and, with --walking-height, config/clips/g1_walking_height) (values within 1e-4; bytes may differ only if another compiler/CPU
// rounds the solver differently in the 6th decimal). Slow (two full runs): label "sil".
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/clips/clip_transforms.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/motion/posture_synthesis.hpp"
#include "temp_dir.hpp"

#ifndef PMG_MAKE_CLIPS_EXE
#error "PMG_MAKE_CLIPS_EXE must name the pmg_make_clips executable"
#endif

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Compares every file of the shipped set @p shipped with the fresh run @p fresh (and, when given,
// byte for byte with a second fresh run @p again); returns the number of files compared.
int expectMatchesShippedSet(const fs::path& shipped, const fs::path& fresh_dir, const fs::path& again = {}) {
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  int files = 0;
  for (const auto& e : fs::directory_iterator(shipped)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    SCOPED_TRACE(name);
    ++files;
    if (!again.empty()) {
      EXPECT_EQ(slurp(fresh_dir / name), slurp(again / name)) << "not deterministic";
    }
    if (e.path().extension() != ".yaml") continue;
    if (name == pmg::kConsistencyMapFile) {  // not a clip: the map of the set, compared as numbers
      const auto a = pmg::readConsistencyMap((fresh_dir / name).string()), s = pmg::readConsistencyMap(e.path().string());
      EXPECT_EQ(a.delta.rows(), s.delta.rows());
      if (a.delta.rows() != s.delta.rows()) continue;
      EXPECT_LT((a.delta - s.delta).cwiseAbs().maxCoeff(), 1e-4);
      continue;
    }
    const std::string fresh = (fresh_dir / name).string();
    if (pmg::readClipKind(fresh) == pmg::ClipKind::kDynamic) {
      const auto a = pmg::readDynamicClip(fresh, robot), s = pmg::readDynamicClip(e.path().string(), robot);
      EXPECT_LT((a.q - s.q).cwiseAbs().maxCoeff(), 1e-4);
      EXPECT_LT((a.v_base - s.v_base).cwiseAbs().maxCoeff(), 1e-4);
      EXPECT_NEAR(a.nominal_scale, s.nominal_scale, 1e-4);
    } else {
      const auto a = pmg::readStaticClip(fresh, robot), s = pmg::readStaticClip(e.path().string(), robot);
      EXPECT_LT((a.q - s.q).cwiseAbs().maxCoeff(), 1e-4);
      EXPECT_LT((a.values - s.values).cwiseAbs().maxCoeff(), 1e-4);
    }
  }
  return files;
}

// Runs pmg_make_clips with @p flags into @p out (created), output discarded; returns its exit status.
int runMakeClips(const std::string& flags, const fs::path& out) {
  fs::create_directories(out);
  const std::string cmd = std::string(PMG_MAKE_CLIPS_EXE) + " " + flags + (flags.empty() ? "" : " ") + "--out " + out.string() +
                          " > /dev/null 2>&1";
  return std::system(cmd.c_str());
}

TEST(MakeClips, TwoRunsAreByteIdenticalAndMatchTheShippedSet) {
  const pmg::test::TempDir tmp_dir;  // removed at the end, also when an assertion stops the test
  const fs::path tmp = tmp_dir.path();
  for (const char* run : {"a", "b"}) {
    ASSERT_EQ(runMakeClips("", tmp / run), 0) << run;
  }
  EXPECT_GE(expectMatchesShippedSet(pmg::test::g1ClipDir(), tmp / "a", tmp / "b"), 11);  // 9 clips + map + report.md
}

// --walking-height (docs/motion.md "Walking height"): the set config/clips/g1_walking_height is this
// run's output, and its walking templates carry the pelvis higher than the captured ones.
TEST(MakeClips, WalkingHeightSetMatchesTheShippedOneAndWalksTaller) {
  const pmg::test::TempDir tmp_dir;
  const fs::path out = tmp_dir.path() / "wh";
  ASSERT_EQ(runMakeClips("--walking-height 1.0 --walking-height-min-knee 0.05", out), 0);
  const fs::path shipped = fs::path(pmg::test::g1ClipDir()).parent_path() / "g1_walking_height";
  EXPECT_GE(expectMatchesShippedSet(shipped, out), 11);
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  for (const char* clip : {"walk_forward", "walk_backward", "walk_lateral_left", "walk_lateral_right"}) {
    SCOPED_TRACE(clip);
    const auto raised = pmg::readDynamicClip((out / (std::string(clip) + ".yaml")).string(), robot);
    const auto captured = pmg::readDynamicClip(pmg::test::g1ClipDir() + "/" + clip + ".yaml", robot);
    EXPECT_GT(raised.base_height.mean() - captured.base_height.mean(), 0.004);
  }
  const auto bend = pmg::readStaticClip((out / "bend.yaml").string(), robot);
  EXPECT_EQ(bend.q, pmg::readStaticClip(pmg::test::g1ClipDir() + "/bend.yaml", robot).q) << "postures unchanged";
}

// --symmetric-gaits with the walking height (docs/motion.md "Symmetric gaits"): the set
// config/clips/g1_walking_height_symmetric is this run's output; its forward and backward walks step
// alike on both feet (to the files' 6 decimals), its side-steps, turns and postures are the walking-height set's.
TEST(MakeClips, SymmetricGaitSetMatchesTheShippedOneAndStepsAlikeOnBothFeet) {
  const pmg::test::TempDir tmp_dir;
  const fs::path out = tmp_dir.path() / "sym";
  ASSERT_EQ(runMakeClips("--walking-height 1.0 --walking-height-min-knee 0.05 --symmetric-gaits", out), 0);
  const fs::path clips = fs::path(pmg::test::g1ClipDir()).parent_path();
  EXPECT_GE(expectMatchesShippedSet(clips / "g1_walking_height_symmetric", out), 11);
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  const pmg::GeneratorJointSpace joints = pmg::generatorJointSpace(robot);
  for (const char* clip : {"walk_forward", "walk_backward"}) {
    SCOPED_TRACE(clip);
    const auto c = pmg::readDynamicClip((out / (std::string(clip) + ".yaml")).string(), robot);
    const auto raised = pmg::readDynamicClip((clips / "g1_walking_height" / (std::string(clip) + ".yaml")).string(), robot);
    const Eigen::Index N = c.q.rows(), h = N / 2;
    Eigen::MatrixXd half_on(N, c.q.cols()), raised_half_on(N, c.q.cols());
    for (Eigen::Index k = 0; k < N; ++k) {
      half_on.row(k) = c.q.row((k + h) % N);
      raised_half_on.row(k) = raised.q.row((k + h) % N);
    }
    EXPECT_LT((half_on - pmg::mirrorJoints(c.q, joints)).cwiseAbs().maxCoeff(), 2e-6);
    EXPECT_GT((raised_half_on - pmg::mirrorJoints(raised.q, joints)).cwiseAbs().maxCoeff(), 0.05);  // the capture's steps differ
    EXPECT_NEAR(c.nominal_scale, raised.nominal_scale, 1e-6);
    double dmu = c.contact[1].mu - c.contact[0].mu;
    dmu -= std::floor(dmu);
    EXPECT_NEAR(dmu, 0.5, 1.0 / static_cast<double>(N));
  }
  for (const char* clip : {"walk_lateral_left", "turn_right"}) {
    SCOPED_TRACE(clip);
    const auto c = pmg::readDynamicClip((out / (std::string(clip) + ".yaml")).string(), robot);
    const auto raised = pmg::readDynamicClip((clips / "g1_walking_height" / (std::string(clip) + ".yaml")).string(), robot);
    EXPECT_EQ(c.q, raised.q);
  }
}

// Torso pitch (feet flat) of the standing pose plus the bend template's offset at command p
// (linear between the rows bracketing p, as the generator interpolates; PMG eq. 10), relative to the
// standing pose's own: what the reference carries for a pitch command p.
double pitchOnStandingPose(const pmg::StaticClip& c, double p, pmg::motion::PostureProbe& probe, const Eigen::VectorXd& q_stand) {
  auto rowAt = [&](double v) {
    Eigen::Index k = 0;
    while (k + 2 < c.values.size() && c.values(k + 1) < v) ++k;
    const double t = std::clamp((v - c.values(k)) / (c.values(k + 1) - c.values(k)), 0.0, 1.0);
    return Eigen::VectorXd((1.0 - t) * c.q.row(k).transpose() + t * c.q.row(k + 1).transpose());
  };
  const Eigen::VectorXd q = q_stand + rowAt(p) - rowAt(c.neutral);
  return probe.measure(q).torso_pitch - probe.measure(q_stand).torso_pitch;
}

// --bend-on-standing-pose (not the shipped set, docs/motion.md): a pitch command p bends the
// reference by p, between the rows too; the shipped bend, labelled by the capture's absolute pitch
// (upright row 0.065 rad), bends it by about p - 0.065. Both runs write a valid, complete set.
TEST(MakeClips, BendOnStandingPoseCarriesTheCommandedTorsoPitch) {
  const pmg::test::TempDir tmp_dir;
  const fs::path out = tmp_dir.path() / "opt";
  ASSERT_EQ(runMakeClips("--bend-on-standing-pose", out), 0);
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  const pmg::StaticClip relabelled = pmg::readStaticClip((out / "bend.yaml").string(), robot);
  const pmg::StaticClip shipped = pmg::readStaticClip((fs::path(pmg::test::g1ClipDir()) / "bend.yaml").string(), robot);
  EXPECT_NEAR(relabelled.neutral, 0.0, 1e-9);
  EXPECT_LT((relabelled.q - shipped.q).cwiseAbs().maxCoeff(), 1e-9) << "only the values change";
  const pmg::KinematicModel model(robot);
  pmg::motion::PostureProbe probe(model);
  const Eigen::VectorXd q_stand = robot.defaultPose();
  for (const double p : {0.1, 0.3, 0.45, 0.8}) {
    SCOPED_TRACE(p);
    EXPECT_NEAR(pitchOnStandingPose(relabelled, p, probe, q_stand), p, 0.01);
    EXPECT_NEAR(pitchOnStandingPose(shipped, p, probe, q_stand), p - shipped.neutral, 0.02);
  }
}

}  // namespace
