#include "pmg/common/mujoco_model.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <sodium.h>
#include <unistd.h>

namespace pmg {
namespace fs = std::filesystem;

std::string withAbsoluteMeshdir(const std::string& mjcf_text, const std::string& mjcf_dir) {
  const std::regex compiler_re(R"(<compiler([^>]*?)(/?)>)");
  std::smatch m;
  if (!std::regex_search(mjcf_text, m, compiler_re)) throw std::runtime_error("MJCF has no <compiler> element");
  std::string attrs = m[1].str();
  std::smatch md;
  std::string meshdir = mjcf_dir;
  if (std::regex_search(attrs, md, std::regex(R"(meshdir=\"([^\"]*)\")"))) {
    const fs::path p(md[1].str());
    meshdir = (p.is_absolute() ? p : fs::path(mjcf_dir) / p).lexically_normal().string();
    attrs = std::regex_replace(attrs, std::regex(R"(\s*meshdir=\"[^\"]*\")"), "");
  }
  return mjcf_text.substr(0, static_cast<std::size_t>(m.position(0))) + "<compiler" + attrs + " meshdir=\"" + meshdir +
         "\"" + m[2].str() + ">" + mjcf_text.substr(static_cast<std::size_t>(m.position(0) + m.length(0)));
}

std::string adaptMjcfForMujoco22(const std::string& mjcf_text, const std::string& mjcf_dir,
                                 const Mujoco22Options& o) {
  if (!(o.timestep > 0 && o.timestep <= 0.01))
    throw std::runtime_error("Mujoco22Options.timestep = " + std::to_string(o.timestep) + ": expected (0, 0.01] s");
  // 1. attributes unknown to 2.2.
  std::string xml = std::regex_replace(mjcf_text, std::regex(R"(\s+actuatorfrc(range|limited)=\"[^\"]*\")"), "");
  // 2. compiler: absolute meshdir + autolimits.
  xml = withAbsoluteMeshdir(xml, mjcf_dir);
  const std::regex compiler_re(R"(<compiler([^>]*?)/?>)");
  std::smatch m;
  std::regex_search(xml, m, compiler_re);  // present: withAbsoluteMeshdir checked it
  std::string attrs = std::regex_replace(m[1].str(), std::regex(R"(\s*autolimits=\"[^\"]*\")"), "");
  std::ostringstream head;
  head << "<compiler" << attrs << " autolimits=\"true\"/>\n"
       << "  <option timestep=\"" << o.timestep << "\"/>\n"
       << "  <size nconmax=\"500\" njmax=\"2000\"/>\n"
       << "  <default><joint armature=\"" << o.armature << "\" damping=\"" << o.damping << "\" frictionloss=\""
       << o.frictionloss << "\"/></default>";
  xml = xml.substr(0, static_cast<std::size_t>(m.position(0))) + head.str() +
        xml.substr(static_cast<std::size_t>(m.position(0) + m.length(0)));
  // 5. IMU orientation sensor.
  const std::string quat = "<framequat name=\"" + o.imu_site + "-orientation\" objtype=\"site\" objname=\"" +
                           o.imu_site + "\"/>";
  const auto sensor_pos = xml.find("<sensor>");
  if (sensor_pos != std::string::npos) {
    xml.insert(sensor_pos + 8, "\n    " + quat);
  } else {
    const auto end = xml.rfind("</mujoco>");
    if (end == std::string::npos) throw std::runtime_error("MJCF has no </mujoco> end tag");
    xml.insert(end, "  <sensor>" + quat + "</sensor>\n");
  }
  return xml;
}

namespace {

// The compiled-model cache (mujoco_model.hpp, loadMujocoModel).
std::atomic<long> g_cache_hits{0}, g_cache_misses{0}, g_cache_rejected{0}, g_cache_stored{0};

bool readWholeFile(const fs::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

class Blake2b {
 public:
  Blake2b() { crypto_generichash_init(&state_, nullptr, 0, crypto_generichash_BYTES); }
  void add(const void* data, std::size_t n) {
    crypto_generichash_update(&state_, static_cast<const unsigned char*>(data), n);
  }
  void addString(const std::string& s) {  // length-prefixed, so concatenations cannot collide
    const std::uint64_t n = s.size();
    add(&n, sizeof n);
    add(s.data(), s.size());
  }
  std::string hex() {
    unsigned char out[crypto_generichash_BYTES];
    crypto_generichash_final(&state_, out, sizeof out);
    char hex[2 * crypto_generichash_BYTES + 1];
    return sodium_bin2hex(hex, sizeof hex, out, sizeof out);
  }

 private:
  crypto_generichash_state state_;
};

std::string checksumOf(const std::string& bytes) {
  Blake2b h;
  h.add(bytes.data(), bytes.size());
  return h.hex();
}

std::string attributeOf(const std::string& xml, const char* element, const char* attribute) {
  std::smatch m;
  const std::regex re(std::string("<") + element + "\\b[^>]*\\s" + attribute + "=\"([^\"]*)\"");
  return std::regex_search(xml, m, re) ? m[1].str() : std::string();
}

/// The cache key of @p xml (adapted; meshdir absolute), or "" when a file it names cannot be read.
std::string cacheKeyOf(const std::string& xml, const fs::path& mjcf_dir) {
  Blake2b h;
  h.addString("pmg-mjcf-cache-1");
  const int version = mj_version();
  const std::uint32_t real_size = sizeof(mjtNum);
  h.add(&version, sizeof version);
  h.add(&real_size, sizeof real_size);
  h.addString(xml);
  std::vector<fs::path> dirs;
  for (const char* attribute : {"meshdir", "texturedir"}) {
    const std::string d = attributeOf(xml, "compiler", attribute);
    if (!d.empty()) dirs.push_back(fs::path(d).is_absolute() ? fs::path(d) : mjcf_dir / d);
  }
  dirs.push_back(mjcf_dir);
  const std::regex file_re(R"(\sfile(?:right|left|up|down|front|back)?=\"([^\"]*)\")");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), file_re); it != std::sregex_iterator(); ++it) {
    const fs::path name((*it)[1].str());
    // Every folder MuJoCo might resolve the name against: a change to whichever it uses changes the key.
    std::vector<fs::path> candidates;
    if (name.is_absolute()) {
      candidates.push_back(name);
    } else {
      for (const fs::path& dir : dirs) candidates.push_back(dir / name);
    }
    bool found = false;
    for (const fs::path& candidate : candidates) {
      std::error_code ec;
      if (!fs::is_regular_file(candidate, ec)) continue;
      std::string content;
      if (!readWholeFile(candidate, content)) return {};
      h.addString(candidate.string());
      h.addString(content);
      found = true;
    }
    if (!found) return {};
  }
  return h.hex();
}

