// pmg_gamepad: a game controller (SDL2 GameController API) drives the robot over LCM:
// PMG_VELOCITY_COMMAND and PMG_POSTURE_COMMAND at --rate, PMG_MODE_COMMAND on button presses, through
// pmg::comms::CommandPublisher (signed when --key is given). Button map: docs/teleop.md.
//
//   pmg_gamepad [--config config/teleop/gamepad.yaml] [--lcm-url URL] [--key FILE] [--rate 50]
//               [--duration S] [--virtual-script FILE] [--controller NAME]
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>

#include "pmg/common/cli_checks.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/hal/modes.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/teleop/gamepad.hpp"
#include "pmg/teleop/gamepad_script.hpp"
#include "pmg/teleop/gamepad_sdl.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
extern "C" void onSignal(int) { g_stop = 1; }

using pmg::teleop::GamepadOutput;

std::string heightText(const GamepadOutput& o) {
  if (!o.height) return "none";
  char b[32];
  std::snprintf(b, sizeof b, "%.3f m", *o.height);
  return b;
}

constexpr const char* kFooter = R"(Button map (config/teleop/gamepad.yaml; after unitree_rl_lab's G1 deploy FSM):
  LT + B       e-stop: damping, latched until released and LT + Start
  LT + up      stand (soft stand)          RB + X      walk (active)
  Back         damping                     LT + Start  reset (damping -> passive), re-arm
  left stick   vx (up = forward), vy (left = +)      right stick  wz (left = counter-clockwise)
  d-pad up/down  height; RT + d-pad up/down  pitch; d-pad left/right  roll; RT + Y  neutral posture
