#include "pmg/motion/keypoint_retarget.hpp"

#include <chrono>
#include <fstream>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <fmt/format.h>

namespace pmg::motion {
namespace {

using Isometry = Eigen::Isometry3d;
constexpr int kBaseDim = 6;  // x, y, z, roll, pitch, yaw

Eigen::Matrix3d rpyToMatrix(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d matrixToRpy(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::max(-1.0, std::min(1.0, -R(2, 0))));
  return {std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0))};
}

/// Rotation error vector (sin θ · axis) of Ra relative to Rb; smooth near zero.
Eigen::Vector3d rotationError(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb) {
  const Eigen::Matrix3d E = Rb.transpose() * Ra;
  return 0.5 * Eigen::Vector3d(E(2, 1) - E(1, 2), E(0, 2) - E(2, 0), E(1, 0) - E(0, 1));
}

Isometry toIso(const KDL::Frame& f) { return toEigen(f); }

/// The robot's keypoint kinematics: four KDL chains from the pelvis (legs to the ankle roll
/// links, arms to the wrist roll links), one forward pass each giving every segment frame.
class RobotKinematics {
 public:
  explicit RobotKinematics(const KinematicModel& model) : robot_(&model.config()) {
    const char* sides[2] = {"left_", "right_"};
    for (int s = 0; s < 2; ++s) {
      const std::string pre = sides[s];
      legs_[s].limb = model.chain(robot_->base_link, s == 0 ? robot_->left_foot_link : robot_->right_foot_link);
      arms_[s].limb = model.chain(robot_->base_link, pre + "wrist_roll_link");
      leg_hip_[s] = segmentIndex(legs_[s], pre + "hip_roll_link");
      leg_knee_[s] = segmentIndex(legs_[s], pre + "knee_link");
      leg_ankle_[s] = segmentIndex(legs_[s], s == 0 ? robot_->left_foot_link : robot_->right_foot_link);
      arm_torso_[s] = segmentIndex(arms_[s], "torso_link");
      arm_shoulder_[s] = segmentIndex(arms_[s], pre + "shoulder_roll_link");
      arm_elbow_[s] = segmentIndex(arms_[s], pre + "elbow_link");
      arm_wrist_[s] = segmentIndex(arms_[s], pre + "wrist_roll_link");
    }
    for (Chain* c : {&legs_[0], &legs_[1], &arms_[0], &arms_[1]}) c->frames.resize(c->limb.chain.getNrOfSegments());
  }

  /// Keypoints and orientations in the base frame B for joint vector q.
  void compute(const double* q) {
    for (Chain* c : {&legs_[0], &legs_[1], &arms_[0], &arms_[1]}) forward(*c, q);
  }
  const Isometry& legFrame(int side, int which) const {
    const int idx = which == 0 ? leg_hip_[side] : which == 1 ? leg_knee_[side] : leg_ankle_[side];
    return legs_[side].frames[static_cast<std::size_t>(idx)];
  }
  const Isometry& armFrame(int side, int which) const {
    const int idx = which == 0 ? arm_torso_[side] : which == 1 ? arm_shoulder_[side] : which == 2 ? arm_elbow_[side] : arm_wrist_[side];
    return arms_[side].frames[static_cast<std::size_t>(idx)];
  }

  /// Fills a HumanFrame-style set (W) from the last compute() and base pose X_WB.
  void toFrame(const Isometry& X_WB, HumanFrame& out) const {
    auto set = [&](Keypoint k, const Eigen::Vector3d& p_B) { out.p_WK[static_cast<std::size_t>(k)] = X_WB * p_B; };
    set(Keypoint::kPelvis, Eigen::Vector3d::Zero());
    const Keypoint hip[2] = {Keypoint::kLeftHip, Keypoint::kRightHip}, knee[2] = {Keypoint::kLeftKnee, Keypoint::kRightKnee},
                   ankle[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle}, toe[2] = {Keypoint::kLeftToe, Keypoint::kRightToe},
                   sh[2] = {Keypoint::kLeftShoulder, Keypoint::kRightShoulder},
                   el[2] = {Keypoint::kLeftElbow, Keypoint::kRightElbow}, wr[2] = {Keypoint::kLeftWrist, Keypoint::kRightWrist};
    for (int s = 0; s < 2; ++s) {
      set(hip[s], legFrame(s, 0).translation());
      set(knee[s], legFrame(s, 1).translation());
      set(ankle[s], legFrame(s, 2).translation());
      set(toe[s], legFrame(s, 2) * Eigen::Vector3d(kToeOffset, 0, 0));
      set(sh[s], armFrame(s, 1).translation());
      set(el[s], armFrame(s, 2).translation());
      set(wr[s], armFrame(s, 3).translation());
      out.R_WFoot[static_cast<std::size_t>(s)] = Eigen::Quaterniond(X_WB.linear() * legFrame(s, 2).linear());
    }
    out.R_WPelvis = Eigen::Quaterniond(X_WB.linear());
    out.R_WTorso = Eigen::Quaterniond(X_WB.linear() * armFrame(0, 0).linear());
  }

