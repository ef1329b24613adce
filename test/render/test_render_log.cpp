// pmg::render without OpenGL: reading PMG_STATE event logs and object tracks, frame times, PNG
// output, strip layout, and pmg_render_log's error messages (no display, log of another robot, a bad
// object track).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

#include "pmg/render/image.hpp"
#include "pmg/render/object_track.hpp"
#include "pmg/render/state_track.hpp"
#include "render_test_util.hpp"

namespace pmg::render {
namespace {

using test::tempDir;
using test::writeStateLog;

StateSample sampleAt(double t, int n, double q0) {
  StateSample s;
  s.t = t;
  s.q = Eigen::VectorXd::LinSpaced(n, q0, q0 + 1.0);
  s.p_WB = Eigen::Vector3d(0.1 * t, -0.2, 0.95);
  s.quat_WB = Eigen::Vector4d(std::cos(0.1 * t), 0.0, 0.0, std::sin(0.1 * t));
  s.command = Eigen::Vector3d(0.5, 0.0, -0.3);
  return s;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(StateTrack, ReadsStateMessagesInOrderAndSkipsOtherChannels) {
  const std::string log = tempDir("read") + "/run.lcmlog";
  std::vector<StateSample> written = {sampleAt(0.0, 29, 0.0), sampleAt(0.01, 29, 0.5), sampleAt(0.02, 29, -0.5)};
  written[1].quat_WB *= 1.05;  // slightly off-unit, as accumulated float error would leave it
  writeStateLog(log, written);
  const StateTrack track = readStateTrack(log, 29);
  ASSERT_EQ(track.samples.size(), 3u);
  EXPECT_EQ(track.source, log);
  for (std::size_t i = 0; i < 3; ++i) {
    const StateSample& s = track.samples[i];
    EXPECT_NEAR(s.t, written[i].t, 1e-9);
    EXPECT_TRUE(s.q.isApprox(written[i].q));
    EXPECT_TRUE(s.p_WB.isApprox(written[i].p_WB));
    EXPECT_NEAR(s.quat_WB.norm(), 1.0, 1e-12);
    EXPECT_TRUE(s.quat_WB.isApprox(written[i].quat_WB.normalized()));
    EXPECT_TRUE(s.command.isApprox(written[i].command));
  }
}

TEST(StateTrack, IndexAtHoldsTheLastSampleAndClampsOutsideTheLog) {
  StateTrack track;
  for (double t : {1.0, 1.5, 2.0}) track.samples.push_back(sampleAt(t, 3, 0.0));
  EXPECT_EQ(track.indexAt(0.0), 0u);    // before the log: first sample
  EXPECT_EQ(track.indexAt(1.0), 0u);
  EXPECT_EQ(track.indexAt(1.49), 0u);   // zero-order hold, not nearest
  EXPECT_EQ(track.indexAt(1.5), 1u);
  EXPECT_EQ(track.indexAt(1.99), 1u);
  EXPECT_EQ(track.indexAt(2.0), 2u);
  EXPECT_EQ(track.indexAt(99.0), 2u);   // after the log: last sample
}

TEST(StateTrack, RejectsALogOfAnotherRobotNamingFileAndField) {
  const std::string log = tempDir("joints") + "/run.lcmlog";
  writeStateLog(log, {sampleAt(0.0, 29, 0.0)}, 23);
  const std::string what = messageOf([&] { readStateTrack(log, 29); });
  EXPECT_NE(what.find(log), std::string::npos) << what;
  EXPECT_NE(what.find("num_joints = 23, expected 29"), std::string::npos) << what;
}

TEST(StateTrack, RejectsNonFiniteValuesBadQuaternionsAndTimeGoingBack) {
  const std::string dir = tempDir("bad");
  StateSample nan_q = sampleAt(0.5, 29, 0.0);
  nan_q.q[4] = std::nan("");
  writeStateLog(dir + "/nan.lcmlog", {sampleAt(0.0, 29, 0.0), nan_q});
  std::string what = messageOf([&] { readStateTrack(dir + "/nan.lcmlog", 29); });
  EXPECT_NE(what.find("t = 0.5 s: q has a non-finite value"), std::string::npos) << what;

  StateSample zero_quat = sampleAt(0.0, 29, 0.0);
  zero_quat.quat_WB.setZero();
  writeStateLog(dir + "/quat.lcmlog", {zero_quat});
  what = messageOf([&] { readStateTrack(dir + "/quat.lcmlog", 29); });
  EXPECT_NE(what.find("|base_quat| = 0"), std::string::npos) << what;

  writeStateLog(dir + "/back.lcmlog", {sampleAt(1.0, 29, 0.0), sampleAt(0.5, 29, 0.0)});
  what = messageOf([&] { readStateTrack(dir + "/back.lcmlog", 29); });
  EXPECT_NE(what.find("time is not increasing"), std::string::npos) << what;
}

TEST(StateTrack, NamesAMessageTypeMismatchAndCorruptMessages) {
  const std::string dir = tempDir("fingerprint");
  for (const bool other_type : {true, false}) {
    const std::string path = dir + (other_type ? "/other_type.lcmlog" : "/truncated.lcmlog");
    {
      lcm::LogFile log(path, "w");
      pmg_lcm::controller_state_t m{};
      m.num_joints = 2;
      for (auto* v : {&m.q, &m.qd, &m.tau, &m.q_ref, &m.qd_ref}) v->assign(2, 0.0);
      std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
      ASSERT_GT(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
      if (other_type) bytes[3] ^= 0x5a;  // as if the .lcm file had changed
      else bytes.resize(bytes.size() / 2);
      lcm::LogEvent ev{0, 0, "PMG_STATE", static_cast<int32_t>(bytes.size()), bytes.data()};
      ASSERT_EQ(log.writeEvent(&ev), 0);
    }
    const std::string what = messageOf([&] { readStateTrack(path, 2); });
    EXPECT_NE(what.find(path + ": PMG_STATE message #0"), std::string::npos) << what;
    EXPECT_NE(what.find(other_type ? "another pmg_lcm::controller_state_t fingerprint" : "truncated or corrupt"),
              std::string::npos)
        << what;
  }
}

TEST(StateTrack, RejectsALogWithoutStateMessagesAndAMissingFile) {
  const std::string dir = tempDir("empty");
  writeStateLog(dir + "/run.lcmlog", {sampleAt(0.0, 29, 0.0)});
  std::string what = messageOf([&] { readStateTrack(dir + "/run.lcmlog", 29, "NOT_THERE"); });
  EXPECT_NE(what.find("no message on channel NOT_THERE (2 events on other channels)"), std::string::npos) << what;
  what = messageOf([&] { readStateTrack(dir + "/missing.lcmlog", 29); });
  EXPECT_NE(what.find("missing.lcmlog: cannot open"), std::string::npos) << what;
}

TEST(FrameTimes, EvenlySpacedIncludesBothEnds) {
  const std::vector<double> t = evenlySpacedTimes(2.0, 14.0, 7);
  ASSERT_EQ(t.size(), 7u);
  for (int i = 0; i < 7; ++i) EXPECT_DOUBLE_EQ(t[static_cast<std::size_t>(i)], 2.0 + 2.0 * i);
  EXPECT_EQ(evenlySpacedTimes(3.0, 5.0, 1), std::vector<double>{3.0});
  EXPECT_THROW(evenlySpacedTimes(0.0, 1.0, 0), std::invalid_argument);
  EXPECT_THROW(evenlySpacedTimes(1.0, 0.0, 2), std::invalid_argument);
}

TEST(Image, PngRoundTripKeepsEveryPixel) {
  Image image(37, 21);
  for (std::size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = static_cast<std::uint8_t>((i * 7919u) % 251u);
  const std::string path = tempDir("png") + "/image.png";
  writePng(path, image);
  const Image back = readPng(path);
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  EXPECT_EQ(back.rgb, image.rgb);
  const std::string what = messageOf([&] { writePng("/nonexistent_dir/x.png", image); });
  EXPECT_NE(what.find("/nonexistent_dir/x.png: cannot write PNG"), std::string::npos) << what;
}

TEST(Image, HstackPlacesFramesLeftToRightWithGaps) {
  const std::uint8_t grey[3] = {9, 9, 9};
  const Image a(3, 4, 255, 0, 0), b(2, 6, 0, 255, 0);
  const Image strip = hstack({a, b}, 1, grey);
  ASSERT_EQ(strip.width, 3 + 1 + 2);
  ASSERT_EQ(strip.height, 6);
  EXPECT_EQ(strip.pixel(0, 0)[0], 255);  // a
  EXPECT_EQ(strip.pixel(2, 3)[0], 255);
  EXPECT_EQ(strip.pixel(2, 4)[0], 9);    // below a: gap colour
  EXPECT_EQ(strip.pixel(3, 0)[0], 9);    // the gap column
  EXPECT_EQ(strip.pixel(4, 5)[1], 255);  // b
  EXPECT_THROW(hstack({}, 1, grey), std::invalid_argument);
}

// pmg_render_log itself: the messages a user sees when something is missing.
std::string runCli(const std::string& env, const std::string& args, int* exit_code) {
  const std::string err = tempDir("cli_err") + "/stderr.txt";
  const std::string cmd = env + " " + PMG_RENDER_LOG_EXE + " " + args + " 2> " + err + " > /dev/null";
  const int status = std::system(cmd.c_str());
  *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(RenderLogCli, WithoutADisplayExitsWith3NamingWhatIsMissing) {
  const std::string dir = tempDir("cli_nodisplay");
  writeStateLog(dir + "/run.lcmlog", {sampleAt(0.0, 29, 0.0)});
  int code = 0;
  const std::string err = runCli("env -u DISPLAY", "--log " + dir + "/run.lcmlog --out-dir " + dir + "/out", &code);
  EXPECT_EQ(code, 3) << err;
  EXPECT_NE(err.find("no X display ($DISPLAY is not set)"), std::string::npos) << err;
  EXPECT_NE(err.find("Xvfb"), std::string::npos) << err;
}

TEST(RenderLogCli, ALogOfAnotherRobotExitsWith1BeforeAnyRendering) {
  const std::string dir = tempDir("cli_joints");
  writeStateLog(dir + "/run.lcmlog", {sampleAt(0.0, 12, 0.0)});
  int code = 0;
  const std::string err = runCli("env -u DISPLAY", "--log " + dir + "/run.lcmlog --out-dir " + dir + "/out", &code);
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("num_joints = 12, expected 29"), std::string::npos) << err;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(ObjectTrack, ReadsPosesPerBodyAndHoldsTheLastOne) {
  const std::string dir = tempDir("objects_ok");
  writeText(dir + "/o.csv",
            "t,body,x,y,z,qw,qx,qy,qz\n"
            "0.00,task_towel,0.5,-0.2,0.67,1,0,0,0\n"
            "0.00,task_box,0.6,0.0,0.60,0,0,0,1.05\n"   // rounded, not unit: normalised
            "0.02,task_towel,0.5,-0.1,0.67,0.7071068,0,0,0.7071068\n"
            "0.04,task_towel,0.5,0.0,0.67,1,0,0,0\n");
  const ObjectTrack track = readObjectTrack(dir + "/o.csv");
  ASSERT_EQ(track.bodies.size(), 2u);
  EXPECT_EQ(track.bodies.at("task_towel").size(), 3u);
  EXPECT_DOUBLE_EQ(track.at("task_towel", 0.01).p_W.y(), -0.2);   // zero-order hold
  EXPECT_DOUBLE_EQ(track.at("task_towel", 0.02).p_W.y(), -0.1);
  EXPECT_DOUBLE_EQ(track.at("task_towel", -1.0).p_W.y(), -0.2);   // clamped before the start
  EXPECT_DOUBLE_EQ(track.at("task_towel", 9.0).p_W.y(), 0.0);     // and after the end
  EXPECT_NEAR(track.at("task_box", 5.0).quat_W[3], 1.0, 1e-12);
  EXPECT_THROW(track.at("task_cup", 0.0), std::out_of_range);
}

TEST(ObjectTrack, NamesFileLineAndFieldOfEveryBadInput) {
  const std::string dir = tempDir("objects_bad");
  const std::string h = "t,body,x,y,z,qw,qx,qy,qz\n";
  const struct {
    std::string text, expect;
  } cases[] = {
      {"t,body,x,y,z\n0,a,0,0,0\n", ":1: header 't,body,x,y,z'"},
      {h + "0,a,0,0,0,1,0,0\n", ":2: 8 columns, expected 9"},
      {h + "0,a,0,zero,0,1,0,0,0\n", ":2: field y = 'zero'"},
      {h + "0,a,0,0,nan,1,0,0,0\n", ":2: field z = 'nan'"},
      {h + "0,a,0,0,0,0.5,0,0,0\n", ":2: quaternion (qw, qx, qy, qz) of 'a' has norm 0.5"},
      {h + "0,a,0,0,0,1,0,0,0\n0,a,0,0,0,1,0,0,0\n", ":3: field t = 0 of 'a': expected greater"},
      {h + "0,,0,0,0,1,0,0,0\n", ":2: field body is empty"},
      {h, "no rows after the header"},
  };
  for (const auto& c : cases) {
    writeText(dir + "/bad.csv", c.text);
    const std::string msg = messageOf([&] { readObjectTrack(dir + "/bad.csv"); });
    EXPECT_NE(msg.find(dir + "/bad.csv"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in: " << msg;
  }
  EXPECT_NE(messageOf([&] { readObjectTrack(dir + "/missing.csv"); }).find("cannot open"), std::string::npos);
}

TEST(RenderLogCli, ABadObjectTrackExitsWith1BeforeAnyRendering) {
  const std::string dir = tempDir("cli_objects");
  writeStateLog(dir + "/run.lcmlog", {sampleAt(0.0, 29, 0.0)});
  writeText(dir + "/o.csv", "t,body,x,y,z,qw,qx,qy,qz\n0,task_towel,0,0,0,2,0,0,0\n");
  int code = 0;
  const std::string err =
      runCli("env -u DISPLAY", "--log " + dir + "/run.lcmlog --objects " + dir + "/o.csv --out-dir " + dir + "/out", &code);
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("o.csv:2: quaternion"), std::string::npos) << err;
}

}  // namespace
}  // namespace pmg::render