bool writeAtomically(const fs::path& destination, const std::string& bytes) {
  std::string tmp = (destination.parent_path() / ".pmg_mjb_XXXXXX").string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) return false;
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  const bool ok = close(fd) == 0 && written == bytes.size();
  std::error_code ec;
  if (ok) fs::rename(tmp, destination, ec);
  if (!ok || ec) {
    fs::remove(tmp, ec);
    return false;
  }
  return true;
}

struct MujocoLoadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void throwMujocoLoadError(const char* message) {
  throw MujocoLoadError(std::string("MuJoCo: ") + (message ? message : "unknown error"));
}

void rejectEntry(const fs::path& entry, const char* why) {
  ++g_cache_rejected;
  std::fprintf(stderr, "pmg: MJCF cache entry %s rejected (%s); compiling the model again\n", entry.c_str(), why);
}

/// The cached model at @p entry, or null (no entry, or one rejected and counted).
MjModelPtr loadEntry(const fs::path& entry) {
  std::string bytes;
  if (!readWholeFile(entry, bytes)) return nullptr;  // no entry
  std::string checksum;
  if (!readWholeFile(fs::path(entry.string() + ".b2"), checksum) || checksum != checksumOf(bytes)) {
    rejectEntry(entry, "its BLAKE2b checksum file is missing or does not match its bytes");
    return nullptr;
  }
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) {
    rejectEntry(entry, "larger than MuJoCo's virtual file system takes");
    return nullptr;
  }
  // From memory (MuJoCo's virtual file system): the bytes loaded are the bytes checked.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "model.mjb", static_cast<int>(bytes.size())) != 0) {
    mj_deleteVFS(vfs.get());
    rejectEntry(entry, "MuJoCo's virtual file system refused it");
    return nullptr;
  }
  std::memcpy(vfs->filedata[vfs->nfile - 1], bytes.data(), bytes.size());
  mjModel* model = nullptr;
  std::string error;
  {
    // mj_loadModel reports a malformed image through mju_error: while it reads, an error throws instead. What
    // it had allocated for the image is lost; this happens only for an entry that passed its checksum.
    const ScopedMujocoErrorHandler guard(throwMujocoLoadError);
    try {
      model = mj_loadModel("model.mjb", vfs.get());
    } catch (const MujocoLoadError& e) {
      error = e.what();
    }
  }
  mj_deleteVFS(vfs.get());
  if (!model) rejectEntry(entry, error.empty() ? "MuJoCo could not load it" : error.c_str());
  return MjModelPtr(model);
}

