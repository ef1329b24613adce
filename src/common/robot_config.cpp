#include "pmg/common/robot_config.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "pmg/common/yaml_archive.hpp"

namespace pmg {
namespace {

namespace fs = std::filesystem;

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

int RobotConfig::jointIndex(const std::string& joint_name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint_name) return static_cast<int>(i);
  return -1;
}

#define PMG_JOINT_VECTOR(fn, field)                                  \
  Eigen::VectorXd RobotConfig::fn() const {                          \
    Eigen::VectorXd v(static_cast<Eigen::Index>(joints.size()));     \
    for (std::size_t i = 0; i < joints.size(); ++i)                  \
      v[static_cast<Eigen::Index>(i)] = joints[i].field;             \
    return v;                                                        \
  }
PMG_JOINT_VECTOR(defaultPose, default_position)
PMG_JOINT_VECTOR(lowerLimits, lower)
PMG_JOINT_VECTOR(zeroOffsets, zero_offset)
PMG_JOINT_VECTOR(upperLimits, upper)
PMG_JOINT_VECTOR(kp, kp)
PMG_JOINT_VECTOR(kd, kd)
PMG_JOINT_VECTOR(torqueLimits, torque_limit)
#undef PMG_JOINT_VECTOR

std::vector<int> RobotConfig::mirrorIndex() const {
  std::vector<int> idx(joints.size(), -1);
  for (std::size_t i = 0; i < joints.size(); ++i) idx[i] = jointIndex(joints[i].mirror);
  return idx;
}

std::vector<std::string> RobotConfig::jointNames() const {
  std::vector<std::string> names;
  names.reserve(joints.size());
  for (const auto& j : joints) names.push_back(j.name);
  return names;
}

namespace {

// One problem found by checkConfig(): the joint it concerns (-1 = none), the key path and what is wrong.
struct Problem {
  int joint = -1;
  std::string key;
  std::string what;
  std::string text() const { return key + (what.rfind("= ", 0) == 0 ? " " : ": ") + what; }
};

std::optional<Problem> checkConfig(const RobotConfig& c) {
  if (c.joints.empty()) return Problem{-1, "joints", "empty: expected at least one joint"};
  if (!(c.standing_base_height > 0.05 && c.standing_base_height < 3.0))
    return Problem{-1, "robot.standing_base_height", "= " + num(c.standing_base_height) + ": expected in (0.05, 3) m"};
  std::set<std::string> names;
  std::map<std::pair<std::string, int>, std::string> bus_ids;
  for (std::size_t i = 0; i < c.joints.size(); ++i) {
    const auto& j = c.joints[i];
    const int ji = static_cast<int>(i);
    const std::string k = "joints[" + std::to_string(i) + "] (" + j.name + ")";
    auto bad = [&](const std::string& field, const std::string& what) { return Problem{ji, k + "." + field, what}; };
    if (j.name.empty()) return bad("name", "empty");
    if (!names.insert(j.name).second) return bad("name", "duplicate joint name");
    for (const auto& [v, field] : {std::pair<double, const char*>{j.lower, "lower"}, {j.upper, "upper"},
                                   {j.velocity_limit, "velocity_limit"}, {j.torque_limit, "torque_limit"},
                                   {j.kp, "kp"}, {j.kd, "kd"}, {j.default_position, "default"}}) {
      if (!std::isfinite(v)) return bad(field, "is not a finite number");
    }
    if (!(j.lower < j.upper))
      return bad("lower/upper", "= [" + num(j.lower) + ", " + num(j.upper) + "]: expected lower < upper");
    if (!(j.velocity_limit > 0)) return bad("velocity_limit", "= " + num(j.velocity_limit) + ": expected > 0 rad/s");
    if (!(j.torque_limit > 0)) return bad("torque_limit", "= " + num(j.torque_limit) + ": expected > 0 N*m");
    if (!(j.kp >= 0 && j.kp <= 5000)) return bad("kp", "= " + num(j.kp) + ": expected 0..5000 N*m/rad");
    if (!(j.kd >= 0 && j.kd <= 500)) return bad("kd", "= " + num(j.kd) + ": expected 0..500 N*m*s/rad");
    if (j.default_position < j.lower || j.default_position > j.upper)
      return bad("default", "= " + num(j.default_position) + ": expected within [" + num(j.lower) + ", " +
                                num(j.upper) + "]");
    if (j.bus.empty()) return bad("bus", "empty: expected the name of a motor bus, e.g. can0");
    if (j.motor_id < 1 || j.motor_id > 254)
      return bad("motor_id", "= " + std::to_string(j.motor_id) + ": expected 1..254");
    const auto [it, fresh] = bus_ids.emplace(std::make_pair(j.bus, j.motor_id), j.name);
    if (!fresh)
      return bad("motor_id", "= " + std::to_string(j.motor_id) + ": duplicate id on bus " + j.bus + " (also " +
                                 it->second + ")");
    if (j.mirror_sign != 1 && j.mirror_sign != -1)
      return bad("mirror_sign", "= " + std::to_string(j.mirror_sign) + ": expected 1 or -1");
    if (!std::isfinite(j.zero_offset) || std::fabs(j.zero_offset) > 0.5)
      return bad("zero_offset", "= " + num(j.zero_offset) + ": expected finite, |offset| <= 0.5 rad");
  }
  for (std::size_t i = 0; i < c.joints.size(); ++i) {
    const auto& j = c.joints[i];
    const int ji = static_cast<int>(i);
    const std::string k = "joints[" + std::to_string(i) + "] (" + j.name + ")";
    const int m = c.jointIndex(j.mirror);
    if (m < 0) return Problem{ji, k + ".mirror", "= '" + j.mirror + "': not a joint of this robot"};
    const auto& partner = c.joints[static_cast<std::size_t>(m)];
    if (partner.mirror != j.name)
      return Problem{ji, k + ".mirror",
                     "= '" + j.mirror + "' whose mirror is '" + partner.mirror + "': expected a pairwise map"};
    if (partner.mirror_sign != j.mirror_sign)
      return Problem{ji, k + ".mirror_sign", "differs from the sign of its partner '" + partner.name + "'"};
  }
  if (!c.urdf_path.empty() && !fs::exists(c.urdf_path))
    return Problem{-1, "robot.urdf", "file '" + c.urdf_path + "' not found"};
  if (!c.mjcf_path.empty() && !fs::exists(c.mjcf_path))
    return Problem{-1, "robot.mjcf", "file '" + c.mjcf_path + "' not found"};
  return std::nullopt;
}

// ---- the file format (read with pmg::yaml) ----

struct RobotSection {
  RobotConfig* c = nullptr;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &c->name, "robot model name", yaml::kRequired);
    a->Visit("urdf", &c->urdf_path, "URDF file (kinematics), relative to this file", yaml::kRequired | yaml::kPath);
    a->Visit("mjcf", &c->mjcf_path, "MJCF file (simulation), relative to this file", yaml::kRequired | yaml::kPath);
    a->Visit("base_link", &c->base_link, "floating-base link", yaml::kRequired);
    a->Visit("left_foot_link", &c->left_foot_link, "left sole link", yaml::kRequired);
    a->Visit("right_foot_link", &c->right_foot_link, "right sole link", yaml::kRequired);
    a->Visit("imu_site", &c->imu_site, "MJCF site of the IMU", yaml::kRequired);
    a->Visit("standing_base_height", &c->standing_base_height, "pelvis height in the default pose [m]");
  }
};

