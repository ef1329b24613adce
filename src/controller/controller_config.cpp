#include "pmg/controller/controller_config.hpp"

#include <cmath>
#include <filesystem>

#include "pmg/common/yaml_archive.hpp"

namespace pmg {

std::vector<std::pair<std::string, BackendKind>> yamlEnumNames(BackendKind) {
  return {{"mujoco", BackendKind::kMujoco}, {"can", BackendKind::kCan}};
}
std::vector<std::pair<std::string, TimingMode>> yamlEnumNames(TimingMode) {
  return {{"lockstep", TimingMode::kLockstep}, {"realtime", TimingMode::kRealtime}};
}
std::vector<std::pair<std::string, Blending>> yamlEnumNames(Blending) {
  return {{"consistent", Blending::kConsistent}, {"paper", Blending::kPaper}};
}
std::vector<std::pair<std::string, StartupMode>> yamlEnumNames(StartupMode) {
  return {{"active", StartupMode::kActive}, {"passive", StartupMode::kPassive}};
}

namespace {
namespace fs = std::filesystem;

// The file's form: one struct per section, each field declared once with its doc and units.
struct CanYaml {
  std::string plan;
  std::string transport = "udp";
  int udp_port = 47000;
  bool paced = false;
  template <class A>
  void Serialize(A* a) {
    a->Visit("plan", &plan, "bus plan YAML (config/hal/*.yaml)", yaml::kPath);
    a->Visit("transport", &transport, "udp (pmg_sil) | socketcan (robot)");
    a->Visit("udp_port", &udp_port, "UDP base port of pmg_sil, 1024..65000");
    a->Visit("paced", &paced, "send each motor at its slot time");
  }
  std::string validate() const {
    if (transport != "udp" && transport != "socketcan") return "transport: '" + transport + "': expected udp or socketcan";
    if (udp_port < 1024 || udp_port > 65000) return "udp_port: expected 1024..65000";
    return {};
  }
};

struct TimingYaml {
  TimingMode mode = TimingMode::kLockstep;
  double loop_rate_hz = 100.0, hal_rate_hz = 500.0;
  int loop_fifo_priority = 0, hal_fifo_priority = 0, hal_cpu = -1;
  bool lock_memory = false;
  double imu_acc_lowpass_s = 0.0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("mode", &mode, "lockstep | realtime");
    a->Visit("loop_rate_hz", &loop_rate_hz, "controller loop rate, 10..1000 Hz");
    a->Visit("hal_rate_hz", &hal_rate_hz, "HAL rate, an integer multiple of loop_rate_hz, <= 4000 Hz");
    a->Visit("loop_fifo_priority", &loop_fifo_priority, "SCHED_FIFO 1..99, 0 = normal");
    a->Visit("hal_fifo_priority", &hal_fifo_priority, "SCHED_FIFO 1..99, 0 = normal");
    a->Visit("hal_cpu", &hal_cpu, "CPU of the HAL thread, -1 = any");
    a->Visit("lock_memory", &lock_memory, "mlockall before real-time operation");
    a->Visit("imu_acc_lowpass_s", &imu_acc_lowpass_s,
             "low-pass time constant of the IMU's specific force in the HAL before the loop samples it, 0 (off) or "
             "[1 / hal_rate_hz, 0.1] s (docs/controller.md)");
  }
  std::string validate() const {
    if (!(loop_rate_hz >= 10 && loop_rate_hz <= 1000)) return "loop_rate_hz: expected 10..1000 Hz";
    const double ratio = hal_rate_hz / loop_rate_hz;
    if (!(ratio >= 1 && std::fabs(ratio - std::round(ratio)) < 1e-9 && hal_rate_hz <= 4000))
      return "hal_rate_hz: expected an integer multiple of loop_rate_hz, <= 4000 Hz";
    if (loop_fifo_priority < 0 || loop_fifo_priority > 99) return "loop_fifo_priority: expected 0..99";
    if (hal_fifo_priority < 0 || hal_fifo_priority > 99) return "hal_fifo_priority: expected 0..99";
    if (hal_cpu < -1) return "hal_cpu: expected -1 (any) or a CPU index";
    return imuAccLowpassError(imu_acc_lowpass_s, 1.0 / hal_rate_hz);
  }
};

struct GantryYaml {
  GantryOptions g;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &g.enabled, "hang the robot in the bring-up gantry");
    a->Visit("anchor_height", &g.anchor_height, "pelvis anchor height [m]");
    a->Visit("stiffness", &g.stiffness, "[N/m]");
    a->Visit("damping", &g.damping, "[N*s/m]");
    a->Visit("rot_stiffness", &g.rot_stiffness, "[N*m/rad]");
    a->Visit("rot_damping", &g.rot_damping, "[N*m*s/rad]");
  }
};

