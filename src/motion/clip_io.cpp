#include "pmg/motion/clip_io.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

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
// Reading
// ---------------------------------------------------------------------------------------------

/// Context of one file being read: builds error messages "file:line: field ...".
struct Reader {
  std::string file;
  YAML::Node root;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                         const std::string& what) const {
    std::string where = file;
    if (node.IsDefined() && node.Mark().line >= 0) where += ":" + std::to_string(node.Mark().line + 1);
    throw ClipFormatError(where + ": " + field + ": " + what);
  }

  YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    const YAML::Node n = parent[key];
    if (!n.IsDefined() || n.IsNull()) fail(parent, field, "missing (required key)");
    return n;
  }

  double getDouble(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, field, "'" + n.Scalar() + "' is not a number");
    }
    if (!std::isfinite(v)) fail(n, field, "'" + n.Scalar() + "': expected a finite number");
    return v;
  }

  int getInt(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected an integer");
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail(n, field, "'" + n.Scalar() + "' is not an integer");
    }
  }

  std::string getString(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected a string");
    return n.Scalar();
  }

  Eigen::MatrixXd getMatrix(const YAML::Node& parent, const std::string& key, Eigen::Index rows,
                            Eigen::Index cols) const {
    const YAML::Node n = require(parent, key, key);
    if (!n.IsSequence()) fail(n, key, "expected a list of rows");
    if (static_cast<Eigen::Index>(n.size()) != rows)
      fail(n, key, fmt::format("has {} rows: expected {} (num_samples)", n.size(), rows));
    Eigen::MatrixXd m(rows, cols);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const YAML::Node row = n[static_cast<std::size_t>(i)];
      const std::string rf = fmt::format("{}[{}]", key, i);
      if (!row.IsSequence()) fail(row, rf, "expected a list of numbers");
      if (static_cast<Eigen::Index>(row.size()) != cols)
        fail(row, rf, fmt::format("has {} columns: expected {}", row.size(), cols));
      for (Eigen::Index j = 0; j < cols; ++j)
        m(i, j) = getDouble(row[static_cast<std::size_t>(j)], fmt::format("{}[{}]", rf, j));
    }
    return m;
  }

  Eigen::VectorXd getVector(const YAML::Node& parent, const std::string& key, Eigen::Index size,
                            const char* size_name) const {
    const YAML::Node n = require(parent, key, key);
    if (!n.IsSequence()) fail(n, key, "expected a list of numbers");
    if (size >= 0 && static_cast<Eigen::Index>(n.size()) != size)
      fail(n, key, fmt::format("has {} entries: expected {} ({})", n.size(), size, size_name));
    Eigen::VectorXd v(static_cast<Eigen::Index>(n.size()));
    for (std::size_t i = 0; i < n.size(); ++i) v(static_cast<Eigen::Index>(i)) = getDouble(n[i], fmt::format("{}[{}]", key, i));
    return v;
  }

  ClipMetadata getMetadata() const {
    ClipMetadata m;
    m.format_version = getInt(require(root, "format_version", "format_version"), "format_version");
    const YAML::Node md = require(root, "metadata", "metadata");
    m.source_file = getString(require(md, "source_file", "metadata.source_file"), "metadata.source_file");
    m.license = getString(require(md, "license", "metadata.license"), "metadata.license");
    m.robot = getString(require(md, "robot", "metadata.robot"), "metadata.robot");
    m.frame_begin = getInt(require(md, "frame_begin", "metadata.frame_begin"), "metadata.frame_begin");
    m.frame_end = getInt(require(md, "frame_end", "metadata.frame_end"), "metadata.frame_end");
    m.source_fps = getDouble(require(md, "source_fps", "metadata.source_fps"), "metadata.source_fps");
    m.provenance = getString(require(md, "provenance", "metadata.provenance"), "metadata.provenance");
    m.retargeting = getString(require(md, "retargeting", "metadata.retargeting"), "metadata.retargeting");
    const YAML::Node notes = md["notes"];
    if (notes.IsDefined() && !notes.IsNull()) m.notes = getString(notes, "metadata.notes");
    const YAML::Node names = require(root, "joint_names", "joint_names");
    if (!names.IsSequence()) fail(names, "joint_names", "expected a list of joint names");
    for (std::size_t j = 0; j < names.size(); ++j)
      m.joint_names.push_back(getString(names[j], fmt::format("joint_names[{}]", j)));
    return m;
  }

  void checkHeader(const std::string& expected_kind) const {
    const YAML::Node v = require(root, "format_version", "format_version");
    const int version = getInt(v, "format_version");
    if (version != kClipFormatVersion)
      fail(v, "format_version", fmt::format("= {}: expected {} (this reader's version)", version, kClipFormatVersion));
    const YAML::Node k = require(root, "kind", "kind");
    const std::string kind = getString(k, "kind");
    if (kind != expected_kind) fail(k, "kind", "= '" + kind + "': expected '" + expected_kind + "'");
  }
};

