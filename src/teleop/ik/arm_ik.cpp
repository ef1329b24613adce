#include "pmg/teleop/arm_ik.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/jntarray.hpp>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "pmg/common/config_error.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"

namespace pmg::teleop {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec7 = Eigen::Matrix<double, kArmDofs, 1>;
using Mat66 = Eigen::Matrix<double, 6, 6>;
using Mat67 = Eigen::Matrix<double, 6, kArmDofs>;

constexpr const char* kRootLink = "torso_link";
constexpr std::array<const char*, 2> kHandLinks{"left_rubber_hand", "right_rubber_hand"};
constexpr std::array<const char*, kArmDofs> kJointSuffixes{
    "shoulder_pitch_joint", "shoulder_roll_joint", "shoulder_yaw_joint", "elbow_joint",
    "wrist_roll_joint",     "wrist_pitch_joint",   "wrist_yaw_joint"};

/// Fraction of the way back to the margin that a pair inside it must gain per iteration (the
/// linearised constraint of a pair at d < d_s is d + ∇d·Δq ≥ d + kRecovery (d_s − d)).
constexpr double kRecovery = 0.2;
/// Line search: halvings of a step that would bring a pair too close before the step is dropped.
constexpr int kLineSearchHalvings = 4;
/// Sweeps of the cyclic projection onto the collision half-spaces.
constexpr int kProjectionSweeps = 4;
/// Passes of the joint-limit active set (each may pin more joints to their bounds).
constexpr int kActiveSetPasses = 8;
constexpr int kMaxPairs = 32;
/// An iteration that keeps more than this fraction of the weighted error counts as stalled.
constexpr double kStallRatio = 0.99;
/// Consecutive stalled iterations after which an arm stops for this solve.
constexpr int kStallIterations = 2;
/// μ²: regularisation of the "undamped" inverse of J Jᵀ (null-space projector) [m²].
constexpr double kSingularEps = 1e-10;

/// One collision pair: arm capsule (arm_a, cap_a) against a body capsule (arm_b = −1) or a
/// capsule of the other arm.
struct Pair {
  int arm_a = 0;
  int cap_a = 0;
  int arm_b = -1;
  int cap_b = 0;
};

/// Kinematic state of one arm at one q: everything in T.
struct ArmState {
  ArmJoints q{};
  Eigen::Vector3d p_TH = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_TH = Eigen::Matrix3d::Identity();
  std::array<Eigen::Vector3d, kArmDofs> axis{};                       ///< joint axis (unit) in T
  std::array<Eigen::Vector3d, kArmDofs> origin{};                     ///< a point on the joint axis in T [m]
  std::array<std::array<Eigen::Vector3d, 2>, kNumArmCapsules> cap{};  ///< capsule ends in T [m]
};

/// Distance of one pair at one state.
struct PairState {
  double d = 0.0;                                 ///< surface distance [m]
  Eigen::Vector3d c_a = Eigen::Vector3d::Zero();  ///< closest point on capsule a's segment, T
  Eigen::Vector3d c_b = Eigen::Vector3d::Zero();  ///< ... on capsule b's segment, T
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();   ///< unit direction b → a, T
};

struct Constraint {
  std::array<Vec7, 2> g;  ///< gradient of the pair distance w.r.t. each arm's Δq
  double c = 0.0;         ///< g·Δq ≥ c
  double g2 = 0.0;        ///< |g|²
};

bool finite(const ArmJoints& q) noexcept {
  for (double v : q) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

double rotationAngle(const Eigen::Matrix3d& R) noexcept {
  const double c = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
  return std::acos(c);
}

}  // namespace

const char* toString(ArmIkStatus status) noexcept {
  switch (status) {
    case ArmIkStatus::kConverged:
      return "converged";
    case ArmIkStatus::kMaxIterations:
      return "max_iterations";
    case ArmIkStatus::kUnreachableClamped:
      return "unreachable_clamped";
    case ArmIkStatus::kInvalidTarget:
      return "invalid_target";
    case ArmIkStatus::kInactive:
      return "inactive";
  }
  return "unknown";
}

std::string ArmIkOptions::validate() const {
  auto bad = [](const char* field, double v, const char* range) {
    return std::string("ArmIkOptions.") + field + " = " + std::to_string(v) + ": expected " + range;
  };
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (max_iterations < 1 || max_iterations > 1000) return bad("max_iterations", max_iterations, "1..1000");
  if (!in(damping, 0.0, 1.0)) return bad("damping", damping, "0..1 m");
  if (!in(singular_value_threshold, 1e-6, 1.0)) {
    return bad("singular_value_threshold", singular_value_threshold, "1e-6..1 m");
  }
  if (!in(error_damping, 0.0, 100.0)) return bad("error_damping", error_damping, "0..100");
  if (!in(position_weight, 1e-6, 1e3)) return bad("position_weight", position_weight, "1e-6..1e3");
  if (!in(orientation_weight, 0.0, 1e3)) return bad("orientation_weight", orientation_weight, "0..1e3 m/rad");
  if (!in(nullspace_gain, 0.0, 1.0)) return bad("nullspace_gain", nullspace_gain, "0..1");
  if (!in(max_joint_step, 1e-6, 100.0)) return bad("max_joint_step", max_joint_step, "1e-6..100 rad");
  if (!in(max_iteration_step, 1e-6, 10.0)) return bad("max_iteration_step", max_iteration_step, "1e-6..10 rad");
  if (!in(position_tolerance, 1e-9, 0.1)) return bad("position_tolerance", position_tolerance, "1e-9..0.1 m");
  if (!in(orientation_tolerance, 1e-9, 1.0)) {
    return bad("orientation_tolerance", orientation_tolerance, "1e-9..1 rad");
  }
  if (!in(collision_margin, 0.0, 0.1)) return bad("collision_margin", collision_margin, "0..0.1 m");
  if (!in(collision_activation, collision_margin, 0.5) || collision_activation <= collision_margin) {
    return bad("collision_activation", collision_activation, "> collision_margin, <= 0.5 m");
  }
  if (max_restarts < 0 || max_restarts > 1000) return bad("max_restarts", max_restarts, "0..1000");
  if (!in(workspace_margin, 0.0, 0.5)) return bad("workspace_margin", workspace_margin, "0..0.5");
  if (!in(quaternion_norm_tolerance, 0.0, 0.5)) {
    return bad("quaternion_norm_tolerance", quaternion_norm_tolerance, "0..0.5");
  }
  return "";
}

struct ArmIk::Impl {
  /// Model and KDL workspace of one arm. Not movable: the KDL solvers keep a reference to `chain`.
  struct Arm {
    KDL::Chain chain;
    std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
    KDL::JntArray jq;
    std::vector<KDL::Frame> frames;                      ///< (segments) link frames in T, sized at setup
    std::array<int, kArmDofs> joint_segment{};           ///< chain segment holding each joint
    std::array<int, kNumArmCapsules> capsule_segment{};  ///< chain segment each capsule is fixed in
    std::array<int, kArmDofs> joint_index{};
    ArmJoints nominal{}, lower{}, upper{};
    Eigen::Vector3d shoulder = Eigen::Vector3d::Zero();
    double reach = 0.0;
    double min_reach = 0.0;
  };

