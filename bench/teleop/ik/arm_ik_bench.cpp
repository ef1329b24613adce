// pmg_arm_ik_bench: solve time of pmg::teleop::ArmIk (both arms, one solve() per 100 Hz tick) at
// the 100 Hz settings (ArmIkOptions defaults), printed as p50 / p90 / p99 / p99.9 / max per scenario:
//   smooth    the pose stream of a smooth arm trajectory (the robot's own forward kinematics,
//             test/teleop/ik/arm_ik_streams.hpp), seeded with the previous solution;
//   jumps     a new random reachable target pair every 0.5 s (the arms walk to it at the
//             continuity bound, every tick uses the whole iteration budget);
//   contact   both hands driven into the torso and into each other (collision pairs active);
//   far       targets far outside the workspace (clamped) in random directions.
// --csv FILE writes the smooth stream per tick (pose errors, IK joints, the known answer q*, the
// generating trajectory q_a) for scripts/plot_arm_ik.py.
// Usage: build/bench/teleop/ik/pmg_arm_ik_bench [--ticks N] [--robot g1.yaml] [--csv out.csv]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "arm_ik_streams.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/teleop/arm_ik.hpp"

namespace {

using pmg::teleop::ArmIk;
using pmg::teleop::ArmIkResult;
using pmg::teleop::ArmIkStatus;
using pmg::teleop::ArmJoints;
using pmg::teleop::ArmPose;
using pmg::teleop::kArmDofs;
using Q2 = std::array<ArmJoints, 2>;
using T2 = std::array<ArmPose, 2>;
using R2 = std::array<ArmIkResult, 2>;

double pct(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}

struct Stats {
  std::vector<double> us;
  double iterations = 0;
  int converged = 0;
  int clamped = 0;
  int collision_limited = 0;
  int arms = 0;
  double ep_max = 0, eo_max = 0;
};

/// Times solve() over `targets` (one pair per tick) starting from q.
Stats run(ArmIk& ik, const std::vector<T2>& targets, Q2 q) {
  Stats s;
  s.us.reserve(targets.size());
  R2 r;
  for (const T2& t : targets) {
    const auto t0 = std::chrono::steady_clock::now();
    ik.solve(t, {true, true}, q, r);
    const auto t1 = std::chrono::steady_clock::now();
    s.us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    for (const ArmIkResult& a : r) {
      s.iterations += a.iterations;
      s.converged += a.status == ArmIkStatus::kConverged;
      s.clamped += a.workspace_clamped;
      s.collision_limited += a.collision_limited;
      s.ep_max = std::max(s.ep_max, a.position_error_m);
      s.eo_max = std::max(s.eo_max, a.orientation_error_rad);
      ++s.arms;
    }
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Arm IK solve time (both arms), p50/p99/max"};
  int ticks = 60000;
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string csv_path;
  app.add_option("--ticks", ticks, "ticks per scenario (100 Hz)")->check(CLI::Range(1000, 10000000));
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--csv", csv_path, "write the smooth stream's tracking per tick to this CSV");
  CLI11_PARSE(app, argc, argv);
  try {
    namespace streams = pmg::teleop::ik_streams;
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    ArmIk ik(robot);
    const auto n = static_cast<std::size_t>(ticks);
    std::mt19937 rng(2024);

    std::vector<T2> smooth(n), jumps(n), contact(n), far(n);
    for (std::size_t k = 0; k < n; ++k) smooth[k] = streams::armPoses(ik, streams::smoothArmTrajectory(ik, 0.01 * k));
    T2 jump_target{};
    for (std::size_t k = 0; k < n; ++k) {
      if (k % 50 == 0) jump_target = streams::armPoses(ik, streams::randomReachableConfig(ik, rng, 0.01));
      jumps[k] = jump_target;
    }
    // Contact: 2 s cycles: hands into the chest, then into each other's place, then back out.
    const T2 rest = streams::armPoses(ik, {ik.nominal(0), ik.nominal(1)});
    for (std::size_t k = 0; k < n; ++k) {
      T2 t = rest;
      const std::size_t phase = (k / 100) % 4;
      if (phase == 1) {
        t[0].position = Eigen::Vector3d(0.02, 0.0, 0.15);
        t[1].position = Eigen::Vector3d(0.02, 0.0, 0.10);
      } else if (phase == 2) {
        t[0].position = Eigen::Vector3d(0.30, -0.10, 0.10);
        t[1].position = Eigen::Vector3d(0.30, 0.10, 0.10);
      }
      contact[k] = t;
    }
    std::normal_distribution<double> g(0.0, 1.0);
    for (std::size_t k = 0; k < n; ++k) {
      for (int h = 0; h < 2; ++h) {
        far[k][h].position = ik.shoulderPosition(h) + 2.0 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        far[k][h].orientation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
      }
    }

    const Q2 start = streams::smoothArmTrajectory(ik, 0.0);
    const Q2 nominal{ik.nominal(0), ik.nominal(1)};
    std::printf(
        "pmg_arm_ik_bench: %d ticks per scenario, both arms per solve, ArmIkOptions defaults "
        "(max_iterations %d, max_joint_step %.3f rad)\n",
        ticks, ik.options().max_iterations, ik.options().max_joint_step);
    std::printf("%-9s %7s %7s %7s %7s %8s | %6s %6s %6s %6s | %9s %9s\n", "[us]", "p50", "p90", "p99", "p99.9", "max",
                "iter", "conv%", "clamp%", "coll%", "ep_max[m]", "eo_max");
    const std::array<const char*, 4> names{"smooth", "jumps", "contact", "far"};
    const std::array<const std::vector<T2>*, 4> sets{&smooth, &jumps, &contact, &far};
    for (int i = 0; i < 4; ++i) {
      const Stats s = run(ik, *sets[i], i == 0 ? start : nominal);
      std::printf("%-9s %7.2f %7.2f %7.2f %7.2f %8.1f | %6.2f %6.1f %6.1f %6.1f | %9.2g %9.2g\n", names[i],
                  pct(s.us, 50), pct(s.us, 90), pct(s.us, 99), pct(s.us, 99.9), pct(s.us, 100), s.iterations / s.arms,
                  100.0 * s.converged / s.arms, 100.0 * s.clamped / s.arms, 100.0 * s.collision_limited / s.arms,
                  s.ep_max, s.eo_max);
    }

    if (!csv_path.empty()) {
      std::ofstream out(csv_path);
      if (!out) throw std::runtime_error(csv_path + ": cannot open for writing");
      out << "t";
      for (int h = 0; h < 2; ++h) {
        const char* side = h == 0 ? "left" : "right";
        out << "," << side << "_ep," << side << "_eo," << side << "_iterations";
        for (const char* kind : {"q", "qstar", "qa"}) {
          for (int j = 0; j < kArmDofs; ++j) out << "," << side << "_" << kind << j;
        }
      }
      out << "\n";
      const std::size_t csv_ticks = std::min<std::size_t>(n, 2000);
      Q2 q{};
      R2 r;
      for (std::size_t k = 0; k < csv_ticks; ++k) {
        const Q2 q_a = streams::smoothArmTrajectory(ik, 0.01 * k);
        Q2 q_star;
        for (int h = 0; h < 2; ++h) {
          if (!streams::resolveRedundancy(ik, h, q_a[h], &q_star[h])) {
            throw std::runtime_error("tick " + std::to_string(k) + ": no redundancy-resolved reference");
          }
        }
        if (k == 0) q = q_star;
        ik.solve(smooth[k], {true, true}, q, r);
        out << 0.01 * static_cast<double>(k);
        for (int h = 0; h < 2; ++h) {
          out << "," << r[h].position_error_m << "," << r[h].orientation_error_rad << "," << r[h].iterations;
          for (const Q2* v : {static_cast<const Q2*>(&q), static_cast<const Q2*>(&q_star), &q_a}) {
            for (int j = 0; j < kArmDofs; ++j) out << "," << (*v)[h][j];
          }
        }
        out << "\n";
      }
      std::printf("wrote %s (%zu ticks)\n", csv_path.c_str(), csv_ticks);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_arm_ik_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
