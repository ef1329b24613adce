// The bad-input battery (issue 11, "Done when"): one table of malformed inputs, each built by
// mutating a valid shipped file or a valid encoded frame/packet, each with the outcome it must
// have:
//  - a named error: the loader throws, and what() names the file and the offending key/field;
//  - a counted rejection: a noexcept decoder refuses the input with a named status, and the
//    component's counter for it goes up.
// Never a crash, a hang (each case has kCaseTimeout), or a silent acceptance. A row marked `pending` names the owner of the
// fix that is not in yet: it runs, and is skipped (reported by name, with what happened) while it
// fails; once it passes it must be flipped to enforced (the skip message says so).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>
#include <system_error>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "temp_dir.hpp"

#include "pmg/calib/bench_log.hpp"
#include "pmg/calib/zero_calibration.hpp"
#include "pmg/calib/zero_io.hpp"
#if __has_include("pmg/clips/clip_io.hpp")
#include "pmg/clips/clip_io.hpp"
#else
#include "pmg/clips/clip_io.hpp"
#endif
#include "pmg/common/robot_config.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#if PMG_BAD_INPUT_HAVE_LCM_DECODER
#include "pmg/controller/lcm_command_source.hpp"
#endif
#include "pmg/gco/gco.hpp"
#include "pmg/hal/bus/bus_plan.hpp"
#include "pmg/hal/bus/imu_protocol.hpp"
#include "pmg/hal/bus/mit_protocol.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"
#include "pmg/hal/bus/udp_transport.hpp"
#include "pmg/policy/contract.hpp"
#include "pmg/policy/onnx_session.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "pmg_lcm/mode_command_t.hpp"
#include "pmg_lcm/posture_command_t.hpp"
#include "pmg_lcm/velocity_command_t.hpp"
#include "pmg_lcm/vr_pose_t.hpp"