  ArmIkOptions opt;
  ArmCapsuleModel caps;
  std::array<Arm, 2> arms;
  std::array<Pair, kMaxPairs> pairs{};
  int num_pairs = 0;

  // Workspace of solve().
  std::array<ArmState, 2> cur{}, trial{};
  std::array<PairState, kMaxPairs> cur_pairs{}, trial_pairs{};
  std::array<Constraint, kMaxPairs> constraints{};
  std::array<Eigen::Vector3d, 2> p_target{};  ///< p*_TH after the workspace clamp [m]
  std::array<Eigen::Matrix3d, 2> R_target{};  ///< R*_TH
  std::array<Vec7, 2> box_lo{}, box_hi{};     ///< hard bounds of this solve: limits ∩ seed ± max_joint_step
  /// Per arm: last estimate of the direction of σ_min of J_w Jᵀ_w (warm start of the inverse iteration).
  std::array<Vec6, 2> v_min{Vec6::Constant(1.0 / std::sqrt(6.0)), Vec6::Constant(1.0 / std::sqrt(6.0))};

  /// DLS iterations of the arms in `solving` from the state in cur / cur_pairs (results: counters).
  void iterate(const std::array<bool, 2>& solving, std::array<ArmIkResult, 2>& results) noexcept;
  /// w_p |p* − p| + w_o angle(R* Rᵀ) of arm h at cur.
  double weightedError(int h) const noexcept;
  bool converged(int h) const noexcept;
  // Scratch of the const queries (forwardKinematics, minCapsuleDistance): they use the KDL workspace
  // too, so the class is not thread-safe (documented).
  std::array<ArmState, 2> scratch{};
  std::array<PairState, kMaxPairs> scratch_pairs{};

