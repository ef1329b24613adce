#include "pmg/motion/posture_synthesis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include "pmg/clips/clip_transforms.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/generator/robot_joint_space.hpp"
#include "pmg/motion/robot_motion.hpp"

namespace pmg::motion {
namespace {

/// Tilt angles of an axis z (W) as postureValues: pitch towards +x, roll towards −y.
double pitchOf(const Eigen::Vector3d& z) { return std::atan2(z.x(), z.z()); }
double rollOf(const Eigen::Vector3d& z) { return std::atan2(-z.y(), z.z()); }

/// Rotation error vector (sin θ · axis) of Ra relative to Rb.
Eigen::Vector3d rotationError(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb) {
  const Eigen::Matrix3d E = Rb.transpose() * Ra;
  return 0.5 * Eigen::Vector3d(E(2, 1) - E(1, 2), E(0, 2) - E(2, 0), E(1, 0) - E(0, 1));
}

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

/// Signed distance of p from the boundary of the convex hull of @p pts (> 0 inside).
double convexHullMargin(std::vector<Eigen::Vector2d> pts, const Eigen::Vector2d& p) {
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Eigen::Vector2d> hull(2 * pts.size());
  std::size_t k = 0;
  for (const auto& q : pts) {  // Andrew's monotone chain, counter-clockwise
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], q) <= 0) --k;
    hull[k++] = q;
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  double margin = std::numeric_limits<double>::infinity();
  bool inside = true;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d a = hull[i], b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2d e = b - a;
    const double side = cross2(a, b, p) / e.norm();  // > 0: left of the edge = inside (CCW)
    if (side < 0) inside = false;
    const double t = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    margin = std::min(margin, (a + t * e - p).norm());
  }
  return inside ? margin : -margin;
}

}  // namespace

struct PostureProbe::Impl {
  LimbChain legs[2];
  LimbChain torso;
  std::unique_ptr<ChainFkWorkspace> ws_leg[2];
  std::unique_ptr<ChainFkWorkspace> ws_torso;
  MjModelPtr mj;
  MjDataPtr md;
  std::vector<int> qpos_adr;  // per robot joint
  std::array<Eigen::Vector3d, 4> soles = g1SolePoints_F();
  Eigen::Vector3d sole_centre = Eigen::Vector3d::Zero();

  Eigen::Isometry3d footPose_B(int f, const Eigen::VectorXd& q) {
    Eigen::Isometry3d X_BF;
    if (!ws_leg[f]->tipPose(q, X_BF)) throw std::runtime_error("PostureProbe: KDL forward kinematics of a leg failed");
    return X_BF;
  }
  Eigen::Matrix3d torso_B(const Eigen::VectorXd& q) {
    Eigen::Isometry3d X_BT;
    if (!ws_torso->tipPose(q, X_BT)) throw std::runtime_error("PostureProbe: KDL forward kinematics pelvis -> torso_link failed");
    return X_BT.linear();
  }
  Eigen::Vector3d com(const Eigen::Isometry3d& X_WB, const Eigen::VectorXd& q) {
    const Eigen::Quaterniond qb(X_WB.linear());
    for (int a = 0; a < 3; ++a) md->qpos[a] = X_WB.translation()(a);
    md->qpos[3] = qb.w();
    md->qpos[4] = qb.x();
    md->qpos[5] = qb.y();
    md->qpos[6] = qb.z();
    for (std::size_t j = 0; j < qpos_adr.size(); ++j) md->qpos[qpos_adr[j]] = q(static_cast<Eigen::Index>(j));
    mj_kinematics(mj.get(), md.get());
    mj_comPos(mj.get(), md.get());
    return {md->subtree_com[0], md->subtree_com[1], md->subtree_com[2]};
  }
};