namespace pmg::test {
namespace {

using hal::bus::CanFrame;

#if !PMG_BAD_INPUT_HAVE_LCM_DECODER
constexpr const char* kVelocityChannel = "PMG_VELOCITY_COMMAND";
constexpr const char* kPostureChannel = "PMG_POSTURE_COMMAND";
constexpr const char* kModeChannel = "PMG_MODE_COMMAND";
constexpr const char* kVrPoseChannel = "PMG_VR_POSE";
#endif

// ---------------------------------------------------------------------------------------------
// What is fed, and what must come out.

enum class Kind {
  kRobotConfig,       // loadRobotConfig
  kGcoOptions,        // gco::loadGcoOptionsFile
  kBusPlan,           // hal::bus::BusPlan::fromYaml
  kRig,               // calib::load_rig_config
  kBenchLogCsv,       // calib::load_bench_log (pmg CSV)
  kBenchLogJson,      // calib::load_bench_log (BAM JSON)
  kZeroProtocol,      // loadZeroProtocol
  kZeroResult,        // loadJointValues (pmg_calib_zero result file)
  kDynamicClip,       // readDynamicClip
  kStaticClip,        // readStaticClip
  kContract,          // policy::parseContract + checkContract (the pmg.contract metadata text)
  kOnnxModel,         // policy::PolicyRunner on the file
  kCommandScript,     // loadCommandScript
  kControllerConfig,  // loadControllerConfig
  kCanReply,          // MitProtocol::decodeReply (host side); input: a UDP-CAN datagram of the frame
  kCanCommand,        // MitProtocol::decodeCommand (driver side, pmg_sil); input: as above
  kMotorCommand,      // MitProtocol::encodeCommand (host side); input: q, qd, kp, kd, tau_ff as 5 doubles
  kImuFrame,          // decodeImu; input: as above
  kUdpDatagram,       // UdpCanTransport::receive on a real loopback socket
  kSilFrame,          // SilDriverEmulator (pmg_sil's motor drivers): a frame on bus 0; input: as kCanReply
  kLcmPacket,         // LcmCommandDecoder::decode; input: channel '\0' packet bytes
};

const char* kindName(Kind k) {
  switch (k) {
    case Kind::kRobotConfig: return "robot config";
    case Kind::kGcoOptions: return "GCO options";
    case Kind::kBusPlan: return "bus plan";
    case Kind::kRig: return "calibration rig";
    case Kind::kBenchLogCsv: return "bench log (csv)";
    case Kind::kBenchLogJson: return "bench log (json)";
    case Kind::kZeroProtocol: return "zero-calibration protocol";
    case Kind::kZeroResult: return "zero-calibration result";
    case Kind::kDynamicClip: return "dynamic clip";
    case Kind::kStaticClip: return "static clip";
    case Kind::kContract: return "policy contract";
    case Kind::kOnnxModel: return "ONNX model";
    case Kind::kCommandScript: return "command script";
    case Kind::kControllerConfig: return "controller config";
    case Kind::kCanReply: return "CAN reply";
    case Kind::kCanCommand: return "CAN command";
    case Kind::kMotorCommand: return "motor command (encode)";
    case Kind::kImuFrame: return "IMU frame";
    case Kind::kUdpDatagram: return "UDP datagram";
    case Kind::kSilFrame: return "SIL driver frame";
    case Kind::kLcmPacket: return "LCM packet";
  }
  return "?";
}

const char* fileExtension(Kind k) {
  switch (k) {
    case Kind::kBenchLogCsv: return ".csv";
    case Kind::kBenchLogJson: return ".json";
    case Kind::kOnnxModel: return ".onnx";
    default: return ".yaml";
  }
}

struct Expect {
  enum Type { kError, kRejection } type = kError;
  /// kError: substrings what() must contain besides the file name (key, field);
  /// kRejection: the name of the rejection (the decoder's status text).
  std::vector<std::string> needles;
};

Expect error(std::vector<std::string> needles = {}) { return {Expect::kError, std::move(needles)}; }
Expect rejected(std::string name) { return {Expect::kRejection, {std::move(name)}}; }

struct Case {
  const char* name;
  Kind kind;
  std::function<std::string()> input;  ///< the malformed bytes (file text, datagram, packet)
  Expect expect;
  const char* pending = nullptr;  ///< owner of the fix that is not in yet; nullptr = enforced
};

std::ostream& operator<<(std::ostream& os, const Case& c) { return os << c.name; }

// ---------------------------------------------------------------------------------------------
// Mutations of valid inputs.

std::string shipped(const std::string& relative) { return readTextFile(sourcePath(relative)); }

/// @p text with the first @p from replaced by @p to; the anchor must exist (a shipped file that
/// changed under a case fails loudly instead of testing nothing).
std::string sub(std::string text, const std::string& from, const std::string& to) {
  const std::size_t p = text.find(from);
  if (p == std::string::npos) throw std::logic_error("bad-input case: mutation anchor not found: '" + from + "'");
  return text.replace(p, from.size(), to);
}

/// Removes the first line that contains @p anchor.
std::string dropLine(std::string text, const std::string& anchor) {
  const std::size_t p = text.find(anchor);
  if (p == std::string::npos) throw std::logic_error("bad-input case: line anchor not found: '" + anchor + "'");
  const std::size_t b = text.rfind('\n', p);
  const std::size_t e = text.find('\n', p);
  const std::size_t from = b == std::string::npos ? 0 : b + 1;
  return text.erase(from, e == std::string::npos ? std::string::npos : e - from + 1);
}

std::string firstHalf(const std::string& text) { return text.substr(0, text.size() / 2); }

/// Deterministic binary garbage: NULs, 0xFF, invalid UTF-8, control characters, YAML indicators.
std::string garbage(std::size_t n = 512) {
  std::string s(n, '\0');
  std::uint32_t x = 0x9E3779B9u;
  for (std::size_t i = 0; i < n; ++i) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    s[i] = static_cast<char>(x & 0xFF);
  }
  s.replace(0, 6, std::string("\xFF\xFE\x00{[:", 6));
  return s;
}

/// The shipped robot config with absolute model paths (loads from any folder).
std::string robotText() { return g1RobotConfigText(); }

/// A shipped controller config with its `../` references made absolute.
std::string controllerText(const std::string& file) {
  const std::string dir = sourcePath("config/controller/");
  return std::regex_replace(shipped("config/controller/" + file), std::regex(R"((:\s*)\.\./)"), "$1" + dir + "../");
}

std::string zeroResultText() {
  return "zero_offsets:\n  left_knee_joint: 0.01\n  right_hip_roll_joint: -0.02\ncalibration: {converged: true}\n";
}

/// The contract (pmg.contract metadata) of the committed test model the runner tests use.
std::string contractText() {
  static const std::string text = [] {
    policy::OnnxSession s(policyTestDataDir() + "g1_legs_ok.onnx");
    std::string t;
    if (!s.metadata(policy::kContractMetadataKey, &t)) throw std::logic_error("g1_legs_ok.onnx has no contract");
    return t;
  }();
  return text;
}

policy::PolicyRobotSpec g1PolicySpec() {
  policy::PolicyRobotSpec s = policy::loadPolicyRobotSpec(g1RobotConfigPath(), 0.01);
  s.pmg = {{"enabled", "true"}, {"gco", "false"}, {"gait_period", "0.8"}};
  return s;
}

// --- frames ---------------------------------------------------------------------------------

const hal::bus::MotorSpec& leftHipPitchMotor() {
  static const hal::bus::BusPlan plan = hal::bus::BusPlan::fromYaml(g1CanPlanPath());
  return plan.buses()[0].motors[0];
}

std::string datagram(const CanFrame& f) {
  std::uint8_t buf[hal::bus::kUdpCanHeader + hal::bus::kCanFdMaxPayload];
  const std::size_t n = hal::bus::encodeUdpCan(f, buf);
  return std::string(reinterpret_cast<const char*>(buf), n);
}

CanFrame validReply() {
  CanFrame f;
  const auto& m = leftHipPitchMotor();
  hal::bus::MitProtocol::encodeReply(m, hal::bus::MotorFeedback{m.motor_id, 0.3, 1.0, -2.0}, f);
  return f;
}

CanFrame validCommand() {
  CanFrame f;
  const hal::bus::MitProtocol mit;
  if (!mit.encodeCommand(leftHipPitchMotor(), hal::bus::MotorCommand{0.1, 0.0, 50.0, 1.0, 0.0}, f))
    throw std::logic_error("valid command did not encode");
  return f;
}

CanFrame validImu() {
  ImuState s;
  s.quat_wxyz = {1.0, 0.0, 0.0, 0.0};
  s.gyro = {0.1, 0.2, 0.3};
  s.acc = {0.0, 0.0, 9.81};
  s.valid = true;
  CanFrame f;
  hal::bus::encodeImu(s, 7, f);
  return f;
}

template <class F>
std::function<std::string()> frame(CanFrame (*base)(), F mutate) {
  return [base, mutate] {
    CanFrame f = base();
    mutate(f);
    return datagram(f);
  };
}

/// A joint-side motor command (q, qd, kp, kd, tau_ff) as raw bytes.
std::function<std::string()> motorCommand(double q, double qd, double kp, double kd, double tau) {
  return [=] {
    const double v[5] = {q, qd, kp, kd, tau};
    return std::string(reinterpret_cast<const char*>(v), sizeof v);
  };
}

std::function<std::string()> imuWith(void (*mutate)(ImuState&)) {
  return [mutate] {
    ImuState s;
    s.quat_wxyz = {1.0, 0.0, 0.0, 0.0};
    s.gyro = {0.1, 0.2, 0.3};
    s.acc = {0.0, 0.0, 9.81};
    s.valid = true;
    mutate(s);
    CanFrame f;
    hal::bus::encodeImu(s, 8, f);
    return datagram(f);
  };
}

std::function<std::string()> rawDatagram(std::function<void(std::string&)> mutate) {
  return [mutate] {
    std::string d = datagram(validReply());
    mutate(d);
    return d;
  };
}

// --- LCM packets ----------------------------------------------------------------------------

template <class Msg>
std::string encoded(const Msg& msg) {
  const int n = msg.getEncodedSize();
  std::string buf(static_cast<std::size_t>(n), '\0');
  if (msg.encode(buf.data(), 0, n) != n) throw std::logic_error("lcm encode failed");
  return buf;
}

pmg_lcm::velocity_command_t velocityMsg() {
  pmg_lcm::velocity_command_t m{};
  m.utime = 1000;
  m.vx = 0.5;
  m.vy = 0.0;
  m.wz = 0.2;
  m.source = "gamepad";
  return m;
}

// posture_command_t gained `has_height` (explicit "no height command"); set it where it exists.
template <class M>
auto setHasHeight(M& m, int) -> decltype(m.has_height = 1, void()) {
  m.has_height = 1;
}
template <class M>
void setHasHeight(M&, long) {}

pmg_lcm::posture_command_t postureMsg() {
  pmg_lcm::posture_command_t m{};
  m.utime = 1000;
  m.pitch = 0.1;
  m.roll = 0.0;
  setHasHeight(m, 0);
  m.height = 0.7;
  m.source = "vr";
  return m;
}

pmg_lcm::mode_command_t modeMsg(int code) {
  pmg_lcm::mode_command_t m{};
  m.utime = 1000;
  m.mode = static_cast<std::int8_t>(code);
  m.source = "gamepad";
  return m;
}

pmg_lcm::vr_pose_t vrPoseMsg() {
  pmg_lcm::vr_pose_t m{};
  m.utime = 1000;
  m.frame = 7;
  m.head_position[2] = 1.6;
  m.head_quat[0] = 1.0;
  for (auto& q : m.hand_quat) q[0] = 1.0;
  m.source = "vr";
  return m;
}

/// channel '\0' bytes
std::string packet(const std::string& channel, const std::string& bytes) { return channel + std::string(1, '\0') + bytes; }

/// Overwrites the big-endian int32 length field of the trailing `source` string (@p source_size
/// bytes without its NUL) with @p value.
std::string withSourceLength(std::string bytes, std::size_t source_size, std::uint32_t value) {
  const std::size_t at = bytes.size() - source_size - 1 - 4;
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<char>((value >> (24 - 8 * i)) & 0xFF);
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// The table.

std::vector<Case> allCases() {
  const std::string kRobot = "config/robots/g1/g1.yaml";
  const std::string kGco = "config/gco/g1.yaml";
  const std::string kPlan = "config/hal/g1_can.yaml";
  const std::string kRig = "config/bench/bam_xl330.yaml";
  const std::string kLog = "test/data/calib/small_log.csv";
  const std::string kBam = "config/bench/data/bam_xl330/2026-01-15_10h28m17.json";
  const std::string kZero = "config/calib/zero_poses_g1.yaml";
  const std::string kWalk = "config/clips/g1/walk_forward.yaml";
  const std::string kSquat = "config/clips/g1/squat.yaml";
  const std::string kScript = "config/commands/demo.yaml";
  const std::string kEval = "config/policies/eval_commands.yaml";
  [[maybe_unused]] const char* const kYaml = "yaml_archive (typed configs)";
  [[maybe_unused]] const char* const kLead = "lead (controller)";
  [[maybe_unused]] const char* const kClips = "clips library";
  [[maybe_unused]] const char* const kCalib = "src/calib owner (bench_log.cpp)";
  const auto text = [](std::function<std::string()> f) { return f; };
  const auto robot = [](std::string from, std::string to) { return [from, to] { return sub(robotText(), from, to); }; };
  const auto file = [](std::string rel, std::string from, std::string to) {
    return [rel, from, to] { return sub(shipped(rel), from, to); };
  };
  const auto ctrl = [](std::string cfg, std::string from, std::string to) {
    return [cfg, from, to] { return sub(controllerText(cfg), from, to); };
  };
  const auto zres = [](std::string from, std::string to) { return [from, to] { return sub(zeroResultText(), from, to); }; };
  const auto contract = [](std::string from, std::string to) { return [from, to] { return sub(contractText(), from, to); }; };
  using hal::bus::kErrorBusOff;

  return {
      // --- robot config ------------------------------------------------------------------------
      {"robot_unknown_top_key", Kind::kRobotConfig, text([] { return robotText() + "hal_supervisr: true\n"; }),
       error({"hal_supervisr"})},
      {"robot_typo_joint_key", Kind::kRobotConfig, robot("kp: 150,", "kpp: 150,"), error({"kpp"})},
      {"robot_inf_velocity_limit", Kind::kRobotConfig, robot("velocity_limit: 32,", "velocity_limit: .inf,"),
       error({"velocity_limit"})},
      {"robot_nan_kd", Kind::kRobotConfig, robot("kd: 4,", "kd: .nan,"), error({"kd"})},
      {"robot_wrong_type_height", Kind::kRobotConfig,
       robot("standing_base_height: 0.78", "standing_base_height: [0.78]"), error({"standing_base_height"})},
      {"robot_missing_base_link", Kind::kRobotConfig, text([] { return dropLine(robotText(), "base_link: pelvis"); }),
       error({"base_link"})},
      {"robot_huge_motor_id", Kind::kRobotConfig, robot("motor_id: 1,", "motor_id: 99999999999,"), error({"motor_id"})},
      {"robot_duplicate_joint", Kind::kRobotConfig, robot("name: left_hip_roll_joint,", "name: left_hip_pitch_joint,"),
       error({"left_hip_pitch_joint"})},
      {"robot_negative_motor_id", Kind::kRobotConfig, robot("motor_id: 2,", "motor_id: -2,"), error({"motor_id"})},
      {"robot_truncated", Kind::kRobotConfig, text([] { return firstHalf(robotText()); }), error()},
      {"robot_binary_garbage", Kind::kRobotConfig, text([] { return garbage(); }), error()},
      {"robot_empty", Kind::kRobotConfig, text([] { return std::string(); }), error()},

      // --- GCO options ---------------------------------------------------------------------------
      {"gco_unknown_key", Kind::kGcoOptions, file(kGco, "w_limit: 100.0", "w_limitt: 100.0"), error({"w_limitt"})},
      {"gco_inf_limit", Kind::kGcoOptions, file(kGco, "v_x_max: 1.5", "v_x_max: .inf"), error({"v_x_max"})},
      {"gco_nan_dt", Kind::kGcoOptions, file(kGco, "dt: 0.01", "dt: .nan"), error({"dt"})},
      {"gco_negative_iterations", Kind::kGcoOptions, file(kGco, "max_iterations: 20", "max_iterations: -5"),
       error({"max_iterations"})},
      {"gco_wrong_type_enabled", Kind::kGcoOptions, file(kGco, "enabled: true", "enabled: maybe"), error({"enabled"})},
      {"gco_empty", Kind::kGcoOptions, text([] { return std::string(); }), error({"gco"})},

      // --- bus plans (config/hal) ----------------------------------------------------------------
      {"bus_unknown_key", Kind::kBusPlan, file(kPlan, "period_s: 0.002", "period_s: 0.002\nperiod_ss: 0.004"),
       error({"period_ss"})},
      {"bus_negative_period", Kind::kBusPlan, file(kPlan, "period_s: 0.002", "period_s: -0.002"), error({"period_s"})},
      {"bus_inf_turnaround", Kind::kBusPlan, file(kPlan, "turnaround_s: 20.0e-6", "turnaround_s: .inf"),
       error({"turnaround_s"})},
      {"bus_unknown_motor_type", Kind::kBusPlan, file(kPlan, "type: m88, joint_range", "type: m999, joint_range"),
       error({"m999"})},
      {"bus_motor_id_out_of_range", Kind::kBusPlan,
       file(kPlan, "motor_id: 1, command_can_id: 1", "motor_id: 300, command_can_id: 1"), error({"motor_id"})},
      {"bus_can_id_over_11_bits", Kind::kBusPlan, file(kPlan, "command_can_id: 1,", "command_can_id: 4096,"),
       error({"command_can_id"})},
      {"bus_unknown_protocol", Kind::kBusPlan, file(kPlan, "protocol: mit", "protocol: mitt"), error({"protocol"})},
      {"bus_nan_codec_range", Kind::kBusPlan, file(kPlan, "q_min: -12.5, q_max: 12.5, qd_min: -30.0",
                                                   "q_min: .nan, q_max: 12.5, qd_min: -30.0"),
       error({"q_min"})},
      {"bus_duplicate_motor_id", Kind::kBusPlan,
       file(kPlan, "motor_id: 2, command_can_id: 2", "motor_id: 1, command_can_id: 2"), error({"motor_id"})},
      {"bus_truncated", Kind::kBusPlan, text([] { return firstHalf(shipped("config/hal/g1_can.yaml")); }), error()},

      // --- calibration rigs (config/bench) -------------------------------------------------------
      {"rig_unknown_key", Kind::kRig, file(kRig, "mass_kg: 0.49", "mass_kgg: 0.49"), error({"mass_kgg"})},
      {"rig_inf_torque_limit", Kind::kRig, file(kRig, "torque_limit_Nm: 0.77", "torque_limit_Nm: .inf"),
       error({"torque_limit_Nm"})},
      {"rig_negative_mass", Kind::kRig, file(kRig, "mass_kg: 0.49", "mass_kg: -0.49"), error({"mass_kg"})},
      {"rig_unknown_type", Kind::kRig, file(kRig, "type: pendulum", "type: pendulm"), error({"type"})},
      {"rig_nan_dt", Kind::kRig, file(kRig, "dt_s: 0.002", "dt_s: .nan"), error({"dt_s"})},
      {"rig_empty", Kind::kRig, text([] { return std::string(); }), error()},

      // --- calibration logs (src/calib/bench_log) ------------------------------------------------
      {"log_nan_position", Kind::kBenchLogCsv, file(kLog, "0.01,0.1,0.002", "0.01,0.1,nan"), error({"q"})},
      {"log_truncated_row", Kind::kBenchLogCsv, file(kLog, "0.03,0.2,0.020,0.8,4,0.1,0", "0.03,0.2,0.0"), error()},
      {"log_unknown_column", Kind::kBenchLogCsv, file(kLog, "t,q_cmd,q,dq,", "t,q_cmd,q,dqq,"), error({"dqq"})},
      {"log_inf_time", Kind::kBenchLogCsv, file(kLog, "0.02,0.2,0.010", "1e400,0.2,0.010"), error({"t"})},
      {"log_empty", Kind::kBenchLogCsv, text([] { return std::string(); }), error()},
      {"log_binary_garbage", Kind::kBenchLogCsv, text([] { return garbage(); }), error()},
      {"log_json_no_entries", Kind::kBenchLogJson, text([kBam] {
         const std::string t = shipped(kBam);
         return t.substr(0, t.find("\"entries\": [")) + "\"entries\": []}";
       }),
       error({"entries"})},
      {"log_json_truncated", Kind::kBenchLogJson, text([kBam] { return firstHalf(shipped(kBam)); }), error()},
      {"log_json_wrong_type", Kind::kBenchLogJson, file(kBam, "\"position\": -0.01380582709097089",
                                                        "\"position\": \"abc\""),
       error({"position"})},

      // --- zero-calibration protocol and result files --------------------------------------------
      {"zero_unknown_key", Kind::kZeroProtocol, file(kZero, "hold_s: 2.0", "hold_ss: 2.0"), error({"hold_ss"})},
      {"zero_inf_move", Kind::kZeroProtocol, file(kZero, "move_s: 1.5", "move_s: .inf"), error({"move_s"})},
      {"zero_nan_gyro_rms", Kind::kZeroProtocol, file(kZero, "max_gyro_rms: 0.02", "max_gyro_rms: .nan"),
       error({"max_gyro_rms"})},
      {"zero_short_leg_kp", Kind::kZeroProtocol,
       file(kZero, "leg_kp: [400, 400, 400, 500, 400, 400]", "leg_kp: [400, 400]"), error({"leg_kp"})},
      {"zero_no_poses", Kind::kZeroProtocol, text([kZero] {
         const std::string t = shipped(kZero);
         return t.substr(0, t.find("  poses:")) + "  poses: []\n";
       }),
       error({"poses"})},
      {"zero_empty", Kind::kZeroProtocol, text([] { return std::string(); }), error()},
      {"zres_unknown_joint", Kind::kZeroResult, zres("left_knee_joint", "left_knee_jiont"), error({"left_knee_jiont"})},
      {"zres_nan_offset", Kind::kZeroResult, zres("0.01", ".nan"), error({"left_knee_joint"})},
      {"zres_offset_too_large", Kind::kZeroResult, zres("0.01", "0.9"), error({"left_knee_joint"})},
      {"zres_unknown_top_key", Kind::kZeroResult, zres("zero_offsets:", "zero_ofsets:"), error({"zero_ofsets"})},
      {"zres_binary_garbage", Kind::kZeroResult, text([] { return garbage(); }), error()},

      // --- clips -----------------------------------------------------------------------------------
      {"clip_unknown_key", Kind::kDynamicClip, file(kWalk, "nominal_scale:", "nominal_scal:"), error({"nominal_scal"})},
      {"clip_nan_period", Kind::kDynamicClip, file(kWalk, "period: 1.266616", "period: .nan"), error({"period"})},
      {"clip_negative_samples", Kind::kDynamicClip, file(kWalk, "num_samples: 96", "num_samples: -96"),
       error({"num_samples"})},
      {"clip_unknown_joint", Kind::kDynamicClip, file(kWalk, "[left_hip_pitch_joint,", "[left_hip_pich_joint,"),
       error({"left_hip_pich_joint"})},
      {"clip_inf_contact", Kind::kDynamicClip, file(kWalk, "mu: 0.234375", "mu: .inf"), error({"mu"})},
      {"clip_short_row", Kind::kDynamicClip, file(kWalk, "  - [-0.459786, ", "  - ["), error({"q"})},
      {"clip_truncated", Kind::kDynamicClip, text([kWalk] { return firstHalf(shipped(kWalk)); }), error()},
      {"clip_static_unknown_axis", Kind::kStaticClip, file(kSquat, "axis: height", "axis: heigth"), error({"axis"})},
      {"clip_static_huge_value", Kind::kStaticClip, file(kSquat, "values: [0.423704", "values: [1e300"),
       error({"values"})},
      {"clip_empty", Kind::kDynamicClip, text([] { return std::string(); }), error()},

      // --- ONNX policy contracts -------------------------------------------------------------------
      {"contract_unknown_key", Kind::kContract, contract("controls_waist: false", "controls_waistt: false"),
       error({"controls_waistt"})},
      {"contract_nan_action_scale", Kind::kContract, contract("scale: [0.25,", "scale: [.nan,"), error({"scale"})},
      {"contract_inf_action_clip", Kind::kContract, contract("clip: 10.0", "clip: .inf"), error({"clip"})},
      {"contract_negative_term_size", Kind::kContract, contract("{name: base_ang_vel_B, size: 3,", "{name: base_ang_vel_B, size: -3,"),
       error({"size"})},
      {"contract_wrong_version", Kind::kContract, contract("version: 1", "version: 99"), error({"version"})},
      {"contract_wrong_type_period", Kind::kContract, contract("control_period: 0.01", "control_period: fast"),
       error({"control_period"})},
      {"contract_huge_history", Kind::kContract, contract("history_length: 1", "history_length: 2147483647"),
       error({"history_length"})},
      {"contract_truncated", Kind::kContract, text([] { return firstHalf(contractText()); }), error()},
      {"onnx_empty_file", Kind::kOnnxModel, text([] { return std::string(); }), error()},
      {"onnx_truncated", Kind::kOnnxModel,
       text([] { return firstHalf(readTextFile(policyTestDataDir() + "g1_legs_ok.onnx")); }), error()},
      {"onnx_binary_garbage", Kind::kOnnxModel, text([] { return garbage(4096); }), error()},

      // --- command scripts -------------------------------------------------------------------------
      {"script_typo_vxx", Kind::kCommandScript, file(kScript, "vx: 0.5}", "vxx: 0.5}"), error({"vxx"})},
      {"script_nan_duration", Kind::kCommandScript, file(kScript, "duration: 3.0, vx", "duration: .nan, vx"),
       error({"duration"})},
      {"script_negative_duration", Kind::kCommandScript, file(kScript, "duration: 2.0}", "duration: -2.0}"),
       error({"duration"})},
      {"script_inf_wz", Kind::kCommandScript, file(kScript, "wz: 0.5}", "wz: .inf}"), error({"wz"})},
      {"script_wrong_type_segments", Kind::kCommandScript, text([] { return std::string("segments: 5\n"); }),
       error({"segments"})},
      {"script_eval_unknown_key", Kind::kCommandScript, file(kEval, "ramp:", "rampp:"), error({"rampp"})},
      {"script_huge_duration", Kind::kCommandScript, file(kScript, "duration: 3.0, vx", "duration: 1e300, vx"),
       error({"duration"})},
      {"script_empty", Kind::kCommandScript, text([] { return std::string(); }), error()},

      // --- controller configs ----------------------------------------------------------------------
      {"ctrl_hal_supervisr", Kind::kControllerConfig, ctrl("g1_sil.yaml", "soft_stand_duration_s: 1.0", "soft_stand_duration_s: 1.0\n  hal_supervisr: true"),
       error({"hal_supervisr"})},
      {"ctrl_q_rate_max_zero", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "soft_stand_duration_s: 1.0", "soft_stand_duration_s: 1.0\n  q_rate_max: 0"), error({"q_rate_max"})},
      {"ctrl_q_rate_max_nan", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "soft_stand_duration_s: 1.0", "soft_stand_duration_s: 1.0\n  q_rate_max: .nan"), error({"q_rate_max"})},
      {"ctrl_q_rate_max_huge", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "soft_stand_duration_s: 1.0", "soft_stand_duration_s: 1.0\n  q_rate_max: 1e6"), error({"q_rate_max"})},
      {"ctrl_policyy", Kind::kControllerConfig, ctrl("g1_sil_policy.yaml", "\npolicy:", "\npolicyy:"),
       error({"policyy"})},
      {"ctrl_inf_max_velocity", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "max_velocity: [1.0, 0.5, 1.0]", "max_velocity: [.inf, 0.5, 1.0]"),
       error({"max_velocity"})},
      {"ctrl_nan_timestep", Kind::kControllerConfig, ctrl("g1_sil.yaml", "timestep: 0.001", "timestep: .nan"),
       error({"timestep"})},
      {"ctrl_mujoco_joint_stops_below_two_timesteps", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "timestep: 0.001", "timestep: 0.001\n  joint_stops: {timeconst: 0.0015}"),
       error({"mujoco", "joint_stops.timeconst", "2 timestep"})},
      {"ctrl_mujoco_joint_stops_nan_dampratio", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "timestep: 0.001", "timestep: 0.001\n  joint_stops: {timeconst: 0.004, dampratio: .nan}"),
       error({"mujoco", "joint_stops.dampratio", "finite"})},
      {"ctrl_mujoco_joint_stops_dampratio_above_10", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "timestep: 0.001", "timestep: 0.001\n  joint_stops: {timeconst: 0.004, dampratio: 20}"),
       error({"mujoco", "joint_stops.dampratio", "(0, 10]"})},
      {"ctrl_mujoco_sliding_friction_below_0_1", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "sliding_friction: 0 ", "sliding_friction: 0.05 "),
       error({"mujoco", "sliding_friction", "[0.1, 2]"})},
      {"ctrl_mujoco_joint_stops_typo_key", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "timestep: 0.001", "timestep: 0.001\n  joint_stops: {time_const: 0.004}"),
       error({"time_const"})},
      {"ctrl_unknown_backend", Kind::kControllerConfig, ctrl("g1_sil.yaml", "backend: mujoco", "backend: mujoko"),
       error({"backend"})},
      {"ctrl_negative_loop_rate", Kind::kControllerConfig, ctrl("g1_sil.yaml", "loop_rate_hz: 100", "loop_rate_hz: -100"),
       error({"loop_rate_hz"})},
      {"ctrl_missing_robot", Kind::kControllerConfig,
       text([] { return dropLine(controllerText("g1_sil.yaml"), "robot: "); }), error({"robot"})},
      {"ctrl_binary_garbage", Kind::kControllerConfig, text([] { return garbage(); }), error()},
      {"ctrl_security_key_fil", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "security:\n  key_fil: robot.key\n"; }), error({"key_fil"})},
      {"ctrl_security_missing_key_file", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "security:\n  key_file: /nonexistent/pmg/robot.key\n"; }),
       error({"security", "/nonexistent/pmg/robot.key", "cannot open"})},
      {"ctrl_security_max_senders_0", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "security:\n  max_senders: 0\n"; }), error({"max_senders"})},
      {"ctrl_security_nan_max_age", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "security:\n  max_message_age_s: .nan\n"; }),
       error({"max_message_age_s"})},
      {"ctrl_velocity_feedback_typo_key", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  enabled: true\n  gain: 1.0\n"; }),
       error({"gain"})},
      {"ctrl_velocity_feedback_negative_ki", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  ki: [1.0, -1.0, 1.0]\n"; }),
       error({"velocity_feedback", "ki[1]", "0..20"})},
      {"ctrl_velocity_feedback_ratio_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  max_ratio: 3.0\n"; }),
       error({"velocity_feedback", "max_ratio", "0..2"})},
      {"ctrl_velocity_feedback_brake_ratio_one", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  brake_ratio: 1.0\n"; }),
       error({"velocity_feedback", "brake_ratio", "[0, 1)"})},
      {"ctrl_velocity_feedback_brake_decel_above_rate", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  brake_decel: 2.0\n  brake_rate: 1.0\n"; }),
       error({"velocity_feedback", "brake_decel", "brake_rate"})},
      {"ctrl_velocity_feedback_brake_crouch_scaled_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  brake_crouch_scaled: 1.5\n"; }),
       error({"brake_crouch_scaled"})},
      {"ctrl_velocity_feedback_upset_guard_upright_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  upset_guard: {enabled: true, upright: 2}\n"; }),
       error({"upset_guard", "upright"})},
      {"ctrl_feedforward_crouch_gain_out_of_range", Kind::kControllerConfig,
       text([] {
         return controllerText("g1_sil.yaml") +
                "velocity_feedback:\n  feedforward:\n    vx: {gain_negative: 0.84, gain_negative_per_crouch: 12.0}\n";
       }),
       error({"velocity_feedback", "feedforward.vx.gain_negative_per_crouch", "-10..10"})},
      {"ctrl_velocity_feedback_restart_median_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  restart_median: yes please\n"; }),
       error({"velocity_feedback", "restart_median"})},
      {"ctrl_velocity_feedback_decay_feedforward_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  decay_feedforward: 2\n"; }),
       error({"velocity_feedback", "decay_feedforward"})},
      {"ctrl_velocity_feedback_combined_max_correction_ratio_out_of_range", Kind::kControllerConfig,
       text([] {
         return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward:\n    combined_max_correction_ratio: 1.5\n";
       }),
       error({"velocity_feedback", "feedforward.combined_max_correction_ratio", "0..1"})},
      {"ctrl_velocity_feedback_feedforward_return_s_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward_return_s: 60\n"; }),
       error({"velocity_feedback", "feedforward_return_s"})},
      {"ctrl_velocity_feedback_brake_crouch_scaled_without_crouched_envelope", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  brake_ratio: 0.8\n  brake_crouch_scaled: true\n"; }),
       error({"velocity_feedback", "brake_crouch_scaled", "crouched_height"})},
      {"ctrl_velocity_feedback_feedforward_gain_out_of_range", Kind::kControllerConfig,
       text([] {
         return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward:\n    vy: {gain_positive: 5.0}\n";
       }),
       error({"velocity_feedback", "feedforward.vy.gain_positive", "0.3..3"})},
      {"ctrl_velocity_feedback_feedforward_own_drift", Kind::kControllerConfig,
       text([] {
         return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward:\n    wz: {drift: [0.1, 0.0, 0.2]}\n";
       }),
       error({"velocity_feedback", "feedforward.wz.drift[2]", "the axis itself"})},
      {"ctrl_velocity_feedback_feedforward_nan_correction", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward:\n    max_correction: [0.3, .nan, 0.4]\n"; }),
       error({"feedforward.max_correction[1]", "finite"})},
      {"ctrl_velocity_feedback_feedforward_typo_key", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  feedforward:\n    vx: {gain: 1.0}\n"; }),
       error({"gain"})},
      {"ctrl_upset_guard_without_velocity_feedback", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  upset_guard: {enabled: true}\n"; }),
       error({"velocity_feedback", "upset_guard.enabled", "needs velocity_feedback.enabled"})},
      {"ctrl_upset_guard_trigger_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  enabled: true\n  upset_guard: {trigger_s: 0}\n"; }),
       error({"velocity_feedback", "upset_guard.trigger_s", "(0, 5]"})},
      {"ctrl_velocity_feedback_within_posture_envelopes_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  within_posture_envelopes: 0.5\n"; }),
       error({"within_posture_envelopes"})},
      {"ctrl_velocity_feedback_yaw_beyond_envelopes_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  yaw_beyond_envelopes: yes please\n"; }),
       error({"yaw_beyond_envelopes"})},
      {"ctrl_velocity_feedback_headroom_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  max_velocity_headroom: [0, 0, 1.5]\n"; }),
       error({"velocity_feedback", "max_velocity_headroom[2]", "0..1"})},
      {"ctrl_velocity_feedback_small_command_bound_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  small_command_bound: [0.6, 0, 0]\n"; }),
       error({"velocity_feedback", "small_command_bound[0]", "0..0.5"})},
      {"ctrl_velocity_feedback_headroom_negative", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  max_velocity_headroom: [-0.1, 0, 0]\n"; }),
       error({"velocity_feedback", "max_velocity_headroom[0]", "0..1"})},
      {"ctrl_upset_guard_typo_key", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  upset_guard: {trigger: 0.5}\n"; }),
       error({"trigger"})},
      {"ctrl_velocity_feedback_nan_band", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  stance_band_m: .nan\n"; }),
       error({"stance_band_m"})},
      {"ctrl_posture_feedback_correction_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  max_correction_rad: 0.5\n"; }),
       error({"posture_feedback", "max_correction_rad", "0..0.3"})},
      {"ctrl_commands_crouched_velocity_above_max", Kind::kControllerConfig,
       text([] {
         return sub(controllerText("g1_sil_policy.yaml"), "crouched_max_velocity: [1.0, 0.4, 0.8]",
                    "crouched_max_velocity: [2.0, 0.4, 0.8]");
       }),
       error({"commands", "crouched_max_velocity", "(0, max_velocity]"})},
      {"ctrl_commands_bent_pitch_beyond_pitch_range", Kind::kControllerConfig,
       text([] {
         return sub(controllerText("g1_sil_policy.yaml"), "bent_pitch: 0.4 ", "bent_pitch: 0.9 ");
       }),
       error({"commands", "bent_pitch", "pitch_range max"})},
      {"ctrl_posture_feedback_envelope_max_negative", Kind::kControllerConfig,
       text([] {
         return sub(controllerText("g1_sil_policy.yaml"), "envelope_max: [0.5, 0.2]", "envelope_max: [-0.1, 0.2]");
       }),
       error({"posture_feedback", "envelope_min/envelope_max[0] (pitch)", "-1.5 <= min <= 0 <= max <= 1.5"})},
      {"ctrl_posture_feedback_envelope_min_not_a_pair", Kind::kControllerConfig,
       text([] {
         return sub(controllerText("g1_sil_policy.yaml"), "envelope_min: [-0.3, -0.2]", "envelope_min: [-0.3]");
       }),
       error({"posture_feedback", "envelope_min"})},
      {"ctrl_generator_cadence_ratio_out_of_range", Kind::kControllerConfig,
       text([] { return sub(controllerText("g1_sil.yaml"), "generator:\n", "generator:\n  max_cadence_ratio: 2.5\n"); }),
       error({"generator", "max_cadence_ratio", "[1, 2]"})},
      {"ctrl_posture_feedback_walking_ki_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_ki: [0.5, 6.0]\n"; }),
       error({"posture_feedback", "walking_ki[1]", "0..5"})},
      {"ctrl_posture_feedback_walking_min_command_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_min_command_rad: -0.1\n"; }),
       error({"posture_feedback", "walking_min_command_rad", "0..0.5"})},
      {"ctrl_posture_feedback_walking_height_ki_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_height_ki: 6\n"; }),
       error({"posture_feedback", "walking_height_ki", "0..5"})},
      {"ctrl_posture_feedback_walking_max_height_correction_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_max_height_correction_m: 0.2\n"; }),
       error({"posture_feedback", "walking_max_height_correction_m", "0..0.1"})},
      {"ctrl_posture_feedback_walking_below_floor_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_below_floor_m: 0.08\n"; }),
       error({"posture_feedback", "walking_below_floor_m", "0..0.05"})},
      {"ctrl_posture_feedback_walking_deadband", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_deadband_rad: 0.5\n"; }),
       error({"posture_feedback", "walking_deadband_rad", "0..0.3"})},
      {"ctrl_posture_feedback_still_measured_velocity_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  still_measured_velocity: 3\n"; }),
       error({"posture_feedback", "still_measured_velocity", "0..2"})},
      {"ctrl_posture_feedback_settle_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  settle_s: 6\n"; }),
       error({"posture_feedback", "settle_s", "0..5"})},
      {"ctrl_posture_feedback_stop_settle_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  stop_settle_s: -1\n"; }),
       error({"posture_feedback", "stop_settle_s", "0..5"})},
      {"ctrl_posture_feedback_walking_filter_time_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_filter_time_s: 7\n"; }),
       error({"posture_feedback", "walking_filter_time_s", "0..5"})},
      {"ctrl_posture_feedback_walking_velocity_settle_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_velocity_settle_s: 6\n"; }),
       error({"posture_feedback", "walking_velocity_settle_s", "0..5"})},
      {"ctrl_commands_crouched_per_axis_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "commands:\n  crouched_per_axis: sometimes\n"; }),
       error({"commands", "crouched_per_axis"})},
      {"ctrl_posture_feedback_overshoot_release_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  overshoot_release: maybe\n"; }),
       error({"posture_feedback", "overshoot_release"})},
      {"ctrl_velocity_feedback_stance_foot_nearest_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  stance_foot_nearest: maybe\n"; }),
       error({"velocity_feedback", "stance_foot_nearest"})},
      {"ctrl_timing_imu_acc_lowpass_below_a_hal_cycle", Kind::kControllerConfig,
       ctrl("g1_sil.yaml", "  loop_rate_hz: 100\n", "  loop_rate_hz: 100\n  imu_acc_lowpass_s: 0.001\n"),
       error({"timing", "imu_acc_lowpass_s", "1 / hal_rate_hz, 0.1"})},
      {"ctrl_velocity_feedback_headroom_in_envelopes_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "velocity_feedback:\n  headroom_in_envelopes: maybe\n"; }),
       error({"velocity_feedback", "headroom_in_envelopes"})},
      {"ctrl_posture_feedback_walking_crouch_release_not_a_bool", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_crouch_release: 2\n"; }),
       error({"posture_feedback", "walking_crouch_release"})},
      {"ctrl_posture_feedback_walking_crouch_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  walking_crouch_m: 0.3\n"; }),
       error({"posture_feedback", "walking_crouch_m", "0..0.2"})},
      {"ctrl_posture_feedback_height_ki_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  height_ki: 25\n"; }),
       error({"posture_feedback", "height_ki", "0..20"})},
      {"ctrl_posture_feedback_height_correction_out_of_range", Kind::kControllerConfig,
       text([] { return controllerText("g1_sil.yaml") + "posture_feedback:\n  max_height_correction_m: 0.2\n"; }),
       error({"posture_feedback", "max_height_correction_m", "0..0.1"})},
      {"ctrl_teleop_typo_key", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "grip_threshold: 0.6", "grip_treshold: 0.6"), error({"grip_treshold"})},
      {"ctrl_teleop_grip_out_of_range", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "grip_threshold: 0.6", "grip_threshold: 1.6"), error({"teleop.grip_threshold", "0.2..0.95"})},
      {"ctrl_teleop_gain_count", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "velocity_gain: [1.5, 1.5, 1.5]", "velocity_gain: [1.5, 1.5]"), error({"velocity_gain"})},
      {"ctrl_teleop_nan_arm_scale", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "arm_scale: 0.7", "arm_scale: .nan"), error({"arm_scale"})},
      {"ctrl_teleop_unknown_orientation", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "arm_scale: 0.7", "arm_scale: 0.7\n  orientation: sideways"), error({"sideways"})},
      {"ctrl_teleop_ik_typo", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "arm_scale: 0.7", "arm_scale: 0.7\n  ik: {max_iteration: 8}"), error({"max_iteration"})},
      {"ctrl_teleop_ik_negative_step", Kind::kControllerConfig,
       ctrl("g1_sil_teleop.yaml", "arm_scale: 0.7", "arm_scale: 0.7\n  ik: {max_joint_step: -0.1}"), error({"max_joint_step"})},

      // --- CAN frames (MIT protocol) ---------------------------------------------------------------
      {"can_reply_truncated", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.len = 5; }),
       rejected("wrong payload length")},
      {"can_reply_oversized", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.len = 8; }),
       rejected("wrong payload length")},
      {"can_reply_wrong_motor_id", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.data[0] = 7; }),
       rejected("wrong motor id")},
      {"can_reply_wrong_can_id", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.id = 0x123; }),
       rejected("wrong arbitration id")},
      {"can_reply_fd_frame", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.fd = true; }),
       rejected("not a data frame of this protocol")},
      {"can_reply_error_frame", Kind::kCanReply, frame(validReply, [](CanFrame& f) { f.error = true; f.id = kErrorBusOff; }),
       rejected("not a data frame of this protocol")},
      {"can_reply_position_at_codec_limit", Kind::kCanReply,
       frame(validReply, [](CanFrame& f) { f.data[1] = 0xFF; f.data[2] = 0xFF; }),
       rejected("value outside plausibility window")},
      {"can_command_truncated", Kind::kCanCommand, frame(validCommand, [](CanFrame& f) { f.len = 7; }),
       rejected("not a command")},
      {"can_command_fd_frame", Kind::kCanCommand, frame(validCommand, [](CanFrame& f) { f.fd = true; }),
       rejected("not a command")},
      {"can_command_error_frame", Kind::kCanCommand,
       frame(validCommand, [](CanFrame& f) { f.error = true; f.id = hal::bus::kErrorProtocol; }), rejected("not a command")},
      {"can_command_empty", Kind::kCanCommand, frame(validCommand, [](CanFrame& f) { f.len = 0; }), rejected("not a command")},
      {"motor_command_nan_position", Kind::kMotorCommand,
       motorCommand(std::numeric_limits<double>::quiet_NaN(), 0.0, 50.0, 1.0, 0.0), rejected("not encoded")},
      {"motor_command_inf_stiffness", Kind::kMotorCommand,
       motorCommand(0.1, 0.0, std::numeric_limits<double>::infinity(), 1.0, 0.0), rejected("not encoded")},
      {"motor_command_minus_inf_torque", Kind::kMotorCommand,
       motorCommand(0.1, 0.0, 50.0, 1.0, -std::numeric_limits<double>::infinity()), rejected("not encoded")},
      {"imu_nan_gyro", Kind::kImuFrame, imuWith([](ImuState& s) { s.gyro[1] = std::numeric_limits<double>::quiet_NaN(); }),
       rejected("not an IMU sample")},
      {"imu_inf_acc", Kind::kImuFrame, imuWith([](ImuState& s) { s.acc[2] = std::numeric_limits<double>::infinity(); }),
       rejected("not an IMU sample")},
      {"imu_truncated", Kind::kImuFrame, frame(validImu, [](CanFrame& f) { f.len = 32; }), rejected("not an IMU sample")},
      {"imu_wrong_id", Kind::kImuFrame, frame(validImu, [](CanFrame& f) { f.id = 0x0F1; }), rejected("not an IMU sample")},

      // --- UDP datagrams (CAN over UDP, pmg_sil) ---------------------------------------------------
      {"udp_empty", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d.clear(); }), rejected("rx_errors")},
      {"udp_truncated_header", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d.resize(6); }), rejected("rx_errors")},
      {"udp_truncated_payload", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d.pop_back(); }), rejected("rx_errors")},
      {"udp_padded_oversized", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d.append(60000, '\x55'); }),
       rejected("rx_errors")},
      {"udp_bad_magic", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[0] = 'X'; }), rejected("rx_errors")},
      {"udp_bad_version", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[2] = 9; }), rejected("rx_errors")},
      {"udp_unknown_flags", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[3] = static_cast<char>(0x80); }),
       rejected("rx_errors")},
      {"udp_nonzero_reserved", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[6] = 1; }), rejected("rx_errors")},
      {"udp_classic_length_9", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[4] = 9; d.append(3, '\0'); }),
       rejected("rx_errors")},
      {"udp_fd_length_13", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[3] = 1; d[4] = 13; d.append(7, '\0'); }),
       rejected("rx_errors")},
      {"udp_id_over_11_bits", Kind::kUdpDatagram, rawDatagram([](std::string& d) { d[9] = 0x10; }), rejected("rx_errors")},
      {"udp_binary_garbage", Kind::kUdpDatagram, text([] { return garbage(70); }), rejected("rx_errors")},

      // --- frames the SIL motor-driver emulator (pmg_sil) receives -------------------------------
      {"sil_unknown_can_id", Kind::kSilFrame, frame(validCommand, [](CanFrame& f) { f.id = 0x7F0; }), rejected("rejected")},
      {"sil_extended_id", Kind::kSilFrame, frame(validCommand, [](CanFrame& f) { f.extended = true; }), rejected("rejected")},
      {"sil_truncated_command", Kind::kSilFrame, frame(validCommand, [](CanFrame& f) { f.len = 5; }), rejected("rejected")},
      {"sil_fd_command", Kind::kSilFrame, frame(validCommand, [](CanFrame& f) { f.fd = true; }), rejected("rejected")},

      // --- LCM command packets ---------------------------------------------------------------------
      {"lcm_source_length_0", Kind::kLcmPacket,
       text([] { return packet(kVelocityChannel, withSourceLength(encoded(velocityMsg()), 7, 0)); }), rejected("bad string")},
      {"lcm_source_length_minus_1", Kind::kLcmPacket,
       text([] { return packet(kPostureChannel, withSourceLength(encoded(postureMsg()), 2, 0xFFFFFFFFu)); }),
       rejected("bad string")},
      {"lcm_source_length_2pow31", Kind::kLcmPacket,
       text([] { return packet(kModeChannel, withSourceLength(encoded(modeMsg(2)), 7, 0x80000000u)); }),
       rejected("bad string")},
      {"lcm_source_length_beyond_packet", Kind::kLcmPacket,
       text([] { return packet(kVelocityChannel, withSourceLength(encoded(velocityMsg()), 7, 9)); }),
       rejected("bad string|truncated")},
      {"lcm_truncated", Kind::kLcmPacket,
       text([] { std::string b = encoded(velocityMsg()); b.resize(b.size() - 12); return packet(kVelocityChannel, b); }),
       rejected("truncated")},
      {"lcm_truncated_to_fingerprint", Kind::kLcmPacket,
       text([] { return packet(kModeChannel, encoded(modeMsg(2)).substr(0, 8)); }), rejected("truncated")},
      {"lcm_empty_packet", Kind::kLcmPacket, text([] { return packet(kPostureChannel, std::string()); }), rejected("truncated")},
      {"lcm_padded_100kB", Kind::kLcmPacket,
       text([] { return packet(kVelocityChannel, encoded(velocityMsg()) + std::string(100 * 1024, '\0')); }),
       rejected("trailing bytes")},
      {"lcm_wrong_fingerprint", Kind::kLcmPacket,
       text([] { std::string b = encoded(velocityMsg()); b[3] = static_cast<char>(b[3] ^ 0x5A); return packet(kVelocityChannel, b); }),
       rejected("bad fingerprint")},
      {"lcm_type_on_wrong_channel", Kind::kLcmPacket, text([] { return packet(kModeChannel, encoded(velocityMsg())); }),
       rejected("bad fingerprint")},
      {"lcm_mode_code_99", Kind::kLcmPacket, text([] { return packet(kModeChannel, encoded(modeMsg(99))); }),
       rejected("unknown mode code")},
      {"lcm_mode_code_minus_5", Kind::kLcmPacket, text([] { return packet(kModeChannel, encoded(modeMsg(-5))); }),
       rejected("unknown mode code")},
      {"lcm_nan_velocity", Kind::kLcmPacket,
       text([] { auto m = velocityMsg(); m.vx = std::numeric_limits<double>::quiet_NaN(); return packet(kVelocityChannel, encoded(m)); }),
       rejected("non-finite value")},
      {"lcm_inf_height", Kind::kLcmPacket,
       text([] { auto m = postureMsg(); m.height = std::numeric_limits<double>::infinity(); return packet(kPostureChannel, encoded(m)); }),
       rejected("non-finite value")},
      {"lcm_unknown_channel", Kind::kLcmPacket, text([] { return packet("PMG_VELOCITY_COMMANDS", encoded(velocityMsg())); }),
       rejected("unknown channel")},
      {"lcm_vr_non_unit_quaternion", Kind::kLcmPacket,
       text([] { auto m = vrPoseMsg(); m.head_quat[0] = 1.01; return packet(kVrPoseChannel, encoded(m)); }),
       rejected("out of range")},
      {"lcm_vr_grip_above_1", Kind::kLcmPacket,
       text([] { auto m = vrPoseMsg(); m.grip[1] = 1.5; return packet(kVrPoseChannel, encoded(m)); }),
       rejected("out of range")},
      {"lcm_vr_nan_hand_position", Kind::kLcmPacket,
       text([] { auto m = vrPoseMsg(); m.hand_position[0][1] = std::numeric_limits<double>::quiet_NaN(); return packet(kVrPoseChannel, encoded(m)); }),
       rejected("non-finite value")},
      {"lcm_vr_truncated", Kind::kLcmPacket,
       text([] { std::string b = encoded(vrPoseMsg()); b.resize(b.size() - 30); return packet(kVrPoseChannel, b); }),
       rejected("truncated")},
  };
}

