#pragma once
/// @file mujoco_backend.hpp
/// In-process MuJoCo 2.2 backend of the HAL (software in the loop).
///
/// Per HAL cycle (2 ms) it steps the physics `cycle_period / timestep` times (≥ 1 kHz), and at
/// every physics step computes the motor-level PD of each joint as a real driver does:
///   τ = kp (q* − q) + kd (q̇* − q̇) + τ_ff, clipped at ± the joint's torque limit
/// with the latest command held between cycles. The IMU comes from the model's sensors on the IMU
/// site (framequat, gyro, accelerometer). Optional:
///  - the virtual gantry: an elastic band (spring-damper on the pelvis position, plus an
///    orientation spring-damper that keeps the torso upright), as robots are commissioned hanging
///    from a gantry. A real bring-up mode; it stays in the product;
///  - hidden encoder zero offsets: reported q = true q + offset (for zero-point calibration tests);
///  - the identified actuator model of a joint (robot config `actuator:` block from
///    pmg_calib_dynamics, pmg::calib::ActuatorModel): transport delay, driver PD rate, zero
///    offset, torque saturation and torque-speed envelope, Coulomb/Stribeck/load-dependent
///    friction with true stiction, viscous friction, armature and gain scales (backlash needs a
///    rotor body and is not applied to the robot: a configured gap is refused with an error);
///  - external pushes on a body (fault-injection tests);
///  - body mass scales (model errors of a "reality", pmg_sil --reality);
///  - stiff "calibration bench" sole contacts (SoleContactOptions, default off).

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/backend.hpp"

namespace pmg {

/// Virtual gantry (elastic band) on the floating base.
struct GantryOptions {
  bool enabled = true;
  double anchor_height = 0.95;      ///< pelvis height the band holds [m] (feet clear of the ground)
  double stiffness = 4000.0;        ///< linear spring [N/m]
  double damping = 400.0;           ///< linear damper [N·s/m]
  double rot_stiffness = 800.0;     ///< orientation spring [N·m/rad]
  double rot_damping = 60.0;        ///< orientation damper [N·m·s/rad]
  std::string validate() const;
};

/// Calibration-bench sole contacts (opt-in; off = the MJCF's soft contacts, which every other SIL test and
/// the policy assume). MuJoCo's default contact (solref 0.02 s, solimp 0.9/0.95) lets a loaded G1 sole
/// sink and tilt by millirad as its load moves; a zero-point calibration that assumes flat, planted soles
/// (docs/calibration.md, "Zero-point calibration") needs a rigid bench floor. When enabled, every
/// colliding geom of the two foot bodies (robot config left/right_foot_link) gets this solref/solimp and a
/// solmix of 1e3 (MuJoCo averages the two geoms' parameters weighted by solmix, so the sole's values
/// dominate the floor's). MuJoCo 2.2 semantics (XML reference, "Solver parameters"): solref =
/// (time constant [s], damping ratio), solimp = (dmin, dmax, width [m]).
struct SoleContactOptions {
  bool enabled = false;
  double timeconst = 0.004;  ///< solref[0] [s], >= 2 physics timesteps (MuJoCo's stability rule)
  double dampratio = 1.0;    ///< solref[1], in (0, 10]
  double dmin = 0.99;        ///< solimp[0], in (0, dmax]
  double dmax = 0.999;       ///< solimp[1], in [dmin, 1)
  double width = 0.001;      ///< solimp[2] [m], > 0
  std::string validate(double timestep) const;  ///< empty if valid, else "sole_contacts.field: expected ..."
};

/// Mechanical stops of the robot's joints: the stiffness of MuJoCo's joint-limit constraint
/// (the MJCF's solreflimit) on every joint of the robot config. The public G1 MJCF sets none, so
/// MuJoCo's default applies: solref (0.02 s, 1), a stop soft enough that a foot landing in a stumble
/// drives an ankle 0.1 rad beyond its range (measured: the right ankle pitch at -0.978 rad against
/// -0.873, at 7 rad/s; docs/controller.md "Joint stops"), where a metal stop gives milliradians. Off
/// (timeconst 0) keeps the MJCF's. MuJoCo 2.2 semantics: solref = (time constant [s], damping ratio);
/// MuJoCo's stability rule asks for a time constant of at least 2 physics timesteps.
struct JointStopOptions {
  double timeconst = 0.0;  ///< solreflimit[0] [s]; 0 = the MJCF's (MuJoCo's default 0.02 s); else in [2 timestep, 1]
  double dampratio = 1.0;  ///< solreflimit[1], in (0, 10]
  bool enabled() const noexcept { return timeconst > 0; }
  std::string validate(double timestep) const;  ///< empty if valid, else "joint_stops.field: expected ..."
};

/// Options of the MuJoCo backend.
struct MujocoBackendOptions {
  double timestep = 0.001;          ///< physics step [s], ≤ 0.001 (≥ 1 kHz)
  double cycle_period = 0.002;      ///< HAL cycle [s] (500 Hz); a multiple of timestep
  GantryOptions gantry;
  std::vector<double> encoder_offsets;  ///< (n or empty) hidden zero offsets [rad]: reported = true + offset
  SoleContactOptions sole_contacts;     ///< calibration-bench floor (default off)
  JointStopOptions joint_stops;         ///< stiffer joint stops than the MJCF's (default off)
  /// The sliding friction coefficient of every geom, feet and floor alike (MuJoCo takes the larger of a
  /// contact's two, so this is the foot-floor friction), as the training's domain randomisation sets it
  /// (training/pmg_train/g1_env.py `friction`, drawn in [0.4, 1.25]). 0 = the MJCF's (1.0 for the G1);
  /// else in [0.1, 2]. Torsional and rolling friction are left as they are.
  double sliding_friction = 0.0;
  /// Model errors (pmg_sil --reality, hal/reality.hpp): MJCF body name -> factor on its mass and
  /// rotational inertia, in [0.5, 2]. An unknown body is a ConfigError.
  std::map<std::string, double> body_mass_scale;
  /// No contacts at all (mjDSBL_CONTACT): for offline fits of a robot hanging in the gantry, whose
  /// feet never touch the floor, at ~15x the speed (pmg_calib_joints). Never for a robot on the ground.
  bool disable_contacts = false;
  std::string validate() const;     ///< empty if valid, else "field: expected ..."
};

class MujocoBackend final : public HalBackend {
 public:
  /// Loads the robot's MJCF (adapted for MuJoCo 2.2), maps the config's joints onto the model and
  /// puts the robot in its default pose (hanging in the gantry, or standing on the ground).
  /// @throws ConfigError / std::runtime_error naming the joint or option on any mismatch.
  MujocoBackend(const RobotConfig& robot, MujocoBackendOptions options);

