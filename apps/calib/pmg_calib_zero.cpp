// pmg_calib_zero: zero-point (encoder offset) calibration of the 12 leg joints by Motor-IMU alignment
// (PMG eqs. 21-25, issue 6). Drives the robot through the protocol of config/calib/zero_poses_g1.yaml via
// a pmg::HalBackend (MuJoCo SIL or the motor buses), then runs the estimator and writes the offsets.
// docs/calibration.md, "Zero-point calibration".
#include <chrono>
#include <functional>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/calib/zero_calibration.hpp"
#include "pmg/calib/zero_io.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/yaml_archive.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/hal/zero_offset_backend.hpp"

namespace {

/// Paces a hardware backend to its cycle period on the one real-time clock (hal::rt; the SIL runs
/// in lockstep).
class PacedBackend final : public pmg::HalBackend {
 public:
  explicit PacedBackend(std::unique_ptr<pmg::HalBackend> inner) : inner_(std::move(inner)) {}
  const char* name() const noexcept override { return inner_->name(); }
  double cyclePeriod() const noexcept override { return inner_->cyclePeriod(); }
  std::string report() const override { return inner_->report(); }
  pmg::BackendStatus exchange(const pmg::LowCommand& c, pmg::LowState& s) noexcept override {
    if (next_ < 0) next_ = pmg::hal::rt::now();
    next_ += inner_->cyclePeriod();
    pmg::hal::rt::sleepUntil(next_);
    return inner_->exchange(c, s);
  }

 private:
  std::unique_ptr<pmg::HalBackend> inner_;
  double next_ = -1.0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_calib_zero: leg zero-point calibration by Motor-IMU alignment (PMG eqs. 21-25)"};
  std::string config_path, backend_name = "mujoco", protocol_path, out_path, inject_file, plot_path, history_csv;
  int inject_seed = -1;
  double max_offset = 0.05;
  pmg::calib::ZeroEstimatorOptions eo;
  app.add_option("--config", config_path, "controller config (with robot:) or robot config YAML")->required();
  app.add_option("--backend", backend_name, "mujoco (SIL, no gantry) | can (controller config's can: settings)")
      ->check(CLI::IsMember({"mujoco", "can"}));
  app.add_option("--protocol", protocol_path, "pose protocol YAML (default: config/calib/zero_poses_g1.yaml of pmg's "
                                              "data directory)");
  app.add_option("--out", out_path, "result YAML (zero_offset per joint, robot-config form)");
  app.add_option("--inject-offsets", inject_file, "SIL: hidden encoder offsets YAML {joint_name: rad}");
  app.add_option("--inject-random", inject_seed, "SIL: random hidden offsets on the 12 leg joints, this seed");
  app.add_option("--max-offset", max_offset, "SIL: |offset| bound of --inject-random [rad]")->check(CLI::Range(0.0, 0.3));
  app.add_option("--tau", eo.tau, "tau: IMU agreement gate [rad]");
  app.add_option("--alpha", eo.alpha, "alpha: update gain");
  app.add_option("--epsilon", eo.epsilon, "epsilon: convergence threshold on |alpha delta| [rad]");
  app.add_option("--consecutive", eo.consecutive, "M: consecutive iterations below epsilon");
  app.add_option("--max-iterations", eo.max_iterations, "iteration limit");
  bool sil_truth = false;
  app.add_flag("--sil-truth", sil_truth, "SIL: print the true foot poses after each pose (slip check)");
  app.add_option("--history-csv", history_csv, "convergence history CSV (iteration, z per joint)");
  app.add_option("--plot", plot_path, "convergence plot PNG (needs python3 + matplotlib; implies a history CSV)");
  std::string sil_contacts = "bench";
  app.add_option("--sil-contacts", sil_contacts, "SIL sole contacts: bench (rigid calibration bench floor, "
                 "MujocoBackendOptions::sole_contacts; default) | mjcf (the MJCF's soft contacts, as every other SIL run)")
      ->check(CLI::IsMember({"bench", "mjcf"}));
  int passes = 1;
  app.add_option("--passes", passes, "capture passes; pass k+1 plans its targets with the estimate of pass k "
                                     "(less internal stress in the closed chain)")->check(CLI::Range(1, 5));
  bool analyze = false;
  app.add_flag("--analyze", analyze, "print the observability (singular values) of the protocol and of subsets, on the "
                                     "nominal model, and exit");
  CLI11_PARSE(app, argc, argv);