// ---------------------------------------------------------------------------------------------
// Running one case.

struct Outcome {
  enum Type { kThrew, kRejected, kAccepted } type = kAccepted;
  std::string text;  ///< what() of the error, or the rejection's name
};

/// Loads a file of @p kind; any exception is the outcome (a crash would end the process).
Outcome loadFile(Kind kind, const std::string& path) {
  // The fixtures a loader needs are loaded first: their failure is not the case's outcome.
  const bool needs_robot = kind == Kind::kZeroResult || kind == Kind::kDynamicClip || kind == Kind::kStaticClip;
  const RobotConfig* robot = needs_robot ? &g1Robot() : nullptr;
  const policy::PolicyRobotSpec spec = kind == Kind::kOnnxModel ? g1PolicySpec() : policy::PolicyRobotSpec{};
  try {
    switch (kind) {
      case Kind::kRobotConfig: (void)loadRobotConfig(path); break;
      case Kind::kGcoOptions: (void)gco::loadGcoOptionsFile(path); break;
      case Kind::kBusPlan: (void)hal::bus::BusPlan::fromYaml(path); break;
      case Kind::kRig: (void)calib::load_rig_config(path); break;
      case Kind::kBenchLogCsv:
      case Kind::kBenchLogJson: (void)calib::load_bench_log(path); break;
      case Kind::kZeroProtocol: (void)calib::loadZeroProtocol(path); break;
      case Kind::kZeroResult: (void)calib::loadJointValues(path, *robot); break;
      case Kind::kDynamicClip: (void)readDynamicClip(path, *robot); break;
      case Kind::kStaticClip: (void)readStaticClip(path, *robot); break;
      case Kind::kOnnxModel: (void)policy::PolicyRunner(path, spec); break;
      case Kind::kCommandScript: (void)loadCommandScript(path); break;
      case Kind::kControllerConfig: (void)loadControllerConfig(path); break;
      default: return {Outcome::kThrew, "bad-input test: not a file kind"};
    }
  } catch (const std::exception& e) {
    return {Outcome::kThrew, e.what()};
  }
  return {Outcome::kAccepted, "loaded without error"};
}

