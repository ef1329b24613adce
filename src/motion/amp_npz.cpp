#include "pmg/motion/amp_npz.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg::motion {
namespace {

std::uint32_t u32(const unsigned char* p) { return p[0] | (p[1] << 8) | (p[2] << 16) | (static_cast<std::uint32_t>(p[3]) << 24); }
std::uint16_t u16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }

/// Value of `'key': value` in a numpy header dict (value up to the next top-level comma or '}').
std::string headerField(const std::string& header, const std::string& key, const std::string& where) {
  const auto pos = header.find("'" + key + "'");
  if (pos == std::string::npos) throw std::runtime_error(where + ": .npy header has no '" + key + "'");
  auto p = header.find(':', pos);
  ++p;
  while (p < header.size() && header[p] == ' ') ++p;
  std::size_t end = p;
  int depth = 0;
  while (end < header.size()) {
    const char c = header[end];
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if ((c == ',' && depth == 0) || (c == '}' && depth == 0)) break;
    ++end;
  }
  return header.substr(p, end - p);
}

NpyArray parseNpy(const unsigned char* d, std::size_t n, const std::string& where) {
  static const unsigned char kMagic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (n < 10 || std::memcmp(d, kMagic, 6) != 0) throw std::runtime_error(where + ": not a .npy array (bad magic)");
  const int major = d[6];
  std::size_t header_len = 0, offset = 0;
  if (major == 1) {
    header_len = u16(d + 8);
    offset = 10;
  } else {
    if (n < 12) throw std::runtime_error(where + ": truncated .npy header");
    header_len = u32(d + 8);
    offset = 12;
  }
  if (offset + header_len > n) throw std::runtime_error(where + ": truncated .npy header");
  const std::string header(reinterpret_cast<const char*>(d + offset), header_len);
  NpyArray a;
  std::string descr = headerField(header, "descr", where);
  descr.erase(std::remove(descr.begin(), descr.end(), '\''), descr.end());
  a.descr = descr;
  if (headerField(header, "fortran_order", where).find("True") != std::string::npos)
    throw std::runtime_error(where + ": Fortran-order arrays are not supported");
  const std::string shape = headerField(header, "shape", where);
  std::size_t i = 0;
  while (i < shape.size()) {
    if (std::isdigit(static_cast<unsigned char>(shape[i]))) {
      std::size_t j = i;
      while (j < shape.size() && std::isdigit(static_cast<unsigned char>(shape[j]))) ++j;
      a.shape.push_back(static_cast<std::size_t>(std::stoull(shape.substr(i, j - i))));
      i = j;
    } else {
      ++i;
    }
  }
  const unsigned char* data = d + offset + header_len;
  const std::size_t avail = n - offset - header_len;
  const std::size_t count = a.size();
  auto need = [&](std::size_t bytes) {
    if (bytes * count > avail)
      throw std::runtime_error(fmt::format("{}: data truncated ({} bytes, need {})", where, avail, bytes * count));
  };
  a.values.resize(0);
  if (descr == "<f4") {
    need(4);
    for (std::size_t k = 0; k < count; ++k) {
      float f;
      std::memcpy(&f, data + 4 * k, 4);
      a.values.push_back(f);
    }
  } else if (descr == "<f8") {
    need(8);
    for (std::size_t k = 0; k < count; ++k) {
      double f;
      std::memcpy(&f, data + 8 * k, 8);
      a.values.push_back(f);
    }
  } else if (descr == "<i8") {
    need(8);
    for (std::size_t k = 0; k < count; ++k) {
      std::int64_t v;
      std::memcpy(&v, data + 8 * k, 8);
      a.values.push_back(static_cast<double>(v));
    }
  } else if (descr == "<i4") {
    need(4);
    for (std::size_t k = 0; k < count; ++k) {
      std::int32_t v;
      std::memcpy(&v, data + 4 * k, 4);
      a.values.push_back(v);
    }
  } else if (descr.empty() || (descr[1] != 'U' && descr[1] != 'S')) {
    throw std::runtime_error(where + ": unsupported dtype '" + descr + "' (expected <f4, <f8, <i4, <i8 or strings)");
  }
  return a;
}

}  // namespace

std::size_t NpyArray::size() const {
  std::size_t s = 1;
  for (const std::size_t d : shape) s *= d;
  return s;
}