struct JointEntry {
  JointConfig j;
  YAML::Node actuator;
  std::map<std::string, double> actuator_uncertainty;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &j.name, "joint name as in URDF/MJCF", yaml::kRequired);
    a->Visit("lower", &j.lower, "position lower limit [rad]", yaml::kRequired);
    a->Visit("upper", &j.upper, "position upper limit [rad]", yaml::kRequired);
    a->Visit("velocity_limit", &j.velocity_limit, "|qd| limit [rad/s]", yaml::kRequired);
    a->Visit("torque_limit", &j.torque_limit, "|tau| limit [N*m]", yaml::kRequired);
    a->Visit("kp", &j.kp, "motor-level PD stiffness [N*m/rad]", yaml::kRequired);
    a->Visit("kd", &j.kd, "motor-level PD damping [N*m*s/rad]", yaml::kRequired);
    a->Visit("default", &j.default_position, "default standing pose [rad]", yaml::kRequired);
    a->Visit("bus", &j.bus, "motor bus name, e.g. can0", yaml::kRequired);
    a->Visit("motor_id", &j.motor_id, "motor driver id on its bus, 1..254", yaml::kRequired);
    a->Visit("mirror", &j.mirror, "left/right mirror joint (default: itself)");
    a->Visit("mirror_sign", &j.mirror_sign, "q_mirror = mirror_sign * q (+-1)");
    a->Visit("actuator", &actuator, "actuator model: a map or the path of an actuator file");
    a->Visit("actuator_uncertainty", &actuator_uncertainty,
             "uncertainty of the identified actuator parameters {key: value >= 0}, same units (pmg_calib_joints)");
  }
};

