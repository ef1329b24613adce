// pmg_make_clips (apps/motion/make_clips.cpp) writes all or nothing. Issue 11: with a truncated
// BVH it used to write 6 of the 8 clips before failing, leaving a mixed set behind. Now every mocap
// file is read before any retargeting, and the files are renamed into place only when all were
// built and written: a failure leaves the output folder as it was.
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "temp_dir.hpp"

#ifndef PMG_MAKE_CLIPS_EXE
#error "PMG_MAKE_CLIPS_EXE must name the pmg_make_clips executable"
#endif

namespace {

namespace fs = std::filesystem;

struct ToolRun {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr
};

ToolRun runMakeClips(const std::string& args) {
  ToolRun r;
  const std::string cmd = std::string(PMG_MAKE_CLIPS_EXE) + " " + args + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p) != nullptr) r.output += buf;
  const int status = ::pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(MakeClips, ATruncatedBvhLeavesTheOutputFolderAsItWas) {
  const pmg::test::TempDir tmp;
  // A copy of the mocap data whose last-used BVH (the bend, built after the dynamic clips and the
  // squat) is cut in the middle of its motion data.
  const fs::path data = tmp.path() / "motions";
  fs::copy(pmg::test::sourcePath("data/motions"), data, fs::copy_options::recursive);
  const fs::path bvh = data / "cmu_bvh" / "cmu_115_01_bend_at_waist_excerpt.bvh";
  const std::string text = pmg::test::readTextFile(bvh.string());
  const std::size_t motion = text.find("MOTION");
  ASSERT_NE(motion, std::string::npos);
  tmp.write("motions/cmu_bvh/cmu_115_01_bend_at_waist_excerpt.bvh", text.substr(0, motion + (text.size() - motion) / 2));
  // An output folder holding an earlier set.
  const std::string old_clip = tmp.write("out/walk_forward.yaml", "an earlier walk_forward\n");
  const std::string old_report = tmp.write("out/report.md", "an earlier report\n");

  const ToolRun r = runMakeClips("--data " + data.string() + " --out " + (tmp.path() / "out").string());
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cmu_115_01_bend_at_waist_excerpt.bvh"), std::string::npos) << r.output;
  // Nothing was retargeted (the inputs are read first) and nothing was written.
  EXPECT_EQ(r.output.find("walk_forward "), std::string::npos) << r.output;
  int files = 0;
  for (const auto& e : fs::directory_iterator(tmp.path() / "out")) {
    ++files;
    EXPECT_TRUE(e.path() == old_clip || e.path() == old_report) << e.path();
  }
  EXPECT_EQ(files, 2);
  EXPECT_EQ(pmg::test::readTextFile(old_clip), "an earlier walk_forward\n");
  EXPECT_EQ(pmg::test::readTextFile(old_report), "an earlier report\n");
}

TEST(MakeClips, AnUnwritableOutputFolderFailsWithoutPartialFiles) {
  const pmg::test::TempDir tmp;
  // --out names a regular file: the folder cannot be created, the run fails naming it.
  const std::string blocker = tmp.write("out", "not a folder\n");
  const ToolRun r = runMakeClips("--out " + blocker + "/clips");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(blocker), std::string::npos) << r.output;
  EXPECT_EQ(pmg::test::readTextFile(blocker), "not a folder\n");
}

}  // namespace
