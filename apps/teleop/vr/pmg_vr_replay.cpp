// pmg_vr_replay: re-publishes a recorded VR session (an LCM log with PMG_VR_POSE events, e.g.
// data/vr/sessions/synthetic_walk.lcmlog) with its original timing, through the same
// CommandPublisher as pmg_vr_bridge: new utime and, with --key, fresh authentication trailers
// (the controller refuses the recorded ones as replays). docs/teleop.md.
//
//   pmg_vr_replay --log FILE.lcmlog [--key FILE] [--lcm-url URL] [--speed 1.0] [--loop]
//
// Exit codes: 0 done or stopped (SIGINT/SIGTERM), 1 setup error (log, LCM, key), 2 bad command
// line, 3 the log holds no valid PMG_VR_POSE event.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <thread>

#include "pmg/common/cli_checks.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_replay.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void onSignal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_vr_replay: re-publish a recorded VR pose stream (LCM log, channel PMG_VR_POSE) in real time"};
  std::string log_path, key_file;
  std::string lcm_url = pmg::kDefaultLcmUrl;
  double speed = 1.0;
  bool loop = false;
  app.add_option("--log", log_path, "LCM log with PMG_VR_POSE events (lcm-logger)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--key", key_file, "authentication key file (pmg_keygen, mode 0600); none: unsigned messages")
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", lcm_url, "LCM provider URL")->capture_default_str();
  app.add_option("--speed", speed, "time scale (2: twice as fast)")
      ->check(pmg::cli::finiteIn(0.01, 100.0))
      ->capture_default_str();
  app.add_flag("--loop", loop, "start over at the end until stopped (frame and XR time keep growing)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    namespace vr = pmg::teleop;
    vr::VrLogReadStats rs;
    const std::vector<vr::VrLogEvent> events = vr::readVrLog(log_path, &rs);
    std::printf("pmg_vr_replay: %s: %llu events, %zu PMG_VR_POSE poses", log_path.c_str(),
                static_cast<unsigned long long>(rs.events), events.size());
    if (rs.other_channels > 0)
      std::printf(", %llu on other channels (skipped)", static_cast<unsigned long long>(rs.other_channels));
    if (rs.rejected > 0)
      std::printf(", %llu rejected (first: %s)", static_cast<unsigned long long>(rs.rejected), rs.first_error.c_str());
    std::printf("\n");
    if (events.empty()) {
      std::fprintf(stderr, "pmg_vr_replay: %s: no valid PMG_VR_POSE event\n", log_path.c_str());
      return 3;
    }
    const double length_s = static_cast<double>(events.back().log_utime - events.front().log_utime) * 1e-6;
    pmg::comms::CommandPublisher publisher(lcm_url, key_file, vr::kVrSource);
    std::printf("  %.2f s at speed %.2f%s -> %s (%s)\n", length_s, speed, loop ? ", looping" : "", lcm_url.c_str(),
                publisher.authenticated() ? "signed" : "UNSIGNED (no --key)");
    std::fflush(stdout);
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    vr::VrReplayOptions opt;
    opt.speed = speed;
    opt.loop = loop;
    const vr::VrReplayStats st = vr::replayVrLog(
        events, opt, [&publisher](const pmg_lcm::vr_pose_t& m) { return publisher.publishVrPose(m); }, &g_stop);
    std::printf("pmg_vr_replay: published %llu, failed %llu, %llu full passes, max lateness %.2f ms\n",
                static_cast<unsigned long long>(st.published), static_cast<unsigned long long>(st.failed),
                static_cast<unsigned long long>(st.loops), st.max_late_s * 1e3);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_vr_replay: %s\n", e.what());
    return 1;
  }
}