A lost controller (unplugged, or no state for 0.5 s) gives zero velocity at once and one damping
request after 1 s. Exit codes: 0 stopped (Ctrl-C, --duration, end of the script), 1 setup error
(config, key file, LCM, SDL), 2 bad command line.)";

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_gamepad: a game controller drives the robot over LCM (velocity, posture, mode requests)"};
  std::string config_path = pmg::resolveData("config/teleop/gamepad.yaml").string();
  std::string url = pmg::kDefaultLcmUrl, key_file, script_path, controller_name;
  double rate = 50.0, duration = 0.0, status_period = 2.0;
  app.add_option("--config", config_path, "gamepad config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--lcm-url", url, "LCM provider URL (the default keeps traffic on this host: ttl=0)")
      ->capture_default_str();
  app.add_option("--key", key_file, "authentication key file (owner-only, from pmg_keygen); none = unsigned")
      ->check(CLI::ExistingFile);
  app.add_option("--rate", rate, "publish rate [Hz]")->check(pmg::cli::finiteIn(1.0, 1000.0))->capture_default_str();
  app.add_option("--duration", duration, "stop after this many seconds; 0 = until Ctrl-C (or the script's end)")
      ->check(pmg::cli::finiteIn(0.0, 1e7));
  app.add_option("--virtual-script", script_path,
                 "attach an SDL virtual controller and play this YAML script of stick/button states into it")
      ->check(CLI::ExistingFile);
  app.add_option("--controller", controller_name, "use only a controller whose SDL name contains this text");
  app.add_option("--status-period", status_period, "seconds between status lines on stderr")
      ->check(pmg::cli::finiteIn(0.1, 3600.0))
      ->capture_default_str();
  app.footer(kFooter);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    const pmg::teleop::GamepadConfig config = pmg::teleop::loadGamepadConfig(config_path);
    pmg::teleop::GamepadScript script;
    const bool scripted = !script_path.empty();
    if (scripted) script = pmg::teleop::loadGamepadScript(script_path);
    if (duration <= 0 && scripted) duration = script.end();
    pmg::teleop::GamepadMapper mapper(config);
    pmg::comms::CommandPublisher publisher(url, key_file, "gamepad");
    pmg::teleop::SdlGamepad reader(controller_name);
    std::unique_ptr<pmg::teleop::SdlVirtualGamepad> virt;
    if (scripted) virt = std::make_unique<pmg::teleop::SdlVirtualGamepad>("pmg virtual gamepad");

    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    std::fprintf(stderr, "pmg_gamepad: config %s, LCM %s, %s, %.0f Hz%s%s\n", config_path.c_str(), url.c_str(),
                 publisher.authenticated() ? "signed" : "unsigned (no --key)", rate,
                 scripted ? ", virtual controller script " : "", scripted ? script_path.c_str() : "");

    const double period = 1.0 / rate;
    const double t0 = pmg::hal::rt::now();
    double next = t0, next_status = 0.0;
    std::size_t step = static_cast<std::size_t>(-1);
    std::string last_name = "-";
    pmg::teleop::GamepadLink last_link = pmg::teleop::GamepadLink::kNone;
    bool last_latched = false;
    while (!g_stop) {
      const double now = pmg::hal::rt::now();
      const double t = now - t0;
      if (duration > 0 && t >= duration) break;
      if (scripted) {
        const std::size_t k = script.stepIndex(t);
        if (k != step) {
          step = k;
          const pmg::teleop::GamepadScriptStep& s = script.steps[k];
          if (s.attached) {
            virt->attach();
            virt->set(s.state());
          } else {
            virt->detach();
          }
          std::fprintf(stderr, "t=%7.2f s  script step %zu%s%s\n", t, k, s.name.empty() ? "" : ": ", s.name.c_str());
        }
      }
      const pmg::teleop::GamepadState state = reader.poll(now);
      const GamepadOutput& out = mapper.update(state, now);
      publisher.publishVelocity(out.vx, out.vy, out.wz);
      publisher.publishPosture(out.pitch, out.roll, out.height);
      if (out.mode != pmg::ModeRequest::kNone) {
        publisher.publishMode(out.mode);
        std::fprintf(stderr, "t=%7.2f s  mode request: %s%s\n", t, pmg::toString(out.mode),
                     out.estop_latched                             ? " (e-stop latched)"
                     : out.link == pmg::teleop::GamepadLink::kLost ? " (controller lost)"
                                                                   : "");
      }
      const bool changed = reader.name() != last_name || out.link != last_link || out.estop_latched != last_latched;
      if (changed || t >= next_status) {
        std::fprintf(stderr,
                     "t=%7.2f s  controller %s | link %s | vx %+.2f vy %+.2f wz %+.2f | pitch %+.2f roll %+.2f "
                     "height %s | e-stop %s%s | sent %llu (%llu failed)\n",
                     t, reader.connected() ? ("'" + reader.name() + "'").c_str() : "none", toString(out.link), out.vx,
                     out.vy, out.wz, out.pitch, out.roll, heightText(out).c_str(),
                     out.estop_latched ? "LATCHED" : "armed", out.waiting_for_centre ? " | centre the sticks" : "",
                     static_cast<unsigned long long>(publisher.published()),
                     static_cast<unsigned long long>(publisher.failed()));
        last_name = reader.name();
        last_link = out.link;
        last_latched = out.estop_latched;
        next_status = t + status_period;
      }
      next += period;
      if (next < now) next = now + period;  // overran by a whole period: re-anchor, no burst
      pmg::hal::rt::sleepUntil(next);
    }
    publisher.publishVelocity(0.0, 0.0, 0.0);  // a clean stop stops the robot now, not at the controller's timeout
    const pmg::teleop::GamepadCounters& c = mapper.counters();
    std::fprintf(stderr,
                 "pmg_gamepad: stopped after %.2f s: %llu updates, %llu mode requests, %llu e-stops, %llu losses "
                 "(%llu damping on loss), %llu controllers connected, %llu messages sent, %llu failed\n",
                 pmg::hal::rt::now() - t0, static_cast<unsigned long long>(c.updates),
                 static_cast<unsigned long long>(c.mode_requests), static_cast<unsigned long long>(c.estops),
                 static_cast<unsigned long long>(c.losses), static_cast<unsigned long long>(c.loss_dampings),
                 static_cast<unsigned long long>(reader.connects()),
                 static_cast<unsigned long long>(publisher.published()),
                 static_cast<unsigned long long>(publisher.failed()));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_gamepad: %s\n", e.what());
    return 1;
  }
}
