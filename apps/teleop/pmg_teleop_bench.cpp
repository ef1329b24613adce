// pmg_teleop_bench: teleoperated tasks in the SIL, scored like the paper's Table III (issue 14).
// Each trial draws the task scene (config/tasks/<task>_scene.yaml, include/pmg/hal/task_scene.hpp),
// runs pmg_controller's composition root (ControllerApp: teleop mode with arm IK, shaper, PMG + GCO,
// the teleop policy, the HAL supervisor) over the MuJoCo 2.2 SIL of the robot in that scene, in
// lockstep, and a scripted operator drives it only through the VR stream a headset would send
// (headset and controller poses, grips, buttons: pmg::teleop::VrSample, as the LCM receiver
// decodes it). The operator sees what a person in the headset sees: the objects' and the robot
// hand's poses relative to the robot's torso, and the robot's place in the room, with noise and
// latency (config/tasks/<task>_operator.yaml); it never reads anything else of the simulator. The
// object's trajectory is judged by include/pmg/hal/task_judge.hpp.
//
// Two operators: wiping (runWipe, config/tasks/wipe_operator.yaml) and box carrying (runBox,
// config/tasks/box_operator.yaml), each a small state machine.
//
//   pmg_teleop_bench --task wipe|box --trials 20 [--seed S] --out DIR [--controller CONFIG] [--operator FILE] [--no-figures]
//
// Writes DIR/summary.json = {"task", "trials", "successes", "success_rate", "paper_success_rate",
// "failures": [{"trial", "reason", "detail"}], "trial_results": [...], "figures": {"success"|"failure":
// {"trial", "log", "objects", "scene", "strip", "trace"}}} and DIR/trial_<k>.csv (t, phase of the
// operator, pelvis, working hand and object positions in W, headset, teleop command), the scene
// DIR/trial_<k>_scene.xml, and for the first success and the first failure the controller's event log
// trial_<k>.lcmlog, the object track trial_<k>_objects.csv, a frame strip <success|failure>_trial_<k>_strip.png
// (pmg_render_log, through scripts/render_sil.sh: it starts Xvfb when there is no display)
// and a trace plot <success|failure>_trial_<k>_trace.png (scripts/plot_teleop_trial.py).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <ostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/yaml_archive.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/controller/sil_eval.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/task_judge.hpp"
#include "pmg/hal/task_scene.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

// ---- The operators' parameters -------------------------------------------------------------------
// What every scripted operator has: what it sees, how it walks the robot (leaning: walkCommand), how
// fast it corrects a hand, how long a trial may last.
struct OperatorCommon {
  double view_noise_m = 0.005;      ///< std. dev. of every position the operator sees [m]
  double view_latency_s = 0.1;      ///< what the operator sees is this old [s] (video + reaction)
  double settle_s = 1.0;            ///< standing before engaging [s]
  double walk_gain = 1.0;           ///< commanded speed per metre of position error [1/s]
  double max_speed = 0.15;          ///< [m/s]
  double min_speed = 0.06;          ///< commanded at least this while not arrived [m/s]
  double walk_integral_gain = 0.5;  ///< integral action on the place error [1/s^2]
  double arrive_tol_m = 0.03;       ///< a walk ends within this [m]
  double hand_gain = 0.5;           ///< fraction of the seen hand error corrected per second [1/s]
  double max_trial_s = 45.0;        ///< the trial ends here [s]
  template <class A>
  void Serialize(A* a) {
    a->Visit("view_noise_m", &view_noise_m, "[m]");
    a->Visit("view_latency_s", &view_latency_s, "[s]");
    a->Visit("settle_s", &settle_s, "[s]");
    a->Visit("walk_gain", &walk_gain, "[1/s]");
    a->Visit("max_speed", &max_speed, "[m/s]");
    a->Visit("min_speed", &min_speed, "[m/s]");
    a->Visit("walk_integral_gain", &walk_integral_gain, "[1/s^2]");
    a->Visit("arrive_tol_m", &arrive_tol_m, "[m]");
    a->Visit("hand_gain", &hand_gain, "[1/s]");
    a->Visit("max_trial_s", &max_trial_s, "[s]");
  }
  std::string validate() const {
    if (!(view_noise_m >= 0 && view_noise_m < 0.05)) return "view_noise_m: expected [0, 0.05) m";
    if (!(view_latency_s >= 0 && view_latency_s <= 1)) return "view_latency_s: expected [0, 1] s";
    if (!(max_speed > 0 && max_speed <= 0.5)) return "max_speed: expected (0, 0.5] m/s";
    if (!(hand_gain > 0 && hand_gain <= 10)) return "hand_gain: expected (0, 10] 1/s";
    if (!(max_trial_s > settle_s && max_trial_s <= 300)) return "max_trial_s: expected (settle_s, 300] s";
    return "";
  }
};

// The wiping operator (config/tasks/wipe_operator.yaml).
struct OperatorConfig : OperatorCommon {
  double stand_off_m = 0.22;        ///< pelvis distance from the table's near edge when working [m]
  double hand_lateral_m = 0.15;     ///< the working hand's lateral offset from the pelvis [m]
  double hover_m = 0.06;            ///< hand above the towel before pressing [m]
  double press_m = 0.015;           ///< hand target below the towel's top [m]
  double wipe_speed = 0.10;         ///< lateral walking speed while wiping [m/s]
  double wipe_margin_m = 0.20;      ///< turn back this far from the table's end [m]
  double wipe_path_m = 1.15;        ///< the operator stops once the towel has moved this far (seen) [m]
  double path_smoothing_s = 0.3;    ///< the operator judges the towel's travel by eye: its seen position averaged over this long [s]
  double look_down_rad = 0.0;       ///< headset pitch while working (beyond 0.25 rad dead band: the torso bends)
  double crouch_m = 0.0;            ///< headset lowered this much while working (beyond 0.03 m: the robot squats)
  double yaw_gain = 0.0;            ///< commanded yaw rate per radian of heading away from the table [1/s] (0: off)
  double stand_off_far_m = 0.30;    ///< pelvis distance from the table's edge while raising the hand [m]
  double clearance_m = 0.05;        ///< the raised hand this much above the hover height [m]
  double raise_margin_m = 0.03;     ///< walk in once the hand is seen within this of its raised height (hover + clearance) [m]
  double transit_height_m = 0.18;   ///< reaching: the travelling hand's height above the top [m]
  double transit_tol_m = 0.0;       ///< reaching: a hand seen farther than this (horizontally) from its aim travels at the raised height, then descends (0: off) [m]
  double grab_inset_m = 0.08;       ///< the hand aims this far short of the towel's centre (its near part)
  double lift_s = 0.8;              ///< placing the hand again: lift it straight up this long first [s]
  double press_s = 1.5;             ///< pressing before walking [s]
  double keep_from_edge_m = 0.27;   ///< while wiping, keep the towel's centre this far from the table's near edge [m]
  double keep_gain = 1.0;           ///< hand forward speed per metre of that error [1/s] (at most 0.05 m/s)
  double max_lead_m = 1.0;          ///< the operator's hand leads the robot hand it sees by at most this (robot scale) [m]
  /// Pinned against the table: the pelvis seen more than unpin_m past its working place for unpin_s
  /// while closing in, reaching or pressing (the crouched thighs wedged under the top's edge, the
  /// robot not stepping back) makes the operator stand up, step back to stand_off_far_m and close in
  /// again. 0: off [m]
  double unpin_m = 0.0;
  double unpin_s = 2.0;             ///< [s]
  /// The keep-from-edge correction moves the wrist at most this far beyond its aim at the towel
  /// (grab_inset_m short of its seen centre). Unbounded, a hand that no longer touched the towel
  /// moved on forward (the towel did not come), out over it to the edge of its reach, pressing
  /// nothing [m]. Negative: unbounded.
  double keep_reach_m = -1.0;
  /// Crouch and look down only once at the working place (from the reach on), walking in upright:
  /// crouched and bent, the robot overshoots its place by 4-20 cm and walks into the table.
  bool crouch_in_place = false;
  /// With crouch_in_place, the first reach keeps the hand at transit height for this long after the
  /// crouch begins, and until the pelvis is seen back within 2 arrive_tol_m of its place (at most 6 s
  /// in all): crouching and bending, the robot sways back by up to 0.2 m, and a hand already down
  /// drags the towel with it and holds the robot there [s].
  double crouch_settle_s = 0.0;
  /// The walks from afar (the approach and the walk in) steer by where the robot will be, not where
  /// it is: the place error is taken from the seen pelvis plus lead_s times its seen velocity (the
  /// robot takes a step or two to stop, and a P controller on the present place overshot by up to
  /// 0.16 m) [s]. Holding a place, the sway of the steps is no velocity to steer by. 0: off.
  double lead_s = 0.0;
  /// In those walks the integral action accumulates only within this distance of the place (a long
  /// approach winds it up to its bound and the robot arrives at full lean) [m]. 0: everywhere.
  double integral_zone_m = 0.0;
  double regrab_offset_m = 0.10;    ///< while wiping, a hand seen this far beside the towel's centre has slipped: lift and place it again [m]
  bool palm_down = false;           ///< with the grip squeezed, the controller turns the hand over so that its palm (the flat side of the scene's hand pad) faces down and its fingers point forward
  double palm_pitch_rad = 0.0;      ///< ... the fingers this far below the torso's forward axis (frame T), so the pad's tip, not the wrist housing, touches first [rad]
  double palm_turn_s = 1.0;         ///< ... over this long [s]
  double palm_level_gain = 0.0;     ///< palm_down: the operator levels the fingers it sees (their elevation in the room, 0.1 s late), turning its controller about the torso's lateral axis at this rate per radian [1/s] (0: off; the arm IK trades the hand's orientation for its position, and a pitched pad touches with its edge)
  /// Strokes that turn back at an end of the table (wipe_margin_m) slide their window inward by what
  /// they fell short, so that the next stroke back is a full 2 x stroke_m: a towel lying near an end
  /// otherwise moved about half as far per stroke (held-out seed 1019: 0.74 m in 90 s). Tried, not
  /// kept (docs/teleop.md).
  bool stroke_keep_length = false;
  double stroke_m = 0.0;            ///< > 0: wipe by arm strokes, the robot standing at its working place: the hand sweeps the towel this far to either side of where it pressed (0: walk sideways with the hand on the towel) [m]
  double stroke_speed = 0.20;       ///< the hand's lateral speed along a stroke [m/s]
  double stroke_press_m = 0.03;     ///< while stroking, the operator's hand leads the robot hand it sees by at most this downwards (robot scale): a light press that the arm can drag sideways [m]
  template <class A>
  void Serialize(A* a) {
    OperatorCommon::Serialize(a);
    a->Visit("stand_off_m", &stand_off_m, "[m]");
    a->Visit("hand_lateral_m", &hand_lateral_m, "[m]");
    a->Visit("hover_m", &hover_m, "[m]");
    a->Visit("press_m", &press_m, "[m]");
    a->Visit("wipe_speed", &wipe_speed, "[m/s]");
    a->Visit("wipe_margin_m", &wipe_margin_m, "[m]");
    a->Visit("wipe_path_m", &wipe_path_m, "[m]");
    a->Visit("path_smoothing_s", &path_smoothing_s, "[s]");
    a->Visit("look_down_rad", &look_down_rad, "[rad]");
    a->Visit("crouch_m", &crouch_m, "[m]");
    a->Visit("yaw_gain", &yaw_gain, "[1/s]");
    a->Visit("palm_down", &palm_down, "true | false");
    a->Visit("palm_pitch_rad", &palm_pitch_rad, "[rad]");
    a->Visit("palm_turn_s", &palm_turn_s, "[s]");
    a->Visit("palm_level_gain", &palm_level_gain, "[1/s] (0: off)");
    a->Visit("stroke_m", &stroke_m, "[m] (0: walk sideways)");
    a->Visit("stroke_keep_length", &stroke_keep_length, "true | false");
    a->Visit("stroke_speed", &stroke_speed, "[m/s]");
    a->Visit("stroke_press_m", &stroke_press_m, "[m]");
    a->Visit("stand_off_far_m", &stand_off_far_m, "[m]");
    a->Visit("clearance_m", &clearance_m, "[m]");
    a->Visit("raise_margin_m", &raise_margin_m, "[m]");
    a->Visit("transit_tol_m", &transit_tol_m, "[m]");
    a->Visit("transit_height_m", &transit_height_m, "[m]");
    a->Visit("grab_inset_m", &grab_inset_m, "[m]");
    a->Visit("regrab_offset_m", &regrab_offset_m, "[m]");
    a->Visit("lift_s", &lift_s, "[s]");
    a->Visit("press_s", &press_s, "[s]");
    a->Visit("keep_from_edge_m", &keep_from_edge_m, "[m]");
    a->Visit("keep_gain", &keep_gain, "[1/s]");
    a->Visit("max_lead_m", &max_lead_m, "[m]");
    a->Visit("unpin_m", &unpin_m, "[m] (0: off)");
    a->Visit("unpin_s", &unpin_s, "[s]");
    a->Visit("crouch_in_place", &crouch_in_place, "true | false");
    a->Visit("crouch_settle_s", &crouch_settle_s, "[s]");
    a->Visit("lead_s", &lead_s, "the walks from afar steer by the seen place plus lead_s x the seen velocity [s], [0, 2] (0: off)");
    a->Visit("integral_zone_m", &integral_zone_m, "in those walks integrate the place error only within this distance [m], [0, 2] (0: everywhere)");
    a->Visit("keep_reach_m", &keep_reach_m, "[m] (negative: unbounded)");
  }
  std::string validate() const {
    if (std::string e = OperatorCommon::validate(); !e.empty()) return e;
    if (!(wipe_speed > 0 && wipe_speed <= 0.4)) return "wipe_speed: expected (0, 0.4] m/s";
    if (!(path_smoothing_s > 0 && path_smoothing_s <= 5)) return "path_smoothing_s: expected (0, 5] s";
    if (!(regrab_offset_m > 0 && regrab_offset_m <= 0.5)) return "regrab_offset_m: expected (0, 0.5] m";
    if (!(lift_s >= 0 && lift_s <= 5)) return "lift_s: expected [0, 5] s";
    if (!(press_s >= 0 && press_s <= 10)) return "press_s: expected [0, 10] s";
    if (!(keep_from_edge_m >= 0.15 && keep_from_edge_m <= 1.0)) return "keep_from_edge_m: expected [0.15, 1] m (half the towel at least)";
    if (!(keep_gain >= 0 && keep_gain <= 10)) return "keep_gain: expected [0, 10] 1/s";
    if (!(max_lead_m > 0 && max_lead_m <= 1.0)) return "max_lead_m: expected (0, 1] m";
    if (!(clearance_m >= 0 && clearance_m <= 0.5)) return "clearance_m: expected [0, 0.5] m";
    if (!(raise_margin_m >= 0 && raise_margin_m <= hover_m + clearance_m))
      return "raise_margin_m: expected [0, hover_m + clearance_m] m";
    if (!(transit_tol_m >= 0 && transit_tol_m <= 0.5)) return "transit_tol_m: expected [0, 0.5] m (0: off)";
    if (!(transit_height_m >= hover_m && transit_height_m <= 0.5)) return "transit_height_m: expected [hover_m, 0.5] m";
    if (!(std::abs(palm_pitch_rad) <= 0.8)) return "palm_pitch_rad: expected [-0.8, 0.8] rad";
    if (!(palm_turn_s > 0 && palm_turn_s <= 10)) return "palm_turn_s: expected (0, 10] s";
    if (!(palm_level_gain >= 0 && palm_level_gain <= 10)) return "palm_level_gain: expected [0, 10] 1/s (0: off)";
    if (!(stroke_m >= 0 && stroke_m <= 0.3)) return "stroke_m: expected [0, 0.3] m (0: walk sideways)";
    if (!(stroke_speed > 0 && stroke_speed <= 0.5)) return "stroke_speed: expected (0, 0.5] m/s";
    if (!(stroke_press_m > 0 && stroke_press_m <= max_lead_m)) return "stroke_press_m: expected (0, max_lead_m] m";
    if (!(unpin_m >= 0 && unpin_m <= 0.3)) return "unpin_m: expected [0, 0.3] m (0: off)";
    if (!(unpin_s >= 0.5 && unpin_s <= 20)) return "unpin_s: expected [0.5, 20] s";
    if (!(crouch_settle_s >= 0 && crouch_settle_s <= 6)) return "crouch_settle_s: expected [0, 6] s";
    if (!(lead_s >= 0 && lead_s <= 2)) return "lead_s: expected [0, 2] s";
    if (!(integral_zone_m >= 0 && integral_zone_m <= 2)) return "integral_zone_m: expected [0, 2] m";
    if (!(keep_reach_m >= -1.0 && keep_reach_m <= 0.5)) return "keep_reach_m: expected [-1, 0.5] m (negative: unbounded)";
    return "";
  }
};

