// Authenticated command channels (src/comms/auth.cpp): the trailer, the verifier's rejection
// causes and key files. Every forged, altered, moved, truncated, replayed, stale or plain message
// is rejected with its cause; a valid one is accepted exactly once.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/comms/auth.hpp"
#include "temp_dir.hpp"

namespace pmg::comms {
namespace {

constexpr std::int64_t kNowUs = 1'700'000'000'000'000;  // a fixed "now" [µs since the epoch]

AuthKey keyOf(std::uint8_t fill) {
  std::array<std::uint8_t, kAuthKeyBytes> b{};
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(fill + i);
  return AuthKey(b);
}

std::vector<std::uint8_t> payload(std::size_t n = 45) {
  std::vector<std::uint8_t> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return p;
}

std::vector<std::uint8_t> signedMessage(const AuthKey& key, const std::string& channel, std::vector<std::uint8_t> p,
                                        std::uint32_t sender, std::uint64_t seq, std::int64_t t_us) {
  const std::size_t n = p.size();
  p.resize(n + kAuthTrailerBytes);
  writeTrailer(key, channel, p.data(), n, AuthTrailerFields{sender, seq, t_us}, p.data() + n);
  return p;
}

struct FakeClock {
  std::int64_t now_us = kNowUs;
  static std::int64_t read(const void* c) noexcept { return static_cast<const FakeClock*>(c)->now_us; }
};

class VerifierTest : public ::testing::Test {
 protected:
  VerifyResult verify(const std::string& channel, const std::vector<std::uint8_t>& m) {
    payload_size_ = 12345;
    return verifier_.verify(channel, m.data(), m.size(), payload_size_);
  }
  std::vector<std::uint8_t> msg(std::uint64_t seq, std::int64_t t_us = kNowUs, std::uint32_t sender = 7,
                                const std::string& channel = "PMG_VELOCITY_COMMAND") {
    return signedMessage(key_, channel, payload(), sender, seq, t_us);
  }
  AuthKey key_ = keyOf(1);
  FakeClock clock_;
  MessageVerifier verifier_{key_, VerifierOptions{0.5, 2}, &FakeClock::read, &clock_};
  std::size_t payload_size_ = 0;
};

TEST(AuthTrailer, LayoutIsTheDocumentedOne) {
  const auto m = signedMessage(keyOf(1), "CH", payload(10), 0x01020304u, 0x1112131415161718ull, 0x2122232425262728);
  ASSERT_EQ(m.size(), 10 + kAuthTrailerBytes);
  const std::uint8_t* t = m.data() + 10;
  EXPECT_EQ(std::memcmp(t, "PMGA", 4), 0);
  EXPECT_EQ(t[4], 1);
  EXPECT_EQ(t[5] | t[6] | t[7], 0);
  const std::uint8_t expect[] = {1, 2, 3, 4, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17, 0x18,
                                 0x21, 0x22, 0x23, 0x24, 0x25, 0x26, 0x27, 0x28};
  EXPECT_EQ(std::memcmp(t + 8, expect, sizeof expect), 0);
  // The tag is HMAC-SHA-512-256 over u16 len | channel | payload | trailer[0..28): recompute it
  // through a second signer path (MessageSigner) with the same fields.
  MessageSigner s(keyOf(1), 0x01020304u, 0x1112131415161718ull);
  std::vector<std::uint8_t> m2 = payload(10);
  s.sign("CH", m2, 0x2122232425262728);
  EXPECT_EQ(m, m2);
  EXPECT_EQ(s.nextSeq(), 0x1112131415161719ull);
}

TEST_F(VerifierTest, ValidMessageIsAcceptedWithItsPayloadSize) {
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(100)), VerifyResult::kOk);
  EXPECT_EQ(payload_size_, payload().size());
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(101)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(250)), VerifyResult::kOk);  // gaps are fine (lost packets)
}

TEST_F(VerifierTest, ForgedTagIsBadMac) {
  auto m = msg(100);
  m.back() ^= 0x01;
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kBadMac);
  EXPECT_EQ(payload_size_, 12345u);  // left unchanged on rejection
  auto z = msg(100);
  std::fill(z.end() - static_cast<std::ptrdiff_t>(kAuthTagBytes), z.end(), 0);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", z), VerifyResult::kBadMac);
}

TEST_F(VerifierTest, WrongKeyIsBadMac) {
  const auto m = signedMessage(keyOf(2), "PMG_VELOCITY_COMMAND", payload(), 7, 100, kNowUs);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kBadMac);
}

