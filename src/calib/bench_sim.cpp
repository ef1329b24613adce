#include "pmg/calib/bench_sim.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <mujoco/mujoco.h>

namespace pmg::calib {
namespace {

std::mutex& compile_mutex() {
  static std::mutex m;  // MuJoCo 2.2's XML parser and compiler are not thread-safe
  return m;
}

std::string rig_mjcf(const RigConfig& rig, bool backlash) {
  const double i_com = std::max(rig.link_inertia_kgm2, 1e-7);
  const std::string link_inertial =
      fmt::format(R"(<inertial pos="0 0 {:.9g}" mass="{:.9g}" diaginertia="{:.9g} {:.9g} {:.9g}"/>)", -rig.com_m,
                  rig.mass_kg, i_com, i_com, i_com);
  std::string body;
  if (!backlash) {
    body = fmt::format(R"(<body name="link"><joint name="motor" type="hinge" axis="0 1 0" armature="{:.9g}"/>{}</body>)",
                       rig.armature_kgm2, link_inertial);
  } else {
    body = fmt::format(
        R"(<body name="rotor"><joint name="motor" type="hinge" axis="0 1 0" armature="{:.9g}"/>)"
        R"(<inertial pos="0 0 0" mass="0.001" diaginertia="1e-7 1e-7 1e-7"/>)"
        R"(<body name="link"><joint name="gap" type="hinge" axis="0 1 0" limited="true" range="-0.001 0.001" )"
        R"(solreflimit="{:.9g} 1" solimplimit="0.99 0.999 0.001"/>{}</body></body>)",
        rig.armature_kgm2, 2.0 * rig.sim_dt_s, link_inertial);
  }
  return fmt::format(R"(<mujoco model="bench_rig"><compiler angle="radian" inertiafromgeom="false"/>)"
                     R"(<option timestep="{:.9g}" gravity="0 0 {:.9g}" integrator="Euler"/>)"
                     R"(<worldbody>{}</worldbody></mujoco>)",
                     rig.sim_dt_s, -rig.gravity_mps2, body);
}

mjModel* compile(const std::string& xml) {
  std::lock_guard<std::mutex> lock(compile_mutex());
  auto vfs_ptr = std::make_unique<mjVFS>();  // ~2 MB: keep it off the stack
  mjVFS& vfs = *vfs_ptr;
  mj_defaultVFS(&vfs);
  const char* fname = "bench_rig.xml";
  if (mj_makeEmptyFileVFS(&vfs, fname, static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("bench rig: cannot allocate MuJoCo VFS file");
  const int idx = mj_findFileVFS(&vfs, fname);
  std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs.filedata[idx]));
  char err[1000] = {0};
  mjModel* m = mj_loadXML(fname, &vfs, err, sizeof(err));
  mj_deleteVFS(&vfs);
  if (!m) throw std::runtime_error(fmt::format("bench rig: MuJoCo could not compile the rig model: {}", err));
  return m;
}

}  // namespace

BenchSimulator::BenchSimulator(const RigConfig& rig, bool with_backlash) : rig_(rig), backlash_(with_backlash) {
  rig_.validate();
  model_ = compile(rig_mjcf(rig_, backlash_));
  data_ = mj_makeData(model_);
}

BenchSimulator::~BenchSimulator() {
  if (data_) mj_deleteData(data_);
  if (model_) mj_deleteModel(model_);
}

double BenchSimulator::rollout(const BenchLog& log, const RigParams& params, RolloutTrace* trace) {
  mjModel* m = model_;
  mjData* d = data_;
  ActuatorParams act = params.act;
  act.rate_hz = rig_.rate_hz;
  m->dof_armature[0] = params.armature_kgm2;
  const double half_gap = 0.5 * std::max(act.backlash_gap_rad, 2e-6);
  if (backlash_) {
    m->jnt_range[2] = -half_gap;
    m->jnt_range[3] = half_gap;
  }
  mj_resetData(m, d);
  state_.reset();
  const std::size_t n = log.size();
  const double dt = m->opt.timestep;
  auto reading = [&]() {
    const double q_enc = (backlash_ && !rig_.encoder_motor_side) ? d->qpos[0] + d->qpos[1] : d->qpos[0];
    return ActuatorModel::encoder(act, q_enc);
  };
  d->qpos[0] = log.q[0] - act.offset_rad;
  d->qvel[0] = log.has_dq() ? log.dq[0] : 0.0;
  if (backlash_) {
    // Start with the link resting on the side that gravity loads (hanging still: the middle).
    d->qpos[1] = 0.0;
  }
  if (trace) {
    trace->q.assign(n, 0.0);
    trace->dq.assign(n, 0.0);
    trace->tau_motor.assign(n, 0.0);
  }
  double sse = 0.0;
  double e0 = reading() - log.q[0];
  sse += e0 * e0;
  if (trace) {
    trace->q[0] = reading();
    trace->dq[0] = d->qvel[0];
  }
  double t_sim = log.t[0];
  double last_tau = 0.0;
  const double kp_gain = params.kp_scale * (log.has_kp() ? rig_.log_gain_to_SI : rig_.kp_Nm_per_rad);
  const double kd_gain = params.kd_scale * (log.has_kd() ? rig_.log_gain_to_SI : rig_.kd_Nms_per_rad);
  double mfull[4];
  for (std::size_t i = 1; i < n; ++i) {
    // Command sent at row i-1 holds until row i (zero-order hold).
    MotorCommand cmd;
    const std::size_t c = i - 1;
    cmd.q_des_rad = log.q_cmd[c];
    cmd.dq_des_rad_per_s = log.has_dq_cmd() ? log.dq_cmd[c] : 0.0;
    cmd.kp_Nm_per_rad = kp_gain * (log.has_kp() ? log.kp[c] : 1.0);
    cmd.kd_Nms_per_rad = kd_gain * (log.has_kd() ? log.kd[c] : 1.0);
    cmd.tau_ff_Nm = log.has_tau_ff() ? log.tau_ff[c] : 0.0;
    cmd.enabled = log.has_enabled() ? log.enabled[c] != 0 : true;
    while (t_sim + 0.5 * dt < log.t[i]) {
      mj_step1(m, d);
      JointSample j;
      j.q_rad = d->qpos[0];
      j.dq_rad_per_s = d->qvel[0];
      j.dt_s = dt;
      if (!backlash_) {
        j.inertia_kgm2 = d->qM[0];
        j.tau_other_Nm = -d->qfrc_bias[0] + d->qfrc_passive[0];
      } else {
        mj_fullM(m, mfull, d->qM);
        const double f0 = -d->qfrc_bias[0] + d->qfrc_passive[0];
        const double f1 = -d->qfrc_bias[1] + d->qfrc_passive[1];
        const bool in_gap = std::abs(d->qpos[1]) < half_gap * 0.999;
        if (in_gap) {
          j.inertia_kgm2 = mfull[0] - mfull[1] * mfull[1] / mfull[3];
          j.tau_other_Nm = f0 - mfull[1] / mfull[3] * f1;
        } else {
          j.inertia_kgm2 = mfull[0];
          j.tau_other_Nm = f0;
        }
      }
      const ActuatorOutput out = ActuatorModel::step(act, state_, cmd, j);
      d->qfrc_applied[0] = out.tau_applied_Nm;
      last_tau = out.tau_motor_Nm;
      mj_step2(m, d);
      t_sim += dt;
      // Parameter sets that make the rig unstable are abandoned before MuJoCo's own (logging) check.
      if (!(std::abs(d->qvel[0]) < 1e3)) return std::numeric_limits<double>::infinity();
    }
    const double r = reading();
    if (!std::isfinite(r) || std::abs(d->qvel[0]) > 1e4) return std::numeric_limits<double>::infinity();
    const double e = r - log.q[i];
    sse += e * e;
    if (trace) {
      trace->q[i] = r;
      trace->dq[i] = d->qvel[0];
      trace->tau_motor[i] = last_tau;
    }
  }
  return sse;
}

}  // namespace pmg::calib
