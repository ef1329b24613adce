#include "pmg/common/robot_config.hpp"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace pmg {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& file, const std::string& key, const std::string& what) {
  throw ConfigError(file + ": " + key + ": " + what);
}

template <typename T>
T required(const YAML::Node& node, const std::string& key, const std::string& file, const std::string& prefix) {
  const YAML::Node child = node[key];
  if (!child) fail(file, prefix + key, "missing (required)");
  try {
    return child.as<T>();
  } catch (const YAML::Exception&) {
    fail(file, prefix + key, "cannot read value '" + YAML::Dump(child) + "' as the expected type");
  }
}

template <typename T>
T optional(const YAML::Node& node, const std::string& key, const T& fallback, const std::string& file,
           const std::string& prefix) {
  if (!node[key]) return fallback;
  return required<T>(node, key, file, prefix);
}

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
PMG_JOINT_VECTOR(velocityLimits, velocity_limit)
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

void validate(const RobotConfig& c) {
  const std::string& f = c.source_file.empty() ? std::string("<robot config>") : c.source_file;
  if (c.joints.empty()) fail(f, "joints", "empty: expected at least one joint");
  if (c.buses.empty()) fail(f, "buses", "empty: expected at least one bus");
  if (!(c.standing_base_height > 0.05 && c.standing_base_height < 3.0))
    fail(f, "robot.standing_base_height", "= " + num(c.standing_base_height) + ": expected in (0.05, 3) m");
  for (std::size_t b = 0; b < c.buses.size(); ++b) {
    const auto& bus = c.buses[b];
    const std::string k = "buses[" + std::to_string(b) + "]";
    if (bus.bitrate < 10000 || bus.bitrate > 1000000)
      fail(f, k + ".bitrate", "= " + std::to_string(bus.bitrate) + ": expected 10000..1000000 bit/s");
    if (bus.data_bitrate != 0 && (!bus.fd || bus.data_bitrate < bus.bitrate || bus.data_bitrate > 8000000))
      fail(f, k + ".data_bitrate", "= " + std::to_string(bus.data_bitrate) +
                                       ": expected 0, or bitrate..8000000 bit/s with fd: true");
  }
  std::set<std::string> names;
  std::set<std::pair<int, int>> bus_ids;
  for (std::size_t i = 0; i < c.joints.size(); ++i) {
    const auto& j = c.joints[i];
    const std::string k = "joints[" + std::to_string(i) + "] (" + j.name + ")";
    if (j.name.empty()) fail(f, k + ".name", "empty");
    if (!names.insert(j.name).second) fail(f, k + ".name", "duplicate joint name");
    auto finite = [&](double v, const char* field) {
      if (!std::isfinite(v)) fail(f, k + "." + field, "is not a finite number");
    };
    finite(j.lower, "lower");
    finite(j.upper, "upper");
    finite(j.kp, "kp");
    finite(j.kd, "kd");
    finite(j.default_position, "default");
    if (!(j.lower < j.upper))
      fail(f, k + ".lower/upper", "= [" + num(j.lower) + ", " + num(j.upper) + "]: expected lower < upper");
    if (!(j.velocity_limit > 0)) fail(f, k + ".velocity_limit", "= " + num(j.velocity_limit) + ": expected > 0 rad/s");
    if (!(j.torque_limit > 0)) fail(f, k + ".torque_limit", "= " + num(j.torque_limit) + ": expected > 0 N*m");
    if (!(j.kp >= 0 && j.kp <= 5000)) fail(f, k + ".kp", "= " + num(j.kp) + ": expected 0..5000 N*m/rad");
    if (!(j.kd >= 0 && j.kd <= 500)) fail(f, k + ".kd", "= " + num(j.kd) + ": expected 0..500 N*m*s/rad");
    if (j.default_position < j.lower || j.default_position > j.upper)
      fail(f, k + ".default", "= " + num(j.default_position) + ": expected within [" + num(j.lower) + ", " +
                                  num(j.upper) + "]");
    if (j.bus < 0 || j.bus >= static_cast<int>(c.buses.size()))
      fail(f, k + ".bus", "= " + std::to_string(j.bus) + ": expected 0.." + std::to_string(c.buses.size() - 1));
    if (j.motor_id < 1 || j.motor_id > 2047)
      fail(f, k + ".motor_id", "= " + std::to_string(j.motor_id) + ": expected 1..2047");
    if (!bus_ids.insert({j.bus, j.motor_id}).second)
      fail(f, k + ".motor_id", "= " + std::to_string(j.motor_id) + ": duplicate id on bus " + std::to_string(j.bus));
    if (j.mirror_sign != 1 && j.mirror_sign != -1)
      fail(f, k + ".mirror_sign", "= " + std::to_string(j.mirror_sign) + ": expected 1 or -1");
  }
  for (std::size_t i = 0; i < c.joints.size(); ++i) {
    const auto& j = c.joints[i];
    const std::string k = "joints[" + std::to_string(i) + "] (" + j.name + ")";
    const int m = c.jointIndex(j.mirror);
    if (m < 0) fail(f, k + ".mirror", "= '" + j.mirror + "': not a joint of this robot");
    const auto& partner = c.joints[static_cast<std::size_t>(m)];
    if (partner.mirror != j.name)
      fail(f, k + ".mirror", "= '" + j.mirror + "' whose mirror is '" + partner.mirror + "': expected a pairwise map");
    if (partner.mirror_sign != j.mirror_sign)
      fail(f, k + ".mirror_sign", "differs from the sign of its partner '" + partner.name + "'");
  }
  if (!c.urdf_path.empty() && !fs::exists(c.urdf_path)) fail(f, "robot.urdf", "file '" + c.urdf_path + "' not found");
  if (!c.mjcf_path.empty() && !fs::exists(c.mjcf_path)) fail(f, "robot.mjcf", "file '" + c.mjcf_path + "' not found");
}