 private:
  struct Chain {
    LimbChain limb;
    std::vector<Isometry> frames;
  };
  static int segmentIndex(const Chain& c, const std::string& link) {
    for (unsigned i = 0; i < c.limb.chain.getNrOfSegments(); ++i)
      if (c.limb.chain.getSegment(i).getName() == link) return static_cast<int>(i);
    throw std::runtime_error("keypoint retargeting: link '" + link + "' not on chain " + c.limb.root_link + " -> " + c.limb.tip_link);
  }
  static void forward(Chain& c, const double* q) {
    KDL::Frame F = KDL::Frame::Identity();
    unsigned j = 0;
    for (unsigned i = 0; i < c.limb.chain.getNrOfSegments(); ++i) {
      const KDL::Segment& seg = c.limb.chain.getSegment(i);
      double qi = 0.0;
      if (seg.getJoint().getType() != KDL::Joint::None) qi = q[c.limb.joint_index[j++]];
      F = F * seg.pose(qi);
      c.frames[i] = toIso(F);
    }
  }

  const RobotConfig* robot_;
  Chain legs_[2], arms_[2];
  int leg_hip_[2]{}, leg_knee_[2]{}, leg_ankle_[2]{};
  int arm_torso_[2]{}, arm_shoulder_[2]{}, arm_elbow_[2]{}, arm_wrist_[2]{};
};

/// Everything one frame's residual needs.
struct FrameTargets {
  KeypointTargets p;                 // robot-scale keypoint targets
  Eigen::Matrix3d R_pelvis, R_torso;
  std::array<Eigen::Matrix3d, 2> R_foot;
  std::array<bool, 2> contact{};
  std::array<Eigen::Vector2d, 2> anchor;  // stance anchor of the ankle (xy)
  bool has_prev = false;
  Eigen::VectorXd x_prev;           // (6 + n)
};

constexpr int kNumResiduals = 3 + 10 * 3 + 2 * 3 + 3 + 3 + 2 * 3 + 2 * 5 + 2 * 4;

class FrameCost {
 public:
  FrameCost(RobotKinematics* kin, const FrameTargets* t, const KeypointRetargetOptions* o, const Eigen::VectorXd* q_default)
      : kin_(kin), t_(t), o_(o), q_default_(q_default) {}

  int numResiduals() const { return kNumResiduals + kBaseDim + static_cast<int>(q_default_->size()) * 2; }