TEST_F(VerifierTest, EveryFlippedByteIsBadMac) {
  const auto good = msg(100);
  for (std::size_t i = 0; i < good.size(); ++i) {
    auto m = good;
    m[i] ^= 0x40;
    const VerifyResult r = verify("PMG_VELOCITY_COMMAND", m);
    // Bytes 0..7 of the trailer are its magic/version/reserved: a flip there is "not a trailer".
    const std::size_t t = good.size() - kAuthTrailerBytes;
    const VerifyResult expected = (i >= t && i < t + 8) ? VerifyResult::kUnauthenticated : VerifyResult::kBadMac;
    EXPECT_EQ(r, expected) << "byte " << i;
  }
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", good), VerifyResult::kOk);  // nothing above was recorded
}

TEST_F(VerifierTest, SameBytesOnAnotherChannelIsBadMac) {
  const auto m = msg(100);
  EXPECT_EQ(verify("PMG_POSTURE_COMMAND", m), VerifyResult::kBadMac);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAN", m), VerifyResult::kBadMac);
  EXPECT_EQ(verify("", m), VerifyResult::kBadMac);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kOk);
}

TEST_F(VerifierTest, TruncatedTrailerIsUnauthenticatedOrBadMac) {
  const auto good = msg(100);
  for (std::size_t cut = 1; cut <= kAuthTrailerBytes + 5; ++cut) {
    std::vector<std::uint8_t> m(good.begin(), good.end() - static_cast<std::ptrdiff_t>(cut));
    const VerifyResult r = verify("PMG_VELOCITY_COMMAND", m);
    EXPECT_TRUE(r == VerifyResult::kUnauthenticated || r == VerifyResult::kBadMac) << "cut " << cut << ": " << toString(r);
  }
  std::vector<std::uint8_t> tiny(good.end() - 10, good.end());
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", tiny), VerifyResult::kUnauthenticated);
  EXPECT_EQ(verifier_.verify("PMG_VELOCITY_COMMAND", nullptr, 100, payload_size_), VerifyResult::kUnauthenticated);
}

TEST_F(VerifierTest, TrailingBytesAfterTheTrailerAreRejected) {
  for (std::size_t extra : {1u, 8u, 60u}) {
    auto m = msg(100);
    m.insert(m.end(), extra, 0x00);
    EXPECT_NE(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kOk) << extra;
  }
  // A signed message with a second, valid-looking trailer appended: the outer trailer's tag covers
  // the inner one as payload, so it must be signed again to pass — which needs the key.
  auto twice = msg(100);
  const auto copy = twice;
  twice.insert(twice.end(), copy.end() - static_cast<std::ptrdiff_t>(kAuthTrailerBytes), copy.end());
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", twice), VerifyResult::kBadMac);
}

TEST_F(VerifierTest, PlainMessageIsUnauthenticated) {
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", payload(45)), VerifyResult::kUnauthenticated);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", payload(200)), VerifyResult::kUnauthenticated);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", {}), VerifyResult::kUnauthenticated);
  auto v2 = msg(100);
  v2[v2.size() - kAuthTrailerBytes + 4] = 2;  // an unknown trailer version
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", v2), VerifyResult::kUnauthenticated);
}

TEST_F(VerifierTest, ReplayedAndOlderSeqAreReplayed) {
  const auto m = msg(100);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", m), VerifyResult::kReplayed);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(99)), VerifyResult::kReplayed);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(0)), VerifyResult::kReplayed);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(101)), VerifyResult::kOk);
  // Sequences are per (channel, sender): another channel and another sender start afresh.
  EXPECT_EQ(verify("PMG_MODE_COMMAND", msg(50, kNowUs, 7, "PMG_MODE_COMMAND")), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(50, kNowUs, 8)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(50, kNowUs, 8)), VerifyResult::kReplayed);
}

TEST_F(VerifierTest, OldAndFutureSendTimesAreStale) {
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(100, kNowUs - 500'001)), VerifyResult::kStale);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(101, kNowUs + 500'001)), VerifyResult::kStale);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(102, kNowUs - 60'000'000)), VerifyResult::kStale);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(103, INT64_MIN)), VerifyResult::kStale);  // no overflow
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(104, INT64_MAX)), VerifyResult::kStale);
  // A stale message records nothing: the same seq, fresh, is accepted.
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(100, kNowUs - 499'000)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(101, kNowUs + 499'000)), VerifyResult::kOk);
  clock_.now_us += 2'000'000;  // the receiver's wall clock moves on: the same message is now old
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(102, kNowUs + 499'000)), VerifyResult::kStale);
}

