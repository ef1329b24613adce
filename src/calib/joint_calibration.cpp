// Single-joint response calibration on the whole robot (include/pmg/calib/joint_calibration.hpp).
#include "pmg/calib/joint_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include "pmg/calib/dynamics_calibration.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/hal/modes.hpp"

namespace pmg::calib {

void JointExcitation::validate() const {
  auto check = [](bool ok, const char* field, double v, const char* range) {
    if (!ok) throw std::invalid_argument(fmt::format("JointExcitation.{} = {}: expected {}", field, v, range));
  };
  check(std::isfinite(amplitude_rad) && amplitude_rad > 0 && amplitude_rad <= 0.5, "amplitude_rad", amplitude_rad, "(0, 0.5] rad");
  check(std::isfinite(ramp_s) && ramp_s >= 0.01 && ramp_s <= 1.0, "ramp_s", ramp_s, "[0.01, 1] s");
  check(std::isfinite(hold_s) && hold_s >= 0.1 && hold_s <= 5.0, "hold_s", hold_s, "[0.1, 5] s");
  check(std::isfinite(chirp_s) && chirp_s >= 0.5 && chirp_s <= 20.0, "chirp_s", chirp_s, "[0.5, 20] s");
}

namespace {

// Cosine ramps between levels (fractions of the amplitude), each followed by a hold.
std::vector<double> staircase(const std::vector<double>& levels, double a, double ramp, double hold, double dt) {
  std::vector<double> out;
  double from = 0.0;
  const int nr = std::max(1, static_cast<int>(std::lround(ramp / dt)));
  const int nh = std::max(1, static_cast<int>(std::lround(hold / dt)));
  for (double l : levels) {
    const double to = l * a;
    for (int k = 1; k <= nr; ++k) out.push_back(from + (to - from) * (0.5 - 0.5 * std::cos(M_PI * k / nr)));
    for (int k = 0; k < nh; ++k) out.push_back(to);
    from = to;
  }
  return out;
}

// Sine sweep f0 -> f1 [Hz] of amplitude a under a sin^2 taper (0.25 s each end).
std::vector<double> chirp(double a, double f0, double f1, double seconds, double dt) {
  const int n = static_cast<int>(std::lround(seconds / dt));
  std::vector<double> out(static_cast<std::size_t>(n));
  const double taper = std::min(0.25, 0.25 * seconds);
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    const double phase = 2.0 * M_PI * (f0 * t + 0.5 * (f1 - f0) / seconds * t * t);
    double w = 1.0;
    if (t < taper) w = std::pow(std::sin(0.5 * M_PI * t / taper), 2);
    if (seconds - t < taper) w = std::pow(std::sin(0.5 * M_PI * (seconds - t) / taper), 2);
    out[static_cast<std::size_t>(k)] = a * w * std::sin(phase);
  }
  return out;
}

}  // namespace

std::vector<std::pair<std::string, std::vector<double>>> excitationSignals(const JointExcitation& ex, double dt) {
  ex.validate();
  if (!(dt > 0 && dt <= 0.01)) throw std::invalid_argument(fmt::format("excitationSignals: dt = {}: expected (0, 0.01] s", dt));
  const double a = ex.amplitude_rad;
  std::vector<double> steps = staircase({1.0, 0.0, -1.0, 0.0, 0.5, -0.5, 0.25, -0.25, 1.0, -1.0, 0.0}, a, ex.ramp_s, ex.hold_s, dt);
  std::vector<double> sweep = chirp(0.6 * a, 0.5, 4.0, ex.chirp_s, dt);
  // Held-out: other step sizes and a slower, larger sine burst (not in the training logs).
  std::vector<double> mixed = staircase({0.7, -0.3, 0.9, -0.8, 0.0}, a, 2.0 * ex.ramp_s, ex.hold_s, dt);
  const std::vector<double> burst = chirp(0.5 * a, 1.5, 1.5, 1.5, dt);
  mixed.insert(mixed.end(), burst.begin(), burst.end());
  const std::vector<double> tail = staircase({0.0}, a, ex.ramp_s, ex.hold_s, dt);
  mixed.insert(mixed.end(), tail.begin(), tail.end());
  return {{"steps", steps}, {"chirp", sweep}, {"mixed", mixed}};
}

