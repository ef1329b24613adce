#pragma once
/// @file lcm_command_source.hpp
/// Operator commands from LCM (PMG_VELOCITY_COMMAND, PMG_POSTURE_COMMAND, PMG_MODE_COMMAND,
/// PMG_VR_POSE; lcmtypes/*.lcm) into the 100 Hz loop.
///
/// Every packet is hostile until proven otherwise. With a key configured (controller config
/// `security.key_file`, LcmCommandDecoder::requireAuthentication()) the packet's authentication
/// trailer is verified first (pmg::comms::MessageVerifier: MAC, replay, age, sender table;
/// include/pmg/comms/auth.hpp) and plain packets are refused; the checks below then run on the
/// payload without its trailer. Without a key, a packet that ends in a trailer (a signed
/// commander, a recorded signed log) is decoded without it: the trailer is not checked, as nothing
/// is. LcmCommandDecoder checks the raw bytes before anything is decoded:
/// the type fingerprint, the exact encoded size (no truncation, no trailing padding), the `source`
/// string's length field (1..64 bytes including its NUL, NUL-terminated), finite numbers, a known
/// mode code (pmg::modeRequestFromWire) and, for PMG_VR_POSE, ranges (unit quaternions to 1e-3,
/// grip/trigger in [0, 1], thumbsticks in [−1, 1], booleans 0/1, known button bits). A packet that
/// fails any check is dropped and counted by cause (LcmInputCounters); nothing is printed from the
/// receive path and no exception can leave it. LcmCommandSource runs the receive thread.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>

#include "pmg/comms/auth.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/controller/commands.hpp"

namespace lcm {
class LCM;
}

namespace pmg {

/// Outcome of decoding one packet.
enum class DecodeResult : std::uint8_t {
  kAccepted = 0,
  kUnknownChannel,  ///< not one of the three command channels
  kTruncated,       ///< fewer bytes than the type's encoding needs
  kTrailingBytes,   ///< more bytes than the encoding (padded or concatenated packets)
  kBadFingerprint,  ///< the 8-byte type hash does not match the channel's type
  kBadString,       ///< `source` length field ≤ 0 or > 64, or not NUL-terminated (one beyond the packet: kTruncated)
  kNonFinite,       ///< NaN/Inf in a command value
  kUnknownMode,     ///< mode code outside 0..4
  kOutOfRange,      ///< VR pose: quaternion not unit (|‖q‖−1| > 1e-3), grip/trigger outside [0, 1],
                    ///< thumbstick outside [−1, 1], boolean not 0/1, unknown button bits
  kUnauthenticated, ///< key configured: no (or a malformed) authentication trailer, e.g. a plain packet
  kBadMac,          ///< key configured: the tag does not match (forged, wrong key, altered, other channel)
  kReplayed,        ///< key configured: seq not above the sender's last accepted one on this channel
  kStale,           ///< key configured: |wall clock − send time| > security.max_message_age_s
  kTooManySenders,  ///< key configured: a new sender while security.max_senders are active on the channel
  kInternalError,   ///< an exception inside the decoder (never expected; counted, not thrown)
  kCount
};
inline constexpr std::size_t kNumDecodeResults = static_cast<std::size_t>(DecodeResult::kCount);
/// "accepted", "truncated", ... (for summaries).
const char* toString(DecodeResult r) noexcept;

/// Packets per outcome (thread-safe to read while the receive thread counts).
class LcmInputCounters {
 public:
  void add(DecodeResult r) noexcept { counts_[static_cast<std::size_t>(r)].fetch_add(1, std::memory_order_relaxed); }
  std::uint64_t count(DecodeResult r) const noexcept {
    return counts_[static_cast<std::size_t>(r)].load(std::memory_order_relaxed);
  }
  std::uint64_t accepted() const noexcept { return count(DecodeResult::kAccepted); }
  /// Every packet that was not accepted.
  std::uint64_t rejected() const noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, kNumDecodeResults> counts_{};
};

// Channel names of the command types (kVelocityChannel, kPostureChannel, kModeChannel,
// kVrPoseChannel): include/pmg/comms/channels.hpp.
/// Longest accepted `source` string, including its terminating NUL [bytes].
inline constexpr std::int32_t kMaxSourceBytes = 64;
/// Packets LCM queues per command channel before the receive thread takes them (LCM's default is
/// 30). Under a flood, packets beyond it are dropped inside LCM (not counted here); at a few µs
/// per packet (verify + decode) a full queue is worked off in about a millisecond.
inline constexpr int kLcmQueueCapacity = 256;
/// Largest accepted |‖q‖ − 1| of a VR pose quaternion.
inline constexpr double kVrQuaternionTolerance = 1e-3;

/// The authentication cause of a verifier outcome (kOk → kAccepted).
DecodeResult toDecodeResult(comms::VerifyResult r) noexcept;

/// Decodes raw LCM command packets into a CommandSample. decode() is noexcept and allocates
/// nothing (also with authentication: the verifier's table is sized in requireAuthentication()).
class LcmCommandDecoder {
 public:
  LcmCommandDecoder();
  ~LcmCommandDecoder();
  LcmCommandDecoder(const LcmCommandDecoder&) = delete;
  LcmCommandDecoder& operator=(const LcmCommandDecoder&) = delete;