  bool operator()(double const* const* params, double* r) const {
    const double* b = params[0];
    const double* q = params[1];
    const Eigen::Index n = q_default_->size();
    kin_->compute(q);
    Isometry X_WB = Isometry::Identity();
    X_WB.linear() = rpyToMatrix(b[3], b[4], b[5]);
    X_WB.translation() = Eigen::Vector3d(b[0], b[1], b[2]);
    HumanFrame f;
    kin_->toFrame(X_WB, f);
    int i = 0;
    auto put3 = [&](const Eigen::Vector3d& v, double w) {
      r[i++] = w * v.x();
      r[i++] = w * v.y();
      r[i++] = w * v.z();
    };
    auto kp = [&](Keypoint k) { return f.p_WK[static_cast<std::size_t>(k)] - t_->p[static_cast<std::size_t>(k)]; };
    const Eigen::Vector3d dp = kp(Keypoint::kPelvis);
    r[i++] = o_->w_pelvis_xy * dp.x();
    r[i++] = o_->w_pelvis_xy * dp.y();
    r[i++] = o_->w_pelvis_z * dp.z();
    for (Keypoint k : {Keypoint::kLeftKnee, Keypoint::kRightKnee, Keypoint::kLeftElbow, Keypoint::kRightElbow,
                       Keypoint::kLeftWrist, Keypoint::kRightWrist})
      put3(kp(k), o_->w_keypoint);
    for (Keypoint k : {Keypoint::kLeftAnkle, Keypoint::kRightAnkle, Keypoint::kLeftToe, Keypoint::kRightToe})
      put3(kp(k), o_->w_foot_keypoint);
    for (Keypoint k : {Keypoint::kLeftShoulder, Keypoint::kRightShoulder}) put3(kp(k), 0.5 * o_->w_keypoint);
    put3(rotationError(X_WB.linear(), t_->R_pelvis), o_->w_orientation);
    put3(rotationError(f.R_WTorso.toRotationMatrix(), t_->R_torso), o_->w_orientation);
    const auto soles = g1SolePoints_F();
    const Keypoint ankles[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle};
    for (int s = 0; s < 2; ++s) {
      const Eigen::Matrix3d R_foot = f.R_WFoot[static_cast<std::size_t>(s)].toRotationMatrix();
      put3(rotationError(R_foot, t_->R_foot[static_cast<std::size_t>(s)]), o_->w_foot_orientation);
      const double wc = t_->contact[static_cast<std::size_t>(s)] ? o_->w_contact : 0.0;
      const Eigen::Vector3d pa = f.p_WK[static_cast<std::size_t>(ankles[s])];
      r[i++] = wc * (pa.x() - t_->anchor[static_cast<std::size_t>(s)].x());
      r[i++] = wc * (pa.y() - t_->anchor[static_cast<std::size_t>(s)].y());
      r[i++] = wc * (pa.z() + soles[0].z());  // sole on the ground when flat
      r[i++] = wc * R_foot(0, 2);             // foot z axis vertical (flat)
      r[i++] = wc * R_foot(1, 2);
      const Isometry X_WF = X_WB * kin_->legFrame(s, 2);
      for (const auto& sp : soles) r[i++] = o_->w_ground * std::max(0.0, -(X_WF * sp).z());
    }
    const double ws = t_->has_prev ? o_->w_smooth : 0.0;
    for (int k = 0; k < kBaseDim; ++k) r[i++] = ws * (b[k] - (t_->has_prev ? t_->x_prev(k) : 0.0));
    for (Eigen::Index k = 0; k < n; ++k) r[i++] = ws * (q[k] - (t_->has_prev ? t_->x_prev(kBaseDim + k) : 0.0));
    for (Eigen::Index k = 0; k < n; ++k) r[i++] = o_->w_posture * (q[k] - (*q_default_)(k));
    return true;
  }

 private:
  RobotKinematics* kin_;
  const FrameTargets* t_;
  const KeypointRetargetOptions* o_;
  const Eigen::VectorXd* q_default_;
};

/// Robot segment lengths and offsets at q = 0 used to build the targets.
struct RobotGeometry {
  std::array<Eigen::Vector3d, 2> hip_B;       // hip point in the pelvis frame
  std::array<Eigen::Vector3d, 2> shoulder_T;  // shoulder point relative to the torso frame origin, torso axes
  Eigen::Vector3d torso_B;                    // torso frame origin in the pelvis frame
  double thigh = 0, shank = 0, upper_arm = 0, forearm = 0;
};

RobotGeometry robotGeometry(RobotKinematics& kin, Eigen::Index n) {
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  kin.compute(q0.data());
  RobotGeometry g;
  g.torso_B = kin.armFrame(0, 0).translation();
  for (int s = 0; s < 2; ++s) {
    g.hip_B[static_cast<std::size_t>(s)] = kin.legFrame(s, 0).translation();
    g.shoulder_T[static_cast<std::size_t>(s)] =
        kin.armFrame(s, 0).linear().transpose() * (kin.armFrame(s, 1).translation() - kin.armFrame(s, 0).translation());
    g.thigh += 0.5 * (kin.legFrame(s, 1).translation() - kin.legFrame(s, 0).translation()).norm();
    g.shank += 0.5 * (kin.legFrame(s, 2).translation() - kin.legFrame(s, 1).translation()).norm();
    g.upper_arm += 0.5 * (kin.armFrame(s, 2).translation() - kin.armFrame(s, 1).translation()).norm();
    g.forearm += 0.5 * (kin.armFrame(s, 3).translation() - kin.armFrame(s, 2).translation()).norm();
  }
  return g;
}

Eigen::Vector3d direction(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d d = to - from;
  const double norm = d.norm();
  return norm > 1e-9 ? Eigen::Vector3d(d / norm) : Eigen::Vector3d(0, 0, -1);
}