JointCapture captureJoint(HalBackend& backend, const RobotConfig& robot, int index, const JointExcitation& ex,
                          const Eigen::VectorXd& hold_targets, const std::function<void(const std::string&)>& log) {
  const int n = static_cast<int>(robot.numJoints());
  if (index < 0 || index >= n) throw std::invalid_argument(fmt::format("captureJoint: joint index {} not in [0, {})", index, n));
  if (hold_targets.size() != n)
    throw std::invalid_argument(fmt::format("captureJoint: hold_targets has {} entries, expected {}", hold_targets.size(), n));
  const JointConfig& jc = robot.joints[static_cast<std::size_t>(index)];
  const double dt = backend.cyclePeriod();
  const auto signals = excitationSignals(ex, dt);
  const Eigen::VectorXd kp = robot.kp(), kd = robot.kd();
  LowCommand cmd;
  cmd.num_motors = n;
  LowState st;
  JointCapture out;
  out.joint = jc.name;
  out.index = index;
  out.held_q = Eigen::VectorXd::Zero(n);
  long samples = 0;
  double t0 = -1.0;
  auto send = [&](double offset) {
    for (int i = 0; i < n; ++i) {
      pmg::MotorCommand& m = cmd.motors[static_cast<std::size_t>(i)];
      m.q = hold_targets(i) + (i == index ? offset : 0.0);
      m.qd = 0.0;
      m.kp = kp(i);
      m.kd = kd(i);
      m.tau_ff = 0.0;
    }
    ++cmd.sequence;
    if (backend.exchange(cmd, st) == BackendStatus::kFault)
      throw std::runtime_error(fmt::format("captureJoint({}): backend '{}' fault at t = {:.3f} s", jc.name, backend.name(), st.time));
    if (st.mode == Mode::kDamping)
      throw std::runtime_error(fmt::format("captureJoint({}): the HAL supervisor latched damping at t = {:.3f} s: {}", jc.name,
                                           st.time, toString(st.fault)));
    if (t0 < 0) t0 = st.time;
    for (int i = 0; i < n; ++i) out.held_q(i) += st.motors[static_cast<std::size_t>(i)].q;
    ++samples;
  };
  // Settle at the hold targets (the stack was engaged at the default pose).
  for (int k = 0; k < static_cast<int>(std::lround(0.5 / dt)); ++k) send(0.0);
  for (const auto& [name, sig] : signals) {
    BenchLog lg;
    lg.name = jc.name + ":" + name;
    std::vector<double> t, q, dq, tau;
    for (double s : sig) {
      send(s);
      // The previous row's command is the one the driver holds from its reading on: this one.
      if (!t.empty()) {
        lg.q_cmd.push_back(cmd.motors[static_cast<std::size_t>(index)].q);
        lg.kp.push_back(cmd.motors[static_cast<std::size_t>(index)].kp);
        lg.kd.push_back(cmd.motors[static_cast<std::size_t>(index)].kd);
      }
      const auto& m = st.motors[static_cast<std::size_t>(index)];
      t.push_back(st.time);
      q.push_back(m.q);
      dq.push_back(m.qd);
      tau.push_back(m.tau);
    }
    t.pop_back();
    q.pop_back();
    dq.pop_back();
    tau.pop_back();
    lg.t = std::move(t);
    lg.q = std::move(q);
    lg.dq = std::move(dq);
    lg.tau = std::move(tau);
    lg.validate();
    (name == "mixed" ? out.heldout : out.train).push_back(std::move(lg));
    if (log) log(fmt::format("  {}: {} log, {:.2f} s", jc.name, name, sig.size() * dt));
  }
  out.held_q /= static_cast<double>(samples);
  out.duration_s = st.time - t0;
  return out;
}