  /// FK of all links of arm h at q into st. False if KDL reports an error.
  bool kinematics(int h, const ArmJoints& q, ArmState& st) noexcept {
    Arm& a = arms[h];
    st.q = q;
    for (int j = 0; j < kArmDofs; ++j) a.jq(j) = q[j];
    if (a.fk->JntToCart(a.jq, a.frames) < 0) return false;
    for (int j = 0; j < kArmDofs; ++j) {
      const int s = a.joint_segment[j];
      const KDL::Frame F = s == 0 ? KDL::Frame::Identity() : a.frames[s - 1];
      const KDL::Joint& joint = a.chain.getSegment(s).getJoint();
      const KDL::Vector o = F * joint.JointOrigin();
      const KDL::Vector ax = F.M * joint.JointAxis();
      st.origin[j] = Eigen::Vector3d(o.x(), o.y(), o.z());
      st.axis[j] = Eigen::Vector3d(ax.x(), ax.y(), ax.z()).normalized();
    }
    for (int c = 0; c < kNumArmCapsules; ++c) {
      const KDL::Frame& F = a.frames[a.capsule_segment[c]];
      const Capsule& cap = caps.arm[h][c];
      for (int e = 0; e < 2; ++e) {
        const Eigen::Vector3d& local = e == 0 ? cap.a : cap.b;
        const KDL::Vector w = F * KDL::Vector(local.x(), local.y(), local.z());
        st.cap[c][e] = Eigen::Vector3d(w.x(), w.y(), w.z());
      }
    }
    const KDL::Frame& X = a.frames.back();
    st.p_TH = Eigen::Vector3d(X.p.x(), X.p.y(), X.p.z());
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) st.R_TH(r, c) = X.M(r, c);
    }
    return true;
  }

  /// Distances of all pairs at the states st. exact = false: a pair whose bounding spheres are
  /// farther apart than collision_activation gets that lower bound as its distance (no closest
  /// points); both uses in the solve (constraint activation, line-search floor) only need to
  /// know that it is beyond collision_activation.
  void evalPairs(const std::array<ArmState, 2>& st, std::array<PairState, kMaxPairs>& out,
                 bool exact = true) const noexcept {
    for (int k = 0; k < num_pairs; ++k) {
      const Pair& p = pairs[k];
      const Eigen::Vector3d& a0 = st[p.arm_a].cap[p.cap_a][0];
      const Eigen::Vector3d& a1 = st[p.arm_a].cap[p.cap_a][1];
      const double ra = caps.arm[p.arm_a][p.cap_a].radius;
      Eigen::Vector3d b0, b1;
      double rb = 0.0;
      if (p.arm_b < 0) {
        b0 = caps.body[p.cap_b].a;
        b1 = caps.body[p.cap_b].b;
        rb = caps.body[p.cap_b].radius;
      } else {
        b0 = st[p.arm_b].cap[p.cap_b][0];
        b1 = st[p.arm_b].cap[p.cap_b][1];
        rb = caps.arm[p.arm_b][p.cap_b].radius;
      }
      PairState& ps = out[k];
      if (!exact) {
        const double bound = (0.5 * (a0 + a1 - b0 - b1)).norm() - 0.5 * ((a1 - a0).norm() + (b1 - b0).norm()) - ra - rb;
        if (bound > opt.collision_activation) {
          ps.d = bound;
          continue;
        }
      }
      double s = 0.0, t = 0.0;
      const double axis_distance = segmentSegmentDistance(a0, a1, b0, b1, &s, &t);
      ps.c_a = a0 + s * (a1 - a0);
      ps.c_b = b0 + t * (b1 - b0);
      ps.d = axis_distance - ra - rb;
      if (axis_distance > 1e-9) {
        ps.n = (ps.c_a - ps.c_b) / axis_distance;
      } else {
        // Segments intersect: push along the line between the segment midpoints (any direction
        // separates; this one is continuous in most configurations).
        const Eigen::Vector3d m = 0.5 * (a0 + a1) - 0.5 * (b0 + b1);
        ps.n = m.norm() > 1e-9 ? Eigen::Vector3d(m.normalized()) : Eigen::Vector3d::UnitZ();
      }
    }
  }

  /// ∂d/∂q of a point c fixed in arm h's capsule segment `seg`, moving along +n: row of length 7.
  Vec7 distanceGradient(int h, const ArmState& st, int capsule, const Eigen::Vector3d& c,
                        const Eigen::Vector3d& n) const noexcept {
    Vec7 g = Vec7::Zero();
    const int seg = arms[h].capsule_segment[capsule];
    for (int j = 0; j < kArmDofs; ++j) {
      if (arms[h].joint_segment[j] > seg) break;
      g(j) = st.axis[j].dot((c - st.origin[j]).cross(n));
    }
    return g;
  }

  /// Weighted pose error e_w = [w_p (p* − p); w_o log(R* Rᵀ)] of arm state st.
  Vec6 poseError(const ArmState& st, const Eigen::Vector3d& p_star, const Eigen::Matrix3d& R_star) const noexcept {
    Vec6 e;
    e.head<3>() = opt.position_weight * (p_star - st.p_TH);
    const Eigen::AngleAxisd aa(Eigen::Matrix3d(R_star * st.R_TH.transpose()));
    e.tail<3>() = opt.orientation_weight * aa.angle() * aa.axis();
    return e;
  }

  /// Hand Jacobian of arm h at st, weighted: rows [w_p ∂p_TH/∂q; w_o ∂ω_TH/∂q] (T frame, reference
  /// point H), columns [a_j × (p_TH − o_j); a_j] from the KDL link frames of kinematics().
  Mat67 weightedJacobian(const ArmState& st, double w_p, double w_o) const noexcept {
    Mat67 J;
    for (int j = 0; j < kArmDofs; ++j) {
      J.block<3, 1>(0, j) = w_p * st.axis[j].cross(st.p_TH - st.origin[j]);
      J.block<3, 1>(3, j) = w_o * st.axis[j];
    }
    return J;
  }

  /// One damped-least-squares step of arm h with the null-space pull and the joint-limit active
  /// set. lo_room/hi_room: how far each joint may move in this step (box − q), lo ≤ 0 ≤ hi.
  Vec7 dlsStep(int h, const ArmState& st, const Vec6& e_w, const Vec7& lo_room, const Vec7& hi_room) noexcept {
    const Arm& a = arms[h];
    const Mat67 J_w = weightedJacobian(st, opt.position_weight, opt.orientation_weight);
    const double error_damping2 = opt.error_damping * 0.5 * e_w.squaredNorm();
    const double eps2 = opt.singular_value_threshold * opt.singular_value_threshold;

    // 1. Task step with the joint-limit active set: a joint the step pushes past its bound is
    //    pinned there and the task is re-solved with the others.
    std::array<bool, kArmDofs> pinned{};
    Vec7 dq_pinned = Vec7::Zero();
    Vec7 dq = Vec7::Zero();
    Mat67 J_m = J_w;
    Eigen::LLT<Mat66> llt0;  // of J_m J_mᵀ + μ² I (μ² = kSingularEps): the (nearly) undamped inverse
    for (int pass = 0; pass < kActiveSetPasses; ++pass) {
      J_m = J_w;
      for (int j = 0; j < kArmDofs; ++j) {
        if (pinned[j]) J_m.col(j).setZero();
      }
      const Vec6 r = e_w - J_w * dq_pinned;
      const Mat66 A0 = J_m * J_m.transpose();
      llt0.compute(A0 + kSingularEps * Mat66::Identity());
      // σ_min² of J_m by inverse iteration (warm-started with the last direction of this arm), then
      // λ² = λ_max² (1 − σ_min²/ε²) below the threshold ε (Chiaverini) plus the error term.
      Vec6& v = v_min[h];
      v = llt0.solve(v);  // one step per iteration: the warm start follows J from tick to tick
      const double nv = v.norm();
      v = nv > 0.0 && std::isfinite(nv) ? Vec6(v / nv) : Vec6::Constant(1.0 / std::sqrt(6.0));
      const double s2_min = std::max(0.0, v.dot(A0 * v));
      double lambda2 = error_damping2;
      if (s2_min < eps2) lambda2 += opt.damping * opt.damping * (1.0 - s2_min / eps2);
      if (lambda2 > kSingularEps) {
        const Eigen::LLT<Mat66> llt(A0 + lambda2 * Mat66::Identity());
        dq = J_m.transpose() * llt.solve(r);
      } else {
        dq = J_m.transpose() * llt0.solve(r);
      }
      for (int j = 0; j < kArmDofs; ++j) {
        if (pinned[j]) dq(j) = dq_pinned(j);
      }
      const double m = dq.cwiseAbs().maxCoeff();
      if (m > opt.max_iteration_step) dq *= opt.max_iteration_step / m;
      bool newly_pinned = false;
      for (int j = 0; j < kArmDofs; ++j) {
        if (pinned[j]) continue;
        if (dq(j) > hi_room(j)) {
          pinned[j] = true;
          dq_pinned(j) = hi_room(j);
          newly_pinned = true;
        } else if (dq(j) < lo_room(j)) {
          pinned[j] = true;
          dq_pinned(j) = lo_room(j);
          newly_pinned = true;
        }
      }
      if (!newly_pinned) break;
    }
    for (int j = 0; j < kArmDofs; ++j) dq(j) = std::clamp(dq(j), lo_room(j), hi_room(j));

    // 2. Null-space pull toward the nominal pose, projected with the (nearly) undamped
    //    pseudo-inverse of the free joints' J, N = I − J_mᵀ (J_m J_mᵀ + μ² I)⁻¹ J_m, so it does not
    //    disturb the task, and scaled down (never pinning a joint) to stay inside the box and cap.
    Vec7 z = Vec7::Zero();
    for (int j = 0; j < kArmDofs; ++j) {
      if (!pinned[j]) z(j) = opt.nullspace_gain * (a.nominal[j] - st.q[j]);
    }
    Vec7 dq_n = z - J_m.transpose() * llt0.solve(J_m * z);
    double alpha = 1.0;
    for (int j = 0; j < kArmDofs; ++j) {
      if (pinned[j]) {
        dq_n(j) = 0.0;
        continue;
      }
      const double hi = std::min(hi_room(j), opt.max_iteration_step);
      const double lo = std::max(lo_room(j), -opt.max_iteration_step);
      if (dq_n(j) > 0.0) alpha = std::min(alpha, std::max(0.0, (hi - dq(j)) / dq_n(j)));
      if (dq_n(j) < 0.0) alpha = std::min(alpha, std::max(0.0, (lo - dq(j)) / dq_n(j)));
    }
    dq += alpha * dq_n;
    for (int j = 0; j < kArmDofs; ++j) dq(j) = std::clamp(dq(j), lo_room(j), hi_room(j));
    return dq;
  }
};

