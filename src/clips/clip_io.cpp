#include "pmg/clips/clip_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "pmg/common/yaml_archive.hpp"

namespace pmg {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

/// Fixed-point number, 6 decimals, negative zero printed as zero (deterministic output).
std::string num(double x) {
  std::string s = fmt::format("{:.6f}", x);
  if (s == "-0.000000") s = "0.000000";
  return s;
}

/// YAML double-quoted string with the characters that need escaping escaped.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default: out += c;
    }
  }
  out += '"';
  return out;
}

void writeRow(std::string& out, const Eigen::Ref<const Eigen::RowVectorXd>& row) {
  out += "  - [";
  for (Eigen::Index j = 0; j < row.size(); ++j) {
    if (j > 0) out += ", ";
    out += num(row(j));
  }
  out += "]\n";
}

void writeMatrix(std::string& out, const char* key, const Eigen::MatrixXd& m) {
  out += key;
  out += ":\n";
  for (Eigen::Index i = 0; i < m.rows(); ++i) writeRow(out, m.row(i));
}

void writeVector(std::string& out, const char* key, const Eigen::VectorXd& v) {
  out += key;
  out += ": [";
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (i > 0) out += ", ";
    out += num(v(i));
  }
  out += "]\n";
}

void writeMetadata(std::string& out, const ClipMetadata& m) {
  out += "metadata:\n";
  out += "  source_file: " + quoted(m.source_file) + "\n";
  out += "  license: " + quoted(m.license) + "\n";
  out += "  robot: " + quoted(m.robot) + "\n";
  out += "  frame_begin: " + std::to_string(m.frame_begin) + "\n";
  out += "  frame_end: " + std::to_string(m.frame_end) + "\n";
  out += "  source_fps: " + num(m.source_fps) + "\n";
  out += "  provenance: " + quoted(m.provenance) + "\n";
  out += "  retargeting: " + quoted(m.retargeting) + "\n";
  out += "  notes: " + quoted(m.notes) + "\n";
  out += "joint_names: [";
  for (std::size_t j = 0; j < m.joint_names.size(); ++j) {
    if (j > 0) out += ", ";
    out += m.joint_names[j];
  }
  out += "]\n";
}

// ---------------------------------------------------------------------------------------------
// Reading (pmg::yaml archive: unknown keys, types and non-finite numbers are refused with
// file:line, the key path and, for an unknown key, the nearest valid key)
// ---------------------------------------------------------------------------------------------

/// `contact.left` / `contact.right`.
struct FootContactFields {
  double mu = 0.0;
  double sigma = 0.0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("mu", &mu, "contact centre [phase units, 0..1)", yaml::kRequired);
    a->Visit("sigma", &sigma, "contact half-range [phase units, 0..0.5]", yaml::kRequired);
  }
};

struct ContactFields {
  FootContactFields left, right;
  template <class A>
  void Serialize(A* a) {
    a->Visit("left", &left, "left foot", yaml::kRequired);
    a->Visit("right", &right, "right foot", yaml::kRequired);
  }
};

/// `metadata:` (ClipMetadata without format_version and joint_names, which are top-level keys).
struct MetadataFields {
  std::string source_file, license, robot, provenance, retargeting, notes;
  int frame_begin = 0;
  int frame_end = 0;
  double source_fps = 0.0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("source_file", &source_file, "mocap file, relative to the mocap data root", yaml::kRequired);
    a->Visit("license", &license, "license of the source data", yaml::kRequired);
    a->Visit("robot", &robot, "robot model name", yaml::kRequired);
    a->Visit("frame_begin", &frame_begin, "first source frame (inclusive)", yaml::kRequired);
    a->Visit("frame_end", &frame_end, "last source frame (exclusive)", yaml::kRequired);
    a->Visit("source_fps", &source_fps, "source frame rate [Hz]", yaml::kRequired);
    a->Visit("provenance", &provenance, "mocap | mocap_mirrored | mocap_time_reversed | synthesized", yaml::kRequired);
    a->Visit("retargeting", &retargeting, "retargeting method", yaml::kRequired);
    a->Visit("notes", &notes, "what was done to the data");
  }
};

