#include "pmg/hal/bus/bus_plan.hpp"

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <array>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "pmg/common/robot_config.hpp"
#include "pmg/common/yaml_archive.hpp"

namespace pmg::hal::bus {

std::size_t classicFrameBitsNoStuffing(std::size_t payload, bool extended_id) noexcept {
  const std::size_t g = extended_id ? 54 : 34;
  return g + 8 * payload + 13;
}

std::size_t classicFrameBitsWorstCase(std::size_t payload, bool extended_id) noexcept {
  const std::size_t g = extended_id ? 54 : 34;
  return g + 8 * payload + 13 + (g + 8 * payload - 1) / 4;
}

double classicFrameTime(std::size_t payload, double bitrate, bool extended_id) noexcept {
  return static_cast<double>(classicFrameBitsWorstCase(payload, extended_id)) / bitrate;
}

double fdFrameTime(std::size_t payload, double nominal_bitrate, double data_bitrate, bool brs) noexcept {
  const std::size_t n = fdPaddedLength(payload);
  const std::size_t arbitration = 17;  // SOF, 11-bit id, RRS, IDE, FDF, res, BRS
  const std::size_t tail = 13;         // CRC delimiter, ACK, ACK delimiter, EOF 7, intermission 3
  const std::size_t crc = n <= 16 ? 17 : 21;
  const std::size_t fixed_stuff = n <= 16 ? 6 : 7;
  const std::size_t data_phase = 1 + 4 + 8 * n + 4 + crc + fixed_stuff;  // ESI, DLC, data, SBC, CRC
  const std::size_t dynamic_stuff = (arbitration + 5 + 8 * n - 1) / 4;
  const double nominal_bits = static_cast<double>(arbitration + tail + dynamic_stuff);
  const double rate = brs ? data_bitrate : nominal_bitrate;
  return nominal_bits / nominal_bitrate + static_cast<double>(data_phase) / rate;
}

std::string BusPlanOptions::validate() const {
  std::ostringstream os;
  if (!(period_s > 0.0 && period_s <= 1.0)) os << "period_s must be in (0, 1] s (got " << period_s << ")";
  else if (!(max_load > 0.0 && max_load <= 1.0)) os << "max_load must be in (0, 1] (got " << max_load << ")";
  else if (!(turnaround_s >= 0.0 && turnaround_s < period_s))
    os << "turnaround_s must be in [0, period_s) (got " << turnaround_s << ")";
  else if (num_joints < 1 || num_joints > 256) os << "num_joints must be in 1..256 (got " << num_joints << ")";
  return os.str();
}

namespace {

BusLoad computeLoad(const BusConfig& bus, const MotorProtocol& proto, const BusPlanOptions& o) {
  BusLoad l;
  const BusTiming& t = bus.timing;
  if (t.fd) {
    l.command_s = fdFrameTime(proto.commandLength(), t.bitrate, t.data_bitrate, true);
    l.reply_s = fdFrameTime(proto.replyLength(), t.bitrate, t.data_bitrate, true);
  } else {
    l.command_s = classicFrameTime(proto.commandLength(), t.bitrate);
    l.reply_s = classicFrameTime(proto.replyLength(), t.bitrate);
  }
  l.per_motor_s = l.command_s + o.turnaround_s + l.reply_s;
  l.motors = bus.motors.size();
  l.busy_s = l.per_motor_s * static_cast<double>(l.motors);
  l.load = (l.command_s + l.reply_s) * static_cast<double>(l.motors) / o.period_s;
  return l;
}

}  // namespace

BusPlanCheck checkBusPlan(const std::vector<BusConfig>& buses, const BusPlanOptions& o) {
  BusPlanCheck res;
  std::ostringstream err;
  const std::string opt = o.validate();
  if (!opt.empty()) err << "options: " << opt << "\n";
  if (buses.empty()) err << "buses: at least one bus is required\n";
  std::vector<int> joint_seen(static_cast<std::size_t>(std::max(o.num_joints, 0)), 0);
  std::set<std::string> names;
  for (std::size_t b = 0; b < buses.size(); ++b) {
    const BusConfig& bus = buses[b];
    const std::string where = "buses[" + std::to_string(b) + "] '" + bus.name + "'";
    if (bus.name.empty()) err << where << ".name: must not be empty\n";
    if (!names.insert(bus.name).second) err << where << ".name: duplicate bus name\n";
    std::unique_ptr<MotorProtocol> proto;
    try {
      proto = makeMotorProtocol(bus.protocol);
    } catch (const std::exception& e) {
      err << where << ".protocol: " << e.what() << "\n";
    }
    const BusTiming& t = bus.timing;
    if (!(t.bitrate >= 10e3 && t.bitrate <= 1e6))
      err << where << ".bitrate: expected 10e3..1e6 bit/s, got " << t.bitrate << "\n";
    if (t.fd && !(t.data_bitrate >= t.bitrate && t.data_bitrate <= 12e6))
      err << where << ".data_bitrate: expected bitrate..12e6 bit/s, got " << t.data_bitrate << "\n";
    std::set<int> ids, cmd_ids, reply_ids;
    for (std::size_t k = 0; k < bus.motors.size(); ++k) {
      const MotorSpec& m = bus.motors[k];
      const std::string mw = where + ".motors[" + std::to_string(k) + "] '" + m.name + "'";
      if (m.joint_index < 0 || m.joint_index >= o.num_joints) {
        err << mw << ".joint_index: expected 0.." << o.num_joints - 1 << ", got " << m.joint_index << "\n";
      } else {
        ++joint_seen[static_cast<std::size_t>(m.joint_index)];
      }
      if (m.motor_id == 0 || m.motor_id == 255)
        err << mw << ".motor_id: expected 1..254, got " << int(m.motor_id) << "\n";
      if (!ids.insert(m.motor_id).second) err << mw << ".motor_id: duplicate on this bus\n";
      if (m.command_can_id > 0x7FF || m.reply_can_id > 0x7FF)
        err << mw << ".command_can_id/reply_can_id: expected 0..0x7FF (11 bit)\n";
      if (!cmd_ids.insert(static_cast<int>(m.command_can_id)).second)
        err << mw << ".command_can_id: duplicate on this bus\n";
      reply_ids.insert(static_cast<int>(m.reply_can_id));
      if (m.direction != 1.0 && m.direction != -1.0)
        err << mw << ".direction: expected +1 or -1, got " << m.direction << "\n";
      if (!std::isfinite(m.offset)) err << mw << ".offset: must be finite\n";
      const std::string r = m.ranges.validate();
      if (!r.empty()) err << mw << ".ranges: " << r << "\n";
      const ReplyLimits& rl = m.reply_limits;
      if (!(rl.q_min < rl.q_max) || !(rl.qd_abs_max > 0) || !(rl.tau_abs_max > 0))
        err << mw << ".reply limits: need q_min < q_max and positive qd/tau bounds\n";
    }
    for (int id : cmd_ids) {
      if (reply_ids.count(id)) err << where << ": command id " << id << " is also a reply id\n";
    }
    if (proto && t.bitrate > 0) {
      BusLoad l = computeLoad(bus, *proto, o);
      if (l.load > o.max_load) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "%s: load %.1f %% > %.1f %% (%zu motors x %.1f us per %.2f ms slot)",
                      where.c_str(), 100.0 * l.load, 100.0 * o.max_load, l.motors,
                      1e6 * (l.command_s + l.reply_s), 1e3 * o.period_s);
        err << buf << "\n";
      }
      if (l.busy_s > o.period_s) {
        err << where << ": request-reply round of " << 1e6 * l.busy_s << " us does not fit the slot\n";
      }
      res.loads.push_back(l);
    } else {
      res.loads.push_back(BusLoad{});
    }
  }
  for (std::size_t j = 0; j < joint_seen.size(); ++j) {
    if (joint_seen[j] != 1)
      err << "joint_index " << j << ": appears " << joint_seen[j] << " times (expected exactly once)\n";
  }
  res.message = err.str();
  res.ok = res.message.empty();
  return res;
}