ArmIk::ArmIk(const RobotConfig& robot, const ArmIkOptions& options) : impl_(std::make_unique<Impl>()) {
  if (const std::string e = options.validate(); !e.empty()) throw std::invalid_argument(e);
  Impl& m = *impl_;
  m.opt = options;
  m.caps = ArmCapsuleModel::g1();
  if (const std::string e = m.caps.validate(); !e.empty()) throw std::invalid_argument("ArmCapsuleModel: " + e);
  const KinematicModel model(robot);  // throws ConfigError naming the URDF
  const std::array<const char*, 2> side{"left_", "right_"};
  for (int h = 0; h < 2; ++h) {
    Impl::Arm& a = m.arms[h];
    const LimbChain limb = model.chain(kRootLink, kHandLinks[h]);  // throws ConfigError naming the URDF
    a.chain = limb.chain;
    if (a.chain.getNrOfJoints() != static_cast<unsigned>(kArmDofs)) {
      throw ConfigError(robot.urdf_path + ": chain " + kRootLink + " -> " + kHandLinks[h] + " has " +
                        std::to_string(a.chain.getNrOfJoints()) + " moving joints, expected 7");
    }
    int j = 0;
    for (unsigned s = 0; s < a.chain.getNrOfSegments(); ++s) {
      const KDL::Joint& joint = a.chain.getSegment(s).getJoint();
      if (joint.getType() == KDL::Joint::None) continue;
      const std::string expected = std::string(side[h]) + kJointSuffixes[j];
      if (joint.getName() != expected) {
        throw ConfigError(robot.urdf_path + ": joint " + std::to_string(j) + " of chain " + kRootLink + " -> " +
                          kHandLinks[h] + " is '" + joint.getName() + "', expected '" + expected + "'");
      }
      a.joint_segment[j] = static_cast<int>(s);
      a.joint_index[j] = limb.joint_index[j];
      const JointConfig& jc = robot.joints[limb.joint_index[j]];
      a.lower[j] = jc.lower;
      a.upper[j] = jc.upper;
      a.nominal[j] = std::clamp(jc.default_position, jc.lower, jc.upper);
      ++j;
    }
    for (int c = 0; c < kNumArmCapsules; ++c) {
      const std::string& link = m.caps.arm[h][c].link;
      a.capsule_segment[c] = -1;
      for (unsigned s = 0; s < a.chain.getNrOfSegments(); ++s) {
        if (a.chain.getSegment(s).getName() == link) a.capsule_segment[c] = static_cast<int>(s);
      }
      if (a.capsule_segment[c] < 0) {
        throw ConfigError(robot.urdf_path + ": capsule '" + m.caps.arm[h][c].name + "' link '" + link +
                          "' is not on the chain " + kRootLink + " -> " + kHandLinks[h]);
      }
    }
    a.fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(a.chain);
    a.jq = KDL::JntArray(kArmDofs);
    a.frames.assign(a.chain.getNrOfSegments(), KDL::Frame::Identity());

    // Shoulder point S: the roll joint origin projected onto the pitch axis (both at q = 0); the
    // pitch axis is fixed in T, so S is too.
    ArmState st;
    if (!m.kinematics(h, ArmJoints{}, st)) throw ConfigError(robot.urdf_path + ": KDL forward kinematics failed");
    const Eigen::Vector3d& o_pitch = st.origin[0];
    const Eigen::Vector3d& u_pitch = st.axis[0];
    a.shoulder = o_pitch + u_pitch * u_pitch.dot(st.origin[1] - o_pitch);

    // Reach: the largest |p_TH − S| over a grid of the joints that change it most (elbow, wrist
    // pitch and yaw, shoulder roll) and uniform random configurations; inner radius: the smallest
    // with the wrist straight.
    double r_max = 0.0;
    double r_min = std::numeric_limits<double>::infinity();
    auto visit = [&](const ArmJoints& q) {
      if (!m.kinematics(h, q, st)) return;
      const double r = (st.p_TH - a.shoulder).norm();
      r_max = std::max(r_max, r);
      if (q[4] == 0.0 && q[5] == 0.0 && q[6] == 0.0) r_min = std::min(r_min, r);
    };
    auto lerp = [&](int joint, int i, int n) {
      return a.lower[joint] + (a.upper[joint] - a.lower[joint]) * static_cast<double>(i) / (n - 1);
    };
    for (int ie = 0; ie < 61; ++ie) {
      for (int ip = 0; ip < 9; ++ip) {
        for (int iy = 0; iy < 9; ++iy) {
          for (int ir = 0; ir < 5; ++ir) {
            ArmJoints q{};
            q[1] = lerp(1, ir, 5);
            q[3] = lerp(3, ie, 61);
            q[5] = ip == 8 ? 0.0 : lerp(5, ip, 8);
            q[6] = iy == 8 ? 0.0 : lerp(6, iy, 8);
            visit(q);
          }
        }
      }
    }
    std::mt19937 rng(12345u + static_cast<unsigned>(h));
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (int i = 0; i < 20000; ++i) {
      ArmJoints q;
      for (int k = 0; k < kArmDofs; ++k) q[k] = a.lower[k] + (a.upper[k] - a.lower[k]) * u01(rng);
      visit(q);
    }
    a.reach = r_max;
    a.min_reach = r_min;
  }

  // Collision pairs (arm_capsules.hpp): arm × body except upper arm – head; left × right except
  // upper arm – upper arm.
  for (int h = 0; h < 2; ++h) {
    for (int c = 0; c < kNumArmCapsules; ++c) {
      for (int b = 0; b < kNumBodyCapsules; ++b) {
        if (c == kUpperArm && b == kHead) continue;
        m.pairs[m.num_pairs++] = Pair{h, c, -1, b};
      }
    }
  }
  for (int cl = 0; cl < kNumArmCapsules; ++cl) {
    for (int cr = 0; cr < kNumArmCapsules; ++cr) {
      if (cl == kUpperArm && cr == kUpperArm) continue;
      m.pairs[m.num_pairs++] = Pair{0, cl, 1, cr};
    }
  }
}