PostureProbe::PostureProbe(const KinematicModel& model) : model_(&model), impl_(std::make_unique<Impl>()) {
  const RobotConfig& robot = model.config();
  impl_->legs[0] = model.leftLeg();
  impl_->legs[1] = model.rightLeg();
  impl_->torso = model.chain(robot.base_link, "torso_link");
  for (int f = 0; f < 2; ++f) impl_->ws_leg[f] = std::make_unique<ChainFkWorkspace>(impl_->legs[f]);
  impl_->ws_torso = std::make_unique<ChainFkWorkspace>(impl_->torso);
  impl_->mj = loadMujocoModel(robot.mjcf_path);
  impl_->md.reset(mj_makeData(impl_->mj.get()));
  if (impl_->mj->nq < 7 || impl_->mj->jnt_type[0] != mjJNT_FREE)
    throw std::runtime_error(robot.mjcf_path + ": expected a floating base (free joint first) for the centre of mass");
  for (const auto& j : robot.joints) {
    const int id = mj_name2id(impl_->mj.get(), mjOBJ_JOINT, j.name.c_str());
    if (id < 0) throw std::runtime_error(fmt::format("PostureProbe: joint '{}' of the robot config is not in {}", j.name, robot.mjcf_path));
    impl_->qpos_adr.push_back(impl_->mj->jnt_qposadr[id]);
  }
  for (const auto& s : impl_->soles) impl_->sole_centre += 0.25 * s;
}

PostureProbe::~PostureProbe() = default;

PostureProbe::Kinematics PostureProbe::kinematics(const Eigen::Isometry3d& X_WB, const Eigen::VectorXd& q) {
  if (q.size() != static_cast<Eigen::Index>(model_->config().numJoints()) || !q.allFinite())
    throw std::invalid_argument(fmt::format("PostureProbe: q has {} entries (expected {}, finite)", q.size(), model_->config().numJoints()));
  Kinematics k;
  const Eigen::Matrix3d R_WT = X_WB.linear() * impl_->torso_B(q);
  const Eigen::Vector3d z_T = R_WT.col(2);
  k.torso_pitch = pitchOf(z_T);
  k.torso_roll = rollOf(z_T);
  k.torso_yaw = std::atan2(R_WT(1, 0), R_WT(0, 0));
  for (int f = 0; f < 2; ++f) k.X_WF[static_cast<std::size_t>(f)] = X_WB * impl_->footPose_B(f, q);
  k.p_WC = impl_->com(X_WB, q);
  return k;
}

FlatFootPosture PostureProbe::measure(const Eigen::VectorXd& q) {
  if (q.size() != static_cast<Eigen::Index>(model_->config().numJoints()) || !q.allFinite())
    throw std::invalid_argument(fmt::format("PostureProbe: q has {} entries (expected {}, finite)", q.size(), model_->config().numJoints()));
  FlatFootPosture out;
  Eigen::Isometry3d X_BF[2];
  Eigen::Vector3d n_sum = Eigen::Vector3d::Zero();
  for (int f = 0; f < 2; ++f) {
    X_BF[f] = impl_->footPose_B(f, q);
    n_sum += X_BF[f].linear().col(2);
  }
  // Least squares over both feet: min Σ |R n_f − e_z|² ⇔ R maps the mean sole normal onto e_z.
  const Eigen::Matrix3d R_WB = soleLevelingRotation(n_sum, &out.pelvis_pitch, &out.pelvis_roll);
  out.R_WB = Eigen::Quaterniond(R_WB);
  double z_min = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 2; ++f) {
    const Eigen::Vector3d n_W = R_WB * X_BF[f].linear().col(2);
    out.foot_tilt = std::max(out.foot_tilt, std::atan2(n_W.head<2>().norm(), n_W.z()));
    for (const auto& s : impl_->soles) z_min = std::min(z_min, (R_WB * (X_BF[f] * s)).z());
  }
  out.pelvis_height = -z_min;
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.linear() = R_WB;
  X_WB.translation() = Eigen::Vector3d(0, 0, out.pelvis_height);
  const Kinematics k = kinematics(X_WB, q);
  out.torso_pitch = k.torso_pitch;
  out.torso_roll = k.torso_roll;
  out.p_WC = k.p_WC;
  std::vector<Eigen::Vector2d> support;
  for (int f = 0; f < 2; ++f) {
    out.p_WS[static_cast<std::size_t>(f)] = k.X_WF[static_cast<std::size_t>(f)] * impl_->sole_centre;
    for (const auto& s : impl_->soles) support.push_back((k.X_WF[static_cast<std::size_t>(f)] * s).head<2>());
  }
  out.com_margin = convexHullMargin(support, out.p_WC.head<2>());
  return out;
}

