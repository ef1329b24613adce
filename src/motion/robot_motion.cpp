#include "pmg/motion/robot_motion.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace pmg::motion {

std::array<Eigen::Vector3d, 4> g1SolePoints_F() {
  // Sphere centres are 0.03 m below the ankle pitch axis, which is 0.017558 m above the ankle
  // roll axis (URDF ankle_roll_joint origin); lowest point = centre − radius 0.005 m.
  const double z = -0.03 + 0.017558 - 0.005;
  return {Eigen::Vector3d(-0.05, 0.025, z), Eigen::Vector3d(-0.05, -0.025, z), Eigen::Vector3d(0.12, 0.03, z),
          Eigen::Vector3d(0.12, -0.03, z)};
}

double headingOf(const Eigen::Quaterniond& R_WB) {
  const Eigen::Matrix3d R = R_WB.toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0));
}

namespace {
void soleTracks(RobotMotion& motion, const LimbChain& left_leg, const LimbChain& right_leg, bool place) {
  const int F = motion.numFrames();
  const auto soles = g1SolePoints_F();
  ChainFkWorkspace ws_left(left_leg), ws_right(right_leg);
  ChainFkWorkspace* ws[2] = {&ws_left, &ws_right};
  for (auto& p : motion.p_WS) p.setZero(F, 3);
  for (int k = 0; k < F; ++k) {
    const Eigen::VectorXd q = motion.q.row(k).transpose();
    const Eigen::Matrix3d R = motion.R_WB[static_cast<std::size_t>(k)].toRotationMatrix();
    Eigen::Vector3d lowest[2];
    for (int f = 0; f < 2; ++f) {
      Eigen::Isometry3d X_BF;
      if (!ws[f]->tipPose(q, X_BF)) throw std::runtime_error("placeOnGround: KDL forward kinematics failed");
      // x, y: centre of the sole points (stable while the foot rolls heel→toe); z: lowest point.
      double zmin = std::numeric_limits<double>::infinity();
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (const auto& s : soles) {
        const Eigen::Vector3d p = R * (X_BF * s);  // relative to the pelvis, world-aligned
        centre += p / static_cast<double>(soles.size());
        zmin = std::min(zmin, p.z());
      }
      lowest[f] = Eigen::Vector3d(centre.x(), centre.y(), zmin);
    }
    if (place) motion.p_WB(k, 2) = -std::min(lowest[0].z(), lowest[1].z());
    const double height = motion.p_WB(k, 2);
    for (int f = 0; f < 2; ++f) {
      Eigen::Vector3d p = lowest[f];
      p.x() += motion.p_WB(k, 0);
      p.y() += motion.p_WB(k, 1);
      p.z() += height;
      motion.p_WS[static_cast<std::size_t>(f)].row(k) = p.transpose();
    }
  }
}

}  // namespace

void placeOnGround(RobotMotion& motion, const LimbChain& left_leg, const LimbChain& right_leg) {
  soleTracks(motion, left_leg, right_leg, true);
}

void computeSoleTracks(RobotMotion& motion, const LimbChain& left_leg, const LimbChain& right_leg) {
  soleTracks(motion, left_leg, right_leg, false);
}

}  // namespace pmg::motion
