// bench_teleop_arms: does a policy keep the G1 balanced while VR teleoperation holds its arms in
// a pose? Product path: ControllerApp (shaper, generator, GCO, teleop stage with arm IK,
// reference limiter, policy stage, supervisor) on the MuJoCo 2.2 SIL in lockstep, from
// config/controller/g1_sil_policy_table1.yaml (the Table I policy's clips and blending) with the policy file replaced and the teleop stage on
// (pmg::teleop::TeleopConfig defaults, the values of config/controller/g1_sil_teleop.yaml).
//
// The synthetic operator (frame V: x forward, y left, z up [m]; headset at (0, 0, 1.6), level):
//   0.0-1.0 s   stands; the controller stands the robot up and engages the actor
//   1.0-1.1 s   presses the right controller's A button (engages teleop at the headset's pose)
//   1.1-2.1 s   holds the grips of the pose's arms and moves those hands (smoothstep) from beside
//               the hips to the pose's hand positions (relative to the headset)
//   2.1-end     holds the pose; for a walking case the headset steps forward over 0.5 s by
//               position_deadband_m + v / velocity_gain[0] (the hands go with it): the robot is
//               commanded v forward (the teleop stage's locomotion mapping)
// Hand controllers point forward (identity orientation). Poses (left hand; the right mirrored):
//   none      no grip: the arms follow the PMG reference (baseline)
//   chest     both hands forward at chest height      (0.45, 0.20, -0.45) from the headset
//   low       both hands forward, low ("carrying")     (0.35, 0.20, -0.70)
//   side      both arms out to the sides               (0.00, 0.60, -0.40)
//   up        right hand up in front, left arm PMG     (0.30, -0.20, +0.30) (right hand)
// Per run: fall (supervisor fall fault, pelvis < 0.4 m or tilt > 60°) and its time, the minimum
// and mean pelvis height and the mean torso pitch (forward +) from 2.1 s on, the mean forward
// speed (heading frame) from 3.6 s on while walking (nan for a run that fell), and the arm
// references reached at 2.1 s (shoulder pitch, elbow).
// Seed k > 0 perturbs the initial joint positions (±0.02 rad) and seeds the observation noise
// (training's levels), as pmg_policy_sil does. --payload adds a mass to each hand (wrist_yaw_link).
//
//   build/bin/bench_teleop_arms --model config/policies/g1_pmg_policy.onnx
//       --model config/policies/g1_pmg_policy_arms.onnx [--seeds 2] [--hold 8] [--out arms.csv]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
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
#include "pmg/teleop/teleop_mode.hpp"