struct JointStopsYaml {
  JointStopOptions s;
  template <class A>
  void Serialize(A* a) {
    a->Visit("timeconst", &s.timeconst, "joint-limit solref time constant [s]: 0 = the MJCF's, else [2 timestep, 1]");
    a->Visit("dampratio", &s.dampratio, "joint-limit solref damping ratio, (0, 10]");
  }
};

struct MujocoYaml {
  double timestep = 0.001;
  std::vector<double> encoder_offsets;
  GantryYaml gantry;
  JointStopsYaml joint_stops;
  double sliding_friction = 0.0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("timestep", &timestep, "physics step [s], <= 0.001");
    a->Visit("encoder_offsets", &encoder_offsets, "hidden zero offsets per joint [rad] (tests)");
    a->Visit("gantry", &gantry, "bring-up gantry");
    a->Visit("joint_stops", &joint_stops, "stiffness of the joints' mechanical stops (MJCF solreflimit)");
    a->Visit("sliding_friction", &sliding_friction, "foot-floor sliding friction of every geom; 0 = the MJCF's");
  }
};

struct GeneratorYaml {
  GeneratorParams p;
  template <class A>
  void Serialize(A* a) {
    a->Visit("blending", &p.blending, "consistent (amplitudes from the clips' implied motion) | paper (PMG eqs. 4-7)");
    a->Visit("epsilon", &p.epsilon, "PMG eq. 6 epsilon");
    a->Visit("max_command", &p.max_command, "|v_x| [m/s], |v_y| [m/s], |w| [rad/s] the generator accepts");
    a->Visit("max_cadence_ratio", &p.max_cadence_ratio,
             "consistent blending: at most this much faster cadence where a stride saturates, [1, 2]; 1 = PMG eq. 12");
    a->Visit("upright_walking", &p.upright_walking,
             "true: the walking clips' mean waist pitch/roll shifted to the standing pose's (no torso lean)");
  }
  std::string validate() const { return p.validate(); }
};

struct CommandsYaml {
  CommandLimits l;
  template <class A>
  void Serialize(A* a) {
    a->Visit("timeout_s", &l.timeout, "older velocity commands are stale [s]");
    a->Visit("max_velocity", &l.max_velocity, "|v_x| [m/s], |v_y| [m/s], |w| [rad/s]");
    a->Visit("max_acceleration", &l.max_acceleration, "slew limits [m/s^2, m/s^2, rad/s^2]");
    a->Visit("pitch_range", &l.pitch_range, "[min, max] torso pitch [rad]");
    a->Visit("roll_range", &l.roll_range, "[min, max] torso roll [rad]");
    a->Visit("height_range", &l.height_range, "[min, max] pelvis height [m]");
    a->Visit("posture_rate", &l.posture_rate, "pitch/roll slew limit [rad/s]");
    a->Visit("height_rate", &l.height_rate, "height slew limit [m/s]");
    a->Visit("max_reference_speed", &l.max_reference_speed, "bound on every joint reference's speed [rad/s]");
    a->Visit("crouched_height", &l.crouched_height,
             "0 (off) or the pelvis height [m] at which crouched_max_velocity holds fully (L1 rule, or per axis with crouched_per_axis)");
    a->Visit("crouched_max_velocity", &l.crouched_max_velocity, "|v_x| [m/s], |v_y| [m/s], |w| [rad/s] at crouched_height");
    a->Visit("crouched_per_axis", &l.crouched_per_axis,
             "true: the crouched envelope holds each axis alone (no L1 rule; combinations do not count against each other), true|false");
    a->Visit("bent_pitch", &l.bent_pitch, "0 (off) or the torso pitch [rad] at which bent_max_velocity holds fully (per axis)");
    a->Visit("bent_max_velocity", &l.bent_max_velocity, "|v_x| [m/s], |v_y| [m/s], |w| [rad/s] at bent_pitch");
    a->Visit("walking_min_height", &l.walking_min_height,
             "0 (off) or the lowest pelvis height [m] while walking and walking_min_height_hold_s after");
    a->Visit("walking_min_height_hold_s", &l.walking_min_height_hold_s, "how long the walking height floor holds after a stop, 0..10 s");
  }
};

