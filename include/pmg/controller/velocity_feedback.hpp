#pragma once
/// @file velocity_feedback.hpp
/// Closed-loop velocity tracking around the PMG generator and the policy (beyond the paper;
/// issue 12, docs/controller.md "Velocity feedback").
///
/// The trained actor achieves 75–90 % of many commands (docs/policy.md "Command fidelity"): it has
/// no measurement of its own linear velocity. The loop can measure it: leg odometry from the IMU
/// and the leg encoders (the base velocity that holds the stance soles still, the same kinematics
/// as PMG eq. 14 on KDL leg chains) and the yaw rate from the gyro. An integral correction on the
/// velocity command then makes the achieved velocity meet the user's command u in steady state:
///
///   e_i = u_i − v̂_i,   c_i ← clamp(c_i + k_i e_i dt, −r |u_i|, r |u_i|)   (once u_i is steady),
///   u_fb,i = clamp(u_ff,i + c_i, envelope_i ∩ ±max(max_velocity_i, |u_i| + headroom_i))   (i = v_x, v_y, ω)
///
/// with u_ff = u, or with a feed-forward (CommandResponseModel) the command that an identified
/// model of the robot's response says achieves u.
///
/// u_fb goes to the generator (and, through GCO's u' or directly, to the actor's observation); u
/// is what the user commanded and what every evaluation compares against. The bound r |u_i| makes
/// the correction vanish with the command (a robot told to stand is not steered back to where it
/// started, and u_fb keeps the sign of u), and keeps u_fb continuous: |du_fb/dt| ≤ (1 + r) ×
/// the shaper's slew limit + k_i × the largest error. The correction holds (does not integrate)
/// while no foot is in stance or the estimate is not finite.
///
/// Frames: B = pelvis (the IMU frame of the G1's imu_in_pelvis, axes parallel to the pelvis link),
/// W = world (the IMU's orientation estimate), H = heading frame (W rotated by the pelvis yaw:
/// x forward, y left, z up). No allocation, noexcept per tick (tested).

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "pmg/common/kinematics.hpp"
#include "pmg/gco/leg_kinematics.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/types.hpp"

