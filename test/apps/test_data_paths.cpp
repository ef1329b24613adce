// pmg::dataDir() and friends (src/common/data_paths.cpp): the data directory of the build tree, the
// PMG_DATA_DIR override, paths relative to the file that names them, output checks that create
// nothing.
#include "pmg/common/data_paths.hpp"

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

/// Sets or clears PMG_DATA_DIR for one test and restores it afterwards.
class ScopedDataDirEnv {
 public:
  explicit ScopedDataDirEnv(const char* value) {
    if (const char* old = std::getenv("PMG_DATA_DIR")) old_ = old;
    if (value) ::setenv("PMG_DATA_DIR", value, 1);
    else ::unsetenv("PMG_DATA_DIR");
  }
  ~ScopedDataDirEnv() {
    if (old_) ::setenv("PMG_DATA_DIR", old_->c_str(), 1);
    else ::unsetenv("PMG_DATA_DIR");
  }

 private:
  std::optional<std::string> old_;
};

/// A fresh folder under the system temp dir, removed at the end.
struct TempFolder {
  fs::path path = fs::temp_directory_path() / ("pmg_test_data_paths_" + std::to_string(::getpid()));
  TempFolder() { fs::create_directories(path); }
  ~TempFolder() { fs::remove_all(path); }
};

}  // namespace

TEST(DataPaths, BuildTreeDataDirHoldsTheCheckoutsConfig) {
  ScopedDataDirEnv env(nullptr);
  const fs::path dir = pmg::dataDir();
  EXPECT_TRUE(dir.is_absolute());
  EXPECT_EQ(dir.filename(), "pmg");
  EXPECT_EQ(dir.parent_path().filename(), "share");
  // The test binary is in build/bin/tests: build/share/pmg, whose config/ links to the checkout.
  EXPECT_TRUE(fs::is_regular_file(dir / "config/robots/g1/g1.yaml")) << dir;
  EXPECT_TRUE(fs::is_regular_file(dir / "scripts/calib_plot.py")) << dir;
  EXPECT_EQ(pmg::resolveData("config/robots/g1/g1.yaml"), dir / "config/robots/g1/g1.yaml");
  EXPECT_EQ(pmg::executableDir().filename(), "tests");
}

TEST(DataPaths, EnvironmentOverridesAndIsMadeAbsolute) {
  {
    ScopedDataDirEnv env("/opt/pmg/share/pmg/");
    EXPECT_EQ(pmg::dataDir(), fs::path("/opt/pmg/share/pmg"));
    EXPECT_EQ(pmg::resolveData("config/gco/g1.yaml"), fs::path("/opt/pmg/share/pmg/config/gco/g1.yaml"));
    EXPECT_EQ(pmg::resolveData("/abs/robot.yaml"), fs::path("/abs/robot.yaml"));
  }
  {
    ScopedDataDirEnv env("relative/data");
    EXPECT_EQ(pmg::dataDir(), (fs::current_path() / "relative/data").lexically_normal());
  }
  {
    ScopedDataDirEnv env("");  // empty = unset
    EXPECT_EQ(pmg::dataDir().filename(), "pmg");
  }
}

TEST(DataPaths, RelativePathsResolveAgainstTheNamingFile) {
  EXPECT_EQ(pmg::resolveRelativeTo("config/controller/g1_sil.yaml", "../robots/g1/g1.yaml"),
            fs::path("config/robots/g1/g1.yaml"));
  EXPECT_EQ(pmg::resolveRelativeTo("/data/ctl/a.yaml", "../clips/g1"), fs::path("/data/clips/g1"));
  EXPECT_EQ(pmg::resolveRelativeTo("a.yaml", "b.yaml"), fs::path("b.yaml"));
  EXPECT_EQ(pmg::resolveRelativeTo("/data/ctl/a.yaml", "/elsewhere/b.yaml"), fs::path("/elsewhere/b.yaml"));
  EXPECT_EQ(pmg::resolveRelativeTo("/data/ctl/a.yaml", ""), fs::path());
}

TEST(DataPaths, RequireWritableFileChecksWithoutCreating) {
  TempFolder tmp;
  const fs::path fresh = tmp.path / "report.json";
  EXPECT_NO_THROW(pmg::requireWritableFile(fresh));
  EXPECT_FALSE(fs::exists(fresh)) << "the check must not create the file";
  std::ofstream(tmp.path / "existing.json") << "{}";
  EXPECT_NO_THROW(pmg::requireWritableFile(tmp.path / "existing.json"));

  const fs::path missing_folder = tmp.path / "no_such_folder" / "report.json";
  try {
    pmg::requireWritableFile(missing_folder);
    FAIL() << "no error for a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing_folder.string() + ": cannot write"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(pmg::requireWritableFile(tmp.path), std::runtime_error);  // a folder
  EXPECT_THROW(pmg::requireWritableFile(""), std::runtime_error);
  EXPECT_FALSE(fs::exists(tmp.path / "no_such_folder"));
}
