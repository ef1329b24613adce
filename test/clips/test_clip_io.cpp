// Clip file I/O (src/clips/clip_io.cpp): write → read round trip, deterministic text, errors that
// name the file, the line, the field and the expected range, and unknown keys refused with the
// nearest valid key.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "temp_dir.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {

using namespace pmg;

class ClipIo : public ::testing::Test {
 protected:
  void SetUp() override { robot_ = pmg::test::g1Robot(); }

  DynamicClip makeClip() const {
    const auto n = static_cast<Eigen::Index>(robot_.numJoints());
    const int N = 8;
    DynamicClip c;
    c.name = "walk_forward";
    c.axis = CommandAxis::kForward;
    c.nominal_scale = 0.5;
    c.period = 1.2;
    c.q = robot_.defaultPose().transpose().replicate(N, 1);
    for (int k = 0; k < N; ++k) c.q(k, 3) += 0.2 * std::sin(2 * M_PI * k / N);  // left knee
    c.qd = Eigen::MatrixXd::Zero(N, n);
    c.v_base = Eigen::MatrixXd::Constant(N, 3, 0.1);
    c.omega_base = Eigen::MatrixXd::Zero(N, 3);
    c.base_height = Eigen::VectorXd::Constant(N, 0.75);
    c.contact = {FootContact{0.25, 0.3}, FootContact{0.75, 0.3}};
    c.meta.source_file = "x.txt";
    c.meta.license = "MIT";
    c.meta.robot = robot_.name;
    c.meta.joint_names = robot_.jointNames();
    c.meta.frame_end = 10;
    c.meta.source_fps = 30;
    c.meta.retargeting = "test";
    c.meta.notes = "quote \" and backslash \\ survive";
    return c;
  }

  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }

  /// Writes the clip text with one line replaced, reads it back, returns the error message.
  std::string errorWith(const std::string& from, const std::string& to) const {
    std::string text = clipToYaml(makeClip());
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    text.replace(pos, from.size(), to);
    const std::string path = write("bad.yaml", text);
    try {
      readDynamicClip(path, robot_);
    } catch (const ClipFormatError& e) {
      return e.what();
    }
    return "no error";
  }

  RobotConfig robot_;
  const pmg::test::TempDir tmp_;  ///< removed with the fixture
  const std::filesystem::path dir_ = tmp_.path();
};

TEST_F(ClipIo, RoundTripIsExactToTheTextPrecisionAndByteIdentical) {
  const DynamicClip c = makeClip();
  const std::string path = (dir_ / "a.yaml").string();
  writeClip(c, path);
  const DynamicClip r = readDynamicClip(path, robot_);
  EXPECT_EQ(r.name, c.name);
  EXPECT_EQ(r.meta.notes, c.meta.notes);
  EXPECT_LT((r.q - c.q).cwiseAbs().maxCoeff(), 5e-7);
  EXPECT_DOUBLE_EQ(r.contact[1].mu, 0.75);
  EXPECT_EQ(clipToYaml(r), clipToYaml(readDynamicClip(path, robot_)));
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_EQ(clipToYaml(r), ss.str());
}

TEST_F(ClipIo, ErrorsNameFileFieldAndRange) {
  EXPECT_NE(errorWith("sigma: 0.300000}", "sigma: 0.700000}").find("contact.left.sigma: = 0.7: expected in [0, 0.5]"), std::string::npos);
  EXPECT_NE(errorWith("mu: 0.750000", "mu: 1.000000").find("contact.right.mu"), std::string::npos);
  EXPECT_NE(errorWith("period: 1.200000", "period: 0.000000").find("period: = 0: expected T in (0, 10) [s]"), std::string::npos);
  EXPECT_NE(errorWith("nominal_scale: 0.500000", "nominal_scale: -0.500000").find("nominal_scale"), std::string::npos);
  EXPECT_NE(errorWith("format_version: 1", "format_version: 2").find("format_version"), std::string::npos);
  EXPECT_NE(errorWith("left_hip_pitch_joint,", "left_hip_pitch_jnt,").find("joint_names[0]"), std::string::npos);
  EXPECT_NE(errorWith("num_samples: 8", "num_samples: 9").find("q: has 8 rows: expected 9"), std::string::npos);
  EXPECT_NE(errorWith("base_height: [0.750000", "base_height: [.nan").find("base_height[0]"), std::string::npos);
  // Joint limit: left ankle roll (index 5) limit is ±0.2618.
  const std::string msg = errorWith("kind: dynamic", "kind: dynamic");  // valid
  EXPECT_EQ(msg, "no error");
  DynamicClip c = makeClip();
  c.q(2, 5) = 0.3;
  try {
    validateClip(c, robot_, "clip.yaml");
    FAIL() << "limit violation not detected";
  } catch (const ClipFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("clip.yaml: q[2][5]: = 0.300000: expected within joint limits [-0.2618, 0.2618] of left_ankle_roll_joint"),
              std::string::npos)
        << e.what();
  }
  // The error names the line of the bad value.
  const std::string line_msg = errorWith("period: 1.200000", "period: abc");
  EXPECT_NE(line_msg.find("bad.yaml:8: period: expected a finite number, got 'abc'"), std::string::npos) << line_msg;
  EXPECT_NE(errorWith("period: 1.200000", "period: .inf").find("bad.yaml:8: period: expected a finite number"), std::string::npos);
  EXPECT_NE(errorWith("num_joints: 29", "num_joints: 28").find("bad.yaml:10: num_joints: = 28: expected 29"), std::string::npos);
  EXPECT_NE(errorWith("kind: dynamic", "kind: static").find("bad.yaml:3: kind: = 'static': expected 'dynamic'"), std::string::npos);
  EXPECT_NE(errorWith("axis: forward", "axis: forwards").find("bad.yaml:5: axis: = 'forwards': expected one of forward"),
            std::string::npos);
}

