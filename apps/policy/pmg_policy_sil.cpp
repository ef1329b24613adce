// pmg_policy_sil: runs a trained actor in the MuJoCo 2.2 SIL (no gantry) on a command script and
// reports the seed's Table I metrics, falls and foot slip.
//
//   pmg_policy_sil --model config/policies/g1_pmg_policy.onnx --seeds 5 --out out/sil
//
// It evaluates the product path: every seed is one pmg::ControllerApp built from the controller
// config (default config/controller/g1_sil_policy.yaml) -- the same HAL stack (supervisor always
// on), command shaper, reference limiter, PMG generator + GCO, policy stage and runner that
// pmg_controller runs. The script (--commands, the one command-script format) is injected as
// pmg_controller --script does. Only the metrics read simulator truth, from an observer after each
// tick. The run is built by pmg::makeSilRun (pmg/controller/sil_eval.hpp, shared with pmg_sim2real_eval).
//
// --config selects the Table I configuration the actor was trained for (the contract check refuses
// a mismatch, naming pmg.gco / pmg.mode):
//   pmg_gco      full PMG: generator + GCO; the actor observes u' (PMG eq. 19)
//   pmg          PMG without GCO: the actor observes the shaped command u
//   single_gait  single-gait imitation: the generator runs on the walk_forward clip alone at its
//                nominal speed whatever the command; the actor observes u
// Seed k > 0 perturbs the initial joint positions (uniform +-0.02 rad) and seeds the sensor noise.
// --sliding-friction MU sets the foot-floor friction coefficient of every run (mujoco.sliding_friction,
// in [0.1, 2]; default the MJCF's 1.0): training draws it in [0.4, 1.25], the SIL otherwise runs 1.0 only.
//
// Metrics (mean absolute error over the run after the first second, per seed, then mean over seeds):
//   LinVel [m/s]  |v_cmd,xy - v_xy| with v the pelvis velocity in the heading (yaw) frame
//   YawVel [rad/s] |w_cmd - w_z|, w_z the pelvis yaw rate (world z)
//   Roll, Pitch [rad] |cmd - torso roll/pitch| (torso_link, ZYX Euler angles in the world frame)
//   Height [m]   |h_cmd - pelvis z|, h_cmd = the commanded pelvis height (standing when none)
//   (all errors against the user's command u, also in the GCO configuration whose actor sees u')
//   falls        runs in which the pelvis dropped below 0.4 m or tilted more than 60 deg, or the
//                supervisor latched a fall
//   foot slip [m/s] mean horizontal speed of a foot (ankle_roll_link origin) while it touches the floor
//
// Per segment of the script (issue 12, "as users feel it"): means over the last 60 % of each
// segment (its steady state), per seed, then the mean over the seeds that ran through that window
// without falling (a seed that fell is left out of the segment it fell in and of all later ones;
// "fallen" counts them). Axes vx, vy [m/s], wz [rad/s], pitch, roll [rad], height [m]:
//   command    the script's command for the segment (height: the standing height when none)
//   achieved   as the Table I metrics above: pelvis velocity in the heading frame, pelvis yaw rate,
//              torso_link pitch/roll, pelvis height
//   reference  what the reference the actor is given implies (Controller::referenceOutput()):
//              vx, vy, wz the base motion that holds its stance feet still
//              (pmg::gco::stanceImpliedVelocity on q_ref/qd_ref of the legs and the contact
//              schedule; mean over ticks with a stance foot), pitch/roll of torso_link in the
//              reference pose as the robot stands on it: the pelvis tilted so that the stance
//              soles lie flat (the rotation that maps their mean normal onto z, as
//              pmg::motion::PostureProbe measures the static clips; level when no foot is in
//              stance; KDL, pelvis -> torso_link), height the template's GeneratorOutput::base_height
//   shaped     the shaper's command: vx, vy, wz, pitch, roll, height after its limits, envelopes
//              (crouched, bent, walking height floor) and slew, before the feedback: what the
//              controller chose to attempt of the command (scripts/segment_band.py scores both)
//   u_prime    GCO's u' (PMG eq. 19; with GCO off the template's own base state)
//   u_feedback vx, vy, wz, pitch, roll (and height, when posture_feedback.height_ki > 0) after the
//              velocity and posture feedback: what the generator got (the shaped command when off;
//              --velocity-feedback / --posture-feedback on|off override the config;
//              --crouched-envelope off drops commands.crouched_height, --bent-envelope off
//              commands.bent_pitch, --walking-height-floor off commands.walking_min_height,
//              --posture-envelope off opens posture_feedback.envelope_min/max, --joint-stops off the
//              MJCF's soft joint stops instead of mujoco.joint_stops, --braking off no braking steps,
//              --upset-upright off a latched upset guard keeps the operator's posture)
//   estimate   the feedback's leg-odometry estimate of vx, vy, wz and, with the height fed back, the
//              kinematic pelvis height (null when off)
//   feedback_held_fraction, feedback_decayed_fraction   the share of the window's ticks in which the
//              velocity feedback did not integrate: leg odometry rejected / pelvis tilted (null when off)
//   ratio, reference_ratio   achieved/command and reference/command for vx, vy, wz where
//              |command| >= 0.05 (m/s or rad/s), else null
// printed as a table and written to summary.json "segments" (per seed under runs[k].segments).
// scripts/plot_segments.py <out> plots them (time series per axis, the tracking envelope).
// A fall ends a seed's run; with --restart-after-fall a fresh robot stands 2 s and goes on from the
// segment after the one it fell in (per-segment results for the rest of a grid such as
// config/policies/eval_envelope.yaml; runs[k].falls_s lists every fall, the Table I metrics stop at
// the first; runs[k].faults lists every latched supervisor fault: script time, cause, joint, value).
// Writes <out>/seed<k>.csv (per tick; *_ref: the reference's implied motion as above, vx/vy/wz nan
// without a stance foot; *_uopt: u'; episode: 0, then 1, 2, ... after each restart, whose first
// 2 s overlap the fallen episode's times; fb_held_ticks / fb_decayed_ticks: the velocity feedback's
// cumulative ticks without integration because leg odometry was rejected / the pelvis tilted;
// upset_hold: 1 while the upset guard holds the velocity command at zero, --upset-guard on|off;
// runs[k].upsets_s lists the script times it latched; vx_shaped, vy_shaped, wz_shaped: the shaper's
// command before the feedback, --feedback-within-envelopes on|off, --yaw-beyond-envelopes on|off, --max-velocity-headroom on|off,
// --stance-foot-nearest on|off (the velocity estimate's foot choice; summary.json stance_foot_nearest);
// --max-tilt-rad X (the pelvis tilt beyond which the velocity feedback's correction decays; summary.json max_tilt_rad);
// --walking-ki P R (the walking posture feedback's gains on pitch and roll; summary.json walking_ki);
// --walking-filter-time-s X, --stop-settle-s X (the posture feedback's walking low-pass and its wait after a stop;
// summary.json walking_filter_time_s, stop_settle_s); --small-command-bound-vx X (velocity_feedback.small_command_bound's
// v_x; summary.json small_command_bound);
// --imu-acc-lowpass-s X (the HAL's low-pass of the accelerometer before the loop; summary.json imu_acc_lowpass_s),
// --headroom-in-envelopes on|off (summary.json headroom_in_envelopes);
// vx_fb, vy_fb, wz_fb, pitch_fb, roll_fb, height_fb: the command after the feedback and feed-forward, the one the
// generator and the actor were given, nan when not active: training/eval_mjx.py --command-log replays it), <out>/frames<k>.csv and
// <out>/summary.json (runs[k].hal_slew_clamped_joint_cycles of runs[k].hal_joint_cycles: the
// supervisor's slew limit, hal_q_rate_max, held a joint's command back; --q-rate-max sets it).
// --probe FILE writes the first seed's first episode tick by tick for training/probe_sil.py: MuJoCo's
// qpos/qvel when the tick read its state, the state it read, the actor's observation and action, the
// motor commands it wrote, hal_slew, the joint-cycles the slew held back since the previous row, and last
// acc_x/y/z, the specific force the tick read (IMU frame, after the HAL's low-pass).
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <mujoco/mujoco.h>

#include "pmg/common/cli_checks.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/controller/sil_eval.hpp"
#include "pmg/gco/foot_slip.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"
#include "pmg/policy/policy_stage.hpp"

