// pmg_command_script: publishes a command script over LCM in real time (50 Hz), as a gamepad or VR
// bridge would: PMG_VELOCITY_COMMAND, PMG_POSTURE_COMMAND and, at segment starts that name one,
// PMG_MODE_COMMAND. Reads the one script format (docs/controller.md) that pmg_controller and
// pmg_policy_sil read. With --key every message carries the authentication trailer
// (pmg::comms::CommandPublisher; docs/teleop.md), as a controller with
// `security.key_file` requires.
//
//   pmg_command_script --script config/commands/demo.yaml [--rate 50] [--lcm-url udpm://...] [--key FILE]
#include <csignal>
#include <cstdio>

#include <CLI/CLI.hpp>

#include "pmg/comms/command_publisher.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/hal/realtime.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
extern "C" void onSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_command_script: publish a scripted command sequence over LCM"};
  std::string script_path, url = pmg::kDefaultLcmUrl, key_file;
  double rate = 50.0;
  app.add_option("--script", script_path, "command script YAML")->required()->check(CLI::ExistingFile);
  app.add_option("--rate", rate, "publish rate [Hz]")->check(CLI::Range(1.0, 1000.0));
  app.add_option("--lcm-url", url, "LCM provider URL (default: ttl=0, host only)");
  app.add_option("--key", key_file, "key file (pmg_keygen, mode 0600): sign every message");
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::CommandScript script = pmg::loadCommandScript(script_path);
    pmg::comms::CommandPublisher publisher(url, key_file, "script");
    if (publisher.authenticated())
      std::printf("signing every message (key id %s, sender id %08x)\n", publisher.keyId().c_str(), publisher.senderId());
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const double t0 = pmg::hal::rt::now();
    std::size_t last_segment = static_cast<std::size_t>(-1);
    for (double next = t0; !g_stop; next += 1.0 / rate) {
      const double t = pmg::hal::rt::now() - t0;
      if (t > script.duration()) break;
      const std::size_t k = script.segmentIndex(t);
      const pmg::Command u = script.at(t);
      if (k != last_segment) {
        last_segment = k;
        const pmg::CommandSegment& seg = script.segments[k];
        std::printf("t=%6.2f s  %-12s vx %.2f vy %.2f wz %.2f pitch %.2f roll %.2f height %s%s%s\n", t,
                    seg.name.c_str(), u.vx, u.vy, u.wz, u.pitch, u.roll,
                    u.height ? std::to_string(*u.height).c_str() : "none", seg.mode != pmg::ModeRequest::kNone ? " mode " : "",
                    seg.mode != pmg::ModeRequest::kNone ? pmg::toString(seg.mode) : "");
        std::fflush(stdout);
        if (seg.mode != pmg::ModeRequest::kNone) publisher.publishMode(seg.mode);
      }
      publisher.publishVelocity(u.vx, u.vy, u.wz);
      publisher.publishPosture(u.pitch, u.roll, u.height);
      pmg::hal::rt::sleepUntil(next + 1.0 / rate);
    }
    if (publisher.failed() > 0)
      std::fprintf(stderr, "pmg_command_script: %llu of %llu messages could not be published\n",
                   static_cast<unsigned long long>(publisher.failed()),
                   static_cast<unsigned long long>(publisher.failed() + publisher.published()));
    return publisher.failed() > 0 ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_command_script: %s\n", e.what());
    return 1;
  }
}