// What the operator sees: a delayed, noisy copy of a position.
class View {
 public:
  View(double latency, double noise, std::mt19937_64& rng) : latency_(latency), noise_(noise), rng_(rng) {}
  void push(double t, const Vector3d& p) { buf_.push_back({t, p}); }
  Vector3d seen(double t) {
    while (buf_.size() > 1 && buf_[1].first <= t - latency_) buf_.pop_front();
    std::normal_distribution<double> n(0.0, noise_);
    return buf_.front().second + (noise_ > 0 ? Vector3d(n(rng_), n(rng_), n(rng_)) : Vector3d::Zero());
  }

 private:
  double latency_, noise_;
  std::mt19937_64& rng_;
  std::deque<std::pair<double, Vector3d>> buf_;
};

double yawOf(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

// The headset displacement that makes teleop command velocity v (body frame, 2D), given its
// dead band and gain (the inverse of TeleopMode's mapping).
Eigen::Vector2d headFor(const Eigen::Vector2d& v, double deadband, double gain) {
  const double s = v.norm();
  if (s < 1e-4) return Eigen::Vector2d::Zero();
  return (s / gain + deadband) * v / s;
}

// The headset yaw that makes teleop command yaw rate w [rad/s], given its dead band [rad] and gain
// [1/s] (the inverse of TeleopMode's mapping; 0 for w = 0).
double headYawFor(double w, double deadband, double gain) {
  if (w == 0.0) return 0.0;
  return (w > 0 ? 1.0 : -1.0) * (std::abs(w) / gain + deadband);
}

// The robot's velocity in the room as the operator judges it from the seen (noisy, late) pelvis
// positions: the mean of the newest 10 samples against the mean of the 10 taken 20 ticks before
// them, over the time between (at 100 Hz and 5 mm of noise: about 1 cm/s of noise, 0.25 s late).
class SeenVelocity {
 public:
  Eigen::Vector2d update(const Vector3d& p_seen, double t) {
    buf_[n_ % kN] = {t, p_seen.head<2>()};
    ++n_;
    if (n_ < kN) return Eigen::Vector2d::Zero();
    Eigen::Vector2d old = Eigen::Vector2d::Zero(), now = Eigen::Vector2d::Zero();
    double t_old = 0.0, t_now = 0.0;
    for (std::size_t i = 0; i < 10; ++i) {
      const auto& o = buf_[(n_ + i) % kN];           // the oldest ten
      const auto& w = buf_[(n_ + kN - 10 + i) % kN];  // the newest ten
      old += o.second / 10.0, t_old += o.first / 10.0;
      now += w.second / 10.0, t_now += w.first / 10.0;
    }
    return t_now > t_old ? Eigen::Vector2d((now - old) / (t_now - t_old)) : Eigen::Vector2d::Zero();
  }
 private:
  static constexpr std::size_t kN = 30;
  std::array<std::pair<double, Eigen::Vector2d>, kN> buf_{};
  std::size_t n_ = 0;
};

// Locomotion by leaning: a P controller on the robot's place (W), with integral action (the operator
// leans further while the robot does not get there, bounded; only within @p integral_zone_m of the
// place when that is > 0) and a minimum speed (small steps are not walked); with @p lead_s > 0 the
// error is taken from where the robot will be (seen place + lead_s x seen velocity @p v_seen_W). The
// result is the body-frame velocity the headset displacement must command. Returns the distance left
// [m] (from the seen place). Op: an operator config (OperatorCommon).
template <class Op>
double walkCommand(const Op& op, const Eigen::Vector2d& target_W, const Vector3d& pelvis_W, double yaw_seen, double max_speed,
                   double dt, Eigen::Vector2d* walk_integral, Eigen::Vector2d* v_body,
                   const Eigen::Vector2d& v_seen_W = Eigen::Vector2d::Zero(), double lead_s = 0.0, double integral_zone_m = 0.0) {
  const Eigen::Vector2d e_now = target_W - pelvis_W.head<2>();
  const Eigen::Vector2d e = e_now - lead_s * v_seen_W;
  if (integral_zone_m <= 0.0 || e_now.norm() < integral_zone_m) *walk_integral += e * dt;
  const double imax = op.max_speed / std::max(op.walk_integral_gain, 1e-9);
  if (walk_integral->norm() > imax) *walk_integral *= imax / walk_integral->norm();
  Eigen::Vector2d v = op.walk_gain * e + op.walk_integral_gain * *walk_integral;
  if (v.norm() > max_speed) v *= max_speed / v.norm();
  // (Braking, when the lead sees the robot past its place, is not raised to min_speed.)
  if (e_now.norm() > op.arrive_tol_m && v.norm() < op.min_speed && v.norm() > 0.0 && (lead_s <= 0.0 || v.dot(e_now) > 0.0))
    v *= op.min_speed / v.norm();
  *v_body = Eigen::Rotation2Dd(-yaw_seen) * v;
  return e_now.norm();
}

// A body's position in the world frame W [m] (mjData::xpos).
Vector3d bodyPos(const mjData* d, int body) { return Vector3d(d->xpos[3 * body], d->xpos[3 * body + 1], d->xpos[3 * body + 2]); }

// Each hand's contact forces on @p body now, for the trace [N]: [0, 1] the normal force through every
// geom of the left / right hand's subtree (rooted at subtree_root, e.g. the wrist roll link), [2, 3]
// the normal force through its geom pad[h] alone (-1: none); [4, 5] the vertical (W z, up +) part of
// the whole force that subtree applies to @p body (normal and friction: what holds it up), [6, 7] the
// vertical part of the normal forces alone (negative: the squeeze pushes the body down, as where a
// housing presses on a top edge). MuJoCo's mj_contactForce gives the force in the contact frame (rows
// of mjContact::frame: the normal, from geom1 to geom2, then the two tangents); it is the force geom1
// applies to geom2.
std::array<double, 8> contactForces(const mjModel* m, const mjData* d, int body, const std::array<int, 2>& subtree_root,
                                    const std::array<int, 2>& pad = {-1, -1}) {
  std::array<double, 8> n{};
  auto inSubtree = [&](int b, int root) {
    for (; b > 0; b = m->body_parentid[b])
      if (b == root) return true;
    return false;
  };
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    const int b1 = m->geom_bodyid[c.geom1], b2 = m->geom_bodyid[c.geom2];
    const int other = b1 == body ? b2 : (b2 == body ? b1 : -1);
    if (other < 0) continue;
    mjtNum f[6];
    mj_contactForce(m, d, i, f);
    const double sign = b2 == body ? 1.0 : -1.0;  // the force on @p body
    const double normal_z = sign * f[0] * c.frame[2];
    const double total_z = sign * (f[0] * c.frame[2] + f[1] * c.frame[5] + f[2] * c.frame[8]);
    for (std::size_t h = 0; h < 2; ++h) {
      if (inSubtree(other, subtree_root[h])) {
        n[h] += std::abs(f[0]);
        n[4 + h] += total_z;
        n[6 + h] += normal_z;
      }
      if (pad[h] >= 0 && (c.geom1 == pad[h] || c.geom2 == pad[h])) n[2 + h] += std::abs(f[0]);
    }
  }
  return n;
}

// Where the operator holds a controller before squeezing its grip: where the teleop mapping
// (p_T = c_T + s (p_H - c_H)) puts the robot hand now (seen at hand_R, frame R), so that the arm does
// not jump when it starts to follow. c_T: the robot's shoulder centre; frame H: the headset's.
Vector3d controllerAtRobotHand(const mjData* d, int shoulder_l, int shoulder_r, const Vector3d& torso_p,
                               const Eigen::AngleAxisd& unyaw, const pmg::teleop::TeleopConfig& tc, const Vector3d& hand_R) {
  const Vector3d sh = 0.5 * (bodyPos(d, shoulder_l) + bodyPos(d, shoulder_r));
  const Vector3d c_R = unyaw * (sh - torso_p);
  const Vector3d c_H(tc.operator_shoulder_center_m[0], tc.operator_shoulder_center_m[1], tc.operator_shoulder_center_m[2]);
  return c_H + (hand_R - c_R) / tc.arm_scale;
}

// As controllerAtRobotHand, for a robot whose torso is bent or leaning: the mapping's frame T is the
// torso link with its pitch and roll (which the operator sees), not only its yaw. hand_R: the seen
// robot hand (frame R); unyaw: W -> R.
Vector3d controllerAtRobotHandBent(const mjData* d, int torso, int shoulder_l, int shoulder_r, const Eigen::AngleAxisd& unyaw,
                                  const pmg::teleop::TeleopConfig& tc, const Vector3d& hand_R) {
  const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> R_WT(d->xmat + 9 * torso);
  const Eigen::Matrix3d R_TR = R_WT.transpose() * unyaw.inverse().toRotationMatrix();  // R -> T
  const Vector3d c_T = R_WT.transpose() * (0.5 * (bodyPos(d, shoulder_l) + bodyPos(d, shoulder_r)) - bodyPos(d, torso));
  const Vector3d c_H(tc.operator_shoulder_center_m[0], tc.operator_shoulder_center_m[1], tc.operator_shoulder_center_m[2]);
  return c_H + (R_TR * hand_R - c_T) / tc.arm_scale;
}

// One line of an object track (include/pmg/render/object_track.hpp).
void writeObjectPose(std::ostream& out, double t, const std::string& name, const pmg::TaskObjectState& obj) {
  out << fmt::format("{:.2f},task_{},{:.5f},{:.5f},{:.5f},{:.6f},{:.6f},{:.6f},{:.6f}\n", t, name, obj.p_W.x(), obj.p_W.y(),
                     obj.p_W.z(), obj.q_W.w(), obj.q_W.x(), obj.q_W.y(), obj.q_W.z());
}

// What every trial sets up: the drawn scene composed with the robot (trial_<k>_scene.xml), the
// controller over its MuJoCo SIL with its telemetry logged (trial_<k>.lcmlog, for the frame strips),
// the bodies the operator looks at, and the object track (trial_<k>_objects.csv).
struct TrialRig {
  pmg::TaskScene scene;
  pmg::ControllerConfig config;
  std::unique_ptr<pmg::ControllerApp> app;
  pmg::MujocoBackend* sim = nullptr;
  int torso = -1, shoulder_l = -1, shoulder_r = -1;
  std::ofstream objects_csv;