/// `implied_motion:` (optional, dynamic clips).
struct ImpliedMotionFields {
  YAML::Node amplitude, velocity;
  template <class A>
  void Serialize(A* a) {
    a->Visit("amplitude", &amplitude, "K amplitudes a, strictly increasing from 0", yaml::kRequired);
    a->Visit("velocity", &velocity, "K x 3 stance-implied (v_x [m/s], v_y [m/s], w [rad/s]) at each amplitude", yaml::kRequired);
  }
};

/// Every key of a clip file (docs/clip_format.md). The kind decides which keys exist: keys of the
/// other kind are unknown keys. Matrices are kept as nodes and read with their shapes checked.
struct ClipFields {
  explicit ClipFields(bool dynamic) : is_dynamic(dynamic) {}
  bool is_dynamic;
  int format_version = 0;
  std::string kind, name, axis;
  int direction = 0;
  double nominal_scale = 0.0, period = 0.0, neutral = 0.0;
  int num_samples = 0, num_joints = 0;
  ContactFields contact;
  ImpliedMotionFields implied_motion;
  MetadataFields metadata;
  std::vector<std::string> joint_names;
  YAML::Node q, qd, v_base, omega_base, base_height, values;
  template <class A>
  void Serialize(A* a) {
    a->Visit("format_version", &format_version, "clip format version (1)", yaml::kRequired);
    a->Visit("kind", &kind, "dynamic | static", yaml::kRequired);
    a->Visit("name", &name, "clip name", yaml::kRequired);
    a->Visit("axis", &axis, "forward | lateral | yaw (dynamic); pitch | roll | height (static)", yaml::kRequired);
    if (is_dynamic) {
      a->Visit("direction", &direction, "sign of the command the clip realises (+1 or -1)", yaml::kRequired);
      a->Visit("nominal_scale", &nominal_scale, "x̄: mean command over the cycle [m/s or rad/s]", yaml::kRequired);
      a->Visit("period", &period, "T: cycle duration [s]", yaml::kRequired);
    } else {
      a->Visit("neutral", &neutral, "command value of the standing posture", yaml::kRequired);
    }
    a->Visit("num_samples", &num_samples, "N (dynamic) or K (static), >= 2", yaml::kRequired);
    a->Visit("num_joints", &num_joints, "n: joints of the robot", yaml::kRequired);
    if (is_dynamic) a->Visit("contact", &contact, "contact model of each foot", yaml::kRequired);
    if (is_dynamic)
      a->Visit("implied_motion", &implied_motion, "stance-implied base velocity against amplitude (optional)");
    a->Visit("metadata", &metadata, "provenance of the clip", yaml::kRequired);
    a->Visit("joint_names", &joint_names, "joint order of every q row", yaml::kRequired);
    if (is_dynamic) {
      a->Visit("q", &q, "N x n joint positions [rad]", yaml::kRequired);
      a->Visit("qd", &qd, "N x n joint velocities [rad/s]", yaml::kRequired);
      a->Visit("v_base", &v_base, "N x 3 pelvis velocity in the heading frame [m/s]", yaml::kRequired);
      a->Visit("omega_base", &omega_base, "N x 3 pelvis angular velocity in the heading frame [rad/s]", yaml::kRequired);
      a->Visit("base_height", &base_height, "N pelvis heights [m]", yaml::kRequired);
    } else {
      a->Visit("values", &values, "K command values, strictly increasing", yaml::kRequired);
      a->Visit("q", &q, "K x n joint positions [rad]", yaml::kRequired);
    }
  }
};

/// A clip file being read: its document and the fields read from it.
struct ClipReader {
  yaml::YamlDocument doc;
  ClipFields fields;

  yaml::YamlSource at(const std::string& key) const { return yaml::childSource(doc.source, key); }