ArmIk::~ArmIk() = default;

void ArmIk::Impl::iterate(const std::array<bool, 2>& solving, std::array<ArmIkResult, 2>& results) noexcept {
  const ArmIkOptions& o = opt;
  const double floor_margin = 0.5 * o.collision_margin;
  std::array<bool, 2> done{};
  std::array<double, 2> e_prev{};
  std::array<bool, 2> was_within{};
  std::array<int, 2> stalls{};
  std::array<Vec7, 2> dq;
  for (int it = 0; it < o.max_iterations; ++it) {
    std::array<Vec6, 2> e_w;
    std::array<bool, 2> moving{};
    for (int h = 0; h < 2; ++h) {
      if (!solving[h] || done[h]) continue;
      e_w[h] = poseError(cur[h], p_target[h], R_target[h]);
      const double ep = (p_target[h] - cur[h].p_TH).norm();
      const double eo = rotationAngle(R_target[h] * cur[h].R_TH.transpose());
      const bool within = ep <= o.position_tolerance && eo <= o.orientation_tolerance;
      const double e_norm = e_w[h].norm();
      // A converged arm still takes the first iteration's step: it carries the null-space pull, so
      // the redundancy (elbow swivel) keeps moving toward the nominal pose while the hand holds.
      if (within && (it > 0 || o.nullspace_gain == 0.0)) {
        done[h] = true;
        continue;
      }
      // Stalled (the last two iterations each removed less than 1 % of the error: the step bound, a
      // joint limit or a collision holds the arm): more iterations cannot help this solve.
      stalls[h] = it > 0 && !was_within[h] && e_norm > kStallRatio * e_prev[h] ? stalls[h] + 1 : 0;
      if (o.stop_when_stalled && stalls[h] >= kStallIterations) {
        done[h] = true;
        continue;
      }
      e_prev[h] = e_norm;
      was_within[h] = within;
      moving[h] = true;
    }
    if (!moving[0] && !moving[1]) break;

    for (int h = 0; h < 2; ++h) {
      dq[h].setZero();
      if (!moving[h]) continue;
      Vec7 lo, hi;
      for (int j = 0; j < kArmDofs; ++j) {
        lo(j) = box_lo[h](j) - cur[h].q[j];
        hi(j) = box_hi[h](j) - cur[h].q[j];
      }
      dq[h] = dlsStep(h, cur[h], e_w[h], lo, hi);
      ++results[h].iterations;
    }

    if (o.avoid_collisions) {
      // Linearised collision constraints of the pairs near contact, projected cyclically.
      int nc = 0;
      for (int k = 0; k < num_pairs; ++k) {
        const Pair& p = pairs[k];
        const PairState& ps = cur_pairs[k];
        const bool a_moves = moving[p.arm_a];
        const bool b_moves = p.arm_b >= 0 && moving[p.arm_b];
        if (ps.d >= o.collision_activation || (!a_moves && !b_moves)) continue;
        Constraint& c = constraints[nc];
        c.g[0].setZero();
        c.g[1].setZero();
        if (a_moves) c.g[p.arm_a] = distanceGradient(p.arm_a, cur[p.arm_a], p.cap_a, ps.c_a, ps.n);
        if (b_moves) c.g[p.arm_b] -= distanceGradient(p.arm_b, cur[p.arm_b], p.cap_b, ps.c_b, ps.n);
        c.g2 = c.g[0].squaredNorm() + c.g[1].squaredNorm();
        if (c.g2 < 1e-12) continue;
        const double target =
            ps.d >= o.collision_margin ? o.collision_margin : ps.d + kRecovery * (o.collision_margin - ps.d);
        c.c = target - ps.d;
        ++nc;
      }
      for (int sweep = 0; sweep < kProjectionSweeps && nc > 0; ++sweep) {
        bool changed = false;
        for (int k = 0; k < nc; ++k) {
          const Constraint& c = constraints[k];
          const double viol = c.c - c.g[0].dot(dq[0]) - c.g[1].dot(dq[1]);
          if (viol <= 1e-12) continue;
          changed = true;
          for (int h = 0; h < 2; ++h) {
            if (c.g[h].squaredNorm() == 0.0) continue;
            dq[h] += c.g[h] * (viol / c.g2);
            results[h].collision_limited = true;
          }
        }
        for (int h = 0; h < 2; ++h) {
          if (!moving[h]) continue;
          for (int j = 0; j < kArmDofs; ++j) {
            dq[h](j) = std::clamp(dq[h](j), box_lo[h](j) - cur[h].q[j], box_hi[h](j) - cur[h].q[j]);
          }
        }
        if (!changed) break;
      }
    }

    // Line search: each pair may not end closer than min(its distance now, margin / 2).
    std::array<double, 2> scale{moving[0] ? 1.0 : 0.0, moving[1] ? 1.0 : 0.0};
    for (int attempt = 0; attempt <= kLineSearchHalvings + 1; ++attempt) {
      for (int h = 0; h < 2; ++h) {
        if (scale[h] == 0.0) {
          trial[h] = cur[h];
          continue;
        }
        ArmJoints qt;
        for (int j = 0; j < kArmDofs; ++j) {
          qt[j] = std::clamp(cur[h].q[j] + scale[h] * dq[h](j), box_lo[h](j), box_hi[h](j));
        }
        if (!kinematics(h, qt, trial[h])) {
          trial[h] = cur[h];
          scale[h] = 0.0;
        }
      }
      if (!o.avoid_collisions) break;
      evalPairs(trial, trial_pairs, false);
      std::array<bool, 2> violates{};
      for (int k = 0; k < num_pairs; ++k) {
        const double floor = std::min(cur_pairs[k].d, floor_margin);
        if (trial_pairs[k].d >= floor - 1e-9) continue;
        const Pair& p = pairs[k];
        if (scale[p.arm_a] > 0.0) violates[p.arm_a] = true;
        if (p.arm_b >= 0 && scale[p.arm_b] > 0.0) violates[p.arm_b] = true;
      }
      if (!violates[0] && !violates[1]) break;
      for (int h = 0; h < 2; ++h) {
        if (!violates[h]) continue;
        results[h].collision_limited = true;
        scale[h] = attempt < kLineSearchHalvings ? 0.5 * scale[h] : 0.0;
      }
      // With both scales 0 the next trial equals the current state, which always passes.
    }
    bool progressed = false;
    for (int h = 0; h < 2; ++h) {
      if (scale[h] == 0.0) continue;
      for (int j = 0; j < kArmDofs; ++j) {
        if (std::abs(trial[h].q[j] - cur[h].q[j]) > 1e-10) progressed = true;
      }
    }
    cur = trial;
    if (o.avoid_collisions) {
      cur_pairs = trial_pairs;
    } else {
      evalPairs(cur, cur_pairs, false);
    }
    if (!progressed) break;  // stalled against the bounds or a collision
  }
}