/// Robot-scale targets of one human frame.
KeypointTargets buildTargets(const HumanFrame& h, const RobotGeometry& g, double s) {
  KeypointTargets t;
  auto H = [&](Keypoint k) { return h.p_WK[static_cast<std::size_t>(k)]; };
  auto T = [&](Keypoint k) -> Eigen::Vector3d& { return t[static_cast<std::size_t>(k)]; };
  const Eigen::Matrix3d Rp = h.R_WPelvis.toRotationMatrix(), Rt = h.R_WTorso.toRotationMatrix();
  T(Keypoint::kPelvis) = s * H(Keypoint::kPelvis);
  const Keypoint hip[2] = {Keypoint::kLeftHip, Keypoint::kRightHip}, knee[2] = {Keypoint::kLeftKnee, Keypoint::kRightKnee},
                 ankle[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle}, toe[2] = {Keypoint::kLeftToe, Keypoint::kRightToe},
                 sh[2] = {Keypoint::kLeftShoulder, Keypoint::kRightShoulder},
                 el[2] = {Keypoint::kLeftElbow, Keypoint::kRightElbow}, wr[2] = {Keypoint::kLeftWrist, Keypoint::kRightWrist};
  const Eigen::Vector3d torso = T(Keypoint::kPelvis) + Rp * g.torso_B;
  for (int side = 0; side < 2; ++side) {
    const auto si = static_cast<std::size_t>(side);
    T(hip[side]) = T(Keypoint::kPelvis) + Rp * g.hip_B[si];
    T(knee[side]) = T(hip[side]) + g.thigh * direction(H(hip[side]), H(knee[side]));
    T(ankle[side]) = T(knee[side]) + g.shank * direction(H(knee[side]), H(ankle[side]));
    T(toe[side]) = T(ankle[side]) + h.R_WFoot[si].toRotationMatrix() * Eigen::Vector3d(kToeOffset, 0, 0);
    T(sh[side]) = torso + Rt * g.shoulder_T[si];
    T(el[side]) = T(sh[side]) + g.upper_arm * direction(H(sh[side]), H(el[side]));
    T(wr[side]) = T(el[side]) + g.forearm * direction(H(el[side]), H(wr[side]));
  }
  return t;
}

double wrapTo(double angle, double reference) {
  while (angle - reference > M_PI) angle -= 2 * M_PI;
  while (angle - reference < -M_PI) angle += 2 * M_PI;
  return angle;
}

}  // namespace

void KeypointRetargetOptions::validate() const {
  auto nonneg = [](double v, const char* name) {
    if (!(v >= 0.0) || !std::isfinite(v)) throw std::invalid_argument(fmt::format("KeypointRetargetOptions.{} = {}: expected finite >= 0", name, v));
  };
  if (!std::isfinite(scale)) throw std::invalid_argument("KeypointRetargetOptions.scale: expected a finite number");
  nonneg(w_keypoint, "w_keypoint");
  nonneg(w_foot_keypoint, "w_foot_keypoint");
  nonneg(w_pelvis_xy, "w_pelvis_xy");
  nonneg(w_pelvis_z, "w_pelvis_z");
  nonneg(w_orientation, "w_orientation");
  nonneg(w_foot_orientation, "w_foot_orientation");
  nonneg(w_contact, "w_contact");
  nonneg(w_ground, "w_ground");
  nonneg(w_smooth, "w_smooth");
  nonneg(w_posture, "w_posture");
  nonneg(swing_blend, "swing_blend");
  if (max_iterations < 1) throw std::invalid_argument(fmt::format("KeypointRetargetOptions.max_iterations = {}: expected >= 1", max_iterations));
  if (!(contact_height > 0.0)) throw std::invalid_argument(fmt::format("KeypointRetargetOptions.contact_height = {}: expected > 0 [m]", contact_height));
  if (!(contact_speed > 0.0)) throw std::invalid_argument(fmt::format("KeypointRetargetOptions.contact_speed = {}: expected > 0 [m/s]", contact_speed));
}

HumanFrame robotKeypoints(const KinematicModel& model, const Eigen::Isometry3d& X_WB, const Eigen::VectorXd& q) {
  RobotKinematics kin(model);
  if (q.size() != static_cast<Eigen::Index>(model.config().numJoints())) throw std::runtime_error("robotKeypoints: q has the wrong size");
  kin.compute(q.data());
  HumanFrame f;
  kin.toFrame(X_WB, f);
  return f;
}