  /// rows × cols numbers of `key` (a list of rows, or one list when cols == 0: a vector).
  Eigen::MatrixXd matrix(const std::string& key, const YAML::Node& node, Eigen::Index rows, Eigen::Index cols,
                         const char* rows_name) const {
    std::vector<std::vector<double>> m;
    if (cols == 0) {
      std::vector<double> v;
      yaml::readYaml(node, at(key), &v);
      if (static_cast<Eigen::Index>(v.size()) != rows)
        yaml::fail(at(key), node, fmt::format("has {} entries: expected {} ({})", v.size(), rows, rows_name));
      return Eigen::Map<const Eigen::VectorXd>(v.data(), rows);
    }
    yaml::readYaml(node, at(key), &m);
    if (static_cast<Eigen::Index>(m.size()) != rows)
      yaml::fail(at(key), node, fmt::format("has {} rows: expected {} ({})", m.size(), rows, rows_name));
    Eigen::MatrixXd out(rows, cols);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const auto& row = m[static_cast<std::size_t>(i)];
      if (static_cast<Eigen::Index>(row.size()) != cols)
        yaml::fail(at(fmt::format("{}[{}]", key, i)), node[static_cast<std::size_t>(i)],
                   fmt::format("has {} columns: expected {}", row.size(), cols));
      for (Eigen::Index j = 0; j < cols; ++j) out(i, j) = row[static_cast<std::size_t>(j)];
    }
    return out;
  }
};

/// The top-level map of a clip file, with format_version and kind checked first (a file of another
/// version or kind is named as such, not as a list of unknown keys).
yaml::YamlDocument openClipDocument(const std::string& path, const char* expected_kind) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw ClipFormatError(path + ": cannot open clip file (no such file)");
  yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  if (!doc.root.IsMap()) yaml::fail(doc.source, doc.root, "expected a YAML mapping at the top level");
  const YAML::Node& root = doc.root;  // const: a look-up never inserts a key
  yaml::YamlSource src = yaml::childSource(doc.source, "format_version");
  const YAML::Node v = root["format_version"];
  if (!v) yaml::fail(doc.source, doc.root, "missing required key 'format_version'");
  int version = 0;
  yaml::readYaml(v, src, &version);
  if (version != kClipFormatVersion)
    yaml::fail(src, v, fmt::format("= {}: expected {} (this reader's version)", version, kClipFormatVersion));
  src = yaml::childSource(doc.source, "kind");
  const YAML::Node k = root["kind"];
  if (!k) yaml::fail(doc.source, doc.root, "missing required key 'kind'");
  std::string kind;
  yaml::readYaml(k, src, &kind);
  if (expected_kind != nullptr && kind != expected_kind)
    yaml::fail(src, k, "= '" + kind + "': expected '" + expected_kind + "'");
  if (kind != "dynamic" && kind != "static") yaml::fail(src, k, "= '" + kind + "': expected 'dynamic' or 'static'");
  return doc;
}

/// Runs @p read and turns the archive's pmg::ConfigError (file:line, key, message) into a
/// ClipFormatError with the same text.
template <class F>
auto asClipError(F&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const ClipFormatError&) {
    throw;
  } catch (const ConfigError& e) {
    throw ClipFormatError(e.what());
  }
}

/// Refuses the keys of @p map that @p fields does not declare (the archive's message: file:line,
/// key, nearest valid key). Run before reading, so that a misspelt required key is named as an
/// unknown key next to its correct spelling rather than as a missing one.
template <class Fields>
void checkKeys(const YAML::Node& map, const yaml::YamlSource& source, Fields& fields) {
  if (!map.IsMap()) return;
  yaml::FieldListArchive declared;
  fields.Serialize(&declared);
  std::vector<std::string> valid;
  for (const yaml::FieldInfo& f : declared.fields) valid.push_back(f.name);
  yaml::rejectUnknownKeys(map, source, valid);
}