Outcome parseContractText(const std::string& yaml, const std::string& source) {
  const policy::PolicyRobotSpec spec = g1PolicySpec();
  try {
    const policy::PolicyContract c = policy::parseContract(yaml, source);
    policy::checkContract(c, spec, source);
  } catch (const std::exception& e) {
    return {Outcome::kThrew, e.what()};
  }
  return {Outcome::kAccepted, "contract accepted"};
}

CanFrame frameOf(const std::string& d) {
  CanFrame f;
  if (!hal::bus::decodeUdpCan(reinterpret_cast<const std::uint8_t*>(d.data()), d.size(), f))
    throw std::logic_error("bad-input case: the test frame does not encode");
  return f;
}

Outcome encodeMotorCommand(const std::string& d) {
  double v[5];
  if (d.size() != sizeof v) throw std::logic_error("bad-input case: a motor command is 5 doubles");
  std::memcpy(v, d.data(), sizeof v);
  const hal::bus::MitProtocol mit;
  CanFrame f;
  f.len = 0;
  if (mit.encodeCommand(leftHipPitchMotor(), hal::bus::MotorCommand{v[0], v[1], v[2], v[3], v[4]}, f))
    return {Outcome::kAccepted, "encoded into a frame"};
  if (f.len != 0) return {Outcome::kRejected, "refused, but the frame was written"};
  return {Outcome::kRejected, "not encoded"};
}

