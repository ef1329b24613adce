#pragma once
/// @file task_judge.hpp
/// Success criteria of the teleoperated tasks (issue 14), measured on the object as the paper's
/// Table III defines them ("Teleoperation task Evaluation"), with the failure classified. Pure
/// functions of an object's trajectory (the simulator's truth, sampled at any rate) and the scene;
/// whether the robot fell is the caller's (the HAL supervisor's fall fault), passed in.
/// Frames: W (task_scene.hpp); T = a table's top frame. SI units.
///
///  * Wiping (paper: success rate 0.95): the towel moves laterally across the tabletop by more
///    than 1 m: its path along the table's y axis (back and forth counts, as wiping does; counted
///    in steps of at least `step_m`, so that jitter does not add up) exceeds `min_travel_m`, and the
///    towel stays on the top throughout (centre inside the top, not below it).
///  * Box picking (paper: 0.80): the box is lifted from its table (bottom at least `min_lift_m`
///    above the pick table's top at some time), carried (final centre at least `min_carry_m` from
///    its start, horizontally), and placed on the place table without dropping: at the end it rests
///    (speed below `rest_speed`) with its bottom on the place table's top (within `place_tol_m`),
///    its centre over the top and upright (tilt below `max_tilt_rad`); it never falls (downward
///    speed above `drop_speed`, or its bottom near the floor).

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "pmg/hal/task_scene.hpp"

namespace pmg {

/// One sample of an object's trajectory.
struct TaskObjectSample {
  double t = 0.0;        ///< [s]
  TaskObjectState state; ///< pose and velocity in W
};

/// The verdict of one trial.
struct TaskVerdict {
  bool success = false;
  /// "" on success, else the first failure class: "loss_of_balance", "left_the_table" (wipe),
  /// "too_short" (wipe), "dropped", "not_lifted", "not_carried", "tipped", "not_placed" (box), in this order of precedence.
  /// "tipped": at rest at the end, turned beyond max_tilt_rad; a box still moving at the end (still held) is "not_placed".
  std::string failure;
  std::string detail;    ///< the measured numbers behind the verdict, for the report
  double measure = 0.0;  ///< wipe: lateral path length [m]; box: largest lift of the bottom [m]
};

struct WipeCriteria {
  double min_travel_m = 1.0;  ///< the paper's "more than 1 m"
  double step_m = 0.01;       ///< path counted in steps of at least this [m]
};

/// Judges a wiping trial of the towel @p object (its samples @p traj, the first one the start) on
/// its table. @throws std::invalid_argument on an empty trajectory or an unknown object.
TaskVerdict judgeWipe(const TaskScene& scene, const std::string& object, const std::vector<TaskObjectSample>& traj,
                      bool robot_fell, const WipeCriteria& c = {});

struct BoxCriteria {
  /// The paper lifts the box "to about 30 cm" above its 50 cm table: at least 28 cm (the place table
  /// is 26 cm higher, so merely sliding it across onto that top does not count as a lift).
  double min_lift_m = 0.28;
  double min_carry_m = 0.45;    ///< the paper carries "about 60 cm": at least 45 cm
  double place_tol_m = 0.01;    ///< bottom on the place top within this
  double rest_speed = 0.02;     ///< [m/s] at the end
  double max_tilt_rad = 0.2;    ///< upright at the end
  double drop_speed = 1.0;      ///< [m/s] downward: a fall of about 5 cm or more
  double floor_margin_m = 0.05; ///< bottom this close to the floor = dropped
};

/// An object's tilt [rad], [0, pi]: the angle between its z axis and W's (0: upright). @p q_W: its
/// orientation in W (normalised here). The box judge's "upright" and the bench's logged tilt.
double tiltAngle(const Eigen::Quaterniond& q_W);

/// Judges a box trial of @p object from table @p pick to table @p place. @throws
/// std::invalid_argument on an empty trajectory or unknown names.
TaskVerdict judgeBox(const TaskScene& scene, const std::string& object, const std::string& pick, const std::string& place,
                     const std::vector<TaskObjectSample>& traj, bool robot_fell, const BoxCriteria& c = {});

}  // namespace pmg
