// pmg_gco_eval: foot slip of the PMG templates with and without GCO over a command grid, the
// kinematic consistency of the optimized command, the cost per tick, and a foot-trajectory trace
// for the Fig.-5 plot (scripts/gco_plot.py). See docs/gco.md.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/foot_slip.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/gco/implied_motion.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"

namespace {

using pmg::PostureCommand;
using pmg::VelocityCommand;
using namespace pmg::gco;

struct Command {
  VelocityCommand u_d;
  PostureCommand u_s;
};

struct Outcome {
  FootSlipStats with, without;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(p / 100.0 * v.size())) - 1);
  return v[i];
}

/// GeneratorWithGco (generator, stance sole levelling and stride adaptation when the options enable
/// them, GCO) with its two halves timed separately, and the meters of the measured ticks.
struct Pipeline {
  Pipeline(std::shared_ptr<const pmg::GeneratorModel> model, std::shared_ptr<const LegModel> legs, const GcoOptions& o)
      : g(std::move(model), legs, o), idx(g.legJointIndex()), kin(legs) {
    const auto& names = g.generator().model().jointSpace().joint_names;
    for (std::size_t j = 0; j < names.size(); ++j) {
      if (names[j] == "waist_pitch_joint") waist_pitch = static_cast<int>(j);
      if (names[j] == "waist_roll_joint") waist_roll = static_cast<int>(j);
    }
  }
  /// Reference torso posture beyond the commanded one, per measured tick (docs/policy.md "Reference
  /// torso pitch"): the waist's pitch/roll away from the posture-only pose q_stand + q_s, and the
  /// pelvis pitch that puts the stance soles flat (from their mean normal in B) minus the posture-only
  /// pose's; forward positive [rad].
  void meterPosture() {
    const pmg::GeneratorOutput& o = g.generatorOutput();
    const Eigen::VectorXd& q_stand = g.generator().model().jointSpace().q_stand;
    if (waist_pitch >= 0) waist_pitch_sum += o.q_ref[waist_pitch] - q_stand[waist_pitch] - o.q_posture[waist_pitch];
    if (waist_roll >= 0) waist_roll_sum += o.q_ref[waist_roll] - q_stand[waist_roll] - o.q_posture[waist_roll];
    ++posture_n;
    Eigen::Vector3d n = Eigen::Vector3d::Zero(), n_post = Eigen::Vector3d::Zero();
    for (std::size_t f = 0; f < pmg::kNumFeet; ++f) {
      if (!o.in_contact[f]) continue;
      LegVector q, qp;
      for (int j = 0; j < pmg::gco::kLegDofs; ++j) {
        q(j) = o.q_ref[idx[f][j]];
        qp(j) = q_stand[idx[f][j]] + o.q_posture[idx[f][j]];
      }
      Eigen::Isometry3d X, Xp;
      if (kin.forward(static_cast<pmg::Foot>(f), q, &X) && kin.forward(static_cast<pmg::Foot>(f), qp, &Xp)) {
        n += X.linear().col(2);
        n_post += Xp.linear().col(2);
      }
    }
    if (n.squaredNorm() > 0.0) {
      sole_pitch_sum += std::atan2(-n.x(), n.z()) - std::atan2(-n_post.x(), n_post.z());
      ++sole_n;
    }
  }
  /// The stride adaptation's change of the leg joints this tick (δ_f), metered over measured ticks:
  /// its mean |δ| and largest per-tick step (continuity of the reference) [rad].
  void meterStride(bool first) {
    const auto& sa = g.strideAdaptation();
    if (!sa.enabled()) return;
    for (std::size_t f = 0; f < pmg::kNumFeet; ++f) {
      const LegVector& d = sa.correction(static_cast<pmg::Foot>(f));
      stride_abs_sum += d.cwiseAbs().sum();
      stride_abs_n += pmg::gco::kLegDofs;
      stride_max = std::max(stride_max, d.cwiseAbs().maxCoeff());
      stride_max_command = std::max(stride_max_command, d.cwiseAbs().maxCoeff());
      if (!first) stride_step_max = std::max(stride_step_max, (d - stride_last[f]).cwiseAbs().maxCoeff());
      stride_last[f] = d;
    }
  }
  GeneratorWithGco g;
  double stride_abs_sum = 0.0, stride_max = 0.0, stride_step_max = 0.0, stride_max_command = 0.0;
  long stride_abs_n = 0;
  std::array<LegVector, pmg::kNumFeet> stride_last{LegVector::Zero(), LegVector::Zero()};
  LegJointIndex idx;
  LegKinematics kin;
  int waist_pitch = -1, waist_roll = -1;
  Eigen::Vector3d u_opt_sum = Eigen::Vector3d::Zero();  ///< Σ u' (v_x, v_y, ω) over the measured ticks
  int u_opt_n = 0;
  int saturated_axes = 0;  ///< most axes at their implied-motion table's last amplitude in a measured tick
  double waist_pitch_sum = 0.0, waist_roll_sum = 0.0, sole_pitch_sum = 0.0;
  int posture_n = 0, sole_n = 0;
  double waistPitch() const { return posture_n ? waist_pitch_sum / posture_n : 0.0; }
  double waistRoll() const { return posture_n ? waist_roll_sum / posture_n : 0.0; }
  double solePitch() const { return sole_n ? sole_pitch_sum / sole_n : 0.0; }
};