std::map<std::string, NpyArray> readNpz(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open .npz file");
  const std::vector<unsigned char> buf((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::map<std::string, NpyArray> out;
  std::size_t p = 0;
  while (p + 30 <= buf.size() && u32(&buf[p]) == 0x04034b50) {
    const std::uint16_t flags = u16(&buf[p + 6]), method = u16(&buf[p + 8]);
    const std::uint32_t csize = u32(&buf[p + 18]), usize = u32(&buf[p + 22]);
    const std::uint16_t name_len = u16(&buf[p + 26]), extra_len = u16(&buf[p + 28]);
    if (p + 30 + name_len > buf.size()) throw std::runtime_error(path + ": truncated ZIP header");
    std::string name(reinterpret_cast<const char*>(&buf[p + 30]), name_len);
    const std::string where = path + ": member " + name;
    if (method != 0) throw std::runtime_error(where + ": compressed (method " + std::to_string(method) + "); only stored .npz (np.savez) is supported");
    if ((flags & 0x8) != 0 || csize != usize || csize == 0xFFFFFFFFu)
      throw std::runtime_error(where + ": sizes not in the local header (streamed or ZIP64 archive) are not supported");
    const std::size_t data = p + 30 + name_len + extra_len;
    if (data + csize > buf.size()) throw std::runtime_error(where + ": truncated data");
    if (name.size() > 4 && name.substr(name.size() - 4) == ".npy") name.resize(name.size() - 4);
    out[name] = parseNpy(&buf[data], csize, where);
    p = data + csize;
  }
  if (out.empty()) throw std::runtime_error(path + ": not a ZIP/.npz archive (no local file header at offset 0)");
  return out;
}

HumanMotion ampNpzToHuman(const std::string& path) {
  const auto arrays = readNpz(path);
  auto get = [&](const char* key) -> const NpyArray& {
    const auto it = arrays.find(key);
    if (it == arrays.end() || it->second.values.empty()) throw std::runtime_error(path + ": missing numeric array '" + key + "'");
    return it->second;
  };
  const NpyArray& fps = get("fps");
  const NpyArray& pos = get("body_positions");
  const NpyArray& rot = get("body_rotations");
  if (pos.shape.size() != 3 || pos.shape[1] != 15 || pos.shape[2] != 3)
    throw std::runtime_error(path + ": body_positions: expected shape (N, 15, 3)");
  if (rot.shape.size() != 3 || rot.shape[0] != pos.shape[0] || rot.shape[1] != 15 || rot.shape[2] != 4)
    throw std::runtime_error(path + ": body_rotations: expected shape (N, 15, 4) matching body_positions");
  HumanMotion h;
  h.source_file = path;
  h.format = "amp_npz";
  h.fps = fps.values[0];
  if (!(h.fps > 0)) throw std::runtime_error(path + ": fps: expected > 0");
  const std::size_t N = pos.shape[0];
  auto P = [&](std::size_t k, std::size_t b) {
    const std::size_t i = (k * 15 + b) * 3;
    return Eigen::Vector3d(pos.values[i], pos.values[i + 1], pos.values[i + 2]);
  };
  auto Q = [&](std::size_t k, std::size_t b) {
    const std::size_t i = (k * 15 + b) * 4;
    return Eigen::Quaterniond(rot.values[i], rot.values[i + 1], rot.values[i + 2], rot.values[i + 3]).normalized();
  };
  // Body indices (SOURCE.md order).
  constexpr std::size_t kPelvis = 0, kTorso = 1, kRUpper = 3, kRLower = 4, kRHand = 5, kLUpper = 6, kLLower = 7, kLHand = 8,
                        kRThigh = 9, kRShin = 10, kRFoot = 11, kLThigh = 12, kLShin = 13, kLFoot = 14;
  h.frames.resize(N);
  double foot_low = 1e9;
  for (std::size_t k = 0; k < N; ++k) {
    HumanFrame& o = h.frames[k];
    auto set = [&](Keypoint kp, std::size_t b) { o.p_WK[static_cast<std::size_t>(kp)] = P(k, b); };
    set(Keypoint::kPelvis, kPelvis);
    set(Keypoint::kLeftHip, kLThigh);
    set(Keypoint::kLeftKnee, kLShin);
    set(Keypoint::kLeftAnkle, kLFoot);
    set(Keypoint::kRightHip, kRThigh);
    set(Keypoint::kRightKnee, kRShin);
    set(Keypoint::kRightAnkle, kRFoot);
    set(Keypoint::kLeftShoulder, kLUpper);
    set(Keypoint::kLeftElbow, kLLower);
    set(Keypoint::kLeftWrist, kLHand);
    set(Keypoint::kRightShoulder, kRUpper);
    set(Keypoint::kRightElbow, kRLower);
    set(Keypoint::kRightWrist, kRHand);
    o.R_WPelvis = Q(k, kPelvis);
    o.R_WTorso = Q(k, kTorso);
    o.R_WFoot = {Q(k, kLFoot), Q(k, kRFoot)};
    for (int s = 0; s < 2; ++s) {
      const auto ankle = static_cast<std::size_t>(s == 0 ? Keypoint::kLeftAnkle : Keypoint::kRightAnkle);
      o.p_WK[static_cast<std::size_t>(s == 0 ? Keypoint::kLeftToe : Keypoint::kRightToe)] =
          o.p_WK[ankle] + o.R_WFoot[static_cast<std::size_t>(s)].toRotationMatrix() * Eigen::Vector3d(kToeOffset, 0, 0);
      foot_low = std::min(foot_low, o.p_WK[ankle].z());
    }
  }
  // The file's ground is z = 0 already; the ankle height is the lowest ankle height in the clip.
  h.ankle_height = std::max(0.0, foot_low);
  putOnGround(h);
  return h;
}

}  // namespace pmg::motion
