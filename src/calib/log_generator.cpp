#include "pmg/calib/log_generator.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "pmg/calib/dynamics_calibration.hpp"

namespace pmg::calib {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Smooth 0 -> 1 over [0, 1].
double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

double command(Trajectory tr, double t, double t_motion, double amp) {
  switch (tr) {
    case Trajectory::kSines:
      return amp * (0.65 * std::sin(2 * kPi * 0.45 * t) + 0.35 * std::sin(2 * kPi * 1.3 * t)) * smoothstep(t / 0.5);
    case Trajectory::kStepsHolds: {
      // Ramps between holds; ramp durations alternate fast/slow.
      static const double targets[] = {0.0, 0.7, 0.7, -0.5, -0.5, 0.2, 0.2, -0.8, -0.8, 0.4, 0.4, 0.0};
      static const double durations[] = {0.3, 0.25, 0.5, 0.6, 0.4, 0.15, 0.5, 0.35, 0.6, 0.2, 0.5, 0.3};
      double total = 0.0;
      for (double d : durations) total += d;
      const double scale = t_motion / total;
      double t0 = 0.0;
      double prev = 0.0;
      for (int k = 0; k < 12; ++k) {
        const double d = durations[k] * scale;
        if (t < t0 + d) return amp * (prev + (targets[k] - prev) * smoothstep((t - t0) / d));
        prev = targets[k];
        t0 += d;
      }
      return amp * prev;
    }
    case Trajectory::kChirp: {
      const double f0 = 0.2, f1 = 2.5, T = std::max(t_motion, 1e-3);
      const double phase = 2 * kPi * (f0 * t + 0.5 * (f1 - f0) / T * t * t);
      return amp * (0.4 + 0.6 * t / T) * 0.7 * std::sin(phase);
    }
  }
  return 0.0;
}

}  // namespace

void SyntheticLogOptions::validate() const {
  auto chk = [](bool ok, const char* f, double v, const char* r) {
    if (!ok) throw std::invalid_argument(fmt::format("SyntheticLogOptions.{} = {}: expected {}", f, v, r));
  };
  chk(duration_s > 2.0 && duration_s < 3600.0, "duration_s", duration_s, "in (2, 3600) s");
  chk(log_rate_hz >= 20.0 && log_rate_hz <= 2000.0, "log_rate_hz", log_rate_hz, "in [20, 2000] Hz");
  chk(amplitude_rad > 0.0 && amplitude_rad <= 2.0, "amplitude_rad", amplitude_rad, "in (0, 2] rad");
  chk(kp_log >= 0.0, "kp_log", kp_log, ">= 0");
  chk(kd_log >= 0.0, "kd_log", kd_log, ">= 0");
  chk(tau_ff_Nm >= 0.0 && std::isfinite(tau_ff_Nm), "tau_ff_Nm", tau_ff_Nm, ">= 0 N·m");
  chk(noise_rad >= 0.0, "noise_rad", noise_rad, ">= 0 rad");
  chk(quantum_rad >= 0.0, "quantum_rad", quantum_rad, ">= 0 rad");
}

BenchLog generate_bench_log(const RigConfig& rig, const RigParams& truth, const SyntheticLogOptions& o) {
  o.validate();
  truth.act.validate();
  const std::size_t n = static_cast<std::size_t>(o.duration_s * o.log_rate_hz) + 1;
  // Motion for 70 % of the log (at most up to 4 s before the end), then lift to +1 rad and switch
  // the torque off for the free swing (at most ~3 s of it).
  const double t_lift = std::max(0.7 * o.duration_s, o.duration_s - 4.0);
  const double t_off = t_lift + std::min(0.1 * o.duration_s, 1.0);
  BenchLog log;
  log.name = "synthetic";
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  double q_end = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / o.log_rate_hz;
    double c;
    if (t < t_lift) {
      c = command(o.trajectory, t, t_lift, o.amplitude_rad);
      q_end = c;
    } else {
      c = q_end + (1.0 - q_end) * smoothstep((t - t_lift) / (0.6 * (t_off - t_lift)));
    }
    log.t.push_back(t);
    log.enabled.push_back(t < t_off ? 1 : 0);
    if (o.tau_ff_Nm > 0.0) {
      // Torque control: the shape becomes the feed-forward torque, ramped out before torque-off.
      log.q_cmd.push_back(0.0);
      log.kp.push_back(0.0);
      log.kd.push_back(0.0);
      const double shape = t < t_lift ? command(o.trajectory, t, t_lift, o.amplitude_rad) / o.amplitude_rad : 0.0;
      log.tau_ff.push_back(o.tau_ff_Nm * shape);
      continue;
    }
    log.q_cmd.push_back(c);
    if (o.kp_log > 0.0) log.kp.push_back(o.kp_log);
    if (o.kd_log > 0.0) log.kd.push_back(o.kd_log);
  }
  log.q.assign(n, 0.0);
  log.q[0] = log.q_cmd[0] + truth.act.offset_rad;  // starts at rest on the command, encoder offset
  log.dq.assign(n, 0.0);
  BenchSimulator sim(rig, truth.act.backlash_gap_rad > 0.0);
  RolloutTrace tr;
  const double sse = sim.rollout(log, truth, &tr);
  if (!std::isfinite(sse)) throw std::runtime_error("generate_bench_log: the true-parameter simulation diverged");
  for (std::size_t i = 0; i < n; ++i) {
    double q = tr.q[i] + o.noise_rad * noise(rng);
    if (o.quantum_rad > 0.0) q = o.quantum_rad * std::round(q / o.quantum_rad);
    log.q[i] = q;
    log.dq[i] = tr.dq[i] + 20.0 * o.noise_rad * noise(rng);
  }
  log.dq[0] = 0.0;
  log.validate();
  return log;
}