Reader openReader(const std::string& path) {
  Reader r;
  r.file = path;
  if (!fs::is_regular_file(path)) throw ClipFormatError(path + ": cannot open clip file (no such file)");
  try {
    r.root = YAML::LoadFile(path);
  } catch (const YAML::ParserException& e) {
    throw ClipFormatError(fmt::format("{}:{}: YAML syntax error: {}", path, e.mark.line + 1, e.msg));
  } catch (const YAML::Exception& e) {
    throw ClipFormatError(path + ": cannot read clip file: " + e.what());
  }
  if (!r.root.IsMap()) throw ClipFormatError(path + ": expected a YAML mapping at the top level");
  return r;
}

CommandAxis parseCommandAxis(const Reader& r, const YAML::Node& n) {
  const std::string s = r.getString(n, "axis");
  if (s == "forward") return CommandAxis::kForward;
  if (s == "lateral") return CommandAxis::kLateral;
  if (s == "yaw") return CommandAxis::kYaw;
  r.fail(n, "axis", "= '" + s + "': expected one of forward, lateral, yaw");
}

PostureAxis parsePostureAxis(const Reader& r, const YAML::Node& n) {
  const std::string s = r.getString(n, "axis");
  if (s == "pitch") return PostureAxis::kPitch;
  if (s == "roll") return PostureAxis::kRoll;
  if (s == "height") return PostureAxis::kHeight;
  r.fail(n, "axis", "= '" + s + "': expected one of pitch, roll, height");
}

// ---------------------------------------------------------------------------------------------
// Validation helpers
// ---------------------------------------------------------------------------------------------

[[noreturn]] void invalid(const std::string& where, const std::string& field, const std::string& what) {
  throw ClipFormatError(where + ": " + field + ": " + what);
}

void checkFinite(const Eigen::MatrixXd& m, const std::string& where, const char* field) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j)
      if (!std::isfinite(m(i, j))) invalid(where, fmt::format("{}[{}][{}]", field, i, j), "expected a finite number");
}

void checkJoints(const Eigen::MatrixXd& q, const ClipMetadata& meta, const RobotConfig& robot,
                 const std::string& where, const ClipValidationOptions& options) {
  const std::size_t n = robot.numJoints();
  if (static_cast<std::size_t>(q.cols()) != n)
    invalid(where, "q", fmt::format("has {} columns: expected {} (joints of robot '{}')", q.cols(), n, robot.name));
  if (meta.joint_names.size() != n)
    invalid(where, "joint_names", fmt::format("has {} names: expected {} (joints of robot '{}')",
                                              meta.joint_names.size(), n, robot.name));
  if (options.check_joint_names) {
    for (std::size_t j = 0; j < n; ++j)
      if (meta.joint_names[j] != robot.joints[j].name)
        invalid(where, fmt::format("joint_names[{}]", j),
                fmt::format("= '{}': expected '{}' (joint order of {})", meta.joint_names[j],
                            robot.joints[j].name, robot.source_file));
  }
  checkFinite(q, where, "q");
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const JointConfig& jc = robot.joints[j];
      const double v = q(i, static_cast<Eigen::Index>(j));
      if (v < jc.lower - options.limit_tolerance || v > jc.upper + options.limit_tolerance)
        invalid(where, fmt::format("q[{}][{}]", i, j),
                fmt::format("= {:.6f}: expected within joint limits [{}, {}] of {}", v, jc.lower, jc.upper, jc.name));
    }
  }
}

