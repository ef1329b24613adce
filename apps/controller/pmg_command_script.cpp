// pmg_command_script: publishes a command script over LCM in real time (50 Hz), as a gamepad or VR
// bridge would: PMG_VELOCITY_COMMAND, PMG_POSTURE_COMMAND and, at segment starts that name one,
// PMG_MODE_COMMAND. Reads the one script format (docs/controller.md) that pmg_controller and
// pmg_policy_sil read.
//
//   pmg_command_script --script config/commands/demo.yaml [--rate 50] [--lcm-url udpm://...]
#include <csignal>
#include <cstdio>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>

#include "pmg/controller/commands.hpp"
#include "pmg/controller/lcm_command_source.hpp"
#include "pmg/hal/realtime.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
extern "C" void onSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_command_script: publish a scripted command sequence over LCM"};
  std::string script_path, url = "udpm://239.255.76.67:7667?ttl=0";
  double rate = 50.0;
  app.add_option("--script", script_path, "command script YAML")->required()->check(CLI::ExistingFile);
  app.add_option("--rate", rate, "publish rate [Hz]")->check(CLI::Range(1.0, 1000.0));
  app.add_option("--lcm-url", url, "LCM provider URL");
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::CommandScript script = pmg::loadCommandScript(script_path);
    lcm::LCM lcm(url);
    if (!lcm.good()) throw std::runtime_error("LCM provider '" + url + "' not available");
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const double t0 = pmg::hal::rt::now();
    std::size_t last_segment = static_cast<std::size_t>(-1);
    for (double next = t0; !g_stop; next += 1.0 / rate) {
      const double t = pmg::hal::rt::now() - t0;
      if (t > script.duration()) break;
      const std::size_t k = script.segmentIndex(t);
      const pmg::Command u = script.at(t);
      const auto utime = static_cast<int64_t>(t * 1e6);
      if (k != last_segment) {
        last_segment = k;
        const pmg::CommandSegment& seg = script.segments[k];
        std::printf("t=%6.2f s  %-12s vx %.2f vy %.2f wz %.2f pitch %.2f roll %.2f height %s%s%s\n", t,
                    seg.name.c_str(), u.vx, u.vy, u.wz, u.pitch, u.roll,
                    u.height ? std::to_string(*u.height).c_str() : "none", seg.mode != pmg::ModeRequest::kNone ? " mode " : "",
                    seg.mode != pmg::ModeRequest::kNone ? pmg::toString(seg.mode) : "");
        std::fflush(stdout);
        if (seg.mode != pmg::ModeRequest::kNone) {
          pmg_lcm::mode_command_t m;
          m.utime = utime;
          m.mode = static_cast<int8_t>(seg.mode);
          m.source = "script";
          lcm.publish(pmg::kModeChannel, &m);
        }
      }
      pmg_lcm::velocity_command_t v;
      v.utime = utime;
      v.vx = u.vx;
      v.vy = u.vy;
      v.wz = u.wz;
      v.source = "script";
      lcm.publish(pmg::kVelocityChannel, &v);
      pmg_lcm::posture_command_t p;
      p.utime = utime;
      p.pitch = u.pitch;
      p.roll = u.roll;
      p.has_height = u.height.has_value();
      p.height = u.height.value_or(0.0);
      p.source = "script";
      lcm.publish(pmg::kPostureChannel, &p);
      pmg::hal::rt::sleepUntil(next + 1.0 / rate);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_command_script: %s\n", e.what());
    return 1;
  }
}