BusPlan::BusPlan(std::vector<BusConfig> buses, BusPlanOptions options, const std::string& source)
    : buses_(std::move(buses)), options_(options) {
  BusPlanCheck c = checkBusPlan(buses_, options_);
  if (!c.ok) throw std::invalid_argument(source + ": bus plan refused:\n" + c.message);
  loads_ = c.loads;
  schedule_.resize(buses_.size());
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    const BusLoad& l = loads_[b];
    for (std::size_t k = 0; k < buses_[b].motors.size(); ++k) {
      SlotEntry e;
      e.motor = static_cast<int>(k);
      e.send_offset_s = static_cast<double>(k) * l.per_motor_s;
      e.reply_due_s = e.send_offset_s + l.per_motor_s;
      schedule_[b].push_back(e);
    }
  }
}

std::size_t BusPlan::motorCount() const noexcept {
  std::size_t n = 0;
  for (const auto& b : buses_) n += b.motors.size();
  return n;
}

std::string BusPlan::report() const {
  std::ostringstream os;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%-8s %-6s %-14s %6s %10s %10s %8s\n", "bus", "proto", "timing", "motors",
                "us/motor", "busy [us]", "load");
  os << buf;
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    const BusConfig& c = buses_[b];
    const BusLoad& l = loads_[b];
    char timing[64];
    if (c.timing.fd)
      std::snprintf(timing, sizeof timing, "FD %.0f/%.0fk", c.timing.bitrate / 1e3, c.timing.data_bitrate / 1e3);
    else
      std::snprintf(timing, sizeof timing, "CAN %.0fk", c.timing.bitrate / 1e3);
    std::snprintf(buf, sizeof buf, "%-8s %-6s %-14s %6zu %10.1f %10.1f %7.1f%%\n", c.name.c_str(),
                  c.protocol.c_str(), timing, l.motors, 1e6 * l.per_motor_s, 1e6 * l.busy_s, 100.0 * l.load);
    os << buf;
  }
  return os.str();
}