ContactSequence detectHumanContacts(const HumanMotion& human, const KeypointRetargetOptions& options) {
  options.validate();
  const int F = human.numFrames();
  ContactSequence out(static_cast<std::size_t>(F));
  const Keypoint ankle[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle}, toe[2] = {Keypoint::kLeftToe, Keypoint::kRightToe};
  for (int s = 0; s < 2; ++s) {
    for (int k = 0; k < F; ++k) {
      const HumanFrame& f = human.frames[static_cast<std::size_t>(k)];
      const int a = std::max(0, k - 1), b = std::min(F - 1, k + 1);
      const Eigen::Vector3d pa = human.frames[static_cast<std::size_t>(a)].p_WK[static_cast<std::size_t>(ankle[s])];
      const Eigen::Vector3d pb = human.frames[static_cast<std::size_t>(b)].p_WK[static_cast<std::size_t>(ankle[s])];
      const double speed = b > a ? (pb - pa).head<2>().norm() * human.fps / (b - a) : 0.0;
      const double low = std::min(f.p_WK[static_cast<std::size_t>(ankle[s])].z(), f.p_WK[static_cast<std::size_t>(toe[s])].z()) - human.ankle_height;
      out[static_cast<std::size_t>(k)][static_cast<std::size_t>(s)] = low < options.contact_height && speed < options.contact_speed;
    }
    // Debounce: flip interior runs shorter than 3 frames.
    for (int pass = 0; pass < 3; ++pass) {
      int start = 0;
      while (start < F) {
        int end = start;
        const bool v = out[static_cast<std::size_t>(start)][static_cast<std::size_t>(s)];
        while (end < F && out[static_cast<std::size_t>(end)][static_cast<std::size_t>(s)] == v) ++end;
        if (start > 0 && end < F && end - start < 3)
          for (int k = start; k < end; ++k) out[static_cast<std::size_t>(k)][static_cast<std::size_t>(s)] = !v;
        start = end;
      }
    }
  }
  for (std::size_t i = 0; i < options.contact_overrides.size(); ++i) {
    const ContactOverride& o = options.contact_overrides[i];
    if (o.begin < 0 || o.end > F || o.begin >= o.end)
      throw std::invalid_argument(fmt::format("KeypointRetargetOptions.contact_overrides[{}]: frames [{}, {}) invalid for a motion "
                                              "of {} frames (need 0 <= begin < end <= frames; {})",
                                              i, o.begin, o.end, F, human.source_file));
    if (!(o.clearance >= 0.0) || !std::isfinite(o.clearance) || (o.contact && o.clearance > 0.0))
      throw std::invalid_argument(fmt::format("KeypointRetargetOptions.contact_overrides[{}].clearance = {}: expected finite >= 0 "
                                              "[m], and 0 on a contact span",
                                              i, o.clearance));
    for (int k = o.begin; k < o.end; ++k) out[static_cast<std::size_t>(k)][static_cast<std::size_t>(o.foot)] = o.contact;
  }
  return out;
}