namespace pmg {

/// One axis i of CommandResponseModel (i = v_x, v_y, ω).
struct CommandResponseAxis {
  /// Achieved ÷ commanded on this axis for a positive / a negative command on it alone [-],
  /// [0.3, 3].
  double gain_positive = 1.0;
  double gain_negative = 1.0;
  /// Change of that gain per unit |u_j| of each axis j = (v_x [1/(m/s)], v_y [1/(m/s)],
  /// ω [1/(rad/s)]), [-3, 3]; the axis's own entry must be 0. A turn that slows a side-step is a
  /// negative entry.
  std::array<double, 3> gain_per_magnitude{0.0, 0.0, 0.0};
  /// Change of that gain per unit u_j, signed (the same units), [-3, 3]; own entry 0. A side-step
  /// to the left achieved better while turning left than while turning right is a positive entry.
  std::array<double, 3> gain_per_command{0.0, 0.0, 0.0};
  /// Velocity achieved on this axis per unit command on axis j (a drift) [-], [-1, 1]; own entry 0.
  std::array<double, 3> drift{0.0, 0.0, 0.0};
  /// Change of gain_positive / gain_negative per metre of crouch c = the controller's standing height
  /// − the shaped pelvis height [1/m], [-10, 10] (c ≥ 0; walking, commands.walking_min_height bounds
  /// it: 0.1045 m with the policy configs). A robot that overshoots backward walks crouched while it
  /// undershoots them upright has a positive gain_negative_per_crouch.
  double gain_positive_per_crouch = 0.0;
  double gain_negative_per_crouch = 0.0;
};

/// `velocity_feedback.feedforward:` an identified model of the steady velocity the robot achieves
/// for a command (the policy with the velocity feedback, flat ground), and its inverse, used as a
/// feed-forward in front of the integral correction (beyond the paper; issue 12, docs/controller.md
/// "Command-response feed-forward"). Per axis i, with u⁺ = max(u, 0), u⁻ = min(u, 0):
///
///   v_i(u, c) = ((g⁺_i + k⁺_i c) u_i⁺ + (g⁻_i + k⁻_i c) u_i⁻) + u_i Σ_{j≠i} (m_ij |u_j| + s_ij u_j)
///               + Σ_{j≠i} d_ij u_j
///
/// g = gain_positive/negative, k = gain_positive/negative_per_crouch, c = the crouch [m] (standing
/// height − the shaped pelvis height, ≥ 0), m = gain_per_magnitude, s = gain_per_command, d = drift.
/// The coefficients come from calibration sweeps in the SIL, upright and crouched, fitted by least
/// squares (scripts/fit_command_response.py, which writes this block). Units: v_x, v_y [m/s],
/// ω [rad/s], in the heading frame H.
struct CommandResponseModel {
  bool enabled = false;
  std::array<CommandResponseAxis, 3> axes{};
  /// |u_ff,i − u_i| at most this [m/s, m/s, rad/s], each 0..1: how far the feed-forward may move
  /// a command.
  std::array<double, 3> max_correction{0.3, 0.2, 0.4};
  /// On a combined command the bound above shrinks to max_correction_i × (1 − (1 − r) κ(u)), with
  /// r = combined_max_correction_ratio [-], [0, 1] (1, the default: off; 0: no feed-forward on a
  /// command that moves all three axes) and the combination κ(u) = Π_j min(1, |u_j| / combined_full_j)
  /// [-] in [0, 1]: 0 when any axis is commanded 0, 1 when every axis is at least combined_full_j.
  /// κ is continuous in u, so u_ff stays continuous. Why: on a slippery floor (sliding friction 0.4)
  /// the two three-axis segments at the envelope's edge fall with the feed-forward, and rarely
  /// without it (docs/controller.md "Slippery floors").
  double combined_max_correction_ratio = 1.0;
  /// The per-axis command at which an axis counts fully in κ [m/s, m/s, rad/s], each (0, 2].
  std::array<double, 3> combined_full{0.2, 0.15, 0.25};
  /// κ(u) above [-], in [0, 1]. noexcept.
  double combination(const std::array<double, 3>& u) const noexcept;
  /// The inverse divides by an axis's modelled gain; it is taken as at least this [-], [0.3, 1].
  double min_gain = 0.5;
  /// Gauss–Seidel sweeps of the inverse, 1..50 (a fixed number: the cost is bounded and the result
  /// a continuous function of u).
  int iterations = 8;
  /// Empty when valid, else "<field>: expected ..." for the first bad field.
  std::string validate() const;
  /// v(u, c) above; @p crouch_m c [m] is clamped to [0, 0.5] (NaN → 0). noexcept, no allocation.
  std::array<double, 3> achieved(const std::array<double, 3>& u, double crouch_m = 0.0) const noexcept;
  /// The command u_ff with v(u_ff) = u: `iterations` Gauss–Seidel sweeps from u_ff = u, each axis
  /// solved exactly for the others' values (u_ff,i = (u_i − Σ d_ij u_ff,j) / max(min_gain, g_i +
  /// Σ (m_ij |u_ff,j| + s_ij u_ff,j)), the gain g⁺ or g⁻ by the sign of the numerator) and kept within
  /// u_i ± max_correction_i (shrunk on a combined command: combined_max_correction_ratio). Continuous
  /// in u and in the crouch; u = 0 gives 0 (a robot told to stand is not moved). g⁺, g⁻ are those at
  /// @p crouch_m [m] (clamped as in achieved()). noexcept, no allocation.
  std::array<double, 3> invert(const std::array<double, 3>& u, double crouch_m = 0.0) const noexcept;
  /// The crouch c [m] as achieved() and invert() use it: clamped to [0, 0.5], NaN → 0. noexcept.
  static double clampCrouch(double crouch_m) noexcept;
};

/// `velocity_feedback.upset_guard:` of the controller config (UpsetGuard; beyond the paper, issue 12,
/// docs/controller.md "Upset guard").
struct UpsetGuardConfig {
  bool enabled = false;
  /// An axis is off its command while |u_i - v_i| exceeds this (v_x, v_y [m/s], yaw rate [rad/s]),
  /// each (0, 3]; u the shaped command, v the guard's own estimate (H; stance_band_m). v_x's bound is the
  /// widest: a robot lags a walk's start by design.
  std::array<double, 3> max_error{0.8, 0.4, 0.7};
  /// An upset: one axis off its command this long without a break [s], (0, 5]. 0.7 s: 1.0 s was
  /// measured too late (posture walks, seed 35: latched at 112.33 s, fell at 113.47 s).
  double trigger_s = 0.7;
  /// Settled: estimated |v_x|, |v_y| below this [m/s] and |yaw rate| below twice it [rad/s], (0, 1], ...
  double settle_velocity = 0.15;
  /// ... for this long [s], [0, 10].
  double settle_s = 1.0;
  /// Re-armed once settled while the operator's velocity command (the shaper's clamped target) is
  /// within this of zero on every axis [m/s, rad/s], [0, 0.3]: the robot never walks off again on
  /// its own; the operator lets go of the stick and commands again.
  double rearm_band = 0.05;
  /// The guard judges on its own estimate: the velocity feedback's estimator settings, with this
  /// stance band [m], (0, 0.1], and the yaw rate from the gyro on every tick. More accurate than
  /// the feedback's (which its integral loop was tuned on): docs/controller.md "What the velocity
  /// estimate gets wrong"; on the feedback's own estimate the guard latched on its glitches.
  double stance_band_m = 0.005;
  /// While latched, the shaped torso pitch and roll also go to 0 (upright) at the shaper's
  /// posture_rate, whatever the operator commands; the height is kept. Released, they slew back to the
  /// operator's posture. Why: a robot that runs on after a stop bent forward falls forward; in the
  /// stress runs every fall came after a latch (docs/controller.md "Upright while upset").
  bool upright = false;
  /// Empty when valid, else "<field>: expected ..." for the first bad field.
  std::string validate() const;
};

/// `velocity_feedback:` of the controller config.
struct VelocityFeedbackConfig {
  bool enabled = false;
  /// Integral gains k_i for v_x, v_y, ω [1/s] (each ≥ 0; 0 turns an axis off).
  std::array<double, 3> ki{1.0, 1.0, 1.0};
  /// r: largest correction as a share of |u_i|, [0, 2].
  double max_ratio = 0.6;
  /// b per axis (v_x, v_y [m/s], ω [rad/s]), each in [0, 0.5]: for a small command the correction may
  /// grow to |u_i| itself, up to b_i. The bound is max(r |u_i|, min(|u_i|, b_i)): continuous in u, zero
  /// at u = 0 (a robot told to stand is still not steered), and unchanged wherever r |u_i| ≥ b_i.
  /// 0 (the default here; [0.1, 0, 0] in config/controller/g1_sil_policy.yaml). Why: told −0.1 m/s
  /// upright, the default actor is slow to start; sent the full r-bound (−0.16) it averaged −0.04 to
  /// −0.05 m/s over the last 2.4 s of a 4 s walk (docs/controller.md "Small commands and the actor's
  /// slow start").
  std::array<double, 3> small_command_bound{0.0, 0.0, 0.0};
  /// The range u_fb stays in (v_x, v_y [m/s], ω [rad/s]): the policy's training command range (the
  /// issue-12 envelope), intersected with the shaper's limits. A correction never pushes a command
  /// beyond it (a command already beyond it is passed on uncorrected).
  std::array<double, 3> envelope_min{-0.5, -0.4, -0.8};
  std::array<double, 3> envelope_max{1.0, 0.4, 0.8};
  /// Headroom h per axis (v_x, v_y [m/s], ω [rad/s]), each in [0, 1]: the corrected command may go
  /// beyond the shaper's max_velocity m as far as the command comes near it, |u_fb,i| ≤
  /// max(m_i, |u_i| + h_i): a command at the limit may be corrected up to m + h, one h or more below
  /// it exactly as without headroom (continuous in u). Still inside envelope_min/max; the user's own
  /// command stays clamped to m. 0 (the default): u_fb stays inside ±m. Why: told the shaper's largest
  /// yaw rate, 0.8 rad/s, the default actor turns 0.63–0.72, and a correction that may not leave ±0.8
  /// cannot close that (docs/controller.md "Headroom beyond the command limit"). The controller
  /// requires m + h inside generator.max_command and GCO's limits.
  std::array<double, 3> max_velocity_headroom{0.0, 0.0, 0.0};
  /// Feet whose sole is within this height of the lowest sole (in H) count as in stance [m], (0, 0.1].
  double stance_band_m = 0.02;
  /// false (the default, what wh6g's integral loop was tuned on): with both soles within stance_band_m
  /// the leg-odometry sample is the mean of the two feet's. true: each such foot is a sample of its own
  /// and the estimator takes the one nearer its IMU prediction (then gates it as before), so a swing
  /// foot that skims the floor inside the band is not averaged with the stance foot. Why: H10a lifts its
  /// swing foot less than 2 cm; walking 0.75 m/s forward both soles were in the band 90 % of the ticks,
  /// the mean read 0.1 m/s, the gate rejected most samples and the estimate lagged the robot by 0.26
  /// m/s, so the integral loop pushed it to 0.88 m/s (docs/controller.md "A swing foot inside the
  /// stance band"). The upset guard's own estimate follows this key too.
  bool stance_foot_nearest = false;
  /// Time constant with which leg odometry corrects the IMU-propagated estimate [s], [0, 2].
  double odometry_time_s = 0.1;
  /// true (the default, what the integral loop and the feed-forward were tuned on): the yaw rate
  /// moves only with the accepted leg-odometry samples (held while the gate rejects, taken from one
  /// sample on a restart). false: the gyro's yaw rate low-passed on every tick (more accurate:
  /// docs/controller.md "What the velocity estimate gets wrong"; the upset guard's own estimate).
  bool yaw_rate_gated = true;
  /// Leg-odometry samples further than this from the prediction are rejected [m/s], (0, 5].
  double gate_mps = 0.15;
  /// After this long of consecutive rejections the estimate restarts from the legs [s], [0, 5].
  double max_rejected_s = 0.3;
  /// How it restarts. false (what the integral loop and the feed-forward were tuned on): from the
  /// next leg-odometry sample alone, so one glitch (a lifting foot counted in stance) can become the
  /// estimate, and the gate then rejects the good samples around the wrong value. true: v_x, v_y
  /// restart from the prediction shifted by the median innovation (sample − prediction, per axis)
  /// of the samples rejected in the last max_rejected_s, this tick's included (at most
  /// kRestartWindow samples); the gated yaw rate still restarts from this sample.
  /// docs/controller.md "A restart from the median".
  bool restart_median = false;
  /// Above this pelvis tilt (IMU roll or pitch) [rad], (0, 1.5], the correction is not integrated
  /// and decays to zero with decay_time_s: a robot that is being shoved or catching itself gets the
  /// user's command (with the feed-forward on, the feed-forward's command unless decay_feedforward).
  /// 0.3 was chosen on earlier actors; the default config (H10a) has 0.6, since H10a walks crouched
  /// side-steps and turns with its pelvis 0.3-0.43 rad from vertical and at 0.3 the correction decayed
  /// through them (docs/controller.md "The tilt gate and H10a's gait").
  double max_tilt_rad = 0.3;
  /// Time constant of that decay [s], (0, 5].
  double decay_time_s = 0.5;
  /// true: while tilted beyond max_tilt_rad the feed-forward's share w decays too, with the same
  /// time constant: u_ff = u + w (feedforward.invert(u) − u), w ← w (1 − dt/decay_time_s). Once the
  /// robot is upright again w returns to 1 at dt/feedforward_return_s per tick. u_ff stays
  /// continuous: it moves by at most dt/min(decay_time_s, feedforward_return_s) ×
  /// feedforward.max_correction per tick on top of the command's own change. So a robot catching
  /// itself gets the user's command, not the model's. false (the default): only the integral
  /// correction decays and the feed-forward stays whole. Measured and not adopted: on a slippery
  /// floor (sliding friction 0.4) the default actor falls in 8 of 120 mirror-image runs, in the two
  /// 3-axis segments at the envelope's edge, where the pelvis tilts beyond 0.3 rad for 44–50 % of the
  /// segment; with this key 4 of 120, with it and a 3 s return 6 of 120 (not significant;
  /// docs/controller.md "Slippery floors").
  bool decay_feedforward = false;
  /// With decay_feedforward: the time over which the share returns from 0 to 1 once upright [s],
  /// (0, 30] (w rises by dt / feedforward_return_s per tick); 0 (the default): decay_time_s. A
  /// return slower than the decay keeps the share low through a walk that tilts beyond max_tilt_rad
  /// again and again (the envelope's combined corners: 44–50 % of the segment), and leaves a walk
  /// that tilts once in a while nearly whole.
  double feedforward_return_s = 0.0;
  /// An axis integrates only once its shaped command has been steady this long [s], [0, 5]: while
  /// the command ramps (and the robot lags it by design) the error is not the robot's shortfall,
  /// and integrating it winds the correction up into an overshoot. "Steady": within
  /// max(steady_band, 5 % of |u|) of where it was when it last settled (a gamepad stick's jitter
  /// is steady) [m/s, rad/s], [0, 0.5].
  double settle_time_s = 0.5;
  double steady_band = 0.02;
  /// Braking steps (v_x, v_y; off when brake_ratio is 0, the default). When the robot moves faster
  /// than the command in the same direction, e.g. the command stopped while it still walks at
  /// speed, the generator keeps a gait of brake_ratio × the estimated velocity (a floor under u_fb),
  /// so the robot brakes over steps instead of being given a standing reference it runs over. The
  /// floor never lifts u_fb above its previous value minus brake_decel × dt (it only lets the
  /// reference decelerate more slowly, at least at brake_decel), it changes by at most
  /// brake_rate × dt per tick (the reference stays continuous), it keeps its direction until it
  /// is back at zero, and it goes to zero (at brake_rate) while the estimate is invalid, the robot
  /// tilts beyond max_tilt_rad or the command points against the motion. brake_ratio [0, 1) [-],
  /// brake_rate (0, 10] [m/s²], brake_decel (0, min(5, brake_rate)] [m/s²].
  double brake_ratio = 0.0;
  double brake_decel = 0.2;  ///< chosen on the stop script (docs/controller.md "Braking steps")
  double brake_rate = 1.0;
  /// true: the floor's share is brake_ratio × w, where w ∈ [0, 1] is how crouched the shaped posture
  /// is (VelocityFeedback::setBrakeWeight(); the controller passes CommandShaper::crouchFraction():
  /// 0 at the standing height, so an upright or bent stop at the standing height is not lengthened;
  /// 1 at commands.crouched_height; needs that envelope on). false (the default): w = 1. Why: crouched
  /// to 0.66 m and bent 0.3 rad, the default actor sometimes runs on after the stop and falls, while
  /// unscaled braking steps doubled the upright stop from 1.0 m/s, and weighted by the bend too they
  /// lengthened the bent stop from 1.0 m/s at the standing height (docs/controller.md "Braking steps
  /// where the robot runs on").
  bool brake_crouch_scaled = false;
  /// Feed-forward (off unless feedforward.enabled, and only while the feedback is enabled): the
  /// correction is added to u_ff = feedforward.invert(u) instead of to u; the integral still drives
  /// the estimate to u.
  CommandResponseModel feedforward{};
  /// true: u_fb stays inside the shaper's crouched and bent velocity envelopes at the shaped posture
  /// (CommandShaper::envelopeScale; scaled along its direction onto their edge, the correction
  /// reduced to match so that nothing winds up), as the shaped command does. false (the default):
  /// only inside envelope_min/max and max_velocity, so a correction can carry a crouched or bent walk
  /// faster than its envelope lets the command go. Why: crouched to 0.66 m and bent 0.3 rad, told
  /// 0.6 m/s (shaped to 0.574), the correction sent up to 0.67 m/s on a low estimate and the robot
  /// ran on after the stop (docs/controller.md "Running on after a crouched bent walk").
  bool within_posture_envelopes = false;
  /// With within_posture_envelopes: true leaves the yaw-rate correction beyond the envelopes. v_x and
  /// v_y are scaled so that they and the shaped command's ω lie inside them
  /// (CommandShaper::envelopeScaleBesideYaw), and u_fb's ω is left as corrected (within
  /// envelope_min/max and max_velocity as always). false (the default): all three scaled together.
  /// Why: crouched to 0.66 m the actor turns 0.36 rad/s when sent the envelope's 0.63 and 0.54 when
  /// sent 0.79, and the run-on the bound prevents is in v_x (docs/controller.md "Running on after a
  /// crouched bent walk", "What it costs on the crouched probe").
  bool yaw_beyond_envelopes = false;
  /// With within_posture_envelopes: true lets max_velocity_headroom reach inside the crouched and bent
  /// envelopes too. Each axis's envelope limit is at least |u_i| + h_i (CommandShaper::envelopeScale's
  /// min_limit), so a command at an envelope's edge may be corrected up to h beyond it, as one at
  /// max_velocity may be standing; one h or more inside the edge, nothing changes (continuous in u).
  /// false (the default): the envelopes bind the corrected command at their edge. Why: crouched to
  /// 0.66 m and told the largest lateral speed, 0.4 m/s, H10a stepped 0.30 while the corrected command
  /// sat at the edge, 0.400; with it 0.34-0.35. Not on in the default config: its lateral estimate reads 0.03-0.04 m/s
  /// low in side-steps (H10a's stance soles slide along the step: training/results/fidelity/foot_slip/), and the
  /// side-steps at 0.74 / 0.70 m went from 0.38 to 0.44-0.46 (docs/controller.md "Headroom inside the posture envelopes").
  bool headroom_in_envelopes = false;
  /// Upset guard (UpsetGuard; needs enabled: it runs on this loop's estimate). Off by default.
  UpsetGuardConfig upset_guard{};
  /// Empty when valid, else "<field>: expected ..." for the first bad field.
  std::string validate() const;
};

/// Base velocity of the pelvis measured by leg odometry, heading frame H.
struct BaseVelocityEstimate {
  bool valid = false;    ///< false: no foot judged in stance or a non-finite input this tick
  int stance_feet = 0;   ///< feet used (1 or 2)
  double v_x = 0.0;      ///< [m/s] forward (H)
  double v_y = 0.0;      ///< [m/s] left (H)
  double yaw_rate = 0.0; ///< [rad/s] about the world z axis (gyro, rotated into W)
  /// Per foot (left, right): whether it is in stance, and the base velocity it alone implies (H)
  /// [m/s]; v_x, v_y above are the mean over the stance feet. Set by LegOdometry only.
  std::array<bool, 2> foot_in_stance{false, false};
  std::array<double, 2> foot_v_x{0.0, 0.0};
  std::array<double, 2> foot_v_y{0.0, 0.0};
};

/// Leg odometry: per stance foot f (vectors in H, R_HB from the IMU orientation with its yaw
/// removed, ω_B the gyro),
///   v_f = −(ω_H × R_HB p_BS,f + R_HB v_BS,f)   with p_BS, v_BS from the KDL leg chain (eq. 13–14),
/// the mean over the stance feet; a foot is in stance when its sole lies within stance_band_m of the
/// lower sole. Assumes the stance soles do not slip (slip shows up as estimate error).
class LegOdometry {
 public:
  /// @param legs leg chains of the robot (gco::LegModel::fromRobotConfig); @param leg_idx the
  /// chain joints' columns in LowState::motors (LegModel::jointIndices on the robot's joint names).
  /// Setup: allocates; throws std::invalid_argument if legs is null.
  LegOdometry(std::shared_ptr<const gco::LegModel> legs, const gco::LegJointIndex& leg_idx, double stance_band_m);
  ~LegOdometry();
  LegOdometry(const LegOdometry&) = delete;
  LegOdometry& operator=(const LegOdometry&) = delete;