RobotConfig loadRobotConfig(const std::string& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(yaml_path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(yaml_path + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  const std::string& f = yaml_path;
  RobotConfig c;
  c.source_file = yaml_path;
  const fs::path dir = fs::absolute(fs::path(yaml_path)).parent_path();
  const YAML::Node robot = root["robot"];
  if (!robot || !robot.IsMap()) fail(f, "robot", "missing (required map)");
  c.name = required<std::string>(robot, "name", f, "robot.");
  c.urdf_path = (dir / required<std::string>(robot, "urdf", f, "robot.")).lexically_normal().string();
  c.mjcf_path = (dir / required<std::string>(robot, "mjcf", f, "robot.")).lexically_normal().string();
  c.base_link = required<std::string>(robot, "base_link", f, "robot.");
  c.left_foot_link = required<std::string>(robot, "left_foot_link", f, "robot.");
  c.right_foot_link = required<std::string>(robot, "right_foot_link", f, "robot.");
  c.imu_site = required<std::string>(robot, "imu_site", f, "robot.");
  c.standing_base_height = optional<double>(robot, "standing_base_height", 0.78, f, "robot.");

  const YAML::Node buses = root["buses"];
  if (!buses || !buses.IsSequence()) fail(f, "buses", "missing (required list)");
  for (std::size_t b = 0; b < buses.size(); ++b) {
    const std::string p = "buses[" + std::to_string(b) + "].";
    BusConfig bus;
    bus.name = required<std::string>(buses[b], "name", f, p);
    bus.bitrate = required<int>(buses[b], "bitrate", f, p);
    bus.fd = optional<bool>(buses[b], "fd", false, f, p);
    bus.data_bitrate = optional<int>(buses[b], "data_bitrate", 0, f, p);
    c.buses.push_back(bus);
  }
  const YAML::Node joints = root["joints"];
  if (!joints || !joints.IsSequence()) fail(f, "joints", "missing (required list)");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const std::string p = "joints[" + std::to_string(i) + "].";
    const YAML::Node n = joints[i];
    JointConfig j;
    j.name = required<std::string>(n, "name", f, p);
    j.lower = required<double>(n, "lower", f, p);
    j.upper = required<double>(n, "upper", f, p);
    j.velocity_limit = required<double>(n, "velocity_limit", f, p);
    j.torque_limit = required<double>(n, "torque_limit", f, p);
    j.kp = required<double>(n, "kp", f, p);
    j.kd = required<double>(n, "kd", f, p);
    j.default_position = required<double>(n, "default", f, p);
    j.bus = required<int>(n, "bus", f, p);
    j.motor_id = required<int>(n, "motor_id", f, p);
    j.mirror = optional<std::string>(n, "mirror", j.name, f, p);
    j.mirror_sign = optional<int>(n, "mirror_sign", 1, f, p);
    if (const YAML::Node a = n["actuator"]) {
      if (a.IsScalar()) {  // path of an actuator file with a top-level `actuator:` map
        const std::string afile = (dir / a.as<std::string>()).lexically_normal().string();
        YAML::Node doc;
        try {
          doc = YAML::LoadFile(afile);
        } catch (const YAML::Exception& e) {
          fail(f, p + "actuator", "cannot read actuator file '" + afile + "': " + e.what());
        }
        if (!doc["actuator"] || !doc["actuator"].IsMap())
          fail(f, p + "actuator", "file '" + afile + "' has no top-level `actuator:` map");
        j.actuator_yaml = YAML::Dump(doc["actuator"]);
        j.actuator_source = afile + ": actuator";
      } else if (a.IsMap()) {
        j.actuator_yaml = YAML::Dump(a);
        j.actuator_source = f + ": " + p + "actuator";
      } else {
        fail(f, p + "actuator", "expected a map of actuator parameters or the path of an actuator file");
      }
    }
    c.joints.push_back(j);
  }
  if (const YAML::Node z = root["zero_offsets"]) {  // optional: pmg_calib_zero result (map or file)
    YAML::Node map = z;
    std::string src = f + ": zero_offsets";
    if (z.IsScalar()) {
      const std::string zfile = (dir / z.as<std::string>()).lexically_normal().string();
      YAML::Node doc;
      try {
        doc = YAML::LoadFile(zfile);
      } catch (const YAML::Exception& e) {
        fail(f, "zero_offsets", "cannot read zero-offset file '" + zfile + "': " + e.what());
      }
      map = doc["zero_offsets"];
      src = zfile + ": zero_offsets";
      if (!map || !map.IsMap()) fail(f, "zero_offsets", "file '" + zfile + "' has no top-level `zero_offsets:` map");
    } else if (!z.IsMap()) {
      fail(f, "zero_offsets", "expected a map {joint_name: offset_rad} or the path of a pmg_calib_zero result file");
    }
    for (const auto& kv : map) {
      const std::string name = kv.first.as<std::string>();
      const int i = c.jointIndex(name);
      if (i < 0) throw ConfigError(src + "." + name + ": not a joint of " + f);
      double v = 0.0;
      try {
        v = kv.second.as<double>();
      } catch (const YAML::Exception&) {
        throw ConfigError(src + "." + name + ": expected a number [rad]");
      }
      if (!std::isfinite(v) || std::fabs(v) > 0.5)
        throw ConfigError(src + "." + name + " = " + kv.second.Scalar() + ": expected finite, |offset| <= 0.5 rad");
      c.joints[static_cast<std::size_t>(i)].zero_offset = v;
    }
  }
  validate(c);
  return c;
}

}  // namespace pmg