struct ResponseAxisYaml {
  CommandResponseAxis a;
  template <class A>
  void Serialize(A* ar) {
    ar->Visit("gain_positive", &a.gain_positive, "achieved / commanded for a positive command on this axis alone, 0.3..3");
    ar->Visit("gain_negative", &a.gain_negative, "achieved / commanded for a negative command on this axis alone, 0.3..3");
    ar->Visit("gain_per_magnitude", &a.gain_per_magnitude,
              "change of that gain per unit |u_j| of v_x, v_y, w, -3..3; the axis's own entry 0");
    ar->Visit("gain_per_command", &a.gain_per_command,
              "change of that gain per unit u_j (signed) of v_x, v_y, w, -3..3; the axis's own entry 0");
    ar->Visit("drift", &a.drift, "velocity on this axis per unit command on v_x, v_y, w, -1..1; the axis's own entry 0");
    ar->Visit("gain_positive_per_crouch", &a.gain_positive_per_crouch,
              "change of gain_positive per metre of crouch below the standing height [1/m], -10..10");
    ar->Visit("gain_negative_per_crouch", &a.gain_negative_per_crouch,
              "change of gain_negative per metre of crouch below the standing height [1/m], -10..10");
  }
};

struct FeedforwardYaml {
  CommandResponseModel m;
  ResponseAxisYaml vx, vy, wz;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &m.enabled, "command-response feed-forward in front of the integral correction");
    a->Visit("vx", &vx, "response of v_x (scripts/fit_command_response.py writes this block)");
    a->Visit("vy", &vy, "response of v_y");
    a->Visit("wz", &wz, "response of the yaw rate w");
    a->Visit("max_correction", &m.max_correction, "|u_ff - u| at most v_x, v_y [m/s], w [rad/s], each 0..1");
    a->Visit("combined_max_correction_ratio", &m.combined_max_correction_ratio,
             "on a command moving all three axes, max_correction shrinks to this share, 0..1 (1: off)");
    a->Visit("combined_full", &m.combined_full,
             "per-axis command at which an axis counts fully as combined, v_x, v_y [m/s], w [rad/s], each (0, 2]");
    a->Visit("min_gain", &m.min_gain, "the inverse divides by at least this modelled gain, 0.3..1");
    a->Visit("iterations", &m.iterations, "Gauss-Seidel sweeps of the inverse, 1..50");
  }
  CommandResponseModel model() const {
    CommandResponseModel out = m;
    out.axes = {vx.a, vy.a, wz.a};
    return out;
  }
};

struct UpsetGuardYaml {
  UpsetGuardConfig g;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &g.enabled, "hold the velocity command at zero while the robot moves far off it (docs/controller.md)");
    a->Visit("max_error", &g.max_error, "an axis is off its command beyond this |u - v| (v_x, v_y [m/s], w [rad/s]), each (0, 3]");
    a->Visit("trigger_s", &g.trigger_s, "an upset: one axis off this long without a break, (0, 5] s");
    a->Visit("settle_velocity", &g.settle_velocity, "settled: |v_x|, |v_y| below this, |w| below twice it, (0, 1] m/s");
    a->Visit("settle_s", &g.settle_s, "settled this long, [0, 10] s");
    a->Visit("rearm_band", &g.rearm_band, "released once settled and the operator's command within this of zero, [0, 0.3]");
    a->Visit("stance_band_m", &g.stance_band_m, "the guard's own estimate: soles within this height of the lowest are in stance, (0, 0.1] m");
    a->Visit("upright", &g.upright, "while latched, the torso pitch and roll go to 0 as well (true|false)");
  }
};