struct RobotFile {
  RobotSection robot;
  std::vector<JointEntry> joints;
  YAML::Node zero_offsets;
  template <class A>
  void Serialize(A* a) {
    a->Visit("robot", &robot, "model files and links", yaml::kRequired);
    a->Visit("joints", &joints, "actuated joints in motor order", yaml::kRequired);
    a->Visit("zero_offsets", &zero_offsets, "{joint: offset_rad} or the path of a pmg_calib_zero result");
  }
};

// A pmg_calib_zero result file (calib/zero_io.cpp writes it): the offsets plus the calibration record.
struct ZeroResultFile {
  YAML::Node zero_offsets, calibration, placement, duration, drift, poses;
  template <class A>
  void Serialize(A* a) {
    a->Visit("zero_offsets", &zero_offsets, "{joint: offset_rad}", yaml::kRequired);
    a->Visit("calibration", &calibration, "solver record");
    a->Visit("placement_right_sole_in_left", &placement, "[x, y, yaw]");
    a->Visit("capture_duration_s", &duration, "[s]");
    a->Visit("home_drift_rad", &drift, "[rad]");
    a->Visit("poses", &poses, "per-pose status");
  }
};

// Applies a {joint_name: offset_rad} map; unknown joints are named with the nearest joint.
void readZeroOffsetMap(const YAML::Node& map, const yaml::YamlSource& src, const RobotConfig& robot,
                       std::vector<double>* out) {
  if (!map.IsMap()) yaml::fail(src, map, "expected a map {joint_name: offset_rad}");
  const std::map<std::string, double> values = [&] {
    std::map<std::string, double> v;
    yaml::readYaml(map, src, &v);
    return v;
  }();
  const std::vector<std::string> names = robot.jointNames();
  for (const auto& kv : map) {
    const std::string name = kv.first.Scalar();
    const int i = robot.jointIndex(name);
    if (i < 0)
      yaml::fail(src, kv.first, "'" + name + "' is not a joint of " + robot.source_file + " (did you mean '" +
                                    yaml::nearestKey(name, names) + "'?)");
    const double v = values.at(name);
    if (std::fabs(v) > 0.5)
      yaml::fail(yaml::childSource(src, name), kv.second, "expected |offset| <= 0.5 rad, got " + kv.second.Scalar());
    (*out)[static_cast<std::size_t>(i)] = v;
  }
}

std::vector<double> readZeroOffsetDocument(const yaml::YamlDocument& doc, const RobotConfig& robot) {
  std::vector<double> out(robot.numJoints(), 0.0);
  if (doc.root.IsMap() && doc.root["zero_offsets"]) {
    ZeroResultFile f;
    yaml::readYaml(doc, &f);
    readZeroOffsetMap(f.zero_offsets, yaml::childSource(doc.source, "zero_offsets"), robot, &out);
  } else {
    readZeroOffsetMap(doc.root, doc.source, robot, &out);
  }
  return out;
}

}  // namespace

std::string RobotConfig::validate() const {
  const auto p = checkConfig(*this);
  return p ? p->text() : std::string();
}

void validate(const RobotConfig& c) {
  const std::string msg = c.validate();
  const std::string& f = c.source_file.empty() ? std::string("<robot config>") : c.source_file;
  if (!msg.empty()) throw ConfigError(f + ": " + msg);
}

std::vector<double> loadZeroOffsetFile(const std::string& path, const RobotConfig& robot) {
  return readZeroOffsetDocument(yaml::loadYamlDocument(path), robot);
}

std::string robotConfigTextWithModelPaths(const RobotConfig& robot) {
  std::ifstream in(robot.source_file);
  if (!in) throw ConfigError(robot.source_file + ": cannot read the robot config");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  for (const auto& [key, path] : {std::pair{"urdf", robot.urdf_path}, std::pair{"mjcf", robot.mjcf_path}})
    text = std::regex_replace(text, std::regex(std::string(R"((\n\s*)") + key + R"(:\s*)[^\s#]+)"), "$1" + path);
  return text;
}

