// The WebXR page in a real browser: headless Chromium loads https://127.0.0.1:PORT/?synthetic=1
// from the bridge's server, connects its secure WebSocket and streams the synthetic pattern; the
// poses must arrive on LCM with exactly the values of pmg::teleop::syntheticSample (the JS and C++
// versions of the pattern agree). Then the server drops the connection and the page must
// reconnect by itself. Skipped with a message when chromium or LCM multicast is missing.
//
// Prints the page's message rate and its reconnect time (drop → first pose of the new session).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "g1_fixture.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/teleop/vr_certificate.hpp"
#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_server.hpp"
#include "pmg/teleop/vr_synthetic.hpp"
#include "temp_dir.hpp"
#include "vr_test_util.hpp"

extern char** environ;

namespace pmg::teleop {
namespace {

using namespace std::chrono_literals;
using test::vr::Clock;
namespace fs = std::filesystem;

std::string findChromium() {
  if (const char* env = std::getenv("PMG_CHROMIUM"); env != nullptr && *env != '\0') return env;
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
    if (::access(p, X_OK) == 0) return p;
  return {};
}

/// Chromium in its own process group (it starts helper processes), output to @p log.
class Browser {
 public:
  Browser(const std::string& exe, const std::string& url, const fs::path& profile, const fs::path& log) {
    std::vector<std::string> args = {exe,
                                     "--headless=new",
                                     "--no-sandbox",
                                     "--ignore-certificate-errors",
                                     "--use-fake-ui-for-media-stream",
                                     "--disable-gpu",
                                     "--disable-dev-shm-usage",
                                     "--no-first-run",
                                     "--no-default-browser-check",
                                     "--disable-extensions",
                                     "--disable-background-networking",
                                     "--disable-component-update",
                                     "--disable-sync",
                                     "--mute-audio",
                                     "--user-data-dir=" + profile.string(),
                                     url};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    posix_spawnattr_t at;
    posix_spawnattr_init(&at);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&at, 0);
    if (posix_spawn(&pid_, exe.c_str(), &fa, &at, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
  }
  ~Browser() {
    if (pid_ <= 0) return;
    ::kill(-pid_, SIGTERM);  // the browser's own process group
    for (int i = 0; i < 50; ++i) {
      if (::waitpid(pid_, nullptr, WNOHANG) == pid_) return;
      std::this_thread::sleep_for(50ms);
    }
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  bool started() const { return pid_ > 0; }
  bool running() const { return pid_ > 0 && ::waitpid(pid_, nullptr, WNOHANG) == 0; }

 private:
  pid_t pid_ = -1;
};

std::string tail(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return "(no browser output)";
  const std::string s = test::readTextFile(file.string());
  return s.size() > 3000 ? s.substr(s.size() - 3000) : s;
}

TEST(VrBrowser, HeadlessChromiumLoadsThePageConnectsAndStreamsPosesToLcm) {
  const std::string chromium = findChromium();
  if (chromium.empty())
    GTEST_SKIP()
        << "chromium not found (Debian package 'chromium', or set PMG_CHROMIUM=/path/to/chrome): browser test skipped";
  const std::string url = test::vr::privateLcmUrl();
  if (const std::string why = test::vr::multicastUnavailable(url); !why.empty()) GTEST_SKIP() << why;

  test::TempDir tmp;
  const VrCertificateInfo cert = ensureVrCertificate(tmp.path() / "cert");
  comms::CommandPublisher publisher(url, "", kVrSource);
  test::vr::VrPoseListener listener(url);
  VrServerOptions o;
  o.bind_address = "127.0.0.1";
  o.port = 0;
  o.cert_file = cert.cert_file;
  o.key_file = cert.key_file;
  o.web_root = test::sourcePath("data/vr/web");
  o.access_token = "browser-test-token";
  VrServer server(
      o, [&](const VrSample& s, std::int64_t utime) { return publisher.publishVrPose(toVrPoseMessage(s, utime)); });
  server.start();

  const std::string page =
      "https://127.0.0.1:" + std::to_string(server.port()) + "/?synthetic=1&token=" + o.access_token;
  const fs::path log = tmp.path() / "chromium.log";
  const auto launched = Clock::now();
  Browser browser(chromium, page, tmp.path() / "profile", log);
  ASSERT_TRUE(browser.started()) << "cannot start " << chromium;

  // The page loads (index.html, vr.js, style.css), connects and streams.
  ASSERT_GE(listener.waitFor(1, 15000ms), 1u)
      << "no pose on LCM within 15 s; server: " << server.stats().last_error << "\nchromium output:\n"
      << tail(log);
  const auto first = listener.received().front().at;
  std::printf("[measure] chromium start -> first pose on LCM: %.0f ms\n",
              std::chrono::duration<double, std::milli>(first - launched).count());
  // ≥ 50 poses within 10 s (72 Hz: ~1 s); then 3 s more to measure the rate.
  ASSERT_GE(listener.waitFor(50, 10000ms), 50u) << tail(log);
  std::this_thread::sleep_until(first + 3100ms);
  auto got = listener.received();
  std::size_t in_window = 0;
  for (const auto& r : got)
    if (r.at >= first + 1000ms && r.at < first + 3000ms) ++in_window;
  const double rate = static_cast<double>(in_window) / 2.0;
  std::printf("[measure] page message rate: %.1f poses/s (synthetic source at %.0f Hz, headless Chromium)\n", rate,
              kVrSyntheticRateHz);
  EXPECT_GT(rate, 0.5 * kVrSyntheticRateHz) << "(72 Hz when the machine is not overloaded)";
  EXPECT_LT(rate, 1.1 * kVrSyntheticRateHz) << "never faster than the pattern (no bursts)";
  std::int64_t last_frame = -1;
  for (const auto& r : got) {
    EXPECT_GT(r.msg.frame, last_frame) << "frames increase";
    last_frame = r.msg.frame;
    const VrSample e = syntheticSample(r.msg.frame);  // what the JS pattern must have produced
    EXPECT_EQ(r.msg.xr_time_us, e.xr_time_us);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(r.msg.head_position[i], e.head_position[i], 1e-9) << r.msg.frame;
    for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(r.msg.head_quat[i], e.head_quat[i], 1e-9) << r.msg.frame;
    for (std::size_t h = 0; h < 2; ++h) {
      for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(r.msg.hand_position[h][i], e.hand_position[h][i], 1e-9);
      EXPECT_NEAR(r.msg.trigger[h], e.trigger[h], 1e-9);
      EXPECT_EQ(static_cast<std::uint32_t>(r.msg.buttons[h]), e.buttons[h]);
      EXPECT_NEAR(r.msg.thumbstick[h][1], e.thumbstick[h][1], 1e-12);
    }
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(got.back().msg.head_position[0], 0.0) << "the synthetic head walks forward (+x in V)";

  // The link drops; the page reconnects by itself (backoff 0.25 s ± 20 %).
  const std::size_t before = listener.count();
  const auto dropped = Clock::now();
  server.dropClients();
  bool back = false;
  Clock::time_point back_at{};
  for (auto end = dropped + 5000ms; Clock::now() < end && !back;) {
    std::this_thread::sleep_for(5ms);
    got = listener.received();
    for (std::size_t i = before; i < got.size(); ++i)
      if (got[i].at > dropped + 20ms && server.stats().ws_sessions >= 2) {
        back = true;
        back_at = got[i].at;
        break;
      }
  }
  ASSERT_TRUE(back) << "the page did not reconnect within 5 s\n" << tail(log);
  std::printf("[measure] page reconnect after a dropped connection: %.0f ms to the first pose of the new session\n",
              std::chrono::duration<double, std::milli>(back_at - dropped).count());
  const auto s = server.stats();
  EXPECT_GE(s.http_requests, 3u) << "index.html, vr.js, style.css";
  EXPECT_EQ(s.ws_sessions, 2u);
  EXPECT_EQ(s.rejected_total, 0u) << s.last_error;
  EXPECT_TRUE(browser.running());
}

}  // namespace
}  // namespace pmg::teleop
