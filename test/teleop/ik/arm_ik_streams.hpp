#pragma once
// Target streams for the arm IK tests and benchmark (test/teleop/ik, bench/teleop/ik): a smooth
// joint trajectory of both arms whose forward kinematics is the "pose stream generated from the
// robot's own forward kinematics" of issue 13, and a stream of random reachable jumps.
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <random>

#include "pmg/teleop/arm_ik.hpp"

namespace pmg::teleop::ik_streams {

/// Smooth arm motion around the nominal pose at time t [s]: per joint
/// q_j(t) = nominal_j + offset_j + A_j sin(2π f_j t + φ_j), mirrored for the right arm (joints with
/// mirror sign −1: roll and yaw). Amplitudes 0.25..0.5 rad at 0.13..0.37 Hz: peak joint speed
/// ≤ 1.2 rad/s, far below the 6 rad/s the controller allows. The shoulder roll offset keeps the
/// arms clear of the torso. Clamped to the joint limits.
inline std::array<ArmJoints, 2> smoothArmTrajectory(const ArmIk& ik, double t) {
  constexpr double kPi = 3.14159265358979323846;
  constexpr std::array<double, kArmDofs> kOffset{-0.3, 0.3, 0.0, -0.4, 0.0, 0.0, 0.0};
  constexpr std::array<double, kArmDofs> kAmplitude{0.5, 0.25, 0.4, 0.35, 0.5, 0.4, 0.4};
  constexpr std::array<double, kArmDofs> kFrequency{0.17, 0.23, 0.13, 0.29, 0.37, 0.31, 0.19};
  constexpr std::array<double, kArmDofs> kPhase{0.0, 1.1, 2.3, 0.7, 1.9, 2.9, 0.4};
  constexpr std::array<double, kArmDofs> kMirror{1, -1, -1, 1, -1, 1, -1};
  std::array<ArmJoints, 2> q;
  for (int h = 0; h < 2; ++h) {
    for (int j = 0; j < kArmDofs; ++j) {
      const double s = h == 0 ? 1.0 : kMirror[j];
      // The right arm runs with a phase lag so the arms do not move symmetrically.
      const double phase = kPhase[j] + (h == 0 ? 0.0 : 1.3);
      const double v =
          ik.nominal(h)[j] + s * (kOffset[j] + kAmplitude[j] * std::sin(2.0 * kPi * kFrequency[j] * t + phase));
      q[h][j] = std::fmin(std::fmax(v, ik.lower(h)[j]), ik.upper(h)[j]);
    }
  }
  return q;
}

/// The IK's answer for the pose of q_a, computed independently of ArmIk's solver: the arm's
/// configuration with the same hand pose that satisfies the documented redundancy resolution
/// (the null-space pull toward the nominal pose is stationary: nᵀ(q − q_nominal) = 0 for the unit
/// null vector n of the hand Jacobian). Found by sliding q_a along the self-motion manifold:
/// Jacobian by central differences of ArmIk::forwardKinematics, n from an SVD, a null-space step
/// followed by a Newton pose correction, until both residuals vanish. Returns false when it does
/// not converge or leaves the joint limits.
inline bool resolveRedundancy(const ArmIk& ik, int hand, const ArmJoints& q_a, ArmJoints* q_out) {
  using Vec7 = Eigen::Matrix<double, kArmDofs, 1>;
  const ArmPose target = ik.forwardKinematics(hand, q_a);
  Vec7 q = Eigen::Map<const Vec7>(q_a.data());
  const Vec7 q_nom = Eigen::Map<const Vec7>(ik.nominal(hand).data());
  auto pose = [&](const Vec7& v) {
    ArmJoints a;
    for (int j = 0; j < kArmDofs; ++j) a[j] = v(j);
    return ik.forwardKinematics(hand, a);
  };
  auto error = [&](const ArmPose& p) {  // 6-D error target − p (position; rotation vector in T)
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = target.position - p.position;
    const Eigen::AngleAxisd aa(target.orientation * p.orientation.conjugate());
    e.tail<3>() = aa.angle() * aa.axis();
    return e;
  };
  for (int it = 0; it < 200; ++it) {
    Eigen::Matrix<double, 6, kArmDofs> J;
    const ArmPose p0 = pose(q);
    for (int j = 0; j < kArmDofs; ++j) {
      constexpr double kH = 1e-6;
      Vec7 qp = q, qm = q;
      qp(j) += kH;
      qm(j) -= kH;
      const ArmPose a = pose(qp), b = pose(qm);
      J.block<3, 1>(0, j) = (a.position - b.position) / (2 * kH);
      const Eigen::AngleAxisd aa(a.orientation * b.orientation.conjugate());
      J.block<3, 1>(3, j) = aa.angle() * aa.axis() / (2 * kH);
    }
    const Eigen::JacobiSVD<Eigen::Matrix<double, 6, kArmDofs>> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Vec7 n = svd.matrixV().col(kArmDofs - 1);
    const double g = n.dot(q - q_nom);
    const Eigen::Matrix<double, 6, 1> e = error(p0);
    if (std::abs(g) < 1e-9 && e.norm() < 1e-10) {
      for (int j = 0; j < kArmDofs; ++j) {
        if (q(j) < ik.lower(hand)[j] || q(j) > ik.upper(hand)[j]) return false;
        (*q_out)[j] = q(j);
      }
      return true;
    }
    // Null-space step (at most 0.05 rad) toward the stationary point, then a Newton pose correction.
    q -= std::clamp(g, -0.05, 0.05) * n;
    q += svd.solve(error(pose(q)));
  }
  return false;
}

/// FK of both arms.
inline std::array<ArmPose, 2> armPoses(const ArmIk& ik, const std::array<ArmJoints, 2>& q) {
  return {ik.forwardKinematics(0, q[0]), ik.forwardKinematics(1, q[1])};
}

/// Random collision-free configuration of both arms (uniform within the limits, capsules at least
/// `clearance` apart, hands inside the workspace shell the IK clamps to).
inline std::array<ArmJoints, 2> randomReachableConfig(const ArmIk& ik, std::mt19937& rng, double clearance) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double m = ik.options().workspace_margin;
  for (;;) {
    std::array<ArmJoints, 2> q;
    for (int h = 0; h < 2; ++h) {
      for (int j = 0; j < kArmDofs; ++j) q[h][j] = ik.lower(h)[j] + (ik.upper(h)[j] - ik.lower(h)[j]) * u(rng);
    }
    bool inside = true;
    for (int h = 0; h < 2; ++h) {
      const double r = (ik.forwardKinematics(h, q[h]).position - ik.shoulderPosition(h)).norm();
      if (r > ik.reach(h) * (1.0 - m) || r < ik.minReach(h) * (1.0 + m)) inside = false;
    }
    if (inside && ik.minCapsuleDistance(q) >= clearance) return q;
  }
}

}  // namespace pmg::teleop::ik_streams