TEST_F(VerifierTest, TooManySendersOnAChannelUntilOneExpires) {
  // max_senders = 2 per channel.
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, kNowUs, 1)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, kNowUs, 2)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, kNowUs, 3)), VerifyResult::kTooManySenders);
  EXPECT_EQ(verify("PMG_POSTURE_COMMAND", msg(1, kNowUs, 3, "PMG_POSTURE_COMMAND")), VerifyResult::kOk);
  EXPECT_EQ(verifier_.trackedStreams(), 3u);
  // Sender 1 keeps sending; sender 2 stops. After 2 × max_age sender 2's slot is free again.
  clock_.now_us += 600'000;
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(2, clock_.now_us, 1)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, clock_.now_us, 3)), VerifyResult::kTooManySenders);
  clock_.now_us += 500'000;  // 1.1 s after sender 2's last message
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(3, clock_.now_us, 1)), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, clock_.now_us, 3)), VerifyResult::kOk);
  // Sender 2's old messages cannot come back through its freed slot: they are stale.
  EXPECT_EQ(verify("PMG_VELOCITY_COMMAND", msg(1, kNowUs, 2)), VerifyResult::kStale);
}

TEST_F(VerifierTest, RestartedSenderWithANewIdGetsThroughAndTheOldCannotBeReplayed) {
  clock_.now_us = wallClockNowUs();  // MessageSigner stamps and seeds seq from the real wall clock
  MessageSigner first(key_);         // random id, seq from the wall clock
  std::vector<std::uint8_t> a = payload();
  first.sign("PMG_MODE_COMMAND", a);
  EXPECT_EQ(verify("PMG_MODE_COMMAND", a), VerifyResult::kOk);
  MessageSigner second(key_);  // the "restarted" commander: a new id, a seq not below the first's
  EXPECT_NE(first.senderId(), second.senderId());
  EXPECT_GE(second.nextSeq(), first.nextSeq() - 1);
  std::vector<std::uint8_t> b = payload();
  second.sign("PMG_MODE_COMMAND", b);
  EXPECT_EQ(verify("PMG_MODE_COMMAND", b), VerifyResult::kOk);
  EXPECT_EQ(verify("PMG_MODE_COMMAND", a), VerifyResult::kReplayed);
  EXPECT_EQ(verify("PMG_MODE_COMMAND", b), VerifyResult::kReplayed);
}

TEST_F(VerifierTest, VerifyAllocatesNothing) {
  std::vector<std::vector<std::uint8_t>> msgs;
  for (std::uint64_t s = 1; s <= 50; ++s) msgs.push_back(msg(s, kNowUs, static_cast<std::uint32_t>(s % 3)));
  msgs.push_back(payload());
  std::size_t ok = 0, n = 0;
  {
    pmg::test::AllocationGuard guard;
    for (const auto& m : msgs) ok += verifier_.verify("PMG_VELOCITY_COMMAND", m.data(), m.size(), n) == VerifyResult::kOk;
    for (const auto& m : msgs) ok += verifier_.verify("PMG_VELOCITY_COMMAND", m.data(), m.size(), n) == VerifyResult::kOk;
    EXPECT_EQ(guard.count(), 0u);
  }
  EXPECT_GT(ok, 0u);
  EXPECT_LT(ok, msgs.size());
}

TEST(AuthTrailer, HeaderAndTagChecksForTools) {
  const AuthKey key = keyOf(1);
  const auto m = signedMessage(key, "CH", payload(30), 1, 2, 3);
  EXPECT_TRUE(hasTrailerHeader(m.data(), m.size()));
  EXPECT_TRUE(tagValid(key, "CH", m.data(), m.size()));
  EXPECT_FALSE(tagValid(key, "CH2", m.data(), m.size()));
  EXPECT_FALSE(tagValid(keyOf(2), "CH", m.data(), m.size()));
  const auto plain = payload(200);
  EXPECT_FALSE(hasTrailerHeader(plain.data(), plain.size()));
  EXPECT_FALSE(tagValid(key, "CH", plain.data(), plain.size()));
  EXPECT_FALSE(hasTrailerHeader(m.data(), kAuthTrailerBytes - 1));
  EXPECT_FALSE(hasTrailerHeader(nullptr, 100));
}