namespace {

void quatToRot(const double* q, double R[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - z * w); R[2] = 2 * (x * z + y * w);
  R[3] = 2 * (x * y + z * w); R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - x * w);
  R[6] = 2 * (x * z - y * w); R[7] = 2 * (y * z + x * w); R[8] = 1 - 2 * (x * x + y * y);
}

constexpr int kAxes = 6;  // vx, vy, wz, pitch, roll, height
constexpr const char* kAxisNames[kAxes] = {"vx", "vy", "wz", "pitch", "roll", "height"};
constexpr double kRatioMinCommand = 0.05;  // |command| below which a velocity ratio is null [m/s, rad/s]
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRestartStand = 2.0;  // --restart-after-fall: standing before the next segment [s]
constexpr std::size_t kNoSegment = static_cast<std::size_t>(-1);
using Axes = std::array<double, kAxes>;

/// Running means per axis (non-finite samples skipped).
struct AxisMeans {
  Axes sum{};
  std::array<long, kAxes> n{};
  void add(int i, double x) {
    if (!std::isfinite(x)) return;
    sum[static_cast<std::size_t>(i)] += x;
    ++n[static_cast<std::size_t>(i)];
  }
  Axes mean() const {
    Axes m;
    for (std::size_t i = 0; i < kAxes; ++i) m[i] = n[i] > 0 ? sum[i] / static_cast<double>(n[i]) : kNaN;
    return m;
  }
};

/// One seed's samples in one segment's window (the last 60 % of the segment).
struct SegmentSeed {
  AxisMeans achieved, reference, shaped, u_prime, feedback, estimate;
  long ticks = 0;         // ticks in the window
  long stance_ticks = 0;  // of which the reference had a stance foot
  long fb_held = 0, fb_decayed = 0;  // of which the velocity feedback held (odometry rejected) / decayed (tilt)
  double first_t = kNaN, last_t = kNaN;  // first and last tick in the window [s]
  bool fell = false;      // the robot fell during this segment
};

struct SegmentWindow {
  std::string name;
  double t_begin = 0, t_end = 0;    // the segment [s]
  double w_begin = 0, w_end = 0;    // the averaging window [s]
  Axes command{};
};

/// JSON text of a number (null when not finite).
std::string jnum(double x) {
  if (!std::isfinite(x)) return "null";
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

/// JSON list of times [s].
std::string jtimes(const std::vector<double>& ts) {
  std::string o = "[";
  for (std::size_t i = 0; i < ts.size(); ++i) o += (i ? ", " : "") + jnum(ts[i]);
  return o + "]";
}

/// JSON string literal (quotes, backslashes and control characters escaped).
std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else {
      o += c;
    }
  }
  return o + '"';
}

/// {"vx": .., ...} over the first @p count axes.
std::string jaxes(const Axes& a, int count = kAxes) {
  std::string o = "{";
  for (int i = 0; i < count; ++i)
    o += std::string(i ? ", " : "") + jstr(kAxisNames[i]) + ": " + jnum(a[static_cast<std::size_t>(i)]);
  return o + "}";
}

/// Velocity ratios x/command (vx, vy, wz; NaN where |command| < kRatioMinCommand).
Axes ratios(const Axes& x, const Axes& command) {
  Axes r;
  r.fill(kNaN);
  for (std::size_t i = 0; i < 3; ++i)
    if (std::abs(command[i]) >= kRatioMinCommand) r[i] = x[i] / command[i];
  return r;
}