RetargetResult retargetKeypoints(const HumanMotion& human, const KinematicModel& model, const KeypointRetargetOptions& options) {
  options.validate();
  const RobotConfig& robot = model.config();
  const int F = human.numFrames();
  if (F < 1) throw std::invalid_argument("retargetKeypoints: human motion has no frames (" + human.source_file + ")");
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  RobotKinematics kin(model);
  const RobotGeometry geo = robotGeometry(kin, n);
  const double s = options.scale > 0.0 ? options.scale : (geo.thigh + geo.shank) / human.legLength();
  if (!(s > 0.0) || !std::isfinite(s)) throw std::runtime_error("retargetKeypoints: could not derive a scale (zero leg length?)");

  RetargetResult res;
  res.scale = s;
  res.contacts = detectHumanContacts(human, options);
  res.targets.resize(static_cast<std::size_t>(F));
  res.human.resize(static_cast<std::size_t>(F));
  for (int k = 0; k < F; ++k)
    for (std::size_t i = 0; i < kNumKeypoints; ++i) res.human[static_cast<std::size_t>(k)][i] = s * human.frames[static_cast<std::size_t>(k)].p_WK[i];
  for (int k = 0; k < F; ++k) {
    const HumanFrame& h = human.frames[static_cast<std::size_t>(k)];
    KeypointTargets& t = res.targets[static_cast<std::size_t>(k)];
    if (options.segment_directions) {
      t = buildTargets(h, geo, s);
    } else {
      for (std::size_t i = 0; i < kNumKeypoints; ++i) t[i] = s * h.p_WK[i];
    }
  }

  // Vertical alignment: human and robot differ in pelvis→hip drop and ankle height, so shift all
  // targets by one constant per motion that puts the target ankles of stance feet at the robot's
  // flat-foot ankle height (median over stance frames).
  {
    std::vector<double> dz;
    const Keypoint ank[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle};
    for (int k = 0; k < F; ++k)
      for (int side = 0; side < 2; ++side)
        if (res.contacts[static_cast<std::size_t>(k)][static_cast<std::size_t>(side)])
          dz.push_back(-g1SolePoints_F()[0].z() - res.targets[static_cast<std::size_t>(k)][static_cast<std::size_t>(ank[side])].z());
    if (!dz.empty()) {
      std::nth_element(dz.begin(), dz.begin() + static_cast<std::ptrdiff_t>(dz.size() / 2), dz.end());
      const double shift = dz[dz.size() / 2];
      for (KeypointTargets& t : res.targets)
        for (auto& p : t) p.z() += shift;
      for (KeypointTargets& t : res.human)
        for (auto& p : t) p.z() += shift;
    }
  }

  // Forced swings: raise the foot targets (after the vertical alignment, which uses stance frames).
  for (const ContactOverride& o : options.contact_overrides) {
    if (o.contact || o.clearance <= 0.0) continue;
    const Keypoint foot_kps[2][2] = {{Keypoint::kLeftAnkle, Keypoint::kLeftToe}, {Keypoint::kRightAnkle, Keypoint::kRightToe}};
    for (int k = o.begin; k < o.end; ++k) {
      const double s_span = (k - o.begin + 0.5) / static_cast<double>(o.end - o.begin);
      for (Keypoint kp : foot_kps[static_cast<int>(o.foot)])
        res.targets[static_cast<std::size_t>(k)][static_cast<std::size_t>(kp)].z() += o.clearance * std::sin(M_PI * s_span);
    }
  }

  // Stance anchors: mean target ankle position over each contact run.
  std::array<std::vector<Eigen::Vector2d>, 2> anchors;
  const Keypoint ankle[2] = {Keypoint::kLeftAnkle, Keypoint::kRightAnkle};
  for (int side = 0; side < 2; ++side) {
    auto& a = anchors[static_cast<std::size_t>(side)];
    a.assign(static_cast<std::size_t>(F), Eigen::Vector2d::Zero());
    int start = 0;
    while (start < F) {
      int end = start;
      const bool c = res.contacts[static_cast<std::size_t>(start)][static_cast<std::size_t>(side)];
      while (end < F && res.contacts[static_cast<std::size_t>(end)][static_cast<std::size_t>(side)] == c) ++end;
      if (c) {
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (int k = start; k < end; ++k) mean += res.targets[static_cast<std::size_t>(k)][static_cast<std::size_t>(ankle[side])].head<2>();
        mean /= (end - start);
        for (int k = start; k < end; ++k) a[static_cast<std::size_t>(k)] = mean;
      }
      start = end;
    }
  }

  // Swing ends blended onto the neighbouring stance anchors (xy of ankle and toe together).
  if (options.swing_blend > 0.0) {
    const double width = options.swing_blend * human.fps;  // [frames]
    const Keypoint toe[2] = {Keypoint::kLeftToe, Keypoint::kRightToe};
    for (int side = 0; side < 2; ++side) {
      const auto sd = static_cast<std::size_t>(side);
      int start = 0;
      while (start < F) {
        int end = start;
        const bool c = res.contacts[static_cast<std::size_t>(start)][sd];
        while (end < F && res.contacts[static_cast<std::size_t>(end)][sd] == c) ++end;
        if (!c) {
          for (int k = start; k < end; ++k) {
            KeypointTargets& t = res.targets[static_cast<std::size_t>(k)];
            const Eigen::Vector2d p = t[static_cast<std::size_t>(ankle[side])].head<2>();
            Eigen::Vector2d delta = Eigen::Vector2d::Zero();
            double w_sum = 0.0;
            const auto weight = [&](int d) { return d < width ? 0.5 * (1.0 + std::cos(M_PI * d / width)) : 0.0; };
            if (start > 0) {  // stance before: lift-off at `start`
              const double w = weight(k - start + 1);
              delta += w * (anchors[sd][static_cast<std::size_t>(start - 1)] - p);
              w_sum += w;
            }
            if (end < F) {  // stance after: touchdown at `end`
              const double w = weight(end - k);
              delta += w * (anchors[sd][static_cast<std::size_t>(end)] - p);
              w_sum += w;
            }
            if (w_sum > 1.0) delta /= w_sum;
            t[static_cast<std::size_t>(ankle[side])].head<2>() += delta;
            t[static_cast<std::size_t>(toe[side])].head<2>() += delta;
          }
        }
        start = end;
      }
    }
  }

  RobotMotion& m = res.motion;
  m.source_file = human.source_file;
  m.fps = human.fps;
  m.q.resize(F, n);
  m.p_WB.resize(F, 3);
  m.R_WB.resize(static_cast<std::size_t>(F));
  m.clamp_excess.setZero(F, n);
  res.achieved.resize(static_cast<std::size_t>(F));

  const Eigen::VectorXd q_default = robot.defaultPose();
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  Eigen::VectorXd base(kBaseDim), q = q_default;
  FrameTargets t;
  t.x_prev.resize(kBaseDim + n);
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < F; ++k) {
    const HumanFrame& h = human.frames[static_cast<std::size_t>(k)];
    t.p = res.targets[static_cast<std::size_t>(k)];
    t.R_pelvis = h.R_WPelvis.toRotationMatrix();
    t.R_torso = h.R_WTorso.toRotationMatrix();
    for (std::size_t sd = 0; sd < 2; ++sd) {
      t.R_foot[sd] = h.R_WFoot[sd].toRotationMatrix();
      t.contact[sd] = res.contacts[static_cast<std::size_t>(k)][sd];
      t.anchor[sd] = anchors[sd][static_cast<std::size_t>(k)];
    }
    if (k == 0) {
      const Eigen::Vector3d rpy = matrixToRpy(t.R_pelvis);
      base << t.p[0].x(), t.p[0].y(), t.p[0].z(), rpy.x(), rpy.y(), rpy.z();
      if (options.level_pelvis) base(3) = base(4) = 0.0;
    } else {
      // Keep yaw continuous: the solver's yaw stays near the previous one.
      base(5) = wrapTo(base(5), base(5));
    }
    auto* functor = new FrameCost(&kin, &t, &options, &q_default);
    auto* cost = new ceres::DynamicNumericDiffCostFunction<FrameCost, ceres::CENTRAL>(functor);
    cost->AddParameterBlock(kBaseDim);
    cost->AddParameterBlock(static_cast<int>(n));
    cost->SetNumResiduals(functor->numResiduals());
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, base.data(), q.data());
    if (options.level_pelvis) problem.SetManifold(base.data(), new ceres::SubsetManifold(kBaseDim, {3, 4}));
    for (Eigen::Index j = 0; j < n; ++j) {
      q(j) = std::min(upper(j), std::max(lower(j), q(j)));
      problem.SetParameterLowerBound(q.data(), static_cast<int>(j), lower(j));
      problem.SetParameterUpperBound(q.data(), static_cast<int>(j), upper(j));
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = k == 0 ? 4 * options.max_iterations : options.max_iterations;
    so.function_tolerance = 1e-12;
    so.gradient_tolerance = 1e-12;
    so.parameter_tolerance = 1e-10;
    so.logging_type = ceres::SILENT;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    m.q.row(k) = q.transpose();
    m.p_WB.row(k) = base.head<3>().transpose();
    m.R_WB[static_cast<std::size_t>(k)] = Eigen::Quaterniond(rpyToMatrix(base(3), base(4), base(5)));
    Isometry X_WB = Isometry::Identity();
    X_WB.linear() = m.R_WB[static_cast<std::size_t>(k)].toRotationMatrix();
    X_WB.translation() = base.head<3>();
    kin.compute(q.data());
    HumanFrame achieved;
    kin.toFrame(X_WB, achieved);
    res.achieved[static_cast<std::size_t>(k)] = achieved.p_WK;
    t.has_prev = true;
    t.x_prev.head(kBaseDim) = base;
    t.x_prev.tail(n) = q;
  }
  res.solve_ms_per_frame =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / static_cast<double>(F);
  computeSoleTracks(m, model.leftLeg(), model.rightLeg());
  return res;
}

