#include "pmg/teleop/vr_static_files.hpp"

#include <system_error>

namespace pmg::teleop {

namespace fs = std::filesystem;

namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

VrStaticLookup refuse(int status, std::string reason) {
  VrStaticLookup r;
  r.status = status;
  r.reason = std::move(reason);
  return r;
}

/// True if @p inner is @p root or below it (both absolute and normal).
bool isBelow(const fs::path& root, const fs::path& inner) {
  auto r = root.begin();
  auto i = inner.begin();
  for (; r != root.end(); ++r, ++i) {
    if (r->empty() && std::next(r) == root.end()) break;  // trailing "" of "dir/"
    if (i == inner.end() || *r != *i) return false;
  }
  return true;
}

}  // namespace

std::string vrMimeType(std::string_view ext) {
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".webmanifest") return "application/manifest+json";
  if (ext == ".txt") return "text/plain; charset=utf-8";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".glb") return "model/gltf-binary";
  return {};
}

bool vrPercentDecode(std::string_view in, std::string& out) {
  out.clear();
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size()) return false;
    const int hi = hexValue(in[i + 1]);
    const int lo = hexValue(in[i + 2]);
    if (hi < 0 || lo < 0) return false;
    out += static_cast<char>(hi * 16 + lo);
    i += 2;
  }
  return true;
}

VrStaticLookup vrLookupStatic(const fs::path& web_root, std::string_view target) {
  try {
    if (target.empty() || target.front() != '/') return refuse(400, "target does not start with '/'");
    if (target.size() > 1024) return refuse(400, "target longer than 1024 bytes");
    const std::size_t cut = target.find_first_of("?#");
    const std::string_view raw = target.substr(0, cut);
    std::string path;
    if (!vrPercentDecode(raw, path)) return refuse(400, "malformed percent escape");
    for (const char c : path) {
      const auto u = static_cast<unsigned char>(c);
      if (u < 0x20 || u == 0x7f || c == '\\') return refuse(400, "control character or backslash in path");
    }
    // Segments: none may start with '.', empty ones ("//") are skipped.
    fs::path relative;
    std::size_t start = 1;
    while (start <= path.size()) {
      const std::size_t end = std::min(path.find('/', start), path.size());
      const std::string segment = path.substr(start, end - start);
      if (!segment.empty()) {
        if (segment.front() == '.') return refuse(404, "segment '" + segment.substr(0, 32) + "' starts with '.'");
        relative /= segment;
      }
      start = end + 1;
    }
    if (path.back() == '/' || relative.empty()) relative /= "index.html";

    std::error_code ec;
    const fs::path root = fs::canonical(web_root, ec);
    if (ec) return refuse(404, "web root " + web_root.string() + " not found");
    const fs::path file = fs::canonical(root / relative, ec);  // resolves symlinks; fails if absent
    if (ec) return refuse(404, "not found");
    if (!isBelow(root, file)) return refuse(404, "resolves outside the web root");
    if (!fs::is_regular_file(file, ec)) return refuse(404, "not a regular file");
    const auto size = fs::file_size(file, ec);
    if (ec || size > kVrMaxStaticFileBytes) return refuse(404, "larger than the served limit");
    std::string mime = vrMimeType(file.extension().string());
    if (mime.empty()) return refuse(404, "extension '" + file.extension().string() + "' not served");
    VrStaticLookup ok;
    ok.status = 200;
    ok.file = file;
    ok.mime = std::move(mime);
    return ok;
  } catch (...) {
    return refuse(400, "internal error");
  }
}

}  // namespace pmg::teleop
