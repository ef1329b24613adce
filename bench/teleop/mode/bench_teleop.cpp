// bench_teleop: the 100 Hz tick with VR teleoperation active, through the product path
// (ControllerApp: shaper, generator, GCO, teleop arm IK, limiter, policy, supervisor, MuJoCo SIL
// in lockstep), fed a synthetic operator: engaged after 1 s, walking forward, both grips held
// and both hands circling in front of the chest. Prints the tick's p50/p99/max, the IK solve time
// of both arms per tick, the IK's position/orientation error on these (reachable) targets, and
// the allocations of the tick.
//
//   build/bin/bench_teleop [--config config/controller/g1_sil_teleop.yaml] [--seconds 30]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace {
struct Pct {
  double p50, p99, max;
};
Pct percentiles(std::vector<double> v) {
  if (v.empty()) return {0, 0, 0};
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v[std::min(v.size() - 1, v.size() * 99 / 100)], v.back()};
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_teleop: the 100 Hz tick and the arm IK with VR teleoperation active (lockstep SIL)"};
  std::string config_path = pmg::resolveData("config/controller/g1_sil_teleop.yaml").string();
  double seconds = 30.0;
  app.add_option("--config", config_path, "controller config YAML with teleop.enabled")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--seconds", seconds, "simulated seconds with teleop engaged")->check(CLI::Range(1.0, 600.0));
  bool arms = true;
  app.add_option("--arms", arms, "grips held: the arms follow through IK (false: the same run, arms on PMG)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  pmg::ControllerConfig config = pmg::loadControllerConfig(config_path);
  if (!config.teleop.enabled) {
    std::fprintf(stderr, "bench_teleop: %s: teleop.enabled is false\n", config_path.c_str());
    return 2;
  }
  config.makeOffline();
  pmg::ControllerApp controller(config);
  const pmg::teleop::TeleopMode& tm = *controller.controller().teleop();

  pmg::CommandSample in;
  in.vr.head_position = {0.0, 0.0, 1.6};
  in.vr.hand_position = {{{0.3, 0.2, 1.2}, {0.3, -0.2, 1.2}}};
  long tick = 0;
  std::vector<double> ik_us, pos_err_mm, ori_err_mrad;
  const auto step = [&](bool a_button, bool grips) {
    const double t = static_cast<double>(tick) * 0.01;
    pmg::teleop::VrSample& s = in.vr;
    const double walk = t > 1.5 ? 0.2 : 0.0;  // 0.15 m beyond the dead band: ~0.2 m/s forward
    const std::array<double, 3> head_before = s.head_position;
    s.head_position = {walk, 0.0, 1.6};
    for (auto& p : s.hand_position)
      for (std::size_t k = 0; k < 3; ++k) p[k] += s.head_position[k] - head_before[k];
    s.head_quat = {1, 0, 0, 0};
    s.hand_valid = {true, true};
    for (int h = 0; h < 2; ++h) {
      // Each hand circles (radius 6 cm, 0.27 Hz) in front of where the robot's hand is in its
      // nominal pose (the shipped policy's arm envelope; docs/teleop.md, "Limits").
      const auto hh = static_cast<std::size_t>(h);
      const double ph = 1.7 * t + h * 1.3;
      const Eigen::Vector3d want = tm.ik().forwardKinematics(h, tm.ik().nominal(h)).position +
                                   Eigen::Vector3d(0.06 + 0.06 * std::cos(ph), 0.03 * std::sin(ph), 0.05 + 0.06 * std::sin(ph));
      const Eigen::Vector3d now = tm.armTarget(s, h).position;
      for (std::size_t k = 0; k < 3; ++k)
        s.hand_position[hh][k] += (want[static_cast<Eigen::Index>(k)] - now[static_cast<Eigen::Index>(k)]) / tm.config().arm_scale;
      s.grip[hh] = grips ? 1.0 : 0.0;
    }
    s.buttons = {0u, a_button ? static_cast<std::uint32_t>(pmg::teleop::kVrButtonLower) : 0u};
    ++s.frame;
    in.vr_time = t;
    controller.stepLockstep(in);
    ++tick;
    const pmg::teleop::TeleopStatus& st = tm.status();
    if (st.arm[0] == pmg::teleop::ArmMode::kFollowing && st.arm[1] == pmg::teleop::ArmMode::kFollowing && t > 3.0) {
      ik_us.push_back(1e6 * st.ik_time_s);
      for (int h = 0; h < 2; ++h) {
        const auto& r = st.ik[static_cast<std::size_t>(h)];
        if (r.status == pmg::teleop::ArmIkStatus::kConverged || r.status == pmg::teleop::ArmIkStatus::kMaxIterations) {
          pos_err_mm.push_back(1e3 * r.position_error_m);
          ori_err_mrad.push_back(1e3 * r.orientation_error_rad);
        }
      }
    }
  };
  for (int k = 0; k < 100; ++k) step(false, false);  // stand up, engage the actor
  for (int k = 0; k < 5; ++k) step(true, false);     // A: engage teleop
  const long n = std::lround(seconds / 0.01);
  for (long k = 0; k < n; ++k) step(false, arms);
  const pmg::RunSummary s = controller.finish();

  const Pct ik = percentiles(ik_us), pe = percentiles(pos_err_mm), oe = percentiles(ori_err_mrad);
  std::printf("teleop engaged %.0f s of %.0f s; both arms following on %zu ticks\n", seconds, tick * 0.01, ik_us.size());
  std::printf("loop tick with teleop (shaper + teleop + generator + GCO + arm IK + limiter + policy + telemetry)"
              "  p50 %7.2f us  p99 %7.2f us  max %7.2f us  (n=%ld)\n",
              1e6 * s.loop.runtime_p50, 1e6 * s.loop.runtime_p99, 1e6 * s.loop.runtime_max, tick);
  std::printf("arm IK, both arms per tick  p50 %7.2f us  p99 %7.2f us  max %7.2f us\n", ik.p50, ik.p99, ik.max);
  std::printf("IK error on the operator's (reachable) targets: position p50 %.3f mm p99 %.3f mm max %.3f mm; "
              "orientation p50 %.3f mrad p99 %.3f mrad max %.3f mrad\n",
              pe.p50, pe.p99, pe.max, oe.p50, oe.p99, oe.max);
  std::printf("final mode %s, fault %s, pelvis height %.2f m\n", pmg::toString(s.final_mode), pmg::toString(s.fault),
              controller.controller().lastState().base_position[2]);
  return 0;
}
