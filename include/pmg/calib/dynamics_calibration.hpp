#pragma once
/// @file dynamics_calibration.hpp
/// Motor dynamic calibration (issue 6, PMG "motor dynamic performance calibration", eq. 20):
/// fit the baseline rig model eta = [Kp, Kd, I] (driver gain scales and rotor armature) to logged
/// responses by minimising L(eta) = sum_t (q_sim(t; eta) - q_real(t))^2 over full rollouts driven
/// by the logged command, then test each extension of the catalogue (fitted on the training logs
/// and judged by K-fold cross-validation over the training logs only, with a per-parameter
/// penalty and a significance test against the logs' noise floor), name the significant causes,
/// build the extended model and report its held-out (test) error once. Held-out logs never
/// influence what is fitted or named.
///
/// Setup/offline code: allocates, throws std::runtime_error / std::invalid_argument.

#include <cstddef>
#include <limits>
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
/// transport_delay, torque_constant, torque_saturation, torque_speed_limit, zero_offset.
/// torque_constant (param kt_scale: delivered = kt_scale x commanded torque) is fitted only when a
/// training log carries a nonzero feed-forward torque (on pure PD data it is kp and kd scaled
/// together, which the baseline already fits); otherwise its verdict says so.
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
  /// A cause is significant against a reference model (the baseline, the nested entry, or the
  /// causes chosen so far) only if all hold (CV = K-fold cross-validated RMSE over the training
  /// logs; floor = NoiseFloor::floor_rad; N_eff = NoiseFloor::effective_samples):
  ///  1. relative: 1 - CV_new / CV_ref > min_gain_per_param x (number of added parameters);
  ///  2. noise: CV_ref - CV_new > noise_z x floor / sqrt(N_eff);
  ///  3. room: CV_ref > min_rmse_over_floor x floor (a model that already explains the data to
  ///     within that multiple of the noise floor is not extended);
  ///  4. consistency: the new model's test error is lower in at least ceil(3K/4) of the K folds;
  ///  5. transport_delay only: the fitted delay_s >= max(driver period 1 / rate_hz, the log's
  ///     median sample period) (a shorter one is the driver's zero-order hold, not a delay).
  double min_gain_per_param = 0.03;
  double noise_z = 3.0;               ///< rule 2 multiple, > 0
  double min_rmse_over_floor = 2.0;   ///< rule 3 multiple, >= 1
  /// Number of cross-validation folds K, in [2, 20]. With >= 2 training logs the folds are whole
  /// logs (log i in fold i mod min(K, number of logs)); with one training log they are K
  /// contiguous time blocks of it (the fold's rows are left out of the fitting loss and scored
  /// on the same open-loop rollout).
  int cv_folds = 4;
  /// BOBYQA evaluations per fold re-fit (warm-started from the fit on all training logs).
  int cv_evals = 60;
  std::vector<std::string> candidates;  ///< subset of the catalogue to test (empty = all)
  int max_evals_baseline = 400;       ///< objective evaluations for the baseline fit
  int max_evals_candidate = 200;      ///< objective evaluations per candidate fit (after the scan)
  int profile_evals = 24;             ///< baseline re-fit evaluations per scan point of a candidate
  unsigned seed = 1;                  ///< global optimisers' seed
  bool verbose = false;               ///< progress lines on stderr
  void validate() const;              ///< throws std::invalid_argument naming the field
};

/// A fitted model: parameter values by report key (kp, kd, armature, kp_scale, kd_scale and the
/// extension parameters), RMSE on training logs, K-fold CV RMSE over the training logs and RMSE
/// on held-out logs [rad].
struct FittedModel {
  std::map<std::string, double> params;  ///< values of the *fitted* parameters only
  double train_rmse_rad = 0.0;
  /// Held-out (test) RMSE. Measured only for the baseline, the extended model and the chosen
  /// chain (CandidateResult in CalibrationReport::causes); NaN elsewhere (never measured).
  double heldout_rmse_rad = std::numeric_limits<double>::quiet_NaN();
  double cv_rmse_rad = std::numeric_limits<double>::quiet_NaN();  ///< what selection used
  std::vector<double> cv_fold_mse;  ///< per fold: mean squared test error of the fold re-fit [rad²]
  int evaluations = 0;
};

struct CandidateResult {
  std::string name;
  std::map<std::string, double> params;  ///< the entry's own parameters (catalogue_params)
  FittedModel fit;                        ///< baseline (+ causes before it) + entry, fitted together
  /// Selection gain 1 - CV_rmse / reference CV_rmse. For `candidates`, the reference is the
  /// baseline; for `causes`, the model before this cause joined (the baseline for the first).
  double gain = 0.0;
  double reference_cv_rmse_rad = std::numeric_limits<double>::quiet_NaN();
  bool significant = false;
  std::string verdict;                    ///< why it was named or not (which rule)
};

/// Measurement noise and quantisation floor of the training logs (never the held-out ones).
struct NoiseFloor {
  /// Encoder resolution [rad]: the smallest nonzero |q[i+1] - q[i]| (0 if none).
  double quantum_rad = 0.0;
  /// High-frequency position noise [rad]: robust scale 1.4826 x median |r| of the residual r of q
  /// minus its 5-sample local quadratic (Savitzky-Golay) smoothing, divided by sqrt(18/35) (the
  /// white-noise share that survives it), over the slowest quarter of each log's samples (by
  /// |q[i+1] - q[i-1]|), so that sampling-time jitter and fast transients, which grow with speed,
  /// do not count as noise. On a quantised encoder at rest r is 0 and the quantum term carries
  /// the floor. Assumes roughly uniform sampling.
  double hf_rad = 0.0;
  /// floor = sqrt(hf^2 + quantum^2 / 12) [rad] (conservative: hf already contains part of the
  /// quantisation error while the joint moves).
  double floor_rad = 0.0;
  /// Effective number of independent residual samples: N (1 - rho1) / (1 + rho1), rho1 the
  /// lag-1 autocorrelation of the baseline's residual on the training logs, clipped to [1, N].
  double effective_samples = 1.0;
  std::size_t samples = 0;  ///< N, rows of the training logs
};

/// Estimates quantum_rad, hf_rad and floor_rad of `logs` (pooled, row-weighted);
/// effective_samples = samples = total rows. @throws std::invalid_argument if `logs` is empty.
NoiseFloor estimate_noise_floor(const std::vector<BenchLog>& logs);

/// Residual concentration on held-out logs (per region: share of samples and RMSE).
struct RegionResidual {
  std::string name;            ///< velocity_reversal | high_torque | steady_hold | fast_move | all
  double fraction_of_samples = 0.0;
  double baseline_rmse_rad = 0.0;
  double extended_rmse_rad = 0.0;
};

struct CalibrationReport {
  FittedModel baseline;                  ///< params: kp, kd, armature, kp_scale, kd_scale
  std::vector<CandidateResult> candidates;  ///< every tested entry, catalogue order (no held-out RMSE)
  /// Named causes in the order they joined the model. causes[i].fit is the chosen model up to
  /// and including cause i; its heldout_rmse_rad is measured after the selection is final.
  std::vector<CandidateResult> causes;
  FittedModel extended;                  ///< baseline + accepted causes (all parameters)
  std::vector<std::string> extended_causes;
  std::vector<RegionResidual> regions;
  std::vector<std::string> train_logs, heldout_logs;
  NoiseFloor noise;
  int cv_folds = 0;              ///< K actually used
  std::string cv_fold_unit;      ///< "logs" | "time_blocks"
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
