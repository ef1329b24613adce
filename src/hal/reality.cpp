// The hidden truth of a SIL robot (include/pmg/hal/reality.hpp).
#include "pmg/hal/reality.hpp"

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "pmg/common/config_error.hpp"
#include "pmg/common/yaml_archive.hpp"

namespace pmg::hal {

std::string LinkError::validate() const {
  if (!(std::isfinite(mass_scale) && mass_scale >= 0.5 && mass_scale <= 2.0)) {
    std::ostringstream s;
    s << "mass_scale = " << mass_scale << ": expected 0.5..2";
    return s.str();
  }
  return "";
}

std::vector<std::string> Reality::affectedJoints(const RobotConfig& robot) const {
  std::vector<std::string> out;
  for (const auto& j : robot.joints) {
    const auto z = zero_offsets.find(j.name);
    if (joints.count(j.name) || (z != zero_offsets.end() && z->second != 0.0)) out.push_back(j.name);
  }
  return out;
}

namespace {

std::vector<std::string> jointNames(const RobotConfig& robot) {
  std::vector<std::string> names;
  for (const auto& j : robot.joints) names.push_back(j.name);
  return names;
}

void checkJoint(const std::string& path, const std::string& key, const std::string& name,
                const std::vector<std::string>& names) {
  for (const auto& n : names)
    if (n == name) return;
  throw ConfigError(path + ": " + key + "." + name + ": not a joint of the robot (did you mean '" +
                    yaml::nearestKey(name, names) + "'?)");
}

}  // namespace

Reality loadReality(const std::string& path, const RobotConfig& robot) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  Reality r;
  if (!doc.root.IsNull()) yaml::readYaml(doc, &r);
  r.source = path;
  const std::vector<std::string> names = jointNames(robot);
  for (const auto& [name, block] : r.joints) {
    checkJoint(path, "joints", name, names);
    const std::string where = path + ": joints." + name;
    try {
      block.validate(where);
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      throw ConfigError(e.what());
    }
    if (block.params.backlash_gap_rad > 0.0)
      throw ConfigError(where + ".backlash_gap_rad: the G1 SIL has no rotor bodies to model backlash (expected 0)");
  }
  for (const auto& [name, offset] : r.zero_offsets) {
    checkJoint(path, "zero_offsets", name, names);
    if (!(std::fabs(offset) <= 0.5)) {
      std::ostringstream s;
      s << path << ": zero_offsets." << name << " = " << offset << ": expected |offset| <= 0.5 rad";
      throw ConfigError(s.str());
    }
  }
  for (const auto& [name, link] : r.links)
    if (const std::string e = link.validate(); !e.empty()) throw ConfigError(path + ": links." + name + "." + e);
  return r;
}

void applyReality(const Reality& reality, RobotConfig* robot, MujocoBackendOptions* options) {
  const std::size_t n = robot->numJoints();
  if (options->encoder_offsets.empty()) options->encoder_offsets.assign(n, 0.0);
  if (options->encoder_offsets.size() != n)
    throw ConfigError("applyReality: the backend has " + std::to_string(options->encoder_offsets.size()) +
                      " encoder offsets, expected " + std::to_string(n));
  const std::string src = reality.source.empty() ? std::string("(drawn reality)") : reality.source;
  for (std::size_t i = 0; i < n; ++i) {
    JointConfig& j = robot->joints[i];
    if (const auto it = reality.joints.find(j.name); it != reality.joints.end()) {
      j.actuator_yaml = YAML::Dump(calib::actuator_block_to_yaml(it->second));
      j.actuator_source = src + ": joints." + j.name;
    }
    if (const auto it = reality.zero_offsets.find(j.name); it != reality.zero_offsets.end())
      options->encoder_offsets[i] += it->second;
  }
  for (const auto& [name, link] : reality.links) options->body_mass_scale[name] = link.mass_scale;
}

const std::vector<std::string>& drawableEffects() {
  static const std::vector<std::string> kEffects{"coulomb_friction", "viscous_friction", "transport_delay",
                                                 "armature", "pd_gain"};
  return kEffects;
}

std::string drawnEffectName(const calib::ActuatorBlock& b) {
  if (b.params.fc_Nm > 0.0) return "coulomb_friction";
  if (b.params.fv_Nms_per_rad > 0.0) return "viscous_friction";
  if (b.params.delay_s > 0.0) return "transport_delay";
  if (b.armature_kgm2) return "armature";
  if (b.kp_scale != 1.0) return "pd_gain";
  return "";
}

