#include "pmg/policy/contract.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "pmg/common/robot_config.hpp"
#include "pmg/common/yaml_archive.hpp"

namespace pmg::policy {
namespace {

std::string fmtNum(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

/// Reads contract fields with error messages that name source and field.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw ContractError(source_, field, problem);
  }

  YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& path) const {
    if (!parent.IsMap()) fail(path, "expected a map");
    YAML::Node n = parent[key];
    if (!n) fail(path.empty() ? key : path + "." + key, "missing");
    return n;
  }

  template <typename T>
  T scalar(const YAML::Node& n, const std::string& field, const char* expected) const {
    if (!n.IsScalar()) fail(field, std::string("expected ") + expected);
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      fail(field, std::string("expected ") + expected + ", got '" + n.Scalar() + "'");
    }
  }

  double finite(const YAML::Node& n, const std::string& field) const {
    const double v = scalar<double>(n, field, "a number");
    if (!std::isfinite(v)) fail(field, "expected a finite number");
    return v;
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& field) const {
    if (!n.IsSequence()) fail(field, "expected a list of numbers");
    std::vector<double> out;
    out.reserve(n.size());
    for (std::size_t i = 0; i < n.size(); ++i) out.push_back(finite(n[i], field + "[" + std::to_string(i) + "]"));
    return out;
  }

  std::vector<float> floats(const YAML::Node& n, const std::string& field) const {
    const auto d = numbers(n, field);
    return std::vector<float>(d.begin(), d.end());
  }

  /// Rejects keys of `map` (at `path`, "" = top level) not in `allowed`, and duplicate keys: a typo in a
  /// contract is an error naming the key, the nearest valid key and the line of the metadata text.
  void keys(const YAML::Node& map, const std::string& path, const std::vector<std::string>& allowed) const {
    if (!map.IsMap()) fail(path.empty() ? kContractMetadataKey : path, "expected a map");
    std::set<std::string> seen;
    for (const auto& kv : map) {
      const std::string key = kv.first.Scalar();
      const std::string field = path.empty() ? key : path + "." + key;
      const std::string line = kv.first.Mark().is_null() ? std::string()
                                                          : " at line " + std::to_string(kv.first.Mark().line + 1) +
                                                                " of the " + kContractMetadataKey + " metadata";
      if (!seen.insert(key).second) fail(field, "duplicate key" + line);
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
        fail(field, "unknown key" + line + " (did you mean '" + yaml::nearestKey(key, allowed) + "'?)");
    }
  }

  std::vector<std::string> names(const YAML::Node& n, const std::string& field) const {
    if (!n.IsSequence()) fail(field, "expected a list of names");
    std::vector<std::string> out;
    std::set<std::string> seen;
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = field + "[" + std::to_string(i) + "]";
      out.push_back(scalar<std::string>(n[i], f, "a name"));
      if (!seen.insert(out.back()).second) fail(f, "duplicate name '" + out.back() + "'");
    }
    return out;
  }

 private:
  std::string source_;
};

void checkSize(const Reader& r, const std::string& field, std::size_t got, std::size_t expected,
               const std::string& why) {
  if (got != expected) {
    r.fail(field, "has " + std::to_string(got) + " entries, expected " + std::to_string(expected) + " (" + why + ")");
  }
}

bool nearlyEqual(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

}  // namespace

ContractError::ContractError(const std::string& source, const std::string& field, const std::string& problem)
    : std::runtime_error(source + ": " + field + ": " + problem), field_(field) {}

int ObservationLayout::frameSize() const noexcept {
  int n = 0;
  for (const auto& t : terms) n += t.size;
  return n;
}

int ObservationLayout::size() const noexcept { return frameSize() * history_length; }

