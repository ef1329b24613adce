// pmg_vr_script: a scripted VR operator (include/pmg/teleop/vr_script.hpp, docs/teleop.md). Plays a
// YAML script of headset / hand keyframes as the VR pose stream PMG_VR_POSE — live over LCM
// (signed with --key, like pmg_vr_bridge) or into an LCM event log that pmg_vr_replay replays.
//
//   pmg_vr_script --script config/teleop/vr_walk_script.yaml [--lcm-url URL] [--key FILE]
//   pmg_vr_script --script config/teleop/vr_walk_script.yaml --log OUT.lcmlog
//
// Exit codes: 0 done (or stopped by SIGINT/SIGTERM), 1 setup error, 2 bad command line.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "pmg/comms/channels.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_script.hpp"

namespace {
std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }
std::int64_t wallMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_vr_script: a scripted VR operator (headset + hand controllers) as a PMG_VR_POSE stream"};
  std::string script_path, lcm_url = pmg::kDefaultLcmUrl, key_file, log_path;
  app.add_option("--script", script_path, "VR script YAML (include/pmg/teleop/vr_script.hpp)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", lcm_url, "LCM provider URL (the default keeps traffic on this host: ttl=0)")
      ->capture_default_str();
  app.add_option("--key", key_file, "authentication key file (owner-only, from pmg_keygen); none = unsigned")
      ->check(CLI::ExistingFile);
  app.add_option("--log", log_path, "write the stream into this LCM event log instead of publishing it");
  CLI11_PARSE(app, argc, argv);

  try {
    const pmg::teleop::VrScript script = pmg::teleop::loadVrScript(script_path);
    const double period = 1.0 / script.rate_hz;
    const auto frames = static_cast<std::int64_t>(script.end() * script.rate_hz);
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    pmg::teleop::VrSample s;
    std::size_t last_step = static_cast<std::size_t>(-1);
    std::int64_t sent = 0;
    if (!log_path.empty()) {
      // Into an LCM event log: the stream's own timing, unsigned (pmg_vr_replay signs on replay).
      lcm::LogFile log(log_path, "w");
      if (!log.good()) throw std::runtime_error(log_path + ": cannot write the LCM log");
      const std::int64_t t0 = wallMicros();
      for (std::int64_t k = 0; k < frames && !g_stop; ++k) {
        const double t = static_cast<double>(k) * period;
        if (!script.sample(t, k, s)) continue;
        const std::int64_t utime = t0 + static_cast<std::int64_t>(t * 1e6);
        pmg_lcm::vr_pose_t msg = pmg::teleop::toVrPoseMessage(s, utime);
        std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
        msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
        lcm::LogEvent ev;
        ev.eventnum = sent;
        ev.timestamp = utime;
        ev.channel = pmg::kVrPoseChannel;
        ev.datalen = static_cast<int32_t>(buf.size());
        ev.data = buf.data();
        if (log.writeEvent(&ev) != 0) throw std::runtime_error(log_path + ": write failed");
        ++sent;
      }
      std::printf("pmg_vr_script: %lld poses (%.1f s at %.0f Hz) written to %s\n", static_cast<long long>(sent),
                  script.end(), script.rate_hz, log_path.c_str());
      return 0;
    }
    pmg::comms::CommandPublisher pub(lcm_url, key_file, "vr_script");
    std::fprintf(stderr, "pmg_vr_script: %s, %zu steps, %.1f s at %.0f Hz on %s (%s)\n", script_path.c_str(),
                 script.steps.size(), script.end(), script.rate_hz, lcm_url.c_str(),
                 pub.authenticated() ? "signed" : "unsigned");
    const auto start = std::chrono::steady_clock::now();
    for (std::int64_t k = 0; k < frames && !g_stop; ++k) {
      const double t = static_cast<double>(k) * period;
      std::this_thread::sleep_until(start + std::chrono::duration<double>(t));
      const std::size_t step = script.stepAt(t);
      if (step != last_step) {
        last_step = step;
        std::fprintf(stderr, "[%6.2f s] %s\n", t, script.steps[step].name.empty() ? "(step)" : script.steps[step].name.c_str());
      }
      if (!script.sample(t, k, s)) continue;
      if (pub.publishVrPose(pmg::teleop::toVrPoseMessage(s, wallMicros()))) ++sent;
    }
    std::fprintf(stderr, "pmg_vr_script: %lld poses published, %llu failed\n", static_cast<long long>(sent),
                 static_cast<unsigned long long>(pub.failed()));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_vr_script: %s\n", e.what());
    return 1;
  }
}
