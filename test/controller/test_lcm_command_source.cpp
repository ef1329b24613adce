// LCM command input (lcm_command_source.cpp): every malformed packet is a counted rejection, never
// an exception, and a valid stream still gets through. Defect 1 of issue 11: a `source` length of
// 0 or -1 used to throw std::length_error out of the receive thread (exit 134).
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>

#include "pmg/controller/lcm_command_source.hpp"

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
  if (!tx.good()) GTEST_SKIP() << "LCM cannot open " << url << " on this machine";
  {  // Does multicast loop back here at all? (Sandboxes without a multicast route drop it.)
    lcm::LCM probe(url);
    bool heard = false;
    struct Probe {
      static void on(const lcm::ReceiveBuffer*, const std::string&, bool* h) { *h = true; }
    };
    probe.subscribeFunction("PMG_TEST_PROBE", &Probe::on, &heard);
    const std::uint8_t byte = 1;
    for (int i = 0; i < 5 && !heard; ++i) {
      tx.publish("PMG_TEST_PROBE", &byte, 1);
      probe.handleTimeout(100);
    }
    if (!heard) GTEST_SKIP() << "LCM multicast does not loop back on this machine (no multicast route)";
  }
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

}  // namespace
}  // namespace pmg
