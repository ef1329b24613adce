#pragma once
/// @file synthetic_gait.hpp
/// Synthetic walking templates built from the G1 leg kinematics, with a known kinematic error.
///
/// The "true" gait moves the pelvis at (v_x, v_y, ω) in the heading frame H at constant height h;
/// each foot is world-fixed (stationary) during its stance and swings on a smooth arc otherwise.
/// Leg joints q come from KDL inverse kinematics of the sole poses, q̇ = J(q)⁻¹ × (sole twist
/// relative to the pelvis, central difference of the analytic sole target, ±1e-6 s). The template then *reports* a wrong base motion,
/// (v_x + v_x_error, v_y + v_y_error, ω + yaw_rate_error, h + height_error): integrated with the
/// reported motion, each stance foot slides by v_error · T_stance and floats by −height_error,
/// which is what GCO must remove (PMG Fig. 5). Used by the GCO tests, bench and app.

#include <vector>

#include "pmg/gco/gco.hpp"
#include "pmg/gco/leg_kinematics.hpp"

namespace pmg::gco {

struct SyntheticGaitOptions {
  double v_x = 0.4;          ///< true base forward velocity [m/s]
  double v_y = 0.0;          ///< true base lateral velocity [m/s]
  double yaw_rate = 0.0;     ///< true base yaw rate [rad/s]
  double base_height = 0.74; ///< true pelvis height [m]
  double period = 0.8;       ///< gait cycle T [s]
  double duty = 0.6;         ///< stance fraction of each foot, (0.3, 0.9); > 0.5 gives double support
  double step_height = 0.06; ///< swing apex height of the sole [m]
  double stance_width = 0.23;  ///< lateral distance between the two sole points [m]
  double stance_x = 0.0;     ///< sole x at mid-stance relative to the pelvis [m]
  double dt = 0.01;          ///< sample period = control period [s]; period/dt must be an integer
  double v_x_error = 0.0;      ///< error of the reported forward velocity [m/s]
  double v_y_error = 0.0;      ///< error of the reported lateral velocity [m/s]
  double yaw_rate_error = 0.0; ///< error of the reported yaw rate [rad/s]
  double height_error = 0.0;   ///< error of the reported pelvis height [m]
  /// Contact centres μ (phase) of the left and right foot (PMG contact model).
  double mu_left = 0.25, mu_right = 0.75;

  /// Throws std::invalid_argument naming the field and its range.
  void validate() const;
};

/// One cycle of a synthetic template: N = period/dt ticks, φ_k = k/N.
struct SyntheticGait {
  SyntheticGaitOptions options;
  std::vector<double> phase;   ///< (N) φ_k
  std::vector<GcoInput> ticks; ///< (N) the template as GCO sees it (reported base motion)
  double ik_max_error = 0.0;   ///< worst IK residual over all samples [m + rad]
};

/// Builds the template (setup time; allocates). `command` fills GcoInput::command.
/// Throws std::invalid_argument from validate() and std::runtime_error if IK fails (> 1e-6).
SyntheticGait makeSyntheticGait(LegKinematics& kin, const SyntheticGaitOptions& options);

}  // namespace pmg::gco