RobotConfig loadRobotConfig(const std::string& yaml_path) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(yaml_path);
  RobotConfig c;
  c.source_file = yaml_path;
  RobotFile file;
  file.robot.c = &c;
  yaml::readYaml(doc, &file);
  const yaml::YamlSource joints_src = yaml::childSource(doc.source, "joints");
  const YAML::Node joints_node = doc.root["joints"];
  for (std::size_t i = 0; i < file.joints.size(); ++i) {
    JointEntry& e = file.joints[i];
    if (e.j.mirror.empty()) e.j.mirror = e.j.name;
    std::vector<std::string> block_keys;  // the keys the actuator block names
    if (const YAML::Node& a = e.actuator; !a.IsNull()) {
      const yaml::YamlSource asrc = yaml::childSource(yaml::itemSource(joints_src, i), "actuator");
      if (a.IsScalar()) {  // path of an actuator file with a top-level `actuator:` map
        const std::string afile = (fs::path(doc.source.base_dir) / a.Scalar()).lexically_normal().string();
        yaml::YamlDocument adoc;
        try {
          adoc = yaml::loadYamlDocument(afile);
        } catch (const ConfigError& err) {
          yaml::fail(asrc, a, std::string("cannot read actuator file: ") + err.what());
        }
        if (!adoc.root.IsMap() || !adoc.root["actuator"] || !adoc.root["actuator"].IsMap())
          yaml::fail(asrc, a, "file '" + afile + "' has no top-level `actuator:` map");
        if (adoc.root.size() != 1) {
          for (const auto& kv : adoc.root)
            if (kv.first.Scalar() != "actuator")
              yaml::fail(adoc.source, kv.first,
                         "unknown key '" + kv.first.Scalar() + "' (an actuator file has only `actuator:`)");
        }
        e.j.actuator_yaml = YAML::Dump(adoc.root["actuator"]);
        e.j.actuator_source = yaml::location(adoc.source, adoc.root["actuator"]) + ": actuator";
        for (const auto& kv : adoc.root["actuator"]) block_keys.push_back(kv.first.Scalar());
      } else if (a.IsMap()) {
        e.j.actuator_yaml = YAML::Dump(a);
        for (const auto& kv : a) block_keys.push_back(kv.first.Scalar());
        e.j.actuator_source = yaml::location(asrc, a) + ": " + asrc.key_path;
      } else {
        yaml::fail(asrc, a, "expected a map of actuator parameters or the path of an actuator file");
      }
    }
    // An uncertainty belongs to a parameter the block identifies (same key, same unit).
    if (!e.actuator_uncertainty.empty()) {
      const yaml::YamlSource usrc = yaml::childSource(yaml::itemSource(joints_src, i), "actuator_uncertainty");
      const YAML::Node unode = joints_node[i]["actuator_uncertainty"];
      for (const auto& [key, v] : e.actuator_uncertainty) {
        if (std::find(block_keys.begin(), block_keys.end(), key) == block_keys.end())
          yaml::fail(usrc, unode, "'" + key + "': not a parameter the joint's `actuator:` block names" +
                                      (block_keys.empty() ? std::string(" (the joint has no actuator block)")
                                                          : " (expected one of its keys, e.g. '" +
                                                                yaml::nearestKey(key, block_keys) + "')"));
        if (!(v >= 0.0) || !std::isfinite(v))
          yaml::fail(usrc, unode, "'" + key + "' = " + std::to_string(v) + ": expected a finite value >= 0");
      }
      e.j.actuator_uncertainty = e.actuator_uncertainty;
    }
    c.joints.push_back(e.j);
  }
  if (const YAML::Node& z = file.zero_offsets; !z.IsNull()) {  // optional: pmg_calib_zero result (map or file)
    const yaml::YamlSource zsrc = yaml::childSource(doc.source, "zero_offsets");
    std::vector<double> offsets;
    if (z.IsScalar()) {
      const std::string zfile = (fs::path(doc.source.base_dir) / z.Scalar()).lexically_normal().string();
      try {
        offsets = loadZeroOffsetFile(zfile, c);
      } catch (const ConfigError& err) {
        yaml::fail(zsrc, z, std::string("in the zero-offset file: ") + err.what());
      }
    } else if (z.IsMap()) {
      offsets.assign(c.numJoints(), 0.0);
      readZeroOffsetMap(z, zsrc, c, &offsets);
    } else {
      yaml::fail(zsrc, z, "expected a map {joint_name: offset_rad} or the path of a pmg_calib_zero result file");
    }
    for (std::size_t i = 0; i < c.joints.size(); ++i) c.joints[i].zero_offset = offsets[i];
  }
  if (const auto p = checkConfig(c)) {
    // Name the line of the joint (or of the robot section) the problem concerns.
    YAML::Node at = doc.root["robot"];
    if (p->joint >= 0 && joints_node && joints_node.IsSequence()) at = joints_node[static_cast<std::size_t>(p->joint)];
    else if (p->key == "robot.urdf") at = doc.root["robot"]["urdf"];
    else if (p->key == "robot.mjcf") at = doc.root["robot"]["mjcf"];
    yaml::fail(doc.source, at, p->text());
  }
  return c;
}

}  // namespace pmg
