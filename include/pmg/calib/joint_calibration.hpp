#pragma once
/// @file joint_calibration.hpp
/// Single-joint response calibration on the whole robot (issue 15; the PMG paper's "Sim-to-Real
/// Transfer": each joint in turn, the others held, robot hanging in the gantry, the simulator's
/// response fitted to the real one, PMG eq. 20). Three pieces:
///  1. excitation: per joint, diverse target trajectories around its hold position (quasi-steps of
///     several sizes and both signs, a chirp), continuous (cosine ramps, no target jumps);
///  2. capture: the trajectories run through any pmg::HalBackend (the product's HAL stack with the
///     supervisor: makeHalStack), every other joint held at its hold target with its PD gains; the
///     log holds what the driver was told and what the encoder read, nothing else;
///  3. fit in the whole-robot model: the same excitation replayed on the nominal MuJoCo model of the
///     robot (JointSimulator: every joint, the gantry, the bus latency the captures show), with a
///     catalogue entry's actuator block on the excited joint, its parameter fitted so that the
///     simulated response matches the captured one (fitJointInRobot). Entries are selected by
///     cross-validation over the two training logs and judged against the encoder's noise floor;
///     the held-out log reports the chosen model's error once.
/// Setup/offline code: allocates, throws std::runtime_error / std::invalid_argument naming the
/// joint, field and expected range.

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/bench_log.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/backend.hpp"
#include "pmg/hal/mujoco_backend.hpp"

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
/// @p with_heldout false stops after the training logs (fits need no held-out response).
JointCapture captureJoint(HalBackend& backend, const RobotConfig& robot, int index, const JointExcitation& ex,
                          const Eigen::VectorXd& hold_targets, const std::function<void(const std::string&)>& log,
                          bool with_heldout = true);

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

/// The whole-robot simulator of one fitting thread: pmg::MujocoBackend of a robot config (its
/// `actuator:` blocks are the model's: none for the nominal robot, the joints identified so far
/// when calibrating joint after joint) hanging in the gantry, without contacts (the feet never touch
/// the floor there; ~15x faster), behind a CommandLatencyBackend of the bus latency.
class JointSimulator {
 public:
  /// @throws ConfigError if a block of @p model is invalid.
  JointSimulator(const RobotConfig& model, const MujocoBackendOptions& options, int bus_latency_cycles);
  /// Runs the excitation of joint @p index with @p block on that joint (std::nullopt: the ideal
  /// motor) instead of its configured one, which is restored afterwards.
  JointCapture capture(int index, const std::optional<ActuatorBlock>& block, const JointExcitation& ex,
                       const Eigen::VectorXd& hold_targets, bool with_heldout = true);
  long evaluations() const noexcept { return evaluations_; }

 private:
  RobotConfig robot_;
  MujocoBackend sim_;
  CommandLatencyBackend lagged_;
  std::vector<std::optional<ActuatorBlock>> configured_;
  long evaluations_ = 0;
};

/// Per log of @p sim (train logs, then held-out logs, in capture order; @p sim may lack the held-out
/// ones): sum of squared differences of the
/// robot's and the simulator's joint positions [rad^2] after removing the log's mean difference
/// (an encoder zero offset is pmg_calib_zero's business), and the sample count.
std::vector<std::pair<double, long>> logSquaredErrors(const JointCapture& robot, const JointCapture& sim);

/// A catalogue entry as the whole-robot fit uses it: one parameter (the ActuatorBlock key of
/// docs/calibration.md) searched in [lo, hi] (log-spaced grid when log_scale).
struct RobotFitEntry {
  std::string name;   ///< catalogue name: pd_gain, armature, coulomb_friction, viscous_friction, transport_delay
  std::string key;    ///< kp_scale, armature_kgm2, fc_Nm, fv_Nms_per_rad, delay_s
  double lo = 0.0, hi = 0.0;
  bool log_scale = false;
};
/// The entries fitted by default (the effects a G1 leg actuator shows in pmg_reality_draw's ranges,
/// with margins): pd_gain kp_scale [0.5, 1.6]; armature [0.002, 0.15] kg m^2; coulomb_friction fc
/// [0.05, 8] N m; viscous_friction fv [0.05, 8] N m s/rad; transport_delay [0.5, 30] ms.
const std::vector<RobotFitEntry>& robotFitCatalogue();
/// The actuator block of a parameter map (keys of RobotFitEntry::key; others are an error).
ActuatorBlock blockFromParams(const std::map<std::string, double>& params);

struct RobotFitOptions {
  int threads = 2;            ///< fitting threads (one JointSimulator each), >= 1
  int grid = 7;               ///< coarse grid points per parameter, >= 3
  int refine = 7;             ///< golden-section evaluations around the best grid point, >= 2
  int max_causes = 2;         ///< forward selection stops after this many entries
  double min_cv_gain = 0.25;  ///< an entry must lower the CV residual by this share ...
  double noise_z = 3.0;       ///< ... and by more than noise_z x noise floor ...
  double min_over_floor = 2;  ///< ... and the reference must exceed this multiple of the floor
  void validate() const;      ///< throws std::invalid_argument naming the field
};

/// One fitted model: its entries' parameters, the CV residual over the two training logs (fit on
/// one, score on the other), the gain 1 - cv/cv_reference, and the held-out residual [rad].
struct RobotFitModel {
  std::string name;                       ///< entry added last ("baseline": none)
  std::map<std::string, double> params;   ///< every entry's parameter so far
  /// Per parameter of `params` (same key, same unit): how well the training logs determine it,
  /// the largest deviation of a one-log estimate (fit on the steps alone, on the chirp alone) from
  /// the estimate on both, and at least half the final search bracket (the search's resolution).
  /// pmg_calib_joints writes it as the joint's `actuator_uncertainty:`; training sizes its domain
  /// randomisation from it (training/pmg_train/g1_env.py).
  std::map<std::string, double> uncertainty;
  double cv_rad = 0.0;
  double gain = 0.0;
  double heldout_rad = -1.0;              ///< < 0 where not evaluated (candidates not chosen)
  std::string verdict;                    ///< why it was (not) chosen
};
struct RobotFitResult {
  RobotFitModel baseline;                 ///< the nominal model (no parameter)
  std::vector<RobotFitModel> candidates;  ///< each entry alone (first step of the selection; empty
                                          ///< when the baseline leaves no room above the noise floor)
  std::vector<RobotFitModel> causes;      ///< the chosen entries, in order (params cumulative)
  RobotFitModel extended;                 ///< the final model (= last cause or the baseline)
  ActuatorBlock block;                    ///< extended.params as an actuator block
  long evaluations = 0;                   ///< whole-robot captures simulated
  double wall_s = 0.0;
};
/// Fits joint @p index of the robot whose captures are @p robot_capture (train: 2 logs, held-out:
/// 1) in the whole-robot model: JointSimulator(s) of @p model (the nominal robot config, plus the
/// blocks identified on other joints; joint @p index's own block is ignored) with @p options and
/// the bus latency. Forward selection over robotFitCatalogue() by 2-fold CV over the training logs;
/// significance against @p noise_floor_rad; held-out residuals of the baseline and the chosen
/// chain only.
RobotFitResult fitJointInRobot(const RobotConfig& model, const MujocoBackendOptions& options, int bus_latency_cycles,
                               int index, const JointCapture& robot_capture, const JointExcitation& ex,
                               const Eigen::VectorXd& hold_targets, double noise_floor_rad, const RobotFitOptions& opt);

}  // namespace pmg::calib