Reality drawReality(const RobotConfig& robot, std::uint64_t seed, const RealityDrawOptions& o) {
  constexpr int kLegs = 12;
  if (robot.numJoints() < static_cast<std::size_t>(kLegs))
    throw ConfigError("drawReality: the robot has " + std::to_string(robot.numJoints()) + " joints, expected >= 12 (legs first)");
  if (o.joints < 0 || o.joints > kLegs) throw ConfigError("drawReality: joints = " + std::to_string(o.joints) + ": expected 0..12");
  if (o.zero_offsets < -1 || o.zero_offsets > kLegs)
    throw ConfigError("drawReality: zero_offsets = " + std::to_string(o.zero_offsets) + ": expected -1..12");
  std::mt19937_64 rng(seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  auto pick = [&](int k) {  // k distinct leg joints, in joint order
    std::vector<int> idx(kLegs);
    std::iota(idx.begin(), idx.end(), 0);
    std::shuffle(idx.begin(), idx.end(), rng);
    idx.resize(static_cast<std::size_t>(k));
    std::sort(idx.begin(), idx.end());
    return idx;
  };
  Reality r;
  const int n_effects = o.joints > 0 ? o.joints : integer(4, 6);
  const auto& effects = drawableEffects();
  for (int i : pick(n_effects)) {
    calib::ActuatorBlock b;
    const std::string& e = effects[static_cast<std::size_t>(integer(0, static_cast<int>(effects.size()) - 1))];
    if (e == "coulomb_friction") b.params.fc_Nm = uniform(1.0, 3.0);
    if (e == "viscous_friction") b.params.fv_Nms_per_rad = uniform(0.5, 2.0);
    if (e == "transport_delay") b.params.delay_s = uniform(0.004, 0.012);
    if (e == "armature") b.armature_kgm2 = uniform(0.02, 0.05);
    if (e == "pd_gain") {
      const double m = uniform(0.12, 0.25);
      b.kp_scale = integer(0, 1) ? 1.0 + m : 1.0 - m;
    }
    r.joints[robot.joints[static_cast<std::size_t>(i)].name] = b;
  }
  const int n_zero = o.zero_offsets >= 0 ? o.zero_offsets : integer(2, 4);
  for (int i : pick(n_zero))
    r.zero_offsets[robot.joints[static_cast<std::size_t>(i)].name] = (integer(0, 1) ? 1.0 : -1.0) * uniform(0.01, 0.05);
  if (o.links && integer(0, 1)) r.links["torso_link"].mass_scale = uniform(0.95, 1.10);
  return r;
}

namespace {

// The block without the keys at their defaults (compact, readable reality files).
YAML::Node compactBlock(const calib::ActuatorBlock& b) {
  YAML::Node full = calib::actuator_block_to_yaml(b);
  YAML::Node out(YAML::NodeType::Map);
  for (const auto& kv : full) {
    const std::string k = kv.first.as<std::string>();
    const double v = kv.second.as<double>();
    if ((k == "kp_scale" || k == "kd_scale") && v == 1.0) continue;
    if (k == "rate_hz" && v == 0.0) continue;
    if (k == "torque_limit_Nm" && std::isinf(v)) continue;
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);  // 6 significant digits, as the rest of the file
    out[k] = std::string(text);
  }
  return out;
}

}  // namespace

void writeReality(const std::string& path, const Reality& reality, const std::string& comment) {
  YAML::Emitter em;
  em.SetDoublePrecision(6);
  em << YAML::BeginMap;
  em << YAML::Key << "joints" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, block] : reality.joints)
    em << YAML::Key << name << YAML::Value << YAML::Flow << compactBlock(block) << YAML::Block;
  em << YAML::EndMap;
  em << YAML::Key << "zero_offsets" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, offset] : reality.zero_offsets) em << YAML::Key << name << YAML::Value << offset;
  em << YAML::EndMap;
  em << YAML::Key << "links" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, link] : reality.links)
    em << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "mass_scale"
       << YAML::Value << link.mass_scale << YAML::EndMap << YAML::Block;
  em << YAML::EndMap;
  em << YAML::EndMap;
  std::ofstream out(path);
  if (!out) throw ConfigError(path + ": cannot write the reality file");
  std::istringstream lines(comment);
  std::string line;
  while (std::getline(lines, line)) out << "# " << line << "\n";
  out << em.c_str() << "\n";
  if (!out) throw ConfigError(path + ": write failed");
}

}  // namespace pmg::hal
