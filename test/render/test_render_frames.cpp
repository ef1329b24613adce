// pmg::render with OpenGL (label sil): renders the G1 with MuJoCo 2.2 and checks what the pixels
// must show: a robot (not a blank frame), deterministic output, leg joints moving pixels below the
// arms' and on the correct side, a camera that follows the pelvis, labels confined to their
// corner, pmg_render_log's strip layout, and a task scene's free object placed where its track says. Without $DISPLAY the suite starts its own Xvfb; it
// skips (GTEST_SKIP, with the reason) when no OpenGL context can be made (no Xvfb, no GLX).
#include <cstdlib>
#include <memory>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/task_scene.hpp"
#include "pmg/render/gl_context.hpp"
#include "pmg/render/scene_renderer.hpp"
#include "render_test_util.hpp"

namespace pmg::render {
namespace {

using test::difference;

class RenderFrames : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    robot_ = std::make_unique<RobotConfig>(pmg::test::g1Robot());
    const char* display = std::getenv("DISPLAY");
    if (display == nullptr || display[0] == '\0') {  // CI: no display, bring a private Xvfb
      xvfb_ = std::make_unique<test::ScopedXvfb>();
      const std::string why = xvfb_->start();
      if (!why.empty()) {
        skip_reason_ = "$DISPLAY is not set and " + why;
        return;
      }
    }
    try {
      gl_ = GlContext::create();
    } catch (const RenderError& e) {
      skip_reason_ = e.what();
      return;
    }
    RenderOptions fast;  // small and without the extra passes: the checks below need no shading detail
    fast.width = 200;
    fast.height = 300;
    fast.samples = 0;
    fast.shadows = false;
    fast.reflections = false;
    fast.show_labels = false;
    renderer_ = std::make_unique<SceneRenderer>(loadMujocoModel(robot_->mjcf_path), *robot_, fast);
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    gl_.reset();
    xvfb_.reset();
    robot_.reset();
  }
  void SetUp() override {
    if (!skip_reason_.empty()) GTEST_SKIP() << "no OpenGL context: " << skip_reason_;
  }

  static StateSample standing(double x = 0.0, double y = 0.0) {
    StateSample s;
    s.t = 1.0;
    s.q = robot_->defaultPose();
    s.p_WB = Eigen::Vector3d(x, y, 0.95);
    return s;
  }
  static StateSample withJoints(StateSample s, const std::vector<std::pair<std::string, double>>& q) {
    for (const auto& [name, value] : q) {
      const int i = robot_->jointIndex(name);
      EXPECT_GE(i, 0) << name;
      s.q[i] = value;
    }
    return s;
  }
  static Image render(const StateSample& s) {
    Image image;
    renderer_->render(s, image);
    return image;
  }

  static inline std::unique_ptr<RobotConfig> robot_;
  static inline std::unique_ptr<test::ScopedXvfb> xvfb_;
  static inline std::unique_ptr<GlContext> gl_;
  static inline std::unique_ptr<SceneRenderer> renderer_;
  static inline std::string skip_reason_;
};

const std::vector<std::pair<std::string, double>> kLeftLegForward = {{"left_hip_pitch_joint", -1.0},
                                                                     {"left_knee_joint", 1.4}};
const std::vector<std::pair<std::string, double>> kRightLegForward = {{"right_hip_pitch_joint", -1.0},
                                                                      {"right_knee_joint", 1.4}};

TEST_F(RenderFrames, ShowsTheRobotAndIsDeterministic) {
  const Image a = render(standing());
  ASSERT_EQ(a.width, 200);
  ASSERT_EQ(a.height, 300);
  EXPECT_GT(test::luminanceStdDev(a), 15.0) << "frame is (nearly) uniform";
  const Image b = render(standing());
  const Image c = render(standing());
  // Bit-identical from the second frame on; llvmpipe's very first frame after the context was
  // made differs by at most 2 levels in a handful of pixels.
  EXPECT_EQ(difference(b, c, 0).count, 0) << "the same pose rendered twice differs";
  EXPECT_EQ(difference(a, b, 2).count, 0) << "the first frame differs by more than 2 levels";
}

TEST_F(RenderFrames, LegJointsMovePixelsBelowThePelvisOnTheirOwnSide) {
  const Image base = render(standing());
  const test::Difference left = difference(base, render(withJoints(standing(), kLeftLegForward)));
  const test::Difference right = difference(base, render(withJoints(standing(), kRightLegForward)));
  const test::Difference arm = difference(base, render(withJoints(standing(), {{"left_shoulder_pitch_joint", -1.5}})));
  ASSERT_GT(left.count, 300);
  ASSERT_GT(right.count, 300);
  ASSERT_GT(arm.count, 100);
  // The camera looks at the pelvis − 0.25 m: the legs swing in the lower part of the frame, the arm above them.
  EXPECT_GT(left.centroid_y, 0.5 * base.height);
  EXPECT_GT(right.centroid_y, 0.5 * base.height);
  EXPECT_LT(arm.centroid_y, left.centroid_y - 20.0);
  // Seen from the front-right quarter, the robot's left leg is on the right of the image.
  EXPECT_GT(left.centroid_x, right.centroid_x + 5.0);
}

