// pmg_generator_vectors: runs the C++ PMG generator (include/pmg/generator/generator.hpp) over a
// fixed command schedule and writes inputs and outputs as JSON, for the Python/JAX port used in
// training (training/pmg_train/pmg_generator.py) to prove equality (test/policy: pmg_port_*).
//
//   build-policy/bin/pmg_generator_vectors --out /tmp/vectors.json            # synthetic clips
//   build-policy/bin/pmg_generator_vectors --clips config/clips/g1/*.yaml --out v.json
//   build-policy/bin/pmg_generator_vectors --clips config/clips/g1 --out v.json    # folder (+ consistency map)
//
// Both blendings (GeneratorParams::blending) run the same command schedule from the same initial
// phase: the top-level "ticks" use "blending" (consistent, the default; GCO runs on it), and
// "paper": {"blending": "paper", "ticks": [...]} the paper's eqs. 4-7 (the ablation), and
// "levelled": {"sole_levelling": true, "upright_walking": true, "ticks": [...]} the consistent blending
// with GeneratorParams::upright_walking and the stance soles levelled (GcoOptions::sole_levelling,
// include/pmg/gco/sole_levelling.hpp), and "adapted": {"stride_adaptation": true, "ticks": [...]} the
// consistent blending with the stride adaptation (include/pmg/gco/stride_adaptation.hpp). A file named
// consistency_map.yaml among --clips (or in a --clips folder) is the library's consistency map.
// The JSON holds everything the port needs: the joint space (from the robot config), the
// generator parameters, the clips as given to GeneratorModel (missing directions are derived by
// both implementations), dt, and per tick the commands and every GeneratorOutput field.
// Since the full-PMG training configuration, the document also carries GCO (PMG eqs. 13-19):
// the KDL leg chains (pelvis -> sole, one entry per segment: pose at q = 0, joint axis and
// origin in the segment's base frame), the resolved GCO options (--gco file), forward-kinematics
// checks at random leg configurations, and per tick GeneratorWithGco's result (u', Δ, s_f), so
// the JAX GCO port (training/pmg_train/gco.py) is proven equal the same way.
// Synthetic clips (default) are smooth periodic joint trajectories around the default pose,
// declared provenance "synthesized"; they exercise every code path (time reversal, mirroring,
// all three static axes, clamping) independently of the motion-preprocessing clips. For the
// command-consistent blending, three of them carry implied_motion tables (nonlinear in the
// amplitude, with off-axis drift, so the Gauss-Seidel solve has to cancel drift with the opposite
// clip of another axis), one has none (the linear fallback), and a small synthetic consistency map
// (grid sizes 4, 2, 3, 3) corrects the command.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/clips/clip_io.hpp"

namespace {

using pmg::CommandAxis;
using pmg::PostureAxis;

class Json {
 public:
  explicit Json(std::FILE* f) : f_(f) {}
  void num(double v) { std::fprintf(f_, "%.17g", std::isfinite(v) ? v : 0.0); }
  void vec(const Eigen::VectorXd& v) {
    std::fputc('[', f_);
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      if (i) std::fputc(',', f_);
      num(v[i]);
    }
    std::fputc(']', f_);
  }
  template <typename C>
  void list(const C& c) {
    std::fputc('[', f_);
    bool first = true;
    for (const auto& v : c) {
      if (!first) std::fputc(',', f_);
      first = false;
      num(static_cast<double>(v));
    }
    std::fputc(']', f_);
  }
  void mat(const Eigen::MatrixXd& m) {
    std::fputc('[', f_);
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
      if (r) std::fputc(',', f_);
      vec(m.row(r).transpose());
    }
    std::fputc(']', f_);
  }
  void key(const char* k) { std::fprintf(f_, "\"%s\":", k); }
  void raw(const char* s) { std::fputs(s, f_); }

 private:
  std::FILE* f_;
};