struct Totals {
  double lin = 0, yaw = 0, roll = 0, pitch = 0, height = 0, slip = 0;
  long n = 0, slip_n = 0;
  bool fell = false;
  double fall_time = -1;
  double survived = 0;                // [s] until the first fall (or the end)
  std::vector<double> falls;          // [s] script time of every fall (more than one with restarts)
  int restarts = 0;
  std::vector<double> upsets;         // [s] script time of every upset the guard latched on
  std::vector<SegmentSeed> segments;  // (script segments)
  struct FaultRecord {
    double t = 0;                     // [s] script time the supervisor latched it
    std::string cause, joint;         // the fault in words; the joint's name for per-joint faults ("" otherwise)
    double value = 0;                 // the offending value (q [rad], tilt [rad], height [m], ...)
  };
  std::vector<FaultRecord> faults;    // every episode's latched supervisor fault, in order
  // The HAL supervisor's slew limit (safety.q_rate_max): joint-cycles it held a command back, of all
  // supervisor cycles x joints (every episode).
  unsigned long long slew_joint_cycles = 0, joint_cycles = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Evaluate a policy in the MuJoCo 2.2 SIL through pmg_controller's loop on a command script"};
  std::string model_path, robot_path, clips_dir, gco_path;
  std::string controller_path = pmg::resolveData("config/controller/g1_sil_policy.yaml").string();
  std::string commands = pmg::resolveData("config/policies/eval_commands.yaml").string(), out = "out/policy_sil";
  std::string config = "pmg_gco";
  int seeds = 3;
  int first_seed = 0;
  bool noise = true, native = true, restart_after_fall = false;
  double duration = -1, frame_period = 0.1;
  std::string probe_path;
  double q_rate_max = -1;
  double feedforward_return_s = -1;  // < 0: the controller config's
  double combined_ff_ratio = -1;     // < 0: the controller config's
  double max_tilt_rad = -1;          // < 0: the controller config's
  double imu_acc_lowpass_s = -1;     // < 0: the controller config's
  std::vector<double> walking_ki;    // empty: the controller config's
  double walking_filter_time_s = -1;  // < 0: the controller config's
  double stop_settle_s = -1;          // < 0: the controller config's
  double small_command_bound_vx = -1;  // < 0: the controller config's
  double sliding_friction = -1;  // < 0: the controller config's mujoco.sliding_friction
  app.add_option("--model", model_path, "ONNX actor with pmg.contract (default: the controller config's policy.model)");
  app.add_option("--controller", controller_path, "controller config YAML (the product path)")->capture_default_str();
  app.add_option("--robot", robot_path, "robot config YAML (default: the controller config's)");
  app.add_option("--clips", clips_dir, "PMG clip directory (default: the controller config's)");
  app.add_option("--config", config, "Table I configuration the actor was trained for")
      ->check(CLI::IsMember({"pmg_gco", "pmg", "single_gait"}));
  app.add_option("--gco", gco_path, "GCO options (default: the controller config's)");
  std::string blending;
  app.add_option("--blending", blending, "generator blending (default: the controller config's): consistent | paper")
      ->check(CLI::IsMember({"consistent", "paper"}));
  app.add_option("--commands", commands, "command script YAML")->capture_default_str();
  app.add_option("--seeds", seeds, "runs (seed k perturbs the initial pose, and the sensor noise)")->check(CLI::Range(1, 100));
  app.add_option("--first-seed", first_seed, "the first run's seed (runs first_seed .. first_seed + seeds - 1; held-out seeds for a check after the choices)")
      ->check(CLI::Range(0, 10000));
  app.add_option("--noise", noise, "sensor noise on the observation (as in training)");
  app.add_option("--native", native, "allocation-free native evaluator (false: ONNX Runtime)");
  app.add_option("--duration", duration, "override the sequence duration [s]")->check(pmg::cli::finiteIn(0.0, 1e5));
  app.add_option("--out", out, "output directory");
  app.add_option("--sliding-friction", sliding_friction,
                 "the foot-floor sliding friction coefficient of every geom (mujoco.sliding_friction; default: the "
                 "controller config's, 0 = the MJCF's 1.0); training draws it in [0.4, 1.25]")
      ->check(pmg::cli::finiteIn(0.1, 2.0));
  // The on|off switches; empty: the controller config's setting.
  std::string velocity_feedback, feedforward, posture_feedback, crouched_envelope, bent_envelope, posture_envelope, upset_guard,
      feedback_within_envelopes, yaw_beyond_envelopes, max_velocity_headroom, walking_height_floor, joint_stops, braking,
      upset_upright, decay_feedforward, stance_foot_nearest, headroom_in_envelopes;
  const auto onOff = [&app](const char* name, std::string* choice, const char* help) {
    app.add_option(name, *choice, help)->check(CLI::IsMember({"on", "off"}));
  };
  onOff("--velocity-feedback", &velocity_feedback,
        "closed-loop velocity tracking on leg odometry (default: the controller config's velocity_feedback)");
  onOff("--feedforward", &feedforward,
        "command-response feed-forward (velocity_feedback.feedforward; default: the controller config's)");
  onOff("--decay-feedforward", &decay_feedforward,
        "on: while the pelvis tilts beyond velocity_feedback.max_tilt_rad the feed-forward's share decays as the correction "
        "does (velocity_feedback.decay_feedforward), off: only the correction; default: the controller config's");
  onOff("--posture-feedback", &posture_feedback,
        "closed-loop torso pitch/roll tracking (default: the controller config's posture_feedback)");
  onOff("--crouched-envelope", &crouched_envelope,
        "off: no crouched velocity envelope (commands.crouched_height 0); default: the controller config's");
  onOff("--bent-envelope", &bent_envelope,
        "off: no bent velocity envelope (commands.bent_pitch 0); default: the controller config's");
  onOff("--posture-envelope", &posture_envelope,
        "off: the posture feedback's pitch/roll bounds wide open (posture_feedback.envelope_min/max +-1.5 rad); default: "
        "the controller config's");
  onOff("--upset-guard", &upset_guard,
        "on: the upset guard (velocity_feedback.upset_guard, with the config's thresholds or the defaults; needs the "
        "velocity feedback), off: none; default: the controller config's");
  onOff("--feedback-within-envelopes", &feedback_within_envelopes,
        "on: the velocity feedback's command kept inside the crouched and bent velocity envelopes "
        "(velocity_feedback.within_posture_envelopes), off: not; default: the controller config's");
  onOff("--stance-foot-nearest", &stance_foot_nearest,
        "on: with both soles in the stance band, the velocity estimate takes the foot nearer its prediction "
        "(velocity_feedback.stance_foot_nearest), off: their mean; default: the controller config's");
  onOff("--yaw-beyond-envelopes", &yaw_beyond_envelopes,
        "on: with the feedback within the envelopes, its yaw-rate correction is not bound by them "
        "(velocity_feedback.yaw_beyond_envelopes); default: the controller config's");
  onOff("--headroom-in-envelopes", &headroom_in_envelopes,
        "on: velocity_feedback.max_velocity_headroom applies at the crouched and bent envelopes' edges too "
        "(velocity_feedback.headroom_in_envelopes, with --feedback-within-envelopes); default: the controller config's");
  onOff("--max-velocity-headroom", &max_velocity_headroom,
        "off: the velocity feedback's command stays inside commands.max_velocity (velocity_feedback.max_velocity_headroom "
        "0), on: the config's (not 0 there); default: the controller config's");
  onOff("--walking-height-floor", &walking_height_floor,
        "off: no walking height floor (commands.walking_min_height 0); default: the controller config's");
  onOff("--joint-stops", &joint_stops,
        "off: the MJCF's soft joint stops (mujoco.joint_stops.timeconst 0); default: the controller config's");
  onOff("--braking", &braking,
        "off: no braking steps (velocity_feedback.brake_ratio 0), on: the config's (brake_ratio > 0 there); "
        "default: the controller config's");
  onOff("--upset-upright", &upset_upright,
        "off: a latched upset guard keeps the operator's posture (velocity_feedback.upset_guard.upright false), on: "
        "the torso goes upright while latched (needs the guard); default: the controller config's");
  app.add_flag("--restart-after-fall", restart_after_fall,
               "after a fall, start a fresh robot standing 2 s before the next segment and go on (per-segment "
               "results for the rest of the script; the Table I metrics stop at the first fall)");
  app.add_option("--frame-period", frame_period, "period of the body-position log <out>/frames<k>.csv [s] (frame strips)")
      ->check(pmg::cli::finiteIn(0.01, 10.0));
  app.add_option("--probe", probe_path,
                 "CSV of the first seed's first episode, one row per loop tick: MuJoCo's qpos and qvel (truth when "
                 "the tick read its state), the state the tick read (joints, IMU orientation, gyro, and at the end "
                 "of the row its specific force), the actor's observation and action, and the motor commands it "
                 "wrote (q, qd, kp, kd, tau_ff of every motor); for sim-to-sim comparisons (training/probe_sil.py)");
  // A number that overrides one config key, range-checked: empty (< 0 here) keeps the config's.
  const auto override_option = [&app](const char* name, double* value, const char* help, double lo, double hi) {
    app.add_option(name, *value, help)->check(pmg::cli::finiteIn(lo, hi));
  };
  override_option("--q-rate-max", &q_rate_max,
                  "the HAL supervisor's slew limit on commanded joint positions [rad/s] (default: the controller "
                  "config's safety.q_rate_max; 20 = before 2026-11-30)",
                  1.0, 2000.0);
  override_option("--feedforward-return-s", &feedforward_return_s,
                  "with the feed-forward's decay: the time its share takes to return from 0 to 1 once upright [s] "
                  "(velocity_feedback.feedforward_return_s; 0 = decay_time_s; default: the controller config's)",
                  0.0, 30.0);
  override_option("--combined-ff-ratio", &combined_ff_ratio,
                  "on a command moving all three axes, the feed-forward's max_correction shrinks to this share [0, 1] "
                  "(velocity_feedback.feedforward.combined_max_correction_ratio; 1 = off; default: the controller config's)",
                  0.0, 1.0);
  override_option("--max-tilt-rad", &max_tilt_rad,
                  "beyond this pelvis tilt the velocity feedback's correction decays instead of integrating [rad] "
                  "(velocity_feedback.max_tilt_rad; default: the controller config's)",
                  0.01, 1.5);
  override_option("--imu-acc-lowpass-s", &imu_acc_lowpass_s,
                  "time constant of the HAL's low-pass on the IMU's specific force before the loop samples it [s] "
                  "(timing.imu_acc_lowpass_s; 0 = raw samples; default: the controller config's)",
                  0.0, 0.1);
  override_option("--walking-filter-time-s", &walking_filter_time_s,
                  "time constant of the posture feedback's walking low-pass of the torso attitude [s] "
                  "(posture_feedback.walking_filter_time_s; default: the controller config's)",
                  0.0, 5.0);
  override_option("--stop-settle-s", &stop_settle_s,
                  "standing, the posture feedback integrates once the velocity command has been still this long [s] "
                  "(posture_feedback.stop_settle_s; 0 = from the first still tick; default: the controller config's)",
                  0.0, 5.0);
  override_option("--small-command-bound-vx", &small_command_bound_vx,
                  "a small v_x command's correction may grow to |u| itself, up to this [m/s] "
                  "(velocity_feedback.small_command_bound[0]; 0 = the ratio bound alone; default: the controller config's)",
                  0.0, 0.5);
  app.add_option("--walking-ki", walking_ki,
                 "the walking posture feedback's integral gains on torso pitch and roll [1/s], two values in [0, 5] "
                 "(posture_feedback.walking_ki; 0 = not fed back while walking; default: the controller config's)")
      ->expected(2)
      ->check(pmg::cli::finiteIn(0.0, 5.0));
  CLI11_PARSE(app, argc, argv);
  try {
    pmg::ControllerConfig base = pmg::loadSilEvalConfig(controller_path);  // lockstep, offline, no gantry
    if (!robot_path.empty()) {
      base.robot_file = robot_path;
      base.robot = pmg::loadRobotConfig(robot_path);
    }
    if (!clips_dir.empty()) base.clips_dir = clips_dir;
    if (!gco_path.empty()) base.gco = pmg::gco::loadGcoOptionsFile(gco_path);
    base.gco.enabled = config == "pmg_gco";
    if (!blending.empty()) base.generator.blending = blending == "paper" ? pmg::Blending::kPaper : pmg::Blending::kConsistent;
    if (!model_path.empty()) base.policy_file = model_path;
    if (q_rate_max > 0) base.q_rate_max = q_rate_max;
    if (base.policy_file.empty()) throw pmg::ConfigError(controller_path + ": policy.model: missing (or give --model)");
    base.policy_native = native;
    if (!velocity_feedback.empty()) base.velocity_feedback.enabled = velocity_feedback == "on";
    if (feedforward == "off") base.velocity_feedback.feedforward.enabled = false;
    if (feedforward == "on") {
      if (!base.velocity_feedback.enabled || !base.velocity_feedback.feedforward.enabled)
        throw pmg::ConfigError(controller_path + ": --feedforward on: velocity_feedback.feedforward is off there (or the feedback is)");
    }
    if (!decay_feedforward.empty()) base.velocity_feedback.decay_feedforward = decay_feedforward == "on";
    if (feedforward_return_s >= 0) base.velocity_feedback.feedforward_return_s = feedforward_return_s;
    if (combined_ff_ratio >= 0) base.velocity_feedback.feedforward.combined_max_correction_ratio = combined_ff_ratio;
    if (max_tilt_rad > 0) base.velocity_feedback.max_tilt_rad = max_tilt_rad;
    if (imu_acc_lowpass_s >= 0) base.imu_acc_lowpass_s = imu_acc_lowpass_s;
    if (!posture_feedback.empty()) base.posture_feedback.enabled = posture_feedback == "on";
    if (walking_ki.size() == 2) base.posture_feedback.walking_ki = {walking_ki[0], walking_ki[1]};
    if (walking_filter_time_s >= 0) base.posture_feedback.walking_filter_time_s = walking_filter_time_s;
    if (stop_settle_s >= 0) base.posture_feedback.stop_settle_s = stop_settle_s;
    if (small_command_bound_vx >= 0) base.velocity_feedback.small_command_bound[0] = small_command_bound_vx;
    const pmg::PostureFeedbackConfig open_posture;  // the keys' defaults: wide open
    const bool posture_open = base.posture_feedback.envelope_min == open_posture.envelope_min &&
                              base.posture_feedback.envelope_max == open_posture.envelope_max;
    if (posture_envelope == "off") {
      base.posture_feedback.envelope_min = open_posture.envelope_min;
      base.posture_feedback.envelope_max = open_posture.envelope_max;
    }
    if (posture_envelope == "on" && posture_open)
      throw pmg::ConfigError(controller_path + ": --posture-envelope on: posture_feedback.envelope_min/max are wide open there");
    if (!upset_guard.empty()) base.velocity_feedback.upset_guard.enabled = upset_guard == "on";
    if (!feedback_within_envelopes.empty()) base.velocity_feedback.within_posture_envelopes = feedback_within_envelopes == "on";
    if (!yaw_beyond_envelopes.empty()) base.velocity_feedback.yaw_beyond_envelopes = yaw_beyond_envelopes == "on";
    if (!headroom_in_envelopes.empty()) base.velocity_feedback.headroom_in_envelopes = headroom_in_envelopes == "on";
    if (!stance_foot_nearest.empty()) base.velocity_feedback.stance_foot_nearest = stance_foot_nearest == "on";
    if (max_velocity_headroom == "off") base.velocity_feedback.max_velocity_headroom = {0.0, 0.0, 0.0};
    if (max_velocity_headroom == "on" && base.velocity_feedback.max_velocity_headroom == std::array<double, 3>{0.0, 0.0, 0.0})
      throw pmg::ConfigError(controller_path + ": --max-velocity-headroom on: velocity_feedback.max_velocity_headroom is 0 there");
    if (const std::string e = base.velocity_feedback.validate(); !e.empty())
      throw pmg::ConfigError(controller_path + ": velocity_feedback." + e);
    // A commands: key whose 0 means off, switched by --OPTION off|on ("on" keeps the config's value).
    const auto commandsSwitch = [&](const std::string& choice, double* key, const char* option, const char* name) {
      if (choice == "off") *key = 0.0;
      if (choice == "on" && !(*key > 0.0))
        throw pmg::ConfigError(controller_path + ": " + option + " on: commands." + name + " is 0 (off) there");
    };
    commandsSwitch(crouched_envelope, &base.commands.crouched_height, "--crouched-envelope", "crouched_height");
    commandsSwitch(bent_envelope, &base.commands.bent_pitch, "--bent-envelope", "bent_pitch");
    commandsSwitch(walking_height_floor, &base.commands.walking_min_height, "--walking-height-floor", "walking_min_height");
    if (sliding_friction > 0) base.mujoco.sliding_friction = sliding_friction;
    if (joint_stops == "off") base.mujoco.joint_stops.timeconst = 0.0;
    if (joint_stops == "on" && !base.mujoco.joint_stops.enabled())
      throw pmg::ConfigError(controller_path + ": --joint-stops on: mujoco.joint_stops.timeconst is 0 (the MJCF's) there");
    if (braking == "off") base.velocity_feedback.brake_ratio = 0.0;
    if (braking == "on" && !(base.velocity_feedback.enabled && base.velocity_feedback.brake_ratio > 0.0))
      throw pmg::ConfigError(controller_path + ": --braking on: velocity_feedback.brake_ratio is 0 (or the feedback is off) there");
    if (!upset_upright.empty()) base.velocity_feedback.upset_guard.upright = upset_upright == "on";
    if (upset_upright == "on" && !(base.velocity_feedback.enabled && base.velocity_feedback.upset_guard.enabled))
      throw pmg::ConfigError(controller_path + ": --upset-upright on: velocity_feedback.upset_guard is off (or the feedback is) there");
    const pmg::RobotConfig& robot = base.robot;
    const pmg::CommandScript script = pmg::loadCommandScript(commands);
    const double T = duration > 0 ? duration : script.duration();
    const bool single_gait = config == "single_gait";
    std::filesystem::create_directories(out);
    const int nj = static_cast<int>(robot.numJoints());
    std::vector<Totals> totals;

    // Per-segment windows: the last 60 % of each segment (the last segment holds until T).
    std::vector<SegmentWindow> windows;
    for (std::size_t k = 0; k < script.segments.size(); ++k) {
      const pmg::CommandSegment& sg = script.segments[k];
      SegmentWindow w;
      w.name = sg.name;
      w.t_begin = sg.start;
      w.t_end = k + 1 == script.segments.size() ? std::max(sg.start + sg.duration, T) : sg.start + sg.duration;
      w.w_begin = w.t_begin + 0.4 * (w.t_end - w.t_begin);
      w.w_end = w.t_end;
      const pmg::Command& c = sg.command;
      w.command = {c.vx, c.vy, c.wz, c.pitch, c.roll, kNaN};
      if (c.height) w.command[5] = *c.height;
      windows.push_back(w);
    }
    // The reference's implied motion: leg chains (as GCO's), torso_link through KDL.
    const auto legs = pmg::gco::LegModel::fromRobotConfig(robot);
    pmg::gco::LegKinematics leg_kin(legs);
    const pmg::KinematicModel kinematics(robot);
    const pmg::LimbChain torso_chain = kinematics.chain(robot.base_link, "torso_link");
    pmg::ChainFkWorkspace torso_fk(torso_chain);
    pmg::gco::GcoInput ref_in;
    Eigen::Isometry3d X_BT = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_BS = Eigen::Isometry3d::Identity();

    std::ofstream probe;
    if (!probe_path.empty()) {
      probe.open(probe_path);
      if (!probe) throw std::runtime_error("--probe " + probe_path + ": cannot open for writing");
      probe.precision(10);
    }
    // The standing height the controller crouches from (ControllerApp takes the squat clip's neutral
    // pelvis height): the summary records it for the feed-forward's fit (gains per crouch).
    double standing_height = base.commands.standing_height;
    double floor_friction = 0.0;  // the floor geom's sliding friction as simulated (summary.json)
    for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
      std::mt19937 rng(static_cast<unsigned>(1000 + seed));
      std::uniform_real_distribution<double> uni(-1.0, 1.0);
      Totals tot;
      tot.segments.resize(windows.size());
      std::ofstream csv(out + "/seed" + std::to_string(seed) + ".csv");
      std::ofstream frames(out + "/frames" + std::to_string(seed) + ".csv");
      const int frame_every = std::max(1, static_cast<int>(std::lround(frame_period / 0.01)));
      long k = 0;
      unsigned long long held = 0;
      pmg::RunSummary rs;
      // Episode 0 plays the script from its start; with --restart-after-fall, each later episode
      // is a fresh robot standing kRestartStand seconds and then playing the script from the
      // segment after the one it fell in (times stay the script's: t = local time + offset).
      std::size_t first_seg = 0;
      for (int episode = 0;; ++episode) {
        pmg::CommandScript sub;
        double offset = 0.0;
        if (episode > 0) {
          sub.source_file = script.source_file;
          sub.ramp = script.ramp;
          offset = script.segments[first_seg].start - kRestartStand;
          pmg::CommandSegment stand;
          stand.name = "restart_stand";
          stand.duration = kRestartStand;
          sub.segments.push_back(stand);
          for (std::size_t s = first_seg; s < script.segments.size(); ++s) {
            sub.segments.push_back(script.segments[s]);
            sub.segments.back().start -= offset;
          }
        }
        const pmg::CommandScript& run_script = episode > 0 ? sub : script;
        // One ControllerApp over the SIL (pmg/controller/sil_eval.hpp, shared with pmg_sim2real_eval).
        pmg::SilRunOptions so;
        so.initial_q_offsets.resize(static_cast<std::size_t>(nj));
        for (int j = 0; j < nj; ++j)
          so.initial_q_offsets[static_cast<std::size_t>(j)] = 0.02 * uni(rng) * (seed > 0 || episode > 0 ? 1.0 : 0.0);
        so.sensor_noise = noise;
        so.noise_seed = static_cast<unsigned>(2000 + seed + 1000 * episode);
        if (single_gait) so.clip_files = {base.clips_dir + "/walk_forward.yaml"};
        so.policy_mode = single_gait ? "single_gait" : "pmg";
        so.telemetry = true;
        pmg::SilRun sil = pmg::makeSilRun(base, so);
        pmg::ControllerApp& loop = *sil.app;
        const mjModel* m = sil.sim->model();
        mjData* d = sil.sim->data();
        const int torso = mj_name2id(m, mjOBJ_BODY, "torso_link");
        const int feet[2] = {mj_name2id(m, mjOBJ_BODY, robot.left_foot_link.c_str()),
                             mj_name2id(m, mjOBJ_BODY, robot.right_foot_link.c_str())};
        const int floor = mj_name2id(m, mjOBJ_GEOM, "floor");
        if (floor >= 0) floor_friction = m->geom_friction[3 * floor];
        pmg::Controller& controller = loop.controller();
        standing_height = controller.config().commands.standing_height;
        if (single_gait)  // the forward clip at its nominal speed, neutral posture, whatever the command
          controller.setFixedGeneratorCommand(
              {controller.generator().model().dynamicClip(pmg::CommandAxis::kForward, 1)->nominal_scale, 0.0, 0.0});
        const int na = controller.policy()->runner().actionSize();
        const double standing = loop.config().commands.standing_height;
        const std::vector<std::string>& gen_joints = controller.generator().model().jointSpace().joint_names;
        bool same_order = gen_joints.size() == static_cast<std::size_t>(nj);
        for (std::size_t j = 0; same_order && j < gen_joints.size(); ++j)
          same_order = gen_joints[j] == robot.joints[j].name;
        if (!same_order)
          throw std::runtime_error("the generator's joint order differs from the robot config's (" + base.robot_file +
                                   ")");
        const pmg::gco::LegJointIndex leg_idx = legs->jointIndices(gen_joints);
        for (SegmentWindow& w : windows)
          if (!std::isfinite(w.command[5])) w.command[5] = standing;

        if (episode == 0) {
          csv << "t,segment";
          for (const char* a : kAxisNames) csv << ',' << a << "_cmd";
          for (const char* a : kAxisNames) csv << ',' << a;
          csv << ",height_ref,phase,contact_l,contact_r,ref_contact_l,ref_contact_r,mode";
          for (int j = 0; j < na; ++j) csv << ",q" << j;
          for (int j = 0; j < na; ++j) csv << ",qref" << j;
          // the reference's implied motion (vx/vy/wz nan without a stance foot) and GCO's u'
          csv << ",vx_ref,vy_ref,wz_ref,pitch_ref,roll_ref";
          for (const char* a : kAxisNames) csv << ',' << a << "_uopt";
          // the velocity command after the feedback (= the command when off) and leg odometry (nan when off)
          csv << ",vx_fb,vy_fb,wz_fb,vx_est,vy_est,wz_est,pitch_fb,roll_fb";
          // the pelvis tilt from vertical (the IMU's attitude) that the feedback's tilt guards read [rad]
          // the velocity feedback's cumulative ticks held (leg odometry rejected: no integration) and
          // decayed (pelvis tilted), 0 when off: their per-tick increments show where it cannot act
          // upset_hold: 1 while the upset guard holds the velocity command at zero
          // vx_leg, vy_leg, leg_feet: the leg-odometry sample of the tick (before the estimator's gate;
          // nan/0 without a stance foot), leg_rejected: 1 when the gate rejected it
          // vx_shaped, vy_shaped, wz_shaped: the shaper's command (after its limits, envelopes and slew;
          // before the feedback; nan when not active)
          // height_fb: the height command after the posture feedback (the shaper's when it is off; nan when not
          // active): with vx_fb..roll_fb, the command the generator and the actor were given (eval_mjx.py
          // --command-log replays it)
          csv << ",pelvis_tilt,episode,fb_held_ticks,fb_decayed_ticks,upset_hold,vx_leg,vy_leg,leg_feet,leg_rejected"
                 ",vx_shaped,vy_shaped,wz_shaped,height_fb\n";
          frames << "t";
          for (int b = 1; b < m->nbody; ++b)
            frames << "," << mj_id2name(m, mjOBJ_BODY, b) << ":" << m->body_parentid[b];
          frames << "\n";
        }
        const bool probing = probe.is_open() && seed == first_seed && episode == 0;
        std::uint64_t probe_slew = 0;
        const int n_obs = controller.policy()->runner().observationSize();
        if (probing) {  // columns: t, qpos[nq], qvel[nv], q/qd of the motors read, IMU, obs, action, commands
          probe << "t";
          for (int i = 0; i < m->nq; ++i) probe << ",qpos" << i;
          for (int i = 0; i < m->nv; ++i) probe << ",qvel" << i;
          for (int j = 0; j < nj; ++j) probe << ",state_q" << j;
          for (int j = 0; j < nj; ++j) probe << ",state_qd" << j;
          // hal_slew: joint-cycles the supervisor's slew limit held back since the previous row
          probe << ",imu_qw,imu_qx,imu_qy,imu_qz,gyro_x,gyro_y,gyro_z,mode,hal_slew";
          for (int i = 0; i < n_obs; ++i) probe << ",obs" << i;
          for (int i = 0; i < na; ++i) probe << ",action" << i;
          for (const char* f : {"cmd_q", "cmd_qd", "cmd_kp", "cmd_kd", "cmd_tau"})
            for (int j = 0; j < nj; ++j) probe << ',' << f << j;
          // acc_*: the specific force the tick read, IMU frame [m/s^2] (after the HAL's low-pass)
          probe << ",acc_x,acc_y,acc_z\n";
        }
        std::atomic<bool> stop{false};
        double fall_time = -1;
        std::uint64_t prev_held = 0, prev_decayed = 0;  // the velocity feedback's counters at the last tick
        std::uint64_t prev_upsets = 0;                  // the upset guard's count at the last tick
        const auto observe = [&](double t_local, const pmg::TickStatus& status, std::size_t local_segment) {
          const double t = t_local + offset;  // script time
          // the script's segment (npos: the stand before a restart)
          const std::size_t segment =
              episode == 0 ? local_segment : (local_segment == 0 ? kNoSegment : first_seg + local_segment - 1);
          const pmg::LowState& state = controller.lastState();
          const pmg::GeneratorOutput& g = controller.generator().output();
          const pmg::Command c = run_script.at(t_local);
          const double u[6] = {c.vx, c.vy, c.wz, c.pitch, c.roll, c.height.value_or(standing)};
          double Rb[9], Rt[9];
          quatToRot(state.base_quat_wxyz.data(), Rb);
          for (int i = 0; i < 9; ++i) Rt[i] = d->xmat[9 * torso + i];
          const double yaw = std::atan2(Rb[3], Rb[0]);
          const double* v = state.base_linear_velocity.data();
          const double vx = std::cos(yaw) * v[0] + std::sin(yaw) * v[1];
          const double vy = -std::sin(yaw) * v[0] + std::cos(yaw) * v[1];
          const double* w_B = state.imu.gyro.data();
          const double wz = Rb[6] * w_B[0] + Rb[7] * w_B[1] + Rb[8] * w_B[2];
          const double pitch = std::asin(std::clamp(-Rt[6], -1.0, 1.0)), roll = std::atan2(Rt[7], Rt[8]);
          const double height = state.base_position[2];
          bool contact[2] = {false, false};
          for (int ci = 0; ci < d->ncon; ++ci) {
            const mjContact& con = d->contact[ci];
            for (int f = 0; f < 2; ++f) {
              const int other = con.geom1 == floor ? con.geom2 : (con.geom2 == floor ? con.geom1 : -1);
              if (other >= 0 && m->geom_bodyid[other] == feet[f] && con.dist < 2e-3) contact[f] = true;
            }
          }
          for (int f = 0; f < 2 && episode == 0; ++f) {
            if (!contact[f]) continue;
            mjtNum vel[6];
            mj_objectVelocity(m, d, mjOBJ_BODY, feet[f], vel, 0);  // [angular; linear], world frame
            tot.slip += std::hypot(vel[3], vel[4]);
            ++tot.slip_n;
          }
          const bool fallen = pmg::silRobotFell(state, status);
          // What the reference the actor was given implies (valid while the loop is active).
          Axes ref;
          ref.fill(kNaN);
          const bool active = status.mode == pmg::Mode::kActive;
          const pmg::GeneratorOutput& r = controller.referenceOutput();
          if (active) {
            pmg::gco::fillFromGenerator(r, leg_idx, pmg::VelocityCommand{}, pmg::PostureCommand{}, &ref_in);
            const pmg::gco::ImpliedBaseVelocity iv = pmg::gco::stanceImpliedVelocity(leg_kin, ref_in);
            if (iv.valid) ref = {iv.v_x, iv.v_y, iv.yaw_rate, kNaN, kNaN, kNaN};
            if (torso_fk.tipPose(r.q_ref, X_BT)) {
              // The pelvis tilt the stance legs imply (the generator plays a level pelvis; a robot
              // standing on flat soles takes this tilt): R_WT = R_WB R_BT.
              Eigen::Vector3d n_B = Eigen::Vector3d::Zero();
              for (const pmg::Foot f : {pmg::Foot::kLeft, pmg::Foot::kRight}) {
                const auto i = static_cast<std::size_t>(f);
                if (ref_in.contact[i] && leg_kin.forward(f, ref_in.q_leg[i], &X_BS)) n_B += X_BS.linear().col(2);
              }
              const Eigen::Matrix3d R = pmg::soleLevelingRotation(n_B) * X_BT.linear();
              ref[3] = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
              ref[4] = std::atan2(R(2, 1), R(2, 2));
            }
            ref[5] = r.base_height;
          }
          const pmg::gco::BaseCommand& up = controller.gcoResult().u_opt;
          const Axes u_prime = {up.v_x, up.v_y, up.yaw_rate, up.pitch, up.roll, up.height};
          const pmg::VelocityCommand& sv = controller.commands().velocity();
          const pmg::PostureCommand& sp = controller.commands().posture();
          const Axes shaped = {sv.vx, sv.vy, sv.wz, sp.pitch, sp.roll, sp.height};
          Axes fb, est;
          fb.fill(kNaN);
          est.fill(kNaN);
          double height_fb = kNaN;  // the height after the posture feedback, whether or not it feeds the height back
          if (const pmg::VelocityFeedback* vf = controller.velocityFeedback(); vf && active) {
            const pmg::VelocityCommand& c_fb = vf->command();
            fb[0] = c_fb.vx;
            fb[1] = c_fb.vy;
            fb[2] = c_fb.wz;
            const std::array<double, 3> e = vf->filteredEstimate();
            std::copy(e.begin(), e.end(), est.begin());
          } else if (active) {
            fb[0] = controller.commands().velocity().vx;
            fb[1] = controller.commands().velocity().vy;
            fb[2] = controller.commands().velocity().wz;
          }
          if (active) {
            const pmg::PostureFeedback* pf = controller.postureFeedback();
            const pmg::PostureCommand& ps = pf ? pf->command() : controller.commands().posture();
            fb[3] = ps.pitch;
            fb[4] = ps.roll;
            height_fb = ps.height;
            if (pf && (base.posture_feedback.height_ki > 0.0 || base.posture_feedback.walking_height_ki > 0.0)) {
              fb[5] = ps.height;
              est[5] = pf->measuredHeight();
            }
          }
          const pmg::VelocityFeedback* vfb = controller.velocityFeedback();
          const std::uint64_t fb_held = vfb ? vfb->heldTicks() : 0, fb_decayed = vfb ? vfb->decayedTicks() : 0;
          const long held_now = static_cast<long>(fb_held - std::min(fb_held, prev_held));
          const long decayed_now = static_cast<long>(fb_decayed - std::min(fb_decayed, prev_decayed));
          prev_held = fb_held;
          prev_decayed = fb_decayed;
          const pmg::UpsetGuard* guard = controller.upsetGuard();
          const std::uint64_t upsets = guard ? guard->upsets() : 0;
          if (upsets > prev_upsets) tot.upsets.push_back(t);
          prev_upsets = upsets;
          if (segment < windows.size()) {
            SegmentSeed& ss = tot.segments[segment];
            if (fallen) ss.fell = true;
            if (!fallen && t >= windows[segment].w_begin - 1e-9 && t < windows[segment].w_end - 1e-9) {
              const Axes ach = {vx, vy, wz, pitch, roll, height};
              if (ss.ticks++ == 0) ss.first_t = t;
              ss.last_t = t;
              if (std::isfinite(ref[0])) ++ss.stance_ticks;
              ss.fb_held += held_now;
              ss.fb_decayed += decayed_now;
              for (int i = 0; i < kAxes; ++i) {
                ss.achieved.add(i, ach[static_cast<std::size_t>(i)]);
                ss.reference.add(i, ref[static_cast<std::size_t>(i)]);
                if (active) ss.u_prime.add(i, u_prime[static_cast<std::size_t>(i)]);
                if (active) ss.shaped.add(i, shaped[static_cast<std::size_t>(i)]);
                ss.feedback.add(i, fb[static_cast<std::size_t>(i)]);
                ss.estimate.add(i, est[static_cast<std::size_t>(i)]);
              }
            }
          }
          if (episode == 0 && t >= 1.0 && !fallen) {  // Table I: until the first fall
            tot.lin += std::hypot(u[0] - vx, u[1] - vy);
            tot.yaw += std::abs(u[2] - wz);
            tot.pitch += std::abs(u[3] - pitch);
            tot.roll += std::abs(u[4] - roll);
            tot.height += std::abs(u[5] - height);
            ++tot.n;
          }
          csv << t << ',' << run_script.segments[local_segment].name;
          for (double x : u) csv << ',' << x;
          csv << ',' << vx << ',' << vy << ',' << wz << ',' << pitch << ',' << roll << ',' << height << ','
              << g.base_height << ',' << g.phase << ',' << contact[0] << ',' << contact[1] << ',' << g.in_contact[0]
              << ',' << g.in_contact[1] << ',' << pmg::toString(status.mode);
          for (int j = 0; j < na; ++j) csv << ',' << state.motors[static_cast<std::size_t>(j)].q;
          for (int j = 0; j < na; ++j) csv << ',' << controller.reference()[static_cast<std::size_t>(j)];
          for (int i = 0; i < 5; ++i) csv << ',' << ref[static_cast<std::size_t>(i)];
          for (double x : u_prime) csv << ',' << x;
          for (int i = 0; i < 3; ++i) csv << ',' << fb[static_cast<std::size_t>(i)];
          for (int i = 0; i < 3; ++i) csv << ',' << est[static_cast<std::size_t>(i)];
          csv << ',' << fb[3] << ',' << fb[4];
          csv << ',' << std::acos(std::clamp(Rb[8], -1.0, 1.0)) << ',' << episode << ',' << fb_held << ',' << fb_decayed
              << ',' << (guard && guard->latched() ? 1 : 0);
          {
            const double nan = std::numeric_limits<double>::quiet_NaN();
            const pmg::BaseVelocityEstimate* leg = vfb ? &vfb->estimator().lastLegOdometry() : nullptr;
            const bool leg_ok = leg && leg->valid;
            csv << ',' << (leg_ok ? leg->v_x : nan) << ',' << (leg_ok ? leg->v_y : nan) << ',' << (leg ? leg->stance_feet : 0)
                << ',' << (vfb && vfb->estimator().rejecting() ? 1 : 0);
            const pmg::VelocityCommand& us = controller.commands().velocity();
            csv << ',' << (active ? us.vx : nan) << ',' << (active ? us.vy : nan) << ',' << (active ? us.wz : nan) << ','
                << height_fb << '\n';
          }
          if (probing) {
            const pmg::LowState& st = controller.lastState();
            probe << t_local;
            for (int i = 0; i < m->nq; ++i) probe << ',' << d->qpos[i];
            for (int i = 0; i < m->nv; ++i) probe << ',' << d->qvel[i];
            for (int j = 0; j < nj; ++j) probe << ',' << st.motors[static_cast<std::size_t>(j)].q;
            for (int j = 0; j < nj; ++j) probe << ',' << st.motors[static_cast<std::size_t>(j)].qd;
            for (double x : st.imu.quat_wxyz) probe << ',' << x;
            for (double x : st.imu.gyro) probe << ',' << x;
            probe << ',' << pmg::toString(status.mode);
            pmg::hal::safety::SafetyStatus hs;
            loop.safety().status(hs);  // the newest status (lockstep: this thread ran the cycles)
            const std::uint64_t slew_now = hs.slew_clamped_joint_ticks;
            probe << ',' << (slew_now - probe_slew);
            probe_slew = slew_now;
            const float* o = controller.policy()->observation();
            for (int i = 0; i < n_obs; ++i) probe << ',' << o[i];
            const float* a = controller.policy()->runner().action();
            for (int i = 0; i < na; ++i) probe << ',' << a[i];
            const pmg::LowCommand& lc = controller.lastCommand();
            for (int f = 0; f < 5; ++f)
              for (int j = 0; j < nj; ++j) {
                const pmg::MotorCommand& mc = lc.motors[static_cast<std::size_t>(j)];
                probe << ',' << (f == 0 ? mc.q : f == 1 ? mc.qd : f == 2 ? mc.kp : f == 3 ? mc.kd : mc.tau_ff);
              }
            for (double x : st.imu.acc) probe << ',' << x;
            probe << '\n';
          }
          if (k++ % frame_every == 0) {  // world positions of every body origin (x y z) for frame strips
            frames << t;
            for (int b = 1; b < m->nbody; ++b)
              frames << ',' << d->xpos[3 * b] << ' ' << d->xpos[3 * b + 1] << ' ' << d->xpos[3 * b + 2];
            frames << '\n';
          }
          if (episode == 0) tot.survived = t + 0.01;
          if (fallen && fall_time < 0) {
            fall_time = t;
            tot.falls.push_back(t);
            if (!tot.fell) {
              tot.fell = true;
              tot.fall_time = t;
            }
            stop = true;
          }
        };
        rs = loop.run(T - offset, &run_script, &stop, observe);
        if (rs.fault != pmg::FaultCode::kNone)
          tot.faults.push_back({offset + rs.fault_time, pmg::toString(rs.fault), rs.fault_joint_name, rs.fault_value});
        held += static_cast<unsigned long long>(controller.policy()->runner().counters().held);
        tot.slew_joint_cycles += rs.slew_clamped_joint_cycles;
        tot.joint_cycles += rs.hal_cycles * static_cast<unsigned long long>(nj);
        if (fall_time < 0 || !restart_after_fall) break;
        // Go on after the segment it fell in (or after the first one of this episode when it
        // fell while standing before it), as long as the script has one left.
        const std::size_t fell_in = script.segmentIndex(fall_time);
        const bool fell_standing = episode > 0 && fall_time < script.segments[first_seg].start;
        first_seg = std::max(fell_in + 1, fell_standing ? first_seg + 1 : first_seg);
        if (first_seg >= script.segments.size() || script.segments[first_seg].start >= T) break;
        ++tot.restarts;
      }
      totals.push_back(tot);
      const double n = std::max<long>(1, tot.n);
      std::printf("seed %d: %s after %.2f s | LinVel %.4f m/s  YawVel %.4f rad/s  Roll %.4f rad  Pitch %.4f rad  Height %.4f m  slip %.4f m/s  (policy holds %llu; HAL slew %.2f %% of joint-cycles; final mode %s, fault %s)",
                  seed, tot.fell ? "FELL" : "ok", tot.survived, tot.lin / n, tot.yaw / n, tot.roll / n, tot.pitch / n,
                  tot.height / n, tot.slip / std::max<long>(1, tot.slip_n), held,
                  100.0 * static_cast<double>(tot.slew_joint_cycles) / static_cast<double>(std::max(1ULL, tot.joint_cycles)),
                  pmg::toString(rs.final_mode),
                  pmg::toString(rs.fault));
      for (const Totals::FaultRecord& f : tot.faults) {
        std::printf(" | %s", f.cause.c_str());
        if (!f.joint.empty()) std::printf(" (%s %.3f)", f.joint.c_str(), f.value);
        std::printf(" at %.2f s", f.t);
      }
      if (!tot.upsets.empty()) {
        std::printf(" | %zu upsets at", tot.upsets.size());
        for (double f : tot.upsets) std::printf(" %.2f", f);
        std::printf(" s");
      }
      if (tot.restarts > 0) {
        std::printf(" | %d restarts, falls at", tot.restarts);
        for (double f : tot.falls) std::printf(" %.2f", f);
        std::printf(" s");
      }
      std::printf("\n");
      std::fflush(stdout);
    }
    // Per segment: the mean over the seeds that ran through its window without falling.
    struct SegmentResult {
      Axes achieved, reference, shaped, u_prime, feedback, estimate;
      int seeds = 0, fallen = 0;
      long ticks = 0, fb_held = 0, fb_decayed = 0;  // over the seeds that covered the window
    };
    std::vector<SegmentResult> seg_results(windows.size());
    for (std::size_t k = 0; k < windows.size(); ++k) {
      const SegmentWindow& w = windows[k];
      AxisMeans a, r, sh, u, fbm, em;
      SegmentResult& res = seg_results[k];
      for (const Totals& t : totals) {
        const SegmentSeed& ss = t.segments[k];
        const bool covered =
            ss.ticks > 0 && !ss.fell && ss.first_t <= w.w_begin + 0.015 && ss.last_t >= w.w_end - 0.015;
        if (!covered) {  // fell in this segment, or earlier without a restart (else: the run ended before)
          const bool fell_before = std::any_of(t.falls.begin(), t.falls.end(), [&](double f) { return f < w.w_end; });
          if (ss.fell || fell_before) ++res.fallen;
          continue;
        }
        ++res.seeds;
        res.ticks += ss.ticks;
        res.fb_held += ss.fb_held;
        res.fb_decayed += ss.fb_decayed;
        const Axes ma = ss.achieved.mean(), mr = ss.reference.mean(), mu = ss.u_prime.mean();
        const Axes mf = ss.feedback.mean(), me = ss.estimate.mean(), ms = ss.shaped.mean();
        for (int i = 0; i < kAxes; ++i) {
          const auto ii = static_cast<std::size_t>(i);
          a.add(i, ma[ii]);
          r.add(i, mr[ii]);
          sh.add(i, ms[ii]);
          u.add(i, mu[ii]);
          fbm.add(i, mf[ii]);
          em.add(i, me[ii]);
        }
      }
      res.achieved = a.mean();
      res.reference = r.mean();
      res.shaped = sh.mean();
      res.u_prime = u.mean();
      res.feedback = fbm.mean();
      res.estimate = em.mean();
    }
    if (!windows.empty()) {
      std::printf("\nper segment (means over the last 60 %% of each segment and over seeds): "
                  "command / reference / achieved\n");
      std::printf("%-14s %5s", "segment", "seeds");
      const char* units[kAxes] = {"m/s", "m/s", "rad/s", "rad", "rad", "m"};
      for (int i = 0; i < kAxes; ++i) {
        char h[32];
        std::snprintf(h, sizeof h, "%s [%s]", kAxisNames[i], units[i]);
        std::printf(" | %-20s", h);
      }
      std::printf("\n");
      for (std::size_t k = 0; k < windows.size(); ++k) {
        const SegmentResult& res = seg_results[k];
        std::printf("%-14.14s %3d/%d", windows[k].name.c_str(), res.seeds, seeds);
        for (std::size_t i = 0; i < kAxes; ++i)
          std::printf(" | %6.3f %6.3f %6.3f", windows[k].command[i], res.reference[i], res.achieved[i]);
        std::printf("\n");
      }
    }

