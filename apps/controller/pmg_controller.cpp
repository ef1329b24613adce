// pmg_controller: the 100 Hz PMG controller over the 500 Hz HAL. One binary for the robot and the
// SIL; the backend and timing mode come from the config (config/controller/*.yaml). The HAL
// supervisor (watchdogs, envelope, fall detection, the mode state machine) is always on.
//
//   pmg_controller --config config/controller/g1_sil.yaml [--duration 14] [--script demo.yaml]
//                  [--log run.lcmlog] [--realtime|--lockstep] [--no-lcm]
//
// Exit status: 0 the run ended without a fault; 3 the robot fell or faulted (it is in damping);
// 1 setup error (the message names the file and field); 2 bad command line.
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>

#include <CLI/CLI.hpp>

#include "pmg/common/cli_checks.hpp"
#include "pmg/controller/controller_app.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void onSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_controller: PMG humanoid controller (100 Hz loop over a 500 Hz HAL)"};
  std::string config_path, script_path, log_path;
  double duration = 0.0;
  bool realtime = false, lockstep = false, no_lcm = false;
  app.add_option("--config", config_path, "controller config YAML")->required()->check(CLI::ExistingFile);
  app.add_option("--duration", duration, "run time [s]; 0 = the script's length (lockstep) or until Ctrl-C")
      ->check(pmg::cli::finiteIn(0.0, 1e7));
  app.add_option("--script", script_path, "scripted command sequence YAML (instead of LCM input)")
      ->check(CLI::ExistingFile);
  app.add_option("--log", log_path, "record telemetry as an LCM event log (lcm-logger format)");
  app.add_flag("--realtime", realtime, "pace to the wall clock (overrides timing.mode)");
  app.add_flag("--lockstep", lockstep, "run as fast as possible, loop-driven HAL (overrides timing.mode)");
  app.add_flag("--no-lcm", no_lcm, "do not open LCM");
  // Motor buses (docs/hal.md): the same loop over the CAN backend, towards pmg_sil or the robot.
  std::string can_plan, can_transport = "udp";
  int can_port = 47000;
  app.add_option("--can-plan", can_plan, "drive the motors over CAN with this bus plan (config/hal/*.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--can-transport", can_transport, "udp (towards pmg_sil) or socketcan (robot)")
      ->check(CLI::IsMember({"udp", "socketcan"}));
  app.add_option("--can-port", can_port, "UDP base port of pmg_sil")->check(CLI::Range(1024, 65000));
  CLI11_PARSE(app, argc, argv);
  // Every run mode stops cleanly on SIGINT/SIGTERM, a signal during setup included: the runner
  // checks the flag every tick (lockstep) or every 10 ms (real time), then the log and the summary
  // are written.
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);

  try {
    pmg::ControllerConfig config = pmg::loadControllerConfig(config_path);
    if (realtime) config.timing = pmg::TimingMode::kRealtime;
    if (lockstep) config.timing = pmg::TimingMode::kLockstep;
    if (no_lcm) config.lcm_enabled = false;
    if (!log_path.empty()) config.log_file = log_path;
    if (!can_plan.empty()) {  // command-line override of the config's backend
      config.backend = pmg::BackendKind::kCan;
      config.can.plan_file = can_plan;
      config.can.transport = can_transport;
      config.can.udp_port = can_port;
    }
    pmg::CommandScript script;
    if (!script_path.empty()) script = pmg::loadCommandScript(script_path);
    if (duration <= 0 && !script_path.empty()) duration = script.duration();
    if (duration <= 0 && config.timing == pmg::TimingMode::kLockstep) {
      std::fprintf(stderr, "pmg_controller: lockstep mode needs --duration or --script\n");
      return 2;
    }
    const bool rt = config.timing == pmg::TimingMode::kRealtime;
    const bool can = config.backend == pmg::BackendKind::kCan;
    std::printf("pmg_controller: robot %s (%zu joints), backend %s, %s, %.0f Hz loop / %.0f Hz HAL, supervisor on\n",
                config.robot.name.c_str(), config.robot.numJoints(),
                can ? ("can (" + config.can.transport + ", plan " + config.can.plan_file + ")").c_str()
                    : (config.mujoco.gantry.enabled ? "mujoco (gantry on)" : "mujoco (gantry off)"),
                rt ? "real time" : "lockstep", config.loop_rate_hz, config.hal_rate_hz);
    std::fflush(stdout);
    pmg::ControllerApp controller(config);
    const pmg::RunSummary s = controller.run(duration, script_path.empty() ? nullptr : &script, &g_stop);
    std::printf("%s", s.text().c_str());
    if (!controller.config().log_file.empty()) std::printf("event log: %s\n", controller.config().log_file.c_str());
    return s.exitCode();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_controller: %s\n", e.what());
    return 1;
  }
}