void checkMetadata(const ClipMetadata& meta, const std::string& where) {
  if (meta.format_version != kClipFormatVersion)
    invalid(where, "format_version", fmt::format("= {}: expected {}", meta.format_version, kClipFormatVersion));
  if (meta.frame_begin < 0 || meta.frame_end < meta.frame_begin)
    invalid(where, "metadata.frame_begin/frame_end",
            fmt::format("= {}/{}: expected 0 <= frame_begin <= frame_end", meta.frame_begin, meta.frame_end));
  if (!(meta.source_fps >= 0.0)) invalid(where, "metadata.source_fps", fmt::format("= {}: expected >= 0", meta.source_fps));
  static const std::set<std::string> kProvenance = {"mocap", "mocap_mirrored", "mocap_time_reversed", "synthesized"};
  if (kProvenance.count(meta.provenance) == 0)
    invalid(where, "metadata.provenance",
            "= '" + meta.provenance + "': expected one of mocap, mocap_mirrored, mocap_time_reversed, synthesized");
}

}  // namespace

void ClipValidationOptions::validate() const {
  if (!(limit_tolerance >= 0.0) || !std::isfinite(limit_tolerance))
    throw ClipFormatError(fmt::format("ClipValidationOptions.limit_tolerance = {}: expected finite >= 0", limit_tolerance));
}

std::string toString(CommandAxis axis) {
  switch (axis) {
    case CommandAxis::kForward: return "forward";
    case CommandAxis::kLateral: return "lateral";
    case CommandAxis::kYaw: return "yaw";
  }
  return "unknown";
}

std::string toString(PostureAxis axis) {
  switch (axis) {
    case PostureAxis::kPitch: return "pitch";
    case PostureAxis::kRoll: return "roll";
    case PostureAxis::kHeight: return "height";
  }
  return "unknown";
}

void validateClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options) {
  options.validate();
  checkMetadata(clip.meta, where);
  const Eigen::Index N = clip.q.rows();
  if (N < 2) invalid(where, "q", fmt::format("has {} rows: expected >= 2 phase samples", N));
  checkJoints(clip.q, clip.meta, robot, where, options);
  if (clip.qd.rows() != N || clip.qd.cols() != clip.q.cols())
    invalid(where, "qd", fmt::format("is {}x{}: expected {}x{} (same shape as q)", clip.qd.rows(), clip.qd.cols(), N, clip.q.cols()));
  if (clip.v_base.rows() != N || clip.v_base.cols() != 3)
    invalid(where, "v_base", fmt::format("is {}x{}: expected {}x3", clip.v_base.rows(), clip.v_base.cols(), N));
  if (clip.omega_base.rows() != N || clip.omega_base.cols() != 3)
    invalid(where, "omega_base", fmt::format("is {}x{}: expected {}x3", clip.omega_base.rows(), clip.omega_base.cols(), N));
  if (clip.base_height.size() != N)
    invalid(where, "base_height", fmt::format("has {} entries: expected {}", clip.base_height.size(), N));
  checkFinite(clip.qd, where, "qd");
  checkFinite(clip.v_base, where, "v_base");
  checkFinite(clip.omega_base, where, "omega_base");
  for (Eigen::Index i = 0; i < N; ++i)
    if (!(clip.base_height(i) > 0.0) || !std::isfinite(clip.base_height(i)))
      invalid(where, fmt::format("base_height[{}]", i), fmt::format("= {}: expected finite > 0 [m]", clip.base_height(i)));
  if (!(clip.period > 0.0) || !std::isfinite(clip.period))
    invalid(where, "period", fmt::format("= {}: expected T > 0 [s]", clip.period));
  if (!(clip.nominal_scale > 0.0) || !std::isfinite(clip.nominal_scale))
    invalid(where, "nominal_scale", fmt::format("= {}: expected x̄ > 0 [m/s or rad/s]", clip.nominal_scale));
  if (clip.direction != 1 && clip.direction != -1)
    invalid(where, "direction", fmt::format("= {}: expected +1 or -1", clip.direction));
  const char* feet[kNumFeet] = {"contact.left", "contact.right"};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const FootContact& c = clip.contact[f];
    if (!(c.mu >= 0.0 && c.mu < 1.0))
      invalid(where, std::string(feet[f]) + ".mu", fmt::format("= {}: expected in [0, 1) (phase units)", c.mu));
    if (!(c.sigma >= 0.0 && c.sigma <= 0.5))
      invalid(where, std::string(feet[f]) + ".sigma", fmt::format("= {}: expected in [0, 0.5] (phase units)", c.sigma));
  }
}

