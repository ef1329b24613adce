#include "pmg/calib/bench_log.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "pmg/common/yaml_archive.hpp"

namespace pmg::calib {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, sep)) out.push_back(trim(cell));
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<double>> cols;
};

Table read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open file", path));
  Table tab;
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(fmt::format("{}: empty file (expected a CSV header)", path));
  tab.header = split(line, ',');
  tab.cols.assign(tab.header.size(), {});
  std::size_t row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (trim(line).empty()) continue;
    const auto cells = split(line, ',');
    if (cells.size() != tab.header.size())
      throw std::runtime_error(fmt::format("{}: line {} has {} fields, expected {} (header)", path, row,
                                           cells.size(), tab.header.size()));
    for (std::size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      const double v = std::strtod(cells[c].c_str(), &end);
      if (cells[c].empty() || end == cells[c].c_str() || *end != '\0')
        throw std::runtime_error(fmt::format("{}: line {}, column '{}': '{}' is not a number", path, row,
                                             tab.header[c], cells[c]));
      if (!std::isfinite(v))
        throw std::runtime_error(fmt::format("{}: line {}, column '{}': '{}' is not a finite number", path, row,
                                             tab.header[c], cells[c]));
      tab.cols[c].push_back(v);
    }
  }
  return tab;
}

int column(const Table& t, const std::string& name) {
  for (std::size_t i = 0; i < t.header.size(); ++i)
    if (t.header[i] == name) return static_cast<int>(i);
  return -1;
}

BenchLog from_pmg_csv(const std::string& path, const Table& tab) {
  BenchLog log;
  auto req = [&](const char* name) -> const std::vector<double>& {
    const int c = column(tab, name);
    if (c < 0) throw std::runtime_error(fmt::format("{}: missing required column '{}' (header must contain t,q_cmd,q)", path, name));
    return tab.cols[c];
  };
  auto opt = [&](const char* name, std::vector<double>& dst) {
    const int c = column(tab, name);
    if (c >= 0) dst = tab.cols[c];
  };
  // Unknown columns are errors (a typo would otherwise silently drop a signal).
  static const std::vector<std::string> known = {"t", "q_cmd", "q", "dq", "tau", "kp", "kd", "dq_cmd", "tau_ff", "enabled"};
  for (const std::string& h : tab.header)
    if (std::find(known.begin(), known.end(), h) == known.end())
      throw std::runtime_error(fmt::format("{}: unknown column '{}' in the header (did you mean '{}'?); expected some of "
                                           "t,q_cmd,q,dq,tau,kp,kd,dq_cmd,tau_ff,enabled",
                                           path, h, yaml::nearestKey(h, known)));
  log.t = req("t");
  log.q_cmd = req("q_cmd");
  log.q = req("q");
  opt("dq", log.dq);
  opt("tau", log.tau);
  opt("kp", log.kp);
  opt("kd", log.kd);
  opt("dq_cmd", log.dq_cmd);
  opt("tau_ff", log.tau_ff);
  const int ce = column(tab, "enabled");
  if (ce >= 0)
    for (double v : tab.cols[ce]) log.enabled.push_back(v != 0.0 ? 1 : 0);
  return log;
}

BenchLog from_dfki(const std::string& measured_path, const Table& meas) {
  std::string desired_path = measured_path;
  const auto pos = desired_path.rfind("measured");
  if (pos == std::string::npos)
    throw std::runtime_error(fmt::format("{}: DFKI format needs the data_measured*.csv file (the command is read "
                                         "from the sibling data_desired*.csv)", measured_path));
  desired_path.replace(pos, 8, "desired");
  const Table des = read_csv(desired_path);
  for (const char* c : {"time", "position", "velocity", "torque"}) {
    if (column(des, c) < 0) throw std::runtime_error(fmt::format("{}: missing column '{}'", desired_path, c));
    if (column(meas, c) < 0) throw std::runtime_error(fmt::format("{}: missing column '{}'", measured_path, c));
  }
  const std::size_t n = std::min(des.cols[0].size(), meas.cols[0].size());
  if (n < 2) throw std::runtime_error(fmt::format("{}: fewer than 2 rows", measured_path));
  auto head = [n](const std::vector<double>& v) { return std::vector<double>(v.begin(), v.begin() + static_cast<long>(n)); };
  BenchLog log;
  log.t = head(meas.cols[column(meas, "time")]);
  log.q = head(meas.cols[column(meas, "position")]);
  log.dq = head(meas.cols[column(meas, "velocity")]);
  log.tau = head(meas.cols[column(meas, "torque")]);
  log.q_cmd = head(des.cols[column(des, "position")]);
  log.dq_cmd = head(des.cols[column(des, "velocity")]);
  log.tau_ff = head(des.cols[column(des, "torque")]);
  const bool torque_mode = std::all_of(log.q_cmd.begin(), log.q_cmd.end(), [](double v) { return v == 0.0; }) &&
                           std::all_of(log.dq_cmd.begin(), log.dq_cmd.end(), [](double v) { return v == 0.0; });
  if (torque_mode) {
    log.kp.assign(n, 0.0);
    log.kd.assign(n, 0.0);
  }
  return log;
}