CommandLatencyBackend::CommandLatencyBackend(HalBackend& inner, int cycles) : inner_(inner), cycles_(cycles) {
  if (cycles < 0 || cycles > 50) throw std::invalid_argument(fmt::format("CommandLatencyBackend: cycles = {}: expected 0..50", cycles));
}

BackendStatus CommandLatencyBackend::exchange(const LowCommand& command, LowState& state) noexcept {
  if (cycles_ == 0) return inner_.exchange(command, state);
  while (static_cast<int>(queue_.size()) < cycles_) queue_.push_back(command);
  queue_.push_back(command);
  const LowCommand due = queue_.front();
  queue_.erase(queue_.begin());
  return inner_.exchange(due, state);
}

int responseLagCycles(const JointCapture& robot, const JointCapture& sim, int max_cycles) {
  double best = std::numeric_limits<double>::infinity();
  int best_lag = 0;
  for (int lag = 0; lag <= max_cycles; ++lag) {
    double sum = 0.0;
    long n = 0;
    for (std::size_t l = 0; l < robot.train.size() && l < sim.train.size(); ++l) {
      const auto& a = robot.train[l].q;
      const auto& b = sim.train[l].q;
      const std::size_t len = std::min(a.size(), b.size());
      if (len <= static_cast<std::size_t>(lag)) continue;
      double ma = 0.0, mb = 0.0;
      const std::size_t m = len - static_cast<std::size_t>(lag);
      for (std::size_t k = 0; k < m; ++k) {
        ma += a[k + static_cast<std::size_t>(lag)];
        mb += b[k];
      }
      ma /= static_cast<double>(m);
      mb /= static_cast<double>(m);
      for (std::size_t k = 0; k < m; ++k) {
        const double e = (a[k + static_cast<std::size_t>(lag)] - ma) - (b[k] - mb);
        sum += e * e;
      }
      n += static_cast<long>(m);
    }
    const double rms = n > 0 ? std::sqrt(sum / static_cast<double>(n)) : std::numeric_limits<double>::infinity();
    if (rms < best) {
      best = rms;
      best_lag = lag;
    }
  }
  return best_lag;
}

