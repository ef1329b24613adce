#include "pmg/motion/bvh.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg::motion {
namespace {

/// Whitespace tokenizer that remembers line numbers.
class Tokens {
 public:
  Tokens(const std::string& path) : path_(path), in_(path) {
    if (!in_) throw std::runtime_error(path + ": cannot open BVH file");
  }
  bool next(std::string& tok) {
    while (!(line_stream_ >> tok)) {
      std::string line;
      if (!std::getline(in_, line)) return false;
      ++line_no_;
      line_stream_.clear();
      line_stream_.str(line);
    }
    return true;
  }
  std::string expectAny(const char* what) {
    std::string t;
    if (!next(t)) fail(fmt::format("unexpected end of file: expected {}", what));
    return t;
  }
  void expect(const std::string& word) {
    const std::string t = expectAny(word.c_str());
    if (t != word) fail(fmt::format("'{}': expected '{}'", t, word));
  }
  double number(const char* what) {
    const std::string t = expectAny(what);
    try {
      std::size_t used = 0;
      const double v = std::stod(t, &used);
      if (used != t.size() || !std::isfinite(v)) throw std::invalid_argument(t);
      return v;
    } catch (const std::exception&) {
      fail(fmt::format("'{}': expected a number ({})", t, what));
    }
  }
  /// Reads the rest of the current line, then whole lines.
  bool line(std::string& out) {
    std::string rest;
    std::getline(line_stream_, rest);
    if (rest.find_first_not_of(" \t\r") != std::string::npos) {
      out = rest;
      line_stream_.clear();
      line_stream_.str("");
      return true;
    }
    line_stream_.clear();
    line_stream_.str("");
    while (std::getline(in_, out)) {
      ++line_no_;
      if (out.find_first_not_of(" \t\r") != std::string::npos) return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(fmt::format("{}:{}: {}", path_, line_no_, what));
  }
  int lineNo() const { return line_no_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::istringstream line_stream_;
  int line_no_ = 0;
};

bool validChannel(const std::string& c) {
  return c == "Xposition" || c == "Yposition" || c == "Zposition" || c == "Xrotation" || c == "Yrotation" || c == "Zrotation";
}

void parseJoint(Tokens& t, BvhMotion& m, int parent, const std::string& name) {
  BvhJoint j;
  j.name = name;
  j.parent = parent;
  t.expect("{");
  t.expect("OFFSET");
  j.offset.x() = t.number("OFFSET x");
  j.offset.y() = t.number("OFFSET y");
  j.offset.z() = t.number("OFFSET z");
  const int index = static_cast<int>(m.joints.size());
  if (name.size() < 4 || name.substr(name.size() - 4) != "_end") {
    t.expect("CHANNELS");
    const double count = t.number("channel count");
    if (count < 0 || count > 6 || count != std::floor(count)) t.fail(fmt::format("CHANNELS {}: expected 0..6", count));
    j.channel_begin = m.num_channels;
    for (int c = 0; c < static_cast<int>(count); ++c) {
      const std::string ch = t.expectAny("channel name");
      if (!validChannel(ch)) t.fail(fmt::format("channel '{}' of joint {}: expected [XYZ]position or [XYZ]rotation", ch, name));
      j.channels.push_back(ch);
    }
    m.num_channels += static_cast<int>(count);
  }
  m.joints.push_back(j);
  while (true) {
    const std::string tok = t.expectAny("JOINT, End or }");
    if (tok == "}") return;
    if (tok == "JOINT") {
      parseJoint(t, m, index, t.expectAny("joint name"));
    } else if (tok == "End") {
      t.expect("Site");
      parseJoint(t, m, index, name + "_end");
    } else {
      t.fail(fmt::format("'{}' in joint {}: expected JOINT, End Site or }}", tok, name));
    }
  }
}

Eigen::Matrix3d axisRotation(char axis, double degrees) {
  const double a = degrees * M_PI / 180.0;
  const Eigen::Vector3d ax = axis == 'X' ? Eigen::Vector3d::UnitX() : axis == 'Y' ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  return Eigen::AngleAxisd(a, ax).toRotationMatrix();
}

}  // namespace

int BvhMotion::jointIndex(const std::string& name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  throw std::runtime_error(source_file + ": BVH joint '" + name + "' not found in the HIERARCHY");
}

BvhMotion readBvh(const std::string& path) {
  Tokens t(path);
  BvhMotion m;
  m.source_file = path;
  t.expect("HIERARCHY");
  t.expect("ROOT");
  parseJoint(t, m, -1, t.expectAny("root name"));
  t.expect("MOTION");
  t.expect("Frames:");
  const double frames = t.number("frame count");
  if (frames < 1 || frames != std::floor(frames)) t.fail(fmt::format("Frames: {}: expected a positive integer", frames));
  t.expect("Frame");
  t.expect("Time:");
  m.frame_time = t.number("frame time");
  if (!(m.frame_time > 0.0)) t.fail(fmt::format("Frame Time: {}: expected > 0 [s]", m.frame_time));
  const int F = static_cast<int>(frames);
  m.values.resize(F, m.num_channels);
  std::string line;
  for (int k = 0; k < F; ++k) {
    if (!t.line(line)) t.fail(fmt::format("file ends after {} frame lines: Frames: says {}", k, F));
    std::istringstream ls(line);
    std::string tok;
    int c = 0;
    while (ls >> tok) {
      if (c >= m.num_channels) t.fail(fmt::format("frame {}: more than {} values (channels in HIERARCHY)", k, m.num_channels));
      try {
        std::size_t used = 0;
        m.values(k, c) = std::stod(tok, &used);
        if (used != tok.size() || !std::isfinite(m.values(k, c))) throw std::invalid_argument(tok);
      } catch (const std::exception&) {
        t.fail(fmt::format("frame {} value {} '{}': expected a number", k, c, tok));
      }
      ++c;
    }
    if (c != m.num_channels) t.fail(fmt::format("frame {}: {} values: expected {} (channels in HIERARCHY)", k, c, m.num_channels));
  }
  if (t.line(line)) t.fail(fmt::format("extra data after the {} frames that Frames: declares", F));
  return m;
}

void bvhForwardKinematics(const BvhMotion& m, int frame, std::vector<Eigen::Vector3d>& p, std::vector<Eigen::Matrix3d>& R) {
  p.resize(m.joints.size());
  R.resize(m.joints.size());
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    const BvhJoint& j = m.joints[i];
    Eigen::Vector3d translation = j.offset;
    Eigen::Matrix3d local = Eigen::Matrix3d::Identity();
    for (std::size_t c = 0; c < j.channels.size(); ++c) {
      const double v = m.values(frame, j.channel_begin + static_cast<int>(c));
      const std::string& ch = j.channels[c];
      if (ch[1] == 'p') {
        translation(ch[0] - 'X') = v;  // position channels replace the offset
      } else {
        local = local * axisRotation(ch[0], v);
      }
    }
    if (j.parent < 0) {
      p[i] = translation;
      R[i] = local;
    } else {
      const auto pi = static_cast<std::size_t>(j.parent);
      p[i] = p[pi] + R[pi] * j.offset;
      R[i] = R[pi] * local;
    }
  }
}

HumanMotion bvhToHuman(const BvhMotion& m, double unit_scale) {
  HumanMotion h;
  h.source_file = m.source_file;
  h.format = "bvh";
  h.fps = 1.0 / m.frame_time;
  h.ankle_height = 0.08;
  Eigen::Matrix3d T;  // file axes → W: x_W = z_file (rest facing), y_W = x_file (left), z_W = y_file (up)
  T << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  const int hips = m.jointIndex("Hips"), spine = m.jointIndex("Spine1");
  const int up[2] = {m.jointIndex("LeftUpLeg"), m.jointIndex("RightUpLeg")};
  const int leg[2] = {m.jointIndex("LeftLeg"), m.jointIndex("RightLeg")};
  const int foot[2] = {m.jointIndex("LeftFoot"), m.jointIndex("RightFoot")};
  const int arm[2] = {m.jointIndex("LeftArm"), m.jointIndex("RightArm")};
  const int fore[2] = {m.jointIndex("LeftForeArm"), m.jointIndex("RightForeArm")};
  const int hand[2] = {m.jointIndex("LeftHand"), m.jointIndex("RightHand")};
  std::vector<Eigen::Vector3d> p;
  std::vector<Eigen::Matrix3d> R;
  h.frames.resize(static_cast<std::size_t>(m.numFrames()));
  for (int k = 0; k < m.numFrames(); ++k) {
    bvhForwardKinematics(m, k, p, R);
    HumanFrame& o = h.frames[static_cast<std::size_t>(k)];
    auto P = [&](int j) -> Eigen::Vector3d { return unit_scale * (T * p[static_cast<std::size_t>(j)]); };
    auto Q = [&](int j) { return Eigen::Quaterniond(T * R[static_cast<std::size_t>(j)] * T.transpose()); };
    o.p_WK[static_cast<std::size_t>(Keypoint::kPelvis)] = P(hips);
    o.R_WPelvis = Q(hips);
    o.R_WTorso = Q(spine);
    for (int s = 0; s < 2; ++s) {
      const bool left = s == 0;
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftHip : Keypoint::kRightHip)] = P(up[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftKnee : Keypoint::kRightKnee)] = P(leg[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftAnkle : Keypoint::kRightAnkle)] = P(foot[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftShoulder : Keypoint::kRightShoulder)] = P(arm[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftElbow : Keypoint::kRightElbow)] = P(fore[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftWrist : Keypoint::kRightWrist)] = P(hand[s]);
      o.R_WFoot[static_cast<std::size_t>(s)] = Q(foot[s]);
      o.p_WK[static_cast<std::size_t>(left ? Keypoint::kLeftToe : Keypoint::kRightToe)] =
          P(foot[s]) + o.R_WFoot[static_cast<std::size_t>(s)].toRotationMatrix() * Eigen::Vector3d(kToeOffset, 0, 0);
    }
  }
  putOnGround(h);
  return h;
}

}  // namespace pmg::motion