// A Rhoban BAM log (JSON): a header and per-sample entries; every key of the format is declared,
// those pmg does not use as raw nodes, so a misspelt key is an error.
struct BamEntry {
  double timestamp = 0.0, goal_position = 0.0, position = 0.0, speed = 0.0;
  bool torque_enable = false;
  YAML::Node input_volts, load, temp;
  template <class A>
  void Serialize(A* a) {
    a->Visit("timestamp", &timestamp, "[s]", yaml::kRequired);
    a->Visit("goal_position", &goal_position, "[rad]", yaml::kRequired);
    a->Visit("position", &position, "[rad]", yaml::kRequired);
    a->Visit("speed", &speed, "[rad/s]", yaml::kRequired);
    a->Visit("torque_enable", &torque_enable, "", yaml::kRequired);
    a->Visit("input_volts", &input_volts, "[V] (unused)");
    a->Visit("load", &load, "(unused)");
    a->Visit("temp", &temp, "(unused)");
  }
};

struct BamLog {
  double kp = 0.0;
  std::vector<BamEntry> entries;
  YAML::Node length, motor, mass, vin, trajectory;
  template <class A>
  void Serialize(A* a) {
    a->Visit("kp", &kp, "firmware P gain", yaml::kRequired);
    a->Visit("entries", &entries, "samples", yaml::kRequired);
    a->Visit("length", &length, "(unused)");
    a->Visit("motor", &motor, "(unused)");
    a->Visit("mass", &mass, "(unused)");
    a->Visit("vin", &vin, "(unused)");
    a->Visit("trajectory", &trajectory, "(unused)");
  }
  std::string validate() const {
    return entries.size() < 2 ? "entries: expected a list of at least 2 samples" : "";
  }
};

BenchLog from_bam_json(const std::string& path) {
  const BamLog bam = yaml::loadYamlFile<BamLog>(path);
  BenchLog log;
  for (const BamEntry& e : bam.entries) {
    log.t.push_back(e.timestamp);
    log.q_cmd.push_back(e.goal_position);
    log.q.push_back(e.position);
    log.dq.push_back(e.speed);
    log.enabled.push_back(e.torque_enable ? 1 : 0);
    log.kp.push_back(bam.kp);
  }
  return log;
}

void apply_window(BenchLog& log, double t0, double t1) {
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < log.size(); ++i)
    if (log.t[i] >= t0 && log.t[i] <= t1) keep.push_back(i);
  auto sub = [&](auto& v) {
    if (v.empty()) return;
    std::remove_reference_t<decltype(v)> out;
    out.reserve(keep.size());
    for (auto k : keep) out.push_back(v[k]);
    v.swap(out);
  };
  sub(log.t); sub(log.q_cmd); sub(log.q); sub(log.dq); sub(log.tau); sub(log.kp); sub(log.kd);
  sub(log.dq_cmd); sub(log.tau_ff); sub(log.enabled);
}

}  // namespace

void BenchLog::validate() const {
  const std::size_t n = t.size();
  if (n < 2) throw std::runtime_error(fmt::format("{}: needs at least 2 rows, has {}", name, n));
  auto same = [&](const auto& v, const char* col) {
    if (!v.empty() && v.size() != n)
      throw std::runtime_error(fmt::format("{}: column '{}' has {} rows, expected {}", name, col, v.size(), n));
  };
  if (q_cmd.size() != n || q.size() != n)
    throw std::runtime_error(fmt::format("{}: columns q_cmd and q must have {} rows", name, n));
  same(dq, "dq"); same(tau, "tau"); same(kp, "kp"); same(kd, "kd"); same(dq_cmd, "dq_cmd");
  same(tau_ff, "tau_ff"); same(enabled, "enabled");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(q_cmd[i]) || !std::isfinite(q[i]))
      throw std::runtime_error(fmt::format("{}: row {}: t, q_cmd and q must be finite", name, i));
    if (i > 0 && !(t[i] > t[i - 1]))
      throw std::runtime_error(fmt::format("{}: row {}: t = {} must be > previous t = {} (strictly increasing)",
                                           name, i, t[i], t[i - 1]));
  }
  for (const auto* v : {&dq, &tau, &kp, &kd, &dq_cmd, &tau_ff})
    for (double x : *v)
      if (!std::isfinite(x)) throw std::runtime_error(fmt::format("{}: optional column has a non-finite value", name));
}

