#pragma once
// pmg::test::TempDir: a fresh directory under the system temp folder, unique per test (named after
// the running test, the process and a counter), removed with everything in it when it goes out of
// scope. Tests write their files here, never into the source tree.
#include <filesystem>
#include <string>

namespace pmg::test {

class TempDir {
 public:
  /// Creates <temp>/pmg_<suite>_<test>_<pid>_<n> (or pmg_<label>_<pid>_<n> outside a test body).
  TempDir();
  explicit TempDir(const std::string& label);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const noexcept { return path_; }
  /// Absolute path of @p name inside the directory (not created).
  std::string file(const std::string& name) const;
  /// Writes @p content to @p name (parent folders created) and returns its absolute path.
  std::string write(const std::string& name, const std::string& content) const;

 private:
  std::filesystem::path path_;
};

}  // namespace pmg::test
