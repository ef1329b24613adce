// pmg_sil: the software-in-the-loop robot as a separate process. MuJoCo 2.2 simulates the robot;
// every motor driver is emulated behind the same CAN protocol as on the robot (MIT mode, motor-side
// PD) and the IMU sends CAN FD frames, all over the UDP CAN transport on loopback. pmg_controller
// (or any HAL built with the CAN backend) talks to it exactly as to the robot, through the real bus
// code. Faults can be injected from the command line.
//
//   pmg_sil [--robot config/robots/g1/g1.yaml] [--plan config/hal/g1_can.yaml] --port 47000
//           [--realtime] [--no-gantry] [--duration 20] [--drop 0.01] [--silent-joint 3] ...
//           [--reality REALITY.yaml] [--bench-contacts]
// With --reality the SIL plays a real robot whose truth is hidden from the tools that talk to it
// over the bus (per-joint actuator effects, encoder zero offsets, link mass errors;
// include/pmg/hal/reality.hpp, docs/calibration.md "A real robot with a hidden truth"). It prints
// only how many joints and links the file affects, never what.
#include <atomic>
#include <csignal>
#include <cstdio>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/reality.hpp"

namespace {
std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  using namespace pmg::hal::bus;
  namespace rt = pmg::hal::rt;
  CLI::App app{"pmg_sil: MuJoCo 2.2 robot behind emulated CAN motor drivers (UDP loopback)"};
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string plan_path = pmg::resolveData("config/hal/g1_can.yaml").string();
  std::string reality_path;
  int port = 47000, fifo = 0;
  double duration = 0.0, faults_after = 0.0, push_at = -1.0, push_force = 300.0, push_duration = 0.2;
  bool realtime = false, no_gantry = false, bench_contacts = false;
  SilFaults f;
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--plan", plan_path, "bus plan YAML (same file as the controller's)")->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--reality", reality_path, "hidden truth of this robot (REALITY.yaml: joints, zero_offsets, links)")
      ->check(CLI::ExistingFile);
  app.add_option("--port", port, "UDP base port (bus b: host base+2b, SIL base+2b+1; IMU after the buses)")
      ->check(CLI::Range(1024, 65000));
  app.add_flag("--realtime", realtime, "step every 2 ms of wall time and answer every command at once, like "
                                       "the drivers (default: lockstep, step when a cycle's commands arrived)");
  app.add_flag("--no-gantry", no_gantry, "robot stands on the ground instead of hanging in the virtual gantry");
  app.add_flag("--bench-contacts", bench_contacts,
               "stiff calibration-bench sole contacts (the rigid floor pmg_calib_zero's protocol stands on; "
               "default: the MJCF's soft contacts)");
  app.add_option("--duration", duration, "stop after this much simulated time [s]; 0 = until Ctrl-C");
  app.add_option("--fifo", fifo, "SCHED_FIFO priority in --realtime (0 = normal)")->check(CLI::Range(0, 99));
  app.add_option("--faults-after", faults_after, "start injecting the faults below at this simulated time [s]");
  app.add_option("--drop", f.drop_prob, "probability a reply is lost")->check(CLI::Range(0.0, 1.0));
  app.add_option("--late", f.late_prob, "probability a reply comes one cycle late")->check(CLI::Range(0.0, 1.0));
  app.add_option("--dup", f.dup_prob, "probability a reply is duplicated")->check(CLI::Range(0.0, 1.0));
  app.add_option("--corrupt", f.corrupt_prob, "probability a reply is corrupted")->check(CLI::Range(0.0, 1.0));
  app.add_option("--silent-joint", f.silent_joint, "joint index whose driver stops replying");
  app.add_option("--bus-off", f.bus_off_bus, "bus index that goes bus-off");
  app.add_flag("--imu-frozen", f.imu_frozen, "IMU repeats its last sample");
  app.add_flag("--imu-silent", f.imu_silent, "IMU stops sending");
  app.add_option("--imu-noise", f.imu_gyro_noise, "extra gyro noise std [rad/s]");
  app.add_option("--push-at", push_at, "push the pelvis at this simulated time [s] (-1 = never)");
  app.add_option("--push-force", push_force, "lateral push force (world y) [N]");
  app.add_option("--push-duration", push_duration, "push duration [s]");
  CLI11_PARSE(app, argc, argv);

  try {
    pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const BusPlan plan = BusPlan::fromYaml(plan_path);
    // The robot config is the source of truth for the wiring: the plan must agree joint by joint.
    pmg::hal::bus::checkPlanAgainstRobot(plan.buses(), plan_path, robot);
    pmg::MujocoBackendOptions mo;
    mo.cycle_period = plan.options().period_s;
    mo.gantry.enabled = !no_gantry;
    mo.sole_contacts.enabled = bench_contacts;
    std::string reality_note = "none";
    if (!reality_path.empty()) {
      const pmg::hal::Reality reality = pmg::hal::loadReality(reality_path, robot);
      pmg::hal::applyReality(reality, &robot, &mo);
      reality_note = "hidden (" + std::to_string(reality.affectedJoints(robot).size()) + " joints, " +
                     std::to_string(reality.links.size()) + " links affected)";
    }
    auto sim = std::make_unique<pmg::MujocoBackend>(robot, mo);
    pmg::MujocoBackend* mj = sim.get();
    SilDriverEmulator sil(plan, std::move(sim), static_cast<std::uint16_t>(port));
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    std::printf("pmg_sil: %s, %zu buses, %zu motors, UDP base port %d, %s, gantry %s, %s sole contacts, reality %s\n",
                robot.name.c_str(), plan.buses().size(), plan.motorCount(), port, realtime ? "real time" : "lockstep",
                no_gantry ? "off" : "on", bench_contacts ? "bench" : "MJCF", reality_note.c_str());
    std::printf("%s", plan.report().c_str());
    std::fflush(stdout);
    if (realtime && fifo > 0) {
      std::string why;
      if (!rt::setThreadFifo(fifo, &why)) std::printf("pmg_sil: %s (continuing with normal scheduling)\n", why.c_str());
    }
    const double period = plan.options().period_s;
    bool faults_on = false, pushed = false;
    double next = rt::now();
    while (!g_stop.load()) {
      const double t_sim = static_cast<double>(sil.counters().cycles) * period;
      if (duration > 0.0 && t_sim >= duration) break;
      if (!faults_on && t_sim >= faults_after) {
        sil.setFaults(f);
        faults_on = true;
      }
      if (!pushed && push_at >= 0.0 && t_sim >= push_at) {
        sil.post([mj, push_force, push_duration](pmg::HalBackend&) {
          mj->push(mj->pelvisBody(), Eigen::Vector3d(0.0, push_force, 0.0), push_duration);
        });
        pushed = true;
      }
      if (realtime) {
        next += period;
        if (rt::now() > next + period) next = rt::now();  // overran a whole period: re-anchor
        sil.runRealtimeCycle(next);
      } else {
        sil.runCycle(0.5);
      }
    }
    const SilCounters& c = sil.counters();
    std::printf("pmg_sil: %llu cycles (%.2f s simulated); commands %llu, replies %llu, dropped %llu, late %llu, "
                "duplicated %llu, corrupted %llu, silenced %llu, bus-off injected %llu, restarts seen %llu, "
                "IMU frames %llu, frames no driver takes %llu\n",
                static_cast<unsigned long long>(c.cycles), static_cast<double>(c.cycles) * period,
                static_cast<unsigned long long>(c.commands), static_cast<unsigned long long>(c.replies),
                static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.late),
                static_cast<unsigned long long>(c.duplicated), static_cast<unsigned long long>(c.corrupted),
                static_cast<unsigned long long>(c.silenced), static_cast<unsigned long long>(c.bus_off_injected),
                static_cast<unsigned long long>(c.restarts_seen), static_cast<unsigned long long>(c.imu_frames),
                static_cast<unsigned long long>(c.rejected));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_sil: %s\n", e.what());
    return 1;
  }
}