struct VelocityFeedbackYaml {
  VelocityFeedbackConfig f;
  FeedforwardYaml feedforward;
  UpsetGuardYaml upset_guard;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &f.enabled, "integral correction of the velocity command on leg odometry");
    a->Visit("ki", &f.ki, "integral gains for v_x, v_y, w, 0..20 [1/s]");
    a->Visit("max_ratio", &f.max_ratio, "largest correction as a share of |u|, 0..2");
    a->Visit("small_command_bound", &f.small_command_bound,
             "v_x, v_y [m/s], w [rad/s], each 0..0.5: a small command's correction may grow to |u| itself up to this");
    a->Visit("envelope_min", &f.envelope_min, "v_x, v_y [m/s], w [rad/s] below which no correction pushes (training range)");
    a->Visit("envelope_max", &f.envelope_max, "v_x, v_y [m/s], w [rad/s] above which no correction pushes (training range)");
    a->Visit("max_velocity_headroom", &f.max_velocity_headroom,
             "v_x, v_y [m/s], w [rad/s], each 0..1: how far beyond commands.max_velocity the correction may take the command");
    a->Visit("stance_band_m", &f.stance_band_m, "soles within this height of the lowest are in stance, (0, 0.1] m");
    a->Visit("stance_foot_nearest", &f.stance_foot_nearest, "both soles in the band: the foot nearer the prediction is the sample (true) or their mean (false, wh6g's tuning)");
    a->Visit("odometry_time_s", &f.odometry_time_s, "time constant of the leg-odometry correction, 0..2 s");
    a->Visit("yaw_rate_gated", &f.yaw_rate_gated, "the yaw rate moves only with accepted leg samples (true, tuned on) or is the gyro's every tick");
    a->Visit("gate_mps", &f.gate_mps, "leg-odometry samples further than this from the IMU prediction are rejected, (0, 5] m/s");
    a->Visit("max_rejected_s", &f.max_rejected_s, "after this long of rejections the estimate restarts from the legs, 0..5 s");
    a->Visit("restart_median", &f.restart_median, "restart from the median innovation of the rejected window (true) or the next sample (false, tuned on)");
    a->Visit("within_posture_envelopes", &f.within_posture_envelopes,
             "keep the corrected command inside the shaper's crouched and bent velocity envelopes (docs/controller.md)");
    a->Visit("yaw_beyond_envelopes", &f.yaw_beyond_envelopes,
             "with within_posture_envelopes: the yaw-rate correction is not bound by those envelopes, v_x and v_y are (true|false)");
    a->Visit("headroom_in_envelopes", &f.headroom_in_envelopes,
             "with within_posture_envelopes: max_velocity_headroom applies at the crouched and bent envelopes' edges too (true|false)");
    a->Visit("max_tilt_rad", &f.max_tilt_rad, "above this pelvis tilt the correction decays to zero, (0, 1.5] rad");
    a->Visit("decay_time_s", &f.decay_time_s, "time constant of that decay, (0, 5] s");
    a->Visit("decay_feedforward", &f.decay_feedforward, "while tilted the feed-forward's share decays too, and returns once upright (true|false)");
    a->Visit("feedforward_return_s", &f.feedforward_return_s, "with decay_feedforward: the share returns from 0 to 1 over this, (0, 30] s (0: decay_time_s)");
    a->Visit("settle_time_s", &f.settle_time_s, "an axis integrates once its command is steady this long, 0..5 s");
    a->Visit("steady_band", &f.steady_band, "steady: within max(this, 5 % of |u|) of where it settled, 0..0.5 m/s, rad/s");
    a->Visit("brake_ratio", &f.brake_ratio, "braking steps: gait floor at this share of the estimated v_x, v_y, [0, 1); 0 = off");
    a->Visit("brake_decel", &f.brake_decel, "the floor lets the reference decelerate at least this fast, (0, min(5, brake_rate)] m/s^2");
    a->Visit("brake_rate", &f.brake_rate, "largest change of the floor per second, (0, 10] m/s^2");
    a->Visit("brake_crouch_scaled", &f.brake_crouch_scaled, "the floor's share scaled by how crouched the shaped posture is (needs commands.crouched_height), true|false");
    a->Visit("feedforward", &feedforward, "identified command response, inverted in front of the correction (docs/controller.md)");
    a->Visit("upset_guard", &upset_guard, "hold the velocity command at zero after an upset (docs/controller.md)");
  }
};