ClipReader readFields(const std::string& path, const char* kind, const RobotConfig& robot) {
  ClipReader r{openClipDocument(path, kind), ClipFields(std::string(kind) == "dynamic")};
  const YAML::Node& root = r.doc.root;
  checkKeys(root, r.doc.source, r.fields);
  checkKeys(root["metadata"], r.at("metadata"), r.fields.metadata);
  if (r.fields.is_dynamic && root["contact"].IsMap()) {
    checkKeys(root["contact"], r.at("contact"), r.fields.contact);
    checkKeys(root["contact"]["left"], r.at("contact.left"), r.fields.contact.left);
    checkKeys(root["contact"]["right"], r.at("contact.right"), r.fields.contact.right);
  }
  yaml::readYaml(r.doc, &r.fields);
  const ClipFields& f = r.fields;
  if (f.num_samples < 2)
    yaml::fail(r.at("num_samples"), r.doc.root["num_samples"], fmt::format("= {}: expected >= 2", f.num_samples));
  if (f.num_joints != static_cast<int>(robot.numJoints()))
    yaml::fail(r.at("num_joints"), r.doc.root["num_joints"],
               fmt::format("= {}: expected {} (joints of robot '{}', {})", f.num_joints, robot.numJoints(), robot.name,
                           robot.source_file));
  return r;
}

ClipMetadata metadataOf(const ClipFields& f) {
  ClipMetadata m;
  m.format_version = f.format_version;
  m.source_file = f.metadata.source_file;
  m.license = f.metadata.license;
  m.robot = f.metadata.robot;
  m.joint_names = f.joint_names;
  m.frame_begin = f.metadata.frame_begin;
  m.frame_end = f.metadata.frame_end;
  m.source_fps = f.metadata.source_fps;
  m.provenance = f.metadata.provenance;
  m.retargeting = f.metadata.retargeting;
  m.notes = f.metadata.notes;
  return m;
}

CommandAxis parseCommandAxis(const ClipReader& r) {
  const std::string& s = r.fields.axis;
  if (s == "forward") return CommandAxis::kForward;
  if (s == "lateral") return CommandAxis::kLateral;
  if (s == "yaw") return CommandAxis::kYaw;
  yaml::fail(r.at("axis"), r.doc.root["axis"], "= '" + s + "': expected one of forward, lateral, yaw");
}

PostureAxis parsePostureAxis(const ClipReader& r) {
  const std::string& s = r.fields.axis;
  if (s == "pitch") return PostureAxis::kPitch;
  if (s == "roll") return PostureAxis::kRoll;
  if (s == "height") return PostureAxis::kHeight;
  yaml::fail(r.at("axis"), r.doc.root["axis"], "= '" + s + "': expected one of pitch, roll, height");
}

}  // namespace

std::string clipToYaml(const DynamicClip& clip) {
  std::string out;
  out.reserve(64 * 1024);
  out += "# PMG dynamic clip (one gait cycle). Format: docs/clip_format.md\n";
  out += "format_version: " + std::to_string(clip.meta.format_version) + "\n";
  out += "kind: dynamic\n";
  out += "name: " + quoted(clip.name) + "\n";
  out += "axis: " + toString(clip.axis) + "\n";
  out += "direction: " + std::to_string(clip.direction) + "\n";
  out += "nominal_scale: " + num(clip.nominal_scale) + "\n";
  out += "period: " + num(clip.period) + "\n";
  out += "num_samples: " + std::to_string(clip.q.rows()) + "\n";
  out += "num_joints: " + std::to_string(clip.q.cols()) + "\n";
  out += "contact:\n";
  out += "  left: {mu: " + num(clip.contact[0].mu) + ", sigma: " + num(clip.contact[0].sigma) + "}\n";
  out += "  right: {mu: " + num(clip.contact[1].mu) + ", sigma: " + num(clip.contact[1].sigma) + "}\n";
  if (!clip.implied.empty()) {
    out += "implied_motion:  # stance-implied base velocity (v_x, v_y, w) of the clip played alone at amplitude a\n";
    out += "  amplitude: [";
    for (Eigen::Index i = 0; i < clip.implied.amplitude.size(); ++i) out += (i > 0 ? ", " : "") + num(clip.implied.amplitude(i));
    out += "]\n  velocity:\n";
    for (Eigen::Index i = 0; i < clip.implied.velocity.rows(); ++i) {
      out += "  ";
      writeRow(out, clip.implied.velocity.row(i));
    }
  }
  writeMetadata(out, clip.meta);
  writeMatrix(out, "q", clip.q);
  writeMatrix(out, "qd", clip.qd);
  writeMatrix(out, "v_base", clip.v_base);
  writeMatrix(out, "omega_base", clip.omega_base);
  writeVector(out, "base_height", clip.base_height);
  return out;
}

