#include "pmg/comms/auth.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "pmg/common/config_error.hpp"

namespace pmg::comms {

static_assert(kAuthKeyBytes == crypto_auth_hmacsha512256_KEYBYTES, "key size");
static_assert(kAuthTagBytes == crypto_auth_hmacsha512256_BYTES, "tag size");
static_assert(kAuthSignedBytes == 28, "trailer layout");

void initSodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium: sodium_init() failed");
}

AuthKey::~AuthKey() { sodium_memzero(bytes_.data(), bytes_.size()); }

AuthKey generateAuthKey() {
  initSodium();
  std::array<std::uint8_t, kAuthKeyBytes> b{};
  randombytes_buf(b.data(), b.size());
  AuthKey key(b);
  sodium_memzero(b.data(), b.size());
  return key;
}

std::string toHex(const AuthKey& key) {
  char hex[2 * kAuthKeyBytes + 1];
  sodium_bin2hex(hex, sizeof hex, key.bytes().data(), key.bytes().size());
  std::string s(hex, 2 * kAuthKeyBytes);
  sodium_memzero(hex, sizeof hex);
  return s;
}

std::string keyId(const AuthKey& key) {
  initSodium();
  unsigned char h[16];
  crypto_generichash(h, sizeof h, key.bytes().data(), key.bytes().size(), nullptr, 0);
  char hex[2 * sizeof h + 1];
  sodium_bin2hex(hex, sizeof hex, h, sizeof h);
  return std::string(hex, 8);
}

namespace {

/// Closes a file descriptor on scope exit.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

std::string errnoText(int e) { return std::strerror(e); }

std::string modeText(mode_t m) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", static_cast<unsigned>(m & 07777));
  return buf;
}

}  // namespace

AuthKey loadAuthKey(const std::string& path) {
  initSodium();
  const std::string what = "key file '" + path + "': ";
  if (path.empty()) throw ConfigError("key file: empty path");
  // O_NONBLOCK: opening a FIFO must not block; the fstat below refuses anything but a regular file.
  Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK)};
  if (f.fd < 0) throw ConfigError(what + "cannot open: " + errnoText(errno));
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) throw ConfigError(what + "cannot stat: " + errnoText(errno));
  if (!S_ISREG(st.st_mode)) throw ConfigError(what + "not a regular file");
  if (st.st_uid != ::geteuid())
    throw ConfigError(what + "owned by uid " + std::to_string(st.st_uid) + ", not by the current user (uid " +
                      std::to_string(::geteuid()) + ")");
  if ((st.st_mode & 077) != 0)
    throw ConfigError(what + "mode " + modeText(st.st_mode) +
                      " lets group or others access it: expected owner-only (run: chmod 600 " + path + ")");
  // Exactly 64 hex characters and an optional newline: read one byte more than that to see excess.
  unsigned char buf[2 * kAuthKeyBytes + 2];
  std::size_t n = 0;
  while (n < sizeof buf) {
    const ssize_t r = ::read(f.fd, buf + n, sizeof buf - n);
    if (r < 0) {
      if (errno == EINTR) continue;
      sodium_memzero(buf, sizeof buf);
      throw ConfigError(what + "cannot read: " + errnoText(errno));
    }
    if (r == 0) break;
    n += static_cast<std::size_t>(r);
  }
  std::size_t hex_len = n;
  if (hex_len == 2 * kAuthKeyBytes + 1 && buf[hex_len - 1] == '\n') --hex_len;
  std::array<std::uint8_t, kAuthKeyBytes> bytes{};
  std::size_t bin_len = 0;
  const bool ok = hex_len == 2 * kAuthKeyBytes &&
                  sodium_hex2bin(bytes.data(), bytes.size(), reinterpret_cast<const char*>(buf), hex_len, nullptr,
                                 &bin_len, nullptr) == 0 &&
                  bin_len == kAuthKeyBytes;
  sodium_memzero(buf, sizeof buf);
  if (!ok) {
    sodium_memzero(bytes.data(), bytes.size());
    const std::string got = n >= sizeof buf ? "more than " + std::to_string(2 * kAuthKeyBytes + 1) + " bytes"
                                            : std::to_string(n) + " bytes";
    throw ConfigError(what + "malformed (" + got + "): expected exactly " + std::to_string(2 * kAuthKeyBytes) +
                      " hex characters and an optional newline (write one with pmg_keygen --out FILE)");
  }
  AuthKey key(bytes);
  sodium_memzero(bytes.data(), bytes.size());
  return key;
}