BenchLog load_bench_log(const std::string& spec) {
  std::string path = spec;
  double t0 = -std::numeric_limits<double>::infinity();
  double t1 = std::numeric_limits<double>::infinity();
  const auto at = spec.rfind('@');
  if (at != std::string::npos) {
    path = spec.substr(0, at);
    const std::string win = spec.substr(at + 1);
    const auto colon = win.find(':');
    if (colon == std::string::npos)
      throw std::runtime_error(fmt::format("{}: time window must be '@t0:t1' (seconds), got '@{}'", spec, win));
    try {
      if (colon > 0) t0 = std::stod(win.substr(0, colon));
      if (colon + 1 < win.size()) t1 = std::stod(win.substr(colon + 1));
    } catch (const std::exception&) {
      throw std::runtime_error(fmt::format("{}: time window bounds must be numbers, got '@{}'", spec, win));
    }
    if (!(t1 > t0)) throw std::runtime_error(fmt::format("{}: time window needs t1 > t0", spec));
  }
  BenchLog log;
  const bool json = path.size() > 5 && path.substr(path.size() - 5) == ".json";
  if (json) {
    log = from_bam_json(path);
  } else {
    const Table tab = read_csv(path);
    if (column(tab, "q_cmd") >= 0 || column(tab, "t") >= 0)
      log = from_pmg_csv(path, tab);
    else if (column(tab, "time") >= 0 && column(tab, "position") >= 0)
      log = from_dfki(path, tab);
    else
      throw std::runtime_error(fmt::format("{}: unknown CSV header (expected t,q_cmd,q[,...] or DFKI "
                                           "time,position,velocity,torque)", path));
  }
  if (at != std::string::npos) apply_window(log, t0, t1);
  log.name = spec;
  log.validate();
  return log;
}

void write_bench_log_csv(const BenchLog& log, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write", path));
  std::vector<std::pair<std::string, const std::vector<double>*>> cols = {{"t", &log.t}, {"q_cmd", &log.q_cmd}, {"q", &log.q}};
  if (log.has_dq()) cols.push_back({"dq", &log.dq});
  if (log.has_tau()) cols.push_back({"tau", &log.tau});
  if (log.has_kp()) cols.push_back({"kp", &log.kp});
  if (log.has_kd()) cols.push_back({"kd", &log.kd});
  if (log.has_dq_cmd()) cols.push_back({"dq_cmd", &log.dq_cmd});
  if (log.has_tau_ff()) cols.push_back({"tau_ff", &log.tau_ff});
  for (std::size_t c = 0; c < cols.size(); ++c) out << (c ? "," : "") << cols[c].first;
  if (log.has_enabled()) out << ",enabled";
  out << "\n";
  for (std::size_t i = 0; i < log.size(); ++i) {
    for (std::size_t c = 0; c < cols.size(); ++c) out << (c ? "," : "") << fmt::format("{:.9g}", (*cols[c].second)[i]);
    if (log.has_enabled()) out << "," << static_cast<int>(log.enabled[i]);
    out << "\n";
  }
}

void RigConfig::validate() const {
  auto check = [&](bool ok, const char* field, const char* range, double v) {
    if (!ok) throw std::runtime_error(fmt::format("{}: {} = {}: expected {}", source_file, field, v, range));
  };
  check(std::isfinite(mass_kg) && mass_kg > 0, "rig.mass_kg", "> 0 kg", mass_kg);
  check(std::isfinite(com_m) && com_m >= 0, "rig.com_m", ">= 0 m", com_m);
  check(std::isfinite(link_inertia_kgm2) && link_inertia_kgm2 >= 0, "rig.link_inertia_kgm2", ">= 0 kg·m²", link_inertia_kgm2);
  check(std::isfinite(gravity_mps2) && gravity_mps2 >= 0, "rig.gravity_mps2", ">= 0 m/s²", gravity_mps2);
  check(std::isfinite(kp_Nm_per_rad) && kp_Nm_per_rad > 0, "motor.kp_Nm_per_rad", "> 0 N·m/rad", kp_Nm_per_rad);
  check(std::isfinite(kd_Nms_per_rad) && kd_Nms_per_rad > 0, "motor.kd_Nms_per_rad", "> 0 N·m·s/rad", kd_Nms_per_rad);
  check(std::isfinite(armature_kgm2) && armature_kgm2 >= 0, "motor.armature_kgm2", ">= 0 kg·m²", armature_kgm2);
  check(torque_limit_Nm > 0, "motor.torque_limit_Nm", "> 0 N·m", torque_limit_Nm);
  check(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 100000, "motor.rate_hz", "in (0, 100000] Hz", rate_hz);
  check(std::isfinite(log_gain_to_SI) && log_gain_to_SI > 0, "motor.log_gain_to_SI", "> 0", log_gain_to_SI);
  check(std::isfinite(sim_dt_s) && sim_dt_s > 0 && sim_dt_s <= 0.005, "sim.dt_s", "in (0, 0.005] s", sim_dt_s);
}

