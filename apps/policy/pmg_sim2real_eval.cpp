// pmg_sim2real_eval: the sim-to-real evaluation of the PMG paper (section "Sim-to-Real Evaluation",
// Table II) in the SIL, where the "real robot" is the MuJoCo 2.2 SIL playing a hidden reality
// (include/pmg/hal/reality.hpp; pmg_reality_draw draws plausible ones).
//
//   pmg_sim2real_eval --policies Baseline=config/controller/g1_sil_policy_consistent.yaml[,NAME=CONTROLLER.yaml...]
//                     --realities R1.yaml,R2.yaml,... [--commands config/policies/eval_sim2real.yaml] --out DIR
//
// A policy is a controller config (its `robot:` is the policy's robot config: PD gains, calibrated
// `actuator:` blocks and `zero_offsets:`; its `policy.model` the actor). Every rollout is the
// product path, built by pmg::makeSilRun (pmg/controller/sil_eval.hpp, shared with pmg_policy_sil):
// one pmg::ControllerApp from the controller config -- the same HAL stack (zero offsets,
// supervisor), shaper, reference limiter, generator + GCO, policy stage and runner as
// pmg_controller -- over an in-process SIL, the script injected as pmg_controller --script does.
// Lockstep and deterministic: seed 0 (no initial perturbation), no sensor noise.
//
// Per policy, two kinds of rollout on the same command script:
//   simulator  the policy's own simulator: the SIL of its robot config, so a calibrated robot
//              config's `actuator:` blocks are applied, and its encoders read the config's
//              `zero_offsets` (which the HAL's ZeroOffsetBackend removes again: the simulated
//              robot has the offsets its config believes in). Once per policy.
//   real       the "real robot": the robot config without its `actuator:` blocks and zero offsets
//              (or --real-robot) plus the reality (pmg::hal::applyReality: the reality's actuator
//              blocks per joint, its zero offsets as hidden encoder offsets of the SIL, its link
//              mass errors). The controller still runs on the policy's robot config, so its
//              `zero_offsets:` are subtracted from the (offset) encoder readings. Once per reality.
//
// Metrics (RMS over the ticks at t >= --skip (1 s) and over the 12 leg joints, [rad]; the joint
// angles are simulator truth, not encoder readings):
//   Motion Imitation Error  q_real - q_ref, q_ref the PMG reference the controller gives the actor
//                           (Controller::reference(), after the reference rate limiter), on the
//                           ticks where the supervisor is active;
//   Sim-to-Real Error       q_real - q_sim at the same tick of the two rollouts.
// (per_reality also has motion_imitation_error_measured_rad: the same with the joint angles the
// controller measures -- encoder readings minus the robot config's zero_offsets --, what a hardware
// log shows; it cannot see an uncalibrated zero offset.)
// A rollout that falls (pmg::silRobotFell) ends at the fall; the metrics cover the ticks before it
// (for Sim-to-Real Error, those of both rollouts).
//
// Writes DIR/summary.json (protocol, realities, per policy per_reality {reality,
// motion_imitation_error_rad, sim_to_real_error_rad, fell, ...} and their means, the paper's
// Table II), DIR/<policy>/sim.csv and DIR/<policy>/real<k>_<reality>.csv (per tick: t, vx_cmd,
// mode, then per leg joint q / q_sim / q_ref), and prints the table beside the paper's values.
// scripts/plot_sim2real.py DIR plots it. Exit code: 0 when no rollout fell, 3 when one fell, 1 on a
// setup error (the message names the file and key), CLI11's code on a bad command line.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "pmg/common/cli_checks.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/controller/sil_eval.hpp"
#include "pmg/gco/leg_kinematics.hpp"
#include "pmg/hal/reality.hpp"