struct PostureFeedbackYaml {
  PostureFeedbackConfig f;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &f.enabled, "integral correction of the pitch/roll command on the measured torso attitude");
    a->Visit("ki", &f.ki, "integral gains for pitch, roll, 0..20 [1/s]");
    a->Visit("max_correction_rad", &f.max_correction_rad, "largest correction, 0..0.3 rad");
    a->Visit("filter_time_s", &f.filter_time_s, "low-pass time constant of the measured attitude, 0..2 s");
    a->Visit("max_tilt_rad", &f.max_tilt_rad, "above this pelvis tilt the correction decays to zero, (0, 1.5] rad");
    a->Visit("decay_time_s", &f.decay_time_s, "time constant of that decay, (0, 5] s");
    a->Visit("still_velocity", &f.still_velocity, "integrates only while |v_x|, |v_y| < this, |w| < 2x this, 0..1");
    a->Visit("still_measured_velocity", &f.still_measured_velocity, "and only while the estimated |v_x|, |v_y| < this, 0..2 m/s (0: off)");
    a->Visit("settle_s", &f.settle_s, "standing, an axis integrates once its posture command is steady this long, 0..5 s (0: always)");
    a->Visit("stop_settle_s", &f.stop_settle_s, "standing, the integrator waits this long after the velocity command goes still, 0..5 s (0: off)");
    a->Visit("walking_ki", &f.walking_ki, "integral gains for pitch, roll while walking, 0..5 [1/s] (0: decays while walking)");
    a->Visit("walking_max_correction_rad", &f.walking_max_correction_rad, "largest correction while walking, 0..0.3 rad");
    a->Visit("walking_filter_time_s", &f.walking_filter_time_s, "low-pass time constant of the attitude while walking, 0..5 s");
    a->Visit("walking_settle_s", &f.walking_settle_s, "walking, an axis integrates once its posture command is steady this long, 0..5 s");
    a->Visit("walking_velocity_settle_s", &f.walking_velocity_settle_s, "walking, pitch and roll integrate once the shaped velocity command is steady (within 0.05) this long, 0..5 s (0: off)");
    a->Visit("walking_min_command_rad", &f.walking_min_command_rad, "walking, an axis integrates only while |its command| >= this, 0..0.5 rad");
    a->Visit("walking_deadband_rad", &f.walking_deadband_rad, "walking below walking_min_command_rad, an axis integrates only its error beyond this band, 0..0.3 rad (0: not at all)");
    a->Visit("walking_crouch_m", &f.walking_crouch_m, "walking with the height at least this far below standing, an axis integrates as if commanded, 0..0.2 m (0: off)");
    a->Visit("overshoot_release", &f.overshoot_release, "standing, a correction that pushes the torso past the command decays too (true/false)");
    a->Visit("walking_crouch_release", &f.walking_crouch_release, "with walking_crouch_m, a held standing correction opposed to the walking error decays instead (true/false)");
    a->Visit("envelope_min", &f.envelope_min, "pitch, roll [rad], -1.5..0: a correction never pushes the command below this");
    a->Visit("envelope_max", &f.envelope_max, "pitch, roll [rad], 0..1.5: nor above this (the actor's trained range)");
    a->Visit("height_ki", &f.height_ki, "integral gain on the pelvis height, 0..20 [1/s] (0: the height is not corrected)");
    a->Visit("max_height_correction_m", &f.max_height_correction_m, "largest height correction, 0..0.1 m");
    a->Visit("height_settle_s", &f.height_settle_s, "the height integrates once its command is steady this long, 0..5 s");
    a->Visit("walking_height_ki", &f.walking_height_ki, "integral gain on the pelvis height while walking, 0..5 [1/s] (0: decays while walking)");
    a->Visit("walking_max_height_correction_m", &f.walking_max_height_correction_m, "largest height correction while walking, 0..0.1 m (never below commands.walking_min_height less walking_below_floor_m)");
    a->Visit("walking_below_floor_m", &f.walking_below_floor_m, "how far below commands.walking_min_height the walking height correction may take the command, 0..0.05 m (0: not below)");
  }
};

