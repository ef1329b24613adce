// pmg_bench_hal: numbers for the 500 Hz HAL on this machine.
//  1. bus load per bus for the G1 bus plans (classic CAN, CAN FD, and the refused per-limb plan);
//  2. cost of the cyclic HAL work: MIT encode/decode per motor, safety supervisor step for 29 joints;
//  3. HAL cycle jitter at 500 Hz (absolute-deadline sleeps) with normal scheduling and with
//     SCHED_FIFO + mlockall (falls back, and says why, without the privileges), p50/p99/max;
//  4. optional (--sil-cycles N): round-trip of one CAN HAL cycle over UDP against the SIL emulator.
//
//   pmg_bench_hal [--seconds 5] [--fifo 80] [--cpu 1] [--sil-cycles 2000] [--csv jitter.csv]
// --csv writes every cycle's wake-up period of both jitter runs (for apps/hal/plot_jitter.py).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/common/robot_config.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/hal/bus/bus_plan.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/bus/mit_protocol.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/supervisor.hpp"

using namespace pmg::hal;

namespace {

void printLoads(const std::string& path) {
  bus::BusPlanOptions o;
  const auto buses = bus::BusPlan::parseYaml(path, o);
  const bus::BusPlanCheck c = bus::checkBusPlan(buses, o);
  std::printf("\n%s: %s\n", path.c_str(), c.ok ? "accepted" : "REFUSED at start-up");
  std::printf("  %-6s %-14s %6s %11s %11s %8s\n", "bus", "timing", "motors", "cmd+reply", "busy [us]", "load");
  for (std::size_t b = 0; b < buses.size(); ++b) {
    const bus::BusLoad& l = c.loads[b];
    char timing[48];
    if (buses[b].timing.fd)
      std::snprintf(timing, sizeof timing, "FD %.0f/%.0fk", buses[b].timing.bitrate / 1e3, buses[b].timing.data_bitrate / 1e3);
    else
      std::snprintf(timing, sizeof timing, "CAN %.0fk", buses[b].timing.bitrate / 1e3);
    std::printf("  %-6s %-14s %6zu %8.1f us %11.1f %7.1f%%%s\n", buses[b].name.c_str(), timing, l.motors,
                1e6 * (l.command_s + l.reply_s), 1e6 * l.busy_s, 100.0 * l.load, l.load > o.max_load ? "  > 80 %" : "");
  }
}

struct CyclicWork {
  bus::BusPlan plan;
  safety::SafetySupervisor sup;
  safety::SafetyInput in;
  safety::SafetyOutput out;
  bus::MitProtocol mit;
  double t = 0;
  CyclicWork(bus::BusPlan p, safety::SafetyOptions so)
      : plan(std::move(p)), sup(std::move(so)), in(sup.makeInput()), out(sup.makeOutput()) {
    for (std::size_t j = 0; j < sup.numJoints(); ++j) in.q[j] = sup.options().stand_q[j];
  }
  // What the HAL thread computes per cycle, without the I/O: decode 29 replies, one supervisor
  // step, encode 29 commands.
  void operator()() noexcept {
    t += 0.002;
    in.now_s = t;
    in.imu.stamp_s = t;
    in.imu.omega_B[0] = 1e-3 * std::sin(1e3 * t);
    in.command_stamp_s = in.policy_stamp_s = t;
    in.policy_valid = true;
    for (const auto& b : plan.buses()) {
      for (const auto& m : b.motors) {
        bus::CanFrame f;
        bus::MitProtocol::encodeReply(m, bus::MotorFeedback{m.motor_id, in.q[static_cast<std::size_t>(m.joint_index)], 0.0, 0.0}, f);
        bus::MotorFeedback fb;
        if (mit.decodeReply(m, f, fb) == bus::ReplyStatus::kOk) in.motor_stamp_s[static_cast<std::size_t>(m.joint_index)] = t;
      }
    }
    sup.step(in, out);
    for (const auto& b : plan.buses()) {
      for (const auto& m : b.motors) {
        const auto j = static_cast<std::size_t>(m.joint_index);
        bus::CanFrame f;
        mit.encodeCommand(m, bus::MotorCommand{out.cmd_q[j], out.cmd_qd[j], out.cmd_kp[j], out.cmd_kd[j], out.cmd_tau[j]}, f);
      }
    }
  }
};

void printSummary(const char* label, pmg::TimingStats& s, const rt::RtReport& r) {
  const pmg::TimingSummary x = s.summary();
  std::printf("  %-30s period p50 %7.1f  p99 %7.1f  max %7.1f us | runtime p50 %5.1f p99 %5.1f max %6.1f us | "
              "overruns %lld / %lld\n",
              label, 1e6 * x.period_p50, 1e6 * x.period_p99, 1e6 * x.period_max, 1e6 * x.runtime_p50,
              1e6 * x.runtime_p99, 1e6 * x.runtime_max, static_cast<long long>(x.deadline_misses),
              static_cast<long long>(x.cycles));
  if (!r.notes.empty()) std::printf("    (%s)\n", r.notes.substr(0, r.notes.size() - 1).c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_bench_hal: bus loads, cyclic cost and 500 Hz jitter of the HAL"};
  double seconds = 5.0;
  int fifo = 80, cpu = -1, sil_cycles = 0;
  app.add_option("--seconds", seconds, "duration of each jitter run [s]")->check(CLI::Range(0.1, 600.0));
  app.add_option("--fifo", fifo, "SCHED_FIFO priority for the second run")->check(CLI::Range(1, 99));
  app.add_option("--cpu", cpu, "pin the HAL task to this CPU (-1: no affinity)");
  app.add_option("--sil-cycles", sil_cycles, "also time N CAN HAL cycles over UDP against the SIL (0: skip)");
  std::string csv;
  app.add_option("--csv", csv, "write run,period_us of every cycle of the jitter runs");
  CLI11_PARSE(app, argc, argv);
  try {
    std::printf("== 1. Bus load per 2 ms slot (worst-case bit stuffing, MIT command 8 B + reply 6 B, 20 us turnaround)\n");
    for (const char* p : {"config/hal/g1_can.yaml", "config/hal/g1_canfd.yaml", "config/hal/g1_can_per_limb.yaml"})
      printLoads(pmg::resolveData(p).string());

    const std::string plan_path = pmg::resolveData("config/hal/g1_can.yaml").string();
    const pmg::RobotConfig robot = pmg::loadRobotConfig(pmg::resolveData("config/robots/g1/g1.yaml").string());
    CyclicWork work(bus::BusPlan::fromYaml(plan_path), safety::SafetyOptions::fromRobot(robot));
    std::printf("\n== 2. Cyclic HAL work, 29 motors (decode replies + supervisor step + encode commands)\n");
    const int reps = 20000;
    const double t0 = rt::now();
    for (int i = 0; i < reps; ++i) work();
    const double per = (rt::now() - t0) / reps;
    std::printf("  %.2f us per cycle (%.0f ns per motor), %.2f %% of the 2 ms budget\n", 1e6 * per, 1e9 * per / 29, 100 * per / 0.002);

    std::printf("\n== 3. HAL cycle jitter at 500 Hz, %.1f s per run, on %ld CPUs (load from other processes included)\n",
                seconds, sysconf(_SC_NPROCESSORS_ONLN));
    const auto cycles = static_cast<std::int64_t>(seconds / 0.002);
    // Wake-up times of every cycle, preallocated (the body stays allocation-free).
    std::vector<double> starts(static_cast<std::size_t>(cycles));
    std::vector<double> periods[2];
    std::string labels[2];
    for (int run = 0; run < 2; ++run) {
      rt::PeriodicOptions o;
      o.cpu = cpu;
      if (run == 1) {
        o.fifo_priority = fifo;
        o.lock_memory = true;
      }
      std::size_t k = 0;
      rt::PeriodicTask task(o, [&] {
        if (k < starts.size()) starts[k++] = rt::now();
        work();
      });
      const rt::RtReport r = task.runFor(cycles);
      char label[64];
      if (run == 0) std::snprintf(label, sizeof label, "normal scheduling");
      else std::snprintf(label, sizeof label, "SCHED_FIFO %d + mlockall%s", fifo, r.fifo ? "" : " (REFUSED)");
      labels[run] = label;
      printSummary(label, task.timing(), r);
      for (std::size_t i = 1; i < k; ++i) periods[run].push_back(starts[i] - starts[i - 1]);
    }
    if (!csv.empty()) {
      std::FILE* f = std::fopen(csv.c_str(), "w");
      if (!f) throw std::runtime_error(csv + ": cannot write");
      std::fprintf(f, "run,period_us\n");
      for (int run = 0; run < 2; ++run)
        for (double p : periods[run]) std::fprintf(f, "%s,%.3f\n", labels[run].c_str(), 1e6 * p);
      std::fclose(f);
      std::printf("  periods written to %s\n", csv.c_str());
    }

    if (sil_cycles > 0) {
      std::printf("\n== 4. CAN HAL cycle over UDP loopback against the SIL emulator (lockstep round trip)\n");
      bus::BusPlan plan = bus::BusPlan::fromYaml(plan_path);
      const auto base = static_cast<std::uint16_t>(30000 + (getpid() % 1000) * 20);
      auto sim = std::make_unique<pmg::MujocoBackend>(robot, pmg::MujocoBackendOptions{});
      bus::SilDriverEmulator sil(plan, std::move(sim), base);
      std::atomic<bool> stop{false};
      std::thread sil_thread([&] { while (!stop) sil.runCycle(0.05); });
      std::unique_ptr<bus::CanTransport> imu;
      auto ts = bus::makeHostUdpTransports(plan, base, imu);
      bus::CanBackendOptions co;
      co.lockstep = true;
      bus::CanBackend can(plan, std::move(ts), std::move(imu), co);
      pmg::LowCommand cmd;
      cmd.num_motors = 29;
      pmg::LowState st;
      pmg::TimingStats stats;
      for (int i = 0; i < sil_cycles; ++i) {
        const double a = rt::now();
        can.exchange(cmd, st);
        stats.record(rt::now() - a, 0.0, false);
      }
      stop = true;
      sil_thread.join();
      const pmg::TimingSummary x = stats.summary();
      std::printf("  exchange() incl. SIL physics step: p50 %.1f us  p99 %.1f us  max %.1f us over %d cycles; "
                  "replies %llu of %d\n",
                  1e6 * x.runtime_p50, 1e6 * x.runtime_p99, 1e6 * x.runtime_max, sil_cycles,
                  static_cast<unsigned long long>(can.motorCounters(0).replies), sil_cycles);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_bench_hal: %s\n", e.what());
    return 1;
  }
}