  /// One estimate from the newest state (motor q [rad], qd [rad/s]; IMU quaternion W←B, gyro in B
  /// [rad/s]). noexcept, no allocation.
  BaseVelocityEstimate estimate(const LowState& state) noexcept;
  /// The same with the IMU orientation R_WB already computed (normalised; the estimator computes it
  /// once per tick for the legs and its prediction). noexcept, no allocation.
  BaseVelocityEstimate estimate(const LowState& state, const Eigen::Matrix3d& R_WB) noexcept;

 private:
  gco::LegKinematics kin_;
  gco::LegJointIndex idx_;
  double band_;
};

/// Leg odometry fused with the IMU (a complementary filter, the pattern of leg-inertial state
/// estimators): the velocity in H is propagated with the accelerometer (specific force rotated into
/// W, plus gravity; the rotation of H by the gyro's yaw rate) and pulled towards the leg-odometry
/// measurement with time constant odometry_time_s; a measurement more than gate_mps from the
/// prediction is rejected (touchdown and lift-off transients, slips, flight phases); once the
/// rejections have lasted max_rejected_s the estimate restarts from the legs' measurement (the next
/// sample, or with restart_median the median of the rejected window). The yaw
/// rate is the gyro's (rotated into W), low-passed alike and moved only with the accepted samples:
/// held while the gate rejects, taken from one sample on a restart. Measured against the
/// simulator (docs/controller.md "Velocity estimate"): RMS error on the envelope grid about 0.10 m/s
/// (v_x), 0.08 m/s (v_y), 0.23 rad/s (yaw rate); an ungated yaw rate and a 5 mm stance band are
/// more accurate, but the integral loop tuned on this estimate then upset more often at the
/// envelope's fast combined corners, so they are not the default.
class BaseVelocityEstimator {
 public:
  /// Setup: allocates; throws std::invalid_argument if legs is null.
  BaseVelocityEstimator(std::shared_ptr<const gco::LegModel> legs, const gco::LegJointIndex& leg_idx,
                        const VelocityFeedbackConfig& config);
  /// One tick [dt s]. valid once a first leg-odometry sample arrived. noexcept, no allocation.
  BaseVelocityEstimate update(const LowState& state, double dt) noexcept;
  void reset() noexcept;
  /// The leg-odometry measurement of the last update (with stance_foot_nearest and both soles in the
  /// band: the chosen foot's sample, stance_feet 1).
  const BaseVelocityEstimate& lastLegOdometry() const noexcept { return last_leg_; }
  /// Leg-odometry samples believed / rejected by the gate so far.
  std::uint64_t accepted() const noexcept { return accepted_; }
  std::uint64_t rejected() const noexcept { return rejected_; }
  /// Whether the last update rejected its leg-odometry sample (the estimate is the IMU's alone).
  bool rejecting() const noexcept { return rejected_run_ > 0; }
  /// Pelvis tilt from vertical of the last update [rad] (IMU orientation).
  double tilt() const noexcept { return tilt_; }
  /// Restarts after max_rejected_s of rejections so far (the first sample is not one).
  std::uint64_t restarts() const noexcept { return restarts_; }
  /// Most rejected samples a median restart looks back over (500 at 100 Hz and max_rejected_s 5 s).
  static constexpr int kRestartWindow = 512;

