#pragma once
/// @file auth.hpp
/// Authenticated LCM command channels (issue 13, "only authorized commanders";
/// docs/teleop.md has the threat model).
///
/// LCM is unauthenticated UDP multicast. A signed message is the ordinary LCM-encoded message
/// followed by a fixed 60-byte trailer (integers big-endian):
///
///   offset  size  field
///        0     4  magic "PMGA"
///        4     1  version (= 1)
///        5     3  reserved (0)
///        8     4  sender_id      u32, random per sender process
///       12     8  seq            u64, starts at the sender's start time [µs since the Unix epoch],
///                                +1 per message (a restarted sender stays monotonic)
///       20     8  send_time_us   i64, sender wall clock [µs since the Unix epoch]
///       28    32  tag            HMAC-SHA-512-256 (libsodium crypto_auth) over
///                                u16 channel length | channel name | payload | trailer bytes 0..27
///
/// The channel name is inside the tag, so a message cannot be moved to another channel. LCM
/// decoders ignore trailing bytes, so lcm-spy and lcm-logger still read signed messages.
///
/// The MAC is libsodium's (`crypto_auth_hmacsha512256` with its streaming state; the tag is
/// compared with `crypto_verify_32`, constant time). Keys are 32 random bytes, stored as 64 hex
/// characters in a file only its owner may read (pmg_keygen writes one).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pmg::comms {

inline constexpr std::size_t kAuthKeyBytes = 32;      ///< crypto_auth_KEYBYTES
inline constexpr std::size_t kAuthTagBytes = 32;      ///< crypto_auth_BYTES
inline constexpr std::size_t kAuthTrailerBytes = 60;  ///< trailer size (see the file comment)
inline constexpr std::size_t kAuthSignedBytes = kAuthTrailerBytes - kAuthTagBytes;  ///< trailer part under the tag
inline constexpr std::uint8_t kAuthVersion = 1;
inline constexpr char kAuthMagic[4] = {'P', 'M', 'G', 'A'};
/// Longest channel name the verifier tracks [bytes] (LCM's own limit, LCM_MAX_CHANNEL_NAME_LENGTH).
inline constexpr std::size_t kMaxChannelBytes = 63;

/// Initialises libsodium (sodium_init(); idempotent, thread-safe). Called by every constructor
/// below and by loadAuthKey(). @throws std::runtime_error if libsodium cannot be initialised.
void initSodium();

/// A 32-byte MAC key. The destructor wipes it (sodium_memzero).
class AuthKey {
 public:
  AuthKey() = default;
  explicit AuthKey(const std::array<std::uint8_t, kAuthKeyBytes>& bytes) noexcept : bytes_(bytes) {}
  AuthKey(const AuthKey&) = default;
  AuthKey& operator=(const AuthKey&) = default;
  ~AuthKey();
  const std::array<std::uint8_t, kAuthKeyBytes>& bytes() const noexcept { return bytes_; }

 private:
  std::array<std::uint8_t, kAuthKeyBytes> bytes_{};
};

/// A fresh random key (randombytes_buf).
AuthKey generateAuthKey();
/// 64 lower-case hex characters (the key file's content without its newline).
std::string toHex(const AuthKey& key);
/// A short public id of the key, safe to print: the first 8 hex characters of its BLAKE2b hash
/// (crypto_generichash). Two hosts with the same key print the same id.
std::string keyId(const AuthKey& key);

/// Reads a key file: exactly 64 hex characters, optionally followed by one "\n".
/// @throws pmg::ConfigError naming @p path and the reason when the file cannot be opened, is not a
///         regular file, is not owned by the current (effective) user, is group- or world-readable
///         or -writable (st_mode & 077: "chmod 600 FILE"), or is malformed (length, non-hex).
///         The checks are made on the opened file (fstat), not on the path.
AuthKey loadAuthKey(const std::string& path);

/// Writes @p key to a new file @p path with mode 0600 (O_CREAT | O_EXCL | O_NOFOLLOW: an existing
/// file or link is never overwritten). @throws std::runtime_error naming the file and the reason.
void writeAuthKeyFile(const std::string& path, const AuthKey& key);

/// The fields of a trailer that are not the tag.
struct AuthTrailerFields {
  std::uint32_t sender_id = 0;
  std::uint64_t seq = 0;
  std::int64_t send_time_us = 0;  ///< [µs since the Unix epoch]
};

/// Writes the 60-byte trailer of the message (@p channel, @p payload of @p size bytes) into
/// @p trailer_out. noexcept, allocation-free. A channel longer than 65535 bytes is cut in the
/// length field only (such channels are never delivered by LCM).
void writeTrailer(const AuthKey& key, std::string_view channel, const std::uint8_t* payload, std::size_t size,
                  const AuthTrailerFields& fields, std::uint8_t* trailer_out) noexcept;

/// True when the last kAuthTrailerBytes of @p data start like a trailer (magic, version, reserved
/// bytes). Says nothing about the tag: for handling signed messages where no key is configured.
bool hasTrailerHeader(const void* data, std::size_t size) noexcept;
/// True when @p data ends in a trailer whose tag is valid for @p channel under @p key (no replay or
/// age check: for tools that re-publish recorded messages). noexcept, allocation-free.
bool tagValid(const AuthKey& key, std::string_view channel, const void* data, std::size_t size) noexcept;

