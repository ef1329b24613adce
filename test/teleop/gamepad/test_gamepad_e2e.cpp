// End to end over LCM loopback (udpm, ttl=0; skipped where multicast does not loop back):
//  1. in process: SDL virtual controller → SdlGamepad → GamepadMapper → pmg::comms::CommandPublisher
//     (signed) → LCM → every message verifies with the key and decodes (pmg_lcm types) to the values
//     the mapper produced;
//  2. the pmg_gamepad executable plays a virtual-controller script (stand, walk, forward, unplug)
//     and the commands on LCM follow it; SIGTERM stops it cleanly.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>
#include <string>
#include <thread>
#include <vector>

#include "g1_fixture.hpp"
#include "lcm_loopback.hpp"
#include "pmg/comms/auth.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/teleop/gamepad.hpp"
#include "pmg/teleop/gamepad_sdl.hpp"
#include "temp_dir.hpp"

namespace pmg::teleop {
namespace {

/// Every command message received, in arrival order.
struct Capture {
  struct Msg {
    std::string channel;
    std::vector<std::uint8_t> data;
  };
  std::vector<Msg> msgs;
  static void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Capture* self) {
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    self->msgs.push_back({channel, std::vector<std::uint8_t>(p, p + rbuf->data_size)});
  }
  void subscribe(lcm::LCM& lcm) { lcm.subscribeFunction("PMG_(VELOCITY|POSTURE|MODE)_COMMAND", &Capture::on, this); }
};


/// The payload of a signed message after verification (fails the test otherwise).
template <class T>
T decodeVerified(comms::MessageVerifier& verifier, const Capture::Msg& m) {
  std::size_t payload = 0;
  const comms::VerifyResult r = verifier.verify(m.channel, m.data.data(), m.data.size(), payload);
  EXPECT_EQ(r, comms::VerifyResult::kOk) << m.channel << ": " << comms::toString(r);
  T out;
  EXPECT_EQ(out.decode(m.data.data(), 0, static_cast<int>(payload)), static_cast<int>(payload)) << m.channel;
  return out;
}

template <class T>
T decodePlain(const Capture::Msg& m) {
  T out;
  EXPECT_GT(out.decode(m.data.data(), 0, static_cast<int>(m.data.size())), 0) << m.channel;
  return out;
}

TEST(GamepadEndToEnd, VirtualControllerToSignedLcmCommands) {
  const std::string url = "udpm://239.255.76.77:7677?ttl=0";
  if (const std::string why = test::lcmMulticastUnavailable(url); !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string key_file = dir.file("gamepad.key");
  const comms::AuthKey key = comms::generateAuthKey();
  comms::writeAuthKeyFile(key_file, key);

  lcm::LCM rx(url);
  Capture cap;
  cap.subscribe(rx);
  comms::CommandPublisher pub(url, key_file, "gamepad");
  ASSERT_TRUE(pub.authenticated());
  SdlVirtualGamepad pad("pmg e2e pad");
  SdlGamepad reader("pmg e2e pad");
  GamepadMapper mapper{GamepadConfig{}};

  // One 50 Hz cycle on a simulated clock, as pmg_gamepad runs it; the expected values are the
  // mapper's own outputs, recorded per cycle.
  double now = 100.0;
  std::vector<GamepadOutput> sent;
  std::vector<ModeRequest> modes_sent;
  auto cycle = [&](const GamepadState& in, bool attached = true) {
    if (attached) {
      if (!pad.attached()) pad.attach();
      pad.set(in);
    } else {
      pad.detach();
    }
    const GamepadOutput& o = mapper.update(reader.poll(now), now);
    EXPECT_TRUE(pub.publishVelocity(o.vx, o.vy, o.wz));
    EXPECT_TRUE(pub.publishPosture(o.pitch, o.roll, o.height));
    if (o.mode != ModeRequest::kNone) {
      EXPECT_TRUE(pub.publishMode(o.mode));
      modes_sent.push_back(o.mode);
    }
    sent.push_back(o);
    // Receive this cycle's messages before the next one (a burst would overrun the socket buffer).
    const std::size_t expected = 2 * sent.size() + modes_sent.size();
    while (cap.msgs.size() < expected && rx.handleTimeout(500) > 0) {
    }
    now += 0.02;
  };
  GamepadState idle, in;
  for (int i = 0; i < 5; ++i) cycle(idle);
  in.left_trigger = 1.0;  // LT + up: stand
  in.buttons = controlBit(GamepadControl::kDpadUp);
  cycle(in);
  cycle(idle);
  in = idle;  // RB + X: walk
  in.buttons = controlBit(GamepadControl::kRightShoulder) | controlBit(GamepadControl::kX);
  cycle(in);
  cycle(idle);
  in = idle;  // full forward, half turn left
  in.left_y = -1.0;
  in.right_x = -0.5;
  for (int i = 0; i < 60; ++i) cycle(in);
  in.buttons = controlBit(GamepadControl::kDpadDown);  // squat one step while walking
  cycle(in);
  in.buttons = 0;
  cycle(in);
  const std::size_t unplugged_at = sent.size();
  for (int i = 0; i < 60; ++i) cycle(idle, false);  // unplugged for 1.2 s
  for (int i = 0; i < 5; ++i) cycle(idle);
  in = idle;  // e-stop chord
  in.left_trigger = 1.0;
  in.buttons = controlBit(GamepadControl::kB);
  cycle(in);
  while (cap.msgs.size() < 2 * sent.size() + modes_sent.size() && rx.handleTimeout(200) > 0) {
  }

  ASSERT_EQ(modes_sent, (std::vector<ModeRequest>{ModeRequest::kSoftStand, ModeRequest::kActive, ModeRequest::kDamping,
                                                  ModeRequest::kDamping}));
  comms::MessageVerifier verifier(key, comms::VerifierOptions{5.0, 8});
  std::vector<pmg_lcm::velocity_command_t> vel;
  std::vector<pmg_lcm::posture_command_t> pos;
  std::vector<pmg_lcm::mode_command_t> mode;
  for (const Capture::Msg& m : cap.msgs) {
    if (m.channel == kVelocityChannel) vel.push_back(decodeVerified<pmg_lcm::velocity_command_t>(verifier, m));
    if (m.channel == kPostureChannel) pos.push_back(decodeVerified<pmg_lcm::posture_command_t>(verifier, m));
    if (m.channel == kModeChannel) mode.push_back(decodeVerified<pmg_lcm::mode_command_t>(verifier, m));
  }
  ASSERT_EQ(vel.size(), sent.size()) << "velocity messages lost on loopback";
  ASSERT_EQ(pos.size(), sent.size());
  ASSERT_EQ(mode.size(), modes_sent.size());
  double max_vx = 0.0, max_wz = 0.0;
  for (std::size_t i = 0; i < sent.size(); ++i) {  // the wire carries exactly what the mapper produced
    EXPECT_EQ(vel[i].vx, sent[i].vx) << i;
    EXPECT_EQ(vel[i].vy, sent[i].vy) << i;
    EXPECT_EQ(vel[i].wz, sent[i].wz) << i;
    EXPECT_EQ(vel[i].source, "gamepad");
    EXPECT_EQ(pos[i].pitch, sent[i].pitch) << i;
    EXPECT_EQ(pos[i].roll, sent[i].roll) << i;
    EXPECT_EQ(pos[i].has_height, sent[i].height.has_value()) << i;
    if (sent[i].height) {
      EXPECT_EQ(pos[i].height, *sent[i].height) << i;
    }
    max_vx = std::max(max_vx, vel[i].vx);
    max_wz = std::max(max_wz, vel[i].wz);
  }
  const GamepadConfig& c = mapper.config();
  EXPECT_DOUBLE_EQ(max_vx, c.sticks.vx.max);  // full stick, 1.2 s of ramp at 1 m/s² reaches 0.6 m/s
  EXPECT_GT(max_wz, 0.0);                     // right stick left → counter-clockwise
  EXPECT_GT(vel[unplugged_at - 1].vx, 0.5);
  EXPECT_EQ(vel[unplugged_at].vx, 0.0);  // first cycle unplugged: zero at once
  EXPECT_TRUE(pos.back().has_height);
  EXPECT_NEAR(pos.back().height, c.posture.standing_height - c.posture.height_step, 1e-12);
  const std::vector<int> codes = {mode[0].mode, mode[1].mode, mode[2].mode, mode[3].mode};
  EXPECT_EQ(codes, (std::vector<int>{1, 2, 3, 3}));  // stand, walk, damping on loss, e-stop
  EXPECT_EQ(vel.back().vx, 0.0);
}

// ------------------------------------------------------------------------------------------------
/// Runs pmg_gamepad with @p args, stderr into @p log; returns its pid.
pid_t spawn(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
    }
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

TEST(GamepadEndToEnd, PmgGamepadPlaysAVirtualScriptOntoLcm) {
  const std::string url = "udpm://239.255.76.78:7678?ttl=0";
  if (const std::string why = test::lcmMulticastUnavailable(url); !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string script = dir.write("script.yaml",
                                       "duration: 3.4\n"
                                       "steps:\n"
                                       "  - {t: 0.0}\n"
                                       "  - {t: 0.2, name: stand, buttons: [lefttrigger, dpup]}\n"
                                       "  - {t: 0.4}\n"
                                       "  - {t: 0.6, name: walk, buttons: [rightshoulder, x]}\n"
                                       "  - {t: 0.8}\n"
                                       "  - {t: 1.0, name: forward, left_y: -0.8}\n"
                                       "  - {t: 2.0, name: unplugged, attached: false}\n");
  lcm::LCM rx(url);
  Capture cap;
  cap.subscribe(rx);
  const std::string log = dir.file("gamepad.log");
  const pid_t pid = spawn({PMG_GAMEPAD_EXE, "--config", test::sourcePath("config/teleop/gamepad.yaml"), "--lcm-url",
                           url, "--virtual-script", script, "--rate", "50"},
                          log);
  ASSERT_GT(pid, 0);
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (waitpid(pid, &status, WNOHANG) == 0) {
    rx.handleTimeout(20);
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      FAIL() << "pmg_gamepad did not end with its script:\n" << test::readTextFile(log);
    }
  }
  while (rx.handleTimeout(50) > 0) {
  }
  const std::string out = test::readTextFile(log);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << out;
  EXPECT_THAT(out, ::testing::HasSubstr("controller 'pmg virtual gamepad'"));
  EXPECT_THAT(out, ::testing::HasSubstr("mode request: soft_stand"));
  EXPECT_THAT(out, ::testing::HasSubstr("(controller lost)"));

  std::vector<int> modes;
  std::vector<double> vx;
  std::size_t postures = 0;
  for (const Capture::Msg& m : cap.msgs) {
    if (m.channel == kModeChannel) modes.push_back(decodePlain<pmg_lcm::mode_command_t>(m).mode);
    if (m.channel == kVelocityChannel) vx.push_back(decodePlain<pmg_lcm::velocity_command_t>(m).vx);
    if (m.channel == kPostureChannel) ++postures;
  }
  EXPECT_EQ(modes, (std::vector<int>{1, 2, 3})) << out;  // stand, walk, damping 1 s after the unplug
  // 3.4 s at 50 Hz (+1 final zero): allow for start-up and scheduling.
  EXPECT_GT(vx.size(), 140u);
  EXPECT_LT(vx.size(), 180u);
  EXPECT_GT(postures, 140u);
  // Expected forward speed for left_y = -0.8 with the shipped config: dead zone 0.1, expo 0.3, max 0.6.
  const double u = (0.8 - 0.1) / 0.9, v = (0.7 * u + 0.3 * u * u * u) * 0.6;
  const double max_vx = *std::max_element(vx.begin(), vx.end());
  EXPECT_NEAR(max_vx, v, 1e-4);  // the trigger/axis Sint16 quantisation (1/32767)
  EXPECT_EQ(vx.back(), 0.0);
}

TEST(GamepadEndToEnd, PmgGamepadStopsCleanlyOnSigterm) {
  test::TempDir dir;
  const std::string log = dir.file("gamepad.log");
  // No controller is needed to run; ttl=0 keeps everything on the host.
  const pid_t pid = spawn({PMG_GAMEPAD_EXE, "--config", test::sourcePath("config/teleop/gamepad.yaml"), "--lcm-url",
                           "udpm://239.255.76.79:7679?ttl=0", "--controller", "no such controller"},
                          log);
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  kill(pid, SIGTERM);
  int status = 0;
  for (int i = 0; i < 100 && waitpid(pid, &status, WNOHANG) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  if (waitpid(pid, &status, WNOHANG) == 0 && !WIFEXITED(status)) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    FAIL() << "no exit within 5 s of SIGTERM:\n" << test::readTextFile(log);
  }
  const std::string out = test::readTextFile(log);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << out;
  EXPECT_THAT(out, ::testing::HasSubstr("pmg_gamepad: stopped after"));
  EXPECT_THAT(out, ::testing::HasSubstr("controller none"));
}

TEST(GamepadEndToEnd, PmgGamepadRejectsBadInputWithNamedErrors) {
  test::TempDir dir;
  const std::string bad = dir.write("bad.yaml", "sticks:\n  vx: {max: 2.0}\n");
  const std::string log = dir.file("out.log");
  auto run = [&](const std::vector<std::string>& args) {
    const pid_t pid = spawn(args, log);
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(run({PMG_GAMEPAD_EXE, "--config", bad, "--duration", "1"}), 1);
  EXPECT_THAT(test::readTextFile(log), ::testing::HasSubstr("bad.yaml:2: sticks: vx.max = 2: expected (0, 1]"));
  EXPECT_EQ(run({PMG_GAMEPAD_EXE, "--rate", "nan"}), 2);
  EXPECT_THAT(test::readTextFile(log), ::testing::HasSubstr("--rate"));
  EXPECT_EQ(run({PMG_GAMEPAD_EXE, "--help"}), 0);
  EXPECT_THAT(test::readTextFile(log), ::testing::HasSubstr("LT + B"));
}

}  // namespace
}  // namespace pmg::teleop
