#pragma once
/// @file foot_slip.hpp
/// Foot-slip metrics of a reference motion (template joints + a base command), PMG Fig. 5.
///
/// The meter integrates the pelvis pose in the world frame W with the base command it is given
/// (v_x, v_y, ω in H; height h), using the midpoint rule at the control period:
///   θ_{k+1} = θ_k + ω dt,  p_WB,xy(k+1) = p_WB,xy(k) + Rz(θ_k + ω dt / 2) v dt,
/// places each sole point in W with the leg kinematics (eq. 13), and evaluates, over every stance
/// (a maximal run of ticks with c_f = 1 whose touchdown and lift-off both lie in the record):
///   - stance-foot speed |v_WS,xy| from eq. 14 [m/s] (mean and max over stance ticks);
///   - slip per stance: largest horizontal distance of the sole from its touchdown point [m];
///   - stance height error |p_WS,z − h_ground| [m] (mean and max over stance ticks);
///   - kinematic consistency: the base velocity implied by each stance foot (the v that makes it
///     stationary) compared with the commanded velocity u (mean |Δ| over stance ticks) [m/s].
/// Setup-time / analysis tool: add() may allocate (it stores the trace).

#include <vector>

#include "pmg/gco/gco.hpp"

namespace pmg::gco {

/// Base motion implied by the stance feet: the base velocity (v_x, v_y) and yaw rate ω, in the
/// heading frame H, that hold every stance sole still on the ground (eq. 14 with v_WS = 0 and the
/// foot yaw rate ω_WF,z = 0, solved for the base terms; averaged over the feet in stance).
struct ImpliedBaseVelocity {
  bool valid = false;   ///< false when no foot is in stance (or a leg state is non-finite)
  int stance_feet = 0;  ///< feet in stance this sample (0, 1 or 2)
  double v_x = 0.0;     ///< [m/s], heading frame x (forward)
  double v_y = 0.0;     ///< [m/s], heading frame y (left)
  double yaw_rate = 0.0;  ///< [rad/s], about z, counter-clockwise positive
};

/// Stance-implied base velocity of one reference sample: joints `in.q_leg`, rates `in.qd_leg`,
/// contacts `in.contact`, pelvis attitude `in.base_roll`/`in.base_pitch` (the base command and
/// template velocity in `in` are not used). Per stance foot f (vectors in H, R_HB from roll/pitch):
///   ω_f = −(R_HB ω_BF,f)_z,   v_f = −(ω_f e_z × R_HB p_BS,f + R_HB v_BS,f)_xy,
/// then the mean over the stance feet. noexcept; no allocation (uses `kin`'s workspace).
ImpliedBaseVelocity stanceImpliedVelocity(LegKinematics& kin, const GcoInput& in) noexcept;

struct FootSlipStats {
  int stances = 0;                   ///< complete stances evaluated
  int stance_ticks = 0;              ///< stance samples evaluated
  double mean_stance_speed = 0.0;    ///< [m/s]
  double max_stance_speed = 0.0;     ///< [m/s]
  double mean_slip_per_stance = 0.0; ///< [m]
  double max_slip_per_stance = 0.0;  ///< [m]
  double mean_height_error = 0.0;    ///< [m]
  double max_height_error = 0.0;     ///< [m]
  double mean_single_support_speed = 0.0;  ///< stance-foot speed over single-support ticks only [m/s]
  double mean_double_support_speed = 0.0;  ///< stance-foot speed over double-support ticks only [m/s]
  double mean_implied_v_x = 0.0;     ///< base v_x implied by the stance feet [m/s]
  double mean_implied_v_y = 0.0;     ///< base v_y implied by the stance feet [m/s]
  double mean_implied_velocity_error = 0.0;  ///< mean |v_implied,xy − u_cmd,xy| [m/s]
  double mean_implied_yaw_rate = 0.0;  ///< base yaw rate implied by the stance feet [rad/s] (stanceImpliedVelocity)
};

/// One recorded tick.
struct FootSlipSample {
  double t = 0.0;                    ///< time since reset [s]
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();  ///< pelvis position in W [m]
  double yaw = 0.0;                  ///< pelvis yaw in W [rad]
  std::array<Eigen::Vector3d, kNumFeet> p_WS{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  ///< soles in W [m]
  std::array<Eigen::Vector3d, kNumFeet> v_WS_H{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  ///< eq. 14 [m/s]
  std::array<bool, kNumFeet> contact{false, false};
};

class FootSlipMeter {
 public:
  /// Throws std::invalid_argument if model is null or dt <= 0.
  FootSlipMeter(std::shared_ptr<const LegModel> model, double dt, double ground_height = 0.0);

  /// Records one tick: template joints/contacts and user command from `in`, base motion from
  /// `base` (v_x, v_y, yaw_rate, height; pitch/roll unused). With GCO, pass GcoResult::u_opt; for
  /// the no-GCO baseline pass the template's own (v, ω, h). Throws std::runtime_error on bad input.
  void add(const GcoInput& in, const BaseCommand& base);

  FootSlipStats stats() const;
  const std::vector<FootSlipSample>& trace() const { return trace_; }
  void reset();

 private:
  std::shared_ptr<const LegModel> model_;
  LegKinematics kin_;
  double dt_;
  double ground_height_;
  Eigen::Vector3d p_WB_ = Eigen::Vector3d::Zero();
  double yaw_ = 0.0;
  std::vector<FootSlipSample> trace_;
  std::vector<Eigen::Vector2d> implied_v_;        ///< per tick, per stance foot (flattened)
  std::vector<Eigen::Vector2d> commanded_v_;
  std::vector<double> implied_w_;                 ///< per tick with a stance foot [rad/s]
};

}  // namespace pmg::gco