 private:
  static constexpr double kGravity = 9.81;
  /// Median of the last n (≤ kRestartWindow) innovations of axis i; reorders scratch_ only.
  double medianInnovation(std::size_t i, int n) noexcept;
  LegOdometry odometry_;
  VelocityFeedbackConfig config_;
  std::array<double, 3> v_{};
  bool initialized_ = false;
  int rejected_run_ = 0;
  std::uint64_t restarts_ = 0;
  /// Innovations (v_x, v_y) of the rejected samples, a ring indexed by rejected_run_.
  std::array<std::array<double, kRestartWindow>, 2> innovations_{};
  std::array<double, kRestartWindow> scratch_{};
  double tilt_ = 0.0;
  std::uint64_t accepted_ = 0, rejected_ = 0;
  BaseVelocityEstimate last_leg_;
};

/// Upset guard (beyond the paper; issue 12, docs/controller.md "Upset guard"): a robot that has been
/// moving far from its command for a while (staggering sideways, spinning, running backwards when
/// told forwards) is no longer walking where it is told, and pushing on with the command is what
/// turns a stagger into a fall. When some axis i has had |u_i - v_i| > max_error_i for trigger_s
/// without a break, the guard latches: the shaper then slews the velocity command to zero (at its
/// max_acceleration, so the command stays continuous) while the posture command goes on. It
/// releases once the robot has settled (settle_velocity for settle_s) and the operator's command is
/// neutral (rearm_band). Ticks with an invalid estimate neither count nor break a run.
/// Why (posture walks, held-out seed 35): told 1.0 m/s forward while leaning back 0.1 rad, the
/// robot staggered sideways at 0.4-1.3 m/s and spun at up to 4 rad/s from 111.3 s and fell at
/// 113.6 s; told to stop at 111.3, 111.8 or 112.3 s instead, it stood. The guard judges on its own
/// estimate (UpsetGuardConfig::stance_band_m, the yaw rate ungated): on the feedback's it latched
/// on that estimate's glitches. Measured (docs/controller.md "Upset guard"): posture walks 1 fall
/// in 24 -> 0; on held-out seeds it latched only on real staggers, and cost 2 of 33 grid segments
/// in one seed set. noexcept, no allocation per tick.
class UpsetGuard {
 public:
  /// Judging on given estimates (update(u, target, est, dt)). Setup: throws ConfigError on an
  /// invalid config.
  explicit UpsetGuard(const UpsetGuardConfig& config);
  /// Judging on its own estimate (update(u, target, state, dt)): a BaseVelocityEstimator with
  /// @p feedback's settings, config.stance_band_m and the yaw rate ungated. Setup: allocates;
  /// throws ConfigError on an invalid config, std::invalid_argument if legs is null.
  UpsetGuard(const UpsetGuardConfig& config, std::shared_ptr<const gco::LegModel> legs,
             const gco::LegJointIndex& leg_idx, const VelocityFeedbackConfig& feedback);
  ~UpsetGuard();
  UpsetGuard(const UpsetGuard&) = delete;
  UpsetGuard& operator=(const UpsetGuard&) = delete;
  /// One tick [dt s]: @p u the shaped command of the last tick (H), @p target the operator's
  /// clamped command (CommandShaper::target()), @p est the velocity estimate (H). Returns whether the
  /// velocity command is to be held at zero. Disabled: always false. noexcept, no allocation.
  bool update(const VelocityCommand& u, const VelocityCommand& target, const BaseVelocityEstimate& est,
              double dt) noexcept;
  /// The same on the guard's own estimate, updated from @p state every tick (the second
  /// constructor; with the first, always false). noexcept, no allocation.
  bool update(const VelocityCommand& u, const VelocityCommand& target, const LowState& state, double dt) noexcept;
  /// The guard's own estimate of the last update (invalid without one).
  const BaseVelocityEstimate& lastEstimate() const noexcept { return est_; }
  /// Not latched, timers cleared, its estimator restarted (entering and leaving kActive).
  void reset() noexcept;
  bool latched() const noexcept { return latched_; }
  /// Upsets detected so far.
  std::uint64_t upsets() const noexcept { return upsets_; }
  const UpsetGuardConfig& config() const noexcept { return config_; }