    std::ofstream js(out + "/summary.json");
    const std::array<double, 3> headroom =
        base.velocity_feedback.enabled ? base.velocity_feedback.max_velocity_headroom : std::array<double, 3>{0.0, 0.0, 0.0};
    double acc[6] = {0, 0, 0, 0, 0, 0};
    int falls = 0;
    js << "{\"model\": " << jstr(model_path) << ", \"config\": " << jstr(config) << ", \"blending\": " << jstr(base.generator.blending == pmg::Blending::kPaper ? "paper" : "consistent")
       << ", \"velocity_feedback\": " << (base.velocity_feedback.enabled ? "true" : "false")
       << ", \"feedforward\": " << (base.velocity_feedback.enabled && base.velocity_feedback.feedforward.enabled ? "true" : "false")
       << ", \"decay_feedforward\": " << (base.velocity_feedback.enabled && base.velocity_feedback.feedforward.enabled && base.velocity_feedback.decay_feedforward ? "true" : "false")
       << ", \"feedforward_return_s\": " << base.velocity_feedback.feedforward_return_s
       << ", \"combined_ff_ratio\": " << base.velocity_feedback.feedforward.combined_max_correction_ratio
       << ", \"posture_feedback\": " << (base.posture_feedback.enabled ? "true" : "false")
       << ", \"upset_guard\": " << (base.velocity_feedback.upset_guard.enabled ? "true" : "false")
       << ", \"upset_upright\": " << (base.velocity_feedback.upset_guard.enabled && base.velocity_feedback.upset_guard.upright ? "true" : "false")
       << ", \"joint_stops_timeconst_s\": " << base.mujoco.joint_stops.timeconst
       << ", \"floor_friction\": " << floor_friction
       << ", \"brake_ratio\": " << (base.velocity_feedback.enabled ? base.velocity_feedback.brake_ratio : 0.0)
       << ", \"brake_crouch_scaled\": " << (base.velocity_feedback.brake_crouch_scaled ? "true" : "false")
       << ", \"feedback_within_envelopes\": " << (base.velocity_feedback.enabled && base.velocity_feedback.within_posture_envelopes ? "true" : "false")
       << ", \"yaw_beyond_envelopes\": " << (base.velocity_feedback.enabled && base.velocity_feedback.within_posture_envelopes && base.velocity_feedback.yaw_beyond_envelopes ? "true" : "false")
       << ", \"headroom_in_envelopes\": " << (base.velocity_feedback.enabled && base.velocity_feedback.within_posture_envelopes && base.velocity_feedback.headroom_in_envelopes ? "true" : "false")
       << ", \"stance_foot_nearest\": " << (base.velocity_feedback.enabled && base.velocity_feedback.stance_foot_nearest ? "true" : "false")
       << ", \"max_tilt_rad\": " << base.velocity_feedback.max_tilt_rad
       << ", \"small_command_bound\": [" << base.velocity_feedback.small_command_bound[0] << ", "
       << base.velocity_feedback.small_command_bound[1] << ", " << base.velocity_feedback.small_command_bound[2] << "]"
       << ", \"imu_acc_lowpass_s\": " << base.imu_acc_lowpass_s
       << ", \"walking_ki\": [" << base.posture_feedback.walking_ki[0] << ", " << base.posture_feedback.walking_ki[1] << "]"
       << ", \"walking_filter_time_s\": " << base.posture_feedback.walking_filter_time_s
       << ", \"stop_settle_s\": " << base.posture_feedback.stop_settle_s
       << ", \"max_velocity_headroom\": [" << headroom[0] << ", " << headroom[1] << ", " << headroom[2] << "]"
       << ", \"posture_envelope\": [" << base.posture_feedback.envelope_min[0] << ", " << base.posture_feedback.envelope_min[1]
       << ", " << base.posture_feedback.envelope_max[0] << ", " << base.posture_feedback.envelope_max[1] << "]"
       << ", \"standing_height\": " << standing_height << ", \"walking_min_height\": " << base.commands.walking_min_height
       << ", \"crouched_height\": " << base.commands.crouched_height << ", \"bent_pitch\": " << base.commands.bent_pitch << ", \"commands\": " << jstr(commands)
       << ", \"duration_s\": " << T << ", \"hal_q_rate_max\": " << base.q_rate_max << ", \"runs\": [";
    for (std::size_t s = 0; s < totals.size(); ++s) {
      const Totals& t = totals[s];
      const double n = std::max<long>(1, t.n);
      const double vals[6] = {t.lin / n, t.yaw / n, t.roll / n, t.pitch / n, t.height / n, t.slip / std::max<long>(1, t.slip_n)};
      for (int i = 0; i < 6; ++i) acc[i] += vals[i];
      falls += t.fell;
      js << (s ? ", " : "") << "{\"seed\": " << (first_seed + static_cast<int>(s)) << ", \"fell\": " << (t.fell ? "true" : "false") << ", \"survived_s\": " << t.survived
         << ", \"lin_vel\": " << vals[0] << ", \"yaw_vel\": " << vals[1] << ", \"roll\": " << vals[2] << ", \"pitch\": " << vals[3]
         << ", \"height\": " << vals[4] << ", \"foot_slip\": " << vals[5]
         << ", \"fall_time_s\": " << jnum(t.fell ? t.fall_time : kNaN) << ", \"restarts\": " << t.restarts
         << ", \"hal_slew_clamped_joint_cycles\": " << t.slew_joint_cycles << ", \"hal_joint_cycles\": " << t.joint_cycles
         << ", \"falls_s\": " << jtimes(t.falls) << ", \"upsets_s\": " << jtimes(t.upsets) << ", \"faults\": [";
      for (std::size_t f = 0; f < t.faults.size(); ++f)
        js << (f ? ", " : "") << "{\"t\": " << jnum(t.faults[f].t) << ", \"cause\": " << jstr(t.faults[f].cause)
           << ", \"joint\": " << jstr(t.faults[f].joint) << ", \"value\": " << jnum(t.faults[f].value) << "}";
      js << "]"
         << ", \"segments\": [";
      for (std::size_t k = 0; k < windows.size(); ++k) {
        const SegmentSeed& ss = t.segments[k];
        js << (k ? ", " : "") << "{\"name\": " << jstr(windows[k].name) << ", \"ticks\": " << ss.ticks
           << ", \"stance_ticks\": " << ss.stance_ticks << ", \"achieved\": " << jaxes(ss.achieved.mean())
           << ", \"reference\": " << jaxes(ss.reference.mean()) << ", \"shaped\": " << jaxes(ss.shaped.mean())
           << ", \"u_prime\": " << jaxes(ss.u_prime.mean())
           << ", \"u_feedback\": " << jaxes(ss.feedback.mean()) << ", \"estimate\": " << jaxes(ss.estimate.mean()) << "}";
      }
      js << "]}";
    }
    const double S = static_cast<double>(totals.size());
    js << "], \"mean\": {\"lin_vel\": " << acc[0] / S << ", \"yaw_vel\": " << acc[1] / S << ", \"roll\": " << acc[2] / S
       << ", \"pitch\": " << acc[3] / S << ", \"height\": " << acc[4] / S << ", \"foot_slip\": " << acc[5] / S
       << ", \"falls\": " << falls << "}, \"segment_window\": 0.6, \"ratio_min_command\": " << kRatioMinCommand
       << ", \"segments\": [";
    const bool fb_on = base.velocity_feedback.enabled;
    for (std::size_t k = 0; k < windows.size(); ++k) {
      const SegmentWindow& w = windows[k];
      const SegmentResult& res = seg_results[k];
      js << (k ? ",\n  " : "\n  ") << "{\"name\": " << jstr(w.name) << ", \"t_begin\": " << jnum(w.t_begin)
         << ", \"t_end\": " << jnum(w.t_end) << ", \"window\": [" << jnum(w.w_begin) << ", " << jnum(w.w_end)
         << "], \"seeds\": " << res.seeds << ", \"fallen\": " << res.fallen << ", \"command\": " << jaxes(w.command)
         << ", \"reference\": " << jaxes(res.reference) << ", \"shaped\": " << jaxes(res.shaped)
         << ", \"achieved\": " << jaxes(res.achieved)
         << ", \"u_prime\": " << jaxes(res.u_prime) << ", \"u_feedback\": " << jaxes(res.feedback)
         << ", \"estimate\": " << jaxes(res.estimate)
         << ", \"feedback_held_fraction\": " << jnum(fb_on && res.ticks > 0 ? static_cast<double>(res.fb_held) / res.ticks : kNaN)
         << ", \"feedback_decayed_fraction\": " << jnum(fb_on && res.ticks > 0 ? static_cast<double>(res.fb_decayed) / res.ticks : kNaN)
         << ", \"ratio\": " << jaxes(ratios(res.achieved, w.command), 3)
         << ", \"reference_ratio\": " << jaxes(ratios(res.reference, w.command), 3) << "}";
    }
    js << "]}\n";
    std::printf("mean over %d seeds: LinVel %.4f  YawVel %.4f  Roll %.4f  Pitch %.4f  Height %.4f  slip %.4f  falls %d/%d\n",
                seeds, acc[0] / S, acc[1] / S, acc[2] / S, acc[3] / S, acc[4] / S, acc[5] / S, falls, seeds);
    return falls == 0 ? 0 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_policy_sil: %s\n", e.what());
    return 1;
  }
}