void validateClip(const StaticClip& clip, const RobotConfig& robot, const std::string& where,
                  const ClipValidationOptions& options) {
  options.validate();
  checkMetadata(clip.meta, where);
  const Eigen::Index K = clip.q.rows();
  if (K < 2) invalid(where, "q", fmt::format("has {} rows: expected >= 2 samples", K));
  if (clip.values.size() != K)
    invalid(where, "values", fmt::format("has {} entries: expected {} (rows of q)", clip.values.size(), K));
  for (Eigen::Index i = 0; i < K; ++i) {
    if (!std::isfinite(clip.values(i))) invalid(where, fmt::format("values[{}]", i), "expected a finite number");
    if (i > 0 && !(clip.values(i) > clip.values(i - 1)))
      invalid(where, fmt::format("values[{}]", i),
              fmt::format("= {}: expected strictly increasing (previous {})", clip.values(i), clip.values(i - 1)));
  }
  checkJoints(clip.q, clip.meta, robot, where, options);
  if (!std::isfinite(clip.neutral) || clip.neutral < clip.values(0) || clip.neutral > clip.values(K - 1))
    invalid(where, "neutral", fmt::format("= {}: expected within [{}, {}] (the values range)", clip.neutral,
                                          clip.values(0), clip.values(K - 1)));
}

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
void writeText(const std::string& text, const std::string& path) {
  const fs::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw ClipFormatError(path + ": cannot open for writing");
  f << text;
  if (!f) throw ClipFormatError(path + ": write failed");
}
}  // namespace

void writeClip(const DynamicClip& clip, const std::string& path) { writeText(clipToYaml(clip), path); }
void writeClip(const StaticClip& clip, const std::string& path) { writeText(clipToYaml(clip), path); }

ClipKind readClipKind(const std::string& path) {
  const Reader r = openReader(path);
  const YAML::Node k = r.require(r.root, "kind", "kind");
  const std::string kind = r.getString(k, "kind");
  if (kind == "dynamic") return ClipKind::kDynamic;
  if (kind == "static") return ClipKind::kStatic;
  r.fail(k, "kind", "= '" + kind + "': expected 'dynamic' or 'static'");
}

