// pmg_calib_joints: single-joint response calibration of the whole robot hanging in the gantry
// (issue 15; the PMG paper's "Sim-to-Real Transfer", eq. 20). Each joint in turn is excited
// (quasi-steps, a chirp; a held-out mixed log) while every other joint is held, through the
// product's HAL stack with its supervisor (makeHalStack). The robot is whatever the controller
// config's backend is: `can` reaches a robot (or `pmg_sil --reality`) over the motor bus only. The
// same excitation on the nominal simulator gives the bus latency and the gate (a joint the
// simulator already reproduces gets nothing named); every other joint is fitted in the whole-robot
// MuJoCo model (include/pmg/calib/joint_calibration.hpp, fitJointInRobot): catalogue entries on
// that joint's actuator, selected by cross-validation over the two training logs and judged
// against the encoder's noise floor; the held-out log reports the chosen model's error once.
//
//   pmg_calib_joints --config config/controller/g1_sil_can.yaml [--joints a,b,...]
//                    --out CALIBRATED_ROBOT.yaml --report REPORT.json [--plot DIR]
// The calibrated robot config is the input one with an `actuator:` block per joint where something
// was named, and absolute model paths.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
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

// The robot config text with `actuator:` blocks on the calibrated joints (flow-style joint lines, as
// the shipped configs have them) and its model paths absolute.
// Each calibrated joint also gets `actuator_uncertainty:` (RobotFitModel::uncertainty), from which
// training sizes its domain randomisation.
std::string calibratedRobotText(const pmg::RobotConfig& robot, const std::map<std::string, std::string>& blocks,
                                const std::map<std::string, std::string>& uncertainties) {
  std::string text = pmg::robotConfigTextWithModelPaths(robot);
  for (const auto& [joint, block] : blocks) {
    const std::regex line("(\\{\\s*name:\\s*" + joint + "\\s*,[^\\n]*?)(,\\s*actuator:\\s*\\{[^}]*\\})?"
                          "(,\\s*actuator_uncertainty:\\s*\\{[^}]*\\})?\\}");
    std::smatch m;
    if (!std::regex_search(text, m, line))
      throw pmg::ConfigError(robot.source_file + ": joint '" + joint +
                             "' is not a one-line flow map {name: ..., ...}: cannot insert its actuator block");
    const auto u = uncertainties.find(joint);
    text = m.prefix().str() + m[1].str() + ", actuator: " + block +
           (u == uncertainties.end() ? std::string() : ", actuator_uncertainty: " + u->second) + "}" + m.suffix().str();
  }
  return text;
}

// RMS residual [rad] over the two training logs (each log's mean difference removed).
double trainResidual(const pmg::calib::JointCapture& robot, const pmg::calib::JointCapture& sim) {
  const auto sse = pmg::calib::logSquaredErrors(robot, sim);
  return std::sqrt((sse[0].first + sse[1].first) / static_cast<double>(sse[0].second + sse[1].second));
}

