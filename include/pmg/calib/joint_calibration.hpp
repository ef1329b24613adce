#pragma once
/// @file joint_calibration.hpp
/// Single-joint response calibration on the whole robot (issue 15; the PMG paper's "Sim-to-Real
/// Transfer": each joint in turn, the others held, robot hanging in the gantry). Three pieces:
///  1. excitation: per joint, diverse target trajectories around its hold position (quasi-steps of
///     several sizes and both signs, a chirp), continuous (cosine ramps, no target jumps);
///  2. capture: the trajectories run through any pmg::HalBackend (the product's HAL stack with the
///     supervisor: makeHalStack), every other joint held at its hold target with its PD gains; the
///     log holds what the driver was told and what the encoder read, nothing else;
///  3. reduction: with the other joints at their measured positions, one joint of the MuJoCo
///     model becomes a pendulum about its axis: gravity torque -A sin(q - q_down) of the locked
///     subtree (statics: the held joints do hold it) and the locked subtree's inertia M_jj. The
///     dynamics are only approximately those of a locked subtree (the held joints' PD and the
///     gantry are soft), so every verdict is differential against the nominal simulator's own fit
///     (differentialEffects). That pendulum is the bench rig of pmg_calib_dynamics (RigConfig: angle 0 =
///     hanging down), so the catalogue, the selection by cross-validation and the noise floor apply
///     unchanged. The reduction neglects the gantry's compliance (the pelvis sways by millimetres).
/// Setup/offline code: allocates, throws std::runtime_error / std::invalid_argument naming the
/// joint, field and expected range.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/bench_log.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/backend.hpp"

namespace pmg::calib {

/// Excitation of one joint (targets relative to its hold position) [rad, s].
struct JointExcitation {
  double amplitude_rad = 0.15;  ///< largest deviation from the hold position, in (0, 0.5]
  double ramp_s = 0.04;         ///< rise time of a quasi-step (cosine ramp), in [0.01, 1]
  double hold_s = 0.4;          ///< hold after each quasi-step, in [0.1, 5]
  double chirp_s = 3.0;         ///< chirp length (0.5 -> 4 Hz), in [0.5, 20]
  /// Throws std::invalid_argument "JointExcitation.<field> = <v>: expected <range>".
  void validate() const;
};

/// The excitation signals sampled every @p dt [s]: {"steps", "chirp", "mixed"} (train, train,
/// held-out), each starting and ending at 0 with zero slope.
std::vector<std::pair<std::string, std::vector<double>>> excitationSignals(const JointExcitation& ex, double dt);

/// What one joint's capture produced.
struct JointCapture {
  std::string joint;                 ///< robot config name
  int index = -1;                    ///< robot config index
  std::vector<BenchLog> train;       ///< "steps", "chirp" (joint angle frame: encoder readings)
  std::vector<BenchLog> heldout;     ///< "mixed"
  Eigen::VectorXd held_q;            ///< mean encoder readings of every joint during the capture [rad]
  double duration_s = 0.0;           ///< robot time spent
};

/// Runs the excitation of joint @p index through @p backend (which should be the HAL stack with its
/// supervisor, engaged), holding every joint at @p hold_targets (n) with the robot config's PD
/// gains. Log row k: t = time of the reading, q = reading, q_cmd/kp/kd = the command the driver
/// holds from then on (the next exchange's). @p log receives progress lines (may be empty).
/// @throws std::runtime_error on a backend fault or when the supervisor latches damping.
JointCapture captureJoint(HalBackend& backend, const RobotConfig& robot, int index, const JointExcitation& ex,
                          const Eigen::VectorXd& hold_targets, const std::function<void(const std::string&)>& log);

/// A backend whose commands take effect @p cycles HAL cycles late (a delay line of whole commands):
/// the nominal simulator given the bus latency the robot's captures show (bus_latency_cycles).
/// Not real-time safe (setup/offline tool).
class CommandLatencyBackend final : public HalBackend {
 public:
  CommandLatencyBackend(HalBackend& inner, int cycles);
  const char* name() const noexcept override { return "command-latency"; }
  double cyclePeriod() const noexcept override { return inner_.cyclePeriod(); }
  BackendStatus exchange(const LowCommand& command, LowState& state) noexcept override;
  /// Forgets the queued commands (the next @p cycles exchanges repeat the first command).
  void clear() noexcept { queue_.clear(); }

