// LCM command input (lcm_command_source.cpp): every malformed packet is a counted rejection, never
// an exception, and a valid stream still gets through. Defect 1 of issue 11: a `source` length of
// 0 or -1 used to throw std::length_error out of the receive thread (exit 134). Issue 13: the VR
// pose channel, and authenticated channels (a key configured: plain, forged, replayed, stale
// packets refused and counted by cause; a valid signed stream gets through a flood of bad ones).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>
#include <pmg_lcm/vr_pose_t.hpp>

#include "alloc_counter.hpp"
#include "lcm_loopback.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/controller/lcm_command_source.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

template <class T>
std::vector<std::uint8_t> encode(const T& msg) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::vector<std::uint8_t> velocityPacket(double vx = 0.4, const std::string& source = "gamepad") {
  pmg_lcm::velocity_command_t m;
  m.utime = 1;
  m.vx = vx;
  m.vy = 0.1;
  m.wz = -0.2;
  m.source = source;
  return encode(m);
}

std::vector<std::uint8_t> posturePacket(bool has_height, double height) {
  pmg_lcm::posture_command_t m;
  m.utime = 1;
  m.pitch = 0.2;
  m.roll = -0.1;
  m.has_height = has_height;
  m.height = height;
  m.source = "vr";
  return encode(m);
}

std::vector<std::uint8_t> modePacket(int code) {
  pmg_lcm::mode_command_t m;
  m.utime = 1;
  m.mode = static_cast<std::int8_t>(code);
  m.source = "gamepad";
  return encode(m);
}

// The int32 length of the `source` string sits right after the fixed fields.
void setStringLength(std::vector<std::uint8_t>& b, std::size_t offset, std::int32_t len) {
  const auto u = static_cast<std::uint32_t>(len);
  for (int i = 0; i < 4; ++i) b[offset + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}
constexpr std::size_t kVelocityStringOffset = 8 + 8 + 3 * 8;
constexpr std::size_t kModeStringOffset = 8 + 8 + 1;

struct Case {
  const char* name;
  const char* channel;
  std::vector<std::uint8_t> bytes;
  DecodeResult expected;
};

std::vector<Case> malformedPackets() {
  std::vector<Case> c;
  for (std::int32_t len : {0, -1, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max(),
                           65, 1 << 20}) {
    auto v = velocityPacket();
    setStringLength(v, kVelocityStringOffset, len);
    c.push_back({"velocity source length", kVelocityChannel, v, DecodeResult::kBadString});
    auto m = modePacket(2);
    setStringLength(m, kModeStringOffset, len);
    c.push_back({"mode source length", kModeChannel, m, DecodeResult::kBadString});
  }
  {
    auto v = velocityPacket();
    setStringLength(v, kVelocityStringOffset, 60);  // plausible length, beyond the packet's end
    c.push_back({"string beyond the end", kVelocityChannel, v, DecodeResult::kTruncated});
  }
  {
    auto v = velocityPacket();
    v.back() = 'x';  // NUL terminator missing
    c.push_back({"string without NUL", kVelocityChannel, v, DecodeResult::kBadString});
  }
  {
    auto v = velocityPacket(0.4, "gamepad");
    v[kVelocityStringOffset + 4 + 3] = 0;  // "gam\0pad\0"
    c.push_back({"NUL inside the string", kVelocityChannel, v, DecodeResult::kBadString});
  }
  const auto good = velocityPacket();
  for (std::size_t n : {std::size_t{0}, std::size_t{3}, std::size_t{8}, std::size_t{20}, good.size() - 1})
    c.push_back({"truncated", kVelocityChannel, std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<long>(n)),
                 DecodeResult::kTruncated});
  {
    auto padded = good;
    padded.resize(good.size() + 100 * 1024, 0);
    c.push_back({"padded by 100 kB", kVelocityChannel, padded, DecodeResult::kTrailingBytes});
    auto twice = good;
    twice.insert(twice.end(), good.begin(), good.end());
    c.push_back({"two packets concatenated", kVelocityChannel, twice, DecodeResult::kTrailingBytes});
  }
  {
    auto wrong = good;
    wrong[0] ^= 0x5a;
    c.push_back({"wrong fingerprint", kVelocityChannel, wrong, DecodeResult::kBadFingerprint});
    c.push_back({"posture bytes on the velocity channel", kVelocityChannel, posturePacket(true, 0.6),
                 DecodeResult::kBadFingerprint});
    c.push_back({"velocity bytes on the mode channel", kModeChannel, good, DecodeResult::kBadFingerprint});
  }
  for (int code : {99, -5, 5, 127, -128}) c.push_back({"unknown mode code", kModeChannel, modePacket(code), DecodeResult::kUnknownMode});
  c.push_back({"NaN velocity", kVelocityChannel, velocityPacket(std::nan("")), DecodeResult::kNonFinite});
  c.push_back({"infinite velocity", kVelocityChannel, velocityPacket(std::numeric_limits<double>::infinity()),
               DecodeResult::kNonFinite});
  c.push_back({"NaN height", kPostureChannel, posturePacket(true, std::nan("")), DecodeResult::kNonFinite});
  c.push_back({"unknown channel", "PMG_VELOCITY_COMMANDS", good, DecodeResult::kUnknownChannel});
  std::vector<std::uint8_t> garbage(333);
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>(i * 37 + 11);
  c.push_back({"binary garbage", kPostureChannel, garbage, DecodeResult::kBadFingerprint});
  return c;
}