TEST(VerifierOptions, ValidateNamesTheFieldAndRange) {
  EXPECT_EQ(VerifierOptions{}.validate(), "");
  EXPECT_NE(VerifierOptions({0.0, 8}).validate().find("max_message_age_s = 0"), std::string::npos);
  EXPECT_NE(VerifierOptions({0.5, 0}).validate().find("max_senders = 0"), std::string::npos);
  EXPECT_NE(VerifierOptions({0.5, 65}).validate().find("expected 1..64"), std::string::npos);
  EXPECT_THROW(MessageVerifier(keyOf(1), VerifierOptions{-1.0, 8}), std::invalid_argument);
}

// ------------------------------------------------------------------------------ key files

std::string writeFile(const pmg::test::TempDir& dir, const std::string& name, const std::string& content,
                      mode_t mode) {
  const std::string path = dir.write(name, content);
  EXPECT_EQ(::chmod(path.c_str(), mode), 0);
  return path;
}

void expectConfigError(const std::string& path, const std::string& needle) {
  try {
    (void)loadAuthKey(path);
    ADD_FAILURE() << path << ": no error, expected '" << needle << "'";
  } catch (const pmg::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

const std::string kHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

TEST(KeyFile, OwnerOnlyFileIsAccepted) {
  pmg::test::TempDir dir;
  const AuthKey k1 = loadAuthKey(writeFile(dir, "a.key", kHex + "\n", 0600));
  const AuthKey k2 = loadAuthKey(writeFile(dir, "b.key", kHex, 0400));
  EXPECT_EQ(k1.bytes(), keyOf(0).bytes());
  EXPECT_EQ(k2.bytes(), keyOf(0).bytes());
  const AuthKey upper = loadAuthKey(writeFile(dir, "c.key", "000102030405060708090A0B0C0D0E0F101112131415161718191A1B1C1D1E1F", 0600));
  EXPECT_EQ(upper.bytes(), keyOf(0).bytes());
  EXPECT_EQ(toHex(k1), kHex);
}

TEST(KeyFile, GroupOrWorldAccessIsRefused) {
  pmg::test::TempDir dir;
  for (mode_t m : {0644, 0640, 0604, 0620, 0602, 0610, 0601, 0666}) {
    expectConfigError(writeFile(dir, "k" + std::to_string(m) + ".key", kHex + "\n", m), "chmod 600");
  }
}

TEST(KeyFile, MalformedContentIsRefused) {
  pmg::test::TempDir dir;
  expectConfigError(writeFile(dir, "short.key", kHex.substr(0, 62) + "\n", 0600), "expected exactly 64 hex");
  expectConfigError(writeFile(dir, "long.key", kHex + "00\n", 0600), "malformed");
  expectConfigError(writeFile(dir, "twonl.key", kHex + "\n\n", 0600), "malformed");
  expectConfigError(writeFile(dir, "huge.key", std::string(4096, 'a'), 0600), "malformed");
  expectConfigError(writeFile(dir, "empty.key", "", 0600), "malformed");
  std::string bad = kHex;
  bad[10] = 'g';
  expectConfigError(writeFile(dir, "nonhex.key", bad + "\n", 0600), "hex");
  expectConfigError(writeFile(dir, "space.key", " " + kHex.substr(1), 0600), "hex");
}

TEST(KeyFile, MissingDirectoryAndFifoAreRefused) {
  pmg::test::TempDir dir;
  expectConfigError(dir.file("none.key"), "cannot open");
  expectConfigError(dir.path().string(), "not a regular file");
  const std::string fifo = dir.file("fifo.key");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expectConfigError(fifo, "not a regular file");  // and does not block
}

TEST(KeyFile, WriteThenLoadRoundTripsAndNeverOverwrites) {
  pmg::test::TempDir dir;
  const std::string path = dir.file("new.key");
  const AuthKey key = generateAuthKey();
  writeAuthKeyFile(path, key);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(loadAuthKey(path).bytes(), key.bytes());
  EXPECT_THROW(writeAuthKeyFile(path, generateAuthKey()), std::runtime_error);
  EXPECT_EQ(loadAuthKey(path).bytes(), key.bytes());
  EXPECT_NE(generateAuthKey().bytes(), key.bytes());
  EXPECT_EQ(keyId(key).size(), 8u);
  EXPECT_EQ(keyId(key), keyId(loadAuthKey(path)));
}

}  // namespace
}  // namespace pmg::comms