 private:
  UpsetGuardConfig config_;
  std::unique_ptr<BaseVelocityEstimator> estimator_;
  BaseVelocityEstimate est_{};
  std::array<double, 3> off_s_{};
  double settled_s_ = 0.0;
  bool latched_ = false;
  std::uint64_t upsets_ = 0;
};

/// The integral correction of the velocity command (file comment). One per control loop.
class VelocityFeedback {
 public:
  /// @param max_velocity |v_x|, |v_y| [m/s], |ω| [rad/s]: the shaper's limits (u_fb stays inside
  /// them, widened near them by config.max_velocity_headroom, and inside config.envelope_min/max).
  /// Setup: allocates; throws ConfigError on an invalid config.
  VelocityFeedback(const VelocityFeedbackConfig& config, std::shared_ptr<const gco::LegModel> legs,
                   const gco::LegJointIndex& leg_idx, const std::array<double, 3>& max_velocity);

  /// One tick [dt s]: estimate from @p state (BaseVelocityEstimator), integrate the error of the
  /// shaped command @p u, and return u_fb. When disabled returns @p u. noexcept, no allocation.
  const VelocityCommand& update(const VelocityCommand& u, const LowState& state, double dt) noexcept;
  /// The integrator alone, on a given estimate @p est (update() = BaseVelocityEstimator + this);
  /// @p hold: do not integrate (the estimator is rejecting its measurements); @p decay: the robot
  /// tilts beyond max_tilt_rad, the correction decays to zero. noexcept, no allocation.
  const VelocityCommand& correct(const VelocityCommand& u, const BaseVelocityEstimate& est, double dt,
                                 bool hold = false, bool decay = false) noexcept;
  /// Scales the last update's u_fb down by @p scale (> 1; otherwise nothing), along its direction,
  /// and the correction with it (c = u_fb − u_ff, so that it does not wind up against the bound);
  /// @p keep_yaw: only v_x and v_y are scaled (VelocityFeedbackConfig::yaw_beyond_envelopes, with
  /// CommandShaper::envelopeScaleBesideYaw). Counted in envelopeTicks(). Returns u_fb. For
  /// VelocityFeedbackConfig::within_posture_envelopes. noexcept, no allocation.
  const VelocityCommand& scaleDown(double scale, bool keep_yaw = false) noexcept;
  /// Ticks on which scaleDown() acted so far.
  std::uint64_t envelopeTicks() const noexcept { return envelope_ticks_; }
  /// The feed-forward's share w ∈ [0, 1] of the last update (VelocityFeedbackConfig::decay_feedforward;
  /// always 1 without it).
  double feedforwardShare() const noexcept { return ff_share_; }
  /// Ticks on which the correction was held (estimator rejecting) / decayed (tilt) so far.
  std::uint64_t heldTicks() const noexcept { return held_ticks_; }
  std::uint64_t decayedTicks() const noexcept { return decayed_ticks_; }
  /// Zero correction, estimator restarted (entering kActive, leaving it).
  void reset() noexcept;

  bool enabled() const noexcept { return config_.enabled; }
  /// The command after feedback of the last update (what the generator got).
  const VelocityCommand& command() const noexcept { return u_fb_; }
  /// The correction c (v_x, v_y, ω) of the last update.
  const std::array<double, 3>& correction() const noexcept { return c_; }
  /// The feed-forward command u_ff of the last update (= u when feedforward is off).
  const std::array<double, 3>& feedforward() const noexcept { return u_ff_; }
  /// The braking floor (v_x, v_y [m/s] in H; 0: none) of the last update (config brake_ratio).
  const std::array<double, 2>& brakeFloor() const noexcept { return brake_; }
  /// The weight w ∈ [0, 1] of the braking floor for the next update() when
  /// config().brake_crouch_scaled (clamped; NaN → 0). noexcept.
  void setBrakeWeight(double w) noexcept { brake_weight_ = w >= 0.0 ? (w <= 1.0 ? w : 1.0) : 0.0; }
  /// The crouch c [m] (standing height − the shaped pelvis height) at which the feed-forward's gains
  /// are taken for the next update() (CommandResponseModel, gain_*_per_crouch; clamped to [0, 0.5],
  /// NaN → 0). The controller passes commands.standing_height − CommandShaper::posture().height, which
  /// the shaper slews, so the feed-forward stays continuous through a crouch. noexcept.
  void setCrouch(double crouch_m) noexcept { crouch_m_ = CommandResponseModel::clampCrouch(crouch_m); }
  double crouch() const noexcept { return crouch_m_; }
  /// Ticks on which the braking floor raised the command so far.
  std::uint64_t brakingTicks() const noexcept { return braking_ticks_; }
  /// The estimate (v_x, v_y [m/s], ω [rad/s] in H) the last update integrated on.
  const BaseVelocityEstimate& lastEstimate() const noexcept { return est_; }
  std::array<double, 3> filteredEstimate() const noexcept { return {est_.v_x, est_.v_y, est_.yaw_rate}; }
  const BaseVelocityEstimator& estimator() const noexcept { return estimator_; }
  const VelocityFeedbackConfig& config() const noexcept { return config_; }