void holdJointsAtNeutral(StaticClip& clip, const std::vector<int>& joints) {
  Eigen::Index neutral_row = 0;
  (clip.values.array() - clip.neutral).abs().minCoeff(&neutral_row);
  for (int j : joints) {
    if (j < 0 || j >= clip.q.cols())
      throw std::invalid_argument(fmt::format("holdJointsAtNeutral({}): joint index {} outside [0, {})", clip.name, j, clip.q.cols()));
    clip.q.col(j).setConstant(clip.q(neutral_row, j));
  }
}

double holdTorsoPitch(StaticClip& clip, PostureProbe& probe) {
  const RobotConfig& robot = probe.model().config();
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  if (clip.q.cols() != n)
    throw std::invalid_argument(fmt::format("holdTorsoPitch({}): clip has {} joints, robot config {}", clip.name, clip.q.cols(), n));
  const auto names = robot.jointNames();
  const auto it = std::find(names.begin(), names.end(), "waist_pitch_joint");
  if (it == names.end()) throw std::invalid_argument(fmt::format("holdTorsoPitch({}): robot has no waist_pitch_joint", clip.name));
  const auto wp = static_cast<Eigen::Index>(it - names.begin());
  const double lo = robot.joints[static_cast<std::size_t>(wp)].lower, hi = robot.joints[static_cast<std::size_t>(wp)].upper;
  Eigen::Index neutral_row = 0;
  (clip.values.array() - clip.neutral).abs().minCoeff(&neutral_row);
  const double target = probe.measure(clip.q.row(neutral_row).transpose()).torso_pitch;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < clip.q.rows(); ++i) {
    Eigen::VectorXd q = clip.q.row(i).transpose();
    auto err = [&](double w) {
      q(wp) = w;
      return probe.measure(q).torso_pitch - target;
    };
    // Secant on the waist pitch (torso pitch is nearly linear in it, slope ≈ 1).
    double w0 = q(wp), e0 = err(w0);
    double w1 = std::clamp(w0 - e0, lo, hi), e1 = err(w1);
    for (int iter = 0; iter < 30 && std::abs(e1) > 1e-9; ++iter) {
      const double slope = std::abs(e1 - e0) > 1e-12 ? (e1 - e0) / (w1 - w0) : 1.0;
      const double w2 = std::clamp(w1 - e1 / slope, lo, hi);
      if (w2 == w1) break;  // on a limit
      w0 = w1;
      e0 = e1;
      w1 = w2;
      e1 = err(w1);
    }
    q(wp) = w1;
    clip.q.row(i) = q.transpose();
    worst = std::max(worst, std::abs(e1));
  }
  return worst;
}

void LeanOptions::validate() const {
  if (!(max_roll > 0.0 && max_roll < 0.5)) throw std::invalid_argument(fmt::format("LeanOptions.max_roll = {}: expected in (0, 0.5) [rad]", max_roll));
  if (samples_per_side < 1) throw std::invalid_argument(fmt::format("LeanOptions.samples_per_side = {}: expected >= 1", samples_per_side));
  for (const auto& [v, name] : {std::pair{w_feet, "w_feet"}, std::pair{w_torso, "w_torso"}, std::pair{w_com, "w_com"},
                                std::pair{w_posture, "w_posture"}})
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(fmt::format("LeanOptions.{} = {}: expected finite > 0", name, v));
}