Outcome decodeFrame(Kind kind, const std::string& d) {
  const CanFrame f = frameOf(d);
  switch (kind) {
    case Kind::kCanReply: {
      const hal::bus::MitProtocol mit;
      hal::bus::MotorFeedback fb;
      const hal::bus::ReplyStatus s = mit.decodeReply(leftHipPitchMotor(), f, fb);
      if (s == hal::bus::ReplyStatus::kOk) return {Outcome::kAccepted, "reply decoded"};
      return {Outcome::kRejected, hal::bus::toString(s)};
    }
    case Kind::kCanCommand: {
      hal::bus::MotorCommand c;
      hal::bus::ControlRequest r{};
      if (hal::bus::MitProtocol::decodeControl(f, r)) return {Outcome::kAccepted, "decoded as a control frame"};
      if (hal::bus::MitProtocol::decodeCommand(leftHipPitchMotor(), f, c)) return {Outcome::kAccepted, "decoded as a command"};
      return {Outcome::kRejected, "not a command"};
    }
    case Kind::kImuFrame: {
      ImuState s;
      std::uint32_t seq = 0;
      if (hal::bus::decodeImu(f, s, seq)) return {Outcome::kAccepted, "IMU sample decoded"};
      return {Outcome::kRejected, "not an IMU sample"};
    }
    default: throw std::logic_error("not a frame kind");
  }
}