RetargetStats retargetStats(const RetargetResult& result, const RobotConfig& robot, int begin, int end) {
  const RobotMotion& m = result.motion;
  if (begin < 0 || end > m.numFrames() || begin >= end)
    throw std::out_of_range(fmt::format("retargetStats: window [{}, {}) outside [0, {})", begin, end, m.numFrames()));
  RetargetStats st;
  st.solve_ms_per_frame = result.solve_ms_per_frame;
  const Keypoint limb[] = {Keypoint::kLeftKnee,  Keypoint::kRightKnee,  Keypoint::kLeftAnkle,  Keypoint::kRightAnkle,
                           Keypoint::kLeftToe,   Keypoint::kRightToe,   Keypoint::kLeftElbow,  Keypoint::kRightElbow,
                           Keypoint::kLeftWrist, Keypoint::kRightWrist, Keypoint::kLeftShoulder, Keypoint::kRightShoulder};
  double sum = 0.0;
  int count = 0;
  for (int k = begin; k < end; ++k)
    for (Keypoint kp : limb) {
      const double e = (result.achieved[static_cast<std::size_t>(k)][static_cast<std::size_t>(kp)] -
                        result.targets[static_cast<std::size_t>(k)][static_cast<std::size_t>(kp)]).norm();
      sum += e;
      ++count;
      st.keypoint_error_max = std::max(st.keypoint_error_max, e);
    }
  st.keypoint_error_mean = count > 0 ? sum / count : 0.0;
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  for (int k = begin; k < end; ++k)
    for (Eigen::Index j = 0; j < m.q.cols(); ++j)
      if (m.q(k, j) < lower(j) - 1e-9 || m.q(k, j) > upper(j) + 1e-9) ++st.joint_limit_violations;
  double skate_sum = 0.0;
  for (int side = 0; side < 2; ++side) {
    const auto sd = static_cast<std::size_t>(side);
    const Eigen::MatrixXd& p = m.p_WS[sd];
    for (int k = begin; k < end; ++k) st.penetration_max_mm = std::max(st.penetration_max_mm, -1000.0 * p(k, 2));
    int start = begin;
    while (start < end) {
      int stop = start;
      const bool c = result.contacts[static_cast<std::size_t>(start)][sd];
      while (stop < end && result.contacts[static_cast<std::size_t>(stop)][sd] == c) ++stop;
      if (c && stop - start >= 2) {
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (int k = start; k < stop; ++k) mean += p.row(k).head<2>().transpose();
        mean /= (stop - start);
        double drift = 0.0;
        for (int k = start; k < stop; ++k) drift = std::max(drift, (p.row(k).head<2>().transpose() - mean).norm());
        skate_sum += 1000.0 * drift;
        st.skate_max_mm = std::max(st.skate_max_mm, 1000.0 * drift);
        ++st.stances;
      }
      start = stop;
    }
  }
  st.skate_mean_mm = st.stances > 0 ? skate_sum / st.stances : 0.0;
  st.penetration_max_mm = std::max(0.0, st.penetration_max_mm);
  return st;
}