namespace {

/// Residuals of one lean row (see synthesizeLean): params[0] = pelvis position (3), params[1] =
/// the moved joints (m).
class LeanCost {
 public:
  struct Targets {
    std::array<Eigen::Isometry3d, kNumFeet> X_WF;
    Eigen::Vector2d com_xy;
    double roll = 0.0, pitch = 0.0;
    Eigen::VectorXd q_default;
    std::vector<int> moved;
  };
  LeanCost(PostureProbe* probe, const Targets* t, const LeanOptions* o) : probe_(probe), t_(t), o_(o) {}
  int numResiduals() const { return 2 * 6 + 3 + 2 + static_cast<int>(t_->moved.size()); }

  bool operator()(double const* const* params, double* r) const {
    Eigen::VectorXd q = t_->q_default;
    for (std::size_t i = 0; i < t_->moved.size(); ++i) q(t_->moved[i]) = params[1][i];
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = Eigen::Vector3d(params[0][0], params[0][1], params[0][2]);
    const PostureProbe::Kinematics k = probe_->kinematics(X_WB, q);
    int i = 0;
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      const Eigen::Vector3d dp = k.X_WF[f].translation() - t_->X_WF[f].translation();
      const Eigen::Vector3d dr = rotationError(k.X_WF[f].linear(), t_->X_WF[f].linear());
      for (int a = 0; a < 3; ++a) r[i++] = o_->w_feet * dp(a);
      for (int a = 0; a < 3; ++a) r[i++] = o_->w_feet * dr(a);
    }
    r[i++] = o_->w_torso * (k.torso_roll - t_->roll);
    r[i++] = o_->w_torso * (k.torso_pitch - t_->pitch);
    r[i++] = o_->w_torso * k.torso_yaw;
    r[i++] = o_->w_com * (k.p_WC.x() - t_->com_xy.x());
    r[i++] = o_->w_com * (k.p_WC.y() - t_->com_xy.y());
    for (std::size_t j = 0; j < t_->moved.size(); ++j) r[i++] = o_->w_posture * (params[1][j] - t_->q_default(t_->moved[j]));
    return true;
  }

 private:
  PostureProbe* probe_;
  const Targets* t_;
  const LeanOptions* o_;
};

}  // namespace

