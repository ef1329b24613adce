#include "temp_dir.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <gtest/gtest.h>

namespace pmg::test {
namespace {

std::string sanitized(std::string s) {
  for (char& c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  return s;
}

std::string currentTestLabel() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  if (info == nullptr) return "test";
  return std::string(info->test_suite_name()) + "_" + info->name();
}

std::filesystem::path makeUnique(const std::string& label) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path base = std::filesystem::temp_directory_path();
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const std::filesystem::path p = base / ("pmg_" + sanitized(label) + "_" + std::to_string(::getpid()) + "_" +
                                            std::to_string(counter.fetch_add(1)));
    if (std::filesystem::create_directories(p)) return p;
  }
  throw std::runtime_error("TempDir: cannot create a unique folder under " + base.string());
}

}  // namespace

TempDir::TempDir() : path_(makeUnique(currentTestLabel())) {}
TempDir::TempDir(const std::string& label) : path_(makeUnique(label)) {}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string TempDir::file(const std::string& name) const { return (path_ / name).string(); }

std::string TempDir::write(const std::string& name, const std::string& content) const {
  const std::filesystem::path p = path_ / name;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << content;
  if (!out) throw std::runtime_error("TempDir: cannot write " + p.string());
  return p.string();
}

}  // namespace pmg::test