pmg::DynamicClip syntheticDynamic(const pmg::GeneratorJointSpace& js, const char* name, CommandAxis axis,
                                  int direction, double nominal, double period, int samples, double seed) {
  const auto n = static_cast<Eigen::Index>(js.joint_names.size());
  pmg::DynamicClip c;
  c.name = name;
  c.axis = axis;
  c.direction = direction;
  c.nominal_scale = nominal;
  c.period = period;
  c.q.resize(samples, n);
  c.qd.resize(samples, n);
  c.v_base.resize(samples, 3);
  c.omega_base.resize(samples, 3);
  c.base_height.resize(samples);
  const double w = 2.0 * M_PI / period;
  for (int k = 0; k < samples; ++k) {
    const double ph = 2.0 * M_PI * k / samples;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double amp = 0.05 + 0.15 * std::fabs(std::sin(1.7 * static_cast<double>(j) + seed));
      const double off = 0.4 * static_cast<double>(j) + seed;
      const double mid = 0.5 * (js.lower[j] + js.upper[j]);
      const double q0 = js.q_stand[j] + 0.02 * (mid - js.q_stand[j]);
      c.q(k, j) = std::clamp(q0 + amp * std::sin(ph + off), js.lower[j] + 1e-3, js.upper[j] - 1e-3);
      c.qd(k, j) = amp * w * std::cos(ph + off);
    }
    const double s = direction * nominal;
    c.v_base.row(k) << (axis == CommandAxis::kForward ? s : 0.0) + 0.05 * std::sin(2 * ph),
        (axis == CommandAxis::kLateral ? s : 0.0) + 0.03 * std::sin(ph + seed), 0.01 * std::cos(2 * ph);
    c.omega_base.row(k) << 0.05 * std::sin(ph), 0.04 * std::cos(ph + seed),
        (axis == CommandAxis::kYaw ? s : 0.0) + 0.02 * std::sin(ph);
    c.base_height[k] = js.standing_base_height - 0.02 + 0.01 * std::sin(2 * ph + seed);
  }
  c.contact[0] = {0.25 + 0.01 * seed, 0.27};
  c.contact[1] = {0.74 - 0.01 * seed, 0.29};
  c.meta.joint_names = js.joint_names;
  c.meta.provenance = "synthesized";
  c.meta.notes = "pmg_generator_vectors test clip";
  return c;
}

pmg::StaticClip syntheticStatic(const pmg::GeneratorJointSpace& js, const char* name, PostureAxis axis,
                                std::vector<double> values, double neutral, double seed) {
  const auto n = static_cast<Eigen::Index>(js.joint_names.size());
  pmg::StaticClip s;
  s.name = name;
  s.axis = axis;
  s.values = Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  s.neutral = neutral;
  s.q.resize(s.values.size(), n);
  for (Eigen::Index k = 0; k < s.values.size(); ++k) {
    const double d = s.values[k] - neutral;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double g = std::sin(0.9 * static_cast<double>(j) + seed) + 0.3 * d;
      s.q(k, j) = std::clamp(js.q_stand[j] + 1.2 * d * g, js.lower[j] + 1e-3, js.upper[j] - 1e-3);
    }
  }
  s.meta.joint_names = js.joint_names;
  s.meta.provenance = "synthesized";
  return s;
}

/// Synthetic implied_motion table: own axis grows as scale·(a − curve·a²) (strictly: curve < 0.25, a ≤ 2),
/// off-axis drift linear in a (drift = per-unit (v_x, v_y, ω)).
void addSyntheticImplied(pmg::DynamicClip& c, double curve, const Eigen::Vector3d& drift) {
  const double amps[] = {0.0, 0.4, 0.9, 1.4, 2.0};
  const Eigen::Index K = 5;
  c.implied.amplitude.resize(K);
  c.implied.velocity.resize(K, 3);
  const auto axis = static_cast<Eigen::Index>(c.axis);
  for (Eigen::Index k = 0; k < K; ++k) {
    const double a = amps[k];
    c.implied.amplitude[k] = a;
    c.implied.velocity.row(k) = (a * drift).transpose();
    c.implied.velocity(k, axis) = c.direction * 0.9 * c.nominal_scale * (a - curve * a * a);
  }
}