void writeAuthKeyFile(const std::string& path, const AuthKey& key) {
  const std::string what = "key file '" + path + "': ";
  Fd f{::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600)};
  if (f.fd < 0) {
    if (errno == EEXIST) throw std::runtime_error(what + "already exists (a key is never overwritten)");
    throw std::runtime_error(what + "cannot create: " + errnoText(errno));
  }
  std::string text = toHex(key) + "\n";
  bool ok = ::fchmod(f.fd, 0600) == 0;
  std::size_t done = 0;
  while (ok && done < text.size()) {
    const ssize_t w = ::write(f.fd, text.data() + done, text.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      ok = false;
      break;
    }
    done += static_cast<std::size_t>(w);
  }
  ok = ok && ::fsync(f.fd) == 0;
  const int e = errno;
  sodium_memzero(&text[0], text.size());
  if (!ok) {
    ::unlink(path.c_str());
    throw std::runtime_error(what + "cannot write: " + errnoText(e));
  }
}

// ------------------------------------------------------------------------------ trailer

namespace {

void putBE(std::uint8_t* p, std::uint64_t v, int bytes) noexcept {
  for (int i = bytes - 1; i >= 0; --i) {
    p[i] = static_cast<std::uint8_t>(v & 0xffu);
    v >>= 8;
  }
}

/// |a − b| without overflow, for any two (hostile) times.
std::uint64_t absDiff(std::int64_t a, std::int64_t b) noexcept {
  return a >= b ? static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)
                : static_cast<std::uint64_t>(b) - static_cast<std::uint64_t>(a);
}

std::uint64_t getBE(const std::uint8_t* p, int bytes) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

/// The tag over u16 channel length | channel | payload | trailer[0..28).
void computeTag(const AuthKey& key, std::string_view channel, const std::uint8_t* payload, std::size_t size,
                const std::uint8_t* signed_part, std::uint8_t* tag) noexcept {
  crypto_auth_hmacsha512256_state st;
  crypto_auth_hmacsha512256_init(&st, key.bytes().data(), key.bytes().size());
  std::uint8_t len[2];
  putBE(len, channel.size() > 0xffffu ? 0xffffu : channel.size(), 2);
  crypto_auth_hmacsha512256_update(&st, len, sizeof len);
  crypto_auth_hmacsha512256_update(&st, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  if (size > 0) crypto_auth_hmacsha512256_update(&st, payload, size);
  crypto_auth_hmacsha512256_update(&st, signed_part, kAuthSignedBytes);
  crypto_auth_hmacsha512256_final(&st, tag);
  sodium_memzero(&st, sizeof st);
}

}  // namespace

void writeTrailer(const AuthKey& key, std::string_view channel, const std::uint8_t* payload, std::size_t size,
                  const AuthTrailerFields& fields, std::uint8_t* out) noexcept {
  std::memcpy(out, kAuthMagic, 4);
  out[4] = kAuthVersion;
  out[5] = out[6] = out[7] = 0;
  putBE(out + 8, fields.sender_id, 4);
  putBE(out + 12, fields.seq, 8);
  putBE(out + 20, static_cast<std::uint64_t>(fields.send_time_us), 8);
  computeTag(key, channel, payload, size, out, out + kAuthSignedBytes);
}

