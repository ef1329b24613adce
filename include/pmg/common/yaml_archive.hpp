#pragma once
/// @file yaml_archive.hpp
/// The one mechanism that reads YAML files into C++ config structs (setup time only: allocates,
/// throws pmg::ConfigError). A struct declares its fields once, in a `Serialize` member template; its
/// defaults are its member initialisers. Reading is strict:
///  - an unknown key is an error naming the file, the line, the key and the nearest valid key:
///      `g1.yaml:12: unknown key 'hal_supervisr' in 'safety' (did you mean 'hal_supervisor'?)`;
///  - a value of the wrong type names file:line, the key path and the expected type:
///      `g1.yaml:27: joints[3].kp: expected a finite number, got 'fast'`;
///  - every floating-point field must be finite (`.inf`, `.nan` refused) unless flagged kAllowNonFinite;
///  - a missing file or a YAML syntax error names the path (and line); no raw yaml-cpp text escapes
///    without the file name;
///  - a duplicate key in one map is an error;
///  - unknown keys are reported before missing required ones, so a misspelt required key is named
///    as unknown next to its correct spelling.
///
/// Example:
/// @code
///   struct Gains {
///     double kp = 100.0;                 // default = member initialiser (the key may be omitted)
///     double kd = 2.0;
///     template <class A> void Serialize(A* a) {
///       a->Visit("kp", &kp, "stiffness [N*m/rad], 0..5000");
///       a->Visit("kd", &kd, "damping [N*m*s/rad], 0..500");
///     }
///     /// The validate() convention: "" = valid, else what is wrong, naming the field and the
///     /// expected range ("kp = -1: expected 0..5000"). The archive calls it after reading the
///     /// struct and throws ConfigError("<file>:<line>: <key path>: <message>"). (A `void validate()
///     /// const` that throws a std::exception is also called; its what() becomes <message>.)
///     std::string validate() const { return kp >= 0 && kp <= 5000 ? "" : "kp: expected 0..5000"; }
///   };
///   enum class Bus { kCan, kUdp };
///   // Enums are read from strings through a table found by argument-dependent lookup:
///   inline std::vector<std::pair<std::string, Bus>> yamlEnumNames(Bus) {
///     return {{"can", Bus::kCan}, {"udp", Bus::kUdp}};
///   }
///   struct Motor {
///     std::string joint;                 // required: a->Visit(..., yaml::kRequired)
///     std::optional<double> offset;      // absent or null = std::nullopt
///     Bus bus = Bus::kCan;
///     std::string calib_file;            // kPath: relative to the folder of the file that names it
///     std::vector<Gains> gains;          // nested structs, lists, std::array<double, N>, std::map<std::string, T>
///     template <class A> void Serialize(A* a) {
///       a->Visit("joint", &joint, "URDF joint name", yaml::kRequired);
///       a->Visit("offset", &offset, "[rad]");
///       a->Visit("bus", &bus, "can | udp");
///       a->Visit("calib_file", &calib_file, "actuator file", yaml::kPath);
///       a->Visit("gains", &gains);
///     }
///   };
///   Motor m = pmg::yaml::loadYamlFile<Motor>("config/motor.yaml");          // the whole document
///   Gains g = pmg::yaml::loadYamlFile<Gains>("config/motor.yaml", "gains");  // one top-level key only
/// @endcode
///
/// Supported field types: bool; integers (range-checked against the C++ type; `0x` hex allowed);
/// float/double (finite); std::string; std::filesystem::path (always resolved, like kPath);
/// enums with a `yamlEnumNames(E)` table; std::optional<T>; std::vector<T>; std::array<T, N> (exactly
/// N items); std::map<std::string, T>; any struct with `template <class A> void Serialize(A*)`; and
/// YAML::Node (the raw node, for fields with a custom form, e.g. "a map or the path of a file").
/// Field declarations may depend on values read before (e.g. visit "type" first, then the fields of
/// that type): keys never visited are unknown keys.

#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "pmg/common/config_error.hpp"

