#pragma once
/// @file log_generator.hpp
/// Synthetic bench logs for testing and benchmarking pmg_calib_dynamics: a rig is simulated with
/// "true" parameters (optionally with one hidden catalogue effect at a seeded random magnitude)
/// and the encoder is quantised and corrupted with noise as a real one would be.

#include <cstdint>
#include <map>
#include <string>

#include "pmg/calib/bench_log.hpp"
#include "pmg/calib/bench_sim.hpp"

namespace pmg::calib {

/// Command shapes. Every log ends with a lift-and-drop: move to +1.0 rad, hold, torque off, free
/// swing (so damping and friction show without the PD).
enum class Trajectory {
  kSines,       ///< sum of two sines (0.45 and 1.3 Hz)
  kStepsHolds,  ///< ramps of different speeds between holds
  kChirp,       ///< 0.2 -> 2.5 Hz chirp, growing amplitude
};

struct SyntheticLogOptions {
  Trajectory trajectory = Trajectory::kSines;
  double duration_s = 8.0;       ///< > 2 s
  double log_rate_hz = 200.0;    ///< command and sample rate, in [20, 2000] Hz
  double amplitude_rad = 0.8;    ///< command amplitude, in (0, 2] rad
  double kp_log = 1.0;           ///< value of the log's kp column (rig log gain units); 0 = no column
  double kd_log = 1.0;           ///< value of the log's kd column; 0 = no column
  /// > 0: a torque-controlled log (as the DFKI AK80-6 runs): kp = kd = 0 columns, q_cmd = 0 and
  /// tau_ff = tau_ff_Nm x (trajectory shape / amplitude_rad) [N·m] while moving, then torque off for
  /// the free swing. 0 = position (PD) control.
  double tau_ff_Nm = 0.0;
  double noise_rad = 2e-4;       ///< encoder noise standard deviation [rad], >= 0
  double quantum_rad = 0.0015339807878856412;  ///< encoder resolution [rad] (4096 counts/rev), >= 0
  std::uint64_t seed = 1;
  void validate() const;         ///< throws std::invalid_argument naming the field
};

/// Simulates a log with `truth` (backlash model if truth.act.backlash_gap_rad > 0).
/// @throws std::invalid_argument on bad options, std::runtime_error if the simulation diverges.
BenchLog generate_bench_log(const RigConfig& rig, const RigParams& truth, const SyntheticLogOptions& options);

/// A hidden effect drawn at a seeded random magnitude within a range where it is clearly visible
/// on the reference test rig (make_test_rig()).
struct HiddenEffect {
  std::string name;                     ///< catalogue entry; "" = clean
  std::map<std::string, double> params; ///< its true parameters (report keys)
};
/// Draws the hidden effect `name` (a catalogue entry, or "" for none) with magnitude uniform in the
/// entry's test range, and returns it; `truth` gets the effect applied on top of the rig nominal.
/// @throws std::invalid_argument for an unknown name.
HiddenEffect draw_hidden_effect(const std::string& name, std::uint64_t seed, const RigConfig& rig, RigParams& truth);

/// Reference rig of the tests and the benchmark: 0.5 kg at 0.1 m, kp 4 N·m/rad, kd 0.08 N·m·s/rad,
/// armature 0.004 kg·m², limit 1.5 N·m, driver at 500 Hz, physics at `sim_dt_s`.
RigConfig make_test_rig(double sim_dt_s = 0.002);

/// Truth for a synthetic log of `rig`: kp and kd as multiples of the rig's nominal gains, the
/// armature [kg·m²], and the rig's torque limit [N·m] and driver rate [Hz]; no extension effects.
RigParams make_rig_truth(const RigConfig& rig, double kp_scale, double kd_scale, double armature_kgm2);

}  // namespace pmg::calib
