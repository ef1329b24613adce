// pmg_command_script: publishes a scripted command sequence over LCM in real time (50 Hz), as a
// gamepad or VR bridge would, on PMG_VELOCITY_COMMAND and PMG_POSTURE_COMMAND.
//
//   pmg_command_script --script config/commands/demo.yaml [--rate 50] [--lcm-url udpm://...]
#include <chrono>
#include <cstdio>
#include <thread>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>

#include "pmg/controller/commands.hpp"
#include "pmg/hal/hal_runner.hpp"

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
    const double t0 = pmg::monotonicSeconds();
    std::string last_label;
    for (double next = t0;; next += 1.0 / rate) {
      const double t = pmg::monotonicSeconds() - t0;
      if (t > script.duration()) break;
      const pmg::CommandSegment& seg = script.at(t);
      if (seg.label != last_label) {
        std::printf("t=%6.2f s  %-12s vx %.2f vy %.2f wz %.2f pitch %.2f roll %.2f height %.2f\n", t,
                    seg.label.c_str(), seg.velocity.vx, seg.velocity.vy, seg.velocity.wz, seg.posture.pitch,
                    seg.posture.roll, seg.posture.height);
        std::fflush(stdout);
        last_label = seg.label;
      }
      const auto utime = static_cast<int64_t>(t * 1e6);
      pmg_lcm::velocity_command_t v;
      v.utime = utime;
      v.vx = seg.velocity.vx;
      v.vy = seg.velocity.vy;
      v.wz = seg.velocity.wz;
      v.source = "script";
      lcm.publish("PMG_VELOCITY_COMMAND", &v);
      pmg_lcm::posture_command_t p;
      p.utime = utime;
      p.pitch = seg.posture.pitch;
      p.roll = seg.posture.roll;
      p.height = seg.posture.height;
      p.source = "script";
      lcm.publish("PMG_POSTURE_COMMAND", &p);
      pmg::sleepUntil(next + 1.0 / rate);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_command_script: %s\n", e.what());
    return 1;
  }
}