// ---------------------------------------------------------------- YAML (pmg::yaml, yaml_archive.hpp)
namespace {

// The file format of a bus plan (docs/hal.md, 'Bus plans').
struct RangesEntry {
  MotorRanges r;
  template <class A>
  void Serialize(A* a) {
    a->Visit("q_min", &r.q_min, "[rad]");
    a->Visit("q_max", &r.q_max, "[rad]");
    a->Visit("qd_min", &r.qd_min, "[rad/s]");
    a->Visit("qd_max", &r.qd_max, "[rad/s]");
    a->Visit("kp_min", &r.kp_min, "[N m/rad]");
    a->Visit("kp_max", &r.kp_max, "[N m/rad]");
    a->Visit("kd_min", &r.kd_min, "[N m s/rad]");
    a->Visit("kd_max", &r.kd_max, "[N m s/rad]");
    a->Visit("tau_min", &r.tau_min, "[N m]");
    a->Visit("tau_max", &r.tau_max, "[N m]");
  }
  std::string validate() const { return r.validate(); }
};

struct MotorEntry {
  std::string joint;
  int joint_index = -1;
  int motor_id = 0;
  std::optional<std::uint32_t> command_can_id;
  std::uint32_t reply_can_id = 0;
  double direction = 1.0;
  double offset = 0.0;
  std::string type;
  std::optional<std::array<double, 2>> joint_range;
  template <class A>
  void Serialize(A* a) {
    a->Visit("joint", &joint, "joint name of the robot config", yaml::kRequired);
    a->Visit("joint_index", &joint_index, "index in the robot's joint order", yaml::kRequired);
    a->Visit("motor_id", &motor_id, "driver id, 1..254", yaml::kRequired);
    a->Visit("command_can_id", &command_can_id, "11-bit id of commands (default: motor_id)");
    a->Visit("reply_can_id", &reply_can_id, "11-bit id of replies");
    a->Visit("direction", &direction, "+1 or -1");
    a->Visit("offset", &offset, "motor position at joint zero [rad]");
    a->Visit("type", &type, "a key of motor_types", yaml::kRequired);
    a->Visit("joint_range", &joint_range, "[low, high] [rad]: narrows the reply plausibility window");
  }
  std::string validate() const {
    if (motor_id < 1 || motor_id > 254) return "motor_id: expected 1..254, got " + std::to_string(motor_id);
    if (joint_range && !((*joint_range)[0] < (*joint_range)[1])) return "joint_range: expected low < high";
    return "";
  }
};

struct BusEntry {
  std::string name;
  std::string protocol = "mit";
  BusTiming timing;
  std::vector<MotorEntry> motors;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, "interface name, e.g. can0", yaml::kRequired);
    a->Visit("protocol", &protocol, "motor protocol (makeMotorProtocol name)");
    a->Visit("bitrate", &timing.bitrate, "nominal bit rate [bit/s]");
    a->Visit("fd", &timing.fd, "CAN FD frames");
    a->Visit("data_bitrate", &timing.data_bitrate, "CAN FD data-phase bit rate [bit/s]");
    a->Visit("motors", &motors, "served in this order inside the slot", yaml::kRequired);
  }
};

struct PlanFile {
  BusPlanOptions* o = nullptr;
  double reply_margin = 0.2;
  std::map<std::string, RangesEntry> motor_types;
  std::vector<BusEntry> buses;
  template <class A>
  void Serialize(A* a) {
    a->Visit("period_s", &o->period_s, "HAL period [s]");
    a->Visit("max_load", &o->max_load, "refuse a bus above this load, (0, 1]");
    a->Visit("turnaround_s", &o->turnaround_s, "driver reply latency [s]");
    a->Visit("num_joints", &o->num_joints, "every joint index 0..num_joints-1 exactly once");
    a->Visit("reply_margin", &reply_margin, "reply window = joint range +- this [rad]");
    a->Visit("motor_types", &motor_types, "codec ranges per motor type");
    a->Visit("buses", &buses, "the buses", yaml::kRequired);
  }
  std::string validate() const {
    if (const std::string ov = o->validate(); !ov.empty()) return ov;
    if (buses.empty()) return "buses: expected a non-empty list of buses";
    if (!(reply_margin >= 0.0 && reply_margin <= 1.0)) return "reply_margin: expected 0..1 rad";
    return "";
  }
};

}  // namespace