TEST(LcmCommandDecoder, MalformedPacketsAreCountedRejectionsAndChangeNothing) {
  LcmCommandDecoder decoder;
  CommandSample sample;
  sample.command.vx = 0.123;
  std::uint64_t expected_rejected = 0;
  for (const Case& c : malformedPackets()) {
    CommandSample before = sample;
    const DecodeResult r = decoder.decode(c.channel, c.bytes.data(), c.bytes.size(), 5.0, sample);
    EXPECT_EQ(r, c.expected) << c.name << ": got " << toString(r);
    if (r != DecodeResult::kAccepted) {
      ++expected_rejected;
      EXPECT_EQ(sample.command.vx, before.command.vx) << c.name;
      EXPECT_EQ(sample.velocity_time, before.velocity_time) << c.name;
      EXPECT_EQ(sample.mode_request_seq, before.mode_request_seq) << c.name;
    }
  }
  EXPECT_EQ(decoder.counters().rejected(), expected_rejected);
  EXPECT_GE(decoder.counters().count(DecodeResult::kBadString), 12u);
  EXPECT_EQ(decoder.counters().count(DecodeResult::kUnknownMode), 5u);
}

TEST(LcmCommandDecoder, ValidPacketsFillTheSample) {
  LcmCommandDecoder decoder;
  CommandSample s;
  const auto v = velocityPacket(0.4);
  ASSERT_EQ(decoder.decode(kVelocityChannel, v.data(), v.size(), 1.5, s), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(s.command.vx, 0.4);
  EXPECT_DOUBLE_EQ(s.command.wz, -0.2);
  EXPECT_DOUBLE_EQ(s.velocity_time, 1.5);
  auto p = posturePacket(false, 0.3);
  ASSERT_EQ(decoder.decode(kPostureChannel, p.data(), p.size(), 1.6, s), DecodeResult::kAccepted);
  EXPECT_FALSE(s.command.height.has_value()) << "has_height false: no height command, whatever height says";
  p = posturePacket(true, 0.62);
  ASSERT_EQ(decoder.decode(kPostureChannel, p.data(), p.size(), 1.7, s), DecodeResult::kAccepted);
  ASSERT_TRUE(s.command.height.has_value());
  EXPECT_DOUBLE_EQ(*s.command.height, 0.62);
  EXPECT_DOUBLE_EQ(s.command.pitch, 0.2);
  for (int code = 0; code <= 4; ++code) {
    const auto m = modePacket(code);
    ASSERT_EQ(decoder.decode(kModeChannel, m.data(), m.size(), 2.0, s), DecodeResult::kAccepted);
    EXPECT_EQ(static_cast<int>(s.mode_request), code) << "wire code = ModeRequest value";
  }
  EXPECT_EQ(s.mode_request, ModeRequest::kReset);
  EXPECT_EQ(s.mode_request_seq, 5u);
  EXPECT_EQ(decoder.counters().accepted(), 8u);
  EXPECT_EQ(decoder.counters().rejected(), 0u);
}


// The receive thread over loopback LCM: a flood of malformed packets, then a valid command that
// still arrives; nothing escapes the thread (an escaped exception would terminate the test).
TEST(LcmCommandSource, ReceiveThreadSurvivesMalformedPacketsAndCountsThem) {
  const std::string url = "udpm://239.255.76.68:7668?ttl=0";
  lcm::LCM tx(url);
  if (const std::string why = test::lcmMulticastUnavailable(url); !why.empty()) GTEST_SKIP() << why;
  struct Sink {
    std::atomic<int> received{0};
    std::atomic<double> vx{0.0};
  } sink;
  LcmCommandSource source(
      url,
      [](void* c, const CommandSample& s) noexcept {
        auto* k = static_cast<Sink*>(c);
        k->vx = s.command.vx;
        ++k->received;
      },
      &sink, [](const void*) noexcept { return 0.0; }, nullptr);
  source.start();
  const auto cases = malformedPackets();
  std::size_t sent_bad = 0;
  for (int round = 0; round < 3; ++round)
    for (const Case& c : cases) {
      // Not subscribed (unknown channel) or beyond a UDP datagram: LCM itself drops those.
      if (c.expected == DecodeResult::kUnknownChannel || c.bytes.size() > 60000) continue;
      tx.publish(c.channel, c.bytes.data(), static_cast<unsigned>(c.bytes.size()));
      ++sent_bad;
    }
  // UDP may drop datagrams on a loaded machine: the valid command is re-sent until it arrives.
  const auto good = velocityPacket(0.77);
  for (int i = 0; i < 100 && sink.received.load() == 0; ++i) {
    tx.publish(kVelocityChannel, good.data(), static_cast<unsigned>(good.size()));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  source.stop();
  ASSERT_GE(sink.received.load(), 1) << "the valid command got through the flood";
  EXPECT_DOUBLE_EQ(sink.vx.load(), 0.77);
  EXPECT_EQ(source.counters().accepted(), static_cast<std::uint64_t>(sink.received.load()));
  EXPECT_GT(source.counters().rejected(), 0u);
  EXPECT_LE(source.counters().rejected(), sent_bad) << "every rejection is one of the packets sent";
  EXPECT_EQ(source.counters().count(DecodeResult::kInternalError), 0u);
}

// ------------------------------------------------------------------------------ PMG_VR_POSE

pmg_lcm::vr_pose_t vrPose() {
  pmg_lcm::vr_pose_t m{};
  m.utime = 1;
  m.xr_time_us = 123456789;
  m.frame = 42;
  const double h = std::sqrt(0.5);
  const double head_pos[3] = {0.1, -0.2, 1.6}, head_q[4] = {h, 0.0, 0.0, h};
  std::copy(head_pos, head_pos + 3, m.head_position);
  std::copy(head_q, head_q + 4, m.head_quat);
  m.hand_valid[0] = 1;
  m.hand_valid[1] = 0;
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 3; ++i) m.hand_position[k][i] = 0.1 * (k + 1) + 0.01 * i;
    m.hand_quat[k][0] = 0.5;
    m.hand_quat[k][1] = 0.5;
    m.hand_quat[k][2] = -0.5;
    m.hand_quat[k][3] = 0.5;
    m.grip[k] = 0.25 * (k + 1);
    m.trigger[k] = 1.0 - 0.5 * k;
    m.thumbstick[k][0] = -1.0 + k;
    m.thumbstick[k][1] = 0.5;
  }
  m.buttons[0] = teleop::kVrButtonLower | teleop::kVrButtonMenu;
  m.buttons[1] = teleop::kVrButtonUpper;
  m.source = "vr";
  return m;
}

