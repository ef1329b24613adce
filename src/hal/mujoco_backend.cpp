#include "pmg/hal/mujoco_backend.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>

namespace pmg {

std::string GantryOptions::validate() const {
  if (!(anchor_height > 0.2 && anchor_height < 3.0)) return "gantry.anchor_height: expected in (0.2, 3) m";
  if (!(stiffness >= 0 && damping >= 0 && rot_stiffness >= 0 && rot_damping >= 0))
    return "gantry.stiffness/damping/rot_stiffness/rot_damping: expected >= 0";
  return {};
}

std::string SoleContactOptions::validate(double timestep) const {
  if (!enabled) return {};
  if (!(timeconst >= 2 * timestep && timeconst <= 1.0))
    return "sole_contacts.timeconst: expected in [2 timestep, 1] s";
  if (!(dampratio > 0 && dampratio <= 10)) return "sole_contacts.dampratio: expected in (0, 10]";
  if (!(dmin > 0 && dmin <= dmax && dmax < 1)) return "sole_contacts.dmin/dmax: expected 0 < dmin <= dmax < 1";
  if (!(width > 0 && width <= 1)) return "sole_contacts.width: expected in (0, 1] m";
  return {};
}

std::string JointStopOptions::validate(double timestep) const {
  if (timeconst == 0.0) return {};  // the MJCF's stops
  if (!(timeconst >= 2 * timestep - 1e-12 && timeconst <= 1.0))
    return "joint_stops.timeconst: expected 0 (the MJCF's) or in [2 timestep, 1] s";
  if (!(dampratio > 0 && dampratio <= 10)) return "joint_stops.dampratio: expected in (0, 10]";
  return {};
}

std::string MujocoBackendOptions::validate() const {
  if (!(timestep > 0 && timestep <= 0.001)) return "mujoco.timestep: expected in (0, 0.001] s (>= 1 kHz physics)";
  const double ratio = cycle_period / timestep;
  if (!(cycle_period > 0) || std::fabs(ratio - std::round(ratio)) > 1e-9 || ratio < 1)
    return "mujoco.cycle_period: expected a positive multiple of timestep";
  for (double o : encoder_offsets)
    if (!std::isfinite(o) || std::fabs(o) > 0.5) return "mujoco.encoder_offsets: expected finite, |offset| <= 0.5 rad";
  if (std::string e = sole_contacts.validate(timestep); !e.empty()) return "mujoco." + e;
  if (std::string e = joint_stops.validate(timestep); !e.empty()) return "mujoco." + e;
  if (!(sliding_friction == 0.0 || (sliding_friction >= 0.1 && sliding_friction <= 2.0)))
    return "mujoco.sliding_friction: expected 0 (the MJCF's) or in [0.1, 2]";
  for (const auto& [body, scale] : body_mass_scale)
    if (!(std::isfinite(scale) && scale >= 0.5 && scale <= 2.0))
      return "links." + body + ".mass_scale: expected 0.5..2";
  return gantry.enabled ? gantry.validate() : std::string();
}

MujocoBackend::MujocoBackend(const RobotConfig& robot, MujocoBackendOptions options)
    : robot_(robot), options_(std::move(options)) {
  if (const std::string e = options_.validate(); !e.empty()) throw ConfigError(e);
  Mujoco22Options mo;
  mo.timestep = options_.timestep;
  mo.imu_site = robot_.imu_site;
  model_ = loadMujocoModel(robot_.mjcf_path, mo);
  data_.reset(mj_makeData(model_.get()));
  substeps_ = static_cast<int>(std::lround(options_.cycle_period / options_.timestep));
  pelvis_body_ = mj_name2id(model_.get(), mjOBJ_BODY, robot_.base_link.c_str());
  if (pelvis_body_ < 0) throw ConfigError(robot_.mjcf_path + ": no body '" + robot_.base_link + "' (robot.base_link)");
  const auto n = robot_.numJoints();
  for (const auto& j : robot_.joints) {
    const int id = mj_name2id(model_.get(), mjOBJ_JOINT, j.name.c_str());
    if (id < 0) throw ConfigError(robot_.mjcf_path + ": joint '" + j.name + "' of " + robot_.source_file + " not in the MJCF");
    if (model_->jnt_type[id] != mjJNT_HINGE)
      throw ConfigError(robot_.mjcf_path + ": joint '" + j.name + "' is not a hinge");
    if (options_.joint_stops.enabled()) {
      model_->jnt_solref[mjNREF * id] = options_.joint_stops.timeconst;
      model_->jnt_solref[mjNREF * id + 1] = options_.joint_stops.dampratio;
    }
    const int act = static_cast<int>(qpos_adr_.size());
    if (act >= model_->nu || model_->actuator_trnid[2 * act] != id)
      throw ConfigError(robot_.mjcf_path + ": actuator " + std::to_string(act) + " does not drive joint '" + j.name +
                        "' (expected one <motor> per joint in the robot config's order)");
    qpos_adr_.push_back(model_->jnt_qposadr[id]);
    dof_adr_.push_back(model_->jnt_dofadr[id]);
  }
  const auto sensor = [&](const std::string& sname) {
    const int id = mj_name2id(model_.get(), mjOBJ_SENSOR, sname.c_str());
    if (id < 0) throw ConfigError(robot_.mjcf_path + ": sensor '" + sname + "' not found");
    return model_->sensor_adr[id];
  };
  sensor_quat_ = sensor(robot_.imu_site + "-orientation");
  // Unitree names its pelvis IMU sensors "imu-pelvis-*".
  const std::string prefix = robot_.imu_site == "imu_in_torso" ? "imu-torso-" : "imu-pelvis-";
  sensor_gyro_ = sensor(prefix + "angular-velocity");
  sensor_acc_ = sensor(prefix + "linear-acceleration");
  tau_.setZero(static_cast<Eigen::Index>(n));
  torque_limit_ = robot_.torqueLimits();
  offsets_.setZero(static_cast<Eigen::Index>(n));
  if (!options_.encoder_offsets.empty()) {
    if (options_.encoder_offsets.size() != n)
      throw ConfigError("mujoco.encoder_offsets: has " + std::to_string(options_.encoder_offsets.size()) +
                        " entries, expected " + std::to_string(n) + " (one per joint)");
    for (std::size_t i = 0; i < n; ++i) offsets_[static_cast<Eigen::Index>(i)] = options_.encoder_offsets[i];
  }
  if (options_.sole_contacts.enabled) {
    const SoleContactOptions& sc = options_.sole_contacts;
    int changed = 0;
    for (const std::string& foot : {robot_.left_foot_link, robot_.right_foot_link}) {
      const int b = mj_name2id(model_.get(), mjOBJ_BODY, foot.c_str());
      if (b < 0) throw ConfigError(robot_.mjcf_path + ": no foot body '" + foot + "' (robot.left/right_foot_link)");
      for (int g = 0; g < model_->ngeom; ++g) {
        if (model_->geom_bodyid[g] != b || (model_->geom_contype[g] == 0 && model_->geom_conaffinity[g] == 0)) continue;
        model_->geom_solref[mjNREF * g] = sc.timeconst;
        model_->geom_solref[mjNREF * g + 1] = sc.dampratio;
        model_->geom_solimp[mjNIMP * g] = sc.dmin;
        model_->geom_solimp[mjNIMP * g + 1] = sc.dmax;
        model_->geom_solimp[mjNIMP * g + 2] = sc.width;
        model_->geom_solmix[g] = 1e3;
        ++changed;
      }
    }
    if (changed == 0) throw ConfigError(robot_.mjcf_path + ": mujoco.sole_contacts: the foot bodies have no colliding geom");
  }
  if (options_.sliding_friction > 0.0)  // every geom: a contact's friction is the larger of its two geoms'
    for (int g = 0; g < model_->ngeom; ++g) model_->geom_friction[3 * g] = options_.sliding_friction;
  // Model errors: body mass and rotational inertia scaled (hal/reality.hpp).
  if (!options_.body_mass_scale.empty()) {
    for (const auto& [body, scale] : options_.body_mass_scale) {
      const int b = mj_name2id(model_.get(), mjOBJ_BODY, body.c_str());
      if (b < 0) throw ConfigError(robot_.mjcf_path + ": links." + body + ": no such body in the MJCF");
      model_->body_mass[b] *= scale;
      for (int k = 0; k < 3; ++k) model_->body_inertia[3 * b + k] *= scale;
    }
    mj_setConst(model_.get(), data_.get());  // subtree masses and other derived constants
  }
  // Identified actuator models (robot config `actuator:` blocks).
  actuator_.resize(n);
  actuator_state_.resize(n);
  nominal_armature_.resize(static_cast<Eigen::Index>(n));
  nominal_frictionloss_.resize(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    nominal_armature_[static_cast<Eigen::Index>(i)] = model_->dof_armature[dof_adr_[i]];
    nominal_frictionloss_[static_cast<Eigen::Index>(i)] = model_->dof_frictionloss[dof_adr_[i]];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const JointConfig& j = robot_.joints[i];
    if (j.actuator_yaml.empty()) continue;
    calib::ActuatorBlock block;
    try {
      block = calib::parse_actuator_block(YAML::Load(j.actuator_yaml), j.actuator_source);
    } catch (const std::exception& e) {
      throw ConfigError(std::string(e.what()) + " (joint " + j.name + ")");
    }
    if (block.params.backlash_gap_rad > 0)
      throw ConfigError(j.actuator_source + ".backlash_gap_rad: backlash needs a rotor body; the G1 SIL does not "
                                            "model it (expected 0 for joint " + j.name + ")");
    setActuatorBlock(static_cast<int>(i), block);
  }
  if (options_.disable_contacts) model_->opt.disableflags |= mjDSBL_CONTACT;
  reset();
}

void MujocoBackend::setActuatorBlock(int i, const std::optional<calib::ActuatorBlock>& block) {
  if (i < 0 || i >= static_cast<int>(dof_adr_.size()))
    throw std::invalid_argument("MujocoBackend::setActuatorBlock: joint index " + std::to_string(i) + " out of range");
  const auto k = static_cast<std::size_t>(i);
  const int v = dof_adr_[k];
  model_->dof_armature[v] = nominal_armature_[i];
  model_->dof_frictionloss[v] = nominal_frictionloss_[i];
  actuator_[k].reset();
  actuator_state_[k].reset();
  if (block) {
    block->params.validate();
    if (block->params.backlash_gap_rad > 0)
      throw ConfigError("joint " + robot_.joints[k].name + ": backlash_gap_rad needs a rotor body (expected 0 in the G1 SIL)");
    calib::ActuatorBlock b = *block;
    b.params.torque_limit_Nm = std::min(b.params.torque_limit_Nm, robot_.joints[k].torque_limit);
    if (b.armature_kgm2) model_->dof_armature[v] = *b.armature_kgm2;
    // A block that names dry friction replaces MuJoCo's (the actuator model has true stiction);
    // one that does not keeps the model's own frictionloss, so that a block changes only what it names.
    if (b.params.fc_Nm > 0.0 || b.params.fs_Nm > 0.0 || b.params.kl > 0.0) model_->dof_frictionloss[v] = 0.0;
    actuator_[k] = b;
  }
  any_actuator_ = std::any_of(actuator_.begin(), actuator_.end(), [](const auto& a) { return a.has_value(); });
}

void MujocoBackend::reset() noexcept {
  mj_resetData(model_.get(), data_.get());
  const double z = options_.gantry.enabled ? options_.gantry.anchor_height : robot_.standing_base_height + 0.015;
  data_->qpos[0] = 0.0;
  data_->qpos[1] = 0.0;
  data_->qpos[2] = z;
  data_->qpos[3] = 1.0;
  data_->qpos[4] = data_->qpos[5] = data_->qpos[6] = 0.0;
  for (std::size_t i = 0; i < qpos_adr_.size(); ++i) data_->qpos[qpos_adr_[i]] = robot_.joints[i].default_position;
  anchor_ = Eigen::Vector3d(0.0, 0.0, z);
  mj_forward(model_.get(), data_.get());
  tau_.setZero();
  for (auto& st : actuator_state_) st.reset();
  push_until_ = -1.0;
  cycles_ = 0;
}

void MujocoBackend::push(int body, const Eigen::Vector3d& f_W, double duration) noexcept {
  push_body_ = body;
  push_force_ = f_W;
  push_until_ = data_->time + duration;
}

void MujocoBackend::applyGantry() noexcept {
  mju_zero(data_->xfrc_applied, 6 * model_->nbody);
  const GantryOptions& g = options_.gantry;
  if (g.enabled) {
    const double* p = data_->xpos + 3 * pelvis_body_;
    const double* v = data_->qvel;  // free joint: linear velocity (world) then angular (body frame)
    double* f = data_->xfrc_applied + 6 * pelvis_body_;
    for (int a = 0; a < 3; ++a) f[a] = g.stiffness * (anchor_[a] - p[a]) - g.damping * v[a];
    // Orientation: torque = −k · axis·angle(R_WB) − d · ω_W.
    const double* q = data_->xquat + 4 * pelvis_body_;
    Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    const Eigen::AngleAxisd aa(quat.normalized());
    double angle = aa.angle();
    if (angle > M_PI) angle -= 2 * M_PI;
    const Eigen::Vector3d rotvec = aa.axis() * angle;
    const Eigen::Vector3d omega_B(v[3], v[4], v[5]);
    const Eigen::Vector3d omega_W = quat.normalized() * omega_B;
    for (int a = 0; a < 3; ++a) f[3 + a] = -g.rot_stiffness * rotvec[a] - g.rot_damping * omega_W[a];
  }
  if (push_body_ >= 0 && data_->time < push_until_) {
    double* f = data_->xfrc_applied + 6 * push_body_;
    for (int a = 0; a < 3; ++a) f[a] += push_force_[a];
  }
}

BackendStatus MujocoBackend::exchange(const LowCommand& command, LowState& state) noexcept {
  const int n = static_cast<int>(qpos_adr_.size());
  const int nc = std::min(n, command.num_motors);
  for (int s = 0; s < substeps_; ++s) {
    applyGantry();
    // Split step: position/velocity stages first, so the actuator model's stiction sees this
    // step's inertia and bias forces (equivalent to mj_step with the Euler integrator).
    mj_step1(model_.get(), data_.get());
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const int v = dof_adr_[k];
      const double q_true = data_->qpos[qpos_adr_[k]];
      const double qd = data_->qvel[v];
      MotorCommand c{};
      const bool enabled = i < nc;
      if (enabled) c = command.motors[k];
      double tau = 0.0;
      if (actuator_[k]) {
        const calib::ActuatorBlock& b = *actuator_[k];
        calib::JointSample js;
        js.q_rad = q_true + offsets_[i];  // hidden zero offsets come on top of the model's own
        js.dq_rad_per_s = qd;
        js.dt_s = model_->opt.timestep;
        js.inertia_kgm2 = data_->qM[model_->dof_Madr[v]];
        js.tau_other_Nm = -data_->qfrc_bias[v] + data_->qfrc_passive[v];
        const calib::MotorCommand mc{c.q, c.qd, c.kp * b.kp_scale, c.kd * b.kd_scale, c.tau_ff,
                                     enabled && std::isfinite(c.q + c.qd + c.kp + c.kd + c.tau_ff)};
        const calib::ActuatorOutput out = calib::ActuatorModel::step(b.params, actuator_state_[k], mc, js);
        data_->qfrc_applied[v] = out.tau_applied_Nm;
        data_->ctrl[i] = 0.0;
        tau = out.tau_motor_Nm;
      } else if (enabled) {
        // The driver sees its own (offset) encoder reading.
        tau = c.kp * (c.q - (q_true + offsets_[i])) + c.kd * (c.qd - qd) + c.tau_ff;
        if (!std::isfinite(tau)) tau = 0.0;
        tau = std::clamp(tau, -torque_limit_[i], torque_limit_[i]);
        data_->ctrl[i] = tau;  // MJCF <motor> gear 1, in joint order
      } else {
        data_->ctrl[i] = 0.0;
      }
      tau_[i] = tau;
    }
    mj_step2(model_.get(), data_.get());
  }
  ++cycles_;
  bool diverged = false;
  for (int i = 0; i < model_->nq; ++i)
    if (!std::isfinite(data_->qpos[i])) diverged = true;
  if (data_->warning[mjWARN_BADQACC].number > 0) diverged = true;
  if (diverged) ++faults_;
  readState(state);
  return diverged ? BackendStatus::kFault : BackendStatus::kOk;
}

