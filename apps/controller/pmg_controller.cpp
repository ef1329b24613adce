// pmg_controller: the 100 Hz PMG controller over the 500 Hz HAL. One binary for the robot and the
// SIL; the backend and timing mode come from the config (config/controller/*.yaml).
//
//   pmg_controller --config config/controller/g1_sil.yaml [--duration 14] [--script demo.yaml]
//                  [--log run.lcmlog] [--realtime|--lockstep] [--no-lcm]
#include <atomic>
#include <csignal>
#include <cstdio>

#include <CLI/CLI.hpp>

#include "pmg/controller/controller.hpp"
#include "pmg/hal/safety/safe_backend.hpp"

namespace {
std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_controller: PMG humanoid controller (100 Hz loop over a 500 Hz HAL)"};
  std::string config_path, script_path, log_path;
  double duration = 0.0;
  bool realtime = false, lockstep = false, no_lcm = false;
  app.add_option("--config", config_path, "controller config YAML")->required()->check(CLI::ExistingFile);
  app.add_option("--duration", duration, "run time [s]; 0 = the script's length (lockstep) or until Ctrl-C");
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
  bool hal_safety = false;
  app.add_flag("--hal-safety", hal_safety, "500 Hz safety supervisor in the HAL (guard mode: per-input watchdogs, "
                                           "envelope, torque bound, latched damping; docs/hal.md)");
  CLI11_PARSE(app, argc, argv);

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
      config.hal_supervisor = true;
    }
    if (hal_safety) config.hal_supervisor = true;
    pmg::CommandScript script;
    if (!script_path.empty()) script = pmg::loadCommandScript(script_path);
    if (duration <= 0 && !script_path.empty()) duration = script.duration();
    if (duration <= 0 && config.timing == pmg::TimingMode::kLockstep) {
      std::fprintf(stderr, "pmg_controller: lockstep mode needs --duration or --script\n");
      return 2;
    }
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const bool rt = config.timing == pmg::TimingMode::kRealtime;
    const bool can = config.backend == pmg::BackendKind::kCan;
    std::printf("pmg_controller: robot %s (%zu joints), backend %s, %s, %.0f Hz loop / %.0f Hz HAL, HAL supervisor %s\n",
                config.robot.name.c_str(), config.robot.numJoints(),
                can ? ("can (" + config.can.transport + ", plan " + config.can.plan_file + ")").c_str()
                    : (config.mujoco.gantry.enabled ? "mujoco (gantry on)" : "mujoco (gantry off)"),
                rt ? "real time" : "lockstep", config.loop_rate_hz, config.hal_rate_hz,
                config.hal_supervisor ? "on" : "off");
    pmg::Controller controller(config);
    pmg::hal::safety::SafeBackend* safe = controller.halSafety();
    const pmg::CommandScript* sp = script_path.empty() ? nullptr : &script;
    const pmg::RunSummary s = rt ? controller.runRealtime(duration, &g_stop, sp) : controller.runLockstep(duration, sp);
    std::printf("ran %lld ticks, %.2f s controller time in %.2f s wall (real-time factor %.1f)\n",
                static_cast<long long>(s.ticks), s.sim_time, s.wall_time, s.real_time_factor);
    std::printf("loop tick runtime  p50 %.1f us  p99 %.1f us  max %.1f us\n", 1e6 * s.loop.runtime_p50,
                1e6 * s.loop.runtime_p99, 1e6 * s.loop.runtime_max);
    std::printf("HAL cycle runtime  p50 %.1f us  p99 %.1f us  max %.1f us\n", 1e6 * s.hal.runtime_p50,
                1e6 * s.hal.runtime_p99, 1e6 * s.hal.runtime_max);
    if (rt)
      std::printf("HAL period p50 %.3f ms p99 %.3f ms max %.3f ms\n", 1e3 * s.hal.period_p50, 1e3 * s.hal.period_p99,
                  1e3 * s.hal.period_max);
    std::printf("deadline misses: %lld; commands rejected (NaN) %llu, clamped %llu, stale ticks %llu\n",
                static_cast<long long>(s.deadline_misses), static_cast<unsigned long long>(s.commands.rejected_nan),
                static_cast<unsigned long long>(s.commands.clamped),
                static_cast<unsigned long long>(s.commands.stale_ticks));
    std::printf("telemetry frames written %llu, dropped %llu; final mode %d, fault %d\n",
                static_cast<unsigned long long>(s.telemetry_written),
                static_cast<unsigned long long>(s.telemetry_dropped), static_cast<int>(s.final_mode),
                static_cast<int>(s.fault));
    if (!config.log_file.empty()) std::printf("event log: %s\n", config.log_file.c_str());
    pmg::hal::safety::SafetyStatus hs;
    if (safe && safe->status(hs))
      std::printf("HAL safety: mode %s, fault %s (joint %d, at %.3f s), clamped joint-cycles %llu, held replies %llu, "
                  "max |tau|/limit %.2f\n",
                  pmg::hal::safety::toString(hs.mode), pmg::hal::safety::toString(hs.fault.code), hs.fault.index,
                  hs.fault.time_s,
                  static_cast<unsigned long long>(hs.clamped_joint_ticks),
                  static_cast<unsigned long long>(hs.held_replies), hs.max_tau_ratio);
    if (safe && hs.mode == pmg::hal::safety::Mode::kDamping) return 3;
    return s.fault == pmg::ControllerFault::kNone ? 0 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_controller: %s\n", e.what());
    return 1;
  }
}
