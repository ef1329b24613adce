#include "pmg/hal/task_judge.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg {
namespace {

// A point of W in table frame T (x, y on the top, relative to its centre).
Eigen::Vector2d inTable(const TaskTable& t, const Eigen::Vector3d& p_W) {
  const double dx = p_W.x() - t.pos[0], dy = p_W.y() - t.pos[1];
  const double c = std::cos(t.yaw), s = std::sin(t.yaw);
  return {c * dx + s * dy, -s * dx + c * dy};
}

bool overTop(const TaskTable& t, const Eigen::Vector2d& p_T) {
  return std::abs(p_T.x()) <= 0.5 * t.top_size[0] && std::abs(p_T.y()) <= 0.5 * t.top_size[1];
}

}  // namespace

TaskVerdict judgeWipe(const TaskScene& scene, const std::string& object, const std::vector<TaskObjectSample>& traj,
                      bool robot_fell, const WipeCriteria& c) {
  if (traj.empty()) throw std::invalid_argument("judgeWipe: empty trajectory");
  const TaskObject& o = scene.object(object);
  const TaskTable& t = scene.table(o.on);
  double anchor = inTable(t, traj.front().state.p_W).y(), span_lo = anchor, span_hi = anchor;
  TaskVerdict v;
  double left_at = -1.0;
  for (const auto& s : traj) {
    const Eigen::Vector2d p = inTable(t, s.state.p_W);
    // Lateral path length, counted in steps of at least step_m: jitter below it does not add up.
    if (std::abs(p.y() - anchor) >= c.step_m) {
      v.measure += std::abs(p.y() - anchor);
      anchor = p.y();
    }
    span_lo = std::min(span_lo, p.y());
    span_hi = std::max(span_hi, p.y());
    if (left_at < 0 && (!overTop(t, p) || s.state.p_W.z() < t.height - 0.01)) left_at = s.t;
  }
  v.detail = fmt::format("lateral path {:.3f} m (needs > {:.2f} m) over y in [{:.3f}, {:.3f}] m of the table",
                         v.measure, c.min_travel_m, span_lo, span_hi);
  if (robot_fell) {
    v.failure = "loss_of_balance";
  } else if (left_at >= 0) {
    v.failure = "left_the_table";
    v.detail += fmt::format("; the towel left the top at {:.2f} s", left_at);
  } else if (!(v.measure > c.min_travel_m)) {
    v.failure = "too_short";
  }
  v.success = v.failure.empty();
  return v;
}

double tiltAngle(const Eigen::Quaterniond& q_W) {
  return std::acos(std::clamp(q_W.normalized().toRotationMatrix()(2, 2), -1.0, 1.0));
}

TaskVerdict judgeBox(const TaskScene& scene, const std::string& object, const std::string& pick, const std::string& place,
                     const std::vector<TaskObjectSample>& traj, bool robot_fell, const BoxCriteria& c) {
  if (traj.empty()) throw std::invalid_argument("judgeBox: empty trajectory");
  const TaskObject& o = scene.object(object);
  const TaskTable& tp = scene.table(pick);
  const TaskTable& tq = scene.table(place);
  const double half = 0.5 * o.size[2];
  TaskVerdict v;
  double dropped_at = -1.0, lift = -1e9;
  for (const auto& s : traj) {
    const double bottom = s.state.p_W.z() - half;
    lift = std::max(lift, bottom - tp.height);
    if (dropped_at < 0 && (s.state.v_W.z() < -c.drop_speed || bottom < c.floor_margin_m)) dropped_at = s.t;
  }
  v.measure = lift;
  const TaskObjectState& start = traj.front().state;
  const TaskObjectState& end = traj.back().state;
  const double carry = (end.p_W - start.p_W).head<2>().norm();
  const double bottom_end = end.p_W.z() - half;
  const bool over_place = overTop(tq, inTable(tq, end.p_W));
  const double tilt = tiltAngle(end.q_W);
  v.detail = fmt::format(
      "lift {:.3f} m (needs >= {:.2f}), carried {:.3f} m (>= {:.2f}), end: bottom {:+.3f} m from the place top, "
      "{} it, speed {:.3f} m/s, tilt {:.3f} rad",
      lift, c.min_lift_m, carry, c.min_carry_m, bottom_end - tq.height, over_place ? "over" : "not over", end.v_W.norm(),
      tilt);
  if (robot_fell) {
    v.failure = "loss_of_balance";
  } else if (dropped_at >= 0) {
    v.failure = "dropped";
    v.detail += fmt::format("; fell at {:.2f} s", dropped_at);
  } else if (!(lift >= c.min_lift_m)) {
    v.failure = "not_lifted";
  } else if (!(carry >= c.min_carry_m)) {
    v.failure = "not_carried";
  } else if (tilt > c.max_tilt_rad && end.v_W.norm() <= c.rest_speed) {
    // Set down on its side (at rest); a box still moving at the end (held) is not placed, however it hangs.
    v.failure = "tipped";
  } else if (!over_place || std::abs(bottom_end - tq.height) > c.place_tol_m || end.v_W.norm() > c.rest_speed) {
    v.failure = "not_placed";
  }
  v.success = v.failure.empty();
  return v;
}

}  // namespace pmg
