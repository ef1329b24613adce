#include "pmg/hal/bus/bus_plan.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

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

// ---------------------------------------------------------------- YAML
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& field, const std::string& what) {
  throw std::runtime_error(path + ": " + field + ": " + what);
}

template <typename T>
T get(const YAML::Node& node, const char* key, const std::string& path, const std::string& where,
      const T* fallback = nullptr) {
  const YAML::Node v = node[key];
  if (!v) {
    if (fallback) return *fallback;
    fail(path, where + "." + key, "missing required field");
  }
  try {
    return v.as<T>();
  } catch (const YAML::Exception& e) {
    fail(path, where + "." + key, std::string("cannot parse value: ") + e.what());
  }
}

template <typename T>
T getOr(const YAML::Node& node, const char* key, const std::string& path, const std::string& where, T def) {
  return get<T>(node, key, path, where, &def);
}

MotorRanges parseRanges(const YAML::Node& n, const std::string& path, const std::string& where) {
  MotorRanges r;
  const MotorRanges d;
  r.q_min = getOr(n, "q_min", path, where, d.q_min);
  r.q_max = getOr(n, "q_max", path, where, d.q_max);
  r.qd_min = getOr(n, "qd_min", path, where, d.qd_min);
  r.qd_max = getOr(n, "qd_max", path, where, d.qd_max);
  r.kp_min = getOr(n, "kp_min", path, where, d.kp_min);
  r.kp_max = getOr(n, "kp_max", path, where, d.kp_max);
  r.kd_min = getOr(n, "kd_min", path, where, d.kd_min);
  r.kd_max = getOr(n, "kd_max", path, where, d.kd_max);
  r.tau_min = getOr(n, "tau_min", path, where, d.tau_min);
  r.tau_max = getOr(n, "tau_max", path, where, d.tau_max);
  const std::string msg = r.validate();
  if (!msg.empty()) fail(path, where, msg);
  return r;
}

}  // namespace

std::vector<BusConfig> BusPlan::parseYaml(const std::string& path, BusPlanOptions& o) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": cannot read bus plan: " + e.what());
  }
  o.period_s = getOr(root, "period_s", path, "", o.period_s);
  o.max_load = getOr(root, "max_load", path, "", o.max_load);
  o.turnaround_s = getOr(root, "turnaround_s", path, "", o.turnaround_s);
  o.num_joints = getOr(root, "num_joints", path, "", o.num_joints);
  const double reply_margin = getOr(root, "reply_margin", path, "", 0.2);
  const std::string ov = o.validate();
  if (!ov.empty()) fail(path, "(top level)", ov);

  std::map<std::string, MotorRanges> types;
  if (const YAML::Node mt = root["motor_types"]) {
    for (const auto& kv : mt) {
      const std::string name = kv.first.as<std::string>();
      types[name] = parseRanges(kv.second, path, "motor_types." + name);
    }
  }
  const YAML::Node bn = root["buses"];
  if (!bn || !bn.IsSequence() || bn.size() == 0) fail(path, "buses", "expected a non-empty list of buses");
  std::vector<BusConfig> buses;
  for (std::size_t b = 0; b < bn.size(); ++b) {
    const YAML::Node n = bn[b];
    const std::string where = "buses[" + std::to_string(b) + "]";
    BusConfig c;
    c.name = get<std::string>(n, "name", path, where);
    c.protocol = getOr<std::string>(n, "protocol", path, where, "mit");
    c.timing.bitrate = getOr(n, "bitrate", path, where, 1e6);
    c.timing.fd = getOr(n, "fd", path, where, false);
    c.timing.data_bitrate = getOr(n, "data_bitrate", path, where, 5e6);
    const YAML::Node mn = n["motors"];
    if (!mn || !mn.IsSequence()) fail(path, where + ".motors", "expected a list of motors");
    for (std::size_t k = 0; k < mn.size(); ++k) {
      const YAML::Node m = mn[k];
      const std::string mw = where + ".motors[" + std::to_string(k) + "]";
      MotorSpec s;
      s.name = get<std::string>(m, "joint", path, mw);
      s.joint_index = get<int>(m, "joint_index", path, mw);
      const int id = get<int>(m, "motor_id", path, mw);
      if (id < 1 || id > 254) fail(path, mw + ".motor_id", "expected 1..254, got " + std::to_string(id));
      s.motor_id = static_cast<std::uint8_t>(id);
      s.command_can_id = getOr<std::uint32_t>(m, "command_can_id", path, mw, s.motor_id);
      s.reply_can_id = getOr<std::uint32_t>(m, "reply_can_id", path, mw, 0);
      s.direction = getOr(m, "direction", path, mw, 1.0);
      s.offset = getOr(m, "offset", path, mw, 0.0);
      const std::string type = get<std::string>(m, "type", path, mw);
      auto it = types.find(type);
      if (it == types.end()) fail(path, mw + ".type", "unknown motor type '" + type + "' (define it in motor_types)");
      s.ranges = it->second;
      s.reply_limits.qd_abs_max = std::max(std::fabs(s.ranges.qd_min), std::fabs(s.ranges.qd_max));
      s.reply_limits.tau_abs_max = std::max(std::fabs(s.ranges.tau_min), std::fabs(s.ranges.tau_max));
      if (const YAML::Node jr = m["joint_range"]) {
        if (!jr.IsSequence() || jr.size() != 2) fail(path, mw + ".joint_range", "expected [low, high] in rad");
        const double lo = jr[0].as<double>(), hi = jr[1].as<double>();
        if (!(lo < hi)) fail(path, mw + ".joint_range", "expected low < high");
        // Reply plausibility is judged motor-side: map the joint range through direction/offset.
        const double a = s.direction * lo + s.offset, bnd = s.direction * hi + s.offset;
        s.reply_limits.q_min = std::min(a, bnd) - reply_margin;
        s.reply_limits.q_max = std::max(a, bnd) + reply_margin;
      }
      c.motors.push_back(s);
    }
    buses.push_back(std::move(c));
  }
  return buses;
}

BusPlan BusPlan::fromYaml(const std::string& path) {
  BusPlanOptions o;
  std::vector<BusConfig> buses = parseYaml(path, o);
  return BusPlan(std::move(buses), o, path);
}

}  // namespace pmg::hal::bus