namespace pmg::yaml {

/// Per-field flags of Visit(); combine with |.
enum Flags : unsigned {
  kOptional = 0,         ///< default: an absent key keeps the member's initial value
  kRequired = 1u << 0,   ///< an absent key is an error ("missing required key")
  kAllowNonFinite = 1u << 1,  ///< floating-point values (also inside containers) may be .inf/.nan
  kPath = 1u << 2,       ///< std::string (or containers of them): a relative path is made absolute against
                         ///< the folder of the file that names it (lexically normalised); "" stays ""
};

/// Where a node comes from: the file (or a name such as "model.onnx: metadata 'pmg_contract'"), the
/// folder relative paths resolve against, and the key path of the node ("" = document root,
/// "joints[3]", "safety.limits").
struct YamlSource {
  std::string file;
  std::string base_dir;
  std::string key_path;
  /// false: the node's line numbers do not refer to `file` (e.g. a block re-parsed from
  /// YAML::Dump text); errors then name `file` without a line.
  bool lines = true;
};

/// A parsed YAML document and where it came from.
struct YamlDocument {
  YAML::Node root;
  YamlSource source;  ///< key_path is ""
};

/// Reads and parses a YAML file. base_dir = the absolute folder of `path`.
/// @throws ConfigError "<path>: cannot open file" or "<path>:<line>:<col>: YAML syntax error: <what>".
YamlDocument loadYamlDocument(const std::string& path);

/// Parses YAML (or JSON) text. `source_name` names it in errors; `base_dir` resolves relative paths
/// ("" = the current directory). @throws ConfigError "<source_name>:<line>:<col>: YAML syntax error: ...".
YamlDocument parseYamlDocument(const std::string& text, const std::string& source_name,
                               const std::string& base_dir = "");

/// Levenshtein distance (insert, delete, substitute = 1) between two strings.
std::size_t editDistance(const std::string& a, const std::string& b);

/// The candidate nearest to `key` by edit distance (among equals the one sharing the longest prefix
/// with `key`, then the first), or "" if there are none.
std::string nearestKey(const std::string& key, const std::vector<std::string>& candidates);

/// "<file>:<line>" of a node (line 1-based; just "<file>" when the node has no position).
std::string location(const YamlSource& source, const YAML::Node& node);

/// Throws ConfigError("<file>:<line>: <key_path>: <message>") (key path omitted when empty).
[[noreturn]] void fail(const YamlSource& source, const YAML::Node& at, const std::string& message);

/// The source of the value of `key` in the map at `source` (key path "safety" -> "safety.limits").
YamlSource childSource(const YamlSource& source, const std::string& key);
/// The source of item `index` of the list at `source` (key path "joints" -> "joints[3]").
YamlSource itemSource(const YamlSource& source, std::size_t index);
/// Rejects duplicate keys and keys of `map` not in `valid` (the unknown-key message of the archive:
/// file:line, key, the nearest valid key). No-op unless `map` is a map. @throws ConfigError.
void rejectUnknownKeys(const YAML::Node& map, const YamlSource& source, const std::vector<std::string>& valid);

/// One field as declared by Serialize(), for documentation and --help output.
struct FieldInfo {
  std::string name;
  std::string doc;
  unsigned flags = kOptional;
};

namespace detail {

// Detects `template <class A> void Serialize(A*)` by trying it with a probe archive.
struct ProbeArchive {
  template <class T>
  void Visit(const char*, T*, const char* = "", unsigned = 0) {}
  template <class T>
  void Visit(const char*, T*, unsigned) {}
};
template <class T, class = void>
struct IsSerializable : std::false_type {};
template <class T>
struct IsSerializable<T, std::void_t<decltype(std::declval<T&>().Serialize(static_cast<ProbeArchive*>(nullptr)))>>
    : std::true_type {};

template <class T, class = void>
struct HasValidate : std::false_type {};
template <class T>
struct HasValidate<
    T, std::enable_if_t<std::is_convertible_v<decltype(std::declval<const T&>().validate()), std::string>>>
    : std::true_type {};
template <class T, class = void>
struct HasThrowingValidate : std::false_type {};
template <class T>
struct HasThrowingValidate<T, std::enable_if_t<std::is_void_v<decltype(std::declval<const T&>().validate())>>>
    : std::true_type {};

template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
struct IsVector : std::false_type {};
template <class T, class Alloc>
struct IsVector<std::vector<T, Alloc>> : std::true_type {};
template <class T>
struct IsArray : std::false_type {};
template <class T, std::size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};
template <class T>
struct IsStringMap : std::false_type {};
template <class T, class Cmp, class Alloc>
struct IsStringMap<std::map<std::string, T, Cmp, Alloc>> : std::true_type {};

// Non-template scalar readers (yaml_archive.cpp). Each checks the node is a scalar of the right form.
bool readBool(const YAML::Node& n, const YamlSource& s);
long long readInteger(const YAML::Node& n, const YamlSource& s, long long lo, unsigned long long hi);
double readDouble(const YAML::Node& n, const YamlSource& s, unsigned flags);
std::string readString(const YAML::Node& n, const YamlSource& s, unsigned flags);
std::size_t readEnumIndex(const YAML::Node& n, const YamlSource& s, const std::vector<std::string>& names);
void expectKind(const YAML::Node& n, const YamlSource& s, YAML::NodeType::value kind, const char* what);
void expectSize(const YAML::Node& n, const YamlSource& s, std::size_t size);
YamlSource child(const YamlSource& s, const std::string& key);
YamlSource item(const YamlSource& s, std::size_t index);
void checkDuplicateKeys(const YAML::Node& map, const YamlSource& s);
void checkUnknownKeys(const YAML::Node& map, const YamlSource& s, const std::set<std::string>& visited,
                      const std::vector<std::string>& valid);
void failValidate(const YamlSource& s, const YAML::Node& at, const std::string& message);

template <class T>
void readValue(const YAML::Node& n, const YamlSource& s, unsigned flags, T* out);

}  // namespace detail