std::string clipToYaml(const StaticClip& clip) {
  std::string out;
  out.reserve(16 * 1024);
  out += "# PMG static clip (posture template over a command range). Format: docs/clip_format.md\n";
  out += "format_version: " + std::to_string(clip.meta.format_version) + "\n";
  out += "kind: static\n";
  out += "name: " + quoted(clip.name) + "\n";
  out += "axis: " + toString(clip.axis) + "\n";
  out += "neutral: " + num(clip.neutral) + "\n";
  out += "num_samples: " + std::to_string(clip.q.rows()) + "\n";
  out += "num_joints: " + std::to_string(clip.q.cols()) + "\n";
  writeMetadata(out, clip.meta);
  writeVector(out, "values", clip.values);
  writeMatrix(out, "q", clip.q);
  return out;
}

namespace {
/// Writes @p text to a temporary file beside @p path, then renames it onto @p path.
void writeText(const std::string& text, const std::string& path) {
  const fs::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  const fs::path tmp = p.parent_path() / ("." + p.filename().string() + ".tmp");
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw ClipFormatError(path + ": cannot open " + tmp.string() + " for writing");
    f << text;
    f.flush();
    if (!f) {
      fs::remove(tmp, ec);
      throw ClipFormatError(path + ": write failed");
    }
  }
  fs::rename(tmp, p, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw ClipFormatError(path + ": cannot rename the written file onto it: " + ec.message());
  }
}
}  // namespace

void writeClip(const DynamicClip& clip, const std::string& path) { writeText(clipToYaml(clip), path); }
void writeClip(const StaticClip& clip, const std::string& path) { writeText(clipToYaml(clip), path); }

ClipKind readClipKind(const std::string& path) {
  const yaml::YamlDocument doc = asClipError([&] { return openClipDocument(path, nullptr); });  // const look-ups
  return doc.root["kind"].Scalar() == "dynamic" ? ClipKind::kDynamic : ClipKind::kStatic;
}

DynamicClip readDynamicClip(const std::string& path, const RobotConfig& robot, const ClipValidationOptions& options) {
  DynamicClip c = asClipError([&] {
    const ClipReader r = readFields(path, "dynamic", robot);
    const ClipFields& f = r.fields;
    const Eigen::Index N = f.num_samples, n = f.num_joints;
    DynamicClip d;
    d.name = f.name;
    d.axis = parseCommandAxis(r);
    d.direction = f.direction;
    d.nominal_scale = f.nominal_scale;
    d.period = f.period;
    d.contact = {FootContact{f.contact.left.mu, f.contact.left.sigma}, FootContact{f.contact.right.mu, f.contact.right.sigma}};
    d.meta = metadataOf(f);
    d.q = r.matrix("q", f.q, N, n, "num_samples");
    d.qd = r.matrix("qd", f.qd, N, n, "num_samples");
    d.v_base = r.matrix("v_base", f.v_base, N, 3, "num_samples");
    d.omega_base = r.matrix("omega_base", f.omega_base, N, 3, "num_samples");
    d.base_height = r.matrix("base_height", f.base_height, N, 0, "num_samples");
    if (f.implied_motion.amplitude) {
      std::vector<double> a;
      yaml::readYaml(f.implied_motion.amplitude, r.at("implied_motion.amplitude"), &a);
      const auto K = static_cast<Eigen::Index>(a.size());
      d.implied.amplitude = Eigen::Map<const Eigen::VectorXd>(a.data(), K);
      d.implied.velocity = r.matrix("implied_motion.velocity", f.implied_motion.velocity, K, 3, "implied_motion.amplitude");
    }
    return d;
  });
  validateClip(c, robot, path, options);
  return c;
}

