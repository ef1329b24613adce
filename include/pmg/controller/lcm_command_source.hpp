#pragma once
/// @file lcm_command_source.hpp
/// Operator commands from LCM (PMG_VELOCITY_COMMAND, PMG_POSTURE_COMMAND, PMG_MODE_COMMAND;
/// lcmtypes/*.lcm) into the 100 Hz loop.
///
/// Every packet is hostile until proven otherwise. LcmCommandDecoder checks the raw bytes before
/// anything is decoded: the type fingerprint, the exact encoded size (no truncation, no trailing
/// padding), the `source` string's length field (1..64 bytes including its NUL, NUL-terminated),
/// finite numbers and a known mode code (pmg::modeRequestFromWire). A packet that fails any check
/// is dropped and counted by cause (LcmInputCounters); nothing is printed from the receive path and
/// no exception can leave it. LcmCommandSource runs the receive thread.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>

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

/// Channel names of the command types.
inline constexpr const char* kVelocityChannel = "PMG_VELOCITY_COMMAND";
inline constexpr const char* kPostureChannel = "PMG_POSTURE_COMMAND";
inline constexpr const char* kModeChannel = "PMG_MODE_COMMAND";
/// Longest accepted `source` string, including its terminating NUL [bytes].
inline constexpr std::int32_t kMaxSourceBytes = 64;

/// Decodes raw LCM command packets into a CommandSample. noexcept; allocates nothing.
class LcmCommandDecoder {
 public:
  /// Checks and decodes one packet of @p channel. On kAccepted updates @p sample (the velocity or
  /// posture part with its receive time @p receive_time_s, or a new mode request with
  /// mode_request_seq incremented); otherwise leaves it unchanged. Counts every outcome.
  DecodeResult decode(std::string_view channel, const void* data, std::size_t size, double receive_time_s,
                      CommandSample& sample) noexcept;
  const LcmInputCounters& counters() const noexcept { return counters_; }
  /// Counts an exception caught around the decoder or LCM's dispatch (kInternalError).
  void countInternalError() noexcept { counters_.add(DecodeResult::kInternalError); }

 private:
  LcmInputCounters counters_;
};

/// The LCM command source: a receive thread that decodes the command channels and writes the
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