struct SafetyYaml {
  double soft_stand_duration_s = 1.0;
  double damping_kd_scale = 1.0;
  double q_rate_max = hal::safety::EnvelopeOptions{}.q_rate_max;
  StartupMode startup = StartupMode::kActive;
  template <class A>
  void Serialize(A* a) {
    a->Visit("soft_stand_duration_s", &soft_stand_duration_s, "supervisor soft stand (0, 60] s");
    a->Visit("damping_kd_scale", &damping_kd_scale, "damping kd = scale * robot kd, (0, 5]");
    a->Visit("startup", &startup, "active (stand up and engage) | passive (wait for an operator)");
    a->Visit("q_rate_max", &q_rate_max, "slew limit on the commanded joint positions [rad/s], per HAL cycle, [1, 2000]");
  }
  std::string validate() const {
    if (!(soft_stand_duration_s > 0 && soft_stand_duration_s <= 60)) return "soft_stand_duration_s: expected (0, 60] s";
    if (!(damping_kd_scale > 0 && damping_kd_scale <= 5)) return "damping_kd_scale: expected (0, 5]";
    if (!(q_rate_max >= 1 && q_rate_max <= 2000)) return "q_rate_max: expected [1, 2000] rad/s";
    return {};
  }
};

struct PolicyYaml {
  std::string model;
  std::string backend = "native";
  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, "ONNX actor with its pmg contract", yaml::kPath | yaml::kRequired);
    a->Visit("backend", &backend, "native (allocation-free) | onnxruntime");
  }
  std::string validate() const {
    if (backend != "native" && backend != "onnxruntime") return "backend: '" + backend + "': expected native or onnxruntime";
    return {};
  }
};

struct TelemetryYaml {
  bool lcm = true;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string log_file;
  template <class A>
  void Serialize(A* a) {
    a->Visit("lcm", &lcm, "publish telemetry / receive commands over LCM");
    a->Visit("lcm_url", &lcm_url, "LCM provider URL (ttl=0 keeps traffic on the host)");
    a->Visit("log_file", &log_file, "LCM event log (\"\" = none)", yaml::kPath);
  }
};

struct SecurityYaml {
  std::string key_file;
  comms::VerifierOptions v;
  template <class A>
  void Serialize(A* a) {
    a->Visit("key_file", &key_file, "MAC key of the command channels (pmg_keygen, mode 0600); \"\" = plain commands",
             yaml::kPath);
    a->Visit("max_message_age_s", &v.max_age_s,
             "largest |wall clock - send time| of a command, (0, 60] s (hosts' clocks synchronised)");
    a->Visit("max_senders", &v.max_senders, "senders active at once on one channel, 1..64");
  }
  std::string validate() const { return v.validate(); }
};