  try {
    eo.validate();
    // Outputs first: a bad path must not cost the capture.
    if (!plot_path.empty() && history_csv.empty()) history_csv = plot_path + ".csv";
    for (const std::string* out : {&out_path, &history_csv, &plot_path})
      if (!out->empty()) pmg::requireWritableFile(*out);
    const std::string plot_script = pmg::resolveData("scripts/pmg_plot_zero.py").string();
    // Config: a controller config names its robot config; else it is the robot config.
    pmg::RobotConfig robot;
    std::unique_ptr<pmg::ControllerConfig> cc;
    if (pmg::yaml::loadYamlDocument(config_path).root["robot"].IsScalar()) {  // names the file on a bad YAML
      cc = std::make_unique<pmg::ControllerConfig>(pmg::loadControllerConfig(config_path));
      robot = cc->robot;
    } else {
      robot = pmg::loadRobotConfig(config_path);
    }
    if (protocol_path.empty()) protocol_path = pmg::resolveData("config/calib/zero_poses_g1.yaml").string();
    const pmg::calib::ZeroProtocol protocol = pmg::calib::loadZeroProtocol(protocol_path);
    auto model = pmg::gco::LegModel::fromRobotConfig(robot);
    const auto idx = pmg::calib::zeroJointIndices(*model, robot);

    if (analyze) {
      pmg::calib::ZeroEstimator est(model, eo);
      const auto report = [&](const std::string& label, const std::function<bool(const pmg::calib::ZeroPoseSpec&)>& keep) {
        pmg::calib::ZeroProtocol sub = protocol;
        sub.poses.clear();
        for (const auto& p : protocol.poses)
          if (keep(p)) sub.poses.push_back(p);
        if (sub.poses.empty()) return;
        const auto samples = pmg::calib::synthesizeZeroSamples(model, robot, sub, pmg::calib::ZeroVector::Zero());
        const auto o = est.observability(samples, pmg::calib::ZeroVector::Zero(), est.placementOf(samples.front().readings));
        const auto& sv = o.singular_values;
        fmt::print("{:<44} poses {:2d}  rank {:2d}/15  sigma_max {:.3g}  sigma_min {:.3g}  sigma_min/sigma_max {:.2g}\n", label,
                   sub.poses.size(), o.rank, sv(0), sv(sv.size() - 1), sv(sv.size() - 1) / sv(0));
        fmt::print("    weakest direction (12 joints, x, y, yaw): [{:.2f}]\n",
                     fmt::join(o.weakest_direction.data(), o.weakest_direction.data() + o.weakest_direction.size(), ", "));
      };
      report("all poses", [](const auto&) { return true; });
      report("squats only (dp.xy = 0, rpy = 0)", [](const auto& p) { return p.rpy.isZero() && p.dp.template head<2>().isZero(); });
      report("no yaw (rpy.z = 0)", [](const auto& p) { return p.rpy.z() == 0.0; });
      report("no roll (rpy.x = 0)", [](const auto& p) { return p.rpy.x() == 0.0; });
      report("no pitch (rpy.y = 0)", [](const auto& p) { return p.rpy.y() == 0.0; });
      report("symmetric only (dp.y = 0, roll = yaw = 0)", [](const auto& p) { return p.dp.y() == 0.0 && p.rpy.x() == 0.0 && p.rpy.z() == 0.0; });
      report("without the twist_* poses", [](const auto& p) { return p.name.rfind("twist", 0) != 0; });
      return 0;
    }
    // The motors move only through the same safety stack as pmg_controller (makeHalStack: backend
    // -> zero offsets of the robot config -> SafeBackend), engaged through soft stand.
    pmg::HalStackConfig hs = cc ? cc->halStack() : pmg::HalStackConfig{};
    std::unique_ptr<pmg::HalBackend> device;
    std::vector<double> injected;
    if (backend_name == "mujoco") {
      pmg::MujocoBackendOptions bo = cc ? cc->mujoco : pmg::MujocoBackendOptions{};
      bo.gantry.enabled = false;  // standing on the ground: the protocol needs the feet planted
      bo.sole_contacts.enabled = sil_contacts == "bench";
      bo.encoder_offsets.assign(robot.numJoints(), 0.0);
      if (inject_seed >= 0)
        bo.encoder_offsets = pmg::calib::randomLegOffsets(robot, *model, static_cast<unsigned>(inject_seed), max_offset);
      if (!inject_file.empty()) bo.encoder_offsets = pmg::calib::loadJointValues(inject_file, robot);
      injected = bo.encoder_offsets;
      device = std::make_unique<pmg::MujocoBackend>(robot, bo);
    } else {
      if (!cc || cc->backend != pmg::BackendKind::kCan)
        throw pmg::ConfigError(config_path + ": --backend can needs a controller config with backend: can");
      if (inject_seed >= 0 || !inject_file.empty())
        throw std::invalid_argument("--inject-offsets / --inject-random only apply to --backend mujoco");
      hs.backend = pmg::BackendKind::kCan;
      // The controller config's timing decides: `realtime` (a robot) paces the exchange to the bus
      // period; `lockstep` (pmg_sil in lockstep, e.g. a SIL with a hidden reality) waits for every
      // reply instead, deterministic and immune to a loaded host.
      if (hs.lockstep)
        device = pmg::makeCanBackendFor(hs);
      else
        device = std::make_unique<PacedBackend>(pmg::makeCanBackendFor(hs));
    }
    auto* sil = dynamic_cast<pmg::MujocoBackend*>(device.get());
    // The protocol's leg gains (stiffer than the walking gains) are declared to the supervisor.
    pmg::calib::declareProtocolGains(protocol, robot, *model, hs);
    // Offsets already in the robot config are applied below the tool (by the stack); it estimates
    // what remains and reports the total (config + residual).
    pmg::calib::ZeroVector z_config;
    for (int j = 0; j < pmg::calib::kZeroJoints; ++j) z_config(j) = -robot.joints[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].zero_offset;
    if (robot.zeroOffsets().cwiseAbs().maxCoeff() > 0.0)
      fmt::print("applying the robot config's zero_offsets below the tool; results are totals\n");
    pmg::HalStack stack = pmg::makeHalStack(robot, hs, std::move(device));
    pmg::engageActive(stack, robot);
    pmg::HalBackend* backend = stack.backend.get();
    const auto feet = [&](const char* tag) {
      if (sil == nullptr || !sil_truth) return;
      for (const std::string& b : {robot.left_foot_link, robot.right_foot_link}) {
        const int id = mj_name2id(sil->model(), mjOBJ_BODY, b.c_str());
        const double* x = sil->data()->xpos + 3 * id;
        const double* R = sil->data()->xmat + 9 * id;
        fmt::print("SIL truth {}: {} at ({:.5f}, {:.5f}, {:.5f}) yaw {:.5f} tilt {:.5f}\n", tag, b, x[0], x[1], x[2],
                   std::atan2(R[3], R[0]), std::acos(std::min(1.0, R[8])));
      }
    };
    feet("before");
    pmg::calib::ZeroEstimator est(model, eo);
    pmg::calib::ZeroCapture cap;
    pmg::calib::ZeroEstimate res;
    pmg::calib::ZeroVector z_guess = pmg::calib::ZeroVector::Zero();
    double t_capture = 0.0, t_est = 0.0;
    for (int pass = 1; pass <= passes; ++pass) {
      const auto t0 = std::chrono::steady_clock::now();
      fmt::print("capture pass {}/{}: {} poses from {} via backend '{}'\n", pass, passes, protocol.poses.size(),
                 protocol.source, backend->name());
      cap = pmg::calib::captureZeroPoses(
          *backend, robot, model, protocol,
          [&](const std::string& s) {
            fmt::print("  {}\n", s);
            if (s.rfind("pose ", 0) == 0 || s.rfind("home", 0) == 0) feet(s.substr(0, 18).c_str());
          },
          z_guess, cap.final_targets);
      feet("after");
      t_capture += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (cap.feet_moved)
        throw std::runtime_error(fmt::format("the feet moved during the capture (home orientation drift {:.4f} rad > "
                                             "max_home_drift {}): repeat on a non-slippery floor",
                                             cap.home_drift, protocol.max_home_drift));
      const pmg::calib::ZeroObservability obs =
          est.observability(cap.samples, z_guess, est.placementOf(cap.samples.front().readings + z_guess));
      fmt::print("observability: rank {} of 15, sigma_max {:.3g}, sigma_min {:.3g}\n", obs.rank, obs.singular_values(0),
                 obs.singular_values(obs.singular_values.size() - 1));
      const auto t1 = std::chrono::steady_clock::now();
      res = est.estimate(cap.samples, z_guess, [](int it, const pmg::calib::ZeroVector& z, double step, int used) {
        if (it <= 10 || it % 10 == 0)
          fmt::print("iter {:4d}  |alpha delta|max {:.3e} rad  poses {:2d}  z = [{:.4f}]\n", it, step, used,
                     fmt::join(z.data(), z.data() + z.size(), ", "));
      });
      t_est += std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      z_guess = res.z;
      if (!injected.empty()) {
        double e = 0.0;
        for (int j = 0; j < pmg::calib::kZeroJoints; ++j)
          e = std::max(e, std::abs(-(res.z(j) + z_config(j)) - injected[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])]));
        fmt::print("pass {}: max |estimated - injected| = {:.5f} rad\n", pass, e);
      }
    }
    fmt::print("{}\n", res.message);
    for (int k : res.rejected_capture)
      fmt::print("  refused at capture: {} ({})\n", cap.samples[static_cast<std::size_t>(k)].name,
                 cap.samples[static_cast<std::size_t>(k)].reason);
    for (int k : res.rejected_tau)
      fmt::print("  excluded by tau: {} (IMU disagreement {:.4f} rad > tau {})\n",
                 cap.samples[static_cast<std::size_t>(k)].name, res.imu_disagreement[static_cast<std::size_t>(k)], eo.tau);
    fmt::print("{:<26} {:>12}{}\n", "joint", "offset [rad]", injected.empty() ? "" : "  injected   error");
    double max_err = 0.0;
    for (int j = 0; j < pmg::calib::kZeroJoints; ++j) {
      const auto i = static_cast<std::size_t>(idx[static_cast<std::size_t>(j)]);
      const double off = -(res.z(j) + z_config(j));
      if (injected.empty()) {
        fmt::print("{:<26} {:>12.5f}\n", robot.joints[i].name, off);
      } else {
        max_err = std::max(max_err, std::abs(off - injected[i]));
        fmt::print("{:<26} {:>12.5f} {:>10.5f} {:>7.5f}\n", robot.joints[i].name, off, injected[i], off - injected[i]);
      }
    }
    if (!injected.empty()) fmt::print("max |estimated - injected| = {:.5f} rad\n", max_err);
    fmt::print("time: capture {:.2f} s wall ({:.1f} s robot time), estimate {:.2f} s\n", t_capture, cap.duration_s, t_est);

    pmg::calib::ZeroEstimate total = res;  // z relative to the raw encoders
    total.z += z_config;
    for (auto& h : total.history) h += z_config;
    if (!out_path.empty()) pmg::calib::writeZeroResult(out_path, robot, *model, total, cap, eo);
    if (!history_csv.empty()) pmg::calib::writeZeroHistoryCsv(history_csv, robot, *model, total);
    if (!plot_path.empty()) {
      const std::string cmd = fmt::format("python3 '{}' '{}' '{}'", plot_script, history_csv, plot_path);
      if (std::system(cmd.c_str()) != 0) std::cerr << "warning: plot failed: " << cmd << "\n";
    }
    return res.converged ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "pmg_calib_zero: " << e.what() << "\n";
    return 1;
  }
}