/// Keeps the folder at kMujocoModelCacheMaxEntries entries, the least recently used going first (a served entry's
/// time is renewed), and removes temporary files a killed writer left (older than 10 minutes).
void evictEntries(const fs::path& dir) {
  std::vector<std::pair<fs::file_time_type, fs::path>> images;
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    const auto time = fs::last_write_time(p, ec);
    if (ec) continue;
    if (p.extension() == ".mjb") {
      images.emplace_back(time, p);
    } else if (p.filename().string().rfind(".pmg_mjb_", 0) == 0 && now - time > std::chrono::minutes(10)) {
      fs::remove(p, ec);
    }
  }
  if (images.size() <= kMujocoModelCacheMaxEntries) return;
  std::sort(images.begin(), images.end());
  for (std::size_t i = 0; i + kMujocoModelCacheMaxEntries < images.size(); ++i) {
    fs::remove(images[i].second, ec);
    fs::remove(fs::path(images[i].second.string() + ".b2"), ec);
  }
}

void storeEntry(const fs::path& entry, const mjModel* model) {
  std::string bytes(static_cast<std::size_t>(mj_sizeModel(model)), '\0');
  mj_saveModel(model, nullptr, bytes.data(), static_cast<int>(bytes.size()));
  if (writeAtomically(fs::path(entry.string() + ".b2"), checksumOf(bytes)) && writeAtomically(entry, bytes))
    ++g_cache_stored;
  evictEntries(entry.parent_path());
}

MjModelPtr compileMjcf(const std::string& mjcf_path, const std::string& xml) {
  // MuJoCo 2.2 compiles from a file: write the adapted text to a private temporary file.
  std::string tmpl = (fs::temp_directory_path() / "pmg_mjcf_XXXXXX").string();
  const int fd = mkstemp(tmpl.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary file for the adapted MJCF");
  close(fd);
  const std::string tmp = tmpl + ".xml";
  fs::rename(tmpl, tmp);
  {
    std::ofstream out(tmp);
    out << xml;
  }
  char error[1024] = {0};
  mjModel* model = mj_loadXML(tmp.c_str(), nullptr, error, sizeof(error));
  std::remove(tmp.c_str());
  if (!model) throw std::runtime_error(mjcf_path + ": MuJoCo 2.2 could not load the adapted MJCF: " + error);
  return MjModelPtr(model);
}

}  // namespace

MujocoModelCacheStats mujocoModelCacheStats() {
  MujocoModelCacheStats s;
  s.hits = g_cache_hits.load();
  s.misses = g_cache_misses.load();
  s.rejected = g_cache_rejected.load();
  s.stored = g_cache_stored.load();
  return s;
}

MjModelPtr loadMujocoModel(const std::string& mjcf_path, const Mujoco22Options& options) {
  std::string text;
  if (!readWholeFile(mjcf_path, text)) throw std::runtime_error(mjcf_path + ": cannot open MJCF file");
  const std::string dir = fs::absolute(fs::path(mjcf_path)).parent_path().string();
  const std::string xml = adaptMjcfForMujoco22(text, dir, options);
  const char* cache_dir = std::getenv("PMG_MJCF_CACHE_DIR");
  if (cache_dir == nullptr || *cache_dir == '\0') return compileMjcf(mjcf_path, xml);

  if (sodium_init() < 0) return compileMjcf(mjcf_path, xml);
  const std::string key = cacheKeyOf(xml, dir);
  std::error_code ec;
  fs::create_directories(cache_dir, ec);
  if (key.empty() || ec) return compileMjcf(mjcf_path, xml);
  const fs::path entry = fs::path(cache_dir) / (key + ".mjb");
  if (MjModelPtr cached = loadEntry(entry)) {
    ++g_cache_hits;
    fs::last_write_time(entry, fs::file_time_type::clock::now(), ec);  // recently used: evicted last
    return cached;
  }
  ++g_cache_misses;
  MjModelPtr model = compileMjcf(mjcf_path, xml);
  storeEntry(entry, model.get());
  return model;
}

}  // namespace pmg
