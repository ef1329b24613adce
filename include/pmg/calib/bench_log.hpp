#pragma once
/// @file bench_log.hpp
/// Single-joint bench logs and bench rig descriptions for motor dynamic calibration (issue 6).
/// Setup code only: loaders allocate and throw std::runtime_error naming the file, the field and
/// the expected range.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace pmg::calib {

/// One bench log, column-major, all columns of length size(). SI units, angle about the joint
/// axis with 0 = pendulum hanging down. Columns that a file does not provide are empty and their
/// has_* flag is false.
struct BenchLog {
  std::string name;                ///< file (and time window) it was read from
  std::vector<double> t;           ///< time [s], strictly increasing
  std::vector<double> q_cmd;       ///< commanded position [rad] (driver's q_des)
  std::vector<double> q;           ///< measured encoder position [rad] (motor side)
  std::vector<double> dq;          ///< measured velocity [rad/s] (optional)
  std::vector<double> tau;         ///< measured torque [N·m] (optional, informative only)
  std::vector<double> kp;          ///< driver stiffness per row, in the rig's log gain units (optional)
  std::vector<double> kd;          ///< driver damping per row, in the rig's log gain units (optional)
  std::vector<double> dq_cmd;      ///< commanded velocity [rad/s] (optional, default 0)
  std::vector<double> tau_ff;      ///< feed-forward torque [N·m] (optional, default 0)
  std::vector<std::uint8_t> enabled;  ///< 0 where torque is off (optional, default all on)

  std::size_t size() const { return t.size(); }
  bool has_dq() const { return !dq.empty(); }
  bool has_tau() const { return !tau.empty(); }
  bool has_kp() const { return !kp.empty(); }
  bool has_kd() const { return !kd.empty(); }
  bool has_dq_cmd() const { return !dq_cmd.empty(); }
  bool has_tau_ff() const { return !tau_ff.empty(); }
  bool has_enabled() const { return !enabled.empty(); }
  /// Throws std::runtime_error if columns differ in length, time is not increasing or a value is
  /// not finite.
  void validate() const;
};

/// Reads a bench log. `spec` is a path, optionally followed by a time window `@t0:t1` (seconds,
/// either bound may be empty), e.g. `run.csv@0:20`. Formats, chosen by content:
///  - pmg CSV: header `t,q_cmd,q` plus any of `dq,tau,kp,kd,dq_cmd,tau_ff,enabled`;
///  - Rhoban BAM JSON (`entries[]` with timestamp, goal_position, position, speed,
///    torque_enable; header `kp` becomes the kp column, in firmware units);
///  - DFKI torque-limited pendulum CSV (`time,position,velocity,torque`): pass data_measured*.csv;
///    the command is read from the sibling data_desired*.csv (q_des, dq_des, tau_ff). Runs whose
///    desired positions and velocities are all 0 are torque-controlled: kp = kd = 0 columns.
/// @throws std::runtime_error naming the file and field on unreadable or invalid input.
BenchLog load_bench_log(const std::string& spec);

/// Writes a pmg CSV (all present columns). @throws std::runtime_error if the file cannot be written.
void write_bench_log_csv(const BenchLog& log, const std::string& path);

/// Bench rig: a motor driving a pendulum (rig YAML, see docs/calibration.md).
struct RigConfig {
  std::string source_file;
  // rig: pendulum, angle 0 = hanging down, rotation about the motor axis.
  double mass_kg = 0.0;                ///< pendulum mass [kg], > 0
  double com_m = 0.0;                  ///< distance axis -> centre of mass [m], >= 0
  double link_inertia_kgm2 = 0.0;      ///< link inertia about its centre of mass [kg·m²], >= 0
  double gravity_mps2 = 9.81;          ///< [m/s²], >= 0
  // motor: PD driver tau = kp (q_cmd - q) - kd dq (+ kd dq_cmd + tau_ff), clipped.
  double kp_Nm_per_rad = 0.0;          ///< nominal stiffness used for logs without a kp column, > 0
  double kd_Nms_per_rad = 0.0;         ///< nominal damping used for logs without a kd column, >= 0
  double armature_kgm2 = 0.0;          ///< nominal rotor inertia at the joint [kg·m²], >= 0
  double torque_limit_Nm = std::numeric_limits<double>::infinity();  ///< > 0
  double rate_hz = 1000.0;             ///< driver PD update rate [Hz], > 0
  bool encoder_motor_side = true;      ///< encoder: motor_side | link_side
  /// Multiplies a log's kp/kd columns to get N·m/rad and N·m·s/rad (1 for SI logs; for a servo
  /// whose gain is in firmware units, the nominal N·m/rad per unit; its scale is fitted).
  double log_gain_to_SI = 1.0;
  double sim_dt_s = 0.001;             ///< physics step of the rig simulation [s], in (0, 0.005]

  /// Pendulum inertia about the axis [kg·m²] (without armature).
  double link_inertia_about_axis() const { return link_inertia_kgm2 + mass_kg * com_m * com_m; }
  /// Peak gravity torque m g com [N·m].
  double gravity_torque_Nm() const { return mass_kg * gravity_mps2 * com_m; }
  /// Throws std::runtime_error naming source_file, field and expected range.
  void validate() const;
};

/// Loads a rig YAML file (`rig:` and `motor:` maps, optional `sim:` map with `dt_s`).
/// @throws std::runtime_error naming the file, field and expected range.
RigConfig load_rig_config(const std::string& path);

}  // namespace pmg::calib
