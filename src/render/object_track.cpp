#include "pmg/render/object_track.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pmg::render {
namespace {

constexpr const char* kHeader = "t,body,x,y,z,qw,qx,qy,qz";
constexpr const char* kFields[] = {"t", "body", "x", "y", "z", "qw", "qx", "qy", "qz"};

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": " + what);
}

}  // namespace

const ObjectPose& ObjectTrack::at(const std::string& body, double t) const {
  const auto it = bodies.find(body);
  if (it == bodies.end()) throw std::out_of_range(source + ": no object '" + body + "' in the track");
  const std::vector<ObjectPose>& p = it->second;
  const auto after = std::upper_bound(p.begin(), p.end(), t, [](double v, const ObjectPose& s) { return v < s.t; });
  return after == p.begin() ? p.front() : *(after - 1);
}

ObjectTrack readObjectTrack(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error(csv_path + ": cannot open the object track");
  ObjectTrack track;
  track.source = csv_path;
  std::string line;
  int n = 0;
  if (!std::getline(in, line)) fail(csv_path, 1, "empty file, expected the header '" + std::string(kHeader) + "'");
  ++n;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != kHeader) fail(csv_path, 1, "header '" + line + "', expected '" + kHeader + "'");
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells.size() != 9) fail(csv_path, n, std::to_string(cells.size()) + " columns, expected 9 (" + kHeader + ")");
    double v[9] = {};
    for (int i = 0; i < 9; ++i) {
      if (i == 1) continue;
      const std::string& c = cells[static_cast<std::size_t>(i)];
      char* end = nullptr;
      v[i] = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size() || !std::isfinite(v[i]))
        fail(csv_path, n, std::string("field ") + kFields[i] + " = '" + c + "': expected a finite number");
    }
    const std::string& body = cells[1];
    if (body.empty()) fail(csv_path, n, "field body is empty, expected a MuJoCo body name");
    ObjectPose p;
    p.t = v[0];
    p.p_W = Eigen::Vector3d(v[2], v[3], v[4]);
    p.quat_W = Eigen::Vector4d(v[5], v[6], v[7], v[8]);
    const double norm = p.quat_W.norm();
    if (!(norm >= 0.9 && norm <= 1.1))
      fail(csv_path, n, "quaternion (qw, qx, qy, qz) of '" + body + "' has norm " + std::to_string(norm) + ", expected in [0.9, 1.1]");
    p.quat_W /= norm;
    std::vector<ObjectPose>& poses = track.bodies[body];
    if (!poses.empty() && !(p.t > poses.back().t))
      fail(csv_path, n, "field t = " + cells[0] + " of '" + body + "': expected greater than its previous " + std::to_string(poses.back().t) + " s");
    poses.push_back(p);
  }
  if (track.bodies.empty()) fail(csv_path, n, "no rows after the header");
  return track;
}

}  // namespace pmg::render