TEST(LcmCommandDecoder, VrPoseFillsTheVrSample) {
  LcmCommandDecoder decoder;
  CommandSample s;
  s.command.vx = 0.3;
  const auto b = encode(vrPose());
  ASSERT_EQ(decoder.decode(kVrPoseChannel, b.data(), b.size(), 2.5, s), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(s.vr_time, 2.5);
  EXPECT_EQ(s.vr.frame, 42);
  EXPECT_EQ(s.vr.xr_time_us, 123456789);
  EXPECT_DOUBLE_EQ(s.vr.head_position[2], 1.6);
  EXPECT_DOUBLE_EQ(s.vr.head_quat[3], std::sqrt(0.5));
  EXPECT_TRUE(s.vr.hand_valid[0]);
  EXPECT_FALSE(s.vr.hand_valid[1]);
  EXPECT_DOUBLE_EQ(s.vr.hand_position[1][2], 0.22);
  EXPECT_DOUBLE_EQ(s.vr.hand_quat[1][2], -0.5);
  EXPECT_DOUBLE_EQ(s.vr.grip[1], 0.5);
  EXPECT_DOUBLE_EQ(s.vr.trigger[1], 0.5);
  EXPECT_DOUBLE_EQ(s.vr.thumbstick[0][0], -1.0);
  EXPECT_DOUBLE_EQ(s.vr.thumbstick[1][0], 0.0);
  EXPECT_EQ(s.vr.buttons[0], teleop::kVrButtonLower | teleop::kVrButtonMenu);
  EXPECT_EQ(s.vr.buttons[1], static_cast<std::uint32_t>(teleop::kVrButtonUpper));
  EXPECT_DOUBLE_EQ(s.command.vx, 0.3) << "a VR pose does not touch the command";
  EXPECT_EQ(s.velocity_time, -1.0);
}

std::vector<Case> badVrPoses() {
  std::vector<Case> c;
  const auto add = [&c](const char* name, void (*edit)(pmg_lcm::vr_pose_t&), DecodeResult r) {
    auto m = vrPose();
    edit(m);
    c.push_back({name, kVrPoseChannel, encode(m), r});
  };
  add("head quaternion norm 1.01", [](pmg_lcm::vr_pose_t& m) { for (double& q : m.head_quat) q *= 1.01; },
      DecodeResult::kOutOfRange);
  add("hand quaternion zero", [](pmg_lcm::vr_pose_t& m) { for (double& q : m.hand_quat[1]) q = 0.0; },
      DecodeResult::kOutOfRange);
  add("grip 1.5", [](pmg_lcm::vr_pose_t& m) { m.grip[0] = 1.5; }, DecodeResult::kOutOfRange);
  add("grip -0.01", [](pmg_lcm::vr_pose_t& m) { m.grip[1] = -0.01; }, DecodeResult::kOutOfRange);
  add("trigger 2", [](pmg_lcm::vr_pose_t& m) { m.trigger[1] = 2.0; }, DecodeResult::kOutOfRange);
  add("thumbstick 1.2", [](pmg_lcm::vr_pose_t& m) { m.thumbstick[0][1] = 1.2; }, DecodeResult::kOutOfRange);
  add("thumbstick -1.5", [](pmg_lcm::vr_pose_t& m) { m.thumbstick[1][0] = -1.5; }, DecodeResult::kOutOfRange);
  add("boolean 2", [](pmg_lcm::vr_pose_t& m) { m.hand_valid[1] = 2; }, DecodeResult::kOutOfRange);
  add("unknown button bit", [](pmg_lcm::vr_pose_t& m) { m.buttons[0] = 1 << 7; }, DecodeResult::kOutOfRange);
  add("negative buttons", [](pmg_lcm::vr_pose_t& m) { m.buttons[1] = -1; }, DecodeResult::kOutOfRange);
  add("NaN head position", [](pmg_lcm::vr_pose_t& m) { m.head_position[0] = std::nan(""); }, DecodeResult::kNonFinite);
  add("NaN quaternion", [](pmg_lcm::vr_pose_t& m) { m.hand_quat[0][0] = std::nan(""); }, DecodeResult::kNonFinite);
  add("infinite thumbstick", [](pmg_lcm::vr_pose_t& m) { m.thumbstick[1][1] = -INFINITY; }, DecodeResult::kNonFinite);
  add("source too long", [](pmg_lcm::vr_pose_t& m) { m.source = std::string(64, 'v'); }, DecodeResult::kBadString);
  const auto good = encode(vrPose());
  c.push_back({"vr truncated", kVrPoseChannel, std::vector<std::uint8_t>(good.begin(), good.end() - 40),
               DecodeResult::kTruncated});
  auto padded = good;
  padded.push_back(0);
  c.push_back({"vr one trailing byte", kVrPoseChannel, padded, DecodeResult::kTrailingBytes});
  c.push_back({"velocity bytes on the VR channel", kVrPoseChannel, velocityPacket(), DecodeResult::kBadFingerprint});
  c.push_back({"VR bytes on the velocity channel", kVelocityChannel, good, DecodeResult::kBadFingerprint});
  return c;
}

TEST(LcmCommandDecoder, VrPoseOutOfRangeIsACountedRejectionAndKeepsTheLastSample) {
  LcmCommandDecoder decoder;
  CommandSample s;
  const auto good = encode(vrPose());
  ASSERT_EQ(decoder.decode(kVrPoseChannel, good.data(), good.size(), 1.0, s), DecodeResult::kAccepted);
  std::map<DecodeResult, std::uint64_t> expected;
  for (const Case& c : badVrPoses()) {
    const CommandSample before = s;
    const DecodeResult r = decoder.decode(c.channel, c.bytes.data(), c.bytes.size(), 9.0, s);
    EXPECT_EQ(r, c.expected) << c.name << ": got " << toString(r);
    EXPECT_EQ(s.vr_time, before.vr_time) << c.name;
    EXPECT_EQ(s.vr.grip, before.vr.grip) << c.name;
    EXPECT_EQ(s.vr.head_quat, before.vr.head_quat) << c.name;
    ++expected[c.expected];
  }
  for (const auto& [cause, n] : expected) EXPECT_EQ(decoder.counters().count(cause), n) << toString(cause);
  EXPECT_EQ(decoder.counters().count(DecodeResult::kOutOfRange), 10u);
  // Within the tolerance: |‖q‖ − 1| ≤ 1e-3 is accepted.
  auto m = vrPose();
  for (double& q : m.head_quat) q *= 1.0009;
  const auto near = encode(m);
  EXPECT_EQ(decoder.decode(kVrPoseChannel, near.data(), near.size(), 3.0, s), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(s.vr_time, 3.0);
}

// ------------------------------------------------------------------------------ authentication

constexpr std::int64_t kNowUs = 1'700'000'000'000'000;

comms::AuthKey testKey(std::uint8_t fill) {
  std::array<std::uint8_t, comms::kAuthKeyBytes> b{};
  b.fill(fill);
  return comms::AuthKey(b);
}

struct FakeWallClock {
  std::int64_t now_us = kNowUs;
  static std::int64_t read(const void* c) noexcept { return static_cast<const FakeWallClock*>(c)->now_us; }
};

std::vector<std::uint8_t> sign(const comms::AuthKey& key, const char* channel, std::vector<std::uint8_t> b,
                               std::uint64_t seq, std::int64_t t_us = kNowUs, std::uint32_t sender = 11) {
  const std::size_t n = b.size();
  b.resize(n + comms::kAuthTrailerBytes);
  comms::writeTrailer(key, channel, b.data(), n, comms::AuthTrailerFields{sender, seq, t_us}, b.data() + n);
  return b;
}

class AuthenticatedDecoder : public ::testing::Test {
 protected:
  AuthenticatedDecoder() { decoder_.requireAuthentication(key_, comms::VerifierOptions{0.5, 2}, &FakeWallClock::read, &clock_); }
  DecodeResult decode(const char* channel, const std::vector<std::uint8_t>& b) {
    return decoder_.decode(channel, b.data(), b.size(), 4.0, sample_);
  }
  comms::AuthKey key_ = testKey(0x42);
  FakeWallClock clock_;
  LcmCommandDecoder decoder_;
  CommandSample sample_;
};

TEST_F(AuthenticatedDecoder, SignedPacketsOfEveryChannelAreAccepted) {
  EXPECT_TRUE(decoder_.authenticated());
  EXPECT_EQ(decode(kVelocityChannel, sign(key_, kVelocityChannel, velocityPacket(0.45), 1)), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(sample_.command.vx, 0.45);
  EXPECT_EQ(decode(kPostureChannel, sign(key_, kPostureChannel, posturePacket(true, 0.6), 1)), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(*sample_.command.height, 0.6);
  EXPECT_EQ(decode(kModeChannel, sign(key_, kModeChannel, modePacket(3), 1)), DecodeResult::kAccepted);
  EXPECT_EQ(sample_.mode_request, ModeRequest::kDamping);
  EXPECT_EQ(decode(kVrPoseChannel, sign(key_, kVrPoseChannel, encode(vrPose()), 1)), DecodeResult::kAccepted);
  EXPECT_EQ(sample_.vr.frame, 42);
  EXPECT_EQ(decoder_.counters().accepted(), 4u);
  EXPECT_EQ(decoder_.counters().rejected(), 0u);
}

// Without a key nothing is verified, and a signed commander's packets are decoded without their
// trailer (a keyed gamepad, or a recorded signed log, against a controller without a key).
TEST(LcmCommandDecoder, WithoutAKeySignedPacketsAreDecodedWithoutTheTrailer) {
  LcmCommandDecoder decoder;
  CommandSample s;
  const auto v = sign(testKey(1), kVelocityChannel, velocityPacket(0.61), 5);
  ASSERT_EQ(decoder.decode(kVelocityChannel, v.data(), v.size(), 1.0, s), DecodeResult::kAccepted);
  EXPECT_DOUBLE_EQ(s.command.vx, 0.61);
  auto extra = v;
  extra.push_back(0);  // one byte after the trailer: no trailer at the end any more
  EXPECT_EQ(decoder.decode(kVelocityChannel, extra.data(), extra.size(), 1.0, s), DecodeResult::kTrailingBytes);
  EXPECT_FALSE(decoder.authenticated());
}

// The trailer is invisible to LCM's own decoders (lcm-spy, lcm-logger, generated types): they read
// the message and ignore the bytes after it.
TEST_F(AuthenticatedDecoder, LcmGeneratedDecodersReadSignedMessages) {
  const auto b = sign(key_, kVrPoseChannel, encode(vrPose()), 1);
  pmg_lcm::vr_pose_t m;
  EXPECT_EQ(m.decode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size() - comms::kAuthTrailerBytes));
  EXPECT_EQ(m.frame, 42);
  EXPECT_EQ(m.source, "vr");
  const auto v = sign(key_, kVelocityChannel, velocityPacket(0.33), 1);
  pmg_lcm::velocity_command_t vm;
  EXPECT_GT(vm.decode(v.data(), 0, static_cast<int>(v.size())), 0);
  EXPECT_DOUBLE_EQ(vm.vx, 0.33);
}

std::vector<Case> badSignedPackets(const comms::AuthKey& key) {
  std::vector<Case> c;
  const auto v = velocityPacket(0.9);
  // Plain packets of every channel: refused while a key is configured.
  c.push_back({"plain velocity", kVelocityChannel, v, DecodeResult::kUnauthenticated});
  c.push_back({"plain posture", kPostureChannel, posturePacket(false, 0.0), DecodeResult::kUnauthenticated});
  c.push_back({"plain mode (e-stop)", kModeChannel, modePacket(3), DecodeResult::kUnauthenticated});
  c.push_back({"plain VR pose", kVrPoseChannel, encode(vrPose()), DecodeResult::kUnauthenticated});
  c.push_back({"empty packet", kModeChannel, {}, DecodeResult::kUnauthenticated});
  // Forged or altered.
  auto forged = sign(key, kVelocityChannel, v, 100);
  forged[forged.size() - 5] ^= 0x01;
  c.push_back({"forged tag", kVelocityChannel, forged, DecodeResult::kBadMac});
  c.push_back({"wrong key", kVelocityChannel, sign(testKey(0x43), kVelocityChannel, v, 101), DecodeResult::kBadMac});
  auto flipped = sign(key, kVelocityChannel, v, 102);
  flipped[20] ^= 0x80;  // inside vx
  c.push_back({"flipped payload byte", kVelocityChannel, flipped, DecodeResult::kBadMac});
  c.push_back({"signed for another channel", kPostureChannel, sign(key, kVelocityChannel, posturePacket(true, 0.5), 103),
               DecodeResult::kBadMac});
  auto truncated = sign(key, kVelocityChannel, v, 104);
  truncated.resize(truncated.size() - 7);
  c.push_back({"truncated trailer", kVelocityChannel, truncated, DecodeResult::kUnauthenticated});
  auto oversized = sign(key, kVelocityChannel, v, 105);
  oversized.resize(oversized.size() + 16, 0);
  c.push_back({"bytes after the trailer", kVelocityChannel, oversized, DecodeResult::kUnauthenticated});
  // Replay and age (each fresh seq below is first accepted in the test, see there).
  c.push_back({"stale (1 s old)", kVelocityChannel, sign(key, kVelocityChannel, v, 106, kNowUs - 1'000'000),
               DecodeResult::kStale});
  c.push_back({"from the future (0.6 s)", kVelocityChannel, sign(key, kVelocityChannel, v, 107, kNowUs + 600'000),
               DecodeResult::kStale});
  // Validly signed, but the payload itself is bad: the raw checks still run.
  c.push_back({"signed NaN velocity", kVelocityChannel, sign(key, kVelocityChannel, velocityPacket(std::nan("")), 108),
               DecodeResult::kNonFinite});
  c.push_back({"signed unknown mode", kModeChannel, sign(key, kModeChannel, modePacket(99), 109), DecodeResult::kUnknownMode});
  auto vr = vrPose();
  vr.grip[0] = 7.0;
  c.push_back({"signed grip 7", kVrPoseChannel, sign(key, kVrPoseChannel, encode(vr), 110), DecodeResult::kOutOfRange});
  auto padded = velocityPacket(0.9);
  padded.push_back(0);
  c.push_back({"signed padded payload", kVelocityChannel, sign(key, kVelocityChannel, padded, 111),
               DecodeResult::kTrailingBytes});
  auto bad_string = velocityPacket(0.9);
  setStringLength(bad_string, kVelocityStringOffset, -1);
  c.push_back({"signed bad string", kVelocityChannel, sign(key, kVelocityChannel, bad_string, 112), DecodeResult::kBadString});
  c.push_back({"signed wrong type", kModeChannel, sign(key, kModeChannel, v, 113), DecodeResult::kBadFingerprint});
  return c;
}

TEST_F(AuthenticatedDecoder, BadPacketsAreRefusedAndCountedByCause) {
  ASSERT_EQ(decode(kVelocityChannel, sign(key_, kVelocityChannel, velocityPacket(0.2), 1)), DecodeResult::kAccepted);
  std::map<DecodeResult, std::uint64_t> expected;
  for (const Case& c : badSignedPackets(key_)) {
    const CommandSample before = sample_;
    const DecodeResult r = decode(c.channel, c.bytes);
    EXPECT_EQ(r, c.expected) << c.name << ": got " << toString(r);
    EXPECT_EQ(sample_.command.vx, before.command.vx) << c.name;
    EXPECT_EQ(sample_.mode_request_seq, before.mode_request_seq) << c.name;
    EXPECT_EQ(sample_.vr_time, before.vr_time) << c.name;
    ++expected[c.expected];
  }
  EXPECT_DOUBLE_EQ(sample_.command.vx, 0.2);
  for (const auto& [cause, n] : expected) EXPECT_EQ(decoder_.counters().count(cause), n) << toString(cause);
  EXPECT_EQ(decoder_.counters().accepted(), 1u);
}

TEST_F(AuthenticatedDecoder, ReplayedAndOlderSequenceNumbersAreRefused) {
  const auto first = sign(key_, kModeChannel, modePacket(2), 1000);
  ASSERT_EQ(decode(kModeChannel, first), DecodeResult::kAccepted);
  EXPECT_EQ(sample_.mode_request_seq, 1u);
  EXPECT_EQ(decode(kModeChannel, first), DecodeResult::kReplayed) << "the same packet twice";
  EXPECT_EQ(decode(kModeChannel, sign(key_, kModeChannel, modePacket(3), 999)), DecodeResult::kReplayed)
      << "a lower seq";
  EXPECT_EQ(sample_.mode_request_seq, 1u) << "no mode request from a replay";
  EXPECT_EQ(decode(kModeChannel, sign(key_, kModeChannel, modePacket(3), 1001)), DecodeResult::kAccepted);
  EXPECT_EQ(sample_.mode_request_seq, 2u);
  EXPECT_EQ(decoder_.counters().count(DecodeResult::kReplayed), 2u);
  // A third sender on one channel (max_senders = 2 here) while two are active.
  EXPECT_EQ(decode(kModeChannel, sign(key_, kModeChannel, modePacket(3), 1, kNowUs, 12)), DecodeResult::kAccepted);
  EXPECT_EQ(decode(kModeChannel, sign(key_, kModeChannel, modePacket(3), 1, kNowUs, 13)), DecodeResult::kTooManySenders);
  EXPECT_EQ(decoder_.counters().count(DecodeResult::kTooManySenders), 1u);
}

TEST_F(AuthenticatedDecoder, DecodeAllocatesNothing) {
  std::vector<std::vector<std::uint8_t>> good;
  for (std::uint64_t seq = 1; seq <= 20; ++seq) good.push_back(sign(key_, kVrPoseChannel, encode(vrPose()), seq));
  const auto bad = badSignedPackets(key_);
  std::size_t accepted = 0;
  {
    test::AllocationGuard guard;
    for (const auto& b : good) accepted += decode(kVrPoseChannel, b) == DecodeResult::kAccepted;
    for (const Case& c : bad) (void)decode(c.channel, c.bytes);
    EXPECT_EQ(guard.count(), 0u);
  }
  EXPECT_EQ(accepted, good.size());
  EXPECT_GE(decoder_.counters().rejected(), bad.size());
}

// A live loopback test: a commander (CommandPublisher with a key file) streams velocity commands at
// 200 Hz while a bounded flood of 20 000 bad packets arrives on the same LCM group (ttl=0):
// plain, forged, wrong key, replays of the commander's own captured packet, stale, truncated and
// oversized trailers, and validly signed packets with bad content. The valid stream gets through,
// no bad packet is accepted, and every bad packet that reached the receiver is counted by cause.
TEST(LcmCommandSource, SignedStreamGetsThroughAFloodOfBadPackets) {
  const std::string url = "udpm://239.255.76.69:7669?ttl=0";
  lcm::LCM tx(url);
  if (const std::string why = test::lcmMulticastUnavailable(url); !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string key_file = dir.file("commands.key");
  const comms::AuthKey key = comms::generateAuthKey();
  comms::writeAuthKeyFile(key_file, key);

  struct Sink {
    std::atomic<int> received{0};
    std::atomic<int> wrong{0};  // accepted samples whose velocity is not the commander's
  } sink;
  LcmCommandSource source(
      url,
      [](void* c, const CommandSample& s) noexcept {
        auto* k = static_cast<Sink*>(c);
        if (s.command.vx != 0.5 || s.command.wz != 0.0) ++k->wrong;
        ++k->received;
      },
      &sink, [](const void*) noexcept { return 0.0; }, nullptr);
  source.requireAuthentication(comms::loadAuthKey(key_file), comms::VerifierOptions{});
  ASSERT_TRUE(source.authenticated());

  // The attacker's raw capture of the commander's first packet (for the replays).
  lcm::LCM spy(url);
  std::vector<std::uint8_t> captured;
  struct Capture {
    static void on(const lcm::ReceiveBuffer* rb, const std::string&, std::vector<std::uint8_t>* out) {
      if (out->empty()) out->assign(static_cast<const std::uint8_t*>(rb->data), static_cast<const std::uint8_t*>(rb->data) + rb->data_size);
    }
  };
  spy.subscribeFunction(kVelocityChannel, &Capture::on, &captured);

  source.start();
  std::atomic<bool> done{false};
  std::atomic<int> valid_sent{0};
  comms::CommandPublisher commander(url, key_file, "gamepad");
  ASSERT_TRUE(commander.authenticated());
  std::thread commander_thread([&] {
    while (!done.load()) {
      if (commander.publishVelocity(0.5, 0.0, 0.0)) ++valid_sent;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  for (int i = 0; i < 40 && captured.empty(); ++i) spy.handleTimeout(50);
  ASSERT_FALSE(captured.empty()) << "no packet of the commander seen on " << url;

  // Bad packets, each with the cause it must be counted under.
  comms::MessageSigner insider(key);                      // holds the key: stale and bad-content packets
  comms::MessageSigner outsider(comms::generateAuthKey());  // another key
  const auto bad = velocityPacket(-0.9);
  auto vr = vrPose();
  vr.trigger[1] = 5.0;
  const auto bad_vr = encode(vr);
  struct Sent {
    const char* channel;
    std::vector<std::uint8_t> bytes;
    DecodeResult cause;
  };
  const auto make = [&](int kind) -> Sent {
    std::vector<std::uint8_t> b = bad;
    switch (kind) {
      case 0: return {kVelocityChannel, b, DecodeResult::kUnauthenticated};
      case 1: insider.sign(kVelocityChannel, b); b[b.size() - 1] ^= 1; return {kVelocityChannel, b, DecodeResult::kBadMac};
      case 2: outsider.sign(kVelocityChannel, b); return {kVelocityChannel, b, DecodeResult::kBadMac};
      case 3: return {kVelocityChannel, captured, DecodeResult::kReplayed};
      case 4: insider.sign(kVelocityChannel, b, comms::wallClockNowUs() - 5'000'000); return {kVelocityChannel, b, DecodeResult::kStale};
      case 5: b = velocityPacket(std::nan("")); insider.sign(kVelocityChannel, b); return {kVelocityChannel, b, DecodeResult::kNonFinite};
      case 6: insider.sign(kVelocityChannel, b); b.resize(b.size() - 10); return {kVelocityChannel, b, DecodeResult::kUnauthenticated};
      case 7: insider.sign(kVelocityChannel, b); b.resize(b.size() + 100, 0); return {kVelocityChannel, b, DecodeResult::kUnauthenticated};
      case 8: b = bad_vr; insider.sign(kVrPoseChannel, b); return {kVrPoseChannel, b, DecodeResult::kOutOfRange};
      default: b = modePacket(3); return {kModeChannel, b, DecodeResult::kUnauthenticated};  // a plain e-stop
    }
  };
  constexpr int kBad = 20000, kBurst = 200, kKinds = 10;  // a burst fits LCM's queue (kLcmQueueCapacity)
  std::map<DecodeResult, std::uint64_t> sent;
  const auto t0 = std::chrono::steady_clock::now();
  int sent_bad = 0;
  while (sent_bad < kBad) {
    for (int i = 0; i < kBurst; ++i, ++sent_bad) {
      const Sent p = make(sent_bad % kKinds);
      if (tx.publish(p.channel, p.bytes.data(), static_cast<unsigned>(p.bytes.size())) == 0) ++sent[p.cause];
    }
    // Bounded: let the receiver catch up before the next burst (the socket buffer is finite).
    for (int w = 0; w < 200 && source.counters().rejected() < static_cast<std::uint64_t>(sent_bad); ++w)
      std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  const double flood_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int received_during_flood = sink.received.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  done = true;
  commander_thread.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  source.stop();

  std::uint64_t total_sent = 0;
  for (const auto& [cause, n] : sent) total_sent += n;
  const std::uint64_t rejected = source.counters().rejected();
  std::printf("flood: %llu bad packets in %.2f s (%.0f /s), %llu counted as rejected (%.2f %%); valid: %d sent, "
              "%llu accepted (%d during the flood)\n",
              static_cast<unsigned long long>(total_sent), flood_s, total_sent / flood_s,
              static_cast<unsigned long long>(rejected), 100.0 * rejected / total_sent, valid_sent.load(),
              static_cast<unsigned long long>(source.counters().accepted()), received_during_flood);
  for (const auto& [cause, n] : sent)
    std::printf("  %-18s sent %6llu counted %6llu\n", toString(cause), static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(source.counters().count(cause)));

  EXPECT_EQ(sink.wrong.load(), 0) << "a bad packet was accepted";
  EXPECT_GT(received_during_flood, 0) << "the valid stream got through during the flood";
  EXPECT_GE(source.counters().accepted(), static_cast<std::uint64_t>(valid_sent.load()) / 2);
  EXPECT_LE(source.counters().accepted(), static_cast<std::uint64_t>(valid_sent.load()));
  EXPECT_EQ(source.counters().count(DecodeResult::kInternalError), 0u);
  for (const auto& [cause, n] : sent) EXPECT_LE(source.counters().count(cause), n) << toString(cause);
  // Loopback UDP with the bursts paced loses (next to) nothing: every bad packet is counted.
  EXPECT_GE(rejected, total_sent * 99 / 100);
  EXPECT_LE(rejected, total_sent);
}

}  // namespace
}  // namespace pmg