StaticClip readStaticClip(const std::string& path, const RobotConfig& robot, const ClipValidationOptions& options) {
  StaticClip c = asClipError([&] {
    const ClipReader r = readFields(path, "static", robot);
    const ClipFields& f = r.fields;
    const Eigen::Index K = f.num_samples, n = f.num_joints;
    StaticClip s;
    s.name = f.name;
    s.axis = parsePostureAxis(r);
    s.neutral = f.neutral;
    s.meta = metadataOf(f);
    s.values = r.matrix("values", f.values, K, 0, "num_samples");
    s.q = r.matrix("q", f.q, K, n, "num_samples");
    return s;
  });
  validateClip(c, robot, path, options);
  return c;
}

ClipLibrary loadClipLibrary(const std::vector<std::string>& files, const RobotConfig& robot,
                            const ClipValidationOptions& options) {
  ClipLibrary lib;
  for (const std::string& file : files) {
    if (readClipKind(file) == ClipKind::kDynamic)
      lib.dynamic_clips.push_back(readDynamicClip(file, robot, options));
    else
      lib.static_clips.push_back(readStaticClip(file, robot, options));
    validateLibraryAxes(lib, file);  // the clip just read duplicates an earlier one: name its file
  }
  return lib;
}

ClipLibrary loadClipLibrary(const std::string& directory, const RobotConfig& robot, const ClipValidationOptions& options) {
  if (!fs::is_directory(directory)) throw ClipFormatError(directory + ": clip library directory does not exist");
  std::vector<std::string> files;
  std::string map_file;
  for (const auto& entry : fs::directory_iterator(directory)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".yaml") continue;
    if (entry.path().filename() == kConsistencyMapFile)
      map_file = entry.path().string();
    else
      files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  ClipLibrary lib = loadClipLibrary(files, robot, options);
  if (!map_file.empty()) lib.consistency = readConsistencyMap(map_file);
  return lib;
}

namespace {
struct ConsistencyMapFields {
  int format_version = 0;
  std::string kind;
  std::vector<double> vx, vy, wz, height, pitch;
  YAML::Node delta;
  template <class A>
  void Serialize(A* a) {
    a->Visit("format_version", &format_version, "clip format version (1)", yaml::kRequired);
    a->Visit("kind", &kind, "consistency_map", yaml::kRequired);
    a->Visit("vx", &vx, "grid of v_x [m/s], strictly increasing", yaml::kRequired);
    a->Visit("vy", &vy, "grid of v_y [m/s], strictly increasing", yaml::kRequired);
    a->Visit("wz", &wz, "grid of the yaw rate [rad/s], strictly increasing", yaml::kRequired);
    a->Visit("height", &height, "grid of the pelvis height [m], strictly increasing", yaml::kRequired);
    a->Visit("pitch", &pitch, "grid of the torso pitch command [rad], strictly increasing", yaml::kRequired);
    a->Visit("delta", &delta, "n_vx*n_vy*n_wz*n_height*n_pitch rows of (dv_x, dv_y, dw)", yaml::kRequired);
  }
};
}  // namespace

std::string consistencyMapToYaml(const ConsistencyMap& map, const std::string& comment) {
  std::string out = "# PMG consistency map (command-consistent blending). Format: docs/clip_format.md\n";
  if (!comment.empty()) out += "# " + comment + "\n";
  out += "format_version: " + std::to_string(kClipFormatVersion) + "\nkind: consistency_map\n";
  const char* keys[kConsistencyMapDims] = {"vx", "vy", "wz", "height", "pitch"};
  for (std::size_t d = 0; d < kConsistencyMapDims; ++d) writeVector(out, keys[d], map.grid[d]);
  writeMatrix(out, "delta", map.delta);
  return out;
}

void writeConsistencyMap(const ConsistencyMap& map, const std::string& comment, const std::string& path) {
  writeText(consistencyMapToYaml(map, comment), path);
}