/// The command the controller's CommandShaper (its `commands:` limits: ranges, the crouched and bent
/// velocity envelopes) settles to when @p c is held for 5 s: what the generator is given in the product path.
Command shapedCommand(const pmg::CommandLimits& limits, const Command& c, double dt) {
  pmg::CommandShaper shaper(limits);
  pmg::CommandSample s;
  s.command = {c.u_d.vx, c.u_d.vy, c.u_d.wz, c.u_s.pitch, c.u_s.roll,
               c.u_s.height > 0.0 ? std::optional<double>(c.u_s.height) : std::nullopt};
  double now = 0.0;
  for (int k = 0; k < static_cast<int>(5.0 / dt); ++k, now += dt) {
    s.velocity_time = s.posture_time = now;
    shaper.update(s, now, dt);
  }
  return {shaper.velocity(), shaper.posture()};
}

/// Runs one command for warm-up + measured ticks; meters the measured part and records timings.
FootSlipStats run(Pipeline& pipe, FootSlipMeter& meter, const Command& c, double dt, int warmup_ticks,
                  int measure_ticks, std::vector<double>* tick_us, std::vector<double>* gco_us, bool posture = false) {
  pipe.g.reset(0.0);
  meter.reset();
  pipe.u_opt_sum.setZero();
  pipe.u_opt_n = 0;
  pipe.saturated_axes = 0;
  pipe.waist_pitch_sum = pipe.waist_roll_sum = pipe.sole_pitch_sum = 0.0;
  pipe.posture_n = pipe.sole_n = 0;
  pipe.stride_max_command = 0.0;
  for (int k = 0; k < warmup_ticks + measure_ticks; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    pipe.g.stepReference(c.u_d, c.u_s, dt);
    const auto t1 = std::chrono::steady_clock::now();
    const GcoResult& res = pipe.g.solveGco();
    const auto t2 = std::chrono::steady_clock::now();
    if (k >= warmup_ticks) {
      if (tick_us) tick_us->push_back(std::chrono::duration<double, std::micro>(t2 - t0).count());
      if (gco_us) gco_us->push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
      meter.add(pipe.g.gcoInput(), res.u_opt);
      pipe.u_opt_sum += Eigen::Vector3d(res.u_opt.v_x, res.u_opt.v_y, res.u_opt.yaw_rate);
      ++pipe.u_opt_n;
      pipe.saturated_axes = std::max(pipe.saturated_axes, pipe.g.generatorOutput().amplitude_saturated);
      if (posture) pipe.meterPosture();
      pipe.meterStride(k == warmup_ticks);
    }
  }
  return meter.stats();
}