double ArmIk::Impl::weightedError(int h) const noexcept {
  const double ep = (p_target[h] - cur[h].p_TH).norm();
  const double eo = rotationAngle(R_target[h] * cur[h].R_TH.transpose());
  return opt.position_weight * ep + opt.orientation_weight * eo;
}

bool ArmIk::Impl::converged(int h) const noexcept {
  return (p_target[h] - cur[h].p_TH).norm() <= opt.position_tolerance &&
         rotationAngle(R_target[h] * cur[h].R_TH.transpose()) <= opt.orientation_tolerance;
}

void ArmIk::solve(const std::array<ArmPose, 2>& targets_T, const std::array<bool, 2>& active,
                  std::array<ArmJoints, 2>& q, std::array<ArmIkResult, 2>& results) noexcept {
  Impl& m = *impl_;
  const ArmIkOptions& o = m.opt;
  std::array<bool, 2> solving{};

  for (int h = 0; h < 2; ++h) {
    const Impl::Arm& a = m.arms[h];
    ArmIkResult& r = results[h];
    r = ArmIkResult{};
    r.status = ArmIkStatus::kInactive;
    if (!finite(q[h])) {
      q[h] = a.nominal;
      r.status = ArmIkStatus::kInvalidTarget;
      continue;
    }
    for (int j = 0; j < kArmDofs; ++j) q[h][j] = std::clamp(q[h][j], a.lower[j], a.upper[j]);
    if (!active[h]) continue;
    const ArmPose& t = targets_T[h];
    const double qn = t.orientation.coeffs().norm();
    if (!t.position.allFinite() || !t.orientation.coeffs().allFinite() ||
        std::abs(qn - 1.0) > o.quaternion_norm_tolerance || qn < 1e-6) {
      r.status = ArmIkStatus::kInvalidTarget;
      continue;
    }
    m.R_target[h] = Eigen::Quaterniond(t.orientation.coeffs() / qn).toRotationMatrix();
    // Workspace clamp onto the shell around the shoulder.
    const Eigen::Vector3d v = t.position - a.shoulder;
    const double dist = v.norm();
    const double r_out = a.reach * (1.0 - o.workspace_margin);
    const double r_in = std::min(a.min_reach * (1.0 + o.workspace_margin), r_out);
    m.p_target[h] = t.position;
    if (dist > r_out) {
      m.p_target[h] = a.shoulder + v * (r_out / dist);
    } else if (dist < r_in) {
      const Eigen::Vector3d dir = dist > 1e-9 ? Eigen::Vector3d(v / dist) : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
      m.p_target[h] = a.shoulder + dir * r_in;
    }
    r.clamp_distance_m = (m.p_target[h] - t.position).norm();
    r.workspace_clamped = r.clamp_distance_m > 0.0;
    for (int j = 0; j < kArmDofs; ++j) {
      m.box_lo[h](j) = std::max(a.lower[j], q[h][j] - o.max_joint_step);
      m.box_hi[h](j) = std::min(a.upper[j], q[h][j] + o.max_joint_step);
    }
    solving[h] = true;
  }

  // Kinematics at the seed (both arms: an inactive arm is an obstacle for the other).
  bool ok = true;
  for (int h = 0; h < 2; ++h) ok = m.kinematics(h, q[h], m.cur[h]) && ok;
  if (!ok) {
    for (int h = 0; h < 2; ++h) {
      if (solving[h]) results[h].status = ArmIkStatus::kMaxIterations;
    }
    return;
  }
  m.evalPairs(m.cur, m.cur_pairs, false);
  m.iterate(solving, results);

  // Restarts (off-line use): one arm at a time from pseudo-random seeds in its box (the other arm
  // frozen, so the arm–arm pairs stay valid), keeping the best result.
  if (o.max_restarts > 0) {
    std::uint64_t rng = 0x9E3779B97F4A7C15ULL;
    auto uniform = [&rng]() {
      rng ^= rng << 13;
      rng ^= rng >> 7;
      rng ^= rng << 17;
      return static_cast<double>(rng >> 11) * (1.0 / 9007199254740992.0);
    };
    for (int h = 0; h < 2; ++h) {
      if (!solving[h]) continue;
      std::array<bool, 2> only{};
      only[h] = true;
      for (int restart = 0; restart < o.max_restarts && !m.converged(h); ++restart) {
        const ArmState best = m.cur[h];
        const std::array<PairState, kMaxPairs> best_pairs = m.cur_pairs;
        const double best_error = m.weightedError(h);
        bool seeded = false;
        for (int attempt = 0; attempt < 20 && !seeded; ++attempt) {
          ArmJoints seed;
          for (int j = 0; j < kArmDofs; ++j) seed[j] = m.box_lo[h](j) + (m.box_hi[h](j) - m.box_lo[h](j)) * uniform();
          if (!m.kinematics(h, seed, m.cur[h])) break;
          m.evalPairs(m.cur, m.cur_pairs, false);
          seeded = true;
          for (int k = 0; k < m.num_pairs; ++k) {
            const Pair& p = m.pairs[k];
            if ((p.arm_a == h || p.arm_b == h) && m.cur_pairs[k].d < o.collision_margin) seeded = false;
          }
        }
        if (seeded) m.iterate(only, results);
        if (!seeded || m.weightedError(h) >= best_error) {
          m.cur[h] = best;
          m.cur_pairs = best_pairs;
        }
      }
    }
  }

  m.evalPairs(m.cur, m.cur_pairs);  // exact distances for the results
  for (int h = 0; h < 2; ++h) {
    ArmIkResult& r = results[h];
    r.min_capsule_distance_m = std::numeric_limits<double>::infinity();
    for (int k = 0; k < m.num_pairs; ++k) {
      const Pair& p = m.pairs[k];
      if (p.arm_a == h || p.arm_b == h) r.min_capsule_distance_m = std::min(r.min_capsule_distance_m, m.cur_pairs[k].d);
    }
    if (!solving[h]) continue;
    q[h] = m.cur[h].q;
    r.position_error_m = (m.p_target[h] - m.cur[h].p_TH).norm();
    r.orientation_error_rad = rotationAngle(m.R_target[h] * m.cur[h].R_TH.transpose());
    if (r.workspace_clamped) {
      r.status = ArmIkStatus::kUnreachableClamped;
    } else {
      r.status = m.converged(h) ? ArmIkStatus::kConverged : ArmIkStatus::kMaxIterations;
    }
  }
}

