#pragma once
/// @file bus_plan.hpp
/// @brief Which motor sits on which CAN bus, how long each frame occupies the wire, and when each
/// bus sends inside the HAL's 2 ms slot.
///
/// Frame times are bit-level worst cases (ISO 11898-1):
///  - classic CAN, 11-bit id, n payload bytes: 47 + 8n bits on the wire plus at most
///    floor((34 + 8n - 1) / 4) stuff bits (R. Davis et al., "Controller Area Network (CAN)
///    schedulability analysis: refuted, revisited and revised", Real-Time Systems 35, 2007, eq. 3;
///    the 47 include the 3-bit intermission). 8 bytes: 135 bits, 6 bytes: 115 bits, so a MIT
///    command + reply costs 0.206 ms without and 0.250 ms with worst-case stuffing at 1 Mbit/s.
///  - CAN FD, 11-bit id: arbitration phase (SOF, id, RRS, IDE, FDF, res, BRS = 17 bits) and the
///    tail (CRC delimiter, ACK, ACK delimiter, EOF, intermission = 13 bits) run at the nominal rate;
///    ESI, DLC, payload, stuff count (4), CRC (17 bits for <= 16 bytes, else 21) and its fixed stuff
///    bits (6, else 7) run at the data rate when BRS is set. Dynamic stuff bits over SOF..payload,
///    floor((17 + 5 + 8n - 1) / 4), are all charged at the nominal rate: a conservative upper bound.
///
/// Cycle model: each motor is served request-reply (command, driver turnaround, reply) one after
/// the other, so a bus is busy sum_k (t_cmd + t_turnaround + t_reply) per slot. Load is that over the
/// period; the plan is refused at start-up if any bus exceeds Options::max_load (80 %).

#include <cstddef>
#include <string>
#include <vector>

#include "pmg/hal/bus/motor_protocol.hpp"

namespace pmg {
struct RobotConfig;
}

namespace pmg::hal::bus {

/// Worst-case (full stuffing) bits of a classic CAN data frame with `payload` bytes (0..8).
std::size_t classicFrameBitsWorstCase(std::size_t payload, bool extended_id = false) noexcept;
/// Bits of a classic CAN data frame without stuff bits (best case).
std::size_t classicFrameBitsNoStuffing(std::size_t payload, bool extended_id = false) noexcept;
/// Worst-case duration [s] of a classic frame at `bitrate` [bit/s].
double classicFrameTime(std::size_t payload, double bitrate, bool extended_id = false) noexcept;
/// Worst-case duration [s] of an 11-bit-id CAN FD frame (payload padded to a legal FD length) with
/// nominal and data bit rates [bit/s]; `brs` false runs the whole frame at the nominal rate.
double fdFrameTime(std::size_t payload, double nominal_bitrate, double data_bitrate, bool brs) noexcept;

/// Bit timing of one bus.
struct BusTiming {
  double bitrate = 1e6;       ///< Nominal (arbitration) bit rate [bit/s].
  bool fd = false;            ///< Use CAN FD frames.
  double data_bitrate = 5e6;  ///< CAN FD data-phase bit rate [bit/s] (used when fd).
};

/// One physical bus (one SocketCAN interface, one UDP port pair, or one EtherCAT-CAN channel).
struct BusConfig {
  std::string name;             ///< Interface name, e.g. "can0".
  std::string protocol = "mit"; ///< Motor protocol on this bus (makeMotorProtocol name).
  BusTiming timing;
  std::vector<MotorSpec> motors;  ///< Served in this order inside the slot.
};

/// Cycle budget and checks.
struct BusPlanOptions {
  double period_s = 0.002;      ///< HAL period [s] (500 Hz).
  double max_load = 0.8;        ///< Refuse a bus whose load exceeds this fraction of the period.
  double turnaround_s = 20e-6;  ///< Driver reply latency after a command [s] (datasheet).
  int num_joints = 29;          ///< Every joint index 0..num_joints-1 must appear exactly once.
  /// Empty if valid, else message naming the field and range.
  std::string validate() const;
};

/// Per-bus time budget inside one slot.
struct BusLoad {
  double command_s = 0.0;    ///< Worst-case command frame time [s].
  double reply_s = 0.0;      ///< Worst-case reply frame time [s].
  double per_motor_s = 0.0;  ///< command + turnaround + reply [s].
  double busy_s = 0.0;       ///< per_motor_s * motors [s].
  double load = 0.0;         ///< Wire occupancy (command + reply frames) / period, 0..1+.
  std::size_t motors = 0;
};

/// When one motor's command goes out inside the slot, relative to the slot start.
struct SlotEntry {
  int motor = 0;             ///< Index into BusConfig::motors.
  double send_offset_s = 0;  ///< Command is queued at slot start + send_offset_s [s].
  double reply_due_s = 0;    ///< Reply expected by slot start + reply_due_s [s].
};

/// Result of checking a plan (no exceptions; used by benches and the CLI to show refused plans).
struct BusPlanCheck {
  bool ok = false;
  std::string message;          ///< Empty when ok, else every problem found, one per line.
  std::vector<BusLoad> loads;   ///< One per bus (filled even when not ok, when computable).
};

/// Compute loads and check a plan against the options. Never throws (except std::bad_alloc).
BusPlanCheck checkBusPlan(const std::vector<BusConfig>& buses, const BusPlanOptions& options);

/// Immutable, validated bus plan with its per-bus send schedule.
class BusPlan {
 public:
  /// Validate `buses` against `options`; throws std::invalid_argument with every problem found,
  /// prefixed by `source` (file name), e.g. "g1.yaml: bus 'can3': load 87.5 % > 80 %".
  BusPlan(std::vector<BusConfig> buses, BusPlanOptions options, const std::string& source = "bus plan");

