// pmg_policy_sil: runs a trained actor in the MuJoCo 2.2 SIL (no gantry) on the preset command
// sequence and reports the seed's Table I metrics, falls and foot slip.
//
//   build-policy/bin/pmg_policy_sil --model config/policies/g1_pmg_policy.onnx --seeds 5 --out out/sil
//
// --config selects the Table I configuration the actor was trained for (the contract check refuses
// a mismatch, naming pmg.gco / pmg.mode):
//   pmg_gco      full PMG: generator + GCO (pmg::gco::GeneratorWithGco, config/gco/g1.yaml); the
//                actor observes u' (PMG eq. 19), as pmg_controller does with GCO on
//   pmg          PMG without GCO: the actor observes the command u
//   single_gait  single-gait imitation: the generator runs on the walk_forward clip alone at its
//                nominal speed whatever the command; the actor observes u
// The loop is the controller's, at its rates: 100 Hz policy tick (PMG generator step ->
// observation -> PolicyRunner::step -> limb separation: legs from the actor, waist and arms from
// the PMG reference), 500 Hz HAL cycles of the MuJoCo 2.2 backend (1 kHz physics, motor PD at
// every physics step, pmg::MujocoBackend). Observations come from what the robot measures (joint
// encoders, pelvis IMU); the metrics use the simulator's ground truth.
//
// Metrics (mean absolute error over the run after the first second, per seed, then mean over seeds):
//   LinVel [m/s]  |v_cmd,xy - v_xy| with v the pelvis velocity in the heading (yaw) frame
//   YawVel [rad/s] |w_cmd - w_z|, w_z the pelvis yaw rate (world z)
//   Roll, Pitch [rad] |cmd - torso roll/pitch| (torso_link, ZYX Euler angles in the world frame)
//   Height [m]   |h_cmd - pelvis z|, h_cmd = the commanded pelvis height (0.78 m standing/walking)
//   (all errors against the user's command u, also in the GCO configuration whose actor sees u')
//   falls        runs in which the pelvis dropped below 0.4 m or tilted more than 60 deg
//   foot slip [m/s] mean horizontal speed of a foot (ankle_roll_link origin) while it touches the floor
// Writes <out>/seed<k>.csv (per tick) and <out>/summary.json.
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
#include <yaml-cpp/yaml.h>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/motion/clip_io.hpp"
#include "pmg/policy/limb_separation.hpp"
#include "pmg/policy/observation.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "pmg/policy/policy_stage.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace {

struct Segment {
  std::string name;
  double t = 0;
  double u[6] = {0, 0, 0, 0, 0, 0.78};  // vx, vy, wz, pitch, roll, height
};

struct Schedule {
  double ramp = 0.5, duration = 0;
  std::vector<Segment> segments;
  void at(double t, double* u, std::string* name) const {
    std::size_t k = 0;
    while (k + 1 < segments.size() && t >= segments[k + 1].t) ++k;
    const double* prev = k > 0 ? segments[k - 1].u : segments[0].u;
    const double a = ramp > 0 ? std::clamp((t - segments[k].t) / ramp, 0.0, 1.0) : 1.0;
    for (int i = 0; i < 6; ++i) u[i] = prev[i] + a * (segments[k].u[i] - prev[i]);
    if (name != nullptr) *name = segments[k].name;
  }
};

