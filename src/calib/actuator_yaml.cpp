#include "pmg/calib/actuator_yaml.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg::calib {

void ActuatorBlock::validate(const std::string& where) const {
  try {
    params.validate();
  } catch (const std::invalid_argument& e) {
    std::string msg = e.what();
    const std::string prefix = "ActuatorParams.";
    if (msg.rfind(prefix, 0) == 0) msg = "actuator." + msg.substr(prefix.size());
    throw std::runtime_error(where + ": " + msg);
  }
  if (armature_kgm2 && !(std::isfinite(*armature_kgm2) && *armature_kgm2 >= 0))
    throw std::runtime_error(fmt::format("{}: actuator.armature_kgm2 = {}: expected >= 0 kg·m²", where, *armature_kgm2));
  if (!(std::isfinite(kp_scale) && kp_scale > 0))
    throw std::runtime_error(fmt::format("{}: actuator.kp_scale = {}: expected > 0", where, kp_scale));
  if (!(std::isfinite(kd_scale) && kd_scale > 0))
    throw std::runtime_error(fmt::format("{}: actuator.kd_scale = {}: expected > 0", where, kd_scale));
}

namespace {

// Reads and validates one block; `where` prefixes validate() messages.
ActuatorBlock read_block(const YAML::Node& map, const yaml::YamlSource& src, const std::string& where) {
  if (!map.IsMap()) {
    const std::string got = map.IsNull() ? "nothing" : map.IsSequence() ? "a list" : "'" + map.Scalar() + "'";
    yaml::fail(src, map, "expected a map of actuator parameters, got " + got);
  }
  ActuatorBlock b;
  yaml::readYaml(map, src, &b);
  try {
    b.validate(where);
  } catch (const std::runtime_error& e) {
    throw ConfigError(e.what());
  }
  return b;
}

// An actuator file: `actuator:` and nothing else.
struct ActuatorFile {
  YAML::Node actuator;
  template <class A>
  void Serialize(A* a) {
    a->Visit("actuator", &actuator, "the actuator block", yaml::kRequired);
  }
};

}  // namespace

ActuatorBlock parse_actuator_block(const YAML::Node& map, const std::string& where) {
  return read_block(map, yaml::YamlSource{where, "", "actuator", false}, where);
}

YAML::Node actuator_block_to_yaml(const ActuatorBlock& b) {
  YAML::Node n;
  const ActuatorParams& p = b.params;
  if (b.armature_kgm2) n["armature_kgm2"] = *b.armature_kgm2;
  n["kp_scale"] = b.kp_scale;
  n["kd_scale"] = b.kd_scale;
  n["rate_hz"] = p.rate_hz;
  n["torque_limit_Nm"] = p.torque_limit_Nm;
  auto put = [&](const char* k, double v) {
    if (v != 0.0) n[k] = v;
  };
  put("delay_s", p.delay_s);
  if (p.kt_scale != 1.0) n["kt_scale"] = p.kt_scale;
  put("offset_rad", p.offset_rad);
  put("tau_stall_Nm", p.tau_stall_Nm);
  put("w_max_rad_per_s", p.w_max_rad_per_s);
  put("fc_Nm", p.fc_Nm);
  put("fs_Nm", p.fs_Nm);
  if (p.fs_Nm != 0.0) n["vs_rad_per_s"] = p.vs_rad_per_s;
  put("kl", p.kl);
  put("fv_Nms_per_rad", p.fv_Nms_per_rad);
  put("backlash_gap_rad", p.backlash_gap_rad);
  return n;
}

ActuatorBlock load_actuator_file(const std::string& path) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  ActuatorFile f;
  yaml::readYaml(doc, &f);
  const yaml::YamlSource src = yaml::childSource(doc.source, "actuator");
  return read_block(f.actuator, src, yaml::location(doc.source, f.actuator));
}

void write_actuator_file(const std::string& path, const ActuatorBlock& block, const std::string& comment) {
  block.validate(path);
  YAML::Node root;
  root["actuator"] = actuator_block_to_yaml(block);
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  std::istringstream lines(comment);
  std::string line;
  while (std::getline(lines, line)) out << "# " << line << "\n";
  YAML::Emitter em;
  em.SetDoublePrecision(6);
  em << root;
  out << em.c_str() << "\n";
}

ActuatorBlock actuator_block_from_params(const RigConfig& rig, const std::map<std::string, double>& params) {
  auto get = [&](const char* k, double dflt) {
    const auto it = params.find(k);
    return it == params.end() ? dflt : it->second;
  };
  ActuatorBlock b;
  ActuatorParams& a = b.params;
  a.rate_hz = rig.rate_hz;
  a.torque_limit_Nm = get("tau_max_Nm", rig.torque_limit_Nm);
  a.tau_stall_Nm = get("tau_stall_Nm", 0.0);
  a.w_max_rad_per_s = get("w_max_rad_per_s", 0.0);
  a.fc_Nm = get("fc_Nm", 0.0);
  a.fs_Nm = get("fs_Nm", 0.0);
  a.vs_rad_per_s = get("vs_rad_per_s", 0.1);
  a.kl = get("kl", 0.0);
  a.fv_Nms_per_rad = get("fv_Nms_per_rad", 0.0);
  a.delay_s = get("delay_s", 0.0);
  a.kt_scale = get("kt_scale", 1.0);
  a.offset_rad = get("offset_rad", 0.0);
  a.backlash_gap_rad = get("gap_rad", 0.0);
  b.armature_kgm2 = get("armature", rig.armature_kgm2);
  b.kp_scale = get("kp_scale", 1.0);
  b.kd_scale = get("kd_scale", 1.0);
  return b;
}

}  // namespace pmg::calib
