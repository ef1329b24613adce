#include "render_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <unistd.h>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

namespace pmg::render::test {

void writeStateLog(const std::string& path, const std::vector<StateSample>& samples, int num_joints_override) {
  lcm::LogFile log(path, "w");
  if (!log.good()) throw std::runtime_error(path + ": cannot write");
  int64_t eventnum = 0;
  auto write = [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
    lcm::LogEvent ev;
    ev.eventnum = eventnum++;
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(bytes.size());
    ev.data = const_cast<uint8_t*>(bytes.data());
    if (log.writeEvent(&ev) != 0) throw std::runtime_error(path + ": write failed");
  };
  for (const StateSample& s : samples) {
    const int64_t utime = static_cast<int64_t>(std::llround(s.t * 1e6));
    write("OTHER", std::vector<uint8_t>{1, 2, 3, 4}, utime);
    pmg_lcm::controller_state_t m{};
    m.utime = utime;
    m.mode = static_cast<int8_t>(s.mode);
    const int n = static_cast<int>(s.q.size());
    m.num_joints = num_joints_override >= 0 ? num_joints_override : n;
    for (auto* v : {&m.q, &m.qd, &m.tau, &m.q_ref, &m.qd_ref}) v->assign(static_cast<std::size_t>(m.num_joints), 0.0);
    for (int i = 0; i < std::min(n, m.num_joints); ++i) m.q[static_cast<std::size_t>(i)] = s.q[i];
    for (int a = 0; a < 3; ++a) m.base_position[a] = s.p_WB[a];
    for (int a = 0; a < 4; ++a) m.base_quat[a] = s.quat_WB[a];
    for (int a = 0; a < 3; ++a) m.command[a] = s.command[a];
    std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
    if (m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) throw std::runtime_error("encode failed");
    write("PMG_STATE", bytes, utime);
  }
}

namespace {
// Removes the folders made by tempDir() when the test process exits.
struct TempDirCleaner {
  std::vector<std::filesystem::path> dirs;
  ~TempDirCleaner() {
    std::error_code ignored;
    for (const auto& d : dirs) std::filesystem::remove_all(d, ignored);
  }
};
TempDirCleaner g_temp_dirs;
}  // namespace

std::string tempDir(const std::string& name) {
  // The process id keeps parallel test processes (ctest -j, several build folders) apart.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("pmg_render_test_" + std::to_string(getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  g_temp_dirs.dirs.push_back(dir);
  return dir.string();
}

double luminanceStdDev(const Image& image) {
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double y = 0.299 * image.rgb[3 * i] + 0.587 * image.rgb[3 * i + 1] + 0.114 * image.rgb[3 * i + 2];
    sum += y;
    sum2 += y * y;
  }
  const double mean = sum / static_cast<double>(n);
  return std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - mean * mean));
}

Difference difference(const Image& a, const Image& b, int tolerance) {
  if (a.width != b.width || a.height != b.height) throw std::invalid_argument("difference: image sizes differ");
  Difference d;
  d.min_x = a.width;
  d.min_y = a.height;
  double sx = 0.0, sy = 0.0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const std::uint8_t* pa = a.pixel(x, y);
      const std::uint8_t* pb = b.pixel(x, y);
      bool differs = false;
      for (int c = 0; c < 3; ++c) differs = differs || std::abs(int(pa[c]) - int(pb[c])) > tolerance;
      if (!differs) continue;
      ++d.count;
      sx += x;
      sy += y;
      d.min_x = std::min(d.min_x, x);
      d.max_x = std::max(d.max_x, x);
      d.min_y = std::min(d.min_y, y);
      d.max_y = std::max(d.max_y, y);
    }
  if (d.count > 0) {
    d.centroid_x = sx / static_cast<double>(d.count);
    d.centroid_y = sy / static_cast<double>(d.count);
  }
  return d;
}

}  // namespace pmg::render::test

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace pmg::render::test {

std::string ScopedXvfb::start() {
  int fds[2];
  if (pipe(fds) != 0) return "pipe() failed";
  // The write end goes to Xvfb as its -displayfd; the read end must not leak into it.
  fcntl(fds[0], F_SETFD, FD_CLOEXEC);
  const std::string fd_arg = std::to_string(fds[1]);
  std::vector<std::string> args = {"Xvfb", "-displayfd", fd_arg, "-screen", "0", "640x480x24", "-nolisten", "tcp"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, "Xvfb", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    return "cannot start Xvfb (" + std::string(std::strerror(rc)) + "; Debian package xvfb)";
  }
  pid_ = pid;
  // Xvfb writes "<display number>\n" once it accepts connections.
  std::string number;
  pollfd pfd{fds[0], POLLIN, 0};
  char c = 0;
  while (poll(&pfd, 1, 10000) > 0 && read(fds[0], &c, 1) == 1 && c != '\n') number += c;
  close(fds[0]);
  if (number.empty()) return "Xvfb started but reported no display number within 10 s";
  setenv("DISPLAY", (":" + number).c_str(), 1);
  return "";
}

ScopedXvfb::~ScopedXvfb() {
  if (pid_ <= 0) return;
  unsetenv("DISPLAY");
  kill(pid_, SIGTERM);
  int status = 0;
  waitpid(pid_, &status, 0);
}

}  // namespace pmg::render::test