// "key: value" per uncertainty, 4 significant digits (the flow map of `actuator_uncertainty:`).
std::vector<std::string> uncertaintyEntries(const std::map<std::string, double>& u) {
  std::vector<std::string> out;
  for (const auto& [key, v] : u) out.push_back(fmt::format("{}: {:.4g}", key, v));
  return out;
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
  std::string config_path, joints_csv, out_path, report_path, plot_dir;
  pmg::calib::JointExcitation ex;
  pmg::calib::RobotFitOptions fopt;
  app.add_option("--config", config_path, "controller config YAML (its robot and backend: can reaches the robot)")
      ->required()->check(CLI::ExistingFile);
  app.add_option("--joints", joints_csv, "comma-separated joint names (default: the 12 leg joints)");
  app.add_option("--out", out_path, "calibrated robot config YAML to write")->required();
  app.add_option("--report", report_path, "report JSON to write")->required();
  app.add_option("--plot", plot_dir, "folder for per-joint held-out traces (CSV) and plots (PNG)");
  app.add_option("--amplitude", ex.amplitude_rad, "excitation amplitude around the hold pose [rad]")->check(CLI::Range(0.01, 0.5));
  app.add_option("--threads", fopt.threads, "fit threads (one whole-robot simulator each)")->check(CLI::Range(1, 64));
  app.add_option("--max-causes", fopt.max_causes, "entries named per joint at most")->check(CLI::Range(0, 5));
  app.add_option("--min-cv-gain", fopt.min_cv_gain, "share by which an entry must lower the CV residual")->check(CLI::Range(0.01, 0.99));
  double gate_floor_multiple = 4.0, gate_min_rad = 3e-4;
  app.add_option("--gate-floor", gate_floor_multiple, "a joint is examined only if its robot-vs-simulator residual exceeds "
                                                      "this multiple of the noise floor ...")->check(CLI::Range(1.0, 100.0));
  app.add_option("--gate-min", gate_min_rad, "... and this [rad]")->check(CLI::Range(0.0, 0.1));
  CLI11_PARSE(app, argc, argv);
  try {
    const auto wall0 = std::chrono::steady_clock::now();
    pmg::requireWritableFile(out_path);
    pmg::requireWritableFile(report_path);
    const std::string plot_script = pmg::resolveData("scripts/plot_joint_calibration.py").string();
    const std::string report_tmp = report_path + ".plot.json";
    if (!plot_dir.empty()) std::filesystem::create_directories(plot_dir);
    fopt.validate();
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
    std::map<std::string, std::string> blocks, uncertainties;  // flow maps per calibrated joint
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
    // 3. Per joint: the gate (does the nominal simulator already reproduce it, on the training
    //    logs?), then the fit in the whole-robot model (pmg::calib::fitJointInRobot). The joints
    //    that misfit are fitted in order of their residual, largest first, each in the model that
    //    carries the blocks identified so far: a joint whose misfit only came from its neighbours'
    //    effects (a knee's friction shows in the hip pitch's response) is then explained by them.
    pmg::MujocoBackendOptions fit_opt = nominal_opt;
    std::vector<std::string> trace_files;
    std::vector<std::pair<double, std::size_t>> order;
    std::vector<double> residuals(idx.size()), gates(idx.size()), floors(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::string& name = robot.joints[static_cast<std::size_t>(idx[k])].name;
      residuals[k] = trainResidual(caps[k], refs[k]);
      floors[k] = pmg::calib::estimate_noise_floor(caps[k].train).floor_rad;
      gates[k] = std::max(gate_floor_multiple * floors[k], gate_min_rad);
      nlohmann::json j;
      j["simulator_residual_rad"] = residuals[k];
      j["gate_rad"] = gates[k];
      j["noise_floor_rad"] = floors[k];
      j["capture_s"] = caps[k].duration_s;
      j["causes"] = nlohmann::json::array();
      if (residuals[k] <= gates[k]) {
        j["verdict"] = "the nominal simulator reproduces this joint (training logs): nothing to name, not fitted";
        j["baseline"] = {{"train_rad", residuals[k]}};
        fmt::print("  {}: robot vs simulator residual {:.2g} rad <= gate {:.2g} rad: nothing to name\n", name, residuals[k], gates[k]);
      } else {
        order.emplace_back(residuals[k], k);
      }
      report["joints"][name] = j;
    }
    std::sort(order.begin(), order.end(), std::greater<>());
    pmg::RobotConfig model = nominal_robot;  // + the blocks identified so far
    for (const auto& [res0, k] : order) {
      const int i = idx[k];
      const std::string& name = robot.joints[static_cast<std::size_t>(i)].name;
      const pmg::calib::JointCapture& cap = caps[k];
      nlohmann::json& j = report["joints"][name];
      // Re-gate in the model with the other joints' identified blocks.
      if (!blocks.empty()) {
        pmg::calib::JointSimulator sim(model, fit_opt, bus_lag);
        const double r = trainResidual(cap, sim.capture(i, std::nullopt, ex, hold, false));
        j["residual_with_identified_neighbours_rad"] = r;
        if (r <= gates[k]) {
          j["verdict"] = "explained by the other joints' identified models (residual " + fmt::format("{:.2g}", r) +
                         " rad <= gate): nothing to name, not fitted";
          j["baseline"] = {{"train_rad", res0}};
          fmt::print("  {}: residual {:.2g} rad, {:.2g} rad with the identified neighbours <= gate {:.2g} rad: nothing to name\n",
                     name, res0, r, gates[k]);
          std::fflush(stdout);
          continue;
        }
      }
      const pmg::calib::RobotFitResult fit =
          pmg::calib::fitJointInRobot(model, fit_opt, bus_lag, i, cap, ex, hold, floors[k], fopt);
      auto modelJson = [](const pmg::calib::RobotFitModel& m) {
        nlohmann::json o = {{"name", m.name}, {"params", m.params}, {"cv_rad", m.cv_rad}, {"gain", m.gain}, {"verdict", m.verdict}};
        if (!m.uncertainty.empty()) o["uncertainty"] = m.uncertainty;
        if (m.heldout_rad >= 0) o["heldout_rad"] = m.heldout_rad;
        return o;
      };
      j["baseline"] = modelJson(fit.baseline);
      j["baseline"]["train_rad"] = res0;
      for (const auto& c : fit.causes) j["causes"].push_back(modelJson(c));
      j["extended"] = modelJson(fit.extended);
      j["candidates"] = nlohmann::json::array();
      for (const auto& c : fit.candidates) j["candidates"].push_back(modelJson(c));
      j["evaluations"] = fit.evaluations;
      j["fit_wall_s"] = fit.wall_s;
      j["verdict"] = fit.causes.empty() ? "the simulator misses this joint's response, but no catalogue entry explains it "
                                          "significantly (see candidates)"
                                        : "named: the entries that make the whole-robot model reproduce the response";
      if (!fit.causes.empty()) {
        blocks[name] = flowBlock(fit.block);
        uncertainties[name] = fmt::format("{{{}}}", fmt::join(uncertaintyEntries(fit.extended.uncertainty), ", "));
        model.joints[static_cast<std::size_t>(i)].actuator_yaml = blocks[name];
        model.joints[static_cast<std::size_t>(i)].actuator_source = "pmg_calib_joints: " + name;
      }
      std::string causes;
      for (const auto& c : fit.causes) {
        std::string ps;
        for (const auto& [key, v] : c.params) ps += fmt::format("{}{} {:.4g}", ps.empty() ? "" : ", ", key, v);
        causes += fmt::format("{}{} ({}; CV gain {:.2f})", causes.empty() ? "" : "; ", c.name, ps, c.gain);
      }
      fmt::print("  {}: residual {:.2g} rad (gate {:.2g}); CV {:.2g} -> {:.2g} rad, held-out {:.2g} -> {:.2g} rad; named: {}; "
                 "{} captures simulated in {:.1f} s\n",
                 name, res0, gates[k], fit.baseline.cv_rad, fit.extended.cv_rad, fit.baseline.heldout_rad,
                 fit.extended.heldout_rad, causes.empty() ? "nothing" : causes, fit.evaluations, fit.wall_s);
      std::fflush(stdout);
    }
    // Held-out traces of every fitted joint: robot, nominal simulator, calibrated simulator (the
    // model with every identified block).
    if (!plot_dir.empty()) {
      for (const auto& [res0, k] : order) {
        const int i = idx[k];
        const std::string& name = robot.joints[static_cast<std::size_t>(i)].name;
        // The model carries joint i's identified block (if any): capture with it, once.
        const auto it = blocks.find(name);
        pmg::calib::JointSimulator sim(model, fit_opt, bus_lag);
        const pmg::calib::JointCapture cal2 = sim.capture(
            i, it == blocks.end() ? std::nullopt
                                  : std::optional<pmg::calib::ActuatorBlock>(
                                        pmg::calib::parse_actuator_block(YAML::Load(it->second), name)),
            ex, hold);
        const std::string csv = (std::filesystem::path(plot_dir) / (name + "_heldout.csv")).string();
        std::ofstream f(csv);
        f << "t,q_cmd,q_robot,q_nominal,q_calibrated\n";
        const auto& a = caps[k].heldout[0];
        const auto& b = refs[k].heldout[0];
        const auto& c = cal2.heldout[0];
        for (std::size_t r = 0; r < std::min({a.q.size(), b.q.size(), c.q.size()}); ++r)
          f << fmt::format("{:.4f},{:.6f},{:.6f},{:.6f},{:.6f}\n", a.t[r], a.q_cmd[r], a.q[r], b.q[r], c.q[r]);
        trace_files.push_back(csv);
      }
    }
    if (!plot_dir.empty() && !trace_files.empty()) {
      const std::string png = (std::filesystem::path(plot_dir) / "joint_calibration.png").string();
      std::string cmd = fmt::format("python3 {} --report {} --out {}", shellQuote(plot_script), shellQuote(report_tmp), shellQuote(png));
      for (const auto& t : trace_files) cmd += " " + shellQuote(t);
      {
        std::ofstream out(report_tmp);
        out << report.dump(1) << "\n";
      }
      if (std::system(cmd.c_str()) != 0) throw std::runtime_error("plot failed: " + cmd);
      std::filesystem::remove(report_tmp);
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
          << calibratedRobotText(robot, blocks, uncertainties);
    }
    fmt::print("pmg_calib_joints: {} joints, {:.1f} s on the robot, {:.1f} s wall; report {}, calibrated config {}\n",
               idx.size(), robot_time, wall, report_path, out_path);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_calib_joints: %s\n", e.what());
    return 1;
  }
}
