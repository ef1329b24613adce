#pragma once
/// @file vr_replay.hpp
/// Recorded VR sessions: LCM event logs of channel PMG_VR_POSE (recorded with `lcm-logger`, e.g.
/// data/vr/sessions/synthetic_walk.lcmlog) read back and re-published with their original timing
/// (pmg_vr_replay). A log is outside input: every message is decoded and checked
/// (checkVrPoseMessage); bad ones are skipped and counted.
///
/// Re-publishing goes through pmg::comms::CommandPublisher (new `utime` and, with a key, a fresh
/// authentication trailer: the controller refuses the recorded trailers as replays). When looping,
/// `frame` and `xr_time_us` continue across the loop boundary (offset by one log length per loop),
/// so a receiver that expects them to grow sees a continuous stream.

#include <atomic>
#include <cstdint>
#include <functional>
#include <pmg_lcm/vr_pose_t.hpp>
#include <string>
#include <vector>

namespace pmg::teleop {

/// One PMG_VR_POSE event of a log.
struct VrLogEvent {
  std::int64_t log_utime = 0;  ///< event timestamp of the log [µs] (the logger's receive time)
  pmg_lcm::vr_pose_t msg;
};

struct VrLogReadStats {
  std::uint64_t events = 0;          ///< events in the file
  std::uint64_t other_channels = 0;  ///< events of other channels (skipped)
  std::uint64_t rejected = 0;        ///< PMG_VR_POSE events that did not decode or failed the checks
  std::uint64_t time_reversals = 0;  ///< events whose timestamp is before the previous one (kept, no wait)
  std::string first_error;           ///< the first rejection, "event N: reason"
};

/// Reads every valid PMG_VR_POSE event of the LCM log @p path, in file order.
/// @throws std::runtime_error naming @p path if it cannot be opened or is not an LCM log.
std::vector<VrLogEvent> readVrLog(const std::string& path, VrLogReadStats* stats = nullptr);

struct VrReplayOptions {
  double speed = 1.0;  ///< time scale: 2 = twice as fast; (0, 100]
  bool loop = false;   ///< start over at the end (until stopped)
  /// @throws std::invalid_argument naming the field and range.
  void validate() const;
};

struct VrReplayStats {
  std::uint64_t published = 0;  ///< publish() returned true
  std::uint64_t failed = 0;     ///< publish() returned false
  std::uint64_t loops = 0;      ///< completed passes over the log
  double max_late_s = 0.0;      ///< largest delay of a publish behind its schedule [s]
};

/// Publishes @p events with their original spacing divided by options.speed, on the calling
/// thread, until the end (or forever with loop) or until @p stop becomes true (checked at least
/// every 50 ms). @p publish receives each message (loop offsets applied).
VrReplayStats replayVrLog(const std::vector<VrLogEvent>& events, const VrReplayOptions& options,
                          const std::function<bool(const pmg_lcm::vr_pose_t&)>& publish,
                          const std::atomic<bool>* stop = nullptr);

}  // namespace pmg::teleop
