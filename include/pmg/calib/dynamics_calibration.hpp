#pragma once
/// @file dynamics_calibration.hpp
/// Motor dynamic calibration (issue 6, PMG "motor dynamic performance calibration", eq. 20):
/// fit the baseline rig model eta = [Kp, Kd, I] (driver gain scales and rotor armature) to logged
/// responses by minimising L(eta) = sum_t (q_sim(t; eta) - q_real(t))^2 over full rollouts driven
/// by the logged command, then test each extension of the catalogue (fitted on the training
/// logs, judged on held-out logs with a per-parameter penalty), name the significant causes,
/// build the extended model and measure its held-out gain.
///
/// Setup/offline code: allocates, throws std::runtime_error / std::invalid_argument.

#include <map>
#include <string>
#include <vector>

#include "pmg/calib/bench_log.hpp"
#include "pmg/calib/bench_sim.hpp"

namespace pmg::calib {

/// Optimiser for the baseline fit (candidate fits always start from the baseline with a coarse
/// scan of the new parameters followed by BOBYQA).
enum class Optimizer {
  kBobyqa,  ///< NLopt LN_BOBYQA from the nominal values (local)
  kCrs2,    ///< NLopt GN_CRS2_LM (global, for rough starts), then BOBYQA polish
  /// (mu/mu_w, lambda)-CMA-ES (cmaes.hpp, Hansen 2016; the PMG seed's choice) on half the budget
  /// from the nominal values (sigma0 = 0.25 of the unit box), then BOBYQA polish. Each generation's
  /// lambda candidates are evaluated concurrently, one worker (own MuJoCo mjData) per thread; each
  /// candidate's loss then runs its logs serially on that worker (no nested threads). Results do
  /// not depend on the thread count (same seed -> bit-identical fit with 1 or N threads).
  kCmaes,
  /// pagmo::cmaes (libpagmo-dev) as a cross-check, then BOBYQA polish: serial population (pagmo's
  /// cmaes has no batch-fitness hook), random initial population in the box, rollouts of
  /// different logs in parallel.
  kCmaesPagmo,
};
/// "bobyqa" | "crs2" | "cmaes" | "cmaes_pagmo"; throws std::invalid_argument otherwise.
Optimizer parse_optimizer(const std::string& name);

/// Catalogue entry names, in report order:
/// coulomb_friction, viscous_friction, stribeck_friction, load_dependent_friction, backlash,
/// transport_delay, torque_saturation, torque_speed_limit, zero_offset.
const std::vector<std::string>& catalogue_names();
/// Parameter names of a catalogue entry (report keys), e.g. {"fc_Nm"}. The nesting entries carry
/// the nested entry's parameters too: stribeck_friction = {fc_Nm, fs_Nm, vs_rad_per_s},
/// load_dependent_friction = {fc_Nm, kl}, torque_speed_limit = {tau_stall_Nm, w_max_rad_per_s}.
/// Throws std::invalid_argument for an unknown name.
const std::vector<std::string>& catalogue_params(const std::string& name);
/// The entry nested in `name` ("" if none): stribeck/load_dependent -> coulomb_friction,
/// torque_speed_limit -> torque_saturation.
std::string nested_entry(const std::string& name);

struct CalibrationOptions {
  Optimizer optimizer = Optimizer::kBobyqa;
  int threads = 0;                    ///< worker threads (one MuJoCo mjData each); 0 = all cores
  /// A cause is significant if its held-out gain exceeds min_gain_per_param x (its number of
  /// parameters). A nesting entry replaces the nested one only if it lowers the nested entry's
  /// held-out RMSE by the same per-parameter margin for its extra parameters.
  double min_gain_per_param = 0.03;
  std::vector<std::string> candidates;  ///< subset of the catalogue to test (empty = all)
  int max_evals_baseline = 400;       ///< objective evaluations for the baseline fit
  int max_evals_candidate = 200;      ///< objective evaluations per candidate fit (after the scan)
  int profile_evals = 24;             ///< baseline re-fit evaluations per scan point of a candidate
  unsigned seed = 1;                  ///< global optimisers' seed
  bool verbose = false;               ///< progress lines on stderr
  void validate() const;              ///< throws std::invalid_argument naming the field
};

/// A fitted model: parameter values by report key (kp, kd, armature, kp_scale, kd_scale and the
/// extension parameters), RMSE on training and held-out logs.
struct FittedModel {
  std::map<std::string, double> params;  ///< values of the *fitted* parameters only
  double train_rmse_rad = 0.0;
  double heldout_rmse_rad = 0.0;
  int evaluations = 0;
};

struct CandidateResult {
  std::string name;
  std::map<std::string, double> params;  ///< the entry's own parameters (catalogue_params)
  FittedModel fit;                        ///< baseline + entry, fitted together
  double gain = 0.0;                      ///< 1 - heldout_rmse / baseline heldout_rmse
  bool significant = false;
  std::string verdict;                    ///< why it was named or not
};

/// Residual concentration on held-out logs (per region: share of samples and RMSE).
struct RegionResidual {
  std::string name;            ///< velocity_reversal | high_torque | steady_hold | fast_move | all
  double fraction_of_samples = 0.0;
  double baseline_rmse_rad = 0.0;
  double extended_rmse_rad = 0.0;
};

struct CalibrationReport {
  FittedModel baseline;                  ///< params: kp, kd, armature, kp_scale, kd_scale
  std::vector<CandidateResult> candidates;  ///< every tested entry, catalogue order
  std::vector<CandidateResult> causes;      ///< significant causes, ranked by gain
  FittedModel extended;                  ///< baseline + accepted causes (all parameters)
  std::vector<std::string> extended_causes;
  std::vector<RegionResidual> regions;
  std::vector<std::string> train_logs, heldout_logs;
  std::string optimizer;
  double wall_time_s = 0.0;
};

/// Rollout parameters from a report parameter map (missing keys: rig nominal / effect off).
RigParams rig_params_from(const RigConfig& rig, const std::map<std::string, double>& params);

/// Step 1 of calibrate_dynamics alone: fits the baseline eta = [Kp, Kd, I] (params kp_scale,
/// kd_scale, armature) on `train` with options.optimizer, options.max_evals_baseline,
/// options.seed and options.threads; train_rmse_rad and evaluations are set, heldout_rmse_rad = 0.
/// @throws std::invalid_argument on bad options or empty `train`, std::runtime_error if a rollout
/// diverges at the nominal parameters.
FittedModel fit_baseline(const RigConfig& rig, const std::vector<BenchLog>& train, const CalibrationOptions& options);

/// Runs the whole calibration. `train` and `heldout` must be non-empty.
/// @throws std::invalid_argument on bad options, std::runtime_error if a rollout diverges at the
/// nominal parameters.
CalibrationReport calibrate_dynamics(const RigConfig& rig, const std::vector<BenchLog>& train,
                                     const std::vector<BenchLog>& heldout, const CalibrationOptions& options);

/// JSON text of the report (keys: baseline, causes, extended, candidates, residual_regions, ...).
std::string report_to_json(const CalibrationReport& report);

/// Writes a CSV of held-out traces (log, t, q_cmd, q_measured, q_baseline, q_extended) used by
/// scripts/calib_plot.py. @throws std::runtime_error if the file cannot be written.
void write_trace_csv(const RigConfig& rig, const std::vector<BenchLog>& heldout, const CalibrationReport& report,
                     const std::string& path);

}  // namespace pmg::calib