 private:
  double estimate(std::size_t i) const noexcept { return i == 0 ? est_.v_x : (i == 1 ? est_.v_y : est_.yaw_rate); }
  VelocityFeedbackConfig config_;
  BaseVelocityEstimator estimator_;
  std::array<double, 3> max_velocity_;  ///< the shaper's limits [m/s, m/s, rad/s]
  std::array<double, 3> c_{};
  std::array<double, 3> u_ff_{};
  std::array<double, 3> u_anchor_{}, steady_{};
  std::array<double, 2> brake_{};
  double brake_weight_ = 1.0;
  double crouch_m_ = 0.0;
  double ff_share_ = 1.0;  ///< w of decay_feedforward
  BaseVelocityEstimate est_;
  VelocityCommand u_fb_{}, u_fb_prev_{};
  std::uint64_t held_ticks_ = 0, decayed_ticks_ = 0, braking_ticks_ = 0, envelope_ticks_ = 0;
};

/// `posture_feedback:` of the controller config (PostureFeedback).
struct PostureFeedbackConfig {
  bool enabled = false;
  /// Integral gains for torso pitch and roll [1/s], each 0..20.
  std::array<double, 2> ki{0.5, 0.5};
  /// Largest correction of the pitch and roll commands [rad], [0, 0.3].
  double max_correction_rad = 0.15;
  /// Time constant of the low-pass on the measured torso pitch/roll [s], [0, 2].
  double filter_time_s = 0.2;
  /// Above this pelvis tilt [rad], (0, 1.5], the correction decays to zero (decay_time_s).
  double max_tilt_rad = 0.5;
  double decay_time_s = 0.5;  ///< [s], (0, 5]
  /// The correction integrates only while the robot is told to stand still: |v_x|, |v_y| of the
  /// shaped command below still_velocity [m/s] and |ω| below twice that [rad/s], [0, 1]; while
  /// walking it decays (decay_time_s). Walking sways the torso, and a lean commanded against the
  /// sway of a side-step at the envelope's edge felled the robot (docs/controller.md).
  double still_velocity = 0.05;
  /// Also require the robot to be still (beyond the paper): the standing pitch/roll integrator
  /// integrates only while the estimated base velocity (H, the velocity feedback's leg odometry,
  /// when valid) has |v_x|, |v_y| below this [m/s], [0, 2]; while the command is still but the
  /// robot still moves, the correction is held (neither integrated nor decayed). 0 (the default):
  /// off. Measured: after a 0.4 rad bent walk at 1.0 m/s the robot ran on at 1.4-2.7 m/s for 3 s
  /// after the stop, its torso behind the bend, and the standing integrator bent it 0.085 rad
  /// further while it ran; it fell (posture walks, seed 21).
  double still_measured_velocity = 0.0;
  /// Standing still, an axis integrates only once its posture command has stayed within 0.01 rad of
  /// where it settled for this long [s], [0, 5]; meanwhile its standing correction is held (neither
  /// integrated nor decayed). 0 (the default): always, as before. The torso lags the shaper's
  /// posture ramp (posture_rate) by 0.1-0.2 rad; integrated, that lag wound the correction to
  /// -0.05 rad by the end of an unbend from 0.4 rad, and the robot then stood leaning back
  /// 0.04-0.08 rad for 2 s (posture walks; docs/controller.md "Settled before the standing integrator").
  double settle_s = 0.0;
  /// Standing still, the pitch/roll integrator integrates only once the velocity command has been
  /// still (still_velocity) for this long [s], [0, 5]; meanwhile the standing correction is held
  /// (neither integrated nor decayed). 0 (the default): from the first still tick, as before. The
  /// robot's own transient after a stop is not a posture error: stopping a 0.4 rad/s turn walked at
  /// the 0.66 m walking floor, H5c's torso swings back 0.13-0.16 rad for about 0.5 s and then
  /// forward; integrated at ki 1 /s, that swing wound a +0.10-0.11 rad forward correction, which the
  /// torso then followed past upright into a forward run-on and a fall (4 of 4 held-out stress falls).
  /// Not adopted: on new seeds H5c still fell as often, as the next walk started (docs/controller.md
  /// "Settled after a stop").
  double stop_settle_s = 0.0;
  /// While walking (not still), integral gains for torso pitch and roll [1/s], each 0..5; 0 (the
  /// default): the correction decays while walking, as above. A walking gait sways the torso about
  /// a mean (roll ±0.1 rad over a side-step cycle), so walking uses its own slower low-pass of the
  /// measured attitude (walking_filter_time_s, about a gait cycle) and its own, smaller bound.
  std::array<double, 2> walking_ki{0.0, 0.0};
  /// Largest walking correction c_w [rad], [0, 0.3].
  double walking_max_correction_rad = 0.05;
  /// Time constant τ of the walking low-pass [s], [0, 5]. With the torso following its command, the
  /// walking integrator on this low-pass is a second-order loop, ω_n = √(walking_ki/τ), damping
  /// ζ = 1/(2√(walking_ki·τ)): 0.29 at 3 /s and 1 s, 0.41 at 0.5 s (g1_sil_policy.yaml since
  /// 2026-12-07; docs/controller.md "The walking posture loop's damping").
  double walking_filter_time_s = 1.0;
  /// While walking, an axis integrates only once its posture command has stayed within 0.01 rad of
  /// where it settled for this long [s], [0, 5]: the torso lags a posture ramp (the shaper's
  /// posture_rate) and the walking low-pass lags more, and integrating that lag overshoots.
  double walking_settle_s = 1.0;
  /// While walking, the pitch and roll walking integrators integrate only once the shaped velocity
  /// command has stayed within 0.05 m/s (v_x, v_y) and 0.05 rad/s (ω) of where it settled for this
  /// long [s], [0, 5]; meanwhile each holds its correction. 0 (the default): off, as before. The
  /// start of a walk, and every change of its command, swings the torso: as a crouched side-step
  /// starts from a stand, H10a's torso pitches 0.2-0.28 rad forward for about 0.4 s and then leans
  /// back 0.05 rad for as long as it walks; integrated from the first tick at 2 /s, that swing wound a
  /// backward correction (−0.12 rad) that took the rest of a 4 s walk to unwind, the wrong way for the
  /// walk. Its measured share on H10a's battery is within the seeds' spread: the walking gain and bound
  /// carry the crouched walks upright (docs/controller.md "Fed back once the walk has settled").
  double walking_velocity_settle_s = 0.0;
  /// While walking, an axis integrates only while |its posture command| is at least this [rad],
  /// [0, 0.5]; 0: always. Walking with the torso upright, the gait's own pitch is left alone (fed
  /// back on bk_vy6, the median stop from 1 m/s grew from 0.50 to 0.62 m; docs/controller.md).
  double walking_min_command_rad = 0.0;
  /// While walking with |its posture command| below walking_min_command_rad, an axis integrates
  /// only the part of its error beyond this dead band [rad], [0, 0.3] (e − sign(e)·band), and
  /// inside the band its correction decays (decay_time_s), so that what one gait needed is not
  /// carried into the next; 0 (the default): it does not integrate there. For a torso that leans
  /// beyond the cross-coupling target while walking upright (issue 12: ≤ 0.05 rad) without feeding
  /// back the gait's ordinary few hundredths of a radian (fed back whole, the median stop from
  /// 1 m/s grew from 0.50 to 0.62 m).
  double walking_deadband_rad = 0.0;
  /// While walking crouched with an upright command (|posture command| below
  /// walking_min_command_rad), with the height command at least this far below the standing height
  /// [m], [0, 0.2], an axis integrates as if its posture command were commanded (the whole error,
  /// no dead band), and the standing integrator's correction is held instead of decaying, up to
  /// walking_max_correction_rad (any part beyond decays at decay_time_s); 0 (the default): off. A
  /// crouched walk leans the torso back 0.05-0.10 rad that nobody commanded (issue 12's
  /// cross-coupling, `crouch_walk`), and the still crouch leans too, where an upright walk's gait
  /// pitch is a few hundredths; this feeds back the first and leaves the second alone. A commanded
  /// bend is not held (held, a 0.4 rad bend walked at 0.66 m fell at the stop). Needs the standing
  /// height (the shaper's: the squat clip's neutral); the constructor throws ConfigError without it.
  double walking_crouch_m = 0.0;
  /// With walking_crouch_m: a held standing correction that pushes the gait-averaged torso (the
  /// walking low-pass) further from the command, the walking error u_p − p̄ beyond 0.02 rad on
  /// its other side, is not held but decays (decay_time_s) for as long as it does; false (the default):
  /// always held, as above. For an actor that leans one way standing crouched and the other way
  /// walking crouched: H3 leans forward standing at 0.62 m and back walking at 0.68 m, so the
  /// held correction (−0.02…−0.06 rad) added to the walk's backward lean and the walking
  /// integrator spent its bound cancelling it (grid crouch_walk −0.080 rad; docs/controller.md
  /// "Crouched walks").
  bool walking_crouch_release = false;
  /// Standing still: a standing correction that pushes the torso further past the command, the
  /// error u_p − p̂ (the fast low-pass) beyond 0.02 rad on the correction's other side, decays
  /// (decay_time_s) for as long as it does, on top of its integration; false (the default): it only
  /// integrates back, at ki·|error|, 0.1 rad/s for a torso 0.1 rad past the command. A crouched
  /// actor whose torso swings back after a stop, and then forward, kept a +0.06-0.15 rad forward
  /// correction as the torso tipped forward, and ran on into a fall (H5c, H7). Not adopted: with
  /// stop_settle_s, H5c fell in 4 of 72 held-out stress runs, as without either (docs/controller.md
  /// "Released where the torso overshoots").
  bool overshoot_release = false;
  /// Bounds on the fed-back pitch and roll [rad], (pitch, roll) minimum and maximum, each finite
  /// with -1.5 ≤ envelope_min ≤ 0 ≤ envelope_max ≤ 1.5: a correction never pushes the command
  /// beyond them, u_fb,p ∈ [min(u_p, envelope_min), max(u_p, envelope_max)] (a command already
  /// beyond is passed on, not corrected further out), and what they cut comes off the integrator
  /// that is acting (anti-windup). The default (±1.5) leaves only the command's range. For the
  /// actor's trained range (wh6g: pitch up to 0.4, roll ±0.2). Why: walking bent 0.4 rad the walking
  /// and standing integrators sent the actor 0.41-0.55 rad, beyond what it was trained on, and in
  /// the stop after a crouched bent walk it ran away forward and fell (posture walks on seeds
  /// 72-95: twice in 48 runs). Bounded at 0.4, bent 0.4 rad stops ran on in 0 of 360 walk-runs,
  /// against 8 (docs/controller.md "Bent beyond the trained range").
  std::array<double, 2> envelope_min{-1.5, -1.5};
  std::array<double, 2> envelope_max{1.5, 1.5};
  /// Integral gain on the pelvis height [1/s], 0..20; 0 (the default) leaves the height alone.
  double height_ki = 0.0;
  /// Largest correction of the height command [m], [0, 0.1].
  double max_height_correction_m = 0.03;
  /// The height integrates only once its command has stayed within 5 mm of where it settled for
  /// this long [s], [0, 5]: the robot lags a crouch by design (the shaper's height slew), and
  /// integrating that lag winds the correction the wrong way (measured: a 0.66 m squat ended 9 mm
  /// low instead of 4 mm high).
  double height_settle_s = 1.0;
  /// While walking (not still, not tilted), integral gain on the pelvis height [1/s], 0..5; 0 (the
  /// default): the height correction decays while walking, as above. A second integrator c_hw on
  /// the same low-pass ĥ (filter_time_s; the integrator averages the pelvis' bob over a step: a
  /// 1 s walking low-pass, as for pitch and roll, left too little of a 4 s walk to close the loop),
  /// integrating once the height command has been steady for height_settle_s and the robot has
  /// walked for walking_settle_s; it decays (decay_time_s) when the robot is told to stand, tilts
  /// beyond max_tilt_rad or is upset (the upset guard's upright hold).
  /// The walking command is never lowered below the walking floor (the shaper's
  /// commands.walking_min_height, passed to the constructor): u_fb,h ≥ min(u_h, floor), less
  /// walking_below_floor_m (below). Why: actors
  /// trained from scratch walk crouched 0.02-0.05 m above the command (N24b: −0.5 m/s at 0.70 m
  /// walked at 0.729), outside issue 12's 0.015 m, and the floor exists because walks at 0.62 m fell.
  double walking_height_ki = 0.0;
  /// Largest walking height correction c_hw [m], [0, 0.1].
  double walking_max_height_correction_m = 0.03;
  /// How far below the walking floor the walking height correction may take the command [m],
  /// [0, 0.05]; 0 (the default): never below it, as above. The floor exists because walks crouched
  /// to 0.62 m fell: it is meant for the pelvis, not for the number sent to the actor. An actor that
  /// walks 2-5 cm above its command (finetune_n24b/F0a: told 0.66 m, 0.679-0.715) cannot be brought
  /// to the floor while the command may not pass it. With this margin the bound becomes
  /// u_fb,h ≥ min(u_h, floor) − walking_below_floor_m, while walking and while the walking correction
  /// decays after it (so the stop returns the command to the floor at decay_time_s, never by a jump).
  /// The integrator's target stays the command itself, u_h ≥ floor: the correction goes below the
  /// floor only as long as the measured pelvis ĥ is above the command, so the pelvis is still held at
  /// the floor (docs/controller.md "Walking height correction").
  double walking_below_floor_m = 0.0;
  std::string validate() const;
};

/// The same idea for the posture (beyond the paper; docs/controller.md "Tracking feedback"): the
/// torso's pitch and roll (ZYX Euler angles of torso_link in W, as Table I measures them) from the
/// IMU orientation and the waist encoders (KDL forward kinematics pelvis -> torso_link),
///   p̂ low-passed,  c_p ← clamp(c_p + k_p (u_p − p̂) dt, ±max_correction_rad),
///   u_fb,p = clamp(u_p + c_p, the command's pitch/roll range ∩ [min(u_p, envelope_min), max(u_p, envelope_max)]);
/// only while the velocity command is still (PostureFeedbackConfig::still_velocity), else c_p decays;
/// with walking_ki > 0 a second integrator c_w acts while walking, once the posture command has been
/// steady for walking_settle_s (and the shaped velocity command for walking_velocity_settle_s):
/// c_w ← clamp(c_w + k_w (u_p − p̄) dt, ±walking_max_correction_rad) on
/// the slower low-pass p̄ (walking_filter_time_s), and decays while standing; the correction is
/// clamp(c_p + c_w, ±max_correction_rad). With walking_crouch_m, an upright-command walk crouched
/// that far below standing counts as commanded, and c_p is held (within the walking bound) while it
/// walks instead of decaying.
/// With height_ki > 0 the pelvis height gets the same treatment: ĥ = the height of the pelvis (B
/// origin) above the lower stance sole, −min_f (R_WB p_BS,f)_z on the KDL leg chains (flat ground
/// assumed: the Table I Height measure on a level floor), low-passed alike;
///   c_h ← clamp(c_h + k_h (u_h − ĥ) dt, ±max_height_correction_m)   (once u_h is steady),
///   u_fb,h = clamp(u_h + c_h, [height_range[0], max(u_h, min(height_range[1], standing_height))]):
/// a crouch is deepened or raised to the commanded height, and a robot that stands a little low is
/// never straightened beyond the standing pose. With walking_height_ki > 0 a walking height
/// integrator c_hw acts as c_w does for pitch and roll (on ĥ), and is bounded by
/// the walking floor: u_fb,h = clamp(u_h + c_h + c_hw, [max(height_range[0], min(u_h, floor)), ...])
/// while walking or while c_hw decays. noexcept and allocation-free per tick (tested).
class PostureFeedback {
 public:
  /// With walking_height_ki > 0, the applied height correction (both integrators, after the bounds) moves at
  /// most this fast [m/s]: half the shipped configs' commands.height_rate (0.2 m/s), so a bound that takes
  /// effect at once (the walking floor as a walk starts) cannot step the height reference.
  static constexpr double kWalkingHeightCorrectionRate = 0.1;
  /// @param pitch_range, roll_range the shaper's posture limits [rad]; @param height_range the
  /// shaper's height limits [m] and @param standing_height its standing height [m]; @param legs,
  /// leg_idx the robot's leg chains and their columns in LowState::motors (needed only with
  /// height_ki or walking_height_ki > 0). Setup: allocates; throws ConfigError on an invalid config, a robot without a
  /// torso_link chain, or height_ki or walking_height_ki > 0 without leg chains.
  /// @param walking_min_height the shaper's walking height floor [m] (commands.walking_min_height; 0:
  /// none): the walking height correction never lowers the command below it.
  PostureFeedback(const PostureFeedbackConfig& config, const RobotConfig& robot, const std::array<double, 2>& pitch_range,
                  const std::array<double, 2>& roll_range, const std::array<double, 2>& height_range = {0.0, 0.0},
                  double standing_height = 0.0, std::shared_ptr<const gco::LegModel> legs = nullptr,
                  const gco::LegJointIndex& leg_idx = {}, double walking_min_height = 0.0);
  ~PostureFeedback();
  PostureFeedback(const PostureFeedback&) = delete;
  PostureFeedback& operator=(const PostureFeedback&) = delete;
  /// One tick [dt s] with the shaped posture @p u and velocity @p v commands: returns the posture
  /// command after feedback. When disabled returns @p u.
  /// @p v_est: the estimated base velocity (v_x, v_y [m/s] in H; the velocity feedback's), or
  /// nullptr when none is available (then still_measured_velocity is not applied).
  /// @p upset: the upset guard holds with UpsetGuardConfig::upright; the standing and walking
  /// corrections decay (decay_time_s) instead of integrating, so that the torso goes upright (the
  /// standing integrator would otherwise push a torso leaning back as the robot runs on forward again).
  const PostureCommand& update(const PostureCommand& u, const VelocityCommand& v, const LowState& state,
                               double dt, const BaseVelocityEstimate* v_est = nullptr, bool upset = false) noexcept;
  void reset() noexcept;
  const PostureCommand& command() const noexcept { return u_fb_; }
  /// Correction (pitch, roll) [rad] and the low-passed measurement (pitch, roll) [rad] of the last update.
  const std::array<double, 2>& correction() const noexcept { return c_; }
  const std::array<double, 2>& measured() const noexcept { return p_hat_; }
  /// Torso pitch and roll of @p state (IMU orientation, waist encoders) [rad]; false on bad input.
  bool torsoAttitude(const LowState& state, double* pitch, double* roll, double* pelvis_tilt) noexcept;
  /// Pelvis height above the lower sole [m] of @p state (IMU orientation, leg encoders); false on
  /// bad input or when the height is not fed back (height_ki and walking_height_ki 0).
  bool pelvisHeight(const LowState& state, double* height) noexcept;
  /// Height correction applied [m] (the bounded sum of c_h and c_hw) and the low-passed measured
  /// height ĥ [m] of the last update (0 when off).
  double heightCorrection() const noexcept { return c_h_applied_; }
  double measuredHeight() const noexcept { return h_hat_; }
  /// The walking height integrator c_hw [m] of the last update.
  double walkingHeightCorrection() const noexcept { return c_hw_; }