namespace {

enum class RigType { kPendulum };
std::vector<std::pair<std::string, RigType>> yamlEnumNames(RigType) { return {{"pendulum", RigType::kPendulum}}; }
enum class MotorControl { kPd };
std::vector<std::pair<std::string, MotorControl>> yamlEnumNames(MotorControl) { return {{"pd", MotorControl::kPd}}; }
enum class Encoder { kMotorSide, kLinkSide };
std::vector<std::pair<std::string, Encoder>> yamlEnumNames(Encoder) {
  return {{"motor_side", Encoder::kMotorSide}, {"link_side", Encoder::kLinkSide}};
}

// The rig file format (config/bench/*.yaml).
struct RigFile {
  RigConfig* c = nullptr;
  struct Rig {
    RigConfig* c = nullptr;
    RigType type = RigType::kPendulum;
    template <class A>
    void Serialize(A* a) {
      a->Visit("type", &type, "pendulum", yaml::kRequired);
      a->Visit("mass_kg", &c->mass_kg, "pendulum mass [kg]", yaml::kRequired);
      a->Visit("com_m", &c->com_m, "axis to centre of mass [m]", yaml::kRequired);
      a->Visit("link_inertia_kgm2", &c->link_inertia_kgm2, "about the centre of mass [kg m^2]");
      a->Visit("gravity_mps2", &c->gravity_mps2, "[m/s^2]");
    }
  } rig;
  struct Motor {
    RigConfig* c = nullptr;
    MotorControl control = MotorControl::kPd;
    Encoder encoder = Encoder::kMotorSide;
    template <class A>
    void Serialize(A* a) {
      a->Visit("control", &control, "pd");
      a->Visit("kp_Nm_per_rad", &c->kp_Nm_per_rad, "nominal stiffness [N m/rad]", yaml::kRequired);
      a->Visit("kd_Nms_per_rad", &c->kd_Nms_per_rad, "nominal damping [N m s/rad]", yaml::kRequired);
      a->Visit("armature_kgm2", &c->armature_kgm2, "rotor inertia at the joint [kg m^2]", yaml::kRequired);
      a->Visit("torque_limit_Nm", &c->torque_limit_Nm, "[N m] (absent = none)");
      a->Visit("rate_hz", &c->rate_hz, "driver PD rate [Hz]");
      a->Visit("encoder", &encoder, "motor_side | link_side");
      a->Visit("log_gain_to_SI", &c->log_gain_to_SI, "log kp/kd unit to SI");
    }
  } motor;
  struct Sim {
    RigConfig* c = nullptr;
    template <class A>
    void Serialize(A* a) {
      a->Visit("dt_s", &c->sim_dt_s, "physics step [s]");
    }
  } sim;
  template <class A>
  void Serialize(A* a) {
    a->Visit("rig", &rig, "the pendulum", yaml::kRequired);
    a->Visit("motor", &motor, "the driver", yaml::kRequired);
    a->Visit("sim", &sim, "rig simulation");
  }
};

}  // namespace

RigConfig load_rig_config(const std::string& path) {
  RigConfig c;
  c.source_file = path;
  RigFile f;
  f.c = f.rig.c = f.motor.c = f.sim.c = &c;
  yaml::readYaml(yaml::loadYamlDocument(path), &f);
  c.encoder_motor_side = f.motor.encoder == Encoder::kMotorSide;
  try {
    c.validate();
  } catch (const std::runtime_error& e) {
    throw ConfigError(e.what());  // names source_file, field and range
  }
  return c;
}

}  // namespace pmg::calib