double simulationResidual(const JointCapture& robot, const JointCapture& sim) {
  double sum = 0.0;
  long n = 0;
  auto add = [&](const std::vector<BenchLog>& a, const std::vector<BenchLog>& b) {
    for (std::size_t l = 0; l < a.size() && l < b.size(); ++l) {
      const std::size_t len = std::min(a[l].q.size(), b[l].q.size());
      double mean = 0.0;
      for (std::size_t k = 0; k < len; ++k) mean += a[l].q[k] - b[l].q[k];
      mean /= std::max<std::size_t>(len, 1);
      for (std::size_t k = 0; k < len; ++k) {
        const double e = a[l].q[k] - b[l].q[k] - mean;
        sum += e * e;
      }
      n += static_cast<long>(len);
    }
  };
  add(robot.train, sim.train);
  add(robot.heldout, sim.heldout);
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

JointRig rigForJoint(const RobotConfig& robot, int index, const Eigen::VectorXd& held_q) {
  const int n = static_cast<int>(robot.numJoints());
  if (index < 0 || index >= n) throw std::invalid_argument(fmt::format("rigForJoint: joint index {} not in [0, {})", index, n));
  if (held_q.size() != n) throw std::invalid_argument(fmt::format("rigForJoint: held_q has {} entries, expected {}", held_q.size(), n));
  const JointConfig& jc = robot.joints[static_cast<std::size_t>(index)];
  MjModelPtr model = loadMujocoModel(robot.mjcf_path, Mujoco22Options{});
  mjModel* m = model.get();
  mjData* d = mj_makeData(m);
  std::vector<int> adr(static_cast<std::size_t>(n));
  int jid = -1;
  for (int i = 0; i < n; ++i) {
    const std::string& name = robot.joints[static_cast<std::size_t>(i)].name;
    const int id = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (id < 0) {
      mj_deleteData(d);
      throw std::runtime_error(robot.mjcf_path + ": joint '" + name + "' not in the model");
    }
    adr[static_cast<std::size_t>(i)] = m->jnt_qposadr[id];
    if (i == index) jid = id;
  }
  const int dof = m->jnt_dofadr[jid];
  const int body = m->jnt_bodyid[jid];
  mj_resetData(m, d);
  d->qpos[2] = 1.0;  // base upright (gantry); position irrelevant
  for (int i = 0; i < n; ++i) d->qpos[adr[static_cast<std::size_t>(i)]] = held_q(i);
  const double q_hold = held_q(index);
  constexpr int kSamples = 13;
  Eigen::MatrixXd A(kSamples, 2);
  Eigen::VectorXd g(kSamples);
  for (int s = 0; s < kSamples; ++s) {
    const double q = q_hold - 1.2 + 2.4 * s / (kSamples - 1);
    d->qpos[adr[static_cast<std::size_t>(index)]] = q;
    mj_forward(m, d);
    A(s, 0) = std::sin(q);
    A(s, 1) = std::cos(q);
    g(s) = -d->qfrc_bias[dof];  // generalized gravity force on the joint (velocities are zero)
  }
  const Eigen::Vector2d ab = A.colPivHouseholderQr().solve(g);
  JointRig out;
  out.gravity_amplitude_Nm = std::hypot(ab(0), ab(1));
  out.q_down_rad = std::atan2(ab(1), -ab(0));  // g = -A sin(q - q_down)
  out.fit_residual_Nm = (A * ab - g).cwiseAbs().maxCoeff();
  d->qpos[adr[static_cast<std::size_t>(index)]] = q_hold;
  mj_forward(m, d);
  out.inertia_locked_kgm2 = d->qM[m->dof_Madr[dof]] - m->dof_armature[dof];
  // Apparent inertia with every other DOF free (base and joints): 1 / (M^-1)_jj.
  std::vector<mjtNum> e(static_cast<std::size_t>(m->nv), 0.0), x(static_cast<std::size_t>(m->nv), 0.0);
  e[static_cast<std::size_t>(dof)] = 1.0;
  mj_solveM(m, d, x.data(), e.data(), 1);
  out.inertia_kgm2 = 1.0 / x[static_cast<std::size_t>(dof)] - m->dof_armature[dof];
  RigConfig& r = out.rig;
  r.source_file = robot.source_file + ": " + jc.name + " (whole-robot model reduced to a pendulum)";
  const double grav = std::sqrt(m->opt.gravity[0] * m->opt.gravity[0] + m->opt.gravity[1] * m->opt.gravity[1] +
                                m->opt.gravity[2] * m->opt.gravity[2]);
  r.gravity_mps2 = grav;
  // The locked subtree as the pendulum: its mass, its centre of mass at the distance that gives the
  // gravity amplitude, its inertia about the axis (M_jj). (The free apparent inertia, the lower
  // bound, fitted worse on the nominal simulator: hip pitch held-out RMSE 29 mrad instead of 7.)
  r.mass_kg = m->body_subtreemass[body];
  r.com_m = out.gravity_amplitude_Nm / (r.mass_kg * grav);
  r.link_inertia_kgm2 = std::max(0.0, out.inertia_locked_kgm2 - r.mass_kg * r.com_m * r.com_m);
  r.kp_Nm_per_rad = jc.kp;
  r.kd_Nms_per_rad = jc.kd;
  r.armature_kgm2 = m->dof_armature[dof];
  r.torque_limit_Nm = jc.torque_limit;
  r.rate_hz = 1.0 / m->opt.timestep;  // the SIL's drivers recompute the PD every physics step
  r.encoder_motor_side = true;
  r.log_gain_to_SI = 1.0;
  r.sim_dt_s = m->opt.timestep;
  mj_deleteData(d);
  r.validate();
  return out;
}

namespace {
double param(const std::map<std::string, double>& p, const char* key, double dflt) {
  const auto it = p.find(key);
  return it == p.end() ? dflt : it->second;
}
}  // namespace

std::vector<JointEffect> differentialEffects(const RigConfig& rig, const std::map<std::string, double>& sim_baseline,
                                             const std::vector<std::pair<std::string, std::map<std::string, double>>>& sim_causes,
                                             const std::map<std::string, double>& robot_baseline,
                                             const std::vector<std::pair<std::string, std::map<std::string, double>>>& robot_causes,
                                             const std::vector<double>& robot_cause_gains) {
  std::vector<JointEffect> base, causes;
  const double kp = param(robot_baseline, "kp_scale", 1.0) / param(sim_baseline, "kp_scale", 1.0);
  if (std::fabs(kp - 1.0) > 0.06) base.push_back({"pd_gain", {{"kp_scale", kp}}, kp - 1.0});
  const double arm_sim = param(sim_baseline, "armature", rig.armature_kgm2);
  const double ref_inertia = arm_sim + rig.link_inertia_about_axis();
  const double excess = param(robot_baseline, "armature", rig.armature_kgm2) - arm_sim;
  if (excess > std::max(0.004, 0.10 * ref_inertia))
    base.push_back({"armature", {{"armature_kgm2", rig.armature_kgm2 + excess}}, excess / ref_inertia});
  std::sort(base.begin(), base.end(), [](const auto& a, const auto& b) { return std::fabs(a.size) > std::fabs(b.size); });
  for (std::size_t k = 0; k < robot_causes.size(); ++k) {
    const auto& [name, params] = robot_causes[k];
    const std::map<std::string, double>* sim = nullptr;
    for (const auto& [sname, sparams] : sim_causes)
      if (sname == name || nested_entry(name) == sname || nested_entry(sname) == name) sim = &sparams;
    bool named = sim == nullptr;
    if (!named) {
      const auto& keys = catalogue_params(name);
      const std::string key = keys.empty() ? std::string() : keys.front();
      const double r = param(params, key.c_str(), 0.0), s0 = param(*sim, key.c_str(), 0.0);
      named = std::fabs(r) >= 1.5 * std::fabs(s0) && std::fabs(r) > 0.0;
    }
    if (named) causes.push_back({name, params, k < robot_cause_gains.size() ? robot_cause_gains[k] : 0.0});
  }
  base.insert(base.end(), causes.begin(), causes.end());
  return base;
}

ActuatorBlock effectsBlock(const RigConfig& rig, const std::map<std::string, double>& sim_baseline,
                           const std::map<std::string, double>& robot_baseline, const std::vector<JointEffect>& effects) {
  std::map<std::string, double> p;
  for (const auto& e : effects)
    if (e.name != "pd_gain" && e.name != "armature") p.insert(e.params.begin(), e.params.end());
  ActuatorBlock b = actuator_block_from_params(rig, p);
  b.kp_scale = param(robot_baseline, "kp_scale", 1.0) / param(sim_baseline, "kp_scale", 1.0);
  b.kd_scale = param(robot_baseline, "kd_scale", 1.0) / param(sim_baseline, "kd_scale", 1.0);
  const double arm = rig.armature_kgm2 + param(robot_baseline, "armature", rig.armature_kgm2) -
                     param(sim_baseline, "armature", rig.armature_kgm2);
  b.armature_kgm2 = std::max(0.0, arm);
  return b;
}

BenchLog toRigFrame(const BenchLog& log, double q_down) {
  BenchLog out = log;
  for (double& v : out.q) v -= q_down;
  for (double& v : out.q_cmd) v -= q_down;
  return out;
}

}  // namespace pmg::calib