 private:
  PostureFeedbackConfig config_;
  LimbChain torso_;
  ChainFkWorkspace fk_;
  Eigen::VectorXd q_;
  std::array<double, 2> pitch_range_, roll_range_, height_range_;
  double standing_height_;
  double walking_min_height_;
  std::unique_ptr<gco::LegKinematics> legs_;  ///< null when the height is not fed back
  gco::LegJointIndex leg_idx_;
  std::array<double, 2> c_{}, p_hat_{}, p_walk_hat_{};
  std::array<double, 2> c_stand_{}, c_walk_{};  ///< the standing and the walking integrators (c_ = their bounded sum)
  std::array<double, 2> p_settled_{}, p_steady_s_{};  ///< where each posture command settled, and for how long
  double still_s_ = 0.0;  ///< how long the velocity command has been still [s] (stop_settle_s)
  std::array<double, 3> v_settled_{};  ///< where the shaped velocity command settled (walking_velocity_settle_s)
  double v_steady_s_ = 0.0;  ///< and for how long [s]
  bool have_ = false;
  double c_h_ = 0.0, h_hat_ = 0.0;
  double c_hw_ = 0.0, c_h_applied_ = 0.0;  ///< the walking integrator, the applied sum of both
  double h_walking_s_ = 0.0;  ///< how long the robot has been told to walk
  bool have_h_ = false;
  double h_settled_ = 0.0, h_steady_s_ = 0.0;  ///< where the height command settled, and for how long
  PostureCommand u_fb_{};
};

}  // namespace pmg