/// Synthetic consistency map over v_x (4), v_y (2), ω (3), height (3), pitch (2): a smooth Δu.
pmg::ConsistencyMap syntheticConsistencyMap() {
  pmg::ConsistencyMap m;
  m.grid[0] = (Eigen::VectorXd(4) << -0.6, 0.0, 0.5, 1.2).finished();
  m.grid[1] = (Eigen::VectorXd(2) << -0.4, 0.4).finished();
  m.grid[2] = (Eigen::VectorXd(3) << -0.9, 0.1, 0.9).finished();
  m.grid[3] = (Eigen::VectorXd(3) << 0.58, 0.68, 0.76).finished();
  m.grid[4] = (Eigen::VectorXd(2) << 0.0, 0.35).finished();
  m.delta.resize(4 * 2 * 3 * 3 * 2, 3);
  for (Eigen::Index i = 0; i < 4; ++i)
    for (Eigen::Index j = 0; j < 2; ++j)
      for (Eigen::Index k = 0; k < 3; ++k)
        for (Eigen::Index l = 0; l < 3; ++l)
          for (Eigen::Index p = 0; p < 2; ++p) {
          const double vx = m.grid[0][i], vy = m.grid[1][j], wz = m.grid[2][k], h = m.grid[3][l], pitch = m.grid[4][p];
          const Eigen::Index row = (((i * 2 + j) * 3 + k) * 3 + l) * 2 + p;
          m.delta(row, 0) = 0.06 * vx * wz - 0.3 * (h - 0.74) * vx + 0.01 * static_cast<double>(k) + 0.1 * pitch * vx;
          m.delta(row, 1) = 0.05 * vx * wz + 0.04 * vy * static_cast<double>(i);
          m.delta(row, 2) = -0.08 * vx * vy + 0.05 * wz * (h - 0.6) + 0.02 * static_cast<double>(l);
        }
  return m;
}