DynamicClip readDynamicClip(const std::string& path, const RobotConfig& robot, const ClipValidationOptions& options) {
  const Reader r = openReader(path);
  r.checkHeader("dynamic");
  DynamicClip c;
  c.name = r.getString(r.require(r.root, "name", "name"), "name");
  c.axis = parseCommandAxis(r, r.require(r.root, "axis", "axis"));
  c.direction = r.getInt(r.require(r.root, "direction", "direction"), "direction");
  c.nominal_scale = r.getDouble(r.require(r.root, "nominal_scale", "nominal_scale"), "nominal_scale");
  c.period = r.getDouble(r.require(r.root, "period", "period"), "period");
  const YAML::Node ns = r.require(r.root, "num_samples", "num_samples");
  const int N = r.getInt(ns, "num_samples");
  if (N < 2) r.fail(ns, "num_samples", fmt::format("= {}: expected >= 2", N));
  const YAML::Node nj = r.require(r.root, "num_joints", "num_joints");
  const int n = r.getInt(nj, "num_joints");
  if (n != static_cast<int>(robot.numJoints()))
    r.fail(nj, "num_joints", fmt::format("= {}: expected {} (joints of robot '{}')", n, robot.numJoints(), robot.name));
  const YAML::Node contact = r.require(r.root, "contact", "contact");
  const char* feet[kNumFeet] = {"left", "right"};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const std::string base = std::string("contact.") + feet[f];
    const YAML::Node fc = r.require(contact, feet[f], base);
    c.contact[f].mu = r.getDouble(r.require(fc, "mu", base + ".mu"), base + ".mu");
    c.contact[f].sigma = r.getDouble(r.require(fc, "sigma", base + ".sigma"), base + ".sigma");
  }
  c.meta = r.getMetadata();
  c.q = r.getMatrix(r.root, "q", N, n);
  c.qd = r.getMatrix(r.root, "qd", N, n);
  c.v_base = r.getMatrix(r.root, "v_base", N, 3);
  c.omega_base = r.getMatrix(r.root, "omega_base", N, 3);
  c.base_height = r.getVector(r.root, "base_height", N, "num_samples");
  validateClip(c, robot, path, options);
  return c;
}

StaticClip readStaticClip(const std::string& path, const RobotConfig& robot, const ClipValidationOptions& options) {
  const Reader r = openReader(path);
  r.checkHeader("static");
  StaticClip c;
  c.name = r.getString(r.require(r.root, "name", "name"), "name");
  c.axis = parsePostureAxis(r, r.require(r.root, "axis", "axis"));
  c.neutral = r.getDouble(r.require(r.root, "neutral", "neutral"), "neutral");
  const YAML::Node ns = r.require(r.root, "num_samples", "num_samples");
  const int K = r.getInt(ns, "num_samples");
  if (K < 2) r.fail(ns, "num_samples", fmt::format("= {}: expected >= 2", K));
  const YAML::Node nj = r.require(r.root, "num_joints", "num_joints");
  const int n = r.getInt(nj, "num_joints");
  if (n != static_cast<int>(robot.numJoints()))
    r.fail(nj, "num_joints", fmt::format("= {}: expected {} (joints of robot '{}')", n, robot.numJoints(), robot.name));
  c.meta = r.getMetadata();
  c.values = r.getVector(r.root, "values", K, "num_samples");
  c.q = r.getMatrix(r.root, "q", K, n);
  validateClip(c, robot, path, options);
  return c;
}

ClipLibrary loadClipLibrary(const std::vector<std::string>& files, const RobotConfig& robot,
                            const ClipValidationOptions& options) {
  ClipLibrary lib;
  for (const std::string& file : files) {
    if (readClipKind(file) == ClipKind::kDynamic) {
      DynamicClip c = readDynamicClip(file, robot, options);
      for (const DynamicClip& other : lib.dynamic_clips)
        if (other.axis == c.axis && other.direction == c.direction)
          throw ClipFormatError(fmt::format("{}: axis/direction: clip '{}' ({} {:+d}) duplicates clip '{}': expected at "
                                            "most one dynamic clip per (axis, direction)",
                                            file, c.name, toString(c.axis), c.direction, other.name));
      lib.dynamic_clips.push_back(std::move(c));
    } else {
      StaticClip c = readStaticClip(file, robot, options);
      for (const StaticClip& other : lib.static_clips)
        if (other.axis == c.axis)
          throw ClipFormatError(fmt::format("{}: axis: clip '{}' ({}) duplicates clip '{}': expected at most one static "
                                            "clip per posture axis",
                                            file, c.name, toString(c.axis), other.name));
      lib.static_clips.push_back(std::move(c));
    }
  }
  return lib;
}

ClipLibrary loadClipLibrary(const std::string& directory, const RobotConfig& robot, const ClipValidationOptions& options) {
  if (!fs::is_directory(directory)) throw ClipFormatError(directory + ": clip library directory does not exist");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(directory))
    if (entry.is_regular_file() && entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return loadClipLibrary(files, robot, options);
}

}  // namespace pmg