/// Wall clock [µs since the Unix epoch] (std::chrono::system_clock).
std::int64_t wallClockNowUs() noexcept;

/// The sending side: a sender id and a sequence counter. Not thread-safe (one per publisher,
/// used under its lock).
class MessageSigner {
 public:
  /// Random sender id (randombytes), seq starting at the current wall clock [µs].
  explicit MessageSigner(const AuthKey& key);
  /// Explicit identity (tests, tools).
  MessageSigner(const AuthKey& key, std::uint32_t sender_id, std::uint64_t first_seq);
  /// Appends the trailer to @p message (the LCM-encoded payload of @p channel), stamped with
  /// @p send_time_us, and advances seq. Allocates only if @p message has no spare capacity.
  void sign(std::string_view channel, std::vector<std::uint8_t>& message, std::int64_t send_time_us);
  /// Same, stamped with wallClockNowUs().
  void sign(std::string_view channel, std::vector<std::uint8_t>& message) { sign(channel, message, wallClockNowUs()); }
  std::uint32_t senderId() const noexcept { return sender_id_; }
  const AuthKey& key() const noexcept { return key_; }
  /// The seq the next message will carry.
  std::uint64_t nextSeq() const noexcept { return next_seq_; }

 private:
  AuthKey key_;
  std::uint32_t sender_id_;
  std::uint64_t next_seq_;
};

/// Outcome of verifying one message.
enum class VerifyResult : std::uint8_t {
  kOk = 0,
  kUnauthenticated,  ///< no (or a malformed) trailer: plain message, wrong magic/version/reserved, channel too long
  kBadMac,           ///< the tag does not match (forged, wrong key, altered bytes, other channel)
  kReplayed,         ///< seq ≤ the last accepted seq of this (channel, sender)
  kStale,            ///< |wall clock − send_time| > max_age (old or from the future)
  kTooManySenders,   ///< a new sender while max_senders senders are active on the channel
};
const char* toString(VerifyResult r) noexcept;

/// Options of MessageVerifier (controller config block `security:`).
struct VerifierOptions {
  /// Largest accepted |receiver wall clock − send_time| [s]. The hosts' clocks must be synchronised
  /// well below this (chrony/NTP/PTP; docs/teleop.md). Range (0, 60].
  double max_age_s = 0.5;
  /// Most senders active at once on one channel (a sender stays active for 2·max_age_s after its
  /// last accepted message). Range 1..kMaxSendersLimit.
  int max_senders = 8;
  /// Empty when valid, else "<field> = <value>: expected ..." (the field names of the controller
  /// config's `security:` block).
  std::string validate() const;
};
/// Upper bound of VerifierOptions::max_senders.
inline constexpr int kMaxSendersLimit = 64;
/// Channels tracked at once (the table holds max_senders × kMaxTrackedChannels entries).
inline constexpr int kMaxTrackedChannels = 8;

/// The receiving side: checks trailer, tag, replay and age. verify() is noexcept and allocates
/// nothing (the sender table is sized once in the constructor); not thread-safe (one receive
/// thread).
///
/// Order of the checks: trailer present and well-formed (kUnauthenticated) → tag (kBadMac; nothing
/// below is trusted before) → seq > last accepted seq of (channel, sender) (kReplayed) → age
/// (kStale) → room for a new sender (kTooManySenders). Only an accepted message updates the table.
/// A sender's entry expires 2·max_age_s (receiver wall clock) after its last accepted send time:
/// any replay of its messages is then stale, so a restarted sender (new random id) takes its place.
class MessageVerifier {
 public:
  /// Wall clock [µs since the Unix epoch]; injectable for tests.
  using WallClock = std::int64_t (*)(const void* context) noexcept;
  /// @throws std::invalid_argument if @p options is invalid; std::runtime_error if libsodium fails.
  MessageVerifier(const AuthKey& key, VerifierOptions options, WallClock clock = nullptr,
                  const void* clock_context = nullptr);

  /// Verifies @p size bytes at @p data received on @p channel. On kOk @p payload_size is the size
  /// of the LCM payload (size − kAuthTrailerBytes); otherwise it is left unchanged.
  VerifyResult verify(std::string_view channel, const void* data, std::size_t size,
                      std::size_t& payload_size) noexcept;

  const VerifierOptions& options() const noexcept { return options_; }
  /// Entries in use (for tests; ≤ max_senders × kMaxTrackedChannels).
  std::size_t trackedStreams() const noexcept;

 private:
  struct Entry {
    bool used = false;
    std::uint8_t channel_len = 0;
    std::array<char, kMaxChannelBytes> channel{};
    std::uint32_t sender_id = 0;
    std::uint64_t last_seq = 0;
    std::int64_t last_send_time_us = 0;
  };
  AuthKey key_;
  VerifierOptions options_;
  std::int64_t max_age_us_;
  WallClock clock_;
  const void* clock_context_;
  std::vector<Entry> table_;
};

}  // namespace pmg::comms