/// Leg chains, resolved GCO options and FK checks (see the file comment).
void writeGcoModel(Json& j, std::FILE* f, const pmg::gco::LegModel& legs, const pmg::gco::GcoOptions& o) {
  j.key("gco_options");
  std::fprintf(f, "{\"enabled\":%s,", o.enabled ? "true" : "false");
  const std::pair<const char*, double> fields[] = {
      {"dt", o.dt}, {"ground_height", o.ground_height}, {"w_foot_velocity", o.w_foot_velocity},
      {"w_foot_yaw_rate", o.w_foot_yaw_rate}, {"w_foot_height", o.w_foot_height},
      {"w_prior_velocity", o.w_prior_velocity}, {"w_prior_yaw_rate", o.w_prior_yaw_rate},
      {"w_prior_height", o.w_prior_height}, {"w_smooth_velocity", o.w_smooth_velocity},
      {"w_smooth_yaw_rate", o.w_smooth_yaw_rate}, {"w_smooth_height", o.w_smooth_height}, {"w_limit", o.w_limit},
      {"contact_ramp_time", o.contact_ramp_time}, {"max_jump_velocity", o.max_jump_velocity},
      {"max_jump_yaw_rate", o.max_jump_yaw_rate}, {"max_jump_height", o.max_jump_height}};
  for (const auto& [k, v] : fields) {
    j.key(k);
    j.num(v);
    j.raw(",");
  }
  j.key("sole_levelling");
  std::fprintf(f, "{\"edge_fraction\":%.17g,\"iterations\":%d,\"max_correction\":%.17g},",
               o.sole_levelling.edge_fraction, o.sole_levelling.iterations, o.sole_levelling.max_correction);
  const pmg::gco::StrideAdaptationOptions& sa = o.stride_adaptation;
  j.key("stride_adaptation");
  std::fprintf(f,
               "{\"touchdown_lead\":%.17g,\"return_fraction\":%.17g,\"standing_time_constant\":%.17g,\"standing_hold\":%s,"
               "\"stepping_margin\":%.17g,\"max_offset\":%.17g,\"max_offset_height\":%.17g,\"max_offset_yaw\":%.17g,"
               "\"max_offset_speed\":%.17g,\"max_offset_yaw_rate\":%.17g,\"iterations\":%d,\"max_correction\":%.17g,"
               "\"height_weight\":%.17g,\"damping\":%.17g,\"max_correction_rate\":%.17g,\"sole_half_length\":%.17g,"
               "\"rolling_slope\":%.17g},",
               sa.touchdown_lead, sa.return_fraction, sa.standing_time_constant, sa.standing_hold ? "true" : "false",
               sa.stepping_margin, sa.max_offset,
               sa.max_offset_height, sa.max_offset_yaw, sa.max_offset_speed, sa.max_offset_yaw_rate, sa.iterations,
               sa.max_correction, sa.height_weight, sa.damping, sa.max_correction_rate, sa.sole_half_length,
               sa.rolling_slope);
  j.key("limits_lo");
  j.list(std::vector<double>{o.limits.v_x_min, o.limits.v_y_min, o.limits.yaw_rate_min, o.limits.height_min});
  j.raw(",");
  j.key("limits_hi");
  j.list(std::vector<double>{o.limits.v_x_max, o.limits.v_y_max, o.limits.yaw_rate_max, o.limits.height_max});
  j.raw("},");
  j.key("leg_chains");
  j.raw("[");
  for (std::size_t foot = 0; foot < pmg::kNumFeet; ++foot) {
    const KDL::Chain& chain = legs.chain(static_cast<pmg::Foot>(foot));
    j.raw(foot ? ",[" : "[");
    for (unsigned sidx = 0; sidx < chain.getNrOfSegments(); ++sidx) {
      const KDL::Segment& seg = chain.getSegment(sidx);
      const KDL::Joint& jt = seg.getJoint();
      const KDL::Frame X = seg.pose(0.0);
      Eigen::MatrixXd T = Eigen::MatrixXd::Identity(4, 4);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) T(r, c) = X.M(r, c);
        T(r, 3) = X.p(r);
      }
      const bool moving = jt.getType() != KDL::Joint::None;
      const KDL::Vector axis = moving ? jt.JointAxis() : KDL::Vector::Zero();
      const KDL::Vector origin = moving ? jt.JointOrigin() : KDL::Vector::Zero();
      j.raw(sidx ? ",{" : "{");
      std::fprintf(f, "\"joint\":\"%s\",\"revolute\":%s,", jt.getName().c_str(), moving ? "true" : "false");
      j.key("pose0"); j.mat(T); j.raw(",");
      j.key("axis"); j.list(std::vector<double>{axis.x(), axis.y(), axis.z()}); j.raw(",");
      j.key("origin"); j.list(std::vector<double>{origin.x(), origin.y(), origin.z()}); j.raw("}");
    }
    j.raw("]");
  }
  j.raw("],");
  // FK checks: sole position, velocity and foot angular velocity in the pelvis frame.
  pmg::gco::LegKinematics kin(std::shared_ptr<const pmg::gco::LegModel>(&legs, [](const pmg::gco::LegModel*) {}));
  j.key("fk_checks");
  j.raw("[");
  for (int k = 0; k < 8; ++k) {
    const std::size_t foot = static_cast<std::size_t>(k % 2);
    pmg::gco::LegVector q, qd;
    for (int i = 0; i < pmg::gco::kLegDofs; ++i) {
      q(i) = 0.4 * std::sin(1.3 * k + 0.7 * i);
      qd(i) = 2.0 * std::cos(0.9 * k + 1.1 * i);
    }
    pmg::gco::FootKinematics fk;
    kin.compute(static_cast<pmg::Foot>(foot), q, qd, &fk);
    std::fprintf(f, "%s{\"foot\":%zu,", k ? "," : "", foot);
    j.key("q"); j.vec(q); j.raw(",");
    j.key("qd"); j.vec(qd); j.raw(",");
    j.key("p_BS_B"); j.vec(fk.p_BS_B); j.raw(",");
    j.key("v_BS_B"); j.vec(fk.v_BS_B); j.raw(",");
    j.key("w_BF_B"); j.vec(fk.w_BF_B); j.raw("}");
  }
  j.raw("],");
}

