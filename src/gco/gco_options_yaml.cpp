// YAML reader of pmg::gco::GcoOptions (setup time only; may allocate and throw).
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>

#include "pmg/gco/gco.hpp"

namespace pmg::gco {

namespace {

template <typename T>
void readScalar(const YAML::Node& node, const std::string& key, const std::string& source, T* value) {
  try {
    *value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(source + ": key '" + key + "' has the wrong type (expected a " +
                             (std::is_same_v<T, bool> ? "boolean" : std::is_same_v<T, int> ? "integer" : "number") +
                             ")");
  }
}

GcoOptions parseNode(const YAML::Node& root, const std::string& source) {
  GcoOptions o;
  if (!root || root.IsNull()) return o;
  if (!root.IsMap()) throw std::runtime_error(source + ": expected a YAML mapping of GcoOptions fields");
  const std::map<std::string, double*> doubles = {
      {"dt", &o.dt},
      {"ground_height", &o.ground_height},
      {"w_foot_velocity", &o.w_foot_velocity},
      {"w_foot_yaw_rate", &o.w_foot_yaw_rate},
      {"w_foot_height", &o.w_foot_height},
      {"w_prior_velocity", &o.w_prior_velocity},
      {"w_prior_yaw_rate", &o.w_prior_yaw_rate},
      {"w_prior_height", &o.w_prior_height},
      {"w_smooth_velocity", &o.w_smooth_velocity},
      {"w_smooth_yaw_rate", &o.w_smooth_yaw_rate},
      {"w_smooth_height", &o.w_smooth_height},
      {"w_limit", &o.w_limit},
      {"contact_ramp_time", &o.contact_ramp_time},
      {"max_jump_velocity", &o.max_jump_velocity},
      {"max_jump_yaw_rate", &o.max_jump_yaw_rate},
      {"max_jump_height", &o.max_jump_height},
      {"failure_gradient_norm", &o.failure_gradient_norm},
  };
  const std::map<std::string, double*> limit_fields = {
      {"v_x_min", &o.limits.v_x_min},           {"v_x_max", &o.limits.v_x_max},
      {"v_y_min", &o.limits.v_y_min},           {"v_y_max", &o.limits.v_y_max},
      {"yaw_rate_min", &o.limits.yaw_rate_min}, {"yaw_rate_max", &o.limits.yaw_rate_max},
      {"height_min", &o.limits.height_min},     {"height_max", &o.limits.height_max},
  };
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key == "enabled") {
      readScalar(kv.second, key, source, &o.enabled);
    } else if (key == "max_iterations") {
      readScalar(kv.second, key, source, &o.max_iterations);
    } else if (key == "newton_polish_iterations") {
      readScalar(kv.second, key, source, &o.newton_polish_iterations);
    } else if (auto it = doubles.find(key); it != doubles.end()) {
      readScalar(kv.second, key, source, it->second);
    } else if (key == "limits") {
      if (!kv.second.IsMap()) throw std::runtime_error(source + ": key 'limits' must be a mapping");
      for (const auto& lv : kv.second) {
        const std::string lkey = lv.first.as<std::string>();
        auto lit = limit_fields.find(lkey);
        if (lit == limit_fields.end()) {
          throw std::runtime_error(source + ": unknown key 'limits." + lkey + "'");
        }
        readScalar(lv.second, "limits." + lkey, source, lit->second);
      }
    } else {
      throw std::runtime_error(source + ": unknown key '" + key + "'");
    }
  }
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return o;
}

}  // namespace

GcoOptions parseGcoOptionsYaml(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source_name + ": YAML syntax error: " + e.what());
  }
  // Accept either the bare mapping or a document with a top-level `gco:` section.
  if (root.IsMap() && root["gco"]) return parseNode(root["gco"], source_name);
  return parseNode(root, source_name);
}

GcoOptions loadGcoOptionsFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot open GCO options file");
  std::stringstream ss;
  ss << file.rdbuf();
  return parseGcoOptionsYaml(ss.str(), path);
}

}  // namespace pmg::gco
