#include "pmg/common/yaml_archive.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace pmg::yaml {
namespace {

namespace fs = std::filesystem;

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar: {
      std::string v = n.Scalar();
      if (v.size() > 40) v = v.substr(0, 37) + "...";
      return "'" + v + "'";
    }
    default:
      return "an undefined value";
  }
}

std::string syntaxError(const std::string& name, const YAML::Exception& e) {
  std::string where = name;
  if (!e.mark.is_null()) where += ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1);
  return where + ": YAML syntax error: " + e.msg;
}

}  // namespace

YamlDocument loadYamlDocument(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw ConfigError(path + ": is a directory, expected a YAML file");
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseYamlDocument(ss.str(), path, fs::absolute(fs::path(path)).parent_path().lexically_normal().string());
}

YamlDocument parseYamlDocument(const std::string& text, const std::string& source_name, const std::string& base_dir) {
  YamlDocument doc;
  doc.source.file = source_name;
  doc.source.base_dir = base_dir.empty() ? fs::current_path().string() : base_dir;
  try {
    doc.root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(syntaxError(source_name, e));
  }
  return doc;
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string nearestKey(const std::string& key, const std::vector<std::string>& candidates) {
  // Smallest edit distance; among equals the longest common prefix ('rp' -> 'rpy', not 'dp').
  const auto prefix = [&key](const std::string& c) {
    std::size_t n = 0;
    while (n < key.size() && n < c.size() && key[n] == c[n]) ++n;
    return n;
  };
  std::string best;
  std::size_t best_d = std::string::npos, best_p = 0;
  for (const auto& c : candidates) {
    const std::size_t d = editDistance(key, c), p = prefix(c);
    if (d < best_d || (d == best_d && p > best_p)) {
      best_d = d;
      best_p = p;
      best = c;
    }
  }
  return best;
}

std::string location(const YamlSource& source, const YAML::Node& node) {
  if (!source.lines) return source.file;
  try {
    const YAML::Mark m = node.Mark();
    if (!m.is_null()) return source.file + ":" + std::to_string(m.line + 1);
  } catch (const YAML::Exception&) {
  }
  return source.file;
}

void fail(const YamlSource& source, const YAML::Node& at, const std::string& message) {
  std::string text = location(source, at) + ": ";
  if (!source.key_path.empty()) text += source.key_path + ": ";
  throw ConfigError(text + message);
}

YamlSource childSource(const YamlSource& source, const std::string& key) { return detail::child(source, key); }

YamlSource itemSource(const YamlSource& source, std::size_t index) { return detail::item(source, index); }

void rejectUnknownKeys(const YAML::Node& map, const YamlSource& source, const std::vector<std::string>& valid) {
  detail::checkUnknownKeys(map, source, std::set<std::string>(valid.begin(), valid.end()), valid);
}

namespace detail {

bool readBool(const YAML::Node& n, const YamlSource& s) {
  if (n.IsScalar()) {
    bool v = false;
    if (YAML::convert<bool>::decode(n, v)) return v;
  }
  fail(s, n, "expected true or false, got " + describe(n));
}

long long readInteger(const YAML::Node& n, const YamlSource& s, long long lo, unsigned long long hi) {
  long long v = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, v))
    fail(s, n, "expected an integer, got " + describe(n));
  if (v < lo || (v >= 0 && static_cast<unsigned long long>(v) > hi))
    fail(s, n, "expected an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + n.Scalar());
  return v;
}

double readDouble(const YAML::Node& n, const YamlSource& s, unsigned flags) {
  double v = 0.0;
  const bool finite_only = !(flags & kAllowNonFinite);
  const char* expected = finite_only ? "expected a finite number, got " : "expected a number, got ";
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) fail(s, n, expected + describe(n));
  if (finite_only && !std::isfinite(v)) fail(s, n, expected + describe(n));
  return v;
}

std::string readString(const YAML::Node& n, const YamlSource& s, unsigned flags) {
  if (!n.IsScalar()) fail(s, n, std::string(flags & kPath ? "expected a path" : "expected a string") + ", got " +
                                    describe(n));
  std::string v = n.Scalar();
  if ((flags & kPath) && !v.empty()) {
    const fs::path p(v);
    if (p.is_relative()) v = (fs::path(s.base_dir) / p).lexically_normal().string();
  }
  return v;
}

std::size_t readEnumIndex(const YAML::Node& n, const YamlSource& s, const std::vector<std::string>& names) {
  std::string list;
  for (const auto& name : names) list += (list.empty() ? "'" : ", '") + name + "'";
  if (n.IsScalar()) {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n.Scalar()) return i;
    fail(s, n, "expected one of " + list + ", got " + describe(n) + " (did you mean '" + nearestKey(n.Scalar(), names) +
                   "'?)");
  }
  fail(s, n, "expected one of " + list + ", got " + describe(n));
}

void expectKind(const YAML::Node& n, const YamlSource& s, YAML::NodeType::value kind, const char* what) {
  if (n.Type() != kind) fail(s, n, std::string("expected ") + what + ", got " + describe(n));
}

void expectSize(const YAML::Node& n, const YamlSource& s, std::size_t size) {
  if (n.size() != size)
    fail(s, n, "expected a list of exactly " + std::to_string(size) + " items, got " + std::to_string(n.size()));
}

YamlSource child(const YamlSource& s, const std::string& key) {
  YamlSource c = s;
  c.key_path = s.key_path.empty() ? key : s.key_path + "." + key;
  return c;
}

YamlSource item(const YamlSource& s, std::size_t index) {
  YamlSource c = s;
  c.key_path = s.key_path + "[" + std::to_string(index) + "]";
  return c;
}

void checkDuplicateKeys(const YAML::Node& map, const YamlSource& s) {
  std::set<std::string> seen;
  for (const auto& kv : map) {
    if (!kv.first.IsScalar()) fail(s, kv.first, "expected a plain key, got " + describe(kv.first));
    if (!seen.insert(kv.first.Scalar()).second) fail(s, kv.first, "duplicate key '" + kv.first.Scalar() + "'");
  }
}

void checkUnknownKeys(const YAML::Node& map, const YamlSource& s, const std::set<std::string>& visited,
                      const std::vector<std::string>& valid) {
  if (!map.IsMap()) return;
  checkDuplicateKeys(map, s);
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    if (visited.count(key)) continue;
    std::string msg = location(s, kv.first) + ": unknown key '" + key + "' " +
                      (s.key_path.empty() ? std::string("at the top level") : "in '" + s.key_path + "'");
    if (valid.empty())
      msg += " (no keys are expected here)";
    else
      msg += " (did you mean '" + nearestKey(key, valid) + "'?)";
    throw ConfigError(msg);
  }
}

void failValidate(const YamlSource& s, const YAML::Node& at, const std::string& message) { fail(s, at, message); }

}  // namespace detail
}  // namespace pmg::yaml
