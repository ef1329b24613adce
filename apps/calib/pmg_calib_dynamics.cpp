// pmg_calib_dynamics: motor dynamic calibration on bench logs (issue 6). See docs/calibration.md.
//   pmg_calib_dynamics --rig RIG.yaml --train A [B ...] --heldout C [D ...] --report OUT.json [--plot OUT.png]
// Every output path is checked before the logs are read and the fit starts. The plot is drawn by
// scripts/calib_plot.py of pmg's data directory (pmg::dataDir()).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/common/data_paths.hpp"

namespace {

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fit a single-joint MuJoCo bench-rig model to measured motor responses; show, name and "
               "measure what the baseline PD + armature model gets wrong (issue 6)."};
  std::string rig_path, report_path, plot_path, optimizer = "bobyqa", actuator_out;
  std::vector<std::string> train_specs, heldout_specs, candidates;
  pmg::calib::CalibrationOptions opt;
  app.add_option("--rig", rig_path, "rig YAML (rig: + motor:)")->required();
  app.add_option("--train", train_specs, "training logs (CSV t,q_cmd,q[,...], BAM JSON, DFKI data_measured.csv; "
                                          "optional time window FILE@t0:t1)")->required();
  app.add_option("--heldout", heldout_specs, "held-out logs (same formats)")->required();
  app.add_option("--report", report_path, "output report JSON")->required();
  app.add_option("--plot", plot_path, "output PNG: measured vs baseline vs extended on the held-out logs");
  app.add_option("--optimizer", optimizer,
                 "baseline optimiser: bobyqa (local), crs2 (NLopt global), cmaes (CMA-ES, population evaluated in "
                 "parallel threads), cmaes_pagmo (pagmo's CMA-ES, serial population; cross-check)")
      ->check(CLI::IsMember({"bobyqa", "crs2", "cmaes", "cmaes_pagmo"}));
  app.add_option("--threads", opt.threads, "worker threads (0 = all cores)");
  app.add_option("--candidates", candidates, "catalogue entries to test (default: all)")->delimiter(',');
  app.add_option("--min-gain-per-param", opt.min_gain_per_param,
                 "cross-validated RMSE gain required per extra parameter (rule 1, docs/calibration.md)");
  app.add_option("--noise-z", opt.noise_z, "rule 2: CV RMSE drop must exceed this x noise floor / sqrt(effective samples)");
  app.add_option("--min-rmse-over-floor", opt.min_rmse_over_floor,
                 "rule 3: a model whose CV RMSE is within this multiple of the noise floor is not extended");
  app.add_option("--cv-folds", opt.cv_folds, "K of the K-fold cross-validation over the training logs (2..20)");
  app.add_option("--cv-evals", opt.cv_evals, "objective evaluations per fold re-fit");
  app.add_option("--max-evals-baseline", opt.max_evals_baseline, "objective evaluations for the baseline fit");
  app.add_option("--max-evals-candidate", opt.max_evals_candidate, "objective evaluations per candidate fit");
  app.add_option("--actuator-out", actuator_out, "write the extended model as an `actuator:` YAML block");
  app.add_flag("--verbose,-v", opt.verbose, "progress on stderr");
  CLI11_PARSE(app, argc, argv);

  try {
    // Outputs first: a bad path must not cost the fit.
    pmg::requireWritableFile(report_path);
    if (!actuator_out.empty()) pmg::requireWritableFile(actuator_out);
    const std::string plot_script = pmg::resolveData("scripts/calib_plot.py").string();
    if (!plot_path.empty()) {
      pmg::requireWritableFile(plot_path);
      pmg::requireWritableFile(plot_path + ".traces.csv");
      if (!std::filesystem::is_regular_file(plot_script))
        throw std::runtime_error(plot_script + ": plot script missing (set PMG_DATA_DIR to pmg's share/pmg)");
    }
    opt.optimizer = pmg::calib::parse_optimizer(optimizer);
    opt.candidates = candidates;
    const pmg::calib::RigConfig rig = pmg::calib::load_rig_config(rig_path);
    std::vector<pmg::calib::BenchLog> train, heldout;
    for (const auto& s : train_specs) train.push_back(pmg::calib::load_bench_log(s));
    for (const auto& s : heldout_specs) heldout.push_back(pmg::calib::load_bench_log(s));
    const auto rep = pmg::calib::calibrate_dynamics(rig, train, heldout, opt);
    {
      std::ofstream out(report_path);
      if (!out) throw std::runtime_error(report_path + ": cannot write report");
      out << pmg::calib::report_to_json(rep);
    }
    fmt::print("noise floor {:.3g} rad (encoder quantum {:.3g} rad, high-frequency noise {:.3g} rad; {:.0f} effective "
               "samples of {}); selection: {}-fold CV over training {}\n",
               rep.noise.floor_rad, rep.noise.quantum_rad, rep.noise.hf_rad, rep.noise.effective_samples, rep.noise.samples,
               rep.cv_folds, rep.cv_fold_unit == "logs" ? "logs" : "time blocks");
    fmt::print("baseline CV RMSE {:.5f} rad, held-out RMSE {:.5f} rad (kp {:.4g} N·m/rad, kd {:.4g} N·m·s/rad, armature {:.4g} "
               "kg·m²)\n",
               rep.baseline.cv_rmse_rad, rep.baseline.heldout_rmse_rad, rep.baseline.params.at("kp"),
               rep.baseline.params.at("kd"), rep.baseline.params.at("armature"));
    if (rep.causes.empty()) fmt::print("causes: none is significant in cross-validation against the noise floor\n");
    for (const auto& c : rep.causes)
      fmt::print("cause {:<24} CV RMSE {:.5f} rad, CV gain {:.3f}; held-out RMSE of the model up to it {:.5f} rad\n", c.name,
                 c.fit.cv_rmse_rad, c.gain, c.fit.heldout_rmse_rad);
    fmt::print("extended held-out RMSE {:.5f} rad (gain {:.3f}); wall time {:.1f} s; report {}\n",
               rep.extended.heldout_rmse_rad, 1.0 - rep.extended.heldout_rmse_rad / rep.baseline.heldout_rmse_rad,
               rep.wall_time_s, report_path);
    if (!actuator_out.empty()) {
      std::string names;
      for (const auto& c : rep.extended_causes) names += (names.empty() ? "" : ", ") + c;
      pmg::calib::write_actuator_file(actuator_out, pmg::calib::actuator_block_from_params(rig, rep.extended.params),
                                      fmt::format("Identified by pmg_calib_dynamics from rig {}\ncauses: {}", rig_path,
                                                  names.empty() ? "none" : names));
    }
    if (!plot_path.empty()) {
      const std::string traces = plot_path + ".traces.csv";
      pmg::calib::write_trace_csv(rig, heldout, rep, traces);
      const std::string cmd = fmt::format("python3 {} --report {} --traces {} --out {}",
                                          shell_quote(plot_script),
                                          shell_quote(report_path), shell_quote(traces), shell_quote(plot_path));
      if (std::system(cmd.c_str()) != 0) throw std::runtime_error("plot failed: " + cmd);
      std::remove(traces.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "pmg_calib_dynamics: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