namespace {

struct Pose {
  const char* name;
  std::array<bool, 2> grip;                 // left, right
  std::array<double, 3> left_rel_head;      // left hand relative to the headset, frame V [m]
  std::array<double, 3> right_rel_head;     // right hand
};

const Pose kPoses[] = {
    {"none", {false, false}, {0.05, 0.22, -0.75}, {0.05, -0.22, -0.75}},
    {"chest", {true, true}, {0.45, 0.20, -0.45}, {0.45, -0.20, -0.45}},
    {"low", {true, true}, {0.35, 0.20, -0.70}, {0.35, -0.20, -0.70}},
    {"side", {true, true}, {0.00, 0.60, -0.40}, {0.00, -0.60, -0.40}},
    {"up", {false, true}, {0.05, 0.22, -0.75}, {0.30, -0.20, 0.30}},
};
constexpr std::array<double, 3> kRestLeft{0.05, 0.22, -0.75};  // hands beside the hips
constexpr double kHeadHeight = 1.6;

struct Result {
  std::string model, pose;
  double speed = 0;
  int seed = 0;
  bool fell = false;
  double fall_time = -1, min_height = 10, mean_height = 0, mean_pitch = 0, mean_vx = 0;
  std::array<double, 4> arm{};  // left shoulder pitch, left elbow, right shoulder pitch, right elbow (references) [rad]
  std::string arm_modes;
};

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

Result runOne(const pmg::ControllerConfig& base, const std::string& model, const Pose& pose, double speed, int seed,
              double hold, double payload) {
  pmg::ControllerConfig config = base;
  config.policy_file = model;
  Result r;
  r.model = model;
  r.pose = pose.name;
  r.speed = speed;
  r.seed = seed;

  const pmg::RobotConfig& robot = config.robot;
  auto sim_owned = std::make_unique<pmg::MujocoBackend>(robot, config.mujoco);
  pmg::MujocoBackend* sim = sim_owned.get();
  const mjModel* m = sim->model();
  mjData* d = sim->data();
  std::mt19937 rng(static_cast<unsigned>(1000 + seed));
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const int nj = static_cast<int>(robot.numJoints());
  for (int j = 0; j < nj; ++j) d->qpos[7 + j] += seed > 0 ? 0.02 * uni(rng) : 0.0;
  if (payload > 0) {
    // The backend owns a non-const mjModel; MuJoCo reads body_mass at every step.
    auto* mm = const_cast<mjModel*>(m);
    for (const char* b : {"left_wrist_yaw_link", "right_wrist_yaw_link"}) mm->body_mass[mj_name2id(m, mjOBJ_BODY, b)] += payload;
  }
  mj_forward(m, d);
  const int torso = mj_name2id(m, mjOBJ_BODY, "torso_link");

  pmg::ControllerAppOptions opt;
  opt.backend = std::move(sim_owned);
  opt.telemetry = false;
  opt.policy.noise_gyro = 0.1;  // training's sensor noise, as pmg_policy_sil
  opt.policy.noise_gravity = 0.03;
  opt.policy.noise_q = 0.01;
  opt.policy.noise_qd = 0.5;
  opt.policy.noise_seed = static_cast<unsigned>(2000 + seed);
  pmg::ControllerApp app(config, std::move(opt));
  const pmg::Controller& controller = app.controller();
  const pmg::teleop::TeleopMode& tm = *controller.teleop();
  const pmg::teleop::TeleopConfig& tc = config.teleop;
  const double walk_offset = speed > 0 ? tc.position_deadband_m + speed / tc.velocity_gain[0] : 0.0;

  pmg::CommandSample in;
  const double t_end = 2.1 + hold;
  double sum_h = 0, sum_pitch = 0, sum_vx = 0;
  long n = 0, n_walk = 0;
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) * 0.01;
    if (t >= t_end) break;
    pmg::teleop::VrSample& s = in.vr;
    const double head_x = t < 2.1 ? 0.0 : walk_offset * smoothstep((t - 2.1) / 0.5);
    s.head_position = {head_x, 0.0, kHeadHeight};
    s.head_quat = {1, 0, 0, 0};
    s.hand_valid = {true, true};
    const double reach = smoothstep((t - 1.1) / 1.0);
    for (int h = 0; h < 2; ++h) {
      const auto hh = static_cast<std::size_t>(h);
      const bool moves = pose.grip[hh] && t >= 1.1;
      const std::array<double, 3>& target = h == 0 ? pose.left_rel_head : pose.right_rel_head;
      const double side = h == 0 ? 1.0 : -1.0;
      const std::array<double, 3> rest{kRestLeft[0], side * kRestLeft[1], kRestLeft[2]};
      for (int i = 0; i < 3; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        const double rel = moves ? rest[ii] + reach * (target[ii] - rest[ii]) : rest[ii];
        s.hand_position[hh][ii] = rel + (i == 0 ? head_x : (i == 2 ? kHeadHeight : 0.0));
      }
      s.hand_quat[hh] = {1, 0, 0, 0};
      s.grip[hh] = moves ? 1.0 : 0.0;
    }
    s.buttons = {0u, (t >= 1.0 && t < 1.05) ? static_cast<std::uint32_t>(pmg::teleop::kVrButtonLower) : 0u};
    ++s.frame;
    in.vr_time = t;
    const pmg::TickStatus st = app.stepLockstep(in);