namespace {

using Json = nlohmann::ordered_json;
constexpr int kLegJoints = 2 * pmg::gco::kLegDofs;
using LegArray = std::array<double, kLegJoints>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The paper's Table II: {policy: {motion imitation error, sim-to-real error}} [rad].
const std::vector<std::pair<std::string, std::array<double, 2>>>& paperTable() {
  static const std::vector<std::pair<std::string, std::array<double, 2>>> kTable{
      {"Baseline", {0.0571, 0.0781}},
      {"Physically Informed Gains", {0.0747, 0.0656}},
      {"Dynamic Calibration", {0.0682, 0.0562}},
      {"Dynamic + Zero-point", {0.0562, 0.0414}}};
  return kTable;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// The paper's row for a policy name (case-insensitive; "Ours" is the paper's Dynamic + Zero-point), or nullptr.
const std::array<double, 2>* paperRow(const std::string& name) {
  const std::string n = lower(name) == "ours" ? "dynamic + zero-point" : lower(name);
  for (const auto& [k, v] : paperTable())
    if (lower(k) == n) return &v;
  return nullptr;
}

/// A name usable as a folder / file name part: [A-Za-z0-9_-], others become '_'.
std::string slug(const std::string& s) {
  std::string o;
  for (const char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return o.empty() ? std::string("_") : o;
}

/// Splits "a,b,c" (empty items are errors).
std::vector<std::string> splitList(const std::string& text, const std::string& option) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item.empty()) throw pmg::ConfigError(option + " '" + text + "': empty item");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

/// One rollout, per loop tick until the end or the first fall (the falling tick excluded).
struct Trace {
  std::vector<double> t, vx_cmd;
  std::vector<std::string> mode;
  std::vector<char> active;
  std::vector<LegArray> q, q_ref;  // simulator truth; the controller's PMG reference
  std::vector<LegArray> q_meas;    // what the controller measures (encoders after the HAL's zero offsets)
  bool fell = false;
  double fall_time = kNaN;
  std::string end;  // final mode and fault in words
  double wall_s = 0;
};

struct PolicySetup {
  std::string name, controller_path;
  pmg::ControllerConfig config;
  pmg::RobotConfig real_robot;                 // the real robot's base (before a reality)
  std::vector<pmg::hal::Reality> realities;    // loaded against real_robot
  std::array<int, kLegJoints> legs{};          // leg joint indices (robot order): left chain, right chain
};

Trace rollout(const PolicySetup& p, const pmg::RobotConfig& physics, const pmg::MujocoBackendOptions& mujoco,
              const pmg::CommandScript& script, double duration) {
  const auto wall0 = std::chrono::steady_clock::now();
  pmg::SilRunOptions o;  // seed 0: no initial perturbation, no sensor noise
  o.physics_robot = &physics;
  o.mujoco = mujoco;
  o.telemetry = false;
  pmg::SilRun run = pmg::makeSilRun(p.config, o);
  const std::vector<int> adr = pmg::silJointQposAddresses(*run.sim, physics);
  const mjData* d = run.sim->data();
  pmg::Controller& controller = run.app->controller();
  Trace tr;
  const auto ticks = static_cast<std::size_t>(duration / 0.01) + 2;
  for (auto* v : {&tr.t, &tr.vx_cmd}) v->reserve(ticks);
  tr.q.reserve(ticks);
  tr.q_ref.reserve(ticks);
  tr.q_meas.reserve(ticks);
  std::atomic<bool> stop{false};
  const auto observe = [&](double t, const pmg::TickStatus& status, std::size_t) {
    if (tr.fell) return;
    if (pmg::silRobotFell(controller.lastState(), status)) {
      tr.fell = true;
      tr.fall_time = t;
      stop = true;
      return;
    }
    LegArray q{}, r{}, qm{};
    for (int j = 0; j < kLegJoints; ++j) {
      const auto i = static_cast<std::size_t>(p.legs[static_cast<std::size_t>(j)]);
      q[static_cast<std::size_t>(j)] = d->qpos[adr[i]];
      r[static_cast<std::size_t>(j)] = controller.reference()[i];
      qm[static_cast<std::size_t>(j)] = controller.lastState().motors[i].q;
    }
    tr.t.push_back(t);
    tr.vx_cmd.push_back(script.at(t).vx);
    tr.mode.emplace_back(pmg::toString(status.mode));
    tr.active.push_back(status.mode == pmg::Mode::kActive);
    tr.q.push_back(q);
    tr.q_ref.push_back(r);
    tr.q_meas.push_back(qm);
  };
  const pmg::RunSummary rs = run.app->run(duration, &script, &stop, observe);
  tr.end = std::string("final mode ") + pmg::toString(rs.final_mode) + ", fault " + pmg::toString(rs.fault);
  tr.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return tr;
}

/// RMS over ticks (t >= skip; @p active_only: supervisor active) and leg joints of a - b.
double rms(const std::vector<double>& t, const std::vector<LegArray>& a, const std::vector<LegArray>& b,
           std::size_t n, double skip, const std::vector<char>* active_only) {
  double sum = 0;
  long count = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (t[k] < skip - 1e-9 || (active_only && !(*active_only)[k])) continue;
    for (std::size_t j = 0; j < kLegJoints; ++j) {
      const double e = a[k][j] - b[k][j];
      sum += e * e;
    }
    count += kLegJoints;
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : kNaN;
}

Json jnum(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

void writeCsv(const std::string& path, const Trace& tr, const Trace* sim, const std::vector<std::string>& names) {
  std::ofstream f(path);
  if (!f) throw pmg::ConfigError(path + ": cannot write");
  f << "t,vx_cmd,mode";
  for (const auto& n : names) {
    f << ",q_" << n;
    if (sim) f << ",qsim_" << n;
    f << ",qref_" << n;
  }
  f << '\n';
  char b[32];
  const auto num = [&](double x) {
    std::snprintf(b, sizeof b, "%.9g", x);
    return b;
  };
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    f << num(tr.t[k]) << ',' << num(tr.vx_cmd[k]) << ',' << tr.mode[k];
    for (std::size_t j = 0; j < kLegJoints; ++j) {
      f << ',' << num(tr.q[k][j]);
      if (sim) f << ',' << (k < sim->q.size() ? num(sim->q[k][j]) : "nan");
      f << ',' << num(tr.q_ref[k][j]);
    }
    f << '\n';
  }
  if (!f) throw pmg::ConfigError(path + ": write failed");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Table II of the PMG paper in the SIL: Motion Imitation Error and Sim-to-Real Error of policies "
               "on robots with a hidden reality"};
  std::string policies_arg, realities_arg, real_robot_path, out;
  std::string commands = pmg::resolveData("config/policies/eval_sim2real.yaml").string();
  double duration = -1, skip = 1.0;
  app.add_option("--policies", policies_arg,
                 "NAME=CONTROLLER.yaml[,NAME=CONTROLLER.yaml...]: each policy's controller config (its robot: is "
                 "the policy's robot config, policy.model its actor)")
      ->required();
  app.add_option("--realities", realities_arg, "R1.yaml[,R2.yaml...]: hidden realities of the real robot (pmg_reality_draw)")
      ->required();
  app.add_option("--commands", commands, "command script YAML (stand 5 s, then forward velocities)")->capture_default_str();
  app.add_option("--real-robot", real_robot_path,
                 "robot config of the real robot before the reality (default: each policy's robot config without "
                 "its actuator: blocks and zero_offsets)");
  app.add_option("--duration", duration, "override the script's duration [s]")->check(pmg::cli::finiteIn(0.0, 1e5));
  app.add_option("--skip", skip, "metrics from this time on [s]")->capture_default_str()->check(pmg::cli::finiteIn(0.0, 1e5));
  app.add_option("--out", out, "output directory")->required();
  CLI11_PARSE(app, argc, argv);
  const auto wall0 = std::chrono::steady_clock::now();
  try {
    // ---- Inputs, all checked before the first rollout.
    std::vector<PolicySetup> policies;
    std::set<std::string> names, slugs;
    for (const std::string& item : splitList(policies_arg, "--policies")) {
      const std::size_t eq = item.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
        throw pmg::ConfigError("--policies: '" + item + "': expected NAME=CONTROLLER.yaml");
      PolicySetup p;
      p.name = item.substr(0, eq);
      p.controller_path = item.substr(eq + 1);
      if (!names.insert(p.name).second) throw pmg::ConfigError("--policies: the name '" + p.name + "' is given twice");
      if (!slugs.insert(slug(p.name)).second)
        throw pmg::ConfigError("--policies: '" + p.name + "' has the same folder name as another policy (" + slug(p.name) + ")");
      p.config = pmg::loadSilEvalConfig(p.controller_path);
      if (p.config.policy_file.empty()) throw pmg::ConfigError(p.controller_path + ": policy.model: missing (a policy is evaluated)");
      for (double o : p.config.mujoco.encoder_offsets)
        if (o != 0.0)
          throw pmg::ConfigError(p.controller_path + ": mujoco.encoder_offsets: hidden zero offsets belong in a reality "
                                 "file (--realities), expected none");
      if (!real_robot_path.empty()) {
        p.real_robot = pmg::loadRobotConfig(real_robot_path);
      } else {
        p.real_robot = p.config.robot;  // the same robot, without what the policy's calibration believes
        for (pmg::JointConfig& j : p.real_robot.joints) {
          j.actuator_yaml.clear();
          j.actuator_source.clear();
          j.zero_offset = 0.0;
        }
      }
      const auto legs = pmg::gco::LegModel::fromRobotConfig(p.config.robot)->jointIndices(p.config.robot.jointNames());
      for (std::size_t f = 0; f < legs.size(); ++f)
        for (std::size_t j = 0; j < legs[f].size(); ++j) p.legs[f * legs[f].size() + j] = legs[f][j];
      policies.push_back(std::move(p));
    }
    const std::vector<std::string> reality_paths = splitList(realities_arg, "--realities");
    for (PolicySetup& p : policies)
      for (const std::string& r : reality_paths) p.realities.push_back(pmg::hal::loadReality(r, p.real_robot));
    const pmg::CommandScript script = pmg::loadCommandScript(commands);
    const double T = duration > 0 ? duration : script.duration();
    std::filesystem::create_directories(out);

    Json summary;
    Json protocol;
    protocol["commands"] = commands;
    protocol["duration_s"] = T;
    protocol["skip_s"] = skip;
    protocol["seed"] = 0;
    protocol["sensor_noise"] = false;
    protocol["timing"] = "lockstep: 100 Hz loop, 500 Hz HAL, 1 kHz physics (MuJoCo 2.2)";
    protocol["motion_imitation_error"] =
        "RMS over ticks t >= skip_s (supervisor active) and the 12 leg joints of q_real - q_ref [rad]; q_real the "
        "true joint angle of the real robot (SIL with the reality), q_ref the PMG reference the controller gives the "
        "actor";
    protocol["sim_to_real_error"] =
        "RMS over ticks t >= skip_s and the 12 leg joints of q_real - q_sim [rad]; q_sim the true joint angle of the "
        "policy's simulator rollout (the SIL of its robot config: actuator blocks applied, encoders with its "
        "zero_offsets) under the same commands";
    protocol["real_robot"] = real_robot_path.empty() ? "each policy's robot config without actuator blocks and zero offsets, plus the reality" : real_robot_path;
    std::vector<std::string> leg_names;
    for (int i : policies.front().legs) leg_names.push_back(policies.front().config.robot.joints[static_cast<std::size_t>(i)].name);
    protocol["leg_joints"] = leg_names;
    summary["protocol"] = protocol;
    summary["realities"] = reality_paths;
    summary["policies"] = Json::object();

    bool any_fell = false;
    std::printf("pmg_sim2real_eval: %zu policies x %zu realities, %s (%.1f s), metrics from t = %.2f s\n",
                policies.size(), reality_paths.size(), commands.c_str(), T, skip);
    for (PolicySetup& p : policies) {
      const std::string dir = out + "/" + slug(p.name);
      std::filesystem::create_directories(dir);
      std::vector<std::string> names_p;
      for (int i : p.legs) names_p.push_back(p.config.robot.joints[static_cast<std::size_t>(i)].name);
      // The policy's simulator: its robot config, encoders reading its zero offsets.
      pmg::MujocoBackendOptions sim_mo = p.config.mujoco;
      sim_mo.encoder_offsets.clear();
      for (const pmg::JointConfig& j : p.config.robot.joints) sim_mo.encoder_offsets.push_back(j.zero_offset);
      const Trace sim = rollout(p, p.config.robot, sim_mo, script, T);
      writeCsv(dir + "/sim.csv", sim, nullptr, names_p);
      const double sim_mie = rms(sim.t, sim.q, sim.q_ref, sim.t.size(), skip, &sim.active);
      std::printf("[%s] simulator: MIE %.4f rad, %s%s (%.1f s wall)\n", p.name.c_str(), sim_mie,
                  sim.fell ? "FELL, " : "", sim.end.c_str(), sim.wall_s);
      std::fflush(stdout);
      any_fell = any_fell || sim.fell;
      Json pj;
      pj["controller"] = p.controller_path;
      pj["robot"] = p.config.robot_file;
      pj["model"] = p.config.policy_file;
      pj["simulator"] = {{"motion_imitation_error_rad", jnum(sim_mie)},
                         {"fell", sim.fell},
                         {"fall_time_s", jnum(sim.fall_time)},
                         {"csv", slug(p.name) + "/sim.csv"}};
      Json per = Json::array();
      double sum_mie = 0, sum_s2r = 0;
      int n_mie = 0, n_s2r = 0, falls = 0;
      for (std::size_t r = 0; r < p.realities.size(); ++r) {
        pmg::RobotConfig physics = p.real_robot;
        pmg::MujocoBackendOptions mo = p.config.mujoco;
        mo.encoder_offsets.clear();
        pmg::hal::applyReality(p.realities[r], &physics, &mo);
        const Trace real = rollout(p, physics, mo, script, T);
        const std::size_t n = std::min(real.t.size(), sim.t.size());
        for (std::size_t k = 0; k < n; ++k)
          if (std::abs(real.t[k] - sim.t[k]) > 1e-9)
            throw std::runtime_error("the simulator and real rollouts are not in lockstep at tick " + std::to_string(k));
        const double mie = rms(real.t, real.q, real.q_ref, real.t.size(), skip, &real.active);
        const double s2r = rms(real.t, real.q, sim.q, n, skip, nullptr);
        const double mie_meas = rms(real.t, real.q_meas, real.q_ref, real.t.size(), skip, &real.active);
        const std::string stem = std::filesystem::path(reality_paths[r]).stem().string();
        const std::string csv = slug(p.name) + "/real" + std::to_string(r) + "_" + slug(stem) + ".csv";
        writeCsv(out + "/" + csv, real, &sim, names_p);
        std::printf("[%s] reality %s: Motion Imitation Error %.4f rad, Sim-to-Real Error %.4f rad, %s%s (%.1f s wall)\n",
                    p.name.c_str(), reality_paths[r].c_str(), mie, s2r, real.fell ? "FELL, " : "", real.end.c_str(),
                    real.wall_s);
        std::fflush(stdout);
        any_fell = any_fell || real.fell;
        falls += real.fell;
        if (std::isfinite(mie)) sum_mie += mie, ++n_mie;
        if (std::isfinite(s2r)) sum_s2r += s2r, ++n_s2r;
        per.push_back({{"reality", reality_paths[r]},
                       {"motion_imitation_error_rad", jnum(mie)},
                       {"sim_to_real_error_rad", jnum(s2r)},
                       {"fell", real.fell},
                       {"motion_imitation_error_measured_rad", jnum(mie_meas)},
                       {"fall_time_s", jnum(real.fall_time)},
                       {"ticks", real.t.size()},
                       {"csv", csv}});
      }
      pj["per_reality"] = per;
      pj["motion_imitation_error_rad"] = jnum(n_mie ? sum_mie / n_mie : kNaN);
      pj["sim_to_real_error_rad"] = jnum(n_s2r ? sum_s2r / n_s2r : kNaN);
      pj["falls"] = falls;
      summary["policies"][p.name] = pj;
    }
    Json paper = Json::object();
    for (const auto& [k, v] : paperTable()) paper[k] = {v[0], v[1]};
    summary["paper"] = paper;
    summary["paper_columns"] = {"motion_imitation_error_rad", "sim_to_real_error_rad"};
    summary["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    {
      std::ofstream js(out + "/summary.json");
      js << summary.dump(2) << '\n';
      if (!js) throw pmg::ConfigError(out + "/summary.json: write failed");
    }

    // ---- The table, beside the paper's.
    std::printf("\nTable II (SIL, %zu realities; mean over realities; RMS over the 12 leg joints, t >= %.2f s) [rad]\n",
                reality_paths.size(), skip);
    std::printf("%-28s %16s %12s %6s | %-26s %16s %12s\n", "policy", "Motion Imitation", "Sim-to-Real", "falls",
                "paper", "Motion Imitation", "Sim-to-Real");
    std::set<std::string> shown;  // paper rows printed beside the policy of the same name
    const auto val = [](const Json& j) { return j.is_null() ? kNaN : j.get<double>(); };
    for (const PolicySetup& p : policies) {
      const Json& pj = summary["policies"][p.name];
      std::printf("%-28.28s %16.4f %12.4f %3d/%-2zu |", p.name.c_str(), val(pj["motion_imitation_error_rad"]),
                  val(pj["sim_to_real_error_rad"]), pj["falls"].get<int>(), p.realities.size());
      bool beside = false;
      if (const std::array<double, 2>* pv = paperRow(p.name))
        for (const auto& [k, v] : paperTable())
          if (&v == pv && shown.insert(k).second) {
            std::printf(" %-26s %16.4f %12.4f", k.c_str(), v[0], v[1]);
            beside = true;
          }
      std::printf("%s\n", beside ? "" : " (no paper row of this name)");
    }
    for (const auto& [k, v] : paperTable())
      if (!shown.count(k)) std::printf("%-28s %16s %12s %6s | %-26s %16.4f %12.4f\n", "", "", "", "", k.c_str(), v[0], v[1]);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    std::printf("wrote %s/summary.json (%.1f s wall)\n", out.c_str(), wall);
    return any_fell ? 3 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_sim2real_eval: %s\n", e.what());
    return 1;
  }
}