ConsistencyMap readConsistencyMap(const std::string& path) {
  return asClipError([&] {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw ClipFormatError(path + ": cannot open consistency map (no such file)");
    yaml::YamlDocument doc = yaml::loadYamlDocument(path);
    ConsistencyMapFields f;
    yaml::readYaml(doc.root, doc.source, &f);
    const yaml::YamlSource src = doc.source;
    if (f.format_version != kClipFormatVersion)
      yaml::fail(yaml::childSource(src, "format_version"), doc.root["format_version"],
                 fmt::format("= {}: expected {}", f.format_version, kClipFormatVersion));
    if (f.kind != "consistency_map")
      yaml::fail(yaml::childSource(src, "kind"), doc.root["kind"], "= '" + f.kind + "': expected 'consistency_map'");
    ConsistencyMap m;
    const std::vector<double>* g[kConsistencyMapDims] = {&f.vx, &f.vy, &f.wz, &f.height, &f.pitch};
    const char* keys[kConsistencyMapDims] = {"vx", "vy", "wz", "height", "pitch"};
    Eigen::Index rows = 1;
    for (std::size_t d = 0; d < kConsistencyMapDims; ++d) {
      if (g[d]->empty()) yaml::fail(yaml::childSource(src, keys[d]), doc.root[keys[d]], "is empty: expected >= 1 value");
      for (std::size_t i = 1; i < g[d]->size(); ++i)
        if (!((*g[d])[i] > (*g[d])[i - 1]))
          yaml::fail(yaml::childSource(src, keys[d]), doc.root[keys[d]], fmt::format("[{}]: expected strictly increasing", i));
      m.grid[d] = Eigen::Map<const Eigen::VectorXd>(g[d]->data(), static_cast<Eigen::Index>(g[d]->size()));
      rows *= static_cast<Eigen::Index>(g[d]->size());
    }
    std::vector<std::vector<double>> delta;
    yaml::readYaml(f.delta, yaml::childSource(src, "delta"), &delta);
    if (static_cast<Eigen::Index>(delta.size()) != rows)
      yaml::fail(yaml::childSource(src, "delta"), f.delta, fmt::format("has {} rows: expected {} (the grid sizes' product)", delta.size(), rows));
    m.delta.resize(rows, 3);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const auto& row = delta[static_cast<std::size_t>(i)];
      if (row.size() != 3)
        yaml::fail(yaml::childSource(src, fmt::format("delta[{}]", i)), f.delta, fmt::format("has {} columns: expected 3", row.size()));
      for (Eigen::Index c = 0; c < 3; ++c) {
        const double v = row[static_cast<std::size_t>(c)];
        if (!(std::fabs(v) <= 2.0))
          yaml::fail(yaml::childSource(src, fmt::format("delta[{}]", i)), f.delta, fmt::format("= {}: expected |value| <= 2", v));
        m.delta(i, c) = v;
      }
    }
    return m;
  });
}

std::string clipsDigest(const ClipLibrary& library) {
  std::vector<std::pair<std::string, const Eigen::MatrixXd*>> clips;
  for (const DynamicClip& c : library.dynamic_clips) clips.emplace_back(c.name, &c.q);
  for (const StaticClip& c : library.static_clips) clips.emplace_back(c.name, &c.q);
  std::sort(clips.begin(), clips.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::uint64_t h = 0xcbf29ce484222325ULL;
  auto byte = [&h](unsigned char b) {
    h ^= b;
    h *= 0x100000001b3ULL;
  };
  for (const auto& [name, q] : clips) {
    for (const char ch : name) byte(static_cast<unsigned char>(ch));
    for (Eigen::Index i = 0; i < q->rows(); ++i)
      for (Eigen::Index j = 0; j < q->cols(); ++j) {
        const auto v = static_cast<std::int64_t>(std::floor((*q)(i, j) * 1e4 + 0.5));
        const auto u = static_cast<std::uint64_t>(v);
        for (int k = 0; k < 8; ++k) byte(static_cast<unsigned char>((u >> (8 * k)) & 0xffU));
      }
  }
  char out[17];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
  return std::string("fnv1a64:") + out;  // the prefix keeps the contract check from reading it as a number
}

}  // namespace pmg