  TrialRig(int trial, std::uint64_t seed, const pmg::TaskScene& base_scene, const pmg::ControllerConfig& base_config,
           const fs::path& out_dir)
      : scene(pmg::drawTaskTrial(base_scene, seed)), config(base_config) {
    config.robot = pmg::robotWithTaskScene(config.robot, scene, (out_dir / fmt::format("trial_{}_scene.xml", trial)).string());
    config.log_file = (out_dir / fmt::format("trial_{}.lcmlog", trial)).string();
    app = std::make_unique<pmg::ControllerApp>(config);
    sim = dynamic_cast<pmg::MujocoBackend*>(&app->backend());
    if (sim == nullptr) throw std::runtime_error("pmg_teleop_bench: the controller config's backend is not the MuJoCo SIL");
    const mjModel* m = sim->model();
    torso = mj_name2id(m, mjOBJ_BODY, "torso_link");
    shoulder_l = mj_name2id(m, mjOBJ_BODY, "left_shoulder_pitch_link");
    shoulder_r = mj_name2id(m, mjOBJ_BODY, "right_shoulder_pitch_link");
    if (torso < 0 || shoulder_l < 0 || shoulder_r < 0)
      throw std::runtime_error("pmg_teleop_bench: the model lacks torso_link / the shoulder pitch links");
    objects_csv.open(out_dir / fmt::format("trial_{}_objects.csv", trial));
    objects_csv << "t,body,x,y,z,qw,qx,qy,qz\n";
    is_table.assign(static_cast<std::size_t>(m->nbody), false);
    for (const pmg::TaskTable& tb : scene.tables) {
      const int b = mj_name2id(m, mjOBJ_BODY, ("task_" + tb.name).c_str());
      if (b < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks the table body task_" + tb.name);
      is_table[static_cast<std::size_t>(b)] = true;
    }
  }

  /// The robot's pelvis and torso (its trunk and head; not the arms or legs) against the tables:
  /// the first time they touched one [s] (-1: never) and the largest normal force [N].
  double trunk_on_table_s = -1.0, trunk_on_table_n = 0.0;
  void watchTrunk(double t) {
    const mjModel* m = sim->model();
    const mjData* d = sim->data();
    const int pelvis = sim->pelvisBody();
    double n = 0.0;
    for (int i = 0; i < d->ncon; ++i) {
      const int b1 = m->geom_bodyid[d->contact[i].geom1], b2 = m->geom_bodyid[d->contact[i].geom2];
      const bool trunk = b1 == torso || b1 == pelvis || b2 == torso || b2 == pelvis;
      if (!trunk || !(is_table[static_cast<std::size_t>(b1)] || is_table[static_cast<std::size_t>(b2)])) continue;
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      n += std::abs(f[0]);
    }
    if (n > 0 && trunk_on_table_s < 0) trunk_on_table_s = t;
    trunk_on_table_n = std::max(trunk_on_table_n, n);
  }
  /// The trunk touching a table goes into the verdict's detail; the verdict itself stays the
  /// object's. The largest force does not tell a fall onto the table from leaning on it while
  /// wiping bent over it (successful tuning trials: up to 1191 N, 3.6 times the robot's weight; held-out
  /// seed 1006, which fell onto it: 2165 N).
  void judgeTrunk(pmg::TaskVerdict* v) const {
    if (trunk_on_table_s < 0) return;
    const double weight = sim->model()->body_subtreemass[sim->pelvisBody()] * 9.81;
    v->detail += fmt::format("; the robot's trunk touched a table at {:.2f} s (largest force {:.0f} N, its weight {:.0f} N)",
                             trunk_on_table_s, trunk_on_table_n, weight);
  }
  /// A fault the supervisor latched (damping: the robot goes limp) goes into the verdict's detail,
  /// naming the joint for per-joint faults: a fall after it was the supervisor's doing, not the policy's.
  void judgeFault(const pmg::RunSummary& rs, pmg::TaskVerdict* v) const {
    if (rs.fault == pmg::FaultCode::kNone) return;
    v->detail += fmt::format("; the supervisor latched '{}'{} at {:.2f} s", pmg::toString(rs.fault),
                             rs.fault_joint_name.empty() ? std::string()
                                                         : fmt::format(" ({} {:.3f})", rs.fault_joint_name, rs.fault_value),
                             rs.fault_time);
  }

 private:
  std::vector<bool> is_table;  ///< per body of the model: one of the scene's tables
};

struct TrialResult {
  int trial = 0;
  pmg::TaskVerdict verdict;
  bool fell = false;
  double seconds = 0.0;
  int regrabs = 0;  ///< times the operator placed the hand again after it slipped off the towel (wipe) / gripped the box again (box)
  int unpins = 0;   ///< wipe: times the operator stood up and stepped back, the robot pinned against the table
  double trunk_on_table_s = -1.0;  ///< first time the pelvis or torso touched a table [s] (-1: never)
  double trunk_on_table_n = 0.0;   ///< the largest normal force between them [N]
  double level_from_rad = -1.0;    ///< box, level_on_place: the seen tilt when levelling began [rad] (-1: not levelled)
  double level_to_rad = -1.0;      ///< ... and when it ended [rad]
  int setbacks = 0;                ///< box, setback_tilt_rad: times the box was set back onto the pick table
};

// One wiping trial. The operator: settle, engage (A), walk to face the towel, squeeze the right
// grip and bring the robot's right hand onto the towel (closing the loop on the hand it sees), then
// walk sideways along the table pressing the towel down, turning back near each end, until it has
// seen the towel move far enough; then lift the hand and let go.
TrialResult runWipe(int trial, std::uint64_t seed, const pmg::TaskScene& base_scene, const pmg::ControllerConfig& base_config,
                    const OperatorConfig& op, const fs::path& out_dir) {
  TrialRig rig(trial, seed, base_scene, base_config, out_dir);
  const pmg::TaskScene& scene = rig.scene;
  const pmg::TaskObject& towel = scene.objects.at(0);
  const pmg::TaskTable& table = scene.table(towel.on);
  pmg::ControllerApp& app = *rig.app;
  pmg::MujocoBackend* sim = rig.sim;
  const pmg::teleop::TeleopConfig& tc = rig.config.teleop;
  const mjModel* m = sim->model();
  const int torso = rig.torso, shoulder_l = rig.shoulder_l, shoulder_r = rig.shoulder_r;
  // The working hand: the one on the table's middle side of the towel, so that the robot stands
  // nearer the middle of the table.
  const bool use_left = towel.pos[1] > 0.0;
  const int side = use_left ? pmg::teleop::kLeftHand : pmg::teleop::kRightHand;
  const double lateral = use_left ? -op.hand_lateral_m : op.hand_lateral_m;  // pelvis y - towel y
  const int hand = mj_name2id(m, mjOBJ_BODY, use_left ? "left_wrist_yaw_link" : "right_wrist_yaw_link");
  if (hand < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks *_wrist_yaw_link");
  bool aligned = false;  // the controller put where the robot hand is, before the grip is squeezed
  Eigen::Quaterniond palm_turn = Eigen::Quaterniond::Identity();  // palm_down: the controller's turn (frame H)
  double palm_t0 = 0.0;

  std::mt19937_64 rng(seed * 7919 + 17);
  View see_towel(op.view_latency_s, op.view_noise_m, rng), see_hand(op.view_latency_s, op.view_noise_m, rng),
      see_pelvis(op.view_latency_s, op.view_noise_m, rng), see_towel_room(op.view_latency_s, op.view_noise_m, rng);
  View see_yaw(op.view_latency_s, 0.0, rng);  // the robot's heading (x: yaw [rad]), late, without noise
  View see_fingers(op.view_latency_s, 0.0, rng);  // the working hand's fingers' elevation in the room (x [rad]), late
  double palm_level = 0.0;  // palm_level_gain: the levelling turn so far [rad]
  Eigen::Vector2d walk_integral = Eigen::Vector2d::Zero();
  SeenVelocity pelvis_velocity;  // the robot's velocity in the room, as seen
  double work_y = 0.0;  // the pelvis' lateral working place
  double raise_x = 0.0;  // the hand's forward place while it is raised
  Vector3d work_hand = Vector3d::Zero();  // the working hand's place relative to the torso (frame R)

  pmg::teleop::VrSample vr;
  const double head_z = 1.6;
  vr.head_position = {0.0, 0.0, head_z};
  vr.hand_valid = {true, true};
  // Operator's hands at rest, relative to the head (frame H = V at the origin, yaw 0).
  const Vector3d rest_left(0.30, 0.20, -0.45), rest_right(0.30, -0.20, -0.45);
  Vector3d work_H = use_left ? rest_left : rest_right;
  vr.hand_position = {{{rest_left.x(), rest_left.y(), head_z + rest_left.z()}, {rest_right.x(), rest_right.y(), head_z + rest_right.z()}}};
  pmg::CommandSample sample;

  enum Phase { kSettle, kEngage, kApproach, kRaise, kCloseIn, kReach, kPress, kWipe, kRelease, kDone };
  const char* phase_names[] = {"settle", "engage", "approach", "raise", "close_in", "reach", "press", "wipe", "release", "done"};
  Phase phase = kSettle;
  Phase last_phase = kDone;
  double phase_t0 = 0.0;
  int wipe_dir = towel.pos[1] > 0 ? -1 : 1;  // wipe towards the far end first
  double seen_path = 0.0, last_seen_y = 0.0;
  bool counting = false;  // the towel's travel is counted from the first stroke on
  double towel_y_eye = 0.0;  // the towel's seen place along the table, as judged by eye (smoothed) [m]
  int regrabs = 0;  // times the hand was placed again after slipping off the towel
  int unpins = 0;   // times the robot was seen pinned against the table and stepped back (unpin_m)
  bool unpinning = false;  // standing up and stepping back to the far stand-off
  double pinned_since = -1.0;  // when the pelvis was first seen past its working place (-1: not)
  bool regrabbing = false;  // the reach in progress follows a slip
  bool descending = false;  // the reaching hand is over its aim and goes down to the hover height
  Vector3d lift_from = Vector3d::Zero();  // where the hand was when it started lifting (frame R)
  double stroke_center_y = 0.0;  // stroke_m > 0: the hand's lateral place (frame R) the strokes sweep about

  std::vector<pmg::TaskObjectSample> traj;
  std::ofstream csv(out_dir / fmt::format("trial_{}.csv", trial));
  csv << "t,phase,pelvis_x,pelvis_y,pelvis_z,hand_x,hand_y,hand_z,obj_x,obj_y,obj_z,head_x,head_y,engaged,cmd_vx,cmd_vy,cmd_wz,cmd_pitch,"
         "press_n,press_pad_n,palm_normal_z\n";
  // The working hand's push on the towel: through its whole hand (from the wrist roll link on) and
  // through the scene's hand collision geom alone (hand_collision; -1 without).
  const int towel_body = mj_name2id(m, mjOBJ_BODY, ("task_" + towel.name).c_str());
  const int hand_root = mj_name2id(m, mjOBJ_BODY, use_left ? "left_wrist_roll_link" : "right_wrist_roll_link");
  const int pad_geom = mj_name2id(m, mjOBJ_GEOM, use_left ? "task_left_hand_collision" : "task_right_hand_collision");
  if (towel_body < 0 || hand_root < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks the towel body or *_wrist_roll_link");
  const std::array<int, 2> press_root{hand_root, -1}, press_pad{pad_geom, -1};  // slot 0: the working hand
  bool fell = false;
  const double dt = 0.01;
  const long ticks = std::lround(op.max_trial_s / dt);
  for (long k = 0; k < ticks && phase != kDone; ++k) {
    const double t = static_cast<double>(k) * dt;
    const mjData* d = sim->data();
    const pmg::TaskObjectState obj = pmg::taskObjectState(m, d, towel.name);
    const Vector3d torso_p = bodyPos(d, torso), hand_p = bodyPos(d, hand);
    const auto& base = app.controller().lastState().base_position;
    const Vector3d pelvis(base[0], base[1], base[2]);
    traj.push_back({t, obj});
    if (k % 2 == 0) writeObjectPose(rig.objects_csv, t, towel.name, obj);  // 50 Hz
    csv << fmt::format("{:.2f},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:d},{:.3f},{:.3f},{:.3f},{:.3f}", t,
                       phase_names[phase], pelvis.x(), pelvis.y(), pelvis.z(), hand_p.x(), hand_p.y(), hand_p.z(),
                       obj.p_W.x(), obj.p_W.y(), obj.p_W.z(), vr.head_position[0], vr.head_position[1],
                       app.controller().teleop()->status().engaged ? 1 : 0, app.controller().teleop()->status().command.vx,
                       app.controller().teleop()->status().command.vy, app.controller().teleop()->status().command.wz,
                       app.controller().teleop()->status().command.pitch);
    {
      const std::array<double, 8> press = contactForces(m, d, towel_body, press_root, press_pad);
      // palm_normal_z: the hand's y axis (across the palm: the pad's thin axis) in W, z component;
      // +-1 with the palm flat on the table, 0 with the palm facing sideways.
      csv << fmt::format(",{:.2f},{:.2f},{:.3f}\n", press[0], press[2], d->xmat[9 * hand + 7]);
    }
    // What the operator sees: object and hand relative to the torso (head camera), the robot's
    // place in the room, with latency and noise.
    // Frame R: the torso's position, yawed with the pelvis (the robot's heading: the waist may turn
    // the torso relative to it).
    const int pb = sim->pelvisBody();
    const double yaw = yawOf(Eigen::Quaterniond(d->xquat[4 * pb], d->xquat[4 * pb + 1], d->xquat[4 * pb + 2], d->xquat[4 * pb + 3]));
    const Eigen::AngleAxisd unyaw(-yaw, Vector3d::UnitZ());
    see_towel.push(t, unyaw * (obj.p_W - torso_p));
    see_hand.push(t, unyaw * (hand_p - torso_p));
    see_pelvis.push(t, pelvis);
    see_towel_room.push(t, obj.p_W);  // the towel on the table, as the operator sees it in the room
    see_yaw.push(t, Vector3d(yaw, 0.0, 0.0));
    const Vector3d towel_R = see_towel.seen(t), hand_R = see_hand.seen(t), pelvis_W = see_pelvis.seen(t);
    const Eigen::Vector2d pelvis_v_W = pelvis_velocity.update(pelvis_W, t);
    const Vector3d towel_room = see_towel_room.seen(t);
    towel_y_eye = k == 0 ? towel_room.y() : towel_y_eye + std::min(1.0, dt / op.path_smoothing_s) * (towel_room.y() - towel_y_eye);
    const double yaw_seen = see_yaw.seen(t).x();

    // Locomotion: a P controller on the robot's place, expressed as headset displacement.
    Eigen::Vector2d v_body = Eigen::Vector2d::Zero();
    // from_afar: the approach and the walk in (lead_s, integral_zone_m act only there).
    auto walkTo = [&](const Eigen::Vector2d& target_W, double max_speed, bool from_afar = false) {
      return from_afar ? walkCommand(op, target_W, pelvis_W, yaw_seen, max_speed, dt, &walk_integral, &v_body, pelvis_v_W,
                                     op.lead_s, op.integral_zone_m)
                       : walkCommand(op, target_W, pelvis_W, yaw_seen, max_speed, dt, &walk_integral, &v_body);
    };
    const double table_near_x = table.pos[0] - 0.5 * table.top_size[0];
    // The pelvis' working place at the table (W): stand_off_m from its near edge, at work_y.
    auto workPlace = [&] { return Eigen::Vector2d(table_near_x - op.stand_off_m, work_y); };
    // The towel's lateral place on the table, in W (seen through the robot: torso + R(yaw) towel_R).
    const Vector3d towel_W_seen = torso_p + Eigen::AngleAxisd(yaw_seen, Vector3d::UnitZ()) * towel_R;
    bool grip = false;
    const bool entered = phase != last_phase;  // first tick of this phase
    last_phase = phase;
    Vector3d hand_target_R = Vector3d::Zero();
    bool have_hand_target = false;
    switch (phase) {
      case kSettle:
        if (t >= op.settle_s) phase = kEngage, phase_t0 = t;
        break;
      case kEngage:
        if (t - phase_t0 < 0.05) vr.buttons[pmg::teleop::kRightHand] = pmg::teleop::kVrButtonLower;
        else vr.buttons[pmg::teleop::kRightHand] = 0;
        if (t - phase_t0 >= 0.15) phase = kApproach, phase_t0 = t;
        break;
      case kApproach: {
        // Stop short of the table: the hands hang at about the top's height and would catch its edge.
        const Eigen::Vector2d target(table_near_x - op.stand_off_far_m, towel_W_seen.y() + lateral);
        work_y = target.y();
        if (walkTo(target, op.max_speed, true) < op.arrive_tol_m && t - phase_t0 > 1.0)
          phase = kRaise, phase_t0 = t, walk_integral.setZero();
        if (t - phase_t0 > 20.0) phase = kRelease, phase_t0 = t;
        break;
      }
      case kRaise:
      case kCloseIn: {
        // Raise the working hand above the top (crouching and looking down meanwhile), then walk in
        // with it hovering over the towel's near part.
        grip = true;
        have_hand_target = true;
        const double top_z_R = table.height - torso_p.z();
        hand_target_R = Vector3d(phase == kRaise ? raise_x : towel_R.x() - op.grab_inset_m, towel_R.y(),
                                 top_z_R + op.hover_m + op.clearance_m);
        if (phase == kRaise) {
          if (entered) raise_x = hand_R.x();
          const double off = walkTo(Eigen::Vector2d(table_near_x - op.stand_off_far_m, work_y), op.max_speed);
          // Unpinning: standing (below), back at the far stand-off; then crouch and raise again.
          if (unpinning && ((off < op.arrive_tol_m && t - phase_t0 > 1.0) || t - phase_t0 > 10.0))
            unpinning = false, phase_t0 = t, walk_integral.setZero();
          // Walk in only with the hand high above the top: a hand that walks in at hover height
          // (the wrist; the rubber hand hangs below it) sweeps the towel out of reach.
          if (!unpinning && t - phase_t0 > 1.0 &&
              (hand_R.z() > top_z_R + op.hover_m + op.clearance_m - op.raise_margin_m || t - phase_t0 > 6.0))
            phase = kCloseIn, phase_t0 = t, walk_integral.setZero();
        } else {
          if (walkTo(workPlace(), op.max_speed, true) < op.arrive_tol_m &&
              t - phase_t0 > 1.0)
            phase = kReach, phase_t0 = t, walk_integral.setZero();
          if (t - phase_t0 > 15.0) phase = kReach, phase_t0 = t, walk_integral.setZero();
        }
        break;
      }
      case kReach:
      case kPress:
      case kWipe: {
        grip = true;
        have_hand_target = true;
        const double top_z_R = table.height - torso_p.z();  // the table top relative to the torso (seen as a plane)
        // Aim at the towel's near part once, when the reach starts: chasing the towel with a hand
        // that touches it pushes it away. While wiping the hand stays where it is on the robot, so
        // that walking sideways drags the towel.
        if (phase == kReach && entered) work_hand = towel_R - Vector3d(op.grab_inset_m, 0.0, 0.0);
        if (phase == kReach) work_hand.y() = towel_R.y();
        hand_target_R = work_hand;
        hand_target_R.z() = top_z_R + (phase == kReach ? op.hover_m : -op.press_m);
        const Vector3d reach_aim = hand_target_R;  // where the reach ends (the press starts)
        // Travel high, then go down: the rubber hand hangs below the wrist, and a hand that moves at
        // the hover height over the towel drags it (towards the robot, off the near edge).
        const double transit_z = top_z_R + op.transit_height_m;
        if (phase == kReach && op.transit_tol_m > 0) {
          if (entered) descending = false;
          const double off = (hand_R - hand_target_R).head<2>().norm();
          if (off < op.transit_tol_m) descending = true;
          if (off > 2.0 * op.transit_tol_m) descending = false;
          if (!descending) hand_target_R.z() = transit_z;
        }
        // Crouching in place: the hand stays high until the crouch has settled (crouch_settle_s).
        const bool settling = t - phase_t0 < op.crouch_settle_s || (workPlace() - pelvis_W.head<2>()).norm() > 2.0 * op.arrive_tol_m;
        if (phase == kReach && op.crouch_in_place && !regrabbing && settling && t - phase_t0 < 6.0)
          hand_target_R.z() = std::max(hand_target_R.z(), transit_z);
        // Placing the hand again after a slip: lift it straight up first (moving it sideways while it
        // still presses drags the towel, and the push shoves the robot back).
        if (phase == kReach && regrabbing && t - phase_t0 < op.lift_s) {
          if (entered) lift_from = hand_R;
          hand_target_R = lift_from;
          hand_target_R.z() = op.transit_tol_m > 0 ? transit_z : top_z_R + op.hover_m;
        }
        // Keep the towel on the top: while wiping, the hand (and the towel under it) goes forward when
        // the towel is seen nearer the table's near edge than keep_from_edge_m, back when farther.
        if (phase == kWipe) {
          const double x_goal = table_near_x + op.keep_from_edge_m;
          work_hand.x() += std::clamp(op.keep_gain * (x_goal - towel_room.x()), -0.05, 0.05) * dt;
          if (op.keep_reach_m >= 0) work_hand.x() = std::min(work_hand.x(), towel_R.x() - op.grab_inset_m + op.keep_reach_m);
          hand_target_R.x() = work_hand.x();
        }
        // Hold the working place while reaching and pressing (the wipe phase walks on its own).
        if (phase != kWipe)
          walkTo(workPlace(), op.max_speed);
        if (phase == kReach && (hand_R - reach_aim).norm() < 0.03 && t - phase_t0 > 1.0) phase = kPress, phase_t0 = t;
        if (phase == kReach && t - phase_t0 > 8.0) phase = kPress, phase_t0 = t;
        if (phase == kPress && t - phase_t0 > op.press_s) phase = kWipe, phase_t0 = t, regrabbing = false;
        if (phase == kWipe) {
          const double half_len = 0.5 * table.top_size[1];
          // Where the towel is along the table, and how far it went: seen against the table (the room),
          // not through the swaying robot.
          const double y_T = towel_room.y() - table.pos[1];
          // Hold the working distance to the table (and, stroking, the working place along it) with
          // a P term only on the seen place (no integral, no minimum speed): a robot pressing its hand
          // on the table does not reach it exactly, and a wound-up lean would keep it stepping into
          // the table.
          const Eigen::Vector2d e = workPlace() - pelvis_W.head<2>();
          Eigen::Vector2d hold = (op.walk_gain * e).cwiseMax(-0.1).cwiseMin(0.1);
          if (op.stroke_m > 0) {
            // Arm strokes: the robot stands at its working place and the hand sweeps the towel to
            // and fro, stroke_m either side of where it pressed, turning back early near an end of
            // the table. The operator moves its controller along with the stroke (feed-forward) and
            // corrects what it sees of the robot hand.
            if (entered) stroke_center_y = work_hand.y();
            if (wipe_dir > 0 && (work_hand.y() > stroke_center_y + op.stroke_m || y_T > half_len - op.wipe_margin_m)) {
              if (op.stroke_keep_length) stroke_center_y = std::min(stroke_center_y, work_hand.y() - op.stroke_m);
              wipe_dir = -1;
            } else if (wipe_dir < 0 && (work_hand.y() < stroke_center_y - op.stroke_m || y_T < -half_len + op.wipe_margin_m)) {
              if (op.stroke_keep_length) stroke_center_y = std::max(stroke_center_y, work_hand.y() + op.stroke_m);
              wipe_dir = 1;
            }
            work_hand.y() += wipe_dir * op.stroke_speed * dt;
            work_H.y() += wipe_dir * op.stroke_speed * dt / tc.arm_scale;
            hand_target_R.y() = work_hand.y();
          } else {
            // Walk sideways, keeping the hand on the towel; turn back near an end of the table.
            if (wipe_dir > 0 && y_T > half_len - op.wipe_margin_m) wipe_dir = -1;
            if (wipe_dir < 0 && y_T < -half_len + op.wipe_margin_m) wipe_dir = 1;
            hold.y() = wipe_dir * op.wipe_speed;
          }
          v_body = Eigen::Rotation2Dd(-yaw_seen) * hold;
          // The hand slipped off (seen beside the towel's centre): stop, lift it and place it again
          // from where the robot is now (reach, press, wipe on in the same direction); with strokes,
          // the robot steps to face the towel again while the hand is placed.
          if (std::abs(hand_R.y() - towel_R.y()) > op.regrab_offset_m) {
            phase = kReach, phase_t0 = t, walk_integral.setZero();
            work_y = op.stroke_m > 0 ? towel_W_seen.y() + lateral : pelvis_W.y();
            regrabbing = true;
            ++regrabs;
          }
          if (!counting) last_seen_y = towel_y_eye, counting = true;
        }
        // The towel's travel along the table as the operator judges it (by eye: smoothed, in 1 cm
        // steps as the judge counts), from the first stroke on, also while the hand is placed again (a dragged towel
        // travels too). Unsmoothed, the 5 mm view noise alone counted about 1 cm/s.
        if (counting && std::abs(towel_y_eye - last_seen_y) >= 0.01) {
          seen_path += std::abs(towel_y_eye - last_seen_y);
          last_seen_y = towel_y_eye;
        }
        if (counting && seen_path >= op.wipe_path_m) phase = kRelease, phase_t0 = t;
        break;
      }
      case kRelease:
        // Lift the hand off the towel straight up, still crouched and bent (standing up first would
        // drag the towel towards the robot), then let go and stand.
        grip = t - phase_t0 < 1.5;
        if (grip) {
          have_hand_target = true;
          if (entered) lift_from = hand_R;
          hand_target_R = lift_from + Vector3d(0, 0, 0.15);
        }
        if (t - phase_t0 > 2.5) phase = kDone;
        break;
      case kDone:
        break;
    }
    // Pinned against the table: the robot, crouched and bent, went past its working place (its thighs
    // under the top's edge) and does not step back when told to. Stand up, step back, close in again.
    if (op.unpin_m > 0 && (phase == kCloseIn || phase == kReach || phase == kPress)) {
      if (pelvis_W.x() - workPlace().x() > op.unpin_m) {
        if (pinned_since < 0) pinned_since = t;
      } else {
        pinned_since = -1.0;
      }
      if (pinned_since >= 0 && t - pinned_since > op.unpin_s) {
        phase = kRaise, phase_t0 = t, walk_integral.setZero();
        unpinning = true, pinned_since = -1.0, descending = false;
        ++unpins;
      }
    } else {
      pinned_since = -1.0;
    }
    // Headset: displacement for the locomotion command, pitch for looking down.
    const Eigen::Vector2d disp = headFor(v_body, tc.position_deadband_m, tc.velocity_gain[0]);
    const bool working = (phase >= (op.crouch_in_place ? kReach : kRaise) && phase <= kWipe && !unpinning) ||
                         (phase == kRelease && t - phase_t0 < 1.5);
    vr.head_position = {disp.x(), disp.y(), head_z - (working ? op.crouch_m : 0.0)};
    const double pitch = working ? op.look_down_rad : 0.0;
    // Keep the robot facing the table: turn the head against the heading it sees (yaw rate
    // = gain (psi beyond the dead band)), once engaged. Off by default (yaw_gain 0): with gain 1
    // the robot stalled in the approach (docs/teleop.md).
    double psi = 0.0;
    if (op.yaw_gain > 0 && phase > kEngage && phase < kRelease && std::abs(yaw_seen) > 0.03) {
      psi = headYawFor(std::clamp(-op.yaw_gain * yaw_seen, -0.5, 0.5), tc.yaw_deadband_rad, tc.velocity_gain[2]);
    }
    const Eigen::Quaterniond hq = Eigen::AngleAxisd(psi, Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3d::UnitY());
    vr.head_quat = {hq.w(), hq.x(), hq.y(), hq.z()};
    // Right controller: closes the loop on the hand it sees (operator hand moves by the robot-hand
    // error over the arm scale).
    if (have_hand_target && !aligned) {
      work_H = controllerAtRobotHand(d, shoulder_l, shoulder_r, torso_p, unyaw, tc, hand_R);
      aligned = true;
      if (op.palm_down) {
        // The hand's orientation in T now, and the one wanted: fingers forward (palm_pitch_rad
        // down), the pad's thin axis (the hand's y axis, across the palm) vertical, whichever way up
        // is the smaller turn. The relative mapping applies the controller's turn since the grip to
        // the hand in T, so the controller turns by R_want R_now^T.
        const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> R_WT(d->xmat + 9 * torso), R_WH(d->xmat + 9 * hand);
        const Eigen::Quaterniond q_now(Eigen::Matrix3d(R_WT.transpose() * R_WH));
        const Eigen::AngleAxisd pitch_down(op.palm_pitch_rad, Vector3d::UnitY());
        const Eigen::Quaterniond up(pitch_down * Eigen::AngleAxisd(0.5 * M_PI, Vector3d::UnitX())),
            down(pitch_down * Eigen::AngleAxisd(-0.5 * M_PI, Vector3d::UnitX()));
        // With a pad (scene hand_collision), the turn that puts the pad's centre lower (it bounds the
        // rubber hand's mesh, 0.11 m ahead of the wrist and 8 mm off its y axis): a fixed choice per
        // hand, the right hand's y axis down and the left's up, the same as the smaller turn on seeds
        // 0-19. The left hand the other way up (y down) was worse: 7 too_short in the first 26 of
        // seeds 40-79, against 7 failures in all 40. Without a pad, the smaller turn.
        bool pick_up = up.angularDistance(q_now) < down.angularDistance(q_now);
        if (pad_geom >= 0) {
          const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> R_WH_now(d->xmat + 9 * hand);
          const Vector3d pad_H = R_WH_now.transpose() * (Vector3d(d->geom_xpos[3 * pad_geom], d->geom_xpos[3 * pad_geom + 1],
                                                                   d->geom_xpos[3 * pad_geom + 2]) - hand_p);
          pick_up = (up * pad_H).z() < (down * pad_H).z();
        }
        palm_turn = (pick_up ? up : down) * q_now.inverse();
        palm_t0 = t;
      }
    }
    if (op.palm_down && aligned) {
      // Levelling: the fingers' elevation in the room as seen (late), driven to zero by turning the
      // controller about frame T's lateral axis (a positive turn about y points the fingers down).
      see_fingers.push(t, Vector3d(std::asin(std::clamp(d->xmat[9 * hand + 6], -1.0, 1.0)), 0.0, 0.0));
      if (op.palm_level_gain > 0 && grip && t - palm_t0 > op.palm_turn_s)
        palm_level = std::clamp(palm_level + op.palm_level_gain * dt * see_fingers.seen(t).x(), -0.6, 0.6);
      const Eigen::Quaterniond qh = Eigen::AngleAxisd(palm_level, Vector3d::UnitY()) *
                                    Eigen::Quaterniond::Identity().slerp(std::clamp((t - palm_t0) / op.palm_turn_s, 0.0, 1.0), palm_turn);
      vr.hand_quat[static_cast<std::size_t>(side)] = {qh.w(), qh.x(), qh.y(), qh.z()};
    }
    if (have_hand_target) {
      work_H += op.hand_gain * dt * (hand_target_R - hand_R) / tc.arm_scale;
      // A person's hand leads the robot hand it sees by a few centimetres at most: it does not keep
      // pushing the controller down while the robot hand rests on the table (that wound-up lead made
      // a lift drag the towel back over the table's edge).
      const Vector3d at = controllerAtRobotHand(d, shoulder_l, shoulder_r, torso_p, unyaw, tc, hand_R);
      const double lead_max = op.max_lead_m / tc.arm_scale;
      if ((work_H - at).norm() > lead_max) work_H = at + lead_max * (work_H - at).normalized();
      // Stroking, the press is light and the lead is mostly sideways: a hand held down by the full
      // lead pressed the towel with about 35 N, and the arm could not drag it (strokes of +-4 cm).
      if (op.stroke_m > 0 && phase == kWipe) work_H.z() = std::max(work_H.z(), at.z() - op.stroke_press_m / tc.arm_scale);
    }
    const Vector3d head(vr.head_position[0], vr.head_position[1], vr.head_position[2]);
    const Vector3d wh = head + work_H, lh = head + rest_left, rh = head + rest_right;
    vr.hand_position = {{{lh.x(), lh.y(), lh.z()}, {rh.x(), rh.y(), rh.z()}}};
    vr.hand_position[static_cast<std::size_t>(side)] = {wh.x(), wh.y(), wh.z()};
    vr.grip = {0.0, 0.0};
    vr.grip[static_cast<std::size_t>(side)] = grip ? 1.0 : 0.0;
    vr.frame = k;
    sample.vr = vr;
    sample.vr_time = t;
    const pmg::TickStatus st = app.stepLockstep(sample);
    rig.watchTrunk(t);
    if (pmg::silRobotFell(app.controller().lastState(), st)) {
      fell = true;
      break;
    }
  }
  const pmg::RunSummary summary = app.finish();  // closes the event log
  TrialResult r;
  r.trial = trial;
  r.fell = fell;
  r.seconds = traj.empty() ? 0.0 : traj.back().t;
  r.regrabs = regrabs;
  r.unpins = unpins;
  r.verdict = pmg::judgeWipe(scene, towel.name, traj, fell);
  rig.judgeTrunk(&r.verdict);
  rig.judgeFault(summary, &r.verdict);
  r.trunk_on_table_s = rig.trunk_on_table_s;
  r.trunk_on_table_n = rig.trunk_on_table_n;
  return r;
}

// ---- Box carrying (the paper's Table III "box picking") -----------------------------------------
// The operator's parameters (config/tasks/box_operator.yaml). Frames as in the wiping operator: R =
// the torso's position yawed with the pelvis (what the head camera sees), W = the room.
struct BoxOperatorConfig : OperatorCommon {
  double stand_off_far_m = 0.35;   ///< pelvis distance from the pick table's near edge while raising the hands [m]
  double stand_off_m = 0.10;       ///< ... while grasping [m]
  double place_stand_off_m = 0.10; ///< pelvis distance from the place table's near edge while placing [m]
  /// Carrying, the pelvis is held this much further back than its place at the pick table until it
  /// is seen within carry_align_m of the place table's centre line, and only then walks in to
  /// place_stand_off_m: sideways first, then in, so that the trunk does not run along the place
  /// table's near edge [m]; 0: straight to the place (the diagonal path of v3).
  double carry_back_m = 0.0;
  double carry_align_m = 0.05;  ///< [m], see carry_back_m
  double carry_speed = 0.15;       ///< walking speed with the box [m/s]
  double crouch_m = 0.18;          ///< headset lowered this much while grasping (beyond 0.03 m: the robot squats)
  double look_down_rad = 0.70;     ///< headset pitch while grasping (beyond 0.25 rad: the torso bends)
  double hover_m = 0.06;           ///< the open hands this far above the box's top while walking in [m]
  double grasp_below_top_m = 0.06; ///< the hands' height: this far below the box's top [m]
  double grasp_in_m = 0.06;        ///< the wrists this far behind the box's near side, < 0: short of it (the hands reach forward of the wrist) [m]
  double spread_m = 0.08;          ///< the wrists this far outside the box's sides before closing [m]
  double squeeze_m = 0.03;         ///< ... and this far inside them when squeezing [m]
  double squeeze_s = 1.5;          ///< closing the hands [s]
  double lift_speed = 0.10;        ///< hands' lifting and lowering speed [m/s]
  double carry_clearance_m = 0.08; ///< the box's bottom this far above the place table's top while carrying [m]
  double place_press_m = 0.01;     ///< lowering aims the box's bottom this far below the place top [m]
  double max_lead_m = 0.10;        ///< the controller at most this far (robot scale) beyond the seen hand (anti-windup); 0 = no limit [m]
  /// > 0: holding the box (lift, carry, lower), the anti-windup bounds the lead's vertical part on
  /// its own, by this [m], and max_lead_m bounds its horizontal part. 0 (v3): one bound on the
  /// whole lead, so that a squeeze which has used it up leaves no lead to raise or lower that hand
  /// (measured: holding, the two wrists stood 5-15 cm apart in height and the box rolled by as much,
  /// atan(dz / 0.34 m)).
  double vertical_lead_m = 0.0;
  double hand_pitch_rad = 0.0;     ///< the controllers are turned so that the hands point forward, this far below horizontal (frame T) [rad]
  double turn_s = 1.0;             ///< ... over this long after the grips are squeezed [s]
  double stand_s = 3.0;            ///< lifting: stand up from the crouch and the bend over this long [s]
  bool lift_in_place = true;       ///< lifting: no stepping back until the box is up
  double slide_to_m = -2.0;        ///< gripped, a box whose near side lies further beyond the pick top's edge than this is slid towards the robot to it and gripped again; < -1 = never [m]
  double slide_speed = 0.05;       ///< ... at this speed [m/s]
  double regrip_in_m = 0.0;        ///< after a slide, grip again with the wrists this far behind the box's near side (nearer its centre of mass; < 0: short of it); 0 = grasp_in_m [m]
  double stand_after_lift_m = 0.0; ///< lifting: stay crouched and bent until the box's bottom is seen this far above the pick top, then stand up over stand_s; 0 = at once [m]
  /// Hug: once the box is seen clear of the pick top, draw the hands this much towards the torso
  /// (at hug_speed), so that the box's near side rests against the body, a third contact against
  /// the box turning about the line through the two grip contacts; 0 = off [m]
  double hug_m = 0.0;
  double hug_speed = 0.05;         ///< [m/s]
  int max_regrabs = 0;             ///< a box seen back on the pick table, upright, after a lift: open, lower the hands beside it and grip it again, at most this often
  bool feedforward = false;        ///< the controllers held where the mapping puts the hands at their targets (torso pose as now), plus the seen error's integral (at most max_lead_m)
  double max_raise_m = 0.0;        ///< lifting and carrying: the hands at most this far above the nominal carrying height, to keep a sagging box clear [m]
  bool hands_along_box = false;    ///< the controllers turned so that the hands point along the box's sides (its seen yaw), not straight ahead: the palms lie flat on a turned box
  double hand_toe_in_rad = 0.0;    ///< ... and each hand turned in by this much (fingers towards the box's centre line) [rad]
  /// ... and each hand rolled about its pointing axis by this much, palm turned down (pronation;
  /// mirrored left/right): at pi/2 the hand's edge, the pad's 0.106 m width across the box, touches
  /// the side instead of the palm, standing out further than the wrist housings [rad]
  double hand_roll_rad = 0.0;
  double side_tol_m = 0.0;         ///< descending: a hand goes below the box's top only once seen this close to its place beside the box; 0 = at once [m]
  double release_clear_m = 0.0;    ///< after a slide, the hands move on to grip again only once both wrists are seen this far outside the box's sides (still touching it, they dragged it forward out of reach); 0 = after the opening time alone [m]
  /// After a slide, the deeper grip's place along the box is taken where the box was seen when the
  /// hands let go, not where it is seen while they move to it (hands that still touched it dragged
  /// it forward, and the place they aimed at went forward with it). Tried, not kept (docs/teleop.md).
  bool freeze_regrip_aim = false;
  /// Letting go (after the slide, and at the place table), the operator brings its controllers back to
  /// where it sees the robot's hands before opening them: squeezing, it held them up to max_lead_m
  /// inside the box (the arm's PD then presses the box), and opening from there the robot's hands
  /// stayed closed until that lead was unwound, and moving on they dragged the box along.
  bool unwind_on_release = false;    // tried, not kept (docs/teleop.md), as are place_in_m 0.10 and face_box_*
  /// The same at the place table only: the box set down, the controllers are brought back to where
  /// the robot's hands are seen before the hands open, so that they do let go (without it, boxes
  /// were left squeezed 1-2 cm above the place top, judged not placed: docs/teleop.md).
  bool unwind_on_place = false;
  /// Placing, lower the hands past the nominal place height (at most place_deeper_m further) until
  /// the box is seen resting on the place top, its lowest corner within 1 cm of it, and turned less
  /// than this [rad] (0: off; the nominal height only). A box hanging turned in the grip touches down
  /// on an edge first, and lowering on turns it flat.
  double place_flat_rad = 0.0;
  double place_deeper_m = 0.06;    ///< [m]
  double place_in_m = 0.04;        ///< placing: the box's near side (as gripped) this far beyond the place top's near edge [m]
  /// Set a box that hangs turned in the grip down on its low edge, then level it: lowering over the
  /// place top, once the box is seen turned far side down (its top leaning away from the robot) by
  /// more than level_tilt_rad, and less than level_max_rad, with its lowest corner within
  /// level_touch_m of the place top (touching it), the operator stops lowering and draws its hands
  /// back towards the robot at level_speed, so that the box turns about its far bottom edge, until
  /// it is seen within level_done_rad of flat (at most level_back_m back, or 4 s); then it lowers
  /// and lets go as before. Why: a box turned beyond about 0.83 rad (the atan of its depth over its
  /// height) and let down on its far edge should topple onto its far face ("tipped"). Tried, not
  /// kept: lowering alone laid such boxes flat more often (held out: 23/100 with it, 27/100
  /// without; docs/teleop.md).
  bool level_on_place = false;
  /// Set the box back and grip it again when it turns in the grip while lifting: once it is seen
  /// turned by more than setback_tilt_rad with its bottom less than setback_height_m above the pick
  /// top, the operator crouches and bends again, lowers the box back onto the top at lift_speed and,
  /// once it is seen resting there (or after 4 s), opens the hands, lowers them beside it and grips
  /// it again, as after a slip (the same max_regrabs). Why: on tuning seeds 0-39 the box had turned
  /// beyond 0.9 rad within 0.15 m of the pick top in 13 of the 19 `dropped` trials and in none of
  /// the 9 successes. Tried, not kept: 0.6 gained on the tuning seeds (11/40 against 9/40) but
  /// not on held-out ones (22/100 against 25/100; docs/teleop.md). 0 = off [rad]
  double setback_tilt_rad = 0.0;
  double setback_height_m = 0.15;  ///< [m]
  double level_tilt_rad = 0.70;    ///< [rad]
  double level_done_rad = 0.10;    ///< [rad]
  double level_max_rad = 1.2;      ///< a box seen turned further lies on its face already: left alone [rad]
  double level_touch_m = 0.02;     ///< [m]
  double level_speed = 0.05;       ///< [m/s]
  double level_back_m = 0.15;      ///< [m]
  /// Face the box square: while walking up (approach, raise, close-in) the operator turns its head
  /// so that the robot turns towards the box's seen yaw (yaw rate = gain x the box's yaw relative to
  /// the robot's heading, at most 0.3 rad/s, 0.03 rad dead band); a box seen turned puts one side
  /// further away than the other, and that hand grips at the edge of its reach. 0 = off [1/s]
  double face_box_gain = 0.0;
  bool face_box_hold = false;      ///< ... and keep facing it while grasping, sliding and letting go (until the lift)
  /// Heading hold with the box: while carrying and lowering, the operator turns its head so that the
  /// robot turns back to face the place table square (yaw rate = gain x the seen heading error, at
  /// most 0.3 rad/s, 0.03 rad dead band). Without it the robot, told only to step sideways, turned
  /// 0.3-0.5 rad while carrying (tuning seeds 2 and 6). 0 = off [1/s]
  double carry_heading_gain = 0.0;
  bool keep_hand_pitch = false;    ///< holding the box (lift, carry, lower): the controllers turned against the torso's seen pitch change, so that the hands keep their pitch in the room while the robot stands up
  double unturn_speed = 0.3;       ///< ... and turned back at this rate once the box is no longer held [rad/s]
  template <class A>
  void Serialize(A* a) {
    OperatorCommon::Serialize(a);
    a->Visit("max_lead_m", &max_lead_m, "[m]");
    a->Visit("vertical_lead_m", &vertical_lead_m, "[m] (0: within max_lead_m)");
    a->Visit("hand_pitch_rad", &hand_pitch_rad, "[rad]");
    a->Visit("turn_s", &turn_s, "[s]");
    a->Visit("stand_s", &stand_s, "[s]");
    a->Visit("lift_in_place", &lift_in_place, "true | false");
    a->Visit("side_tol_m", &side_tol_m, "[m]");
    a->Visit("hands_along_box", &hands_along_box, "true | false");
    a->Visit("hand_toe_in_rad", &hand_toe_in_rad, "[rad]");
    a->Visit("hand_roll_rad", &hand_roll_rad, "[rad]");
    a->Visit("keep_hand_pitch", &keep_hand_pitch, "true | false");
    a->Visit("release_clear_m", &release_clear_m, "[m]");
    a->Visit("freeze_regrip_aim", &freeze_regrip_aim, "true | false");
    a->Visit("unwind_on_release", &unwind_on_release, "true | false");
    a->Visit("unwind_on_place", &unwind_on_place, "true | false");
    a->Visit("place_flat_rad", &place_flat_rad, "[rad] (0: off)");
    a->Visit("place_deeper_m", &place_deeper_m, "[m]");
    a->Visit("place_in_m", &place_in_m, "[m]");
    a->Visit("level_on_place", &level_on_place, "true | false");
    a->Visit("setback_tilt_rad", &setback_tilt_rad, "[rad] (0: off)");
    a->Visit("setback_height_m", &setback_height_m, "[m]");
    a->Visit("level_tilt_rad", &level_tilt_rad, "[rad]");
    a->Visit("level_done_rad", &level_done_rad, "[rad]");
    a->Visit("level_max_rad", &level_max_rad, "[rad]");
    a->Visit("level_touch_m", &level_touch_m, "[m]");
    a->Visit("level_speed", &level_speed, "[m/s]");
    a->Visit("level_back_m", &level_back_m, "[m]");
    a->Visit("face_box_gain", &face_box_gain, "[1/s] (0: off)");
    a->Visit("face_box_hold", &face_box_hold, "true | false");
    a->Visit("carry_heading_gain", &carry_heading_gain, "[1/s] (0: off)");
    a->Visit("unturn_speed", &unturn_speed, "[rad/s]");
    a->Visit("max_raise_m", &max_raise_m, "[m]");
    a->Visit("feedforward", &feedforward, "true | false");
    a->Visit("stand_after_lift_m", &stand_after_lift_m, "[m]");
    a->Visit("hug_m", &hug_m, "[m] (0: off)");
    a->Visit("hug_speed", &hug_speed, "[m/s]");
    a->Visit("slide_to_m", &slide_to_m, "[m]");
    a->Visit("slide_speed", &slide_speed, "[m/s]");
    a->Visit("regrip_in_m", &regrip_in_m, "[m]");
    a->Visit("max_regrabs", &max_regrabs, "[0, 5]");
    a->Visit("stand_off_far_m", &stand_off_far_m, "[m]");
    a->Visit("stand_off_m", &stand_off_m, "[m]");
    a->Visit("place_stand_off_m", &place_stand_off_m, "[m]");
    a->Visit("carry_back_m", &carry_back_m, "[m]");
    a->Visit("carry_align_m", &carry_align_m, "[m]");
    a->Visit("carry_speed", &carry_speed, "[m/s]");
    a->Visit("crouch_m", &crouch_m, "[m]");
    a->Visit("look_down_rad", &look_down_rad, "[rad]");
    a->Visit("hover_m", &hover_m, "[m]");
    a->Visit("grasp_below_top_m", &grasp_below_top_m, "[m]");
    a->Visit("grasp_in_m", &grasp_in_m, "[m]");
    a->Visit("spread_m", &spread_m, "[m]");
    a->Visit("squeeze_m", &squeeze_m, "[m]");
    a->Visit("squeeze_s", &squeeze_s, "[s]");
    a->Visit("lift_speed", &lift_speed, "[m/s]");
    a->Visit("carry_clearance_m", &carry_clearance_m, "[m]");
    a->Visit("place_press_m", &place_press_m, "[m]");
  }
  std::string validate() const {
    if (std::string e = OperatorCommon::validate(); !e.empty()) return e;
    if (!(carry_speed > 0 && carry_speed <= 0.4)) return "carry_speed: expected (0, 0.4] m/s";
    if (!(spread_m > 0 && spread_m <= 0.2)) return "spread_m: expected (0, 0.2] m";
    if (!(squeeze_m >= 0 && squeeze_m <= 0.1)) return "squeeze_m: expected [0, 0.1] m";
    if (!(lift_speed > 0 && lift_speed <= 0.5)) return "lift_speed: expected (0, 0.5] m/s";
    if (!(max_lead_m >= 0 && max_lead_m <= 1.0)) return "max_lead_m: expected [0, 1] m (0: no limit)";
    if (!(vertical_lead_m >= 0 && vertical_lead_m <= 0.5)) return "vertical_lead_m: expected [0, 0.5] m (0: within max_lead_m)";
    if (!(std::abs(hand_pitch_rad) <= 1.6)) return "hand_pitch_rad: expected [-1.6, 1.6] rad (1.6: the hands pointing down)";
    if (!(turn_s > 0 && turn_s <= 10)) return "turn_s: expected (0, 10] s";
    if (!(stand_s >= 0 && stand_s <= 10)) return "stand_s: expected [0, 10] s (0: at once)";
    if (!(max_raise_m >= 0 && max_raise_m <= 0.3)) return "max_raise_m: expected [0, 0.3] m";
    if (!(stand_after_lift_m >= 0 && stand_after_lift_m <= 0.3)) return "stand_after_lift_m: expected [0, 0.3] m (0: at once)";
    if (!(hug_m >= 0 && hug_m <= 0.3)) return "hug_m: expected [0, 0.3] m (0: off)";
    if (!(hug_speed > 0 && hug_speed <= 0.3)) return "hug_speed: expected (0, 0.3] m/s";
    if (!(max_regrabs >= 0 && max_regrabs <= 5)) return "max_regrabs: expected [0, 5]";
    if (!(slide_to_m >= -2.0 && slide_to_m <= 0.3)) return "slide_to_m: expected [-2, 0.3] m (< -1: never)";
    if (!(slide_speed > 0 && slide_speed <= 0.2)) return "slide_speed: expected (0, 0.2] m/s";
    if (!(regrip_in_m >= -0.15 && regrip_in_m <= 0.3)) return "regrip_in_m: expected [-0.15, 0.3] m (0: grasp_in_m)";
    if (!(std::abs(hand_toe_in_rad) <= 0.5)) return "hand_toe_in_rad: expected [-0.5, 0.5] rad";
    if (!(std::abs(hand_roll_rad) <= 1.8)) return "hand_roll_rad: expected [-1.8, 1.8] rad";
    if (!(side_tol_m >= 0 && side_tol_m <= 0.2)) return "side_tol_m: expected [0, 0.2] m (0: no check)";
    if (!(unturn_speed > 0 && unturn_speed <= 2.0)) return "unturn_speed: expected (0, 2] rad/s";
    if (!(release_clear_m >= 0 && release_clear_m <= 0.2)) return "release_clear_m: expected [0, 0.2] m (0: no check)";
    if (!(face_box_gain >= 0 && face_box_gain <= 5.0)) return "face_box_gain: expected [0, 5] 1/s (0: off)";
    if (!(carry_heading_gain >= 0 && carry_heading_gain <= 5.0)) return "carry_heading_gain: expected [0, 5] 1/s (0: off)";
    if (!(place_in_m >= 0 && place_in_m <= 0.3)) return "place_in_m: expected [0, 0.3] m";
    if (!(place_flat_rad >= 0 && place_flat_rad <= 0.5)) return "place_flat_rad: expected [0, 0.5] rad (0: off)";
    if (!(place_deeper_m >= 0 && place_deeper_m <= 0.15)) return "place_deeper_m: expected [0, 0.15] m";
    if (!(level_tilt_rad > 0 && level_tilt_rad <= 1.2)) return "level_tilt_rad: expected (0, 1.2] rad";
    if (!(setback_tilt_rad >= 0 && setback_tilt_rad <= 1.5)) return "setback_tilt_rad: expected [0, 1.5] rad (0: off)";
    if (!(setback_height_m > 0 && setback_height_m <= 0.5)) return "setback_height_m: expected (0, 0.5] m";
    if (!(level_done_rad > 0 && level_done_rad < level_tilt_rad)) return "level_done_rad: expected (0, level_tilt_rad) rad";
    if (!(level_max_rad > level_tilt_rad && level_max_rad <= 1.6)) return "level_max_rad: expected (level_tilt_rad, 1.6] rad";
    if (!(level_touch_m >= 0 && level_touch_m <= 0.1)) return "level_touch_m: expected [0, 0.1] m";
    if (!(level_speed > 0 && level_speed <= 0.3)) return "level_speed: expected (0, 0.3] m/s";
    if (!(level_back_m > 0 && level_back_m <= 0.3)) return "level_back_m: expected (0, 0.3] m";
    if (!(stand_off_far_m >= 0 && stand_off_far_m <= 1.0)) return "stand_off_far_m: expected [0, 1] m";
    if (!(stand_off_m >= 0 && stand_off_m <= stand_off_far_m)) return "stand_off_m: expected [0, stand_off_far_m] m";
    if (!(place_stand_off_m >= 0 && place_stand_off_m <= 1.0)) return "place_stand_off_m: expected [0, 1] m";
    if (!(carry_back_m >= 0 && carry_back_m <= 0.5)) return "carry_back_m: expected [0, 0.5] m";
    if (!(carry_align_m > 0 && carry_align_m <= 0.5)) return "carry_align_m: expected (0, 0.5] m";
    if (!(crouch_m >= 0 && crouch_m <= 0.4)) return "crouch_m: expected [0, 0.4] m";
    if (!(look_down_rad >= 0 && look_down_rad <= 1.2)) return "look_down_rad: expected [0, 1.2] rad";
    if (!(hover_m >= 0 && hover_m <= 0.3)) return "hover_m: expected [0, 0.3] m";
    if (!(grasp_below_top_m >= -0.1 && grasp_below_top_m <= 0.3)) return "grasp_below_top_m: expected [-0.1, 0.3] m";
    if (!(grasp_in_m >= -0.15 && grasp_in_m <= 0.3)) return "grasp_in_m: expected [-0.15, 0.3] m";
    if (!(squeeze_s > 0 && squeeze_s <= 10)) return "squeeze_s: expected (0, 10] s";
    if (!(carry_clearance_m >= 0 && carry_clearance_m <= 0.3)) return "carry_clearance_m: expected [0, 0.3] m";
    if (!(place_press_m >= 0 && place_press_m <= 0.1)) return "place_press_m: expected [0, 0.1] m";
    return "";
  }
};

// One box trial. The operator: settle, engage (A), walk up to the pick table (stopping short), squeeze
// both grips and bring the robot's hands beside the box (crouching and looking down), walk in, close
// the hands on the box's sides, lift it above the place table's height (standing up), walk sideways
// to the place table, lower the box onto it, open the hands and lift them away, and wait.
TrialResult runBox(int trial, std::uint64_t seed, const pmg::TaskScene& base_scene, const pmg::ControllerConfig& base_config,
                   const BoxOperatorConfig& op, const fs::path& out_dir) {
  TrialRig rig(trial, seed, base_scene, base_config, out_dir);
  const pmg::TaskScene& scene = rig.scene;
  const pmg::TaskObject& box = scene.objects.at(0);
  const pmg::TaskTable& pick = scene.table(box.on);
  const pmg::TaskTable* place_ptr = nullptr;
  for (const pmg::TaskTable& tb : scene.tables)
    if (tb.name != pick.name) place_ptr = &tb;
  if (place_ptr == nullptr) throw std::runtime_error("pmg_teleop_bench: the box scene needs a second (place) table");
  const pmg::TaskTable& place = *place_ptr;
  pmg::ControllerApp& app = *rig.app;
  pmg::MujocoBackend* sim = rig.sim;
  const pmg::teleop::TeleopConfig& tc = rig.config.teleop;
  const mjModel* m = sim->model();
  const int torso = rig.torso, shoulder_l = rig.shoulder_l, shoulder_r = rig.shoulder_r;
  const std::array<int, 2> hand_body{mj_name2id(m, mjOBJ_BODY, "left_wrist_yaw_link"), mj_name2id(m, mjOBJ_BODY, "right_wrist_yaw_link")};
  if (hand_body[0] < 0 || hand_body[1] < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks *_wrist_yaw_link");
  const double half_w = 0.5 * box.size[1], box_h = box.size[2];
  const int box_body = mj_name2id(m, mjOBJ_BODY, ("task_" + box.name).c_str());
  const std::array<int, 2> hand_subtree{mj_name2id(m, mjOBJ_BODY, "left_wrist_roll_link"), mj_name2id(m, mjOBJ_BODY, "right_wrist_roll_link")};
  // The rubber hands' collision geoms (scene hand_collision; -1 without): the grip through the palms.
  const std::array<int, 2> hand_geom{mj_name2id(m, mjOBJ_GEOM, "task_left_hand_collision"), mj_name2id(m, mjOBJ_GEOM, "task_right_hand_collision")};
  if (box_body < 0 || hand_subtree[0] < 0 || hand_subtree[1] < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks the box body or *_wrist_roll_link");
  const std::array<int, 2> arm_root{mj_name2id(m, mjOBJ_BODY, "left_shoulder_pitch_link"), mj_name2id(m, mjOBJ_BODY, "right_shoulder_pitch_link")};
  if (arm_root[0] < 0 || arm_root[1] < 0) throw std::runtime_error("pmg_teleop_bench: the model lacks *_shoulder_pitch_link");

  std::mt19937_64 rng(seed * 7919 + 17);
  View see_box(op.view_latency_s, op.view_noise_m, rng), see_box_room(op.view_latency_s, op.view_noise_m, rng),
      see_pelvis(op.view_latency_s, op.view_noise_m, rng), see_yaw(op.view_latency_s, 0.0, rng),
      see_box_yaw(op.view_latency_s, 0.0, rng),  // the box's yaw relative to the robot's heading (x) [rad]
      see_box_up(op.view_latency_s, 0.0, rng),   // the box's z axis in W (upright: (0, 0, 1))
      see_box_xy_z(op.view_latency_s, 0.0, rng),  // the W z components of the box's x and y axes (x, y)
      see_torso_pitch(op.view_latency_s, 0.0, rng);  // the torso's pitch (x) [rad]: the head camera's horizon
  std::array<View, 2> see_hand{View(op.view_latency_s, op.view_noise_m, rng), View(op.view_latency_s, op.view_noise_m, rng)};
  Eigen::Vector2d walk_integral = Eigen::Vector2d::Zero();

  pmg::teleop::VrSample vr;
  const double head_z = 1.6;
  vr.head_position = {0.0, 0.0, head_z};
  vr.hand_valid = {true, true};
  const std::array<Vector3d, 2> rest{Vector3d(0.30, 0.20, -0.45), Vector3d(0.30, -0.20, -0.45)};  // frame H
  std::array<Vector3d, 2> hand_H = rest;
  std::array<Vector3d, 2> hand_bias{Vector3d::Zero(), Vector3d::Zero()};  // feedforward: the seen error's integral (frame H)
  bool aligned = false;
  std::array<Eigen::Quaterniond, 2> turn_H{Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()};
  double turn_t0 = 0.0;
  double pitch_comp = 0.0;  // keep_hand_pitch: the controllers' extra turn about the pitch axis [rad]
  double last_torso_pitch = std::numeric_limits<double>::quiet_NaN();
  pmg::CommandSample sample;

  enum Phase { kSettle, kEngage, kApproach, kRaise, kCloseIn, kDescend, kSqueeze, kSlide, kRelease, kLift, kSetBack, kCarry, kLower, kOpen, kWait, kDone };
  const char* phase_names[] = {"settle",  "engage", "approach", "raise", "close_in", "descend", "squeeze", "slide",
                               "release", "lift",   "set_back", "carry", "lower",    "open",    "wait",    "done"};
  bool slid = false;     // the box was slid towards the robot and gripped again
  double regrip_x = std::numeric_limits<double>::quiet_NaN();  // freeze_regrip_aim: the deeper grip's forward place (frame R) [m]
  double slide_x = 0.0;  // sliding: the hands' forward place (frame R, ramps back) [m]
  Phase phase = kSettle, last_phase = kDone;
  double phase_t0 = 0.0;
  double lift_z = 0.0;     // the hands' height target while lifting / lowering (frame R, ramps) [m]
  double carry_x = 0.0;    // the hands' forward place while carrying (frame R) [m]
  double hug_x = 0.0;      // hug_m: where carry_x goes once the box is clear (frame R) [m]
  double squeeze_y = 0.0;  // half the distance between the wrists' targets (ramps) [m]
  double working_y = 0.0;  // the pelvis' lateral place at the pick table (W) [m]
  double carry_y = 0.0;    // the hands' lateral centre while holding the box (frame R) [m]
  double held_yaw = 0.0;   // the box's seen yaw (relative to the robot) when it was gripped [rad]
  double stand_t0 = -1.0;  // lifting: when standing up began (< 0: not yet) [s]
  int regrabs = 0;         // times the box was gripped again after it stayed on (or fell back onto) the pick table
  enum Level { kLevelNo, kLevelOn, kLevelDone } level = kLevelNo;  // level_on_place: not (yet), levelling, done
  double level_t0 = 0.0, level_x0 = 0.0;  // when levelling began, and carry_x then
  double level_from = -1.0, level_to = -1.0;  // the seen tilt when it began and ended [rad]
  double grip_z = 0.0;     // setback_tilt_rad: the hands' height when the lift began (frame R) [m]
  int setbacks = 0;        // times the box was set back onto the pick table to be gripped again

  std::vector<pmg::TaskObjectSample> traj;
  std::ofstream csv(out_dir / fmt::format("trial_{}.csv", trial));
  csv << "t,phase,pelvis_x,pelvis_y,pelvis_z,hand_x,hand_y,hand_z,obj_x,obj_y,obj_z,head_x,head_y,engaged,cmd_vx,cmd_vy,cmd_wz,cmd_pitch,"
         "left_hand_x,left_hand_y,left_hand_z,grip_left_n,grip_right_n,box_tilt,left_hand_pitch,right_hand_pitch,"
         "grip_left_hand_n,grip_right_hand_n,grip_left_up_n,grip_right_up_n,grip_left_normal_up_n,grip_right_normal_up_n,"
         "arm_left_n,arm_right_n,arm_left_up_n,arm_right_up_n,arm_left_normal_up_n,arm_right_normal_up_n,body_n\n";
  bool fell = false;
  const double dt = 0.01;
  const long ticks = std::lround(op.max_trial_s / dt);
  for (long k = 0; k < ticks && phase != kDone; ++k) {
    const double t = static_cast<double>(k) * dt;
    const mjData* d = sim->data();
    const pmg::TaskObjectState obj = pmg::taskObjectState(m, d, box.name);
    const Vector3d torso_p = bodyPos(d, torso);
    const std::array<Vector3d, 2> hand_p{bodyPos(d, hand_body[0]), bodyPos(d, hand_body[1])};
    const auto& base = app.controller().lastState().base_position;
    const Vector3d pelvis(base[0], base[1], base[2]);
    traj.push_back({t, obj});
    const auto& ts = app.controller().teleop()->status();
    csv << fmt::format("{:.2f},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:d},{:.3f},{:.3f},{:.3f},{:.3f},{:.4f},{:.4f},{:.4f}", t,
                       phase_names[phase], pelvis.x(), pelvis.y(), pelvis.z(), hand_p[1].x(), hand_p[1].y(), hand_p[1].z(),
                       obj.p_W.x(), obj.p_W.y(), obj.p_W.z(), vr.head_position[0], vr.head_position[1], ts.engaged ? 1 : 0,
                       ts.command.vx, ts.command.vy, ts.command.wz, ts.command.pitch, hand_p[0].x(), hand_p[0].y(), hand_p[0].z());
    {
      const std::array<double, 8> grip_n = contactForces(m, d, box_body, hand_subtree, hand_geom);
      csv << fmt::format(",{:.2f},{:.2f}", grip_n[0], grip_n[1]);
      // The box's tilt (angle of its z axis from W's) and each hand's pitch (elevation of its x
      // axis, along the fingers, above the horizontal; negative: pointing down) [rad].
      csv << fmt::format(",{:.4f}", pmg::tiltAngle(obj.q_W));
      for (std::size_t h = 0; h < 2; ++h) csv << fmt::format(",{:.4f}", std::asin(std::clamp(d->xmat[9 * hand_body[h] + 6], -1.0, 1.0)));
      csv << fmt::format(",{:.2f},{:.2f}", grip_n[2], grip_n[3]);  // through the rubber hands' own geoms
      csv << fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f}", grip_n[4], grip_n[5], grip_n[6], grip_n[7]);  // up: the whole force, its normal part
      // The same through each whole arm (shoulder on: the forearms and elbows too), and the normal
      // force through the rest of the robot (trunk, legs: the box against the body).
      const std::array<double, 8> arm_n = contactForces(m, d, box_body, arm_root);
      const std::array<double, 8> robot_n = contactForces(m, d, box_body, {sim->pelvisBody(), -1});
      csv << fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f},{:.2f},{:.2f},{:.2f}", arm_n[0], arm_n[1], arm_n[4], arm_n[5], arm_n[6], arm_n[7],
                         robot_n[0] - arm_n[0] - arm_n[1]);
    }
    csv << "\n";
    if (k % 2 == 0) writeObjectPose(rig.objects_csv, t, box.name, obj);  // 50 Hz
    const int pb = sim->pelvisBody();
    const double yaw = yawOf(Eigen::Quaterniond(d->xquat[4 * pb], d->xquat[4 * pb + 1], d->xquat[4 * pb + 2], d->xquat[4 * pb + 3]));
    const Eigen::AngleAxisd unyaw(-yaw, Vector3d::UnitZ());
    see_box.push(t, unyaw * (obj.p_W - torso_p));
    see_box_room.push(t, obj.p_W);
    see_pelvis.push(t, pelvis);
    see_yaw.push(t, Vector3d(yaw, 0.0, 0.0));
    see_box_yaw.push(t, Vector3d(std::remainder(yawOf(obj.q_W) - yaw, 2.0 * M_PI), 0.0, 0.0));
    see_box_up.push(t, obj.q_W * Vector3d::UnitZ());
    see_box_xy_z.push(t, Vector3d((obj.q_W * Vector3d::UnitX()).z(), (obj.q_W * Vector3d::UnitY()).z(), 0.0));
    see_torso_pitch.push(t, Vector3d(std::asin(std::clamp(-d->xmat[9 * torso + 6], -1.0, 1.0)), 0.0, 0.0));
    for (std::size_t h = 0; h < 2; ++h) see_hand[h].push(t, unyaw * (hand_p[h] - torso_p));
    const Vector3d box_R = see_box.seen(t), box_room = see_box_room.seen(t), pelvis_W = see_pelvis.seen(t);
    const std::array<Vector3d, 2> hand_R{see_hand[0].seen(t), see_hand[1].seen(t)};
    const double yaw_seen = see_yaw.seen(t).x();
    const double box_yaw_R = see_box_yaw.seen(t).x();  // the box's seen yaw relative to the robot's heading [rad]
    const Eigen::AngleAxisd box_turn(box_yaw_R, Vector3d::UnitZ());  // box frame -> R

    Eigen::Vector2d v_body = Eigen::Vector2d::Zero();
    auto walkTo = [&](const Eigen::Vector2d& target_W, double max_speed) {
      return walkCommand(op, target_W, pelvis_W, yaw_seen, max_speed, dt, &walk_integral, &v_body);
    };
    const double pick_near_x = pick.pos[0] - 0.5 * pick.top_size[0];
    const double place_near_x = place.pos[0] - 0.5 * place.top_size[0];
    const double torso_z = torso_p.z();  // the operator sees the tables' tops relative to the head camera
    const double grasp_z_R = box_R.z() + 0.5 * box_h - op.grasp_below_top_m;  // the hands' height at the box
    const double carry_z_R = place.height + op.carry_clearance_m + box_h - op.grasp_below_top_m - torso_z;
    const double place_z_R = place.height - op.place_press_m + box_h - op.grasp_below_top_m - torso_z;
    const bool entered = phase != last_phase;
    const bool unwind = entered && ((op.unwind_on_release && (phase == kRelease || phase == kOpen)) || (op.unwind_on_place && phase == kOpen));
    last_phase = phase;
    bool grip = false, working = false;
    double work_f = -1.0;  // crouch and look-down fraction when not all or nothing (standing up slowly)
    std::array<Vector3d, 2> target{hand_R[0], hand_R[1]};
    // The wrists' targets beside the box: centre c (frame R), half distance w across the box (its
    // sides' normal, as the operator sees the box turned).
    auto beside = [&](const Vector3d& c, double w) {
      target[0] = c + box_turn * Vector3d(0, w, 0);
      target[1] = c - box_turn * Vector3d(0, w, 0);
    };
    // Holding the box: the hands keep the grip's frame (centre and turn as when it was gripped)
    // instead of following the box they hold: following it, a box that turned or slid in the grip
    // turned or pushed the hands' targets further the same way, and slipped out.
    auto holding = [&](double x, double z, double w) {
      const Eigen::AngleAxisd turn(held_yaw, Vector3d::UnitZ());
      target[0] = Vector3d(x, carry_y, z) + turn * Vector3d(0, w, 0);
      target[1] = Vector3d(x, carry_y, z) - turn * Vector3d(0, w, 0);
    };
    // The box as seen resting upright on the pick top (slipped out of the hands, or set back), and
    // the operator's second grip of it: open the hands and lower them beside it again (kDescend
    // keeps a hand above the box's top until it is beside the box).
    auto restingOnPick = [&]() {
      return std::abs(box_room.z() - 0.5 * box_h - pick.height) < 0.02 && see_box_up.seen(t).z() > std::cos(0.2);
    };
    auto gripAgain = [&]() { phase = kDescend, phase_t0 = t, ++regrabs, regrip_x = std::numeric_limits<double>::quiet_NaN(); };
    // Lifting and carrying, the operator watches the box, not its own hands: the hands go up (or
    // down) at most lift_speed until the box's bottom is seen carry_clearance_m above the place
    // table's top, however far the box has sagged in the grip; at most max_raise_m above the
    // nominal carrying height.
    auto raiseBox = [&]() {
      const double want = place.height + op.carry_clearance_m, bottom = box_room.z() - 0.5 * box_h;
      const double rate = std::clamp(2.0 * (want - bottom), -op.lift_speed, op.lift_speed);
      lift_z = std::min(carry_z_R + op.max_raise_m, lift_z + rate * dt);
    };
    // The box's near side as the operator sees it (W x; the tables face the robot's start) [m].
    auto boxNearSide = [&]() {
      const double yaw_W = box_yaw_R + yaw_seen;
      return box_room.x() - 0.5 * box.size[0] * std::abs(std::cos(yaw_W)) - 0.5 * box.size[1] * std::abs(std::sin(yaw_W));
    };
    // The grasp's centre on the box: `in` behind its near side (along the box), at the box's centre
    // height (frame R); grasp_in_m, or regrip_in_m after a slide.
    auto graspCentre = [&](double in) -> Vector3d { return box_R + box_turn * Vector3d(-0.5 * box.size[0] + in, 0, 0); };
    const double regrip_in = op.regrip_in_m != 0 ? op.regrip_in_m : op.grasp_in_m;
    const double grasp_in = slid ? regrip_in : op.grasp_in_m;
    Vector3d grasp_c = graspCentre(grasp_in);
    if (op.freeze_regrip_aim && slid && std::isfinite(regrip_x)) grasp_c.x() = regrip_x;
    switch (phase) {
      case kSettle:
        if (t >= op.settle_s) phase = kEngage, phase_t0 = t;
        break;
      case kEngage:
        if (t - phase_t0 < 0.05) vr.buttons[pmg::teleop::kRightHand] = pmg::teleop::kVrButtonLower;
        else vr.buttons[pmg::teleop::kRightHand] = 0;
        if (t - phase_t0 >= 0.15) phase = kApproach, phase_t0 = t;
        break;
      case kApproach: {
        const Vector3d box_W = torso_p + Eigen::AngleAxisd(yaw_seen, Vector3d::UnitZ()) * box_R;
        working_y = box_W.y();
        if (walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_far_m, working_y), op.max_speed) < op.arrive_tol_m && t - phase_t0 > 1.0)
          phase = kRaise, phase_t0 = t, walk_integral.setZero();
        if (t - phase_t0 > 20.0) phase = kDone;
        break;
      }
      case kRaise:
      case kCloseIn: {
        // Standing upright, hands open beside the box and above its top; then walk in. (Walking in
        // crouched and bent with both arms forward tipped the robot onto the table.)
        grip = true;
        const double hover_z_R = box_R.z() + 0.5 * box_h + op.hover_m;
        beside(Vector3d(phase == kRaise ? std::min(hand_R[0].x(), hand_R[1].x()) : grasp_c.x(), grasp_c.y(), hover_z_R), half_w + op.spread_m);
        const double err = std::max((hand_R[0] - target[0]).norm(), (hand_R[1] - target[1]).norm());
        if (phase == kRaise) {
          walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_far_m, working_y), op.max_speed);
          if (t - phase_t0 > 1.5 && (err < 0.04 || t - phase_t0 > 6.0)) phase = kCloseIn, phase_t0 = t, walk_integral.setZero();
        } else {
          const bool there = walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m, working_y), op.max_speed) < op.arrive_tol_m;
          if ((there && t - phase_t0 > 1.0) || t - phase_t0 > 12.0) phase = kDescend, phase_t0 = t, walk_integral.setZero();
        }
        break;
      }
      case kDescend: {
        // In place: crouch and bend, the open hands going down beside the box to the grasp height.
        grip = working = true;
        beside(Vector3d(grasp_c.x(), grasp_c.y(), grasp_z_R), half_w + op.spread_m);
        // A hand not yet seen beside the box (across it, within side_tol_m of its place) stays above
        // the box's top: lowered early it lands on the box and shoves it away. After a slide the
        // open hands are beside the box already and move along its sides at the grasp height
        // (raised over it, they dragged it forward again).
        for (std::size_t h = 0; h < 2; ++h) {
          const Vector3d off = box_turn.inverse() * (hand_R[h] - target[h]);
          if (op.side_tol_m > 0 && !slid && std::hypot(off.x(), off.y()) > op.side_tol_m)
            target[h].z() = std::max(target[h].z(), box_R.z() + 0.5 * box_h + op.hover_m);
        }
        walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m, working_y), op.max_speed);
        const double err = std::max((hand_R[0] - target[0]).norm(), (hand_R[1] - target[1]).norm());
        if ((err < 0.04 && t - phase_t0 > 1.5) || t - phase_t0 > 6.0) phase = kSqueeze, phase_t0 = t;
        break;
      }
      case kSqueeze:
        grip = working = true;
        if (entered) squeeze_y = half_w + op.spread_m;
        squeeze_y = std::max(half_w - op.squeeze_m, squeeze_y - (op.spread_m + op.squeeze_m) / op.squeeze_s * dt);
        beside(Vector3d(grasp_c.x(), grasp_c.y(), grasp_z_R), squeeze_y);
        walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m, working_y), op.max_speed);
        if (t - phase_t0 > op.squeeze_s + 0.5) {
          // A box whose near side is further beyond the pick top's edge than slide_to_m is first slid
          // towards the robot and gripped again, nearer its centre of mass.
          if (op.slide_to_m > -1.0 && !slid && boxNearSide() - pick_near_x > op.slide_to_m + 0.01)
            phase = kSlide, phase_t0 = t, slide_x = 0.5 * (hand_R[0].x() + hand_R[1].x());
          else
            phase = kLift, phase_t0 = t, lift_z = 0.5 * (hand_R[0].z() + hand_R[1].z()), grip_z = lift_z;
        }
        break;
      case kSlide:
        // Gripped, the hands draw back at slide_speed along the table until the box's near side is
        // seen slide_to_m beyond the pick top's edge.
        grip = working = true;
        slide_x -= op.slide_speed * dt;
        beside(Vector3d(slide_x, grasp_c.y(), grasp_z_R), half_w - op.squeeze_m);
        walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m, working_y), op.max_speed);
        if (boxNearSide() - pick_near_x <= op.slide_to_m || t - phase_t0 > 6.0) phase = kRelease, phase_t0 = t;
        break;
      case kRelease:
        // Open the hands beside the box; then lower them beside it again (kDescend) and squeeze.
        grip = working = true;
        if (entered) squeeze_y = half_w - op.squeeze_m;
        squeeze_y = std::min(half_w + op.spread_m, squeeze_y + (op.spread_m + op.squeeze_m) / op.squeeze_s * dt);
        beside(Vector3d(std::min(grasp_c.x(), 0.5 * (hand_R[0].x() + hand_R[1].x())), grasp_c.y(), grasp_z_R), squeeze_y);
        walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m, working_y), op.max_speed);
        {
          // Open until both wrists are seen clear of the box's sides (across it): hands still touching
          // it drag it forward as they move on to the deeper grip.
          bool clear = true;  // release_clear_m 0: no check, the opening time alone
          for (std::size_t h = 0; op.release_clear_m > 0 && h < 2; ++h)
            clear = clear && std::abs((box_turn.inverse() * (hand_R[h] - box_R)).y()) >= half_w + op.release_clear_m;
          if ((t - phase_t0 > op.squeeze_s + 0.3 && clear) || t - phase_t0 > op.squeeze_s + 4.0) {
            phase = kDescend, phase_t0 = t, slid = true;
            regrip_x = graspCentre(regrip_in).x();
          }
        }
        break;
      case kLift:
        // Up to the carrying height, standing up meanwhile (the head rises at once; the robot's
        // posture follows at the shaper's rate).
        grip = true;
        if (entered) {
          stand_t0 = -1.0;
          carry_x = 0.5 * (hand_R[0].x() + hand_R[1].x());
          hug_x = carry_x - op.hug_m;
          carry_y = 0.5 * (hand_R[0].y() + hand_R[1].y());
          held_yaw = box_yaw_R;
        }
        // Stand up only once the box is seen clear of the pick top (standing up swings the hands
        // back with the torso and drags a box still on the table out of a grip at its near part).
        if (stand_t0 < 0 && op.stand_after_lift_m <= 0) stand_t0 = phase_t0;
        if (stand_t0 < 0 && (box_room.z() - 0.5 * box_h > pick.height + op.stand_after_lift_m || t - phase_t0 > 4.0)) stand_t0 = t;
        work_f = stand_t0 < 0 ? 1.0 : (op.stand_s > 0 ? std::max(0.0, 1.0 - (t - stand_t0) / op.stand_s) : 0.0);
        if (op.hug_m > 0 && box_room.z() - 0.5 * box_h > pick.height + std::max(0.02, op.stand_after_lift_m))
          carry_x = std::max(hug_x, carry_x - op.hug_speed * dt);
        raiseBox();
        holding(carry_x, lift_z, half_w - op.squeeze_m);
        if (!op.lift_in_place) walkTo(Eigen::Vector2d(pick_near_x - op.stand_off_m - 0.10, working_y), op.max_speed);
        // Walk off with the box once it is up and, with stand_after_lift_m, once the robot has stood
        // up (standing up while stepping off swung the box out of the hands).
        if (box_room.z() - 0.5 * box_h > place.height + 0.5 * op.carry_clearance_m && t - phase_t0 > 2.0 &&
            (op.stand_after_lift_m <= 0 || (stand_t0 >= 0 && t - stand_t0 > op.stand_s + 0.5)))
          phase = kCarry, phase_t0 = t, walk_integral.setZero();
        if (t - phase_t0 > 12.0) phase = kCarry, phase_t0 = t, walk_integral.setZero();
        if (op.setback_tilt_rad > 0 && regrabs < op.max_regrabs && phase == kLift) {
          const double tilt = std::acos(std::clamp(see_box_up.seen(t).z(), -1.0, 1.0));
          if (tilt > op.setback_tilt_rad && box_room.z() - 0.5 * box_h - pick.height < op.setback_height_m)
            phase = kSetBack, phase_t0 = t, ++setbacks;
        }
        break;
      case kSetBack: {
        // Crouch and bend again, and lower the box back onto the pick top in the grip's frame; once
        // it rests there, grip it again (kDescend, as after a slip).
        grip = working = true;
        lift_z = std::max(grip_z - 0.01, lift_z - op.lift_speed * dt);
        holding(carry_x, lift_z, half_w - op.squeeze_m);
        if ((restingOnPick() && t - phase_t0 > 1.0) || t - phase_t0 > 4.0) gripAgain();
        break;
      }
      case kCarry: {
        grip = true;
        raiseBox();
        holding(carry_x, lift_z, half_w - op.squeeze_m);
        // Sideways first, then in (carry_back_m): held back from the tables until in line with the place top.
        Eigen::Vector2d place_at(place_near_x - op.place_stand_off_m, place.pos[1]);
        if (op.carry_back_m > 0 && std::abs(pelvis_W.y() - place_at.y()) > op.carry_align_m)
          place_at.x() = std::min(place_at.x(), pick_near_x - op.stand_off_m - op.carry_back_m);
        const bool there = walkTo(place_at, op.carry_speed) < op.arrive_tol_m && place_at.x() == place_near_x - op.place_stand_off_m;
        if ((there && t - phase_t0 > 1.0) || t - phase_t0 > 25.0) phase = kLower, phase_t0 = t, walk_integral.setZero();
        break;
      }
      case kLower: {
        // Forward until the box is over the place top, then down onto it.
        grip = true;
        if (entered) level = kLevelNo;
        const double x_goal = place_near_x + op.place_in_m - torso_p.x() + grasp_in;
        if (level == kLevelNo) carry_x += std::clamp(x_goal - carry_x, -0.05 * dt, 0.05 * dt);
        const bool over = std::abs(x_goal - carry_x) < 0.01 || t - phase_t0 > 3.0;
        // The box as seen: its z axis (which way its top leans), its tilt and its lowest corner (W z).
        const Vector3d up = see_box_up.seen(t), xy_z = see_box_xy_z.seen(t);
        const double tilt = std::acos(std::clamp(up.z(), -1.0, 1.0));
        const double lowest = box_room.z() - 0.5 * (box.size[0] * std::abs(xy_z.x()) + box.size[1] * std::abs(xy_z.y()) + box_h * std::abs(up.z()));
        if (op.level_on_place && over && level != kLevelDone) {
          if (level == kLevelNo && tilt > op.level_tilt_rad && tilt < op.level_max_rad && (unyaw * up).x() > 0.0 && std::abs(lowest - place.height) < op.level_touch_m)
            level = kLevelOn, level_t0 = t, level_x0 = carry_x, level_from = tilt;
          if (level == kLevelOn) {
            carry_x -= op.level_speed * dt;  // back towards the robot, at the height held: the box turns about its far edge
            if (tilt < op.level_done_rad || level_x0 - carry_x > op.level_back_m || t - level_t0 > 4.0) level = kLevelDone, level_to = tilt;
          }
        }
        // place_flat_rad: on down until the box is seen resting flat on the top (or place_deeper_m deeper).
        const bool resting_flat = op.place_flat_rad <= 0 || (tilt < op.place_flat_rad && lowest - place.height < 0.01);
        const double place_floor = op.place_flat_rad > 0 ? place_z_R - op.place_deeper_m : place_z_R;
        if (over && level != kLevelOn && !(resting_flat && lift_z <= place_z_R)) lift_z = std::max(place_floor, lift_z - op.lift_speed * dt);
        holding(carry_x, lift_z, half_w - op.squeeze_m);
        walkTo(Eigen::Vector2d(place_near_x - op.place_stand_off_m, place.pos[1]), op.max_speed);
        const bool placed = lift_z <= place_z_R && (resting_flat || lift_z <= place_floor);
        if ((level != kLevelOn && placed && t - phase_t0 > 2.0) || t - phase_t0 > 12.0) phase = kOpen, phase_t0 = t;
        break;
      }
      case kOpen:
        grip = true;
        if (entered) squeeze_y = half_w - op.squeeze_m;
        squeeze_y = std::min(half_w + op.spread_m, squeeze_y + (op.spread_m + op.squeeze_m) / op.squeeze_s * dt);
        if (t - phase_t0 > op.squeeze_s) lift_z += op.lift_speed * dt;  // then up, away from the box
        holding(carry_x, lift_z, squeeze_y);
        if (t - phase_t0 > op.squeeze_s + 1.0) phase = kWait, phase_t0 = t;
        break;
      case kWait:
        if (t - phase_t0 > 2.0) phase = kDone;
        break;
      case kDone:
        break;
    }
    // Headset: displacement for walking, crouch and look-down while grasping.
    const Eigen::Vector2d disp = headFor(v_body, tc.position_deadband_m, tc.velocity_gain[0]);
    const double wf = work_f >= 0.0 ? work_f : (working ? 1.0 : 0.0);
    vr.head_position = {disp.x(), disp.y(), head_z - wf * op.crouch_m};
    double psi = 0.0;  // headset yaw beyond the dead band: the robot turns (teleop velocity_gain[2] per rad)
    if (op.face_box_gain > 0 && phase >= kApproach && phase <= (op.face_box_hold ? kRelease : kCloseIn) && std::abs(box_yaw_R) > 0.03)
      psi = headYawFor(std::clamp(op.face_box_gain * box_yaw_R, -0.3, 0.3), tc.yaw_deadband_rad, tc.velocity_gain[2]);
    if (op.carry_heading_gain > 0 && (phase == kCarry || phase == kLower)) {
      const double e = std::remainder(yaw_seen - place.yaw, 2.0 * M_PI);  // heading error to the place table's square [rad]
      if (std::abs(e) > 0.03) psi = headYawFor(std::clamp(-op.carry_heading_gain * e, -0.3, 0.3), tc.yaw_deadband_rad, tc.velocity_gain[2]);
    }
    const Eigen::Quaterniond hq(Eigen::AngleAxisd(psi, Vector3d::UnitZ()) * Eigen::AngleAxisd(wf * op.look_down_rad, Vector3d::UnitY()));
    vr.head_quat = {hq.w(), hq.x(), hq.y(), hq.z()};
    if (grip && !aligned) {
      for (std::size_t h = 0; h < 2; ++h) {
        hand_H[h] = controllerAtRobotHand(d, shoulder_l, shoulder_r, torso_p, unyaw, tc, hand_R[h]);
        // The hand's pointing direction (its x axis, along the forearm) in T when the grip is
        // squeezed: the operator turns the controller so that the hand points forward (fingers
        // along the box's side), the palm kept facing in.
        const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> R_WT(d->xmat + 9 * torso), R_WHd(d->xmat + 9 * hand_body[h]);
        const Vector3d x0 = (R_WT.transpose() * R_WHd).col(0);
        // Along the box's sides when the operator turns its hands to the box's seen yaw; toe-in
        // turns the left hand's fingers right (-z) and the right hand's left.
        const double yaw_h = (op.hands_along_box ? box_yaw_R : 0.0) + (h == 0 ? -1.0 : 1.0) * op.hand_toe_in_rad;
        const Vector3d want =
            Eigen::AngleAxisd(yaw_h, Vector3d::UnitZ()) * Vector3d(std::cos(op.hand_pitch_rad), 0.0, -std::sin(op.hand_pitch_rad));
        // Pronation: the left hand rolls clockwise about its pointing axis seen from behind, the right anticlockwise.
        turn_H[h] = Eigen::Quaterniond(Eigen::AngleAxisd((h == 0 ? 1.0 : -1.0) * op.hand_roll_rad, want)) *
                    Eigen::Quaterniond::FromTwoVectors(x0, want);
      }
      aligned = true;
      turn_t0 = t;
    }
    // Holding the box, the operator turns its controllers against the torso's pitch change (seen as
    // the camera's horizon tilting): the teleop mapping puts the hands' orientation in the torso's
    // frame, so a robot standing up from the bend would otherwise turn the hands, and the box held
    // between them, up by as much. Not holding, the turn goes back at unturn_speed.
    {
      const double pitch_seen = see_torso_pitch.seen(t).x();
      if (op.keep_hand_pitch && (phase == kLift || phase == kCarry || phase == kLower) && std::isfinite(last_torso_pitch))
        pitch_comp -= pitch_seen - last_torso_pitch;
      else
        pitch_comp -= std::clamp(pitch_comp, -op.unturn_speed * dt, op.unturn_speed * dt);
      last_torso_pitch = pitch_seen;
    }
    if (aligned) {
      const double f = std::clamp((t - turn_t0) / op.turn_s, 0.0, 1.0);
      for (std::size_t h = 0; h < 2; ++h) {
        const Eigen::Quaterniond qh =
            Eigen::Quaterniond(Eigen::AngleAxisd(pitch_comp, Vector3d::UnitY())) * Eigen::Quaterniond::Identity().slerp(f, turn_H[h]);
        vr.hand_quat[h] = {qh.w(), qh.x(), qh.y(), qh.z()};
      }
    }
    if (grip && unwind)
      for (std::size_t h = 0; h < 2; ++h) hand_H[h] = controllerAtRobotHandBent(d, torso, shoulder_l, shoulder_r, unyaw, tc, hand_R[h]);
    if (grip)
      for (std::size_t h = 0; h < 2; ++h) {
        if (op.feedforward) {
          // The operator holds the controller where the mapping puts the robot hand at its target,
          // for the torso's pitch and roll as they are now (as a person keeps a held box in front of
          // them while standing up), plus a correction of what it sees still off.
          hand_bias[h] += op.hand_gain * dt * (target[h] - hand_R[h]) / tc.arm_scale;
          if (hand_bias[h].norm() > op.max_lead_m / tc.arm_scale) hand_bias[h] *= op.max_lead_m / tc.arm_scale / hand_bias[h].norm();
          hand_H[h] = controllerAtRobotHandBent(d, torso, shoulder_l, shoulder_r, unyaw, tc, target[h]) + hand_bias[h];
          continue;
        }
        hand_H[h] += op.hand_gain * dt * (target[h] - hand_R[h]) / tc.arm_scale;
        // Anti-windup: an operator does not hold the controller further than max_lead_m (robot
        // scale) beyond where the robot's hand is seen: a hand that stalls is not pushed on.
        if (op.max_lead_m > 0) {
          const Vector3d at = controllerAtRobotHandBent(d, torso, shoulder_l, shoulder_r, unyaw, tc, hand_R[h]);
          Vector3d lead = hand_H[h] - at;
          const double lim = op.max_lead_m / tc.arm_scale;
          if (op.vertical_lead_m > 0 && (phase == kLift || phase == kCarry || phase == kLower)) {
            const double lim_z = op.vertical_lead_m / tc.arm_scale;  // the height on its own bound
            lead.z() = std::clamp(lead.z(), -lim_z, lim_z);
            const double horizontal = lead.head<2>().norm();
            if (horizontal > lim) lead.head<2>() *= lim / horizontal;
            hand_H[h] = at + lead;
          } else if (lead.norm() > lim) {
            hand_H[h] = at + lead * (lim / lead.norm());
          }
        }
      }
    const Vector3d head(vr.head_position[0], vr.head_position[1], vr.head_position[2]);
    for (std::size_t h = 0; h < 2; ++h) {
      const Vector3d p = head + (aligned ? hand_H[h] : rest[h]);
      vr.hand_position[h] = {p.x(), p.y(), p.z()};
      vr.grip[h] = grip ? 1.0 : 0.0;
    }
    vr.frame = k;
    sample.vr = vr;
    sample.vr_time = t;
    const pmg::TickStatus st = app.stepLockstep(sample);
    rig.watchTrunk(t);
    if (pmg::silRobotFell(app.controller().lastState(), st)) {
      fell = true;
      break;
    }
    // A box seen back on the pick table, upright, while lifting or carrying: it slipped out of the
    // hands; grip it again.
    if ((phase == kLift || phase == kCarry) && t - phase_t0 > 2.0 && regrabs < op.max_regrabs && restingOnPick()) gripAgain();
    // A box seen below the pick table's top has fallen: nothing left to do.
    if (phase > kSqueeze && box_room.z() < pick.height - 0.05) phase = kDone;
  }
  const pmg::RunSummary summary = app.finish();
  TrialResult r;
  r.trial = trial;
  r.fell = fell;
  r.seconds = traj.empty() ? 0.0 : traj.back().t;
  r.verdict = pmg::judgeBox(scene, box.name, pick.name, place.name, traj, fell);
  rig.judgeTrunk(&r.verdict);
  rig.judgeFault(summary, &r.verdict);
  r.trunk_on_table_s = rig.trunk_on_table_s;
  r.trunk_on_table_n = rig.trunk_on_table_n;
  r.regrabs = regrabs;
  r.level_from_rad = level_from;
  r.level_to_rad = level_to;
  r.setbacks = setbacks;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_teleop_bench: teleoperated tasks in the SIL, scored like the paper's Table III"};
  std::string task = "wipe", out_dir, controller_path = pmg::resolveData("config/controller/g1_sil_teleop.yaml").string();
  std::string operator_path, scene_path;
  int trials = 20;
  std::uint64_t seed = 0;
  app.add_option("--task", task, "wipe | box")->check(CLI::IsMember({"wipe", "box"}));
  app.add_option("--trials", trials, "randomised trials")->check(CLI::Range(1, 1000));
  app.add_option("--seed", seed, "first trial's seed (trial k draws seed + k)");
  app.add_option("--out", out_dir, "output folder (created)")->required();
  app.add_option("--controller", controller_path, "controller config with teleop enabled")->check(CLI::ExistingFile);
  app.add_option("--operator", operator_path, "operator parameters (default config/tasks/<task>_operator.yaml)");
  app.add_option("--scene", scene_path, "task scene (default config/tasks/<task>_scene.yaml)");
  bool no_figures = false;
  app.add_flag("--no-figures", no_figures, "no frame strips and trace plots (the event logs are still kept)");
  CLI11_PARSE(app, argc, argv);
  const bool figures = !no_figures;
  try {
    if (operator_path.empty()) operator_path = pmg::resolveData("config/tasks/" + task + "_operator.yaml").string();
    if (scene_path.empty()) scene_path = pmg::resolveData("config/tasks/" + task + "_scene.yaml").string();
    // Each task's operator has its own parameters (unknown keys are refused naming the file).
    OperatorConfig wipe_op;
    BoxOperatorConfig box_op;
    if (task == "wipe") wipe_op = pmg::yaml::loadYamlFile<OperatorConfig>(operator_path);
    else box_op = pmg::yaml::loadYamlFile<BoxOperatorConfig>(operator_path);
    const pmg::TaskScene scene = pmg::loadTaskScene(scene_path);
    pmg::ControllerConfig config = pmg::loadControllerConfig(controller_path);
    config.makeOffline();
    if (!config.teleop.enabled) throw pmg::ConfigError(controller_path + ": teleop.enabled must be true for the task bench");
    fs::create_directories(out_dir);
    nlohmann::json summary = {{"task", task}, {"trials", trials}, {"seed", seed}, {"scene", scene_path},
                              {"operator", operator_path}, {"controller", controller_path},
                              {"paper_success_rate", task == "wipe" ? 0.95 : 0.80}};
    int successes = 0;
    int shown_success = -1, shown_failure = -1;  // the trials whose event logs are kept for the frame strips
    summary["failures"] = nlohmann::json::array();
    summary["trial_results"] = nlohmann::json::array();
    for (int k = 0; k < trials; ++k) {
      const std::uint64_t trial_seed = seed + static_cast<std::uint64_t>(k);
      const TrialResult r = task == "wipe" ? runWipe(k, trial_seed, scene, config, wipe_op, out_dir)
                                           : runBox(k, trial_seed, scene, config, box_op, out_dir);
      successes += r.verdict.success ? 1 : 0;
      fmt::print("trial {:2d}: {} {} ({:.1f} s) {}\n", k, r.verdict.success ? "success" : "FAILED ",
                 r.verdict.failure, r.seconds, r.verdict.detail);
      std::fflush(stdout);
      summary["trial_results"].push_back({{"trial", k}, {"success", r.verdict.success}, {"measure", r.verdict.measure},
                                          {"fell", r.fell}, {"seconds", r.seconds}, {"regrabs", r.regrabs}, {"detail", r.verdict.detail}});
      if (task == "wipe") summary["trial_results"].back()["unpins"] = r.unpins;
      summary["trial_results"].back()["trunk_on_table_s"] = r.trunk_on_table_s;
      summary["trial_results"].back()["trunk_on_table_n"] = r.trunk_on_table_n;
      if (task == "box") {
        summary["trial_results"].back()["level_from_rad"] = r.level_from_rad;
        summary["trial_results"].back()["level_to_rad"] = r.level_to_rad;
        summary["trial_results"].back()["setbacks"] = r.setbacks;
      }
      if (!r.verdict.success)
        summary["failures"].push_back({{"trial", k}, {"reason", r.verdict.failure}, {"detail", r.verdict.detail}});
      // Keep the event log and object track of the first success and the first failure; drop the rest
      // (about 10 MB per trial).
      int& shown = r.verdict.success ? shown_success : shown_failure;
      if (shown < 0) {
        shown = k;
      } else {
        fs::remove(fs::path(out_dir) / fmt::format("trial_{}.lcmlog", k));
        fs::remove(fs::path(out_dir) / fmt::format("trial_{}_objects.csv", k));
      }
    }
    summary["successes"] = successes;
    summary["success_rate"] = static_cast<double>(successes) / trials;
    // Figures of the first success and the first failure: a frame strip (pmg_render_log over the
    // trial's scene, the object placed from its track) and a trace plot (scripts/plot_teleop_trial.py).
    summary["figures"] = nlohmann::json::object();
    for (const auto& [label, k] : {std::pair<const char*, int>{"success", shown_success}, {"failure", shown_failure}}) {
      if (k < 0) continue;
      nlohmann::json f = {{"trial", k}, {"log", fmt::format("trial_{}.lcmlog", k)}, {"objects", fmt::format("trial_{}_objects.csv", k)},
                          {"scene", fmt::format("trial_{}_scene.xml", k)}};
      if (figures) {
        const fs::path dir = fs::absolute(out_dir);  // render_sil.sh runs from its own folder
        const std::string strip = fmt::format("{}_trial_{}_strip.png", label, k), trace = fmt::format("{}_trial_{}_trace.png", label, k);
        // scripts/render_sil.sh starts Xvfb when there is no display and runs this build's pmg_render_log.
        const std::string render_cmd = fmt::format(
            "PMG_RENDER_LOG='{}' bash '{}' '{}' '{}' --mjcf '{}' --objects '{}' --strip '{}' --frames 8 --t0 1 --width 320 --height 420 "
            "--azimuth 145 --elevation -20 --distance 2.6 --lookat-dz -0.15 --no-reflections --samples 2",
            (pmg::executableDir() / "pmg_render_log").string(), pmg::resolveData("scripts/render_sil.sh").string(),
            (dir / f["log"].get<std::string>()).string(), dir.string(), (dir / f["scene"].get<std::string>()).string(),
            (dir / f["objects"].get<std::string>()).string(), strip);
        const std::string trace_cmd = fmt::format("python3 '{}' '{}' --out '{}'", pmg::resolveData("scripts/plot_teleop_trial.py").string(),
                                                  (dir / fmt::format("trial_{}.csv", k)).string(), (dir / trace).string());
        // A missing display or renderer costs the picture, not the trials' results.
        f["strip"] = std::system(render_cmd.c_str()) == 0 ? nlohmann::json(strip) : nlohmann::json(nullptr);
        f["trace"] = std::system(trace_cmd.c_str()) == 0 ? nlohmann::json(trace) : nlohmann::json(nullptr);
        if (f["strip"].is_null()) fmt::print(stderr, "pmg_teleop_bench: warning: no frame strip: {}\n", render_cmd);
        if (f["trace"].is_null()) fmt::print(stderr, "pmg_teleop_bench: warning: no trace plot: {}\n", trace_cmd);
      }
      summary["figures"][label] = f;
    }
    std::ofstream(fs::path(out_dir) / "summary.json") << summary.dump(1) << "\n";
    fmt::print("{}: {}/{} successes ({:.2f}; paper {:.2f})\n", task, successes, trials,
               static_cast<double>(successes) / trials, summary["paper_success_rate"].get<double>());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_teleop_bench: %s\n", e.what());
    return 1;
  }
}