  const char* name() const noexcept override { return "mujoco"; }
  double cyclePeriod() const noexcept override { return options_.cycle_period; }
  BackendStatus exchange(const LowCommand& command, LowState& state) noexcept override;

  /// Resets to the default pose at time 0.
  void reset() noexcept;
  /// Applies a world-frame force [N] at the centre of mass of @p body for the next @p duration [s].
  void push(int body, const Eigen::Vector3d& f_W, double duration) noexcept;
  const mjModel* model() const noexcept { return model_.get(); }
  mjData* data() noexcept { return data_.get(); }
  int pelvisBody() const noexcept { return pelvis_body_; }
  /// Latest torques applied by the motor model (n) [N·m].
  const Eigen::VectorXd& appliedTorque() const noexcept { return tau_; }
  /// Replaces joint @p i's identified actuator model (std::nullopt: the ideal motor of the MJCF) and
  /// resets its state. Armature: the block's or the MJCF's; MuJoCo's frictionloss is kept unless the
  /// block names dry friction (fc, fs or kl), which then replaces it. Setup/offline only (allocates
  /// nothing, but is not meant to run between exchanges of a live robot).
  /// @throws std::invalid_argument (index), ConfigError / std::invalid_argument (invalid block).
  void setActuatorBlock(int i, const std::optional<calib::ActuatorBlock>& block);
  /// Whether joint @p i runs an identified actuator model.
  bool hasActuatorModel(int i) const noexcept { return actuator_[static_cast<std::size_t>(i)].has_value(); }

 private:
  void applyGantry() noexcept;
  void readState(LowState& state) const noexcept;

  RobotConfig robot_;
  MujocoBackendOptions options_;
  MjModelPtr model_;
  MjDataPtr data_;
  int substeps_ = 2;
  int pelvis_body_ = -1;
  std::vector<int> qpos_adr_, dof_adr_;
  int sensor_quat_ = -1, sensor_gyro_ = -1, sensor_acc_ = -1;
  Eigen::VectorXd tau_, torque_limit_, offsets_;
  std::vector<std::optional<calib::ActuatorBlock>> actuator_;  // per joint, from the robot config
  std::vector<calib::ActuatorState> actuator_state_;           // per joint (fixed-size delay lines)
  bool any_actuator_ = false;
  Eigen::VectorXd nominal_armature_, nominal_frictionloss_;    // per joint, as loaded from the MJCF
  Eigen::Vector3d anchor_{0, 0, 0};
  Eigen::Vector3d push_force_{0, 0, 0};
  int push_body_ = -1;
  double push_until_ = -1.0;
  std::uint64_t cycles_ = 0;
  std::uint32_t faults_ = 0;
};

}  // namespace pmg
