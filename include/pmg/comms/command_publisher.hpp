#pragma once
/// @file command_publisher.hpp
/// pmg::comms::CommandPublisher: the one way a commander (pmg_command_script, pmg_gamepad,
/// pmg_vr_bridge) puts operator commands on LCM. It fills the LCM messages (lcmtypes/*.lcm; `utime`
/// = sender wall clock [µs since the Unix epoch], `source` = the commander's name), encodes them and,
/// when a key file is given, appends the 60-byte authentication trailer of pmg::comms::MessageSigner
/// (include/pmg/comms/auth.hpp, docs/teleop.md) before publishing.
///
/// Setup (the constructor) may allocate and throw; the publish calls never throw: they return false
/// and count a failure (bad value such as NaN is NOT filtered here: the controller rejects it and
/// counts it, which is what the tests of the receiver rely on). Thread-safe (one internal mutex):
/// the publish calls may come from several threads of one commander.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "pmg/comms/auth.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/hal/modes.hpp"

namespace lcm {
class LCM;
}
namespace pmg_lcm {
class vr_pose_t;
}

namespace pmg::comms {

class CommandPublisher {
 public:
  /// @param lcm_url LCM provider URL (pmg::kDefaultLcmUrl keeps traffic on the host: ttl=0).
  /// @param key_file key written by pmg_keygen (owner-only, 0600); empty: plain (unsigned) messages,
  ///        which a controller with `security.key_file` set refuses.
  /// @param source the `source` string of every message ("gamepad", "vr", "script"; 1..63 bytes).
  /// @throws std::runtime_error if LCM cannot be opened on @p lcm_url; pmg::ConfigError if the key
  ///         file is unsafe or malformed (loadAuthKey()); std::invalid_argument for a bad @p source.
  CommandPublisher(const std::string& lcm_url, const std::string& key_file, std::string source);
  ~CommandPublisher();
  CommandPublisher(const CommandPublisher&) = delete;
  CommandPublisher& operator=(const CommandPublisher&) = delete;

  /// PMG_VELOCITY_COMMAND: heading frame H, vx forward [m/s], vy left [m/s], wz yaw rate CCW [rad/s].
  bool publishVelocity(double vx, double vy, double wz);
  /// PMG_POSTURE_COMMAND: torso pitch (forward bend) [rad], roll (lean right) [rad], pelvis height
  /// above the ground [m] or nullopt (the standing height).
  bool publishPosture(double pitch, double roll, std::optional<double> height);
  /// PMG_MODE_COMMAND: a mode request (its wire code, include/pmg/hal/modes.hpp). kNone is refused
  /// (returns false, counted as failed).
  bool publishMode(pmg::ModeRequest m);
  /// PMG_VR_POSE: @p m as given, except `source` (set to this publisher's) and `utime` (set to now).
  bool publishVrPose(const pmg_lcm::vr_pose_t& m);
  /// Publishes already LCM-encoded bytes on @p channel (replay tools, tests), signing them when
  /// keyed. Bytes that already end in a trailer (a recorded signed message): keyed, the trailer is
  /// replaced by a fresh one only if its tag is valid under this publisher's key, else the message
  /// is refused (false, counted as failed: a recorded forgery is never re-signed); unkeyed, the
  /// trailer is removed.
  bool publishEncoded(const std::string& channel, const std::vector<std::uint8_t>& lcm_bytes);

  /// True when a key was loaded (every message carries a trailer).
  bool authenticated() const noexcept { return signer_ != nullptr; }
  /// Sender id of the trailers (random per process; 0 when not authenticated).
  std::uint32_t senderId() const noexcept;
  /// The key's public id (pmg::comms::keyId(), as pmg_controller prints it); "" when not authenticated.
  const std::string& keyId() const noexcept { return key_id_; }
  /// Messages handed to LCM successfully / refused or failed.
  std::uint64_t published() const noexcept { return published_.load(std::memory_order_relaxed); }
  std::uint64_t failed() const noexcept { return failed_.load(std::memory_order_relaxed); }
  const std::string& source() const noexcept { return source_; }

 private:
  bool send(const char* channel);  // signs (when keyed) and publishes buffer_; caller holds mutex_
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<MessageSigner> signer_;
  std::string source_;
  std::string key_id_;
  std::mutex mutex_;
  std::vector<std::uint8_t> buffer_;
  std::atomic<std::uint64_t> published_{0}, failed_{0};
};

}  // namespace pmg::comms