void writeTrace(const std::string& path, const FootSlipMeter& with, const FootSlipMeter& without) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write the trace CSV");
  f << "t,variant,foot,contact,x,y,z,speed\n";
  for (int variant = 0; variant < 2; ++variant) {
    const auto& tr = variant == 0 ? without.trace() : with.trace();
    for (const auto& s : tr) {
      for (std::size_t ft = 0; ft < pmg::kNumFeet; ++ft) {
        f << s.t << ',' << (variant == 0 ? "without_gco" : "with_gco") << ',' << (ft == 0 ? "left" : "right") << ','
          << (s.contact[ft] ? 1 : 0) << ',' << s.p_WS[ft].x() << ',' << s.p_WS[ft].y() << ',' << s.p_WS[ft].z() << ','
          << s.v_WS_H[ft].head<2>().norm() << '\n';
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Foot slip of PMG templates with and without GCO over a command grid (issue 4)"};
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string clips_dir = pmg::resolveData("config/clips/g1").string();
  std::string gco_config;
  std::string out_dir;
  double seconds = 5.0, warmup = 2.0, dt = 0.01;  // the grid of docs/gco.md
  std::vector<double> vx{-0.6, -0.3, 0.0, 0.3, 0.6, 0.9}, vy{0.0, 0.3}, wz{-0.6, 0.0, 0.6};
  std::vector<double> pitch{0.0, 0.2}, roll{0.0, 0.1}, height{0.0, 0.70};
  std::vector<double> trace{0.6, 0.0, 0.0}, trace_posture{0.0, 0.0, 0.0};
  std::string blending = "consistent";
  double max_cadence_ratio = pmg::GeneratorParams{}.max_cadence_ratio;
  bool envelope = false;
  std::string controller_path;
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--clips", clips_dir, "clip directory")->check(CLI::ExistingDirectory)->capture_default_str();
  app.add_option("--gco-config", gco_config, "GcoOptions YAML (defaults if omitted)")->check(CLI::ExistingFile);
  app.add_option("--out-dir", out_dir, "write gco_grid.csv and gco_trace.csv here");
  app.add_option("--seconds", seconds, "measured time per command [s]")->check(CLI::Range(1.0, 120.0));
  app.add_option("--warmup", warmup, "warm-up time per command [s]")->check(CLI::Range(0.0, 60.0));
  app.add_option("--vx", vx, "grid values of v_x [m/s]");
  app.add_option("--vy", vy, "grid values of v_y [m/s]");
  app.add_option("--wz", wz, "grid values of the yaw rate [rad/s]");
  app.add_option("--pitch", pitch, "grid values of the pitch command [rad]");
  app.add_option("--roll", roll, "grid values of the roll command [rad]");
  app.add_option("--height", height, "grid values of the height command [m] (0 = standing height)");
  app.add_option("--trace", trace, "command (v_x v_y ω) whose foot trajectories go to gco_trace.csv")->expected(3);
  app.add_option("--trace-posture", trace_posture, "posture (pitch roll height) of the traced command")->expected(3);
  app.add_option("--max-cadence-ratio", max_cadence_ratio,
                 "consistent blending: at most this much faster cadence where a stride saturates (1 = eq. 12's period)")
      ->check(CLI::Range(1.0, 2.0))
      ->capture_default_str();
  app.add_option("--blending", blending, "generator blending: consistent | paper (PMG eqs. 4-7)")
      ->check(CLI::IsMember({"consistent", "paper"}))
      ->capture_default_str();
  app.add_flag("--envelope", envelope,
               "the command envelope of issue 12 instead of the grid options: v_x -0.5..1.0, v_y -0.4..0.4, w -0.8..0.8 "
               "and their combinations (9 x 7 x 7 values, mostly off the consistency map's grid), posture pitch "
               "{-0.1, 0, 0.3}, roll {0, 0.15}, height {standing, 0.66, 0.62}");
  bool upright_walking = false, sole_levelling = false, stride_adaptation = false;
  app.add_flag("--upright-walking", upright_walking,
               "remove the walking clips' mean waist lean (GeneratorParams::upright_walking; beyond the paper)");
  app.add_flag("--sole-levelling", sole_levelling,
               "level the reference's stance soles before GCO (GcoOptions::sole_levelling; beyond the paper)");
  app.add_flag("--stride-adaptation", stride_adaptation,
               "hold the reference's stance soles still under the command before GCO (GcoOptions::stride_adaptation; "
               "beyond the paper)");
  auto* controller_opt = app.add_option(
      "--controller", controller_path,
      "evaluate the product path: this controller config's robot, clips, generator and GCO settings, and each "
      "command shaped by its `commands:` limits (ranges, crouched velocity envelope) as pmg_controller shapes it; "
      "the target is then checked against the shaped command, and commands the shaper slowed are counted")
      ->check(CLI::ExistingFile);
  for (const char* o : {"--robot", "--clips", "--gco-config", "--max-cadence-ratio", "--blending", "--upright-walking",
                        "--sole-levelling", "--stride-adaptation"})
    controller_opt->excludes(app.get_option(o));
  CLI11_PARSE(app, argc, argv);
  if (envelope) {
    // Mostly between the consistency map's grid points (docs/generator.md), so interpolation is
    // measured too; the envelope's ends are included.
    vx = {-0.5, -0.3, -0.1, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0};
    vy = {-0.4, -0.3, -0.1, 0.0, 0.1, 0.3, 0.4};
    wz = {-0.8, -0.6, -0.2, 0.0, 0.2, 0.6, 0.8};
    pitch = {-0.1, 0.0, 0.3};
    roll = {0.0, 0.15};
    height = {0.0, 0.66, 0.62};
  }

  try {
    std::optional<pmg::ControllerConfig> controller;
    if (!controller_path.empty()) {
      controller = pmg::loadControllerConfig(controller_path);
      clips_dir = controller->clips_dir;
    }
    const pmg::RobotConfig robot = controller ? controller->robot : pmg::loadRobotConfig(robot_path);
    pmg::ClipLibrary clips = pmg::loadClipLibrary(clips_dir, robot);
    for (const auto& c : clips.dynamic_clips) {
      if (!c.implied.empty()) continue;
      std::printf("clip %s has no implied_motion table: computing the tables of all clips (pmg_clip_implied)\n", c.name.c_str());
      addImpliedMotion(&clips, robot);
      break;
    }
    pmg::GeneratorParams gen_params = controller ? controller->generator : pmg::GeneratorParams{};
    if (!controller) {
      gen_params.blending = blending == "paper" ? pmg::Blending::kPaper : pmg::Blending::kConsistent;
      gen_params.max_cadence_ratio = max_cadence_ratio;
      gen_params.upright_walking = upright_walking;
    }
    auto gen_model = std::make_shared<const pmg::GeneratorModel>(clips, pmg::generatorJointSpace(robot), gen_params);
    std::printf("blending: %s, max cadence ratio %.2f, upright walking %s\n",
                gen_params.blending == pmg::Blending::kPaper ? "paper" : "consistent", gen_params.max_cadence_ratio,
                gen_params.upright_walking ? "on" : "off");
    pmg::CommandLimits limits;
    if (controller) {
      // As ControllerApp does: "no height command" is the squat clip's neutral height.
      limits = controller->commands;
      if (const pmg::StaticClip* squat = gen_model->staticClip(pmg::PostureAxis::kHeight)) limits.standing_height = squat->neutral;
      if (const std::string e = limits.validate(); !e.empty()) throw std::runtime_error(controller->source_file + ": " + e);
      char floor[32] = "off";
      if (limits.walking_min_height > 0.0) std::snprintf(floor, sizeof floor, "%.3f m", limits.walking_min_height);
      std::printf("product path: %s (commands shaped by its limits; crouched envelope %s; bent envelope %s; walking height "
                  "floor %s)\n",
                  controller_path.c_str(), limits.crouched_height > 0.0 ? "on" : "off", limits.bent_pitch > 0.0 ? "on" : "off",
                  floor);
    }
    auto legs = LegModel::fromRobotConfig(robot);
    GcoOptions on = controller ? controller->gco : (gco_config.empty() ? GcoOptions{} : loadGcoOptionsFile(gco_config));
    on.enabled = true;
    on.dt = dt;
    if (!controller) {
      on.sole_levelling.enabled = sole_levelling;
      on.stride_adaptation.enabled = stride_adaptation;
    }
    std::printf("stance sole levelling %s, stride adaptation %s\n", on.sole_levelling.enabled ? "on" : "off",
                on.stride_adaptation.enabled ? "on" : "off");
    GcoOptions off = on;
    off.enabled = false;
    Pipeline pipe_on(gen_model, legs, on), pipe_off(gen_model, legs, off);
    LegKinematics cycle_kin(legs);
    FootSlipMeter meter_on(legs, dt, on.ground_height), meter_off(legs, dt, on.ground_height);
    const int warm = static_cast<int>(std::lround(warmup / dt)), meas = static_cast<int>(std::lround(seconds / dt));

    std::printf("clips: %zu dynamic, %zu static from %s\n", clips.dynamic_clips.size(), clips.static_clips.size(),
                clips_dir.c_str());
    for (const auto& c : clips.dynamic_clips) std::printf("  dynamic %s\n", c.name.c_str());
    for (const auto& c : clips.static_clips) std::printf("  static  %s\n", c.name.c_str());
    std::printf("\n%6s %5s %5s %5s %5s %5s | %4s | %8s %8s | %8s %8s | %7s %7s | %7s %7s %7s\n", "vx", "vy", "wz", "pitch",
                "roll", "h", "st", "spd0", "spdG", "slip0", "slipG", "herr0", "herrG", "vx_im", "vy_im", "w_im");
    std::printf("%6s %5s %5s %5s %5s %5s | %4s | %8s %8s | %8s %8s | %7s %7s | %7s %7s %7s\n", "m/s", "m/s", "rad/s",
                "rad", "rad", "m", "", "mm/s", "mm/s", "mm", "mm", "mm", "mm", "m/s", "m/s", "rad/s");

    std::ofstream grid_csv;
    if (!out_dir.empty()) {
      grid_csv.open(out_dir + "/gco_grid.csv");
      if (!grid_csv) throw std::runtime_error(out_dir + "/gco_grid.csv: cannot write");
      grid_csv << "vx,vy,wz,pitch,roll,height,stances,speed_without,speed_with,slip_without,slip_with,"
                  "height_err_without,height_err_with,max_height_err_with,implied_vx_with,implied_vx_without,"
                  "ss_speed_without,ss_speed_with,ds_speed_without,ds_speed_with,cycle_implied_vx,cycle_implied_vy,"
                  "cycle_implied_wz,within_target,saturated_axes,target_vx,target_vy,target_wz,"
                  "waist_pitch_lean,waist_roll_lean,stance_sole_pitch\n";
    }
    std::vector<double> tick_us, gco_us;
    tick_us.reserve(2000000);
    gco_us.reserve(2000000);
    double sum_slip0 = 0, sum_slipG = 0, sum_spd0 = 0, sum_spdG = 0, sum_h0 = 0, sum_hG = 0, max_hG = 0;
    double sum_cons0 = 0, sum_consG = 0, sum_ss0 = 0, sum_ssG = 0, sum_ds0 = 0, sum_dsG = 0;
    int n_walk = 0, n_all = 0, n_within = 0, n_outside_saturated = 0, n_slowed = 0, n_slowed_within = 0;
    double slowed_share_sum = 0.0;
    double axis_err[3] = {0, 0, 0}, uopt_err[3] = {0, 0, 0};
    int axis_ok[3] = {0, 0, 0};
    struct Miss { double vx, vy, wz, pitch, roll, h, ix, iy, iw; };
    std::vector<Miss> worst;
    std::vector<double> h_sum0(height.size(), 0.0), h_sumG(height.size(), 0.0);
    std::vector<int> h_n(height.size(), 0);
    std::uint64_t failures = 0, jump_limited = 0, ticks = 0;
    std::uint64_t stride_counts[5] = {0, 0, 0, 0, 0};  // ticks, speed-, offset-limited, unreached foot-ticks, failures
    double lean_sum[3] = {0, 0, 0}, lean_max[3] = {0, 0, 0};  // waist pitch, waist roll, stance-sole pitch
    int n_lean = 0;
    for (double a : vx)
      for (double b : vy)
        for (double w : wz)
          for (double p : pitch)
            for (double r : roll)
              for (double h : height) {
                const Command user{{a, b, w}, {p, r, h}};
                // The product path: the generator is given the shaped command, and the target is the
                // shaped command (what the controller promises); slowed commands are counted apart.
                const Command c = controller ? shapedCommand(limits, user, dt) : user;
                const bool slowed = controller && (std::fabs(c.u_d.vx - a) > 1e-9 || std::fabs(c.u_d.vy - b) > 1e-9 ||
                                                   std::fabs(c.u_d.wz - w) > 1e-9);
                const FootSlipStats s0 = run(pipe_off, meter_off, c, dt, warm, meas, nullptr, nullptr);
                const FootSlipStats sG = run(pipe_on, meter_on, c, dt, warm, meas, &tick_us, &gco_us, true);
                const bool walking = std::fabs(c.u_d.vx) + std::fabs(c.u_d.vy) + std::fabs(c.u_d.wz) > 1e-9;
                if (walking) {
                  const double lean[3] = {pipe_on.waistPitch(), pipe_on.waistRoll(), pipe_on.solePitch()};
                  for (int k = 0; k < 3; ++k) {
                    lean_sum[k] += lean[k];
                    lean_max[k] = std::max(lean_max[k], std::fabs(lean[k]));
                  }
                  ++n_lean;
                }
                // Issue 12 target: the stance-implied velocity within ±10 % of the command, or within
                // 0.03 m/s / 0.05 rad/s when that is larger (only commands with complete stances).
                // Reference-implied motion: the exact cycle mean (cycleImpliedVelocity), the quantity the
                // consistent blending targets; the slip meter's window means are not whole cycles.
                const Eigen::Vector3d cyc = cycleImpliedVelocity(pipe_on.g.generator(), cycle_kin, pipe_on.idx, c.u_d, c.u_s);
                const double implied[3] = {cyc.x(), cyc.y(), cyc.z()};
                const double cmd[3] = {c.u_d.vx, c.u_d.vy, c.u_d.wz};
                const double abs_tol[3] = {0.03, 0.03, 0.05};
                const Eigen::Vector3d u_opt = pipe_on.u_opt_sum / std::max(1, pipe_on.u_opt_n);
                for (int ax = 0; ax < 3; ++ax) uopt_err[ax] += std::fabs(u_opt[ax] - cmd[ax]);
                bool within = true;
                for (int ax = 0; ax < 3; ++ax) {
                  const double err = std::fabs(implied[ax] - cmd[ax]);
                  const bool ok = err <= std::max(0.1 * std::fabs(cmd[ax]), abs_tol[ax]);
                  axis_err[ax] += err;
                  axis_ok[ax] += ok ? 1 : 0;
                  within = within && ok;
                }
                n_within += within ? 1 : 0;
                if (slowed) {
                  ++n_slowed;
                  n_slowed_within += within ? 1 : 0;
                  const double user_norm = std::hypot(a, b, w);
                  slowed_share_sum += user_norm > 0 ? std::hypot(cmd[0], cmd[1], cmd[2]) / user_norm : 1.0;
                }
                n_outside_saturated += (!within && pipe_on.saturated_axes > 0) ? 1 : 0;
                if (!within && worst.size() < 400)
                  worst.push_back({cmd[0], cmd[1], cmd[2], p, r, h, implied[0], implied[1], implied[2]});
                failures += pipe_on.g.gco().counters().solver_failures;
                if (pipe_on.g.gco().counters().solver_failures > 0) {
                  std::printf("  (GCO solver failures for this command: %llu)\n",
                              static_cast<unsigned long long>(pipe_on.g.gco().counters().solver_failures));
                }
                jump_limited += pipe_on.g.gco().counters().jump_limited;
                const pmg::gco::StrideAdaptationCounters& sc = pipe_on.g.strideAdaptation().counters();
                stride_counts[0] += sc.ticks;
                stride_counts[1] += sc.speed_limited;
                stride_counts[2] += sc.offset_limited;
                stride_counts[3] += sc.unreached;
                stride_counts[4] += sc.failures;
                if (sc.unreached > 0 || sc.failures > 0)
                  std::printf("  (stride adaptation for this command: %llu of %llu foot-ticks unreached, %llu failures, "
                              "largest |δ| %.3f rad)\n",
                              static_cast<unsigned long long>(sc.unreached), static_cast<unsigned long long>(2 * sc.ticks),
                              static_cast<unsigned long long>(sc.failures), pipe_on.stride_max_command);
                ticks += pipe_on.g.gco().counters().ticks;
                std::printf("%6.2f %5.2f %5.2f %5.2f %5.2f %5.2f | %4d | %8.1f %8.2f | %8.1f %8.2f | %7.2f %7.3f | %7.3f %7.3f %7.3f %s\n",
                            a, b, w, p, r, h, sG.stances, 1e3 * s0.mean_stance_speed, 1e3 * sG.mean_stance_speed,
                            1e3 * s0.mean_slip_per_stance, 1e3 * sG.mean_slip_per_stance, 1e3 * s0.mean_height_error,
                            1e3 * sG.mean_height_error, implied[0], implied[1], implied[2], within ? (slowed ? "s" : "") : (slowed ? "*s" : "*"));
                if (grid_csv) {
                  grid_csv << a << ',' << b << ',' << w << ',' << p << ',' << r << ',' << h << ',' << sG.stances << ','
                           << s0.mean_stance_speed << ',' << sG.mean_stance_speed << ',' << s0.mean_slip_per_stance
                           << ',' << sG.mean_slip_per_stance << ',' << s0.mean_height_error << ','
                           << sG.mean_height_error << ',' << sG.max_height_error << ',' << sG.mean_implied_v_x << ','
                           << s0.mean_implied_v_x << ',' << s0.mean_single_support_speed << ','
                           << sG.mean_single_support_speed << ',' << s0.mean_double_support_speed << ','
                           << sG.mean_double_support_speed << ',' << implied[0] << ',' << implied[1] << ','
                           << implied[2] << ',' << (within ? 1 : 0) << ',' << pipe_on.saturated_axes << ',' << cmd[0] << ','
                           << cmd[1] << ',' << cmd[2] << ',' << pipe_on.waistPitch() << ',' << pipe_on.waistRoll() << ','
                           << pipe_on.solePitch() << '\n';
                }
                ++n_all;
                const auto hi = static_cast<std::size_t>(std::find(height.begin(), height.end(), h) - height.begin());
                h_sum0[hi] += s0.mean_height_error;
                h_sumG[hi] += sG.mean_height_error;
                ++h_n[hi];
                sum_spd0 += s0.mean_stance_speed;
                sum_spdG += sG.mean_stance_speed;
                sum_h0 += s0.mean_height_error;
                sum_ss0 += s0.mean_single_support_speed;
                sum_ssG += sG.mean_single_support_speed;
                sum_ds0 += s0.mean_double_support_speed;
                sum_dsG += sG.mean_double_support_speed;
                sum_hG += sG.mean_height_error;
                max_hG = std::max(max_hG, sG.max_height_error);
                if (sG.stances > 0) {
                  ++n_walk;
                  sum_slip0 += s0.mean_slip_per_stance;
                  sum_slipG += sG.mean_slip_per_stance;
                }
                // Kinematic consistency: |base velocity implied by the stance feet − u' (GCO) or template|.
                sum_cons0 += s0.mean_implied_velocity_error;
                sum_consG += sG.mean_implied_velocity_error;
              }

    std::printf("\nsummary over %d commands (%d with complete stances):\n", n_all, n_walk);
    std::printf("  mean stance-foot speed  without GCO %8.2f mm/s   with GCO %8.3f mm/s   reduction %5.1f %%\n",
                1e3 * sum_spd0 / n_all, 1e3 * sum_spdG / n_all, 100.0 * (1.0 - sum_spdG / std::max(sum_spd0, 1e-12)));
    if (n_walk > 0) {
      std::printf("  mean slip per stance    without GCO %8.2f mm     with GCO %8.3f mm     reduction %5.1f %%\n",
                  1e3 * sum_slip0 / n_walk, 1e3 * sum_slipG / n_walk,
                  100.0 * (1.0 - sum_slipG / std::max(sum_slip0, 1e-12)));
    }
    std::printf("    single support only   without GCO %8.2f mm/s   with GCO %8.3f mm/s\n", 1e3 * sum_ss0 / n_all,
                1e3 * sum_ssG / n_all);
    std::printf("    double support only   without GCO %8.2f mm/s   with GCO %8.3f mm/s\n", 1e3 * sum_ds0 / n_all,
                1e3 * sum_dsG / n_all);
    std::printf("  stance height error     without GCO %8.2f mm     with GCO %8.3f mm (max %.3f mm)\n",
                1e3 * sum_h0 / n_all, 1e3 * sum_hG / n_all, 1e3 * max_hG);
    for (std::size_t i = 0; i < height.size(); ++i)
      if (h_n[i] > 0)
        std::printf("    height command %-8s    without GCO %8.2f mm     with GCO %8.3f mm (%d commands)\n",
                    height[i] > 0.0 ? (std::to_string(height[i]).substr(0, 4) + " m").c_str() : "standing",
                    1e3 * h_sum0[i] / h_n[i], 1e3 * h_sumG[i] / h_n[i], h_n[i]);
    std::printf("  kinematic consistency: mean |v implied by stance feet - commanded v|: without %.3f m/s, with %.3f m/s\n",
                sum_cons0 / n_all, sum_consG / n_all);
    std::printf("  implied velocity vs command, per axis (mean |implied - command|; within ±10 %% or 0.03 m/s / 0.05 rad/s):\n"
                "    v_x %.3f m/s (%d/%d within)   v_y %.3f m/s (%d/%d)   w %.3f rad/s (%d/%d)   all axes within: %d/%d commands\n",
                axis_err[0] / n_all, axis_ok[0], n_all, axis_err[1] / n_all, axis_ok[1], n_all, axis_err[2] / n_all, axis_ok[2],
                n_all, n_within, n_all);
    std::printf("  outside the target: %d commands, %d of them with an amplitude at its table's end (amplitude_saturated)\n",
                n_all - n_within, n_outside_saturated);
    if (controller)
      std::printf("  product path: %d of %d commands slowed by the controller's limits (to %.0f %% of the commanded "
                  "speed on average; target checked against the shaped command: %d/%d within); %d/%d unslowed within\n",
                  n_slowed, n_all, n_slowed > 0 ? 100.0 * slowed_share_sum / n_slowed : 100.0, n_slowed_within, n_slowed,
                  n_within - n_slowed_within, n_all - n_slowed);
    if (n_lean > 0)
      std::printf("  reference torso beyond the posture, walking commands (%d; docs/policy.md \"Reference torso pitch\"):\n"
                  "    waist pitch lean mean %+.3f rad (largest |.| %.3f), waist roll lean mean %+.3f (%.3f), "
                  "pelvis pitch that puts the stance soles flat mean %+.3f (%.3f)\n",
                  n_lean, lean_sum[0] / n_lean, lean_max[0], lean_sum[1] / n_lean, lean_max[1], lean_sum[2] / n_lean,
                  lean_max[2]);
    std::printf("  GCO's u' vs command: mean |u' - u|: v_x %.3f m/s   v_y %.3f m/s   w %.3f rad/s (what the full-PMG policy is told)\n",
                uopt_err[0] / n_all, uopt_err[1] / n_all, uopt_err[2] / n_all);
    for (std::size_t i = 0; i < std::min<std::size_t>(worst.size(), 12); ++i)
      std::printf("    outside: target (%.2f, %.2f, %.2f | %.2f %.2f %.2f) implied (%.3f, %.3f, %.3f)\n", worst[i].vx, worst[i].vy,
                  worst[i].wz, worst[i].pitch, worst[i].roll, worst[i].h, worst[i].ix, worst[i].iy, worst[i].iw);
    if (on.stride_adaptation.enabled) {
      std::printf("  stride adaptation: mean |δ| %.4f rad, largest |δ| %.3f rad, largest per-tick step of δ %.4f rad "
                  "(measured ticks); over all %llu ticks: speed-limited %llu, offset-limited %llu, unreached %llu "
                  "foot-ticks, failures %llu\n",
                  pipe_on.stride_abs_sum / std::max(1L, pipe_on.stride_abs_n), pipe_on.stride_max, pipe_on.stride_step_max,
                  static_cast<unsigned long long>(stride_counts[0]), static_cast<unsigned long long>(stride_counts[1]),
                  static_cast<unsigned long long>(stride_counts[2]), static_cast<unsigned long long>(stride_counts[3]),
                  static_cast<unsigned long long>(stride_counts[4]));
    }
    std::printf("  GCO solver failures %llu, jump-limited ticks %llu of %llu\n",
                static_cast<unsigned long long>(failures), static_cast<unsigned long long>(jump_limited),
                static_cast<unsigned long long>(ticks));
    std::printf("  cost per tick (this machine, %zu ticks): GCO solve p50 %.1f us  p99 %.1f us  max %.1f us\n",
                gco_us.size(), percentile(gco_us, 50), percentile(gco_us, 99), percentile(gco_us, 100));
    std::printf("                                   generator+GCO p50 %.1f us  p99 %.1f us  max %.1f us\n",
                percentile(tick_us, 50), percentile(tick_us, 99), percentile(tick_us, 100));

    if (!out_dir.empty()) {
      const Command c{{trace[0], trace[1], trace[2]}, {trace_posture[0], trace_posture[1], trace_posture[2]}};
      run(pipe_off, meter_off, c, dt, warm, 300, nullptr, nullptr);
      run(pipe_on, meter_on, c, dt, warm, 300, nullptr, nullptr);
      writeTrace(out_dir + "/gco_trace.csv", meter_on, meter_off);
      std::printf("wrote %s/gco_grid.csv and %s/gco_trace.csv\n", out_dir.c_str(), out_dir.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_gco_eval: %s\n", e.what());
    return 1;
  }
  return 0;
}
