// pmg_calib_joints: single-joint response calibration of the whole robot hanging in the gantry
// (issue 15; the PMG paper's "Sim-to-Real Transfer"). Each joint in turn is excited (quasi-steps,
// a chirp; a held-out mixed log) while every other joint is held, through the product's HAL stack
// with its supervisor (makeHalStack). The robot is whatever the controller config's backend is:
// `can` reaches a robot (or `pmg_sil --reality`) over the motor bus only. Each joint is then fitted
// as the pendulum the whole-robot MuJoCo model reduces to with the others locked at their measured
// positions (include/pmg/calib/joint_calibration.hpp), by pmg_calib_dynamics' engine: baseline
// kp/kd/armature, then the catalogue's causes selected by cross-validation on the training logs and
// judged against the noise floor; held-out error reported once.
//
//   pmg_calib_joints --config config/controller/g1_sil_can.yaml [--joints a,b,...]
//                    --out CALIBRATED_ROBOT.yaml --report REPORT.json [--plot DIR]
// The calibrated robot config is the input one with an `actuator:` block per calibrated joint (the
// extended model's parameters) and absolute model paths.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/calib/joint_calibration.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/hal/hal_stack.hpp"

namespace {

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw pmg::ConfigError(path + ": cannot read");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The robot config text with `actuator:` blocks on the calibrated joints (flow-style joint lines, as
// the shipped configs have them) and its model paths absolute.
std::string calibratedRobotText(const pmg::RobotConfig& robot, const std::map<std::string, std::string>& blocks) {
  std::string text = readText(robot.source_file);
  const std::string dir = std::filesystem::path(robot.source_file).parent_path().string();
  for (const char* key : {"urdf", "mjcf"}) {
    const std::regex re(std::string("(\\n\\s*") + key + ":\\s*)([^\\s#]+)");
    std::smatch m;
    if (std::regex_search(text, m, re) && !std::filesystem::path(m[2].str()).is_absolute())
      text = m.prefix().str() + m[1].str() + (std::filesystem::path(dir) / m[2].str()).lexically_normal().string() +
             m.suffix().str();
  }
  for (const auto& [joint, block] : blocks) {
    const std::regex line("(\\{\\s*name:\\s*" + joint + "\\s*,[^\\n]*?)(,\\s*actuator:\\s*\\{[^}]*\\})?\\}");
    std::smatch m;
    if (!std::regex_search(text, m, line))
      throw pmg::ConfigError(robot.source_file + ": joint '" + joint +
                             "' is not a one-line flow map {name: ..., ...}: cannot insert its actuator block");
    text = m.prefix().str() + m[1].str() + ", actuator: " + block + "}" + m.suffix().str();
  }
  return text;
}

std::string flowBlock(const pmg::calib::ActuatorBlock& b) {
  YAML::Emitter em;
  em.SetDoublePrecision(6);
  YAML::Node n = pmg::calib::actuator_block_to_yaml(b);
  em << YAML::Flow << n;
  return em.c_str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_calib_joints: single-joint response calibration of the whole robot in the gantry"};
  std::string config_path, joints_csv, out_path, report_path, plot_dir, optimizer = "bobyqa";
  pmg::calib::JointExcitation ex;
  pmg::calib::CalibrationOptions opt;
  app.add_option("--config", config_path, "controller config YAML (its robot and backend: can reaches the robot)")
      ->required()->check(CLI::ExistingFile);
  app.add_option("--joints", joints_csv, "comma-separated joint names (default: the 12 leg joints)");
  app.add_option("--out", out_path, "calibrated robot config YAML to write")->required();
  app.add_option("--report", report_path, "report JSON to write")->required();
  app.add_option("--plot", plot_dir, "folder for per-joint held-out traces (CSV) and plots (PNG)");
  app.add_option("--amplitude", ex.amplitude_rad, "excitation amplitude around the hold pose [rad]")->check(CLI::Range(0.01, 0.5));
  app.add_option("--threads", opt.threads, "fit threads (0 = all cores)")->check(CLI::Range(0, 256));
  app.add_option("--optimizer", optimizer, "bobyqa | cmaes | cmaes-pagmo");
  double gate_floor_multiple = 4.0, gate_min_rad = 3e-4;
  app.add_option("--gate-floor", gate_floor_multiple, "a joint is examined only if its robot-vs-simulator residual exceeds "
                                                      "this multiple of the noise floor ...")->check(CLI::Range(1.0, 100.0));
  app.add_option("--gate-min", gate_min_rad, "... and this [rad]")->check(CLI::Range(0.0, 0.1));
  CLI11_PARSE(app, argc, argv);
  try {
    const auto wall0 = std::chrono::steady_clock::now();
    pmg::requireWritableFile(out_path);
    pmg::requireWritableFile(report_path);
    const std::string plot_script = pmg::resolveData("scripts/calib_plot.py").string();
    if (!plot_dir.empty()) std::filesystem::create_directories(plot_dir);
    opt.optimizer = pmg::calib::parse_optimizer(optimizer);
    opt.validate();
    const pmg::ControllerConfig cc = pmg::loadControllerConfig(config_path);
    const pmg::RobotConfig& robot = cc.robot;
    std::vector<int> idx;
    if (joints_csv.empty()) {
      for (int i = 0; i < 12; ++i) idx.push_back(i);
    } else {
      std::stringstream ss(joints_csv);
      std::string name;
      while (std::getline(ss, name, ',')) {
        int found = -1;
        for (std::size_t i = 0; i < robot.numJoints(); ++i)
          if (robot.joints[i].name == name) found = static_cast<int>(i);
        if (found < 0) throw pmg::ConfigError("--joints: '" + name + "' is not a joint of " + robot.source_file);
        idx.push_back(found);
      }
    }
    // The motors move only through the product's safety stack, engaged through soft stand.
    pmg::HalStackConfig hs = cc.halStack();
    std::unique_ptr<pmg::HalBackend> device;
    if (cc.backend == pmg::BackendKind::kCan) {
      device = pmg::makeCanBackendFor(hs);
    } else {
      pmg::MujocoBackendOptions bo = cc.mujoco;
      bo.gantry.enabled = true;  // hanging, as on the robot
      device = std::make_unique<pmg::MujocoBackend>(robot, bo);
    }
    pmg::HalStack stack = pmg::makeHalStack(robot, hs, std::move(device));
    pmg::engageActive(stack, robot);
    // The control experiment: the same excitation on the nominal simulator (the SIL's MuJoCo model
    // in the gantry, no hidden effects), calibrated the same way; the verdict is the difference
    // (pmg::calib::differentialEffects).
    pmg::MujocoBackendOptions nominal_opt = cc.mujoco;
    nominal_opt.gantry.enabled = true;
    nominal_opt.encoder_offsets.clear();
    pmg::RobotConfig nominal_robot = robot;
    for (auto& j : nominal_robot.joints) j.actuator_yaml.clear();
    pmg::MujocoBackend nominal_sim(nominal_robot, nominal_opt);
    const Eigen::VectorXd hold = robot.defaultPose();
    nlohmann::json report;
    report["config"] = config_path;
    report["excitation"] = {{"amplitude_rad", ex.amplitude_rad}, {"ramp_s", ex.ramp_s}, {"hold_s", ex.hold_s}, {"chirp_s", ex.chirp_s}};
    std::map<std::string, std::string> blocks;
    double robot_time = 0.0;
    // 1. Capture every joint on the robot, then the same on the nominal simulator.
    std::vector<pmg::calib::JointCapture> caps, refs;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      fmt::print("[{}/{}] {}: capture\n", k + 1, idx.size(), robot.joints[static_cast<std::size_t>(idx[k])].name);
      std::fflush(stdout);
      caps.push_back(pmg::calib::captureJoint(*stack.backend, robot, idx[k], ex, hold, [](const std::string& s) { fmt::print("{}\n", s); }));
      robot_time += caps.back().duration_s;
    }
    // 2. The bus latency: whole cycles by which the robot's responses lag the simulator's, the most
    //    common lag over the joints (most joints carry no effect of their own; one that does can
    //    look faster or slower). The simulator is then given that latency, so that it stays out of
    //    every joint's verdict.
    std::map<int, int> lag_votes;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      nominal_sim.reset();
      const pmg::calib::JointCapture ref0 = pmg::calib::captureJoint(nominal_sim, nominal_robot, idx[k], ex, hold, {});
      ++lag_votes[pmg::calib::responseLagCycles(caps[k], ref0)];
    }
    int bus_lag = 0, votes = -1;
    for (const auto& [lag, v] : lag_votes)
      if (v > votes) bus_lag = lag, votes = v;
    fmt::print("bus latency: {} HAL cycle(s) = {:.1f} ms (the lag of {} of {} joints' responses behind the simulator's)\n",
               bus_lag, 1e3 * bus_lag * nominal_sim.cyclePeriod(), votes, idx.size());
    report["bus_latency_cycles"] = bus_lag;
    report["bus_latency_s"] = bus_lag * nominal_sim.cyclePeriod();
    pmg::calib::CommandLatencyBackend lagged_sim(nominal_sim, bus_lag);
    for (std::size_t k = 0; k < idx.size(); ++k) {
      nominal_sim.reset();
      lagged_sim.clear();
      refs.push_back(pmg::calib::captureJoint(lagged_sim, nominal_robot, idx[k], ex, hold, {}));
    }
    // 3. Fit each joint on both, and take the difference.
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const int i = idx[k];
      const std::string& name = robot.joints[static_cast<std::size_t>(i)].name;
      const pmg::calib::JointCapture& cap = caps[k];
      const pmg::calib::JointCapture& ref = refs[k];
      const pmg::calib::JointRig jr = pmg::calib::rigForJoint(robot, i, cap.held_q);
      auto rigLogs = [&](const std::vector<pmg::calib::BenchLog>& in) {
        std::vector<pmg::calib::BenchLog> out;
        for (const auto& l : in) out.push_back(pmg::calib::toRigFrame(l, jr.q_down_rad));
        return out;
      };
      // The gate first: a joint whose response the simulator reproduces to within the noise gets
      // nothing named and is not fitted (its nominal model is right).
      const double residual = pmg::calib::simulationResidual(cap, ref);
      const pmg::calib::NoiseFloor floor = pmg::calib::estimate_noise_floor(rigLogs(cap.train));
      const double gate = std::max(gate_floor_multiple * floor.floor_rad, gate_min_rad);
      if (residual <= gate) {
        report["joints"][name] = {{"simulator_residual_rad", residual}, {"gate_rad", gate}, {"noise_floor_rad", floor.floor_rad},
                                  {"effects", nlohmann::json::array()}, {"capture_s", cap.duration_s},
                                  {"verdict", "the nominal simulator reproduces this joint: nothing to name, not fitted"}};
        fmt::print("  {}: robot vs simulator residual {:.2g} rad <= gate {:.2g} rad: nothing to name\n", name, residual, gate);
        std::fflush(stdout);
        continue;
      }
      const pmg::calib::CalibrationReport sim = pmg::calib::calibrate_dynamics(jr.rig, rigLogs(ref.train), rigLogs(ref.heldout), opt);
      const pmg::calib::CalibrationReport rep = pmg::calib::calibrate_dynamics(jr.rig, rigLogs(cap.train), rigLogs(cap.heldout), opt);
      auto causeList = [](const pmg::calib::CalibrationReport& r) {
        std::vector<std::pair<std::string, std::map<std::string, double>>> out;
        for (const auto& c : r.causes) out.emplace_back(c.name, c.params);
        return out;
      };
      std::vector<double> gains;
      for (const auto& c : rep.causes) gains.push_back(c.gain);
      const std::vector<pmg::calib::JointEffect> effects = pmg::calib::differentialEffects(
          jr.rig, sim.baseline.params, causeList(sim), rep.baseline.params, causeList(rep), gains);
      nlohmann::json j = nlohmann::json::parse(pmg::calib::report_to_json(rep));
      j["rig"] = {{"mass_kg", jr.rig.mass_kg},         {"com_m", jr.rig.com_m},
                  {"link_inertia_kgm2", jr.rig.link_inertia_kgm2}, {"inertia_free_kgm2", jr.inertia_kgm2},
                  {"inertia_locked_kgm2", jr.inertia_locked_kgm2},
                  {"gravity_amplitude_Nm", jr.gravity_amplitude_Nm}, {"q_down_rad", jr.q_down_rad},
                  {"gravity_fit_residual_Nm", jr.fit_residual_Nm}, {"armature_nominal_kgm2", jr.rig.armature_kgm2},
                  {"rate_hz", jr.rig.rate_hz}};
      j["capture_s"] = cap.duration_s;
      nlohmann::json simj = nlohmann::json::parse(pmg::calib::report_to_json(sim));
      j["simulator"] = {{"baseline", simj["baseline"]}, {"causes", simj["causes"]}};
      nlohmann::json ej = nlohmann::json::array();
      for (const auto& e : effects) ej.push_back({{"name", e.name}, {"params", e.params}, {"size", e.size}});
      j["effects"] = ej;
      j["simulator_residual_rad"] = residual;
      j["gate_rad"] = gate;
      j["verdict"] = effects.empty() ? "the simulator misses this joint's response, but no catalogue entry explains the difference"
                                     : "named: what the robot's fit has and the simulator's has not";
      report["joints"][name] = j;
      blocks[name] = flowBlock(pmg::calib::effectsBlock(jr.rig, sim.baseline.params, rep.baseline.params, effects));
      std::string causes;
      for (const auto& e : effects) causes += fmt::format("{}{} ({:.3g})", causes.empty() ? "" : ", ", e.name, e.size);
      std::string sim_causes;
      for (const auto& c : sim.causes) sim_causes += (sim_causes.empty() ? "" : ", ") + c.name;
      fmt::print("  {}: robot vs simulator residual {:.2g} rad (gate {:.2g}); simulator's own fit names: {}\n", name, residual,
                 gate, sim_causes.empty() ? "none" : sim_causes);
      fmt::print("  {}: baseline held-out RMSE {:.5f} rad, extended {:.5f} rad; noise floor {:.2g} rad; effects: {}; fit {:.1f} s\n",
                 name, rep.baseline.heldout_rmse_rad, rep.extended.heldout_rmse_rad, rep.noise.floor_rad,
                 causes.empty() ? "none" : causes, rep.wall_time_s);
      std::fflush(stdout);
      if (!plot_dir.empty()) {
        const std::string traces = (std::filesystem::path(plot_dir) / (name + "_heldout.csv")).string();
        const std::string jreport = (std::filesystem::path(plot_dir) / (name + "_report.json")).string();
        pmg::calib::write_trace_csv(jr.rig, rigLogs(cap.heldout), rep, traces);
        // The raw captures, robot and nominal simulator side by side (pmg CSV bench logs).
        for (const auto& [who, logs] : {std::pair{std::string("robot"), &cap}, std::pair{std::string("simulator"), &ref}}) {
          std::vector<pmg::calib::BenchLog> all = logs->train;
          all.insert(all.end(), logs->heldout.begin(), logs->heldout.end());
          for (const auto& l : all) {
            const std::string tag = l.name.substr(l.name.find(':') + 1);
            pmg::calib::write_bench_log_csv(l, (std::filesystem::path(plot_dir) / (name + "_" + who + "_" + tag + ".csv")).string());
          }
        }
        std::ofstream(jreport) << pmg::calib::report_to_json(rep);
        const std::string png = (std::filesystem::path(plot_dir) / (name + ".png")).string();
        const std::string cmd = fmt::format("python3 {} --report {} --traces {} --out {}", shellQuote(plot_script),
                                            shellQuote(jreport), shellQuote(traces), shellQuote(png));
        if (std::system(cmd.c_str()) != 0) throw std::runtime_error("plot failed: " + cmd);
      }
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    report["robot_time_s"] = robot_time;
    report["wall_time_s"] = wall;
    {
      std::ofstream out(report_path);
      if (!out) throw std::runtime_error(report_path + ": cannot write");
      out << report.dump(1) << "\n";
    }
    {
      std::ofstream out(out_path);
      if (!out) throw std::runtime_error(out_path + ": cannot write");
      out << "# Calibrated by pmg_calib_joints from " << config_path << " (report " << report_path << ")\n"
          << calibratedRobotText(robot, blocks);
    }
    fmt::print("pmg_calib_joints: {} joints, {:.1f} s on the robot, {:.1f} s wall; report {}, calibrated config {}\n",
               idx.size(), robot_time, wall, report_path, out_path);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_calib_joints: %s\n", e.what());
    return 1;
  }
}