 private:
  HalBackend& inner_;
  int cycles_;
  std::vector<LowCommand> queue_;
};

/// Whole HAL cycles (0..max_cycles) by which @p robot's joint response lags @p sim's on the same
/// commands (least squares on the mean-removed position of each log pair).
int responseLagCycles(const JointCapture& robot, const JointCapture& sim, int max_cycles = 4);

/// RMS [rad] of the robot's joint position minus the simulator's over all logs of the two captures
/// (same commands; each log's mean difference removed, so that an encoder zero offset, which
/// pmg_calib_zero finds, does not count): how wrong the simulation is about this joint's response.
double simulationResidual(const JointCapture& robot, const JointCapture& sim);

/// The bench-rig pendulum equivalent to joint @p index of the robot's MuJoCo 2.2 model (the SIL's
/// nominal model: pmg::loadMujocoModel with its default armature, damping, frictionloss), base
/// fixed upright, every joint at @p held_q (n, model angles).
struct JointRig {
  RigConfig rig;                  ///< mass = subtree mass, com_m / link inertia from A and M_jj
  double q_down_rad = 0.0;        ///< joint angle at which the locked subtree hangs straight down
  double gravity_amplitude_Nm = 0.0;  ///< A: gravity torque = -A sin(q - q_down)
  /// Apparent inertia about the axis with every other DOF free, 1 / (M^-1)_jj, minus the model
  /// armature [kg m^2] (reported: the truth lies between this and the locked value, since the held
  /// joints' PD and the gantry are soft; the rig uses the locked value).
  double inertia_kgm2 = 0.0;
  double inertia_locked_kgm2 = 0.0;  ///< M_jj minus the model armature (others locked): the rig's [kg m^2]
  double fit_residual_Nm = 0.0;   ///< largest |gravity torque - sinusoid| over the samples
};
/// @throws std::runtime_error if the model cannot be loaded or the joint is not in it.
JointRig rigForJoint(const RobotConfig& robot, int index, const Eigen::VectorXd& held_q);

/// Differential verdict of one joint (for joints whose simulationResidual exceeds the gate; a
/// joint the simulator already reproduces gets nothing named): the same excitation and the same reduction on the nominal
/// simulator (the control experiment: the SIL's MuJoCo model in the gantry, no hidden effects) and
/// on the robot, both calibrated by calibrate_dynamics. A one-joint pendulum lacks the coupling to
/// the held joints and the gantry, and the model's passive joint friction and damping; those
/// misfits show in both fits alike. What the robot's fit has and the simulator's has not is what
/// the simulation gets wrong:
///  - "pd_gain": |kp_scale_robot / kp_scale_sim - 1| > 0.06 (params kp_scale = that ratio);
///  - "armature": armature_robot - armature_sim > max(0.004 kg m^2, 10 % of the simulator's
///    inertia about the axis) (params armature_kgm2 = model armature + that excess);
///  - a cause named on the robot and not on the simulator (the same entry or one nested in it), or
///    named on both with its first parameter at least 1.5x the simulator's (params: the robot's).
/// Sorted by relative size (baseline deviations) then in the robot's naming order.
struct JointEffect {
  std::string name;                       ///< catalogue entry, "pd_gain" or "armature"
  std::map<std::string, double> params;   ///< catalogue parameter keys (docs/calibration.md)
  double size = 0.0;                      ///< relative deviation, or the cause's CV gain on the robot
};
std::vector<JointEffect> differentialEffects(const RigConfig& rig, const std::map<std::string, double>& sim_baseline,
                                             const std::vector<std::pair<std::string, std::map<std::string, double>>>& sim_causes,
                                             const std::map<std::string, double>& robot_baseline,
                                             const std::vector<std::pair<std::string, std::map<std::string, double>>>& robot_causes,
                                             const std::vector<double>& robot_cause_gains);
/// The actuator block for the robot config: kp/kd scales relative to the simulator's fit, armature
/// = the model's plus the excess, and the parameters of the named effects (nothing else).
ActuatorBlock effectsBlock(const RigConfig& rig, const std::map<std::string, double>& sim_baseline,
                           const std::map<std::string, double>& robot_baseline, const std::vector<JointEffect>& effects);

/// @p log in the rig's angle frame: q, q_cmd shifted by -q_down.
BenchLog toRigFrame(const BenchLog& log, double q_down);

}  // namespace pmg::calib