  /// Load a plan from YAML (format in docs/hal.md, read with pmg::yaml). Throws pmg::ConfigError
  /// naming the file, line and field on any missing/invalid value or unknown key (with the nearest
  /// valid key), and std::invalid_argument with the load check's message if the budget is exceeded.
  static BusPlan fromYaml(const std::string& path);
  /// Parse YAML into configs without the load check (for tools that show refused plans).
  /// @throws pmg::ConfigError as fromYaml().
  static std::vector<BusConfig> parseYaml(const std::string& path, BusPlanOptions& options_out);

  const std::vector<BusConfig>& buses() const noexcept { return buses_; }
  const BusPlanOptions& options() const noexcept { return options_; }
  const std::vector<BusLoad>& loads() const noexcept { return loads_; }
  /// schedule()[b][k]: k-th send of bus b inside the slot, ordered by send_offset_s.
  const std::vector<std::vector<SlotEntry>>& schedule() const noexcept { return schedule_; }
  /// Total motor count over all buses.
  std::size_t motorCount() const noexcept;
  /// Fixed-width text table: bus, timing, motors, per-motor time, load.
  std::string report() const;

 private:
  std::vector<BusConfig> buses_;
  BusPlanOptions options_;
  std::vector<BusLoad> loads_;
  std::vector<std::vector<SlotEntry>> schedule_;
};

/// The robot config is the single source of truth for the wiring: checks that every motor of a
/// plan names a joint of `robot` with the same joint index, bus name and motor id, and that every
/// joint of `robot` appears exactly once. Called by makeCanBackend() when the setup names the robot.
/// @throws pmg::ConfigError naming both files, the joint and both values, e.g. "g1_can.yaml:
/// buses[1].motors[3]: joint 'right_knee_joint' is on bus can1 with motor_id 4, but g1.yaml says bus
/// can1 with motor_id 10".
void checkPlanAgainstRobot(const std::vector<BusConfig>& buses, const std::string& plan_file,
                           const pmg::RobotConfig& robot);

}  // namespace pmg::hal::bus
