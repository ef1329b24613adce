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
// tick.
//
// --config selects the Table I configuration the actor was trained for (the contract check refuses
// a mismatch, naming pmg.gco / pmg.mode):
//   pmg_gco      full PMG: generator + GCO; the actor observes u' (PMG eq. 19)
//   pmg          PMG without GCO: the actor observes the shaped command u
//   single_gait  single-gait imitation: the generator runs on the walk_forward clip alone at its
//                nominal speed whatever the command; the actor observes u
// Seed k > 0 perturbs the initial joint positions (uniform +-0.02 rad) and seeds the sensor noise.
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
// Writes <out>/seed<k>.csv (per tick), <out>/frames<k>.csv and <out>/summary.json.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <mujoco/mujoco.h>

#include "pmg/common/cli_checks.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/controller/controller_app.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/policy/policy_stage.hpp"

namespace {

void quatToRot(const double* q, double R[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - z * w); R[2] = 2 * (x * z + y * w);
  R[3] = 2 * (x * y + z * w); R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - x * w);
  R[6] = 2 * (x * z - y * w); R[7] = 2 * (y * z + x * w); R[8] = 1 - 2 * (x * x + y * y);
}

struct Totals {
  double lin = 0, yaw = 0, roll = 0, pitch = 0, height = 0, slip = 0;
  long n = 0, slip_n = 0;
  bool fell = false;
  double fall_time = -1;
  double survived = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Evaluate a policy in the MuJoCo 2.2 SIL through pmg_controller's loop on a command script"};
  std::string model_path, robot_path, clips_dir, gco_path;
  std::string controller_path = pmg::resolveData("config/controller/g1_sil_policy.yaml").string();
  std::string commands = pmg::resolveData("config/policies/eval_commands.yaml").string(), out = "out/policy_sil";
  std::string config = "pmg_gco";
  int seeds = 3;
  bool noise = true, native = true;
  double duration = -1, frame_period = 0.1;
  app.add_option("--model", model_path, "ONNX actor with pmg.contract (default: the controller config's policy.model)");
  app.add_option("--controller", controller_path, "controller config YAML (the product path)")->capture_default_str();
  app.add_option("--robot", robot_path, "robot config YAML (default: the controller config's)");
  app.add_option("--clips", clips_dir, "PMG clip directory (default: the controller config's)");
  app.add_option("--config", config, "Table I configuration the actor was trained for")
      ->check(CLI::IsMember({"pmg_gco", "pmg", "single_gait"}));
  app.add_option("--gco", gco_path, "GCO options (default: the controller config's)");
  app.add_option("--commands", commands, "command script YAML")->capture_default_str();
  app.add_option("--seeds", seeds, "runs (seed k perturbs the initial pose, and the sensor noise)")->check(CLI::Range(1, 100));
  app.add_option("--noise", noise, "sensor noise on the observation (as in training)");
  app.add_option("--native", native, "allocation-free native evaluator (false: ONNX Runtime)");
  app.add_option("--duration", duration, "override the sequence duration [s]")->check(pmg::cli::finiteIn(0.0, 1e5));
  app.add_option("--out", out, "output directory");
  app.add_option("--frame-period", frame_period, "period of the body-position log <out>/frames<k>.csv [s] (frame strips)")
      ->check(pmg::cli::finiteIn(0.01, 10.0));
  CLI11_PARSE(app, argc, argv);
  try {
    pmg::ControllerConfig base = pmg::loadControllerConfig(controller_path);
    base.makeOffline();
    base.mujoco.gantry.enabled = false;
    if (!robot_path.empty()) {
      base.robot_file = robot_path;
      base.robot = pmg::loadRobotConfig(robot_path);
    }
    if (!clips_dir.empty()) base.clips_dir = clips_dir;
    if (!gco_path.empty()) base.gco = pmg::gco::loadGcoOptionsFile(gco_path);
    base.gco.enabled = config == "pmg_gco";
    if (!model_path.empty()) base.policy_file = model_path;
    if (base.policy_file.empty()) throw pmg::ConfigError(controller_path + ": policy.model: missing (or give --model)");
    base.policy_native = native;
    const pmg::RobotConfig& robot = base.robot;
    const pmg::CommandScript script = pmg::loadCommandScript(commands);
    const double T = duration > 0 ? duration : script.duration();
    const bool single_gait = config == "single_gait";
    std::filesystem::create_directories(out);
    const int nj = static_cast<int>(robot.numJoints());
    std::vector<Totals> totals;
    const char* axes[6] = {"vx", "vy", "wz", "pitch", "roll", "height"};

    for (int seed = 0; seed < seeds; ++seed) {
      std::mt19937 rng(static_cast<unsigned>(1000 + seed));
      std::uniform_real_distribution<double> uni(-1.0, 1.0);
      pmg::MujocoBackendOptions bo = base.mujoco;
      auto sim_owned = std::make_unique<pmg::MujocoBackend>(robot, bo);
      pmg::MujocoBackend* sim = sim_owned.get();
      const mjModel* m = sim->model();
      mjData* d = sim->data();
      for (int j = 0; j < nj; ++j) d->qpos[7 + j] += 0.02 * uni(rng) * (seed > 0 ? 1.0 : 0.0);
      mj_forward(m, d);
      const int torso = mj_name2id(m, mjOBJ_BODY, "torso_link");
      const int feet[2] = {mj_name2id(m, mjOBJ_BODY, robot.left_foot_link.c_str()),
                           mj_name2id(m, mjOBJ_BODY, robot.right_foot_link.c_str())};
      const int floor = mj_name2id(m, mjOBJ_GEOM, "floor");

      pmg::ControllerAppOptions opt;
      opt.backend = std::move(sim_owned);
      opt.telemetry = true;
      if (single_gait) opt.clip_files = {base.clips_dir + "/walk_forward.yaml"};
      opt.policy.noise_gyro = noise ? 0.1 : 0.0;
      opt.policy.noise_gravity = noise ? 0.03 : 0.0;
      opt.policy.noise_q = noise ? 0.01 : 0.0;
      opt.policy.noise_qd = noise ? 0.5 : 0.0;
      opt.policy.noise_seed = static_cast<unsigned>(2000 + seed);
      opt.policy.mode = single_gait ? "single_gait" : "pmg";
      pmg::ControllerApp loop(base, std::move(opt));
      pmg::Controller& controller = loop.controller();
      if (single_gait)  // the forward clip at its nominal speed, neutral posture, whatever the command
        controller.setFixedGeneratorCommand(
            {controller.generator().model().dynamicClip(pmg::CommandAxis::kForward, 1)->nominal_scale, 0.0, 0.0});
      const int na = controller.policy()->runner().actionSize();
      const double standing = loop.config().commands.standing_height;

      std::ofstream csv(out + "/seed" + std::to_string(seed) + ".csv");
      csv << "t,segment";
      for (const char* a : axes) csv << ',' << a << "_cmd";
      for (const char* a : axes) csv << ',' << a;
      csv << ",height_ref,phase,contact_l,contact_r,ref_contact_l,ref_contact_r,mode";
      for (int j = 0; j < na; ++j) csv << ",q" << j;
      for (int j = 0; j < na; ++j) csv << ",qref" << j;
      csv << "\n";
      std::ofstream frames(out + "/frames" + std::to_string(seed) + ".csv");
      frames << "t";
      for (int b = 1; b < m->nbody; ++b) frames << "," << mj_id2name(m, mjOBJ_BODY, b) << ":" << m->body_parentid[b];
      frames << "\n";
      const int frame_every = std::max(1, static_cast<int>(std::lround(frame_period / 0.01)));
      Totals tot;
      std::atomic<bool> stop{false};
      long k = 0;
      const auto observe = [&](double t, const pmg::TickStatus& status, std::size_t segment) {
        const pmg::LowState& state = controller.lastState();
        const pmg::GeneratorOutput& g = controller.generator().output();
        const pmg::Command c = script.at(t);
        const double u[6] = {c.vx, c.vy, c.wz, c.pitch, c.roll, c.height.value_or(standing)};
        double Rb[9], Rt[9];
        quatToRot(state.base_quat_wxyz.data(), Rb);
        for (int i = 0; i < 9; ++i) Rt[i] = d->xmat[9 * torso + i];
        const double yaw = std::atan2(Rb[3], Rb[0]);
        const double* v = state.base_linear_velocity.data();
        const double vx = std::cos(yaw) * v[0] + std::sin(yaw) * v[1], vy = -std::sin(yaw) * v[0] + std::cos(yaw) * v[1];
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
        for (int f = 0; f < 2; ++f) {
          if (!contact[f]) continue;
          mjtNum vel[6];
          mj_objectVelocity(m, d, mjOBJ_BODY, feet[f], vel, 0);  // [angular; linear], world frame
          tot.slip += std::hypot(vel[3], vel[4]);
          ++tot.slip_n;
        }
        const bool fallen = height < 0.4 || Rb[8] < 0.5 || status.fault == pmg::FaultCode::kFallHeight ||
                            status.fault == pmg::FaultCode::kFallTilt;
        if (t >= 1.0 && !fallen) {
          tot.lin += std::hypot(u[0] - vx, u[1] - vy);
          tot.yaw += std::abs(u[2] - wz);
          tot.pitch += std::abs(u[3] - pitch);
          tot.roll += std::abs(u[4] - roll);
          tot.height += std::abs(u[5] - height);
          ++tot.n;
        }
        csv << t << ',' << script.segments[segment].name;
        for (double x : u) csv << ',' << x;
        csv << ',' << vx << ',' << vy << ',' << wz << ',' << pitch << ',' << roll << ',' << height << ',' << g.base_height << ','
            << g.phase << ',' << contact[0] << ',' << contact[1] << ',' << g.in_contact[0] << ',' << g.in_contact[1] << ','
            << pmg::toString(status.mode);
        for (int j = 0; j < na; ++j) csv << ',' << state.motors[static_cast<std::size_t>(j)].q;
        for (int j = 0; j < na; ++j) csv << ',' << controller.reference()[static_cast<std::size_t>(j)];
        csv << '\n';
        if (k++ % frame_every == 0) {  // world positions of every body origin (x y z) for frame strips
          frames << t;
          for (int b = 1; b < m->nbody; ++b) frames << ',' << d->xpos[3 * b] << ' ' << d->xpos[3 * b + 1] << ' ' << d->xpos[3 * b + 2];
          frames << '\n';
        }
        tot.survived = t + 0.01;
        if (fallen && !tot.fell) {
          tot.fell = true;
          tot.fall_time = t;
          stop = true;
        }
      };
      const pmg::RunSummary rs = loop.run(T, &script, &stop, observe);
      totals.push_back(tot);
      const double n = std::max<long>(1, tot.n);
      std::printf("seed %d: %s after %.2f s | LinVel %.4f m/s  YawVel %.4f rad/s  Roll %.4f rad  Pitch %.4f rad  Height %.4f m  slip %.4f m/s  (policy holds %llu; final mode %s, fault %s)\n",
                  seed, tot.fell ? "FELL" : "ok", tot.survived, tot.lin / n, tot.yaw / n, tot.roll / n, tot.pitch / n,
                  tot.height / n, tot.slip / std::max<long>(1, tot.slip_n),
                  static_cast<unsigned long long>(controller.policy()->runner().counters().held),
                  pmg::toString(rs.final_mode), pmg::toString(rs.fault));
      std::fflush(stdout);
    }
    std::ofstream js(out + "/summary.json");
    double acc[6] = {0, 0, 0, 0, 0, 0};
    int falls = 0;
    js << "{\"model\": \"" << model_path << "\", \"config\": \"" << config << "\", \"duration_s\": " << T << ", \"runs\": [";
    for (std::size_t s = 0; s < totals.size(); ++s) {
      const Totals& t = totals[s];
      const double n = std::max<long>(1, t.n);
      const double vals[6] = {t.lin / n, t.yaw / n, t.roll / n, t.pitch / n, t.height / n, t.slip / std::max<long>(1, t.slip_n)};
      for (int i = 0; i < 6; ++i) acc[i] += vals[i];
      falls += t.fell;
      js << (s ? ", " : "") << "{\"seed\": " << s << ", \"fell\": " << (t.fell ? "true" : "false") << ", \"survived_s\": " << t.survived
         << ", \"lin_vel\": " << vals[0] << ", \"yaw_vel\": " << vals[1] << ", \"roll\": " << vals[2] << ", \"pitch\": " << vals[3]
         << ", \"height\": " << vals[4] << ", \"foot_slip\": " << vals[5] << "}";
    }
    const double S = static_cast<double>(totals.size());
    js << "], \"mean\": {\"lin_vel\": " << acc[0] / S << ", \"yaw_vel\": " << acc[1] / S << ", \"roll\": " << acc[2] / S
       << ", \"pitch\": " << acc[3] / S << ", \"height\": " << acc[4] / S << ", \"foot_slip\": " << acc[5] / S
       << ", \"falls\": " << falls << "}}\n";
    std::printf("mean over %d seeds: LinVel %.4f  YawVel %.4f  Roll %.4f  Pitch %.4f  Height %.4f  slip %.4f  falls %d/%d\n",
                seeds, acc[0] / S, acc[1] / S, acc[2] / S, acc[3] / S, acc[4] / S, acc[5] / S, falls, seeds);
    return falls == 0 ? 0 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_policy_sil: %s\n", e.what());
    return 1;
  }
}