/// Reads one YAML map into a struct through its Serialize(). Usually used through readYaml() /
/// loadYamlFile(); a Serialize() body sees it only as `A* a` and calls Visit().
class YamlReadArchive {
 public:
  YamlReadArchive(const YAML::Node& map, const YamlSource& source) : map_(map), source_(source) {}

  /// Declares field `name`: reads it into *value if present (see the file comment for the types),
  /// else keeps *value (kOptional) or throws (kRequired). `doc` documents meaning and units.
  template <class T>
  void Visit(const char* name, T* value, const char* doc = "", unsigned flags = kOptional) {
    (void)doc;
    visited_.insert(name);
    valid_.emplace_back(name);
    const YAML::Node n = map_[name];  // const access: never inserts into the map
    if (!n) {
      // Reported by checkUnknownKeys(), after unknown keys: a misspelt required key is named as such.
      if (flags & kRequired) missing_.emplace_back(name);
      if constexpr (detail::IsOptional<T>::value) value->reset();
      return;
    }
    detail::readValue(n, detail::child(source_, name), flags, value);
  }
  template <class T>
  void Visit(const char* name, T* value, unsigned flags) {
    Visit(name, value, "", flags);
  }

  /// True if the map has key `name` (for fields whose form depends on another one).
  bool has(const char* name) const { return map_.IsMap() && static_cast<bool>(map_[name]); }
  /// The node being read and where it is, for custom error messages (fail(source(), node(), ...)).
  const YAML::Node& node() const { return map_; }
  const YamlSource& source() const { return source_; }

  /// Rejects keys that no Visit() named, then missing required keys. Called by readYaml() after
  /// Serialize(). (A YAML::Node field whose key is absent stays a Null node: test IsNull().)
  void checkUnknownKeys() const {
    detail::checkUnknownKeys(map_, source_, visited_, valid_);
    if (!missing_.empty()) fail(source_, map_, "missing required key '" + missing_.front() + "'");
  }

 private:
  const YAML::Node map_;
  YamlSource source_;
  std::set<std::string> visited_;
  std::vector<std::string> valid_;
  std::vector<std::string> missing_;
};

/// Collects the declared fields of T (for docs and --help).
class FieldListArchive {
 public:
  template <class T>
  void Visit(const char* name, T*, const char* doc = "", unsigned flags = kOptional) {
    fields.push_back(FieldInfo{name, doc, flags});
  }
  template <class T>
  void Visit(const char* name, T* value, unsigned flags) {
    Visit(name, value, "", flags);
  }
  std::vector<FieldInfo> fields;
};

/// The fields T declares, in Serialize() order.
template <class T>
std::vector<FieldInfo> describeFields() {
  T value{};
  FieldListArchive a;
  value.Serialize(&a);
  return a.fields;
}

/// Reads `node` (a map; null = all defaults) into *out, keeping the values of keys not in the map.
/// Rejects unknown keys, then calls out->validate() if T has one. @throws ConfigError.
template <class T>
void readYaml(const YAML::Node& node, const YamlSource& source, T* out) {
  detail::readValue(node, source, kOptional, out);
}

/// Reads a whole document (or, with `key` non-empty, the value of that top-level key, which must be
/// there; other top-level keys are then not checked) into *out. @throws ConfigError.
template <class T>
void readYaml(const YamlDocument& doc, T* out, const std::string& key = "") {
  if (key.empty()) return readYaml(doc.root, doc.source, out);
  detail::expectKind(doc.root, doc.source, YAML::NodeType::Map, "a map");
  const YAML::Node n = doc.root[key];
  if (!n) fail(doc.source, doc.root, "missing required key '" + key + "'");
  readYaml(n, detail::child(doc.source, key), out);
}

