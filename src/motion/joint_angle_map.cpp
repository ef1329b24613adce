#include "pmg/motion/joint_angle_map.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace pmg::motion {
namespace {

constexpr double kHipRollTilt = 0.1749;        // URDF hip_roll_joint origin pitch [rad]
constexpr double kShoulderRollTilt = 0.27931;  // URDF shoulder_pitch_joint origin roll [rad] (left +, right −)

Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

double clampUnit(double x) { return std::max(-1.0, std::min(1.0, x)); }

}  // namespace

void JointAngleMapOptions::validate() const {
  if (!std::isfinite(scale)) throw std::invalid_argument("JointAngleMapOptions.scale: expected a finite number");
}

Eigen::Vector3d eulerYXZ(const Eigen::Matrix3d& R) {
  // R = Ry(a) Rx(b) Rz(c): row 1 = [cb sc, cb cc, −sb], column 2 = [sa cb, −sb, ca cb].
  const double b = std::asin(clampUnit(-R(1, 2)));
  const double a = std::atan2(R(0, 2), R(2, 2));
  const double c = std::atan2(R(1, 0), R(1, 1));
  return {a, b, c};
}

Eigen::Vector3d eulerZXY(const Eigen::Matrix3d& R) {
  // R = Rz(a) Rx(b) Ry(c): row 2 = [−cb sc, sb, cb cc], column 1 = [−sa cb, ca cb, sb].
  const double b = std::asin(clampUnit(R(2, 1)));
  const double a = std::atan2(-R(0, 1), R(1, 1));
  const double c = std::atan2(-R(2, 0), R(2, 2));
  return {a, b, c};
}

double robotLegLength(const KinematicModel& model) {
  const LimbChain leg = model.chain("pelvis", model.config().left_foot_link);
  ChainFkWorkspace ws(leg);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.config().numJoints()));
  Eigen::Isometry3d X_foot, X_hip;
  if (!ws.tipPose(q0, X_foot) || !ws.segmentPose(q0, 1, X_hip))  // after segment 1 = hip pitch link
    throw std::runtime_error("robotLegLength: KDL forward kinematics failed");
  return (X_foot.translation() - X_hip.translation()).norm();
}

RobotMotion retargetJointAngleMap(const DeepMimicMotion& motion, const KinematicModel& model,
                                  const JointAngleMapOptions& options) {
  options.validate();
  const RobotConfig& robot = model.config();
  auto idx = [&](const char* name) {
    const int i = robot.jointIndex(name);
    if (i < 0) throw std::invalid_argument(fmt::format("retargetJointAngleMap: joint '{}' not in robot config {}", name, robot.source_file));
    return static_cast<Eigen::Index>(i);
  };
  const double s = options.scale > 0.0 ? options.scale : robotLegLength(model) / kDeepMimicLegLength;
  const Eigen::Matrix3d C = deepMimicToZUp();
  auto toW = [&](const Eigen::Quaterniond& q) -> Eigen::Matrix3d { return C * q.toRotationMatrix() * C.transpose(); };

  const int F = static_cast<int>(motion.frames.size());
  const Eigen::Index n = static_cast<Eigen::Index>(robot.numJoints());
  RobotMotion out;
  out.source_file = motion.source_file;
  out.fps = motion.fps;
  out.q.resize(F, n);
  out.p_WB.setZero(F, 3);
  out.R_WB.resize(static_cast<std::size_t>(F));
  out.clamp_excess.setZero(F, n);
  const Eigen::VectorXd q_default = robot.defaultPose();
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();

  struct Side {
    const char* prefix;
    double shoulder_tilt;
  };
  const Side sides[2] = {{"left_", kShoulderRollTilt}, {"right_", -kShoulderRollTilt}};

  for (int k = 0; k < F; ++k) {
    const DeepMimicFrame& f = motion.frames[static_cast<std::size_t>(k)];
    Eigen::VectorXd q = q_default;
    for (int side = 0; side < 2; ++side) {
      const std::string pre = sides[side].prefix;
      const bool left = side == 0;
      const Eigen::Vector3d hip = eulerYXZ(toW(left ? f.left_hip : f.right_hip) * Ry(-kHipRollTilt));
      q(idx((pre + "hip_pitch_joint").c_str())) = hip(0) + kHipRollTilt;
      q(idx((pre + "hip_roll_joint").c_str())) = hip(1);
      q(idx((pre + "hip_yaw_joint").c_str())) = hip(2);
      q(idx((pre + "knee_joint").c_str())) = -(left ? f.left_knee : f.right_knee);
      const Eigen::Vector3d ankle = eulerYXZ(toW(left ? f.left_ankle : f.right_ankle));
      q(idx((pre + "ankle_pitch_joint").c_str())) = ankle(0);
      q(idx((pre + "ankle_roll_joint").c_str())) = ankle(1);
      const double b = sides[side].shoulder_tilt;
      const Eigen::Vector3d sh = eulerYXZ(Rx(-b) * toW(left ? f.left_shoulder : f.right_shoulder));
      q(idx((pre + "shoulder_pitch_joint").c_str())) = sh(0);
      q(idx((pre + "shoulder_roll_joint").c_str())) = sh(1) + b;
      q(idx((pre + "shoulder_yaw_joint").c_str())) = sh(2);
      q(idx((pre + "elbow_joint").c_str())) = M_PI / 2 - (left ? f.left_elbow : f.right_elbow);
    }
    const Eigen::Vector3d waist = eulerZXY(toW(f.chest));
    q(idx("waist_yaw_joint")) = waist(0);
    q(idx("waist_roll_joint")) = waist(1);
    q(idx("waist_pitch_joint")) = waist(2);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (q(j) < lower(j)) {
        out.clamp_excess(k, j) = lower(j) - q(j);
        q(j) = lower(j);
      } else if (q(j) > upper(j)) {
        out.clamp_excess(k, j) = q(j) - upper(j);
        q(j) = upper(j);
      }
    }
    out.q.row(k) = q.transpose();
    out.R_WB[static_cast<std::size_t>(k)] = Eigen::Quaterniond(toW(f.R_MR));
    const Eigen::Vector3d p = C * f.p_MR;
    out.p_WB(k, 0) = s * p.x();
    out.p_WB(k, 1) = s * p.y();
  }
  placeOnGround(out, model.leftLeg(), model.rightLeg());
  return out;
}

}  // namespace pmg::motion
