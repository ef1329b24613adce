// pmg_make_clips is reproducible: two runs give byte-identical files, and they match the shipped
// set in config/clips/g1 (values within 1e-4; bytes may differ only if another compiler/CPU
// rounds the solver differently in the 6th decimal). Slow (two full runs): label "sil".
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

TEST(MakeClips, TwoRunsAreByteIdenticalAndMatchTheShippedSet) {
  const pmg::test::TempDir tmp_dir;  // removed at the end, also when an assertion stops the test
  const fs::path tmp = tmp_dir.path();
  for (const char* run : {"a", "b"}) {
    fs::create_directories(tmp / run);
    const std::string cmd = std::string(PMG_MAKE_CLIPS_EXE) + " --out " + (tmp / run).string() + " > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  const pmg::RobotConfig& robot = pmg::test::g1Robot();
  int files = 0;
  for (const auto& e : fs::directory_iterator(pmg::test::g1ClipDir())) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    SCOPED_TRACE(name);
    ++files;
    EXPECT_EQ(slurp(tmp / "a" / name), slurp(tmp / "b" / name)) << "not deterministic";
    if (e.path().extension() != ".yaml") continue;
    if (name == pmg::kConsistencyMapFile) {  // not a clip: the map of the set, compared as numbers
      const auto a = pmg::readConsistencyMap((tmp / "a" / name).string()), s = pmg::readConsistencyMap(e.path().string());
      ASSERT_EQ(a.delta.rows(), s.delta.rows());
      EXPECT_LT((a.delta - s.delta).cwiseAbs().maxCoeff(), 1e-4);
      continue;
    }
    const std::string fresh = (tmp / "a" / name).string();
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
  EXPECT_GE(files, 11);  // 9 clips + consistency_map.yaml + report.md
}

}  // namespace