/// Sends @p d to a UdpCanTransport from a plain socket and receives it: a rejection must be
/// answered RxStatus::kError and counted in rx_errors (the transport keeps working after it).
Outcome sendDatagram(const std::string& d) {
  hal::bus::UdpCanTransport::Options o;
  hal::bus::UdpCanTransport rx(o);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw std::runtime_error("socket");
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(rx.localPort());
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const auto send = [&](const std::string& bytes) {
    if (::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) !=
        static_cast<ssize_t>(bytes.size()))
      throw std::runtime_error("sendto");
  };
  const auto next = [&](CanFrame& f) {
    pollfd p{rx.pollFd(), POLLIN, 0};
    ::poll(&p, 1, 1000);
    return rx.receive(f);
  };
  send(d);
  CanFrame f;
  const hal::bus::RxStatus st = next(f);
  const std::uint64_t errors = rx.counters().rx_errors;
  // The transport still takes a valid frame afterwards.
  send(datagram(validReply()));
  CanFrame g;
  const hal::bus::RxStatus after = next(g);
  ::close(fd);
  if (after != hal::bus::RxStatus::kFrame) return {Outcome::kThrew, "transport stopped receiving after the bad datagram"};
  if (st == hal::bus::RxStatus::kFrame) return {Outcome::kAccepted, "datagram accepted as a frame"};
  if (st == hal::bus::RxStatus::kError && errors == 1) return {Outcome::kRejected, "rx_errors"};
  return {Outcome::kRejected, std::string("not counted (status ") + (st == hal::bus::RxStatus::kEmpty ? "empty" : "error") +
                                  ", rx_errors " + std::to_string(errors) + ")"};
}