TEST_F(RenderFrames, CameraFollowsThePelvis) {
  // The same leg motion seen with the robot at two places 2.2 m apart changes the same pixels.
  const test::Difference here =
      difference(render(standing()), render(withJoints(standing(), kLeftLegForward)));
  const test::Difference there =
      difference(render(standing(1.8, -1.3)), render(withJoints(standing(1.8, -1.3), kLeftLegForward)));
  ASSERT_GT(here.count, 300);
  EXPECT_NEAR(there.centroid_x, here.centroid_x, 3.0);
  EXPECT_NEAR(there.centroid_y, here.centroid_y, 3.0);
  EXPECT_NEAR(static_cast<double>(there.count), static_cast<double>(here.count), 0.1 * here.count);
}

TEST_F(RenderFrames, LabelsStayInTheTopLeftCorner) {
  Image plain, labelled;
  renderer_->render(standing(), "", "", plain);
  renderer_->render(standing(), "t\nvx", "1.00 s\n+0.50 m/s", labelled);
  const test::Difference d = difference(plain, labelled);
  EXPECT_GT(d.count, 50);
  EXPECT_LT(d.max_x, 3 * plain.width / 4);
  EXPECT_LT(d.max_y, plain.height / 3);
}

TEST_F(RenderFrames, PlacesATaskScenesObjectWhereItsPoseSays) {
  // The wiping scene (robot + table + towel) composed as pmg_teleop_bench does, towel moved 0.4 m
  // along the table: the changed pixels are the towel's (on the table, below the look-at point), and
  // they move the way the camera sees +y (to the right of the image from the front-right quarter).
  const std::string dir = test::tempDir("task_scene");
  const TaskScene scene = loadTaskScene(resolveData("config/tasks/wipe_scene.yaml").string());
  const RobotConfig composed = robotWithTaskScene(*robot_, scene, dir + "/scene.xml");
  RenderOptions fast = renderer_->options();
  SceneRenderer r(loadMujocoModel(composed.mjcf_path), composed, fast);
  Image none, a, b;
  r.render(standing(), none);
  const Eigen::Vector4d upright(1, 0, 0, 0);
  r.setFreeBodyPose("task_towel", Eigen::Vector3d(0.45, -0.2, 0.673), upright);
  r.render(standing(), a);
  r.setFreeBodyPose("task_towel", Eigen::Vector3d(0.45, 0.2, 0.673), upright);
  r.render(standing(), b);
  const test::Difference moved = difference(a, b);
  ASSERT_GT(moved.count, 200) << "moving the towel 0.4 m changed too few pixels";
  EXPECT_GT(moved.centroid_y, 0.4 * a.height);  // on the table, in front of the robot's hips
  const test::Difference from_a = difference(none, a), from_b = difference(none, b);
  EXPECT_GT(from_a.count, 100);
  EXPECT_GT(from_b.count, 100);
  // Camera from the front-right (azimuth 130): the robot's +y (its left) is on the image's right.
  EXPECT_GT(from_b.centroid_x, from_a.centroid_x + 10.0);
  EXPECT_THROW(r.setFreeBodyPose("task_cup", Eigen::Vector3d::Zero(), upright), std::invalid_argument);
  EXPECT_THROW(r.setFreeBodyPose("pelvis", Eigen::Vector3d::Zero(), upright), std::invalid_argument);
  EXPECT_THROW(r.setFreeBodyPose("task_towel", Eigen::Vector3d::Zero(), Eigen::Vector4d(2, 0, 0, 0)), std::invalid_argument);
}

TEST_F(RenderFrames, CliWritesAStripOfDistinctFrames) {
  const std::string dir = test::tempDir("cli_strip");
  std::vector<StateSample> samples;
  for (int k = 0; k < 30; ++k) {
    StateSample s = standing(0.02 * k);
    s.t = 0.1 * k;
    s.q[robot_->jointIndex("left_knee_joint")] = 0.05 * k;
    s.q[robot_->jointIndex("right_hip_pitch_joint")] = -0.03 * k;
    samples.push_back(s);
  }
  test::writeStateLog(dir + "/run.lcmlog", samples);
  const std::string cmd = std::string(PMG_RENDER_LOG_EXE) + " --log " + dir + "/run.lcmlog --out-dir " + dir +
                          "/out --frames 3 --width 120 --height 180 --samples 0 --no-shadows --no-reflections" +
                          " --video-fps 5 > " + dir + "/stdout.txt 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd;
  const Image strip = readPng(dir + "/out/strip.png");
  ASSERT_EQ(strip.width, 3 * 120 + 2 * 4);
  ASSERT_EQ(strip.height, 180);
  Image frame[3];
  for (int i = 0; i < 3; ++i) {
    frame[i] = Image(120, 180);
    for (int y = 0; y < 180; ++y)
      for (int x = 0; x < 120; ++x)
        for (int c = 0; c < 3; ++c) frame[i].pixel(x, y)[c] = strip.pixel(i * 124 + x, y)[c];
    EXPECT_GT(test::luminanceStdDev(frame[i]), 15.0) << "frame " << i;
  }
  EXPECT_GT(difference(frame[0], frame[1]).count, 100);
  EXPECT_GT(difference(frame[1], frame[2]).count, 100);
  EXPECT_EQ(strip.pixel(121, 90)[0], 255);  // white gap between frames
  // Video frames: t = 0.0, 0.2, ..., 2.8 s at 5 fps -> 15 files, same size as a frame.
  for (int k : {0, 14}) {
    char name[64];
    std::snprintf(name, sizeof(name), "/out/frames/frame_%05d.png", k);
    const Image f = readPng(dir + name);
    EXPECT_EQ(f.width, 120);
    EXPECT_EQ(f.height, 180);
  }
  EXPECT_THROW(readPng(dir + "/out/frames/frame_00015.png"), std::runtime_error);
}

}  // namespace
}  // namespace pmg::render
