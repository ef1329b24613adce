// pmg::comms::CommandPublisher (src/comms/command_publisher.cpp): setup errors name their cause;
// over loopback LCM (ttl=0) every message type arrives, is verified by a keyed controller decoder
// and decodes to what was published; an unkeyed publisher's messages are refused by that decoder.
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/velocity_command_t.hpp>
#include <pmg_lcm/vr_pose_t.hpp>

#include "lcm_loopback.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/controller/lcm_command_source.hpp"
#include "temp_dir.hpp"

namespace pmg::comms {
namespace {

const std::string kUrl = "udpm://239.255.76.70:7670?ttl=0";

TEST(CommandPublisher, SetupErrorsNameTheCause) {
  test::TempDir dir;
  const std::string open_key = dir.write("open.key", std::string(64, 'a') + "\n");
  ASSERT_EQ(::chmod(open_key.c_str(), 0644), 0);
  try {
    CommandPublisher p(kUrl, open_key, "gamepad");
    ADD_FAILURE() << "a 0644 key file was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(open_key), std::string::npos) << e.what();
  }
  EXPECT_THROW(CommandPublisher(kUrl, dir.file("missing.key"), "gamepad"), ConfigError);
  EXPECT_THROW(CommandPublisher(kUrl, "", ""), std::invalid_argument);
  EXPECT_THROW(CommandPublisher(kUrl, "", std::string(64, 's')), std::invalid_argument);
  EXPECT_THROW(CommandPublisher("nonsense://x", "", "gamepad"), std::runtime_error);
}

TEST(CommandPublisher, PlainPublisherAndNoneModeRequest) {
  CommandPublisher p(kUrl, "", "script");
  EXPECT_FALSE(p.authenticated());
  EXPECT_EQ(p.senderId(), 0u);
  EXPECT_EQ(p.keyId(), "");
  EXPECT_FALSE(p.publishMode(ModeRequest::kNone));
  EXPECT_EQ(p.failed(), 1u);
  EXPECT_FALSE(p.publishEncoded(std::string(64, 'C'), {1, 2, 3})) << "channel longer than LCM's 63 bytes";
  EXPECT_EQ(p.failed(), 2u);
}

/// Collects what a keyed LcmCommandSource accepts.
struct Received {
  std::mutex m;
  CommandSample last;
  int count = 0;
  static void sink(void* c, const CommandSample& s) noexcept {
    auto* r = static_cast<Received*>(c);
    std::lock_guard<std::mutex> lock(r->m);
    r->last = s;
    ++r->count;
  }
};


TEST(CommandPublisher, EveryTypeArrivesVerifiedAndDecoded) {
  if (const std::string why = test::lcmMulticastUnavailable(kUrl); !why.empty()) GTEST_SKIP() << why;
  test::TempDir dir;
  const std::string key_file = dir.file("k.key");
  const AuthKey key = generateAuthKey();
  writeAuthKeyFile(key_file, key);
  Received got;
  LcmCommandSource source(kUrl, &Received::sink, &got, [](const void*) noexcept { return 7.0; }, nullptr);
  source.requireAuthentication(key, VerifierOptions{});
  source.start();
  CommandPublisher signed_pub(kUrl, key_file, "gamepad");
  CommandPublisher plain_pub(kUrl, "", "intruder");
  EXPECT_TRUE(signed_pub.authenticated());
  EXPECT_EQ(signed_pub.keyId(), keyId(key));
  const auto waitFor = [&](int n) {
    for (int i = 0; i < 200; ++i) {
      {
        std::lock_guard<std::mutex> lock(got.m);
        if (got.count >= n) return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  };
  // Each message is re-sent until it arrives (UDP); a later copy is a new message (new seq).
  const auto until = [&](int n, const std::function<bool()>& publish) {
    for (int i = 0; i < 20; ++i) {
      EXPECT_TRUE(publish());
      if (waitFor(n)) return;
    }
    FAIL() << "message " << n << " never arrived";
  };
  until(1, [&] { return signed_pub.publishVelocity(0.3, -0.1, 0.25); });
  until(2, [&] { return signed_pub.publishPosture(0.1, -0.05, 0.62); });
  until(3, [&] { return signed_pub.publishMode(ModeRequest::kSoftStand); });
  pmg_lcm::vr_pose_t vr{};
  vr.frame = 99;
  vr.head_quat[0] = 1.0;
  vr.hand_quat[0][0] = vr.hand_quat[1][0] = 1.0;
  vr.grip[1] = 0.75;
  vr.source = "ignored";  // replaced by the publisher's
  until(4, [&] { return signed_pub.publishVrPose(vr); });
  // A recorded signed message (old seq and time) is re-signed fresh; a recorded forgery is refused.
  std::vector<std::uint8_t> recorded;
  {
    pmg_lcm::velocity_command_t m{};
    m.vx = 0.44;
    m.wz = 0.25;
    m.source = "gamepad";
    recorded.resize(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(recorded.data(), 0, static_cast<int>(recorded.size()));
    MessageSigner old_signer(key, 1, 1);
    old_signer.sign(kVelocityChannel, recorded, wallClockNowUs() - 3'600'000'000);
  }
  auto forged = recorded;
  forged[10] ^= 1;
  EXPECT_FALSE(signed_pub.publishEncoded(kVelocityChannel, forged));
  EXPECT_EQ(signed_pub.failed(), 1u);
  until(5, [&] { return signed_pub.publishEncoded(kVelocityChannel, recorded); });
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(plain_pub.publishVelocity(-1.0, 0.0, 0.0));
    EXPECT_TRUE(plain_pub.publishMode(ModeRequest::kDamping));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  source.stop();

  std::lock_guard<std::mutex> lock(got.m);
  EXPECT_DOUBLE_EQ(got.last.command.vx, 0.44) << "the re-signed recording";
  EXPECT_DOUBLE_EQ(got.last.command.wz, 0.25);
  EXPECT_DOUBLE_EQ(got.last.command.pitch, 0.1);
  ASSERT_TRUE(got.last.command.height.has_value());
  EXPECT_DOUBLE_EQ(*got.last.command.height, 0.62);
  EXPECT_EQ(got.last.mode_request, ModeRequest::kSoftStand) << "the plain e-stop was refused";
  EXPECT_EQ(got.last.vr.frame, 99);
  EXPECT_DOUBLE_EQ(got.last.vr.grip[1], 0.75);
  EXPECT_DOUBLE_EQ(got.last.vr_time, 7.0);
  EXPECT_EQ(source.counters().accepted(), static_cast<std::uint64_t>(got.count));
  EXPECT_GT(source.counters().count(DecodeResult::kUnauthenticated), 0u);
  EXPECT_EQ(source.counters().rejected(), source.counters().count(DecodeResult::kUnauthenticated));
  EXPECT_EQ(plain_pub.published(), 10u);
  EXPECT_GE(signed_pub.published(), 5u);
  EXPECT_EQ(signed_pub.failed(), 1u);
}

}  // namespace
}  // namespace pmg::comms