  /// Setup: from now on every packet must carry a valid trailer signed with @p key
  /// (include/pmg/comms/auth.hpp); plain packets are refused (kUnauthenticated). @p clock: the
  /// wall clock [µs since the Unix epoch] of the age check (nullptr: the system clock; tests
  /// inject one). @throws std::invalid_argument if @p options is invalid.
  void requireAuthentication(const comms::AuthKey& key, const comms::VerifierOptions& options,
                             comms::MessageVerifier::WallClock clock = nullptr, const void* clock_context = nullptr);
  bool authenticated() const noexcept { return verifier_ != nullptr; }

  /// Checks and decodes one packet of @p channel. On kAccepted updates @p sample (the velocity,
  /// posture or VR part with its receive time @p receive_time_s, or a new mode request with
  /// mode_request_seq incremented); otherwise leaves it unchanged. Counts every outcome.
  DecodeResult decode(std::string_view channel, const void* data, std::size_t size, double receive_time_s,
                      CommandSample& sample) noexcept;
  const LcmInputCounters& counters() const noexcept { return counters_; }
  /// Counts an exception caught around the decoder or LCM's dispatch (kInternalError).
  void countInternalError() noexcept { counters_.add(DecodeResult::kInternalError); }

 private:
  LcmInputCounters counters_;
  std::unique_ptr<comms::MessageVerifier> verifier_;
};

/// The LCM command source: a receive thread that decodes the four command channels and writes the
/// newest CommandSample to @p sink (the loop reads it once per tick). start()/stop() are setup
/// calls; the thread itself never throws and never prints per packet.
class LcmCommandSource {
 public:
  /// Sink: called from the receive thread with the updated sample (must be noexcept, wait-free).
  using Sink = void (*)(void* context, const CommandSample& sample) noexcept;
  /// Clock: controller time [s] (the loop's clock), called from the receive thread.
  using Clock = double (*)(const void* context) noexcept;
  /// @throws std::runtime_error if LCM cannot be opened on @p url.
  LcmCommandSource(const std::string& url, Sink sink, void* sink_context, Clock clock, const void* clock_context);
  ~LcmCommandSource();
  LcmCommandSource(const LcmCommandSource&) = delete;
  LcmCommandSource& operator=(const LcmCommandSource&) = delete;

  /// Setup, before start(): authenticated commands only (LcmCommandDecoder::requireAuthentication()).
  /// @throws std::logic_error once started; std::invalid_argument for bad @p options.
  void requireAuthentication(const comms::AuthKey& key, const comms::VerifierOptions& options);
  bool authenticated() const noexcept { return decoder_.authenticated(); }

  void start();
  void stop();
  const LcmInputCounters& counters() const noexcept { return decoder_.counters(); }

 private:
  void threadMain() noexcept;
  std::unique_ptr<lcm::LCM> lcm_;
  LcmCommandDecoder decoder_;
  CommandSample sample_{};
  Sink sink_;
  void* sink_context_;
  Clock clock_;
  const void* clock_context_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace pmg