/// The physics behind the emulated drivers: holds still (the emulator only needs a period).
class StillSim final : public HalBackend {
 public:
  explicit StillSim(double period) : period_(period) {}
  const char* name() const noexcept override { return "still"; }
  double cyclePeriod() const noexcept override { return period_; }
  BackendStatus exchange(const LowCommand&, LowState& state) noexcept override {
    state.num_motors = 29;
    return BackendStatus::kOk;
  }

 private:
  double period_;
};

/// Sends the frame in @p d to bus 0 of a SilDriverEmulator on the G1 plan and runs one cycle: it
/// must be dropped and counted (SilCounters::rejected), and a valid command afterwards still taken.
Outcome sendToSil(const std::string& d) {
  static const hal::bus::BusPlan plan = hal::bus::BusPlan::fromYaml(g1CanPlanPath());
  std::unique_ptr<hal::bus::SilDriverEmulator> sil;
  std::vector<std::unique_ptr<hal::bus::CanTransport>> host;
  std::unique_ptr<hal::bus::CanTransport> imu;
  for (int attempt = 0;; ++attempt) {
    const auto base = static_cast<std::uint16_t>(40000 + ((::getpid() + 53 * attempt) % 1000) * 20);
    try {
      sil = std::make_unique<hal::bus::SilDriverEmulator>(plan, std::make_unique<StillSim>(plan.options().period_s), base);
      host = hal::bus::makeHostUdpTransports(plan, base, imu);
      break;
    } catch (const std::system_error&) {
      sil.reset();
      if (attempt >= 20) throw;
    }
  }
  if (host[0]->send(frameOf(d)) != hal::bus::TxStatus::kOk) throw std::runtime_error("send to the SIL failed");
  sil->runCycle(0.05, true);
  const hal::bus::SilCounters bad = sil->counters();
  host[0]->send(validCommand());
  sil->runCycle(0.05, true);
  if (sil->counters().commands != bad.commands + 1) return {Outcome::kThrew, "the emulator stopped taking commands"};
  if (bad.commands != 0 || bad.controls != 0) return {Outcome::kAccepted, "taken as a command or control frame"};
  if (bad.rejected == 1) return {Outcome::kRejected, "rejected"};
  return {Outcome::kRejected, "dropped without being counted"};
}