    const pmg::LowState& ls = controller.lastState();
    const double* q = ls.base_quat_wxyz.data();  // w x y z
    const double up = 1 - 2 * (q[1] * q[1] + q[2] * q[2]);  // R_zz of the pelvis
    const double yaw = std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
    const double h = ls.base_position[2];
    const bool fallen = h < 0.4 || up < 0.5 || st.fault == pmg::FaultCode::kFallHeight ||
                        st.fault == pmg::FaultCode::kFallTilt;
    if (fallen) {
      r.fell = true;
      r.fall_time = t;
      r.min_height = std::min(r.min_height, h);
      break;
    }
    if (t >= 2.1) {
      const double* R = d->xmat + 9 * torso;
      sum_h += h;
      sum_pitch += std::asin(std::clamp(-R[6], -1.0, 1.0));
      r.min_height = std::min(r.min_height, h);
      ++n;
      if (speed > 0 && t >= 3.6) {  // after the command's slew: 0.5 s step + 1 m/s² ramp
        const double* v = ls.base_linear_velocity.data();
        sum_vx += std::cos(yaw) * v[0] + std::sin(yaw) * v[1];
        ++n_walk;
      }
    }
    if (std::fabs(t - 2.1) < 0.005) {
      const auto& ref = controller.reference();
      const auto l = tm.ik().jointIndices(0), rr = tm.ik().jointIndices(1);
      r.arm = {ref[static_cast<std::size_t>(l[0])], ref[static_cast<std::size_t>(l[3])],
               ref[static_cast<std::size_t>(rr[0])], ref[static_cast<std::size_t>(rr[3])]};
      r.arm_modes = std::string(pmg::teleop::toString(tm.status().arm[0])) + "/" +
                    pmg::teleop::toString(tm.status().arm[1]);
    }
  }
  if (n > 0) {
    r.mean_height = sum_h / static_cast<double>(n);
    r.mean_pitch = sum_pitch / static_cast<double>(n);
  }
  // Walking speed only of runs that walked the whole time (a falling robot lunges forward).
  r.mean_vx = n_walk > 0 && !r.fell ? sum_vx / static_cast<double>(n_walk) : (speed > 0 ? std::nan("") : 0.0);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_teleop_arms: balance with teleoperated arm poses, per policy (lockstep MuJoCo SIL, product path)"};
  std::string controller_path = pmg::resolveData("config/controller/g1_sil_policy_table1.yaml").string();
  std::vector<std::string> models;
  std::vector<std::string> poses{"none", "chest", "low", "side", "up"};
  std::vector<double> speeds{0.0, 0.3};
  int seeds = 2;
  double hold = 8.0, payload = 0.0;
  std::string out;
  app.add_option("--controller", controller_path, "controller config YAML (policy and teleop stage replaced)")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--model", models, "ONNX policy (repeat for several; default: the config's policy.model)")
      ->check(CLI::ExistingFile);
  app.add_option("--pose", poses, "arm poses: none, chest, low, side, up")
      ->check(CLI::IsMember({"none", "chest", "low", "side", "up"}))
      ->capture_default_str();
  app.add_option("--speed", speeds, "forward speeds commanded through the headset [m/s], 0..0.8")
      ->check(pmg::cli::finiteIn(0.0, 0.8))
      ->capture_default_str();
  app.add_option("--seeds", seeds, "runs per case (seed k > 0 perturbs the initial pose and the noise)")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  app.add_option("--hold", hold, "seconds to hold each pose after reaching it")
      ->check(pmg::cli::finiteIn(0.5, 120.0))
      ->capture_default_str();
  app.add_option("--payload", payload, "mass added to each hand [kg]")->check(pmg::cli::finiteIn(0.0, 5.0));
  app.add_option("--out", out, "CSV of every run");
  CLI11_PARSE(app, argc, argv);

  try {
    pmg::ControllerConfig base = pmg::loadControllerConfig(controller_path);
    base.makeOffline();
    base.mujoco.gantry.enabled = false;
    base.teleop.enabled = true;  // TeleopConfig defaults = config/controller/g1_sil_teleop.yaml's values
    if (const std::string e = base.teleop.validate(); !e.empty()) throw pmg::ConfigError(e);
    if (models.empty()) models.push_back(base.policy_file);

    std::vector<Result> results;
    std::printf("%-34s %-6s %5s %4s %5s %7s %6s %6s %7s %6s  %-22s %s\n", "model", "pose", "v", "seed", "fell", "t_fall",
                "h_min", "h_mean", "pitch", "vx", "arm ref L(sp,el) R(sp,el)", "arm modes");
    for (const std::string& model : models) {
      for (const std::string& pn : poses) {
        const Pose* pose = nullptr;
        for (const Pose& p : kPoses)
          if (pn == p.name) pose = &p;
        for (const double v : speeds) {
          for (int seed = 0; seed < seeds; ++seed) {
            const Result r = runOne(base, model, *pose, v, seed, hold, payload);
            std::string short_model = model.substr(model.find_last_of('/') + 1);
            std::printf("%-34s %-6s %5.2f %4d %5s %7.2f %6.3f %6.3f %7.3f %6.3f  %5.2f %5.2f %5.2f %5.2f  %s\n",
                        short_model.c_str(), r.pose.c_str(), r.speed, r.seed, r.fell ? "FELL" : "no", r.fall_time,
                        r.min_height, r.mean_height, r.mean_pitch, r.mean_vx, r.arm[0], r.arm[1], r.arm[2], r.arm[3],
                        r.arm_modes.c_str());
            std::fflush(stdout);
            results.push_back(r);
          }
        }
      }
    }
    std::printf("\nsummary (falls / runs; lowest pelvis height of the runs that stood)\n");
    for (const std::string& model : models) {
      int falls = 0, runs = 0;
      double lowest = 10.0;
      for (const Result& r : results)
        if (r.model == model) {
          ++runs;
          falls += r.fell ? 1 : 0;
          if (!r.fell) lowest = std::min(lowest, r.min_height);
        }
      std::printf("  %s: %d / %d falls; lowest pelvis %.3f m\n", model.c_str(), falls, runs, lowest);
    }
    if (!out.empty()) {
      std::ofstream f(out);
      if (!f) throw pmg::ConfigError(out + ": cannot write");
      f << "model,pose,speed,seed,payload,fell,fall_time,min_height,mean_height,mean_pitch,mean_vx,"
           "ref_l_shoulder_pitch,ref_l_elbow,ref_r_shoulder_pitch,ref_r_elbow,arm_modes\n";
      for (const Result& r : results)
        f << r.model << ',' << r.pose << ',' << r.speed << ',' << r.seed << ',' << payload << ',' << (r.fell ? 1 : 0)
          << ',' << r.fall_time << ',' << r.min_height << ',' << r.mean_height << ',' << r.mean_pitch << ','
          << r.mean_vx << ',' << r.arm[0] << ',' << r.arm[1] << ',' << r.arm[2] << ',' << r.arm[3] << ','
          << r.arm_modes << '\n';
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_teleop_arms: %s\n", e.what());
    return 2;
  }
  return 0;
}