LeanSynthesis synthesizeLean(PostureProbe& probe, const LeanOptions& options) {
  options.validate();
  const RobotConfig& robot = probe.model().config();
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  const auto names = robot.jointNames();
  if (std::find(names.begin(), names.end(), "waist_roll_joint") == names.end())
    throw std::invalid_argument("synthesizeLean: the robot has no waist_roll_joint");
  LeanCost::Targets t;
  t.q_default = robot.defaultPose();
  // Moved joints: both legs and the waist; arms stay at the default pose.
  const KinematicModel& model = probe.model();
  for (const LimbChain& leg : {model.leftLeg(), model.rightLeg()})
    for (int j : leg.joint_index) t.moved.push_back(j);
  for (const char* w : {"waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint"}) {
    const auto it = std::find(names.begin(), names.end(), w);
    if (it != names.end()) t.moved.push_back(static_cast<int>(it - names.begin()));
  }
  // Standing: the default pose with the feet flat (its pelvis pose from measure()).
  const FlatFootPosture stand = probe.measure(t.q_default);
  Eigen::Isometry3d X_WB0 = Eigen::Isometry3d::Identity();
  X_WB0.linear() = stand.R_WB.toRotationMatrix();
  X_WB0.translation() = Eigen::Vector3d(0, 0, stand.pelvis_height);
  const PostureProbe::Kinematics k0 = probe.kinematics(X_WB0, t.q_default);
  t.X_WF = k0.X_WF;
  t.com_xy = k0.p_WC.head<2>();
  t.pitch = k0.torso_pitch;

  LeanSynthesis out;
  const int K = options.samples_per_side;
  Eigen::MatrixXd rows(K, n);  // positive side, increasing roll
  Eigen::Vector3d base = X_WB0.translation();
  Eigen::VectorXd x(static_cast<Eigen::Index>(t.moved.size()));
  for (std::size_t i = 0; i < t.moved.size(); ++i) x(static_cast<Eigen::Index>(i)) = t.q_default(t.moved[i]);
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  for (int k = 1; k <= K; ++k) {
    t.roll = options.max_roll * k / K;
    auto* functor = new LeanCost(&probe, &t, &options);
    auto* cost = new ceres::DynamicNumericDiffCostFunction<LeanCost, ceres::CENTRAL>(functor);
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(static_cast<int>(x.size()));
    cost->SetNumResiduals(functor->numResiduals());
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, base.data(), x.data());
    for (std::size_t i = 0; i < t.moved.size(); ++i) {
      problem.SetParameterLowerBound(x.data(), static_cast<int>(i), lower(t.moved[i]));
      problem.SetParameterUpperBound(x.data(), static_cast<int>(i), upper(t.moved[i]));
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = 200;
    so.function_tolerance = 1e-14;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-12;
    so.logging_type = ceres::SILENT;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    Eigen::VectorXd q = t.q_default;
    for (std::size_t i = 0; i < t.moved.size(); ++i) q(t.moved[i]) = x(static_cast<Eigen::Index>(i));
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = base;
    const PostureProbe::Kinematics kk = probe.kinematics(X_WB, q);
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      out.max_foot_error = std::max(out.max_foot_error, (kk.X_WF[f].translation() - t.X_WF[f].translation()).norm());
      out.max_foot_tilt = std::max(out.max_foot_tilt, std::asin(std::min(1.0, rotationError(kk.X_WF[f].linear(), t.X_WF[f].linear()).norm())));
    }
    out.max_com_shift = std::max(out.max_com_shift, (kk.p_WC.head<2>() - t.com_xy).norm());
    out.max_roll_error = std::max(out.max_roll_error, std::abs(kk.torso_roll - t.roll));
    if (out.max_foot_error > 2e-3 || out.max_roll_error > 5e-3)
      throw std::runtime_error(fmt::format("synthesizeLean: row roll {:.3f} rad misses its targets (foot error {:.4f} m, roll error "
                                           "{:.4f} rad; Ceres: {})",
                                           t.roll, out.max_foot_error, out.max_roll_error, summary.BriefReport()));
    rows.row(k - 1) = q.transpose();
  }
  // Rows: mirrored negative side (decreasing |roll| → increasing value), neutral, positive side.
  const Eigen::MatrixXd mirrored = mirrorJoints(rows, generatorJointSpace(robot));
  StaticClip& c = out.clip;
  c.name = "lean";
  c.axis = PostureAxis::kRoll;
  c.q.resize(2 * K + 1, n);
  for (int k = 0; k < K; ++k) c.q.row(k) = mirrored.row(K - 1 - k);
  c.q.row(K) = t.q_default.transpose();
  for (int k = 0; k < K; ++k) c.q.row(K + 1 + k) = rows.row(k);
  c.values.resize(2 * K + 1);
  out.min_com_margin = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < c.q.rows(); ++i) {
    const FlatFootPosture m = probe.measure(c.q.row(i).transpose());
    // The default pose is left/right symmetric: its roll is 0 (measured: rounding, ~1e-17).
    c.values(i) = i == K && std::abs(m.torso_roll) < 1e-9 ? 0.0 : m.torso_roll;
    out.max_pitch_change = std::max(out.max_pitch_change, std::abs(m.torso_pitch - stand.torso_pitch));
    out.max_height_change = std::max(out.max_height_change, std::abs(m.pelvis_height - stand.pelvis_height));
    out.min_com_margin = std::min(out.min_com_margin, m.com_margin);
    if (i > 0 && !(c.values(i) > c.values(i - 1)))
      throw std::runtime_error(fmt::format("synthesizeLean: measured torso roll not strictly increasing at row {} ({:.4f} after {:.4f})", i,
                                           c.values(i), c.values(i - 1)));
  }
  c.neutral = c.values(K);
  c.meta.robot = robot.name;
  c.meta.joint_names = names;
  c.meta.source_file = "";
  c.meta.frame_begin = 0;
  c.meta.frame_end = 0;
  c.meta.source_fps = 0.0;
  c.meta.provenance = "synthesized";
  c.meta.retargeting = "posture_ik_v1";
  return out;
}

}  // namespace pmg::motion