void MujocoBackend::readState(LowState& state) const noexcept {
  const int n = static_cast<int>(qpos_adr_.size());
  state.sequence = cycles_;
  state.time = data_->time;
  state.num_motors = n;
  for (int i = 0; i < n; ++i) {
    MotorState& m = state.motors[static_cast<std::size_t>(i)];
    const auto k = static_cast<std::size_t>(i);
    m.q = data_->qpos[qpos_adr_[k]] + offsets_[i] + (actuator_[k] ? actuator_[k]->params.offset_rad : 0.0);
    m.qd = data_->qvel[dof_adr_[static_cast<std::size_t>(i)]];
    m.tau = tau_[i];
    m.valid = true;
  }
  const mjtNum* sd = data_->sensordata;
  for (int a = 0; a < 4; ++a) state.imu.quat_wxyz[static_cast<std::size_t>(a)] = sd[sensor_quat_ + a];
  for (int a = 0; a < 3; ++a) {
    state.imu.gyro[static_cast<std::size_t>(a)] = sd[sensor_gyro_ + a];
    state.imu.acc[static_cast<std::size_t>(a)] = sd[sensor_acc_ + a];
    state.base_position[static_cast<std::size_t>(a)] = data_->qpos[a];
    state.base_linear_velocity[static_cast<std::size_t>(a)] = data_->qvel[a];
  }
  for (int a = 0; a < 4; ++a) state.base_quat_wxyz[static_cast<std::size_t>(a)] = data_->qpos[3 + a];
  state.imu.valid = true;
  state.base_truth_valid = true;
  state.backend_faults = faults_;
}

}  // namespace pmg