void writeRetargetCsv(const RetargetResult& result, const std::string& path, int begin, int end) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << "frame,source,keypoint,x,y,z,contact_left,contact_right\n";
  for (int k = std::max(0, begin); k < std::min(end, result.motion.numFrames()); ++k)
    for (std::size_t i = 0; i < kNumKeypoints; ++i) {
      const auto c = result.contacts[static_cast<std::size_t>(k)];
      const char* name = keypointName(static_cast<Keypoint>(i));
      const Eigen::Vector3d& t = result.targets[static_cast<std::size_t>(k)][i];
      const Eigen::Vector3d& a = result.achieved[static_cast<std::size_t>(k)][i];
      const Eigen::Vector3d& hu = result.human[static_cast<std::size_t>(k)][i];
      f << fmt::format("{},human,{},{:.4f},{:.4f},{:.4f},{},{}\n", k - begin, name, hu.x(), hu.y(), hu.z(), int(c[0]), int(c[1]));
      f << fmt::format("{},target,{},{:.4f},{:.4f},{:.4f},{},{}\n", k - begin, name, t.x(), t.y(), t.z(), int(c[0]), int(c[1]));
      f << fmt::format("{},robot,{},{:.4f},{:.4f},{:.4f},{},{}\n", k - begin, name, a.x(), a.y(), a.z(), int(c[0]), int(c[1]));
    }
}

}  // namespace pmg::motion