struct ControllerYaml {
  std::string robot, clips, gco;
  BackendKind backend = BackendKind::kMujoco;
  std::optional<CanYaml> can;
  TimingYaml timing;
  MujocoYaml mujoco;
  std::optional<bool> gco_enabled;
  std::optional<bool> sole_levelling;
  std::optional<bool> stride_adaptation;
  GeneratorYaml generator;
  CommandsYaml commands;
  VelocityFeedbackYaml velocity_feedback;
  PostureFeedbackYaml posture_feedback;
  UpperBodyConfig upper_body;
  SafetyYaml safety;
  std::optional<PolicyYaml> policy;
  TelemetryYaml telemetry;
  SecurityYaml security;
  teleop::TeleopConfig teleop;
  template <class A>
  void Serialize(A* a) {
    a->Visit("robot", &robot, "robot config YAML", yaml::kPath | yaml::kRequired);
    a->Visit("clips", &clips, "clip library folder", yaml::kPath | yaml::kRequired);
    a->Visit("backend", &backend, "mujoco (in-process SIL) | can (motor buses)");
    a->Visit("can", &can, "motor-bus settings (backend: can)");
    a->Visit("timing", &timing, "rates and real-time settings");
    a->Visit("mujoco", &mujoco, "MuJoCo 2.2 SIL settings");
    a->Visit("gco", &gco, "GCO options YAML", yaml::kPath);
    a->Visit("gco_enabled", &gco_enabled, "false: PMG w/o GCO");
    a->Visit("sole_levelling", &sole_levelling, "true: level the reference's stance soles (gco.sole_levelling.enabled)");
    a->Visit("stride_adaptation", &stride_adaptation,
             "true: hold the reference's stance soles still under the command (gco.stride_adaptation.enabled)");
    a->Visit("generator", &generator, "PMG generator parameters");
    a->Visit("commands", &commands, "command limits");
    a->Visit("velocity_feedback", &velocity_feedback, "closed-loop velocity tracking (docs/controller.md)");
    a->Visit("posture_feedback", &posture_feedback, "closed-loop torso pitch/roll tracking (docs/controller.md)");
    a->Visit("upper_body", &upper_body, "upper-body gravity compensation and damping (docs/controller.md)");
    a->Visit("safety", &safety, "supervisor settings");
    a->Visit("policy", &policy, "trained actor (absent: PMG references drive the motors)");
    a->Visit("telemetry", &telemetry, "LCM telemetry and event log");
    a->Visit("teleop", &teleop, "VR teleoperation (docs/teleop.md)");
    a->Visit("security", &security, "authenticated LCM command channels (docs/teleop.md)");
  }
};

}  // namespace

HalStackConfig ControllerConfig::halStack() const {
  HalStackConfig h;
  h.backend = backend;
  h.can = can;
  h.mujoco = mujoco;
  h.lockstep = timing == TimingMode::kLockstep;
  h.soft_stand_duration_s = soft_stand_duration;
  h.damping_kd_scale = damping_kd_scale;
  h.q_rate_max = q_rate_max;
  h.imu_acc_lowpass_s = imu_acc_lowpass_s;
  return h;
}

RunnerOptions ControllerConfig::runner() const {
  RunnerOptions r;
  r.mode = timing;
  r.loop_period_s = 1.0 / loop_rate_hz;
  r.hal_cycles_per_tick = cyclesPerTick();
  r.loop_fifo_priority = loop_fifo_priority;
  r.hal_fifo_priority = hal_fifo_priority;
  r.hal_cpu = hal_cpu;
  r.lock_memory = lock_memory;
  return r;
}