std::int64_t wallClockNowUs() noexcept {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool hasTrailerHeader(const void* data, std::size_t size) noexcept {
  if (data == nullptr || size < kAuthTrailerBytes) return false;
  const std::uint8_t* t = static_cast<const std::uint8_t*>(data) + (size - kAuthTrailerBytes);
  return std::memcmp(t, kAuthMagic, 4) == 0 && t[4] == kAuthVersion && t[5] == 0 && t[6] == 0 && t[7] == 0;
}

bool tagValid(const AuthKey& key, std::string_view channel, const void* data, std::size_t size) noexcept {
  if (!hasTrailerHeader(data, size)) return false;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  const std::size_t n = size - kAuthTrailerBytes;
  std::uint8_t tag[kAuthTagBytes];
  computeTag(key, channel, bytes, n, bytes + n, tag);
  const bool ok = crypto_verify_32(tag, bytes + n + kAuthSignedBytes) == 0;
  sodium_memzero(tag, sizeof tag);
  return ok;
}

// ------------------------------------------------------------------------------ signer

MessageSigner::MessageSigner(const AuthKey& key) : key_(key) {
  initSodium();
  sender_id_ = randombytes_random();
  next_seq_ = static_cast<std::uint64_t>(wallClockNowUs());
}

MessageSigner::MessageSigner(const AuthKey& key, std::uint32_t sender_id, std::uint64_t first_seq)
    : key_(key), sender_id_(sender_id), next_seq_(first_seq) {
  initSodium();
}

void MessageSigner::sign(std::string_view channel, std::vector<std::uint8_t>& message, std::int64_t send_time_us) {
  const std::size_t n = message.size();
  message.resize(n + kAuthTrailerBytes);
  writeTrailer(key_, channel, message.data(), n, AuthTrailerFields{sender_id_, next_seq_, send_time_us},
               message.data() + n);
  ++next_seq_;
}

// ------------------------------------------------------------------------------ verifier

const char* toString(VerifyResult r) noexcept {
  switch (r) {
    case VerifyResult::kOk: return "ok";
    case VerifyResult::kUnauthenticated: return "unauthenticated";
    case VerifyResult::kBadMac: return "bad MAC";
    case VerifyResult::kReplayed: return "replayed";
    case VerifyResult::kStale: return "stale";
    case VerifyResult::kTooManySenders: return "too many senders";
  }
  return "unknown";
}

std::string VerifierOptions::validate() const {
  if (!(std::isfinite(max_age_s) && max_age_s > 0.0 && max_age_s <= 60.0))
    return "max_message_age_s = " + std::to_string(max_age_s) + ": expected (0, 60] s";
  if (max_senders < 1 || max_senders > kMaxSendersLimit)
    return "max_senders = " + std::to_string(max_senders) + ": expected 1.." +
           std::to_string(kMaxSendersLimit);
  return {};
}

namespace {
std::int64_t systemWallClock(const void*) noexcept { return wallClockNowUs(); }
}  // namespace

MessageVerifier::MessageVerifier(const AuthKey& key, VerifierOptions options, WallClock clock,
                                 const void* clock_context)
    : key_(key),
      options_(options),
      max_age_us_(0),
      clock_(clock != nullptr ? clock : &systemWallClock),
      clock_context_(clock_context) {
  initSodium();
  if (const std::string e = options_.validate(); !e.empty()) throw std::invalid_argument(e);
  max_age_us_ = static_cast<std::int64_t>(std::llround(options_.max_age_s * 1e6));
  table_.resize(static_cast<std::size_t>(options_.max_senders) * kMaxTrackedChannels);
}

std::size_t MessageVerifier::trackedStreams() const noexcept {
  std::size_t n = 0;
  for (const Entry& e : table_) n += e.used ? 1 : 0;
  return n;
}

VerifyResult MessageVerifier::verify(std::string_view channel, const void* data, std::size_t size,
                                     std::size_t& payload_size) noexcept {
  if (data == nullptr || size < kAuthTrailerBytes || channel.size() > kMaxChannelBytes)
    return VerifyResult::kUnauthenticated;
  if (!hasTrailerHeader(data, size)) return VerifyResult::kUnauthenticated;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  const std::size_t n = size - kAuthTrailerBytes;
  const std::uint8_t* t = bytes + n;

  std::uint8_t tag[kAuthTagBytes];
  computeTag(key_, channel, bytes, n, t, tag);
  const bool mac_ok = crypto_verify_32(tag, t + kAuthSignedBytes) == 0;
  sodium_memzero(tag, sizeof tag);
  if (!mac_ok) return VerifyResult::kBadMac;

  const auto sender_id = static_cast<std::uint32_t>(getBE(t + 8, 4));
  const std::uint64_t seq = getBE(t + 12, 8);
  const auto send_time_us = static_cast<std::int64_t>(getBE(t + 20, 8));
  const std::int64_t now_us = clock_(clock_context_);

  // Find this stream; note free (or expired) slots and the senders active on this channel.
  Entry* found = nullptr;
  Entry* free_slot = nullptr;
  int on_channel = 0;
  for (Entry& e : table_) {
    if (e.used && e.last_send_time_us < now_us &&
        absDiff(now_us, e.last_send_time_us) > 2 * static_cast<std::uint64_t>(max_age_us_))
      e.used = false;  // expired: every replay of this sender is stale by now
    if (!e.used) {
      if (free_slot == nullptr) free_slot = &e;
      continue;
    }
    if (e.channel_len != channel.size() || std::memcmp(e.channel.data(), channel.data(), channel.size()) != 0)
      continue;
    ++on_channel;
    if (e.sender_id == sender_id) found = &e;
  }
  if (found != nullptr && seq <= found->last_seq) return VerifyResult::kReplayed;
  if (absDiff(now_us, send_time_us) > static_cast<std::uint64_t>(max_age_us_)) return VerifyResult::kStale;
  if (found == nullptr) {
    if (free_slot == nullptr || on_channel >= options_.max_senders) return VerifyResult::kTooManySenders;
    found = free_slot;
    found->used = true;
    found->channel_len = static_cast<std::uint8_t>(channel.size());
    std::memcpy(found->channel.data(), channel.data(), channel.size());
    found->sender_id = sender_id;
  }
  found->last_seq = seq;
  found->last_send_time_us = send_time_us;
  payload_size = n;
  return VerifyResult::kOk;
}

}  // namespace pmg::comms