PolicyContract parseContract(const std::string& yaml_text, const std::string& source) {
  const Reader r(source);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    r.fail(kContractMetadataKey, "not valid YAML at line " + std::to_string(e.mark.line + 1) + ", column " +
                                     std::to_string(e.mark.column + 1) + " of the metadata: " + e.msg);
  }
  if (!root.IsMap()) r.fail(kContractMetadataKey, "expected a YAML map");
  r.keys(root, "", {"version", "robot", "joint_names", "actuated_joints", "controls_waist", "control_period",
                    "default_pose", "kp", "kd", "action", "observation", "pmg", "reference_pairs"});

  PolicyContract c;
  c.version = r.scalar<int>(r.require(root, "version", ""), "version", "an integer");
  if (c.version != kContractVersion) {
    r.fail("version", "is " + std::to_string(c.version) + ", this runner reads version " + std::to_string(kContractVersion));
  }
  if (root["robot"]) c.robot = r.scalar<std::string>(root["robot"], "robot", "a name");
  c.joint_names = r.names(r.require(root, "joint_names", ""), "joint_names");
  if (c.joint_names.empty()) r.fail("joint_names", "is empty");
  const std::size_t nj = c.joint_names.size();
  c.actuated_joints = r.names(r.require(root, "actuated_joints", ""), "actuated_joints");
  if (c.actuated_joints.empty()) r.fail("actuated_joints", "is empty");
  for (std::size_t i = 0; i < c.actuated_joints.size(); ++i) {
    if (std::find(c.joint_names.begin(), c.joint_names.end(), c.actuated_joints[i]) == c.joint_names.end()) {
      r.fail("actuated_joints[" + std::to_string(i) + "]", "'" + c.actuated_joints[i] + "' is not in joint_names");
    }
  }
  const std::size_t na = c.actuated_joints.size();
  c.controls_waist = r.scalar<bool>(r.require(root, "controls_waist", ""), "controls_waist", "true or false");
  c.control_period = r.finite(r.require(root, "control_period", ""), "control_period");
  if (c.control_period <= 0.0) r.fail("control_period", "must be > 0 s, got " + fmtNum(c.control_period));
  c.default_pose = r.numbers(r.require(root, "default_pose", ""), "default_pose");
  checkSize(r, "default_pose", c.default_pose.size(), nj, "one per joint_names entry");
  c.kp = r.numbers(r.require(root, "kp", ""), "kp");
  checkSize(r, "kp", c.kp.size(), nj, "one per joint_names entry");
  c.kd = r.numbers(r.require(root, "kd", ""), "kd");
  checkSize(r, "kd", c.kd.size(), nj, "one per joint_names entry");
  for (std::size_t j = 0; j < nj; ++j) {
    if (c.kp[j] < 0.0) r.fail("kp[" + std::to_string(j) + "]", "must be >= 0");
    if (c.kd[j] < 0.0) r.fail("kd[" + std::to_string(j) + "]", "must be >= 0");
  }

  const YAML::Node act = r.require(root, "action", "");
  r.keys(act, "action", {"scale", "offset", "clip"});
  c.action.scale = r.numbers(r.require(act, "scale", "action"), "action.scale");
  checkSize(r, "action.scale", c.action.scale.size(), na, "one per actuated_joints entry");
  c.action.offset = r.numbers(r.require(act, "offset", "action"), "action.offset");
  checkSize(r, "action.offset", c.action.offset.size(), na, "one per actuated_joints entry");
  c.action.clip = static_cast<float>(r.finite(r.require(act, "clip", "action"), "action.clip"));
  if (!(c.action.clip > 0.0f)) r.fail("action.clip", "must be > 0");

  const YAML::Node obs = r.require(root, "observation", "");
  r.keys(obs, "observation", {"history_length", "history_order", "clip", "terms"});
  c.observation.history_length = r.scalar<int>(r.require(obs, "history_length", "observation"),
                                               "observation.history_length", "an integer");
  if (c.observation.history_length < 1 || c.observation.history_length > 1000) {
    r.fail("observation.history_length", "must be in [1, 1000], got " + std::to_string(c.observation.history_length));
  }
  if (obs["history_order"]) {
    const auto order = r.scalar<std::string>(obs["history_order"], "observation.history_order", "a name");
    if (order != "newest_first") r.fail("observation.history_order", "must be 'newest_first', got '" + order + "'");
  }
  c.observation.clip = static_cast<float>(r.finite(r.require(obs, "clip", "observation"), "observation.clip"));
  if (!(c.observation.clip > 0.0f)) r.fail("observation.clip", "must be > 0");
  const YAML::Node terms = r.require(obs, "terms", "observation");
  if (!terms.IsSequence() || terms.size() == 0) r.fail("observation.terms", "expected a non-empty list");
  std::set<std::string> term_names;
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const std::string f = "observation.terms[" + std::to_string(i) + "]";
    r.keys(terms[i], f, {"name", "size", "scale"});
    ObservationTerm t;
    t.name = r.scalar<std::string>(r.require(terms[i], "name", f), f + ".name", "a name");
    if (!term_names.insert(t.name).second) r.fail(f + ".name", "duplicate term '" + t.name + "'");
    t.size = r.scalar<int>(r.require(terms[i], "size", f), f + ".size", "an integer");
    if (t.size < 1 || t.size > 100000) r.fail(f + ".size", "must be in [1, 100000], got " + std::to_string(t.size));
    const YAML::Node s = r.require(terms[i], "scale", f);
    if (s.IsSequence()) {
      t.scale = r.floats(s, f + ".scale");
      checkSize(r, f + ".scale", t.scale.size(), static_cast<std::size_t>(t.size), "one per value of term '" + t.name + "'");
    } else {
      t.scale.assign(static_cast<std::size_t>(t.size), static_cast<float>(r.finite(s, f + ".scale")));
    }
    c.observation.terms.push_back(std::move(t));
  }

  const YAML::Node pmg = r.require(root, "pmg", "");
  if (!pmg.IsMap()) r.fail("pmg", "expected a map of scalar settings");
  for (const auto& kv : pmg) {
    const auto key = kv.first.as<std::string>();
    if (!kv.second.IsScalar()) r.fail("pmg." + key, "expected a scalar");
    c.pmg[key] = kv.second.Scalar();
  }
  // Contracts written before the Table I ablation have no pmg.mode: they were trained on PMG.
  c.pmg.emplace("mode", "pmg");
  // Contracts written before the sole levelling have no pmg.sole_levelling: trained without it.
  c.pmg.emplace("sole_levelling", "false");
  // Contracts written before the stride adaptation (2026-12-04) were trained without it.
  c.pmg.emplace("stride_adaptation", "false");
  // Contracts written before StrideAdaptationOptions::standing_hold (2026-12-04) were trained with every
  // offset decaying while standing (and those without the stride adaptation have the key false too).
  c.pmg.emplace("stride_standing_hold", "false");
  c.pmg.emplace("upright_walking", "false");
  // Contracts written before the upper-body feed-forward in training have no pmg.upper_body_ff.
  c.pmg.emplace("upper_body_ff", "false");

  const YAML::Node pairs = r.require(root, "reference_pairs", "");
  if (!pairs.IsSequence() || pairs.size() == 0) r.fail("reference_pairs", "expected a non-empty list");
  const auto n_obs = static_cast<std::size_t>(c.observation.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::string f = "reference_pairs[" + std::to_string(i) + "]";
    r.keys(pairs[i], f, {"obs", "action"});
    ReferencePair p;
    p.obs = r.floats(r.require(pairs[i], "obs", f), f + ".obs");
    checkSize(r, f + ".obs", p.obs.size(), n_obs, "observation size = frame size x history_length");
    p.action = r.floats(r.require(pairs[i], "action", f), f + ".action");
    checkSize(r, f + ".action", p.action.size(), na, "one per actuated_joints entry");
    c.reference_pairs.push_back(std::move(p));
  }
  return c;
}

