#include "pmg/controller/controller_config.hpp"

#include <cmath>
#include <filesystem>

#include <yaml-cpp/yaml.h>

namespace pmg {
namespace {
namespace fs = std::filesystem;

template <typename T>
T get(const YAML::Node& node, const char* key, const T& fallback, const std::string& where) {
  if (!node || !node[key]) return fallback;
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception&) {
    throw ConfigError(where + "." + key + ": cannot read '" + YAML::Dump(node[key]) + "' as the expected type");
  }
}

template <std::size_t N>
std::array<double, N> getArray(const YAML::Node& node, const char* key, const std::array<double, N>& fallback,
                               const std::string& where) {
  if (!node || !node[key]) return fallback;
  const auto v = get<std::vector<double>>(node, key, {}, where);
  if (v.size() != N) throw ConfigError(where + "." + key + ": expected " + std::to_string(N) + " numbers");
  std::array<double, N> a{};
  for (std::size_t i = 0; i < N; ++i) a[i] = v[i];
  return a;
}
}  // namespace

ControllerConfig loadControllerConfig(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  ControllerConfig c;
  c.source_file = path;
  const fs::path dir = fs::absolute(fs::path(path)).parent_path();
  const std::string f = path + ": ";
  if (!root["robot"]) throw ConfigError(f + "robot: missing (path of the robot config)");
  if (!root["clips"]) throw ConfigError(f + "clips: missing (folder of the clip library)");
  c.robot_file = (dir / root["robot"].as<std::string>()).lexically_normal().string();
  c.clips_dir = (dir / root["clips"].as<std::string>()).lexically_normal().string();
  if (!fs::is_directory(c.clips_dir)) throw ConfigError(f + "clips: folder '" + c.clips_dir + "' not found");
  c.robot = loadRobotConfig(c.robot_file);

  const std::string backend = get<std::string>(root, "backend", "mujoco", path + ": backend");
  if (backend == "mujoco") {
    c.backend = BackendKind::kMujoco;
  } else if (backend == "can") {
    c.backend = BackendKind::kCan;
    c.hal_supervisor = true;
  } else {
    throw ConfigError(f + "backend: '" + backend + "': expected mujoco or can");
  }
  const YAML::Node can = root["can"];
  const std::string canw = path + ": can";
  if (can && can["plan"])
    c.can.plan_file = (dir / get<std::string>(can, "plan", "", canw)).lexically_normal().string();
  c.can.transport = get<std::string>(can, "transport", c.can.transport, canw);
  c.can.udp_port = get<int>(can, "udp_port", c.can.udp_port, canw);
  c.can.paced = get<bool>(can, "paced", false, canw);
  if (c.can.transport != "udp" && c.can.transport != "socketcan")
    throw ConfigError(canw + ".transport: '" + c.can.transport + "': expected udp or socketcan");
  if (c.can.udp_port < 1024 || c.can.udp_port > 65000) throw ConfigError(canw + ".udp_port: expected 1024..65000");
  if (c.backend == BackendKind::kCan && !fs::exists(c.can.plan_file))
    throw ConfigError(canw + ".plan: bus plan '" + c.can.plan_file + "' not found (required with backend: can)");

  const YAML::Node t = root["timing"];
  const std::string w = path + ": timing";
  const std::string mode = get<std::string>(t, "mode", "lockstep", w);
  if (mode == "lockstep")
    c.timing = TimingMode::kLockstep;
  else if (mode == "realtime")
    c.timing = TimingMode::kRealtime;
  else
    throw ConfigError(w + ".mode: '" + mode + "': expected lockstep or realtime");
  c.loop_rate_hz = get<double>(t, "loop_rate_hz", 100.0, w);
  c.hal_rate_hz = get<double>(t, "hal_rate_hz", 500.0, w);
  c.loop_fifo_priority = get<int>(t, "loop_fifo_priority", 0, w);
  c.hal.fifo_priority = get<int>(t, "hal_fifo_priority", 0, w);
  c.hal.cpu = get<int>(t, "hal_cpu", -1, w);
  c.lock_memory = get<bool>(t, "lock_memory", false, w);
  if (!(c.loop_rate_hz >= 10 && c.loop_rate_hz <= 1000)) throw ConfigError(w + ".loop_rate_hz: expected 10..1000 Hz");
  const double ratio = c.hal_rate_hz / c.loop_rate_hz;
  if (!(ratio >= 1 && std::fabs(ratio - std::round(ratio)) < 1e-9 && c.hal_rate_hz <= 4000))
    throw ConfigError(w + ".hal_rate_hz: expected an integer multiple of loop_rate_hz, <= 4000 Hz");
  for (int prio : {c.loop_fifo_priority, c.hal.fifo_priority})
    if (prio < 0 || prio > 99) throw ConfigError(w + ".*_fifo_priority: expected 0..99");

  const YAML::Node m = root["mujoco"];
  const std::string mw = path + ": mujoco";
  c.mujoco.timestep = get<double>(m, "timestep", 0.001, mw);
  c.mujoco.cycle_period = 1.0 / c.hal_rate_hz;
  c.mujoco.encoder_offsets = get<std::vector<double>>(m, "encoder_offsets", {}, mw);
  const YAML::Node g = m ? m["gantry"] : YAML::Node();
  const std::string gw = mw + ".gantry";
  c.mujoco.gantry.enabled = get<bool>(g, "enabled", true, gw);
  c.mujoco.gantry.anchor_height = get<double>(g, "anchor_height", 0.95, gw);
  c.mujoco.gantry.stiffness = get<double>(g, "stiffness", 4000.0, gw);
  c.mujoco.gantry.damping = get<double>(g, "damping", 400.0, gw);
  c.mujoco.gantry.rot_stiffness = get<double>(g, "rot_stiffness", 800.0, gw);
  c.mujoco.gantry.rot_damping = get<double>(g, "rot_damping", 60.0, gw);
  if (const std::string e = c.mujoco.validate(); !e.empty()) throw ConfigError(f + e);

  const YAML::Node gen = root["generator"];
  c.generator.epsilon = get<double>(gen, "epsilon", c.generator.epsilon, path + ": generator");
  c.generator.max_command = getArray<3>(gen, "max_command", c.generator.max_command, path + ": generator");
  if (const std::string e = c.generator.validate(); !e.empty()) throw ConfigError(f + e);

  if (root["gco"]) {
    c.gco_file = (dir / get<std::string>(root, "gco", "", path + ": gco")).lexically_normal().string();
    c.gco = gco::loadGcoOptionsFile(c.gco_file);  // throws naming the file and field
  }
  if (root["gco_enabled"]) c.gco.enabled = get<bool>(root, "gco_enabled", true, path + ": gco_enabled");

  const YAML::Node cmd = root["commands"];
  const std::string cw = path + ": commands";
  c.commands.timeout = get<double>(cmd, "timeout_s", c.commands.timeout, cw);
  c.commands.max_velocity = getArray<3>(cmd, "max_velocity", c.commands.max_velocity, cw);
  c.commands.max_acceleration = getArray<3>(cmd, "max_acceleration", c.commands.max_acceleration, cw);
  c.commands.posture_min = getArray<3>(cmd, "posture_min", c.commands.posture_min, cw);
  c.commands.posture_max = getArray<3>(cmd, "posture_max", c.commands.posture_max, cw);
  c.commands.posture_rate = get<double>(cmd, "posture_rate", c.commands.posture_rate, cw);
  if (const std::string e = c.commands.validate(); !e.empty()) throw ConfigError(f + e);

  const YAML::Node s = root["safety"];
  c.soft_stand_duration = get<double>(s, "soft_stand_duration_s", 1.0, path + ": safety");
  c.damping_kd_scale = get<double>(s, "damping_kd_scale", 1.0, path + ": safety");
  c.hal_supervisor = get<bool>(s, "hal_supervisor", c.hal_supervisor, path + ": safety");
  c.max_invalid_ticks = get<int>(s, "max_invalid_ticks", 3, path + ": safety");
  if (c.max_invalid_ticks < 0 || c.max_invalid_ticks > 50)
    throw ConfigError(f + "safety.max_invalid_ticks: expected 0..50 ticks");
  if (!(c.soft_stand_duration >= 0 && c.soft_stand_duration <= 10))
    throw ConfigError(f + "safety.soft_stand_duration_s: expected 0..10 s");
  if (!(c.damping_kd_scale > 0 && c.damping_kd_scale <= 5)) throw ConfigError(f + "safety.damping_kd_scale: expected (0, 5]");

  const YAML::Node pol = root["policy"];
  if (pol && pol["model"]) {
    c.policy_file = (dir / get<std::string>(pol, "model", "", path + ": policy")).lexically_normal().string();
    if (!fs::exists(c.policy_file)) throw ConfigError(f + "policy.model: '" + c.policy_file + "' not found");
    const std::string engine = get<std::string>(pol, "backend", "native", path + ": policy");
    if (engine != "native" && engine != "onnxruntime")
      throw ConfigError(f + "policy.backend: '" + engine + "': expected native or onnxruntime");
    c.policy_native = engine == "native";
  }

  const YAML::Node tel = root["telemetry"];
  c.lcm_enabled = get<bool>(tel, "lcm", true, path + ": telemetry");
  c.lcm_url = get<std::string>(tel, "lcm_url", c.lcm_url, path + ": telemetry");
  const std::string log = get<std::string>(tel, "log_file", "", path + ": telemetry");
  c.log_file = log.empty() ? "" : (fs::path(log).is_absolute() ? log : fs::absolute(log).string());
  return c;
}

}  // namespace pmg