ArmPose ArmIk::forwardKinematics(int hand, const ArmJoints& q) const noexcept {
  ArmPose pose;
  const int h = hand == 1 ? 1 : 0;
  ArmState& st = impl_->scratch[h];
  if (!finite(q) || !impl_->kinematics(h, q, st)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    pose.position = Eigen::Vector3d::Constant(nan);
    pose.orientation = Eigen::Quaterniond(nan, nan, nan, nan);
    return pose;
  }
  pose.position = st.p_TH;
  pose.orientation = Eigen::Quaterniond(st.R_TH).normalized();
  return pose;
}

Eigen::Matrix<double, 6, kArmDofs> ArmIk::jacobian(int hand, const ArmJoints& q) const noexcept {
  const int h = hand == 1 ? 1 : 0;
  ArmState& st = impl_->scratch[h];
  if (!finite(q) || !impl_->kinematics(h, q, st)) {
    return Eigen::Matrix<double, 6, kArmDofs>::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return impl_->weightedJacobian(st, 1.0, 1.0);
}

double ArmIk::minCapsuleDistance(const std::array<ArmJoints, 2>& q, std::array<double, 2>* per_hand) const noexcept {
  Impl& m = *impl_;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int h = 0; h < 2; ++h) {
    if (!finite(q[h]) || !m.kinematics(h, q[h], m.scratch[h])) {
      if (per_hand != nullptr) *per_hand = {nan, nan};
      return nan;
    }
  }
  m.evalPairs(m.scratch, m.scratch_pairs);
  double d_min = std::numeric_limits<double>::infinity();
  std::array<double, 2> d_hand{d_min, d_min};
  for (int k = 0; k < m.num_pairs; ++k) {
    const Pair& p = m.pairs[k];
    const double d = m.scratch_pairs[k].d;
    d_min = std::min(d_min, d);
    d_hand[p.arm_a] = std::min(d_hand[p.arm_a], d);
    if (p.arm_b >= 0) d_hand[p.arm_b] = std::min(d_hand[p.arm_b], d);
  }
  if (per_hand != nullptr) *per_hand = d_hand;
  return d_min;
}

const std::array<int, kArmDofs>& ArmIk::jointIndices(int hand) const noexcept {
  return impl_->arms[hand == 1 ? 1 : 0].joint_index;
}
const ArmJoints& ArmIk::nominal(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].nominal; }
const ArmJoints& ArmIk::lower(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].lower; }
const ArmJoints& ArmIk::upper(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].upper; }
Eigen::Vector3d ArmIk::shoulderPosition(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].shoulder; }
double ArmIk::reach(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].reach; }
double ArmIk::minReach(int hand) const noexcept { return impl_->arms[hand == 1 ? 1 : 0].min_reach; }
const ArmCapsuleModel& ArmIk::capsules() const noexcept { return impl_->caps; }
const ArmIkOptions& ArmIk::options() const noexcept { return impl_->opt; }

}  // namespace pmg::teleop
