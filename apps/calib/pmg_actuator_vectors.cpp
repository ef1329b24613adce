// pmg_actuator_vectors: runs pmg::calib::ActuatorModel::step (include/pmg/calib/actuator_model.hpp)
// over random parameter sets and random command / joint-sample sequences and writes inputs and
// outputs as JSON, for the NumPy/JAX port used in training (training/pmg_train/actuator.py) to prove
// equality (training/tests/test_actuator_port.py, ctest actuator_port_equals_cpp).
//
//   build/bin/pmg_actuator_vectors --out /tmp/actuator_vectors.json [--seed 1] [--cases 96] [--steps 240]
//
// Cases: the first has every effect off, the second every effect on; the others switch each effect
// on with probability 1/2 (transport delay as a fraction of physics steps, encoder offset, kt_scale,
// saturation, torque-speed envelope, Coulomb, Stribeck with fs above or below fc, load-dependent and
// viscous friction), driver rate 0 (every step), 200, 333, 500 or 1000 Hz, physics step 0.001,
// 0.002 or 0.005 s, and implicit stiction on (inertia > 0) or off. Sequences mix velocities that are
// exactly zero, tiny and large, gains that change (the delay line interpolates them), commands that
// are disabled for a few steps, and pure torque commands. Two long cases (more steps than the
// 512-entry delay line, delays up to 0.25 s) make the ring buffer wrap.
//
// JSON: {"generator", "seed", "max_delay_steps", "cases": [{"params": {ActuatorParams keys},
// "dt_s", "cmd": [[q_des, dq_des, kp, kd, tau_ff, enabled], ...], "joint": [[q, dq, inertia,
// tau_other], ...], "out": [[tau_motor, tau_friction, tau_applied, stuck, encoder], ...]}],
// "counts": {...}}. torque_limit_Nm = +inf is written as null. Units: SI (rad, rad/s, N m, s, Hz).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "pmg/calib/actuator_model.hpp"
#include "pmg/common/data_paths.hpp"

namespace {

using pmg::calib::ActuatorModel;
using pmg::calib::ActuatorOutput;
using pmg::calib::ActuatorParams;
using pmg::calib::ActuatorState;
using pmg::calib::JointSample;
using pmg::calib::MotorCommand;

struct Rng {
  std::mt19937_64 gen;
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  bool coin(double p = 0.5) { return uni(0.0, 1.0) < p; }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(gen); }
};

nlohmann::json paramsJson(const ActuatorParams& p) {
  nlohmann::json j;
  j["rate_hz"] = p.rate_hz;
  j["delay_s"] = p.delay_s;
  j["offset_rad"] = p.offset_rad;
  j["kt_scale"] = p.kt_scale;
  j["torque_limit_Nm"] = std::isfinite(p.torque_limit_Nm) ? nlohmann::json(p.torque_limit_Nm) : nlohmann::json();
  j["tau_stall_Nm"] = p.tau_stall_Nm;
  j["w_max_rad_per_s"] = p.w_max_rad_per_s;
  j["fc_Nm"] = p.fc_Nm;
  j["fs_Nm"] = p.fs_Nm;
  j["vs_rad_per_s"] = p.vs_rad_per_s;
  j["kl"] = p.kl;
  j["fv_Nms_per_rad"] = p.fv_Nms_per_rad;
  j["backlash_gap_rad"] = p.backlash_gap_rad;
  return j;
}