ControllerConfig loadControllerConfig(const std::string& path) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  ControllerYaml y;
  yaml::readYaml(doc, &y);
  const auto fail = [&](const std::string& key, const std::string& msg) {
    yaml::fail(yaml::YamlSource{path, doc.source.base_dir, key}, doc.root[key], msg);
  };
  ControllerConfig c;
  c.source_file = path;
  c.robot_file = y.robot;
  c.clips_dir = y.clips;
  if (!fs::is_directory(c.clips_dir)) fail("clips", "folder '" + c.clips_dir + "' not found");
  c.robot = loadRobotConfig(c.robot_file);
  c.backend = y.backend;
  if (y.can) {
    c.can = CanSettings{y.can->plan, y.can->transport, y.can->udp_port, y.can->paced};
  }
  if (c.backend == BackendKind::kCan && !fs::exists(c.can.plan_file))
    fail("can", "plan: bus plan '" + c.can.plan_file + "' not found (required with backend: can)");
  c.timing = y.timing.mode;
  c.loop_rate_hz = y.timing.loop_rate_hz;
  c.hal_rate_hz = y.timing.hal_rate_hz;
  c.loop_fifo_priority = y.timing.loop_fifo_priority;
  c.hal_fifo_priority = y.timing.hal_fifo_priority;
  c.hal_cpu = y.timing.hal_cpu;
  c.lock_memory = y.timing.lock_memory;
  c.imu_acc_lowpass_s = y.timing.imu_acc_lowpass_s;
  c.mujoco.timestep = y.mujoco.timestep;
  c.mujoco.cycle_period = 1.0 / c.hal_rate_hz;
  c.mujoco.encoder_offsets = y.mujoco.encoder_offsets;
  c.mujoco.gantry = y.mujoco.gantry.g;
  c.mujoco.joint_stops = y.mujoco.joint_stops.s;
  c.mujoco.sliding_friction = y.mujoco.sliding_friction;
  if (const std::string e = c.mujoco.validate(); !e.empty()) fail("mujoco", e);
  c.generator = y.generator.p;
  if (!y.gco.empty()) {
    c.gco_file = y.gco;
    c.gco = gco::loadGcoOptionsFile(c.gco_file);  // throws naming the file and field
  }
  if (y.gco_enabled) c.gco.enabled = *y.gco_enabled;
  if (y.sole_levelling) c.gco.sole_levelling.enabled = *y.sole_levelling;
  if (y.stride_adaptation) c.gco.stride_adaptation.enabled = *y.stride_adaptation;
  c.commands = y.commands.l;
  c.commands.standing_height = c.robot.standing_base_height;
  if (const std::string e = c.commands.validate(); !e.empty()) fail("commands", e);
  c.velocity_feedback = y.velocity_feedback.f;
  c.velocity_feedback.feedforward = y.velocity_feedback.feedforward.model();
  c.velocity_feedback.upset_guard = y.velocity_feedback.upset_guard.g;
  if (const std::string e = c.velocity_feedback.validate(); !e.empty()) fail("velocity_feedback", e);
  if (c.velocity_feedback.brake_crouch_scaled && c.velocity_feedback.brake_ratio > 0.0 && !(c.commands.crouched_height > 0.0))
    fail("velocity_feedback", "brake_crouch_scaled: true needs commands.crouched_height > 0 "
                              "(the weight is how far the posture is crouched towards it; without it the floor never acts)");
  c.posture_feedback = y.posture_feedback.f;
  if (const std::string e = c.posture_feedback.validate(); !e.empty()) fail("posture_feedback", e);
  c.upper_body = y.upper_body;
  if (const std::string e = c.upper_body.validate(); !e.empty()) fail("upper_body", e);
  c.soft_stand_duration = y.safety.soft_stand_duration_s;
  c.damping_kd_scale = y.safety.damping_kd_scale;
  c.q_rate_max = y.safety.q_rate_max;
  c.startup = y.safety.startup;
  if (y.policy) {
    c.policy_file = y.policy->model;
    if (!fs::exists(c.policy_file)) fail("policy", "model: '" + c.policy_file + "' not found");
    c.policy_native = y.policy->backend == "native";
  }
  c.lcm_enabled = y.telemetry.lcm;
  c.lcm_url = y.telemetry.lcm_url;
  c.log_file = y.telemetry.log_file;
  c.teleop = y.teleop;
  if (const std::string e = c.teleop.validate(); !e.empty()) fail("teleop", e);
  c.security.key_file = y.security.key_file;
  c.security.verifier = y.security.v;
  if (c.security.enabled()) {
    try {
      c.security.key = comms::loadAuthKey(c.security.key_file);
    } catch (const ConfigError& e) {
      fail("security", std::string("key_file: ") + e.what());
    }
  }
  return c;
}

}  // namespace pmg
