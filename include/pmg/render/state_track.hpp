#pragma once
/// @file state_track.hpp
/// The robot's recorded motion, read back from a pmg_controller LCM event log (lcm-logger format,
/// written by `pmg_controller --log`): one StateSample per `PMG_STATE` message
/// (pmg_lcm::controller_state_t, lcmtypes/controller_state_t.lcm). Setup code: allocates, throws.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace pmg::render {

/// The pose of the robot at one controller tick, as recorded in the telemetry.
struct StateSample {
  double t = 0.0;                 ///< controller time [s] (utime · 1e-6; simulated time in lockstep mode)
  Eigen::VectorXd q;              ///< measured joint positions (n) [rad], robot-config joint order
  Eigen::Vector3d p_WB{0, 0, 0};  ///< pelvis (base B) position in the world frame W [m]
  Eigen::Vector4d quat_WB{1, 0, 0, 0};  ///< pelvis orientation in W, unit quaternion (w, x, y, z)
  Eigen::Vector3d command{0, 0, 0};     ///< commanded (vx [m/s], vy [m/s], wz [rad/s]) of that tick
  double phase = 0.0;             ///< gait phase φ in [0, 1) (PMG generator)
  double period = 0.0;            ///< gait period T_u [s] of that tick
  int mode = 0;                   ///< controller mode (0 passive, 1 soft stand, 2 PMG, 3 damping)
};

/// All samples of one log, sorted by time (the log order; a non-monotonic log is an error).
struct StateTrack {
  std::string source;                ///< the log file the track was read from
  std::vector<StateSample> samples;  ///< ≥ 1 sample, strictly increasing t

  double startTime() const { return samples.front().t; }
  double endTime() const { return samples.back().t; }
  /// Index of the sample shown at time @p t [s]: the last sample with t_i ≤ t (zero-order hold,
  /// like the controller's telemetry), clamped to the first/last sample outside the log's span.
  std::size_t indexAt(double t) const;
  const StateSample& at(double t) const { return samples[indexAt(t)]; }
};

/// Reads every message on @p channel of the LCM event log @p log_path.
/// @param num_joints expected `num_joints` of each message (the robot config's joint count).
/// @throws std::runtime_error naming the file (and the message time / field where it applies) if
///   the file cannot be opened, a message on @p channel does not decode, its num_joints differs
///   from @p num_joints, a value is not finite, the quaternion norm is outside [0.9, 1.1], time
///   goes backwards, or the channel has no message at all. The quaternion is normalised.
StateTrack readStateTrack(const std::string& log_path, int num_joints,
                          const std::string& channel = "PMG_STATE");

/// @p count times evenly spaced over [@p t0, @p t1] [s], both ends included (count = 1: t0).
/// @throws std::invalid_argument if count < 1 or t1 < t0.
std::vector<double> evenlySpacedTimes(double t0, double t1, int count);

}  // namespace pmg::render
