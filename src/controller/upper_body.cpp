#include "pmg/controller/upper_body.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "pmg/common/config_error.hpp"

namespace pmg {

std::string UpperBodyConfig::validate() const {
  const auto bad = [](const char* field, double v, const char* range) {
    return fmt::format("upper_body.{} = {}: expected {}", field, v, range);
  };
  if (!(gravity_scale >= 0.0 && gravity_scale <= 1.5)) return bad("gravity_scale", gravity_scale, "0..1.5");
  if (!(damping >= 0.0 && damping <= 50.0)) return bad("damping", damping, "0..50 N*m*s/rad");
  if (!(max_torque > 0.0 && max_torque <= 300.0)) return bad("max_torque", max_torque, "(0, 300] N*m");
  if (!(ramp_s >= 0.0 && ramp_s <= 10.0)) return bad("ramp_s", ramp_s, "0..10 s");
  if (enabled && joints.empty()) return "upper_body.joints: empty: expected at least one joint when enabled";
  return "";
}

UpperBodyCompensation::UpperBodyCompensation(const RobotConfig& robot, const UpperBodyConfig& config,
                                             const std::vector<std::string>& leg_joints)
    : config_(config) {
  const std::set<std::string> legs(leg_joints.begin(), leg_joints.end());
  std::set<int> seen;
  for (std::size_t i = 0; i < config_.joints.size(); ++i) {
    const std::string& name = config_.joints[i];
    const std::string key = fmt::format("upper_body.joints[{}] = '{}'", i, name);
    const int j = robot.jointIndex(name);
    if (j < 0) throw ConfigError(key + ": not a joint of " + robot.source_file);
    if (legs.count(name)) throw ConfigError(key + ": a joint the actor commands (its torque is the actor's contract)");
    if (!seen.insert(j).second) throw ConfigError(key + ": listed twice");
    joint_index_.push_back(j);
  }
  try {
    Mujoco22Options mo;
    mo.imu_site = robot.imu_site;
    model_ = loadMujocoModel(robot.mjcf_path, mo);
  } catch (const std::runtime_error& e) {
    throw ConfigError(std::string("upper_body: ") + e.what());
  }
  const mjModel* m = model_.get();
  data_.reset(mj_makeData(m));
  if (!data_) throw ConfigError("upper_body: " + robot.mjcf_path + ": mj_makeData failed");
  // The floating base: the model's first free joint.
  int free_joint = -1;
  for (int k = 0; k < m->njnt && free_joint < 0; ++k)
    if (m->jnt_type[k] == mjJNT_FREE) free_joint = k;
  if (free_joint < 0) throw ConfigError("upper_body: " + robot.mjcf_path + ": no free joint (floating base)");
  base_qpos_ = m->jnt_qposadr[free_joint];
  const int base_body = m->jnt_bodyid[free_joint];
  const int site = mj_name2id(m, mjOBJ_SITE, robot.imu_site.c_str());
  if (site < 0 || m->site_bodyid[site] != base_body)
    throw ConfigError("upper_body: " + robot.mjcf_path + ": IMU site '" + robot.imu_site +
                      "' is not on the floating base body (the IMU gives the base orientation)");
  const mjtNum* qs = m->site_quat + 4 * site;  // base <- site
  q_site_inv_ = {qs[0], -qs[1], -qs[2], -qs[3]};
  std::vector<int> dof_adr_of_joint;  // per robot joint
  for (const JointConfig& jc : robot.joints) {
    const int id = mj_name2id(m, mjOBJ_JOINT, jc.name.c_str());
    if (id < 0) throw ConfigError("upper_body: " + robot.mjcf_path + ": no joint '" + jc.name + "'");
    qpos_adr_.push_back(m->jnt_qposadr[id]);
    dof_adr_of_joint.push_back(m->jnt_dofadr[id]);
  }
  for (const int j : joint_index_) {
    const auto k = static_cast<std::size_t>(j);
    dof_adr_.push_back(dof_adr_of_joint[k]);
    limit_.push_back(std::min(config_.max_torque, robot.joints[k].torque_limit));
  }
  // Zero velocity, set once: nothing later writes qvel or the velocity terms mj_rne reads (cvel,
  // cdof_dot; mj_comVel is never called), so its bias forces are the gravity forces alone.
  mju_zero(data_->qvel, m->nv);
  mju_zero(data_->cvel, 6 * m->nbody);
  mju_zero(data_->cdof_dot, 6 * m->nv);
  gravity_.assign(joint_index_.size(), 0.0);
  tau_ff_.assign(joint_index_.size(), 0.0);
  rne_.assign(static_cast<std::size_t>(m->nv), 0.0);
}

UpperBodyCompensation::~UpperBodyCompensation() = default;

const std::vector<double>& UpperBodyCompensation::gravity(const LowState& state) noexcept {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  // Base pose: world <- base = (world <- IMU) * (IMU <- base); the position does not matter.
  double* qb = d->qpos + base_qpos_;
  qb[0] = qb[1] = 0.0;
  qb[2] = 1.0;
  mjtNum q_wb[4] = {1, 0, 0, 0};
  if (state.imu.valid) {
    const mjtNum q_wi[4] = {state.imu.quat_wxyz[0], state.imu.quat_wxyz[1], state.imu.quat_wxyz[2], state.imu.quat_wxyz[3]};
    mju_mulQuat(q_wb, q_wi, q_site_inv_.data());  // (world <- IMU) (IMU <- base)
    mju_normalize4(q_wb);
    if (!std::isfinite(q_wb[0] + q_wb[1] + q_wb[2] + q_wb[3])) q_wb[0] = 1, q_wb[1] = q_wb[2] = q_wb[3] = 0;
  }
  for (int a = 0; a < 4; ++a) qb[3 + a] = q_wb[a];
  const int n = std::min(state.num_motors, static_cast<int>(qpos_adr_.size()));
  for (int i = 0; i < n; ++i) {
    const double q = state.motors[static_cast<std::size_t>(i)].q;
    if (std::isfinite(q)) d->qpos[qpos_adr_[static_cast<std::size_t>(i)]] = q;
  }
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_rne(m, d, 0, rne_.data());  // zero velocity (see the constructor), no acceleration term: the gravity forces
  for (std::size_t k = 0; k < gravity_.size(); ++k) gravity_[k] = rne_[static_cast<std::size_t>(dof_adr_[k])];
  return gravity_;
}

void UpperBodyCompensation::apply(const LowState& state, LowCommand& command, double dt) noexcept {
  gravity(state);
  if (std::isfinite(dt) && dt > 0.0) elapsed_s_ = std::min(elapsed_s_ + dt, config_.ramp_s);
  const double fade = config_.ramp_s > 0.0 ? std::min(1.0, elapsed_s_ / config_.ramp_s) : 1.0;
  for (std::size_t k = 0; k < joint_index_.size(); ++k) {
    const auto j = static_cast<std::size_t>(joint_index_[k]);
    double qd = state.motors[j].qd;
    if (!std::isfinite(qd)) qd = 0.0;
    double tau = fade * (config_.gravity_scale * gravity_[k] - config_.damping * qd);
    if (!std::isfinite(tau)) tau = 0.0;
    tau = std::clamp(tau, -limit_[k], limit_[k]);
    tau_ff_[k] = tau;
    if (static_cast<int>(j) < command.num_motors) command.motors[j].tau_ff = tau;
  }
}

}  // namespace pmg