/// Command schedule: kScheduleSegments segments covering standing, every axis and sign,
/// combinations, clamping (and amplitude saturation), posture axes, height "no command" (0),
/// walking crouched / bent, and smooth transitions between them.
constexpr int kScheduleSegments = 17;
void commandAt(int tick, int ticks_per_segment, pmg::VelocityCommand& u_d, pmg::PostureCommand& u_s) {
  static const double table[][6] = {
      // vx, vy, wz, pitch, roll, height
      {0.0, 0.0, 0.0, 0.0, 0.0, 0.0},   {0.6, 0.0, 0.0, 0.0, 0.0, 0.0},   {1.2, 0.0, 0.0, 0.0, 0.0, 0.0},
      {-0.5, 0.0, 0.0, 0.0, 0.0, 0.0},  {0.0, 0.4, 0.0, 0.0, 0.0, 0.0},   {0.0, -0.5, 0.0, 0.0, 0.0, 0.0},
      {0.0, 0.0, 0.8, 0.0, 0.0, 0.0},   {0.0, 0.0, -1.0, 0.0, 0.0, 0.0},  {0.5, 0.2, 0.5, 0.1, -0.1, 0.70},
      {2.0, -1.0, 2.0, 0.0, 0.0, 0.0},  {0.0, 0.0, 0.0, 0.4, 0.0, 0.62}, {0.0, 0.0, 0.0, -0.3, 0.25, 0.50},
      {-0.3, 0.3, -0.4, 0.8, -0.5, 0.9}, {0.02, -0.01, 0.03, 0.0, 0.0, 0.0},
      {0.8, -0.3, -0.6, 0.3, 0.0, 0.64}, {-0.4, -0.2, 0.7, -0.1, 0.15, 0.76}, {0.0, 0.0, 0.5, 0.0, 0.0, 0.66}};
  constexpr int kSegments = sizeof(table) / sizeof(table[0]);
  static_assert(kSegments == kScheduleSegments, "kScheduleSegments");
  const int seg = (tick / ticks_per_segment) % kSegments;
  const int next = (seg + 1) % kSegments;
  const double t = static_cast<double>(tick % ticks_per_segment) / ticks_per_segment;
  const double blend = t < 0.7 ? 0.0 : (t - 0.7) / 0.3;  // hold, then ramp to the next segment
  double v[6];
  for (int i = 0; i < 6; ++i) v[i] = (1 - blend) * table[seg][i] + blend * table[next][i];
  u_d = {v[0], v[1], v[2]};
  u_s = {v[3], v[4], v[5]};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Emit PMG generator test vectors (JSON) for the Python port"};
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string(), out = "pmg_vectors.json";
  std::vector<std::string> clip_files;
  int ticks = 850;  // 17 segments x 50 ticks, per blending
  std::string gco_path = pmg::resolveData("config/gco/g1.yaml").string();
  double dt = 0.01, phase0 = 0.3;
  app.add_option("--robot", robot_path, "robot config YAML")->capture_default_str();
  app.add_option("--clips", clip_files, "clip files or one clip folder (default: synthetic clips); "
                                      "consistency_map.yaml among them is the consistency map");
  app.add_option("--out", out, "output JSON file");
  app.add_option("--ticks", ticks, "generator ticks")->check(CLI::Range(1, 1000000));
  app.add_option("--dt", dt, "tick period [s]")->check(CLI::PositiveNumber);
  app.add_option("--phase0", phase0, "initial phase")->check(CLI::Range(0.0, 1.0));
  app.add_option("--gco", gco_path, "GCO options YAML (the controller's)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const pmg::GeneratorJointSpace js = pmg::generatorJointSpace(robot);
    pmg::ClipLibrary lib;
    if (clip_files.size() == 1 && std::filesystem::is_directory(clip_files[0])) {
      lib = pmg::loadClipLibrary(clip_files[0], robot);
    } else if (!clip_files.empty()) {
      std::vector<std::string> files, maps;
      for (const auto& f : clip_files)
        (std::filesystem::path(f).filename() == pmg::kConsistencyMapFile ? maps : files).push_back(f);
      if (maps.size() > 1) throw std::runtime_error("--clips: more than one " + std::string(pmg::kConsistencyMapFile));
      lib = pmg::loadClipLibrary(files, robot);
      if (!maps.empty()) lib.consistency = pmg::readConsistencyMap(maps[0]);
    } else {
      lib.dynamic_clips.push_back(syntheticDynamic(js, "walk_forward", CommandAxis::kForward, 1, 0.8, 0.9, 40, 0.0));
      addSyntheticImplied(lib.dynamic_clips.back(), 0.12, Eigen::Vector3d(0.0, 0.05, -0.1));
      lib.dynamic_clips.push_back(syntheticDynamic(js, "walk_left", CommandAxis::kLateral, 1, 0.35, 0.8, 33, 1.0));
      addSyntheticImplied(lib.dynamic_clips.back(), 0.2, Eigen::Vector3d(-0.04, 0.0, 0.15));
      lib.dynamic_clips.push_back(syntheticDynamic(js, "turn_left", CommandAxis::kYaw, 1, 0.7, 1.1, 48, 2.0));
      addSyntheticImplied(lib.dynamic_clips.back(), 0.15, Eigen::Vector3d(0.06, 0.08, 0.0));
      lib.dynamic_clips.push_back(syntheticDynamic(js, "turn_right", CommandAxis::kYaw, -1, 0.6, 1.0, 45, 3.0));  // no table
      lib.consistency = syntheticConsistencyMap();
      lib.static_clips.push_back(syntheticStatic(js, "squat", PostureAxis::kHeight, {0.55, 0.65, 0.72, js.standing_base_height},
                                                 js.standing_base_height, 0.5));
      lib.static_clips.push_back(syntheticStatic(js, "bend", PostureAxis::kPitch, {-0.2, 0.0, 0.3, 0.6}, 0.0, 1.5));
      lib.static_clips.push_back(syntheticStatic(js, "lean", PostureAxis::kRoll, {-0.3, 0.0, 0.3}, 0.0, 2.5));
    }
    const pmg::GeneratorParams params;  // blending: kConsistent
    pmg::GeneratorParams paper_params = params;
    paper_params.blending = pmg::Blending::kPaper;
    auto model = std::make_shared<const pmg::GeneratorModel>(lib, js, params);
    auto paper_model = std::make_shared<const pmg::GeneratorModel>(lib, js, paper_params);
    const auto legs = pmg::gco::LegModel::fromRobotConfig(robot);
    pmg::gco::GcoOptions gco_options = pmg::gco::loadGcoOptionsFile(gco_path);
    gco_options.enabled = true;
    pmg::gco::GeneratorWithGco gen(model, legs, gco_options);
    pmg::gco::GeneratorWithGco paper_gen(paper_model, legs, gco_options);
    pmg::gco::GcoOptions levelled_options = gco_options;
    levelled_options.sole_levelling.enabled = true;
    pmg::GeneratorParams upright_params = params;
    upright_params.upright_walking = true;
    auto upright_model = std::make_shared<const pmg::GeneratorModel>(lib, js, upright_params);
    pmg::gco::GeneratorWithGco levelled_gen(upright_model, legs, levelled_options);
    pmg::gco::GcoOptions adapted_options = gco_options;
    adapted_options.stride_adaptation.enabled = true;
    pmg::gco::GeneratorWithGco adapted_gen(model, legs, adapted_options);

    std::FILE* f = std::fopen(out.c_str(), "w");
    if (f == nullptr) throw std::runtime_error(out + ": cannot open for writing");
    Json j(f);
    j.raw("{");
    j.key("generator");
    j.raw("\"include/pmg/generator/generator.hpp\",");
    j.key("joint_names");
    j.raw("[");
    for (std::size_t i = 0; i < js.joint_names.size(); ++i) std::fprintf(f, "%s\"%s\"", i ? "," : "", js.joint_names[i].c_str());
    j.raw("],");
    j.key("q_stand"); j.vec(js.q_stand); j.raw(",");
    j.key("lower"); j.vec(js.lower); j.raw(",");
    j.key("upper"); j.vec(js.upper); j.raw(",");
    j.key("mirror_index"); j.list(js.mirror_index); j.raw(",");
    j.key("mirror_sign"); j.list(js.mirror_sign); j.raw(",");
    j.key("standing_base_height"); j.num(js.standing_base_height); j.raw(",");
    j.key("epsilon"); j.num(params.epsilon); j.raw(",");
    j.key("max_cadence_ratio"); j.num(params.max_cadence_ratio); j.raw(",");
    j.key("max_command"); j.list(params.max_command); j.raw(",");
    j.key("blending"); j.raw("\"consistent\",");
    j.key("consistency_map");
    if (lib.consistency.empty()) {
      j.raw("null,");
    } else {
      const char* keys[pmg::kConsistencyMapDims] = {"vx", "vy", "wz", "height", "pitch"};
      j.raw("{");
      for (std::size_t d = 0; d < pmg::kConsistencyMapDims; ++d) {
        j.key(keys[d]);
        j.vec(lib.consistency.grid[d]);
        j.raw(",");
      }
      j.key("delta"); j.mat(lib.consistency.delta); j.raw("},");
    }
    j.key("dynamic_clips");
    j.raw("[");
    for (std::size_t i = 0; i < lib.dynamic_clips.size(); ++i) {
      const auto& c = lib.dynamic_clips[i];
      std::fprintf(f, "%s{\"name\":\"%s\",\"axis\":%d,\"direction\":%d,", i ? "," : "", c.name.c_str(), static_cast<int>(c.axis), c.direction);
      j.key("nominal_scale"); j.num(c.nominal_scale); j.raw(",");
      j.key("period"); j.num(c.period); j.raw(",");
      j.key("q"); j.mat(c.q); j.raw(",");
      j.key("qd"); j.mat(c.qd); j.raw(",");
      j.key("v_base"); j.mat(c.v_base); j.raw(",");
      j.key("omega_base"); j.mat(c.omega_base); j.raw(",");
      j.key("base_height"); j.vec(c.base_height); j.raw(",");
      j.key("implied_motion");
      if (c.implied.empty()) {
        j.raw("null,");
      } else {
        j.raw("{");
        j.key("amplitude"); j.vec(c.implied.amplitude); j.raw(",");
        j.key("velocity"); j.mat(c.implied.velocity); j.raw("},");
      }
      j.key("contact");
      std::fprintf(f, "[[%.17g,%.17g],[%.17g,%.17g]]}", c.contact[0].mu, c.contact[0].sigma, c.contact[1].mu, c.contact[1].sigma);
    }
    j.raw("],");
    j.key("static_clips");
    j.raw("[");
    for (std::size_t i = 0; i < lib.static_clips.size(); ++i) {
      const auto& s = lib.static_clips[i];
      std::fprintf(f, "%s{\"name\":\"%s\",\"axis\":%d,", i ? "," : "", s.name.c_str(), static_cast<int>(s.axis));
      j.key("values"); j.vec(s.values); j.raw(",");
      j.key("neutral"); j.num(s.neutral); j.raw(",");
      j.key("q"); j.mat(s.q); j.raw("}");
    }
    j.raw("],");
    writeGcoModel(j, f, *legs, gco_options);
    j.key("leg_joint_index");
    j.raw("[");
    for (std::size_t foot = 0; foot < pmg::kNumFeet; ++foot) {
      j.raw(foot ? "," : "");
      j.list(gen.legJointIndex()[foot]);
    }
    j.raw("],");
    j.key("dt"); j.num(dt); j.raw(",");
    j.key("phase0"); j.num(phase0); j.raw(",");
    const int per_segment = std::max(1, ticks / kScheduleSegments);
    int saturated_ticks = 0, opposite_ticks = 0;
    const auto writeTicks = [&](pmg::gco::GeneratorWithGco& g) {
      g.reset(phase0);
      j.raw("[\n");
      for (int t = 0; t < ticks; ++t) {
        pmg::VelocityCommand u_d;
        pmg::PostureCommand u_s;
        commandAt(t, per_segment, u_d, u_s);
        const pmg::gco::GcoResult& r = g.step(u_d, u_s, dt);
        const pmg::GeneratorOutput& o = g.generatorOutput();
        if (&g == &gen) {
          saturated_ticks += o.amplitude_saturated > 0;
          for (std::size_t i = 0; i < pmg::kNumCommandAxes; ++i)
            if (o.amplitude[i] > 0 && o.clip_direction[i] != (u_d[i] < 0 ? -1 : 1)) {
              ++opposite_ticks;
              break;
            }
        }
        j.raw(t ? ",\n{" : "{");
        j.key("u_d"); j.list(std::vector<double>{u_d.vx, u_d.vy, u_d.wz}); j.raw(",");
        j.key("u_s"); j.list(std::vector<double>{u_s.pitch, u_s.roll, u_s.height}); j.raw(",");
        j.key("phase"); j.num(o.phase); j.raw(",");
        j.key("next_phase"); j.num(o.next_phase); j.raw(",");
        j.key("period"); j.num(o.period); j.raw(",");
        j.key("q_ref"); j.vec(o.q_ref); j.raw(",");
        j.key("qd_ref"); j.vec(o.qd_ref); j.raw(",");
        j.key("alpha"); j.list(o.alpha); j.raw(",");
        j.key("weight"); j.list(o.weight); j.raw(",");
        j.key("amplitude"); j.list(o.amplitude); j.raw(",");
        j.key("clip_direction"); j.list(o.clip_direction); j.raw(",");
        j.key("amplitude_saturated"); j.num(o.amplitude_saturated); j.raw(",");
        j.key("command_correction"); j.list(o.command_correction); j.raw(",");
        j.key("standing_weight"); j.num(o.standing_weight); j.raw(",");
        j.key("beta"); j.list(o.beta); j.raw(",");
        j.key("contact_mu"); j.list(std::vector<double>{o.contact[0].mu, o.contact[1].mu}); j.raw(",");
        j.key("contact_sigma"); j.list(std::vector<double>{o.contact[0].sigma, o.contact[1].sigma}); j.raw(",");
        j.key("in_contact"); j.list(std::vector<double>{o.in_contact[0] ? 1.0 : 0.0, o.in_contact[1] ? 1.0 : 0.0}); j.raw(",");
        j.key("v_base"); j.vec(o.v_base); j.raw(",");
        j.key("omega_base"); j.vec(o.omega_base); j.raw(",");
        j.key("yaw_rate"); j.num(o.yaw_rate); j.raw(",");
        j.key("base_height"); j.num(o.base_height); j.raw(",");
        j.key("clamped_joints"); j.num(o.clamped_joints); j.raw(",");
        j.key("gco_u_opt");
        j.list(std::vector<double>{r.u_opt.v_x, r.u_opt.v_y, r.u_opt.yaw_rate, r.u_opt.pitch, r.u_opt.roll, r.u_opt.height});
        j.raw(",");
        j.key("gco_delta"); j.vec(r.delta); j.raw(",");
        j.key("gco_s"); j.list(r.contact_weight); j.raw(",");
        j.key("gco_status"); j.num(static_cast<double>(r.status)); j.raw("}");
      }
      j.raw("]");
    };
    j.key("ticks");
    writeTicks(gen);
    j.raw(",");
    j.key("paper");
    j.raw("{\"blending\":\"paper\",");
    j.key("ticks");
    writeTicks(paper_gen);
    j.raw("},");
    // The consistent blending with the stance soles levelled (sole_levelling.hpp).
    j.key("levelled");
    j.raw("{\"sole_levelling\":true,\"upright_walking\":true,");
    j.key("ticks");
    writeTicks(levelled_gen);
    j.raw("},");
    // The consistent blending with the stride adaptation (stride_adaptation.hpp).
    j.key("adapted");
    j.raw("{\"stride_adaptation\":true,");
    j.key("ticks");
    writeTicks(adapted_gen);
    j.raw("}");
    j.raw("}\n");
    std::fclose(f);
    std::printf("wrote %d ticks x 4 (consistent, paper, consistent + upright walking + levelled soles, consistent + "
                "stride adaptation), %zu dynamic + %zu static clips%s to %s; "
                "consistent: %d ticks with a saturated amplitude, %d playing a clip of the other sign than u_i\n",
                ticks, lib.dynamic_clips.size(), lib.static_clips.size(),
                lib.consistency.empty() ? "" : " + consistency map", out.c_str(), saturated_ticks, opposite_ticks);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
