#pragma once
/// @file object_track.hpp
/// Recorded poses of a scene's free objects (a task scene's towel or box, issue 14) for
/// pmg_render_log: the robot's pose comes from the controller's telemetry (state_track.hpp), the
/// objects' from a CSV the task bench writes beside it (`pmg_teleop_bench`: trial_<k>_objects.csv).
/// Setup code: allocates, throws.
///
/// CSV format: a header line `t,body,x,y,z,qw,qx,qy,qz`, then one row per object per sample:
/// t the simulated time [s] (the controller's clock: same time base as the telemetry), body the
/// MuJoCo body name, (x, y, z) its position in the world frame W [m], (qw, qx, qy, qz) its
/// orientation in W (unit quaternion; normalised on reading). Per body, t must increase.
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace pmg::render {

/// One object's pose at one time, in the world frame W.
struct ObjectPose {
  double t = 0.0;                     ///< [s]
  Eigen::Vector3d p_W{0, 0, 0};       ///< position [m]
  Eigen::Vector4d quat_W{1, 0, 0, 0}; ///< orientation (w, x, y, z), unit
};

/// The poses of every object of one CSV, per body, sorted by time.
struct ObjectTrack {
  std::string source;                                 ///< the CSV it was read from
  std::map<std::string, std::vector<ObjectPose>> bodies;  ///< body name -> ≥ 1 pose, strictly increasing t
  /// Pose of @p body at time @p t [s]: the last pose with t_i ≤ t (zero-order hold), clamped to
  /// the first/last pose outside its span. @throws std::out_of_range for a body not in the track.
  const ObjectPose& at(const std::string& body, double t) const;
};

/// Reads an object track CSV (format above).
/// @throws std::runtime_error naming the file, line and field if the file cannot be opened, the
///   header differs, a row has another column count, a number does not parse or is not finite, a
///   quaternion's norm is outside [0.9, 1.1], a body's time does not increase, or there is no row.
ObjectTrack readObjectTrack(const std::string& csv_path);

}  // namespace pmg::render
