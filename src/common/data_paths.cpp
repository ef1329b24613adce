#include "pmg/common/data_paths.hpp"

#include <cstdlib>
#include <stdexcept>
#include <system_error>

#include <unistd.h>

namespace pmg {

namespace fs = std::filesystem;

fs::path executableDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return {};
  return exe.parent_path();
}

fs::path dataDir() {
  if (const char* env = std::getenv("PMG_DATA_DIR"); env != nullptr && *env != '\0') {
    fs::path dir = fs::absolute(fs::path(env)).lexically_normal();
    return dir.has_filename() ? dir : dir.parent_path();  // "share/pmg/" -> "share/pmg"
  }
  const fs::path exe_dir = executableDir();
  if (exe_dir.empty()) return fs::absolute("share/pmg").lexically_normal();
  const fs::path installed = (exe_dir / ".." / "share" / "pmg").lexically_normal();
  std::error_code ec;
  if (fs::is_directory(installed, ec)) return installed;
  const fs::path nested = (exe_dir / ".." / ".." / "share" / "pmg").lexically_normal();
  if (fs::is_directory(nested, ec)) return nested;
  return installed;
}

fs::path resolveData(const fs::path& relative) {
  if (relative.is_absolute()) return relative;
  return (dataDir() / relative).lexically_normal();
}

fs::path resolveRelativeTo(const fs::path& naming_file, const fs::path& path) {
  if (path.empty() || path.is_absolute()) return path;
  return (naming_file.parent_path() / path).lexically_normal();
}

void requireWritableFile(const fs::path& path) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(path.string() + ": cannot write (" + why + ")");
  };
  if (path.empty()) fail("empty path");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) fail("folder " + dir.string() + " does not exist");
  if (fs::is_directory(path, ec)) fail("it is a folder");
  if (fs::exists(path, ec)) {
    if (::access(path.c_str(), W_OK) != 0) fail("file is read-only");
  } else if (::access(dir.c_str(), W_OK) != 0) {
    fail("folder " + dir.string() + " is read-only");
  }
}

}  // namespace pmg