Schedule loadSchedule(const std::string& path) {
  const YAML::Node root = YAML::LoadFile(path);
  Schedule s;
  s.ramp = root["ramp"].as<double>();
  s.duration = root["duration"].as<double>();
  const char* keys[6] = {"vx", "vy", "wz", "pitch", "roll", "height"};
  for (const auto& n : root["segments"]) {
    Segment g;
    g.name = n["name"].as<std::string>();
    g.t = n["t"].as<double>();
    for (int i = 0; i < 6; ++i) g.u[i] = n[keys[i]].as<double>();
    s.segments.push_back(g);
  }
  if (s.segments.empty() || s.segments[0].t != 0.0) throw std::runtime_error(path + ": segments: first must start at t: 0");
  return s;
}

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
  CLI::App app{"Evaluate a policy in the MuJoCo 2.2 SIL on the preset command sequence"};
  // Defaults: pmg's data directory (pmg::dataDir()); the output folder is relative to the working directory.
  std::string model_path = pmg::resolveData("config/policies/g1_pmg_policy.onnx").string();
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string clips_dir = pmg::resolveData("config/clips/g1").string();
  std::string commands = pmg::resolveData("config/policies/eval_commands.yaml").string(), out = "out/policy_sil";
  std::string config = "pmg_gco", gco_path = pmg::resolveData("config/gco/g1.yaml").string();
  int seeds = 3;
  bool noise = true, native = false;
  double duration = -1, frame_period = 0.1;
  app.add_option("--model", model_path, "ONNX actor with pmg.contract");
  app.add_option("--robot", robot_path, "robot config YAML");
  app.add_option("--clips", clips_dir, "PMG clip directory");
  app.add_option("--config", config, "Table I configuration the actor was trained for")
      ->check(CLI::IsMember({"pmg_gco", "pmg", "single_gait"}));
  app.add_option("--gco", gco_path, "GCO options (pmg_gco)");
  app.add_option("--commands", commands, "command sequence YAML");
  app.add_option("--seeds", seeds, "runs (seed k perturbs the initial pose and phase, and the sensor noise)")->check(CLI::Range(1, 100));
  app.add_option("--noise", noise, "sensor noise on the observation (as in training)");
  app.add_option("--native", native, "evaluate the actor with the allocation-free native backend instead of ONNX Runtime");
  app.add_option("--duration", duration, "override the sequence duration [s]");
  app.add_option("--out", out, "output directory");
  app.add_option("--frame-period", frame_period, "period of the body-position log <out>/frames<k>.csv [s] (frame strips)");
  CLI11_PARSE(app, argc, argv);
  try {
    namespace pp = pmg::policy;
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const Schedule sched = loadSchedule(commands);
    const double T = duration > 0 ? duration : sched.duration;
    const bool single_gait = config == "single_gait";
    const auto gen_model = std::make_shared<const pmg::GeneratorModel>(
        single_gait ? pmg::loadClipLibrary(std::vector<std::string>{clips_dir + "/walk_forward.yaml"}, robot)
                    : pmg::loadClipLibrary(clips_dir, robot),
        pmg::generatorJointSpace(robot));
    pmg::gco::GcoOptions gco_options = pmg::gco::loadGcoOptionsFile(gco_path);
    gco_options.enabled = config == "pmg_gco";
    const auto legs = pmg::gco::LegModel::fromRobotConfig(robot);
    // Single gait: the forward clip at its nominal speed, neutral posture, whatever the command.
    const pmg::VelocityCommand single_gait_ud{gen_model->dynamicClip(pmg::CommandAxis::kForward, 1)->nominal_scale, 0.0, 0.0};
    std::filesystem::create_directories(out);
    const int nj = static_cast<int>(robot.numJoints());
    std::vector<Totals> totals;

    for (int seed = 0; seed < seeds; ++seed) {
      std::mt19937 rng(static_cast<unsigned>(1000 + seed));
      std::normal_distribution<double> gauss(0.0, 1.0);
      std::uniform_real_distribution<double> uni(-1.0, 1.0);
      pmg::MujocoBackendOptions bo;
      bo.gantry.enabled = false;
      pmg::MujocoBackend sim(robot, bo);
      const mjModel* m = sim.model();
      mjData* d = sim.data();
      for (int j = 0; j < nj; ++j) d->qpos[7 + j] += 0.02 * uni(rng) * (seed > 0 ? 1.0 : 0.0);
      mj_forward(m, d);
      const int torso = mj_name2id(m, mjOBJ_BODY, "torso_link");
      const int feet[2] = {mj_name2id(m, mjOBJ_BODY, robot.left_foot_link.c_str()),
                           mj_name2id(m, mjOBJ_BODY, robot.right_foot_link.c_str())};
      const int floor = mj_name2id(m, mjOBJ_GEOM, "floor");

      pmg::gco::GeneratorWithGco gen(gen_model, legs, gco_options);
      gen.reset(seed > 0 ? 0.5 * (uni(rng) + 1.0) : 0.0);
      pp::PolicyStageOptions so;
      so.backend = native ? pp::PolicyBackend::kNative : pp::PolicyBackend::kOnnxRuntime;
      so.noise_gyro = noise ? 0.1 : 0.0;
      so.noise_gravity = noise ? 0.03 : 0.0;
      so.noise_q = noise ? 0.01 : 0.0;
      so.noise_qd = noise ? 0.5 : 0.0;
      so.noise_seed = static_cast<unsigned>(2000 + seed);
      so.gco = gco_options.enabled;
      so.mode = single_gait ? "single_gait" : "pmg";
      pp::PolicyStage stage(model_path, robot, so);  // observation, actor, limb separation as in training
      const int na = stage.runner().actionSize();
      pmg::LowCommand low;
      low.num_motors = nj;
      pmg::LowState state;
      sim.exchange(low, state);  // first state (zero gains: nothing applied yet)

      std::ofstream csv(out + "/seed" + std::to_string(seed) + ".csv");
      csv << "t,segment,vx_cmd,vy_cmd,wz_cmd,pitch_cmd,roll_cmd,height_cmd,vx,vy,wz,pitch,roll,height,height_ref,phase,contact_l,contact_r,ref_contact_l,ref_contact_r";
      for (int j = 0; j < na; ++j) csv << ",q" << j;
      for (int j = 0; j < na; ++j) csv << ",qref" << j;
      csv << "\n";
      std::ofstream frames(out + "/frames" + std::to_string(seed) + ".csv");
      frames << "t";
      for (int b = 1; b < m->nbody; ++b) frames << "," << mj_id2name(m, mjOBJ_BODY, b) << ":" << m->body_parentid[b];
      frames << "\n";
      const int frame_every = std::max(1, static_cast<int>(std::lround(frame_period / 0.01)));
      Totals tot;
      const int ticks = static_cast<int>(std::lround(T / 0.01));
      for (int k = 0; k < ticks; ++k) {
        const double t = k * 0.01;
        double u[6];
        std::string seg;
        sched.at(t, u, &seg);
        const pmg::gco::GcoResult& gr = single_gait ? gen.step(single_gait_ud, {0.0, 0.0, 0.0}, 0.01)
                                                    : gen.step({u[0], u[1], u[2]}, {u[3], u[4], u[5]}, 0.01);
        const pmg::GeneratorOutput& g = gen.generatorOutput();
        const std::array<double, 6> observed =
            gco_options.enabled ? std::array<double, 6>{gr.u_opt.v_x, gr.u_opt.v_y, gr.u_opt.yaw_rate, gr.u_opt.pitch,
                                                        gr.u_opt.roll, gr.u_opt.height}
                                : std::array<double, 6>{u[0], u[1], u[2], u[3], u[4], u[5]};
        stage.step(state, observed, g, low);
        ++low.sequence;
        for (int c = 0; c < 5; ++c) sim.exchange(low, state);

        // Ground truth after the tick.
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
        for (int c = 0; c < d->ncon; ++c) {
          const mjContact& con = d->contact[c];
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
        const bool fallen = height < 0.4 || Rb[8] < 0.5;
        if (t >= 1.0 && !fallen) {
          tot.lin += std::hypot(u[0] - vx, u[1] - vy);
          tot.yaw += std::abs(u[2] - wz);
          tot.pitch += std::abs(u[3] - pitch);
          tot.roll += std::abs(u[4] - roll);
          tot.height += std::abs(u[5] - height);
          ++tot.n;
        }
        csv << t << ',' << seg;
        for (double x : u) csv << ',' << x;
        csv << ',' << vx << ',' << vy << ',' << wz << ',' << pitch << ',' << roll << ',' << height << ',' << g.base_height << ','
            << g.phase << ',' << contact[0] << ',' << contact[1] << ',' << g.in_contact[0] << ',' << g.in_contact[1];
        for (int j = 0; j < na; ++j) csv << ',' << state.motors[static_cast<std::size_t>(j)].q;
        for (int j = 0; j < na; ++j) csv << ',' << g.q_ref[j];
        csv << '\n';
        if (k % frame_every == 0) {  // world positions of every body origin (x y z) for frame strips
          frames << t;
          for (int b = 1; b < m->nbody; ++b) frames << ',' << d->xpos[3 * b] << ' ' << d->xpos[3 * b + 1] << ' ' << d->xpos[3 * b + 2];
          frames << '\n';
        }
        tot.survived = t + 0.01;
        if (fallen) {
          tot.fell = true;
          tot.fall_time = t;
          break;
        }
      }
      totals.push_back(tot);
      const double n = std::max<long>(1, tot.n);
      std::printf("seed %d: %s after %.2f s | LinVel %.4f m/s  YawVel %.4f rad/s  Roll %.4f rad  Pitch %.4f rad  Height %.4f m  slip %.4f m/s  (policy holds %llu)\n",
                  seed, tot.fell ? "FELL" : "ok", tot.survived, tot.lin / n, tot.yaw / n, tot.roll / n, tot.pitch / n,
                  tot.height / n, tot.slip / std::max<long>(1, tot.slip_n),
                  static_cast<unsigned long long>(stage.runner().counters().held));
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
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