TEST_F(ClipIo, UnknownKeysNameFileLineKeyAndNearestKey) {
  EXPECT_EQ(errorWith("period: 1.200000", "perod: 1.200000"),
            (dir_ / "bad.yaml").string() + ":8: unknown key 'perod' at the top level (did you mean 'period'?)");
  EXPECT_EQ(errorWith("left: {mu: 0.250000, sigma: 0.300000}", "left: {mu: 0.250000, sigmaa: 0.300000}"),
            (dir_ / "bad.yaml").string() + ":12: unknown key 'sigmaa' in 'contact.left' (did you mean 'sigma'?)");
  EXPECT_EQ(errorWith("  license:", "  licence:"),
            (dir_ / "bad.yaml").string() + ":16: unknown key 'licence' in 'metadata' (did you mean 'license'?)");
  // A static clip's key in a dynamic clip is unknown too.
  EXPECT_EQ(errorWith("num_samples: 8", "neutral: 0.5\nnum_samples: 8")
                .rfind((dir_ / "bad.yaml").string() + ":9: unknown key 'neutral' at the top level (did you mean '", 0),
            0u);
}

TEST_F(ClipIo, LibraryRejectsDuplicateAxisDirection) {
  writeClip(makeClip(), (dir_ / "a.yaml").string());
  DynamicClip b = makeClip();
  b.name = "other_forward";
  writeClip(b, (dir_ / "b.yaml").string());
  EXPECT_THROW(loadClipLibrary(dir_.string(), robot_), ClipFormatError);
  std::filesystem::remove(dir_ / "b.yaml");
  const ClipLibrary lib = loadClipLibrary(dir_.string(), robot_);
  EXPECT_EQ(lib.dynamic_clips.size(), 1u);
  EXPECT_THROW(loadClipLibrary((dir_ / "missing").string(), robot_), ClipFormatError);
}

TEST_F(ClipIo, WriteReplacesTheFileWholeAndLeavesNoTemporaryFile) {
  const std::string path = write("w.yaml", "an older, longer text that must not survive in part\n");
  writeClip(makeClip(), path);
  EXPECT_EQ(readDynamicClip(path, robot_).name, "walk_forward");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir_)) files += e.path().filename() != "w.yaml" ? 100 : 1;
  EXPECT_EQ(files, 1);  // no ".w.yaml.tmp" left behind
  // A folder that cannot be created: the error names the file.
  const std::string blocked = write("blocker", "a file, not a folder\n") + "/sub/w.yaml";
  try {
    writeClip(makeClip(), blocked);
    FAIL() << "wrote into a file";
  } catch (const ClipFormatError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(blocked + ": cannot open", 0), 0u) << e.what();
  }
}

TEST_F(ClipIo, StaticClipRoundTripAndValueOrder) {
  StaticClip s;
  s.name = "squat";
  s.axis = PostureAxis::kHeight;
  s.values = Eigen::Vector3d(0.5, 0.6, 0.75);
  s.neutral = 0.75;
  s.q = robot_.defaultPose().transpose().replicate(3, 1);
  s.meta.robot = robot_.name;
  s.meta.joint_names = robot_.jointNames();
  const std::string path = (dir_ / "s.yaml").string();
  writeClip(s, path);
  EXPECT_EQ(readClipKind(path), ClipKind::kStatic);
  EXPECT_EQ(clipToYaml(readStaticClip(path, robot_)), clipToYaml(s));
  s.values(1) = 0.5;
  EXPECT_THROW(validateClip(s, robot_, "s"), ClipFormatError);
}

}  // namespace