HiddenEffect draw_hidden_effect(const std::string& name, std::uint64_t seed, const RigConfig& rig, RigParams& truth) {
  std::mt19937_64 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  HiddenEffect h;
  h.name = name;
  ActuatorParams& a = truth.act;
  a.rate_hz = rig.rate_hz;
  a.torque_limit_Nm = rig.torque_limit_Nm;
  if (name.empty()) {
  } else if (name == "coulomb_friction") {
    a.fc_Nm = U(0.04, 0.1);
    h.params = {{"fc_Nm", a.fc_Nm}};
  } else if (name == "viscous_friction") {
    a.fv_Nms_per_rad = U(0.03, 0.08);
    h.params = {{"fv_Nms_per_rad", a.fv_Nms_per_rad}};
  } else if (name == "stribeck_friction") {
    a.fc_Nm = U(0.03, 0.05);
    a.fs_Nm = a.fc_Nm * U(3.0, 4.0);
    a.vs_rad_per_s = U(0.1, 0.25);
    h.params = {{"fc_Nm", a.fc_Nm}, {"fs_Nm", a.fs_Nm}, {"vs_rad_per_s", a.vs_rad_per_s}};
  } else if (name == "load_dependent_friction") {
    a.fc_Nm = 0.005;
    a.kl = U(0.15, 0.3);
    h.params = {{"fc_Nm", a.fc_Nm}, {"kl", a.kl}};
  } else if (name == "backlash") {
    a.backlash_gap_rad = U(0.02, 0.05);
    h.params = {{"gap_rad", a.backlash_gap_rad}};
  } else if (name == "transport_delay") {
    a.delay_s = U(0.015, 0.04);
    h.params = {{"delay_s", a.delay_s}};
  } else if (name == "torque_saturation") {
    a.torque_limit_Nm = U(0.55, 0.7);
    h.params = {{"tau_max_Nm", a.torque_limit_Nm}};
  } else if (name == "torque_speed_limit") {
    a.tau_stall_Nm = U(0.9, 1.2);
    a.w_max_rad_per_s = U(3.0, 5.0);
    h.params = {{"tau_stall_Nm", a.tau_stall_Nm}, {"w_max_rad_per_s", a.w_max_rad_per_s}};
  } else if (name == "torque_constant") {
    a.kt_scale = U(0.7, 0.9);
    h.params = {{"kt_scale", a.kt_scale}};
  } else if (name == "zero_offset") {
    a.offset_rad = U(0.02, 0.05) * (U(0.0, 1.0) < 0.5 ? -1.0 : 1.0);
    h.params = {{"offset_rad", a.offset_rad}};
  } else {
    throw std::invalid_argument("draw_hidden_effect: unknown catalogue entry '" + name + "'");
  }
  return h;
}

RigParams make_rig_truth(const RigConfig& rig, double kp_scale, double kd_scale, double armature_kgm2) {
  RigParams t;
  t.kp_scale = kp_scale;
  t.kd_scale = kd_scale;
  t.armature_kgm2 = armature_kgm2;
  t.act.torque_limit_Nm = rig.torque_limit_Nm;
  t.act.rate_hz = rig.rate_hz;
  return t;
}

RigConfig make_test_rig(double sim_dt_s) {
  RigConfig r;
  r.source_file = "make_test_rig()";
  r.mass_kg = 0.5;
  r.com_m = 0.1;
  r.link_inertia_kgm2 = 2e-4;
  r.gravity_mps2 = 9.81;
  r.kp_Nm_per_rad = 4.0;
  r.kd_Nms_per_rad = 0.08;
  r.armature_kgm2 = 0.004;
  r.torque_limit_Nm = 1.5;
  r.rate_hz = 500.0;
  r.sim_dt_s = sim_dt_s;
  r.validate();
  return r;
}

}  // namespace pmg::calib