Outcome decodeLcm(const std::string& p) {
#if !PMG_BAD_INPUT_HAVE_LCM_DECODER
  (void)p;
  return {Outcome::kThrew, "LcmCommandDecoder is not built into pmg::controller yet"};
#else
  const std::size_t nul = p.find('\0');
  const std::string_view channel(p.data(), nul);
  const std::string bytes = p.substr(nul + 1);
  LcmCommandDecoder decoder;
  CommandSample sample;
  sample.command.vx = 0.125;
  const CommandSample before = sample;
  const DecodeResult r = decoder.decode(channel, bytes.data(), bytes.size(), 1.0, sample);
  if (r == DecodeResult::kAccepted) return {Outcome::kAccepted, "packet accepted"};
  // Rejected: counted under its cause, and the sample untouched.
  if (decoder.counters().count(r) != 1 || decoder.counters().rejected() != 1 || decoder.counters().accepted() != 0)
    return {Outcome::kRejected, std::string(toString(r)) + " (not counted)"};
  if (sample.command.vx != before.command.vx || sample.mode_request_seq != before.mode_request_seq ||
      sample.velocity_time != before.velocity_time || sample.posture_time != before.posture_time)
    return {Outcome::kRejected, std::string(toString(r)) + " (but the sample changed)"};
  return {Outcome::kRejected, toString(r)};
#endif
}

Outcome run(const Case& c, const TempDir& dir, std::string* file) {
  const std::string input = c.input();
  switch (c.kind) {
    case Kind::kContract:
      *file = std::string(c.name) + ".onnx";
      return parseContractText(input, dir.file(*file));
    case Kind::kCanReply:
    case Kind::kCanCommand:
    case Kind::kImuFrame: return decodeFrame(c.kind, input);
    case Kind::kMotorCommand: return encodeMotorCommand(input);
    case Kind::kUdpDatagram: return sendDatagram(input);
    case Kind::kSilFrame: return sendToSil(input);
    case Kind::kLcmPacket: return decodeLcm(input);
    default:
      *file = std::string(c.name) + fileExtension(c.kind);
      return loadFile(c.kind, dir.write(*file, input));
  }
}

/// "" when @p out is what @p c expects, else what is wrong.
std::string mismatch(const Case& c, const Outcome& out, const std::string& file) {
  const std::string got = out.type == Outcome::kThrew      ? "error: " + out.text
                          : out.type == Outcome::kRejected ? "rejected: " + out.text
                                                           : "SILENTLY ACCEPTED (" + out.text + ")";
  if (c.expect.type == Expect::kError) {
    if (out.type != Outcome::kThrew) return "expected an error naming the file, got " + got;
    if (out.text.find(file) == std::string::npos) return "the error does not name the file " + file + ": " + out.text;
    for (const std::string& n : c.expect.needles) {
      if (out.text.find(n) == std::string::npos) return "the error does not name '" + n + "': " + out.text;
    }
    return "";
  }
  // "a|b": either named rejection is right.
  const std::string& names = c.expect.needles.front();
  bool named = false;
  for (std::size_t b = 0; b <= names.size();) {
    const std::size_t e = std::min(names.find('|', b), names.size());
    named = named || (out.type == Outcome::kRejected && out.text == names.substr(b, e - b));
    b = e + 1;
  }
  if (!named) return "expected the counted rejection '" + names + "', got " + got;
  return "";
}

constexpr std::chrono::seconds kCaseTimeout{30};

class BadInput : public ::testing::TestWithParam<Case> {};

TEST_P(BadInput, EndsInANamedErrorOrACountedRejection) {
  const Case& c = GetParam();
  const TempDir dir;
  std::string file;
  // A hang is a failure too: no case may take more than kCaseTimeout (the process cannot cancel a
  // stuck thread, so it ends with the case named).
  auto pending_outcome = std::async(std::launch::async, [&] { return run(c, dir, &file); });
  if (pending_outcome.wait_for(kCaseTimeout) != std::future_status::ready) {
    std::fprintf(stderr, "bad-input case %s (%s): no outcome after %lld s: a hang\n", c.name, kindName(c.kind),
                 static_cast<long long>(kCaseTimeout.count()));
    std::_Exit(3);
  }
  const Outcome out = pending_outcome.get();
  const std::string why = mismatch(c, out, file);
  RecordProperty("kind", kindName(c.kind));
  if (c.pending != nullptr) {
    if (!why.empty()) GTEST_SKIP() << "pending (" << c.pending << "): " << why;
    std::printf("[pending-now-passes] %s (%s): flip it to enforced\n", c.name, c.pending);
    return;
  }
  EXPECT_TRUE(why.empty()) << kindName(c.kind) << " case " << c.name << ": " << why;
}

INSTANTIATE_TEST_SUITE_P(Table, BadInput, ::testing::ValuesIn(allCases()),
                         [](const ::testing::TestParamInfo<Case>& row) { return std::string(row.param.name); });

// The battery covers what issue 11 asks for: at least 60 cases, every input kind.
TEST(BadInputTable, CoversEveryKindWithAtLeast60Cases) {
  const std::vector<Case> cases = allCases();
  EXPECT_GE(cases.size(), 60u);
  std::map<Kind, int> per_kind;
  for (const Case& c : cases) ++per_kind[c.kind];
  for (Kind k : {Kind::kRobotConfig, Kind::kGcoOptions, Kind::kBusPlan, Kind::kRig, Kind::kBenchLogCsv,
                 Kind::kBenchLogJson, Kind::kZeroProtocol, Kind::kZeroResult, Kind::kDynamicClip, Kind::kStaticClip,
                 Kind::kContract, Kind::kOnnxModel, Kind::kCommandScript, Kind::kControllerConfig, Kind::kCanReply,
                 Kind::kCanCommand, Kind::kMotorCommand, Kind::kImuFrame, Kind::kUdpDatagram, Kind::kSilFrame, Kind::kLcmPacket}) {
    EXPECT_GT(per_kind[k], 0) << kindName(k);
  }
  int pending = 0;
  for (const Case& c : cases) pending += c.pending != nullptr ? 1 : 0;
  std::printf("bad-input cases: %zu (%d pending)\n", cases.size(), pending);
  for (const auto& [kind, n] : per_kind) std::printf("  %-26s %d\n", kindName(kind), n);
  std::set<std::string> names;
  for (const Case& c : cases) EXPECT_TRUE(names.insert(c.name).second) << "duplicate case name " << c.name;
}

}  // namespace
}  // namespace pmg::test
