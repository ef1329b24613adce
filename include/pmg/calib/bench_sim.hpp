#pragma once
/// @file bench_sim.hpp
/// MuJoCo 2.2 simulation of a single-joint bench rig (motor + pendulum), driven by a logged
/// command. One BenchSimulator owns its own mjModel copy and mjData, so one per thread gives
/// parallel rollouts.
///
/// Model (built in code as an MJCF string): a hinge about the world y axis; without backlash the
/// pendulum link hangs on it directly (armature on the hinge). With backlash the hinge carries a
/// rotor body (encoder side) and the link hangs on a second hinge relative to the rotor whose
/// joint limit range [-gap/2, gap/2] is the dead zone (a MuJoCo limit constraint, so stiff
/// contact at any rotor/link inertia ratio stays stable). Angle 0 = hanging down.
/// Each physics step: mj_step1, ActuatorModel::step (driver PD on the delayed logged command, at
/// rate_hz, limits, friction with implicit stiction) -> qfrc_applied of the motor DOF, mj_step2
/// (semi-implicit Euler).

#include <memory>
#include <vector>

#include "pmg/calib/actuator_model.hpp"
#include "pmg/calib/bench_log.hpp"

struct mjModel_;
struct mjData_;

namespace pmg::calib {

/// Everything a rollout needs besides the rig: the fitted driver scales, armature and the
/// extended actuator parameters.
struct RigParams {
  double kp_scale = 1.0;      ///< multiplies the nominal / logged kp (dimensionless)
  double kd_scale = 1.0;      ///< multiplies the nominal / logged kd (dimensionless)
  double armature_kgm2 = 0.0; ///< rotor inertia at the joint [kg·m²]
  ActuatorParams act;         ///< extended effects (act.rate_hz is overwritten by the rig's)
};

/// Output traces of one rollout, one value per log row.
struct RolloutTrace {
  std::vector<double> q;        ///< simulated encoder reading [rad]
  std::vector<double> dq;       ///< simulated motor-side velocity [rad/s]
  std::vector<double> tau_motor;///< motor torque after limits [N·m]
};

class BenchSimulator {
 public:
  /// Builds the MuJoCo model. `with_backlash` adds the rotor body and dead-zone joint.
  /// @throws std::runtime_error with MuJoCo's message if the model does not compile.
  BenchSimulator(const RigConfig& rig, bool with_backlash);
  ~BenchSimulator();
  BenchSimulator(const BenchSimulator&) = delete;
  BenchSimulator& operator=(const BenchSimulator&) = delete;

  bool with_backlash() const { return backlash_; }

  /// Simulates `log` from its first row (initial state from the first measured q, dq).
  /// Returns the sum over rows of (q_sim - q_log)^2 [rad²]. If `trace` is given, it is resized
  /// and filled. Does not throw; returns +inf if the state diverges.
  double rollout(const BenchLog& log, const RigParams& params, RolloutTrace* trace = nullptr);

 private:
  RigConfig rig_;
  bool backlash_;
  mjModel_* model_ = nullptr;
  mjData_* data_ = nullptr;
  ActuatorState state_;
};

}  // namespace pmg::calib