/// Loads a file into a T that starts from its defaults. See readYaml(). @throws ConfigError.
template <class T>
T loadYamlFile(const std::string& path, const std::string& key = "") {
  T out{};
  readYaml(loadYamlDocument(path), &out, key);
  return out;
}

/// Parses text into a T that starts from its defaults. See readYaml(). @throws ConfigError.
template <class T>
T parseYamlString(const std::string& text, const std::string& source_name, const std::string& key = "",
                  const std::string& base_dir = "") {
  T out{};
  readYaml(parseYamlDocument(text, source_name, base_dir), &out, key);
  return out;
}

namespace detail {

template <class T>
void readValue(const YAML::Node& n, const YamlSource& s, unsigned flags, T* out) {
  if constexpr (std::is_same_v<T, YAML::Node>) {
    *out = n;
  } else if constexpr (IsOptional<T>::value) {
    if (n.IsNull()) {
      out->reset();
    } else {
      typename T::value_type v{};
      readValue(n, s, flags, &v);
      *out = std::move(v);
    }
  } else if constexpr (std::is_same_v<T, bool>) {
    *out = readBool(n, s);
  } else if constexpr (std::is_enum_v<T>) {
    const auto table = yamlEnumNames(T{});  // found by argument-dependent lookup
    std::vector<std::string> names;
    for (const auto& kv : table) names.push_back(kv.first);
    *out = table[readEnumIndex(n, s, names)].second;
  } else if constexpr (std::is_integral_v<T>) {
    *out = static_cast<T>(readInteger(n, s, static_cast<long long>(std::numeric_limits<T>::min()),
                                      static_cast<unsigned long long>(std::numeric_limits<T>::max())));
  } else if constexpr (std::is_floating_point_v<T>) {
    const double v = readDouble(n, s, flags);
    if (std::isfinite(v) && std::fabs(v) > static_cast<double>(std::numeric_limits<T>::max()))
      fail(s, n, "value " + n.Scalar() + " out of range of a float");
    *out = static_cast<T>(v);
  } else if constexpr (std::is_same_v<T, std::string>) {
    *out = readString(n, s, flags);
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
    *out = readString(n, s, flags | kPath);
  } else if constexpr (IsVector<T>::value) {
    if (n.IsNull()) {
      out->clear();
      return;
    }
    expectKind(n, s, YAML::NodeType::Sequence, "a list");
    T v;
    v.reserve(n.size());
    for (std::size_t i = 0; i < n.size(); ++i) {
      typename T::value_type x{};
      readValue(n[i], item(s, i), flags, &x);
      v.push_back(std::move(x));
    }
    *out = std::move(v);
  } else if constexpr (IsArray<T>::value) {
    expectKind(n, s, YAML::NodeType::Sequence, "a list");
    expectSize(n, s, std::tuple_size<T>::value);
    for (std::size_t i = 0; i < n.size(); ++i) readValue(n[i], item(s, i), flags, &(*out)[i]);
  } else if constexpr (IsStringMap<T>::value) {
    if (n.IsNull()) {
      out->clear();
      return;
    }
    expectKind(n, s, YAML::NodeType::Map, "a map");
    checkDuplicateKeys(n, s);
    T m;
    for (const auto& kv : n) {
      const std::string key = kv.first.Scalar();
      typename T::mapped_type x{};
      readValue(kv.second, child(s, key), flags, &x);
      m.emplace(key, std::move(x));
    }
    *out = std::move(m);
  } else if constexpr (IsSerializable<T>::value) {
    // A null value (`key:` or `key: ~`) reads as an empty map: all defaults, required keys missing.
    if (!n.IsNull()) expectKind(n, s, YAML::NodeType::Map, "a map");
    YamlReadArchive a(n, s);
    out->Serialize(&a);
    a.checkUnknownKeys();
    if constexpr (HasValidate<T>::value) {
      const std::string msg = out->validate();
      if (!msg.empty()) failValidate(s, n, msg);
    } else if constexpr (HasThrowingValidate<T>::value) {
      try {
        out->validate();
      } catch (const std::exception& e) {
        failValidate(s, n, e.what());
      }
    }
  } else {
    static_assert(sizeof(T) == 0,
                  "pmg::yaml: unsupported field type (add `template <class A> void Serialize(A*)` to the struct)");
  }
}

}  // namespace detail
}  // namespace pmg::yaml