PolicyRobotSpec makePolicyRobotSpec(const RobotConfig& robot, double control_period) {
  if (!(control_period > 0.0) || !std::isfinite(control_period)) {
    throw std::invalid_argument("makePolicyRobotSpec: control_period must be > 0 s, got " + fmtNum(control_period));
  }
  PolicyRobotSpec s;
  s.name = robot.name;
  s.control_period = control_period;
  for (const auto& j : robot.joints) {
    s.joint_names.push_back(j.name);
    s.default_pose.push_back(j.default_position);
    s.kp.push_back(j.kp);
    s.kd.push_back(j.kd);
    if (j.name.find("hip") != std::string::npos || j.name.find("knee") != std::string::npos ||
        j.name.find("ankle") != std::string::npos) {
      s.leg_joints.push_back(j.name);
    } else if (j.name.rfind("waist", 0) == 0) {
      s.waist_joints.push_back(j.name);
    }
  }
  return s;
}

PolicyRobotSpec loadPolicyRobotSpec(const std::string& path, double control_period) {
  return makePolicyRobotSpec(loadRobotConfig(path), control_period);
}

void checkContract(const PolicyContract& c, const PolicyRobotSpec& robot, const std::string& source) {
  const Reader r(source);
  const std::size_t nj = robot.joint_names.size();
  if (c.joint_names.size() != nj) {
    r.fail("joint_names", "has " + std::to_string(c.joint_names.size()) + " joints, robot config has " + std::to_string(nj));
  }
  for (std::size_t j = 0; j < nj; ++j) {
    if (c.joint_names[j] != robot.joint_names[j]) {
      r.fail("joint_names[" + std::to_string(j) + "]",
             "is '" + c.joint_names[j] + "', robot config has '" + robot.joint_names[j] + "' (joint order must match)");
    }
  }
  auto compare = [&](const char* field, const std::vector<double>& got, const std::vector<double>& want, const char* unit) {
    for (std::size_t j = 0; j < nj; ++j) {
      if (!nearlyEqual(got[j], want[j])) {
        r.fail(std::string(field) + "[" + std::to_string(j) + "] (" + robot.joint_names[j] + ")",
               "contract has " + fmtNum(got[j]) + " " + unit + ", robot config has " + fmtNum(want[j]) + " " + unit);
      }
    }
  };
  compare("default_pose", c.default_pose, robot.default_pose, "rad");
  compare("kp", c.kp, robot.kp, "N*m/rad");
  compare("kd", c.kd, robot.kd, "N*m*s/rad");
  if (!nearlyEqual(c.control_period, robot.control_period)) {
    r.fail("control_period", "contract has " + fmtNum(c.control_period) + " s, controller runs at " +
                                 fmtNum(robot.control_period) + " s");
  }

  // Limb separation: the actor commands exactly the legs (+ the waist iff controls_waist).
  std::set<std::string> expected(robot.leg_joints.begin(), robot.leg_joints.end());
  if (c.controls_waist) expected.insert(robot.waist_joints.begin(), robot.waist_joints.end());
  for (std::size_t i = 0; i < c.actuated_joints.size(); ++i) {
    if (expected.erase(c.actuated_joints[i]) == 0) {
      r.fail("actuated_joints[" + std::to_string(i) + "]",
             "'" + c.actuated_joints[i] + "' is not a leg joint" + (c.controls_waist ? " or waist joint" : "") +
                 " (controls_waist: " + (c.controls_waist ? "true" : "false") + ")");
    }
  }
  if (!expected.empty()) {
    r.fail("actuated_joints", "does not command '" + *expected.begin() + "' (the actor must command every leg joint" +
                                  (c.controls_waist ? " and waist joint" : "") + ")");
  }

  for (const auto& [key, want] : robot.pmg) {
    const auto it = c.pmg.find(key);
    // The clips' digest is checked where the contract has one: actors exported before 2026-11-27
    // carry none.
    if (it == c.pmg.end() && key == "clips_digest") continue;
    if (it == c.pmg.end()) r.fail("pmg." + key, "missing, controller runs with '" + want + "'");
    bool same = it->second == want;
    if (!same) {
      try {
        std::size_t pa = 0, pb = 0;
        const double a = std::stod(it->second, &pa), b = std::stod(want, &pb);
        same = pa == it->second.size() && pb == want.size() && nearlyEqual(a, b);
      } catch (const std::exception&) {
        same = false;
      }
    }
    if (!same) r.fail("pmg." + key, "contract has '" + it->second + "', controller runs with '" + want + "'");
  }
}

}  // namespace pmg::policy