/// Random parameters: every effect on with probability @p p_on (all off for 0, all on for 1).
ActuatorParams drawParams(Rng& r, double dt, double p_on) {
  ActuatorParams p;
  const double rates[] = {0.0, 0.0, 200.0, 333.0, 500.0, 1000.0};
  p.rate_hz = rates[r.pick(6)];
  if (r.coin(p_on)) {
    // A fraction of steps (exact multiples sometimes), below the 0.25 s bound.
    const double steps = r.coin(0.2) ? static_cast<double>(1 + r.pick(8)) : r.uni(0.05, 12.0);
    p.delay_s = std::min(steps * dt, 0.25);
  }
  if (r.coin(p_on)) p.offset_rad = r.uni(-0.1, 0.1);
  if (r.coin(p_on)) p.kt_scale = r.uni(0.5, 1.5);
  if (r.coin(p_on)) p.torque_limit_Nm = r.uni(2.0, 40.0);
  if (r.coin(p_on)) {
    p.tau_stall_Nm = r.uni(5.0, 60.0);
    p.w_max_rad_per_s = r.uni(3.0, 20.0);
  }
  if (r.coin(p_on)) p.fc_Nm = r.uni(0.05, 2.0);
  if (r.coin(p_on)) {
    p.fs_Nm = p.fc_Nm * r.uni(0.5, 2.0) + r.uni(0.0, 0.5);  // above or below fc (the model takes the larger)
    p.vs_rad_per_s = r.uni(0.02, 0.5);
  }
  if (r.coin(p_on)) p.kl = r.uni(0.0, 0.3);
  if (r.coin(p_on)) p.fv_Nms_per_rad = r.uni(0.0, 0.5);
  p.validate();
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_actuator_vectors: ActuatorModel::step over random parameters and sequences, as JSON test "
               "vectors for the training port (training/pmg_train/actuator.py, training/tests/test_actuator_port.py)"};
  std::string out_path = "actuator_vectors.json";
  unsigned seed = 1;
  int n_cases = 96, n_steps = 240;
  app.add_option("--out", out_path, "JSON file to write")->capture_default_str();
  app.add_option("--seed", seed, "random seed")->capture_default_str();
  app.add_option("--cases", n_cases, "parameter sets (>= 4; the first all effects off, the second all on)")
      ->check(CLI::Range(4, 100000))
      ->capture_default_str();
  app.add_option("--steps", n_steps, "physics steps per case (two long cases run 700)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    pmg::requireWritableFile(out_path);
  } catch (const std::exception& e) {
    std::cerr << "pmg_actuator_vectors: " << e.what() << "\n";
    return 1;
  }

  Rng r{std::mt19937_64(seed)};
  nlohmann::json cases = nlohmann::json::array();
  long stuck = 0, kinetic_explicit = 0, saturated = 0, disabled = 0, held = 0, total = 0;
  const double dts[] = {0.001, 0.002, 0.005};
  for (int c = 0; c < n_cases; ++c) {
    const bool long_case = c == 2 || c == 3;
    const double dt = long_case ? 0.001 : dts[r.pick(3)];
    const double p_on = c == 0 ? 0.0 : (c == 1 ? 1.0 : 0.5);
    ActuatorParams p = drawParams(r, dt, p_on);
    if (long_case) p.delay_s = c == 2 ? 0.2375 : 0.25;  // 237.5 and 250 steps; the ring wraps after 512
    const int steps = long_case ? 700 : n_steps;
    const bool implicit = c == 1 || r.coin(0.75);
    const bool torque_mode = c > 3 && r.coin(0.1);   // pure torque commands (kp = kd = 0)
    ActuatorState st;
    st.reset();
    nlohmann::json cmd = nlohmann::json::array(), joint = nlohmann::json::array(), out = nlohmann::json::array();
    double q = r.uni(-1.0, 1.0), q_des = q, kp = torque_mode ? 0.0 : r.uni(0.0, 200.0);
    double kd = torque_mode ? 0.0 : r.uni(0.0, 5.0), inertia = implicit ? r.uni(0.005, 0.2) : 0.0;
    int off_for = 0;
    for (int k = 0; k < steps; ++k) {
      if (r.coin(0.05)) q_des = r.uni(-1.5, 1.5);             // steps in the target
      else q_des += r.uni(-0.01, 0.01);
      if (!torque_mode && r.coin(0.03)) kp = r.uni(0.0, 200.0);  // gains change: the delay line carries them
      if (!torque_mode && r.coin(0.03)) kd = r.uni(0.0, 5.0);
      if (off_for == 0 && r.coin(0.02)) off_for = 1 + r.pick(6);
      MotorCommand mc;
      mc.q_des_rad = q_des;
      mc.dq_des_rad_per_s = r.coin(0.3) ? 0.0 : r.uni(-2.0, 2.0);
      mc.kp_Nm_per_rad = kp;
      mc.kd_Nms_per_rad = kd;
      mc.tau_ff_Nm = torque_mode ? r.uni(-20.0, 20.0) : (r.coin(0.3) ? r.uni(-5.0, 5.0) : 0.0);
      mc.enabled = off_for == 0;
      if (off_for > 0) --off_for;
      JointSample js;
      const double mode = r.uni(0.0, 1.0);
      js.dq_rad_per_s = mode < 0.25 ? 0.0 : (mode < 0.5 ? r.uni(-1e-3, 1e-3) : r.uni(-5.0, 5.0));
      q += js.dq_rad_per_s * dt + r.uni(-1e-3, 1e-3);
      js.q_rad = q;
      js.inertia_kgm2 = inertia;
      js.tau_other_Nm = r.coin(0.5) ? r.uni(-0.5, 0.5) : r.uni(-10.0, 10.0);
      js.dt_s = dt;
      const ActuatorOutput o = ActuatorModel::step(p, st, mc, js);
      cmd.push_back({mc.q_des_rad, mc.dq_des_rad_per_s, mc.kp_Nm_per_rad, mc.kd_Nms_per_rad, mc.tau_ff_Nm,
                     mc.enabled ? 1 : 0});
      joint.push_back({js.q_rad, js.dq_rad_per_s, js.inertia_kgm2, js.tau_other_Nm});
      out.push_back({o.tau_motor_Nm, o.tau_friction_Nm, o.tau_applied_Nm, o.stuck ? 1 : 0,
                     ActuatorModel::encoder(p, js.q_rad)});
      ++total;
      if (o.stuck) ++stuck;
      if (!implicit && js.dq_rad_per_s != 0.0 && std::abs(o.tau_friction_Nm) > 0.0) ++kinetic_explicit;
      if (std::isfinite(p.torque_limit_Nm) && std::abs(std::abs(o.tau_motor_Nm) - p.torque_limit_Nm) < 1e-12)
        ++saturated;
      if (!mc.enabled) ++disabled;
      if (p.rate_hz > 0.0 && 1.0 / p.rate_hz > dt * 1.5) ++held;
    }
    cases.push_back({{"params", paramsJson(p)}, {"dt_s", dt}, {"cmd", cmd}, {"joint", joint}, {"out", out}});
  }
  nlohmann::json doc;
  doc["generator"] = "pmg_actuator_vectors";
  doc["seed"] = seed;
  doc["max_delay_steps"] = ActuatorState::kMaxDelaySteps;
  doc["cases"] = cases;
  doc["counts"] = {{"steps", total},
                   {"stuck", stuck},
                   {"kinetic_explicit", kinetic_explicit},
                   {"saturated", saturated},
                   {"disabled_commands", disabled},
                   {"zoh_steps", held}};
  std::ofstream f(out_path);
  f << doc.dump() << "\n";
  if (!f) {
    std::cerr << "pmg_actuator_vectors: " << out_path << ": cannot write\n";
    return 1;
  }
  std::cout << "wrote " << out_path << ": " << n_cases << " cases, " << total << " steps (stuck " << stuck
            << ", saturated " << saturated << ", disabled " << disabled << ")\n";
  return 0;
}