std::vector<BusConfig> BusPlan::parseYaml(const std::string& path, BusPlanOptions& o) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  PlanFile f;
  f.o = &o;
  yaml::readYaml(doc, &f);
  const YAML::Node buses_node = doc.root["buses"];
  std::vector<BusConfig> buses;
  for (std::size_t b = 0; b < f.buses.size(); ++b) {
    const BusEntry& e = f.buses[b];
    BusConfig c;
    c.name = e.name;
    c.protocol = e.protocol;
    c.timing = e.timing;
    for (std::size_t k = 0; k < e.motors.size(); ++k) {
      const MotorEntry& m = e.motors[k];
      MotorSpec s;
      s.name = m.joint;
      s.joint_index = m.joint_index;
      s.motor_id = static_cast<std::uint8_t>(m.motor_id);
      s.command_can_id = m.command_can_id.value_or(s.motor_id);
      s.reply_can_id = m.reply_can_id;
      s.direction = m.direction;
      s.offset = m.offset;
      auto it = f.motor_types.find(m.type);
      if (it == f.motor_types.end()) {
        std::vector<std::string> names;
        for (const auto& kv : f.motor_types) names.push_back(kv.first);
        const YAML::Node mn = buses_node[b]["motors"][k]["type"];
        yaml::YamlSource src = doc.source;
        src.key_path = "buses[" + std::to_string(b) + "].motors[" + std::to_string(k) + "].type";
        const std::string hint =
            names.empty() ? std::string(")") : "; did you mean '" + yaml::nearestKey(m.type, names) + "'?)";
        yaml::fail(src, mn, "unknown motor type '" + m.type + "' (define it in motor_types" + hint);
      }
      s.ranges = it->second.r;
      s.reply_limits.qd_abs_max = std::max(std::fabs(s.ranges.qd_min), std::fabs(s.ranges.qd_max));
      s.reply_limits.tau_abs_max = std::max(std::fabs(s.ranges.tau_min), std::fabs(s.ranges.tau_max));
      if (m.joint_range) {
        // Reply plausibility is judged motor-side: map the joint range through direction/offset.
        const double lo = (*m.joint_range)[0], hi = (*m.joint_range)[1];
        const double a = s.direction * lo + s.offset, bnd = s.direction * hi + s.offset;
        s.reply_limits.q_min = std::min(a, bnd) - f.reply_margin;
        s.reply_limits.q_max = std::max(a, bnd) + f.reply_margin;
      }
      c.motors.push_back(s);
    }
    buses.push_back(std::move(c));
  }
  return buses;
}

void checkPlanAgainstRobot(const std::vector<BusConfig>& buses, const std::string& plan_file,
                           const pmg::RobotConfig& robot) {
  const std::string& rf = robot.source_file.empty() ? std::string("<robot config>") : robot.source_file;
  const std::vector<std::string> names = robot.jointNames();
  std::vector<int> seen(robot.numJoints(), 0);
  for (std::size_t b = 0; b < buses.size(); ++b) {
    for (std::size_t k = 0; k < buses[b].motors.size(); ++k) {
      const MotorSpec& m = buses[b].motors[k];
      const std::string where = plan_file + ": buses[" + std::to_string(b) + "].motors[" + std::to_string(k) + "]";
      const int i = robot.jointIndex(m.name);
      if (i < 0)
        throw ConfigError(where + ": joint '" + m.name + "' is not a joint of " + rf + " (did you mean '" +
                          yaml::nearestKey(m.name, names) + "'?)");
      const pmg::JointConfig& j = robot.joints[static_cast<std::size_t>(i)];
      if (m.joint_index != i)
        throw ConfigError(where + ": joint '" + m.name + "' has joint_index " + std::to_string(m.joint_index) +
                          ", but " + rf + " has it at index " + std::to_string(i));
      if (buses[b].name != j.bus || static_cast<int>(m.motor_id) != j.motor_id)
        throw ConfigError(where + ": joint '" + m.name + "' is on bus " + buses[b].name + " with motor_id " +
                          std::to_string(m.motor_id) + ", but " + rf + " says bus " + j.bus + " with motor_id " +
                          std::to_string(j.motor_id));
      ++seen[static_cast<std::size_t>(i)];
    }
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (seen[i] != 1)
      throw ConfigError(plan_file + ": joint '" + robot.joints[i].name + "' of " + rf + " appears " +
                        std::to_string(seen[i]) + " times (expected exactly once)");
}

BusPlan BusPlan::fromYaml(const std::string& path) {
  BusPlanOptions o;
  std::vector<BusConfig> buses = parseYaml(path, o);
  return BusPlan(std::move(buses), o, path);
}

}  // namespace pmg::hal::bus
