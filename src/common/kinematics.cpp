#include "pmg/common/kinematics.hpp"

#include <algorithm>
#include <cmath>

#include <kdl_parser/kdl_parser.hpp>
#include <urdf_parser/urdf_parser.h>

namespace pmg {

Eigen::Matrix3d soleLevelingRotation(const Eigen::Vector3d& n_B, double* pitch, double* roll) noexcept {
  double p = 0.0, r = 0.0;
  const double len = n_B.norm();
  if (len > 0.0 && std::isfinite(len)) {
    // With R = Ry(p)·Rx(r): Rᵀ e_z = (−sin p, cos p sin r, cos p cos r) = n̂.
    const Eigen::Vector3d n = n_B / len;
    p = std::asin(std::clamp(-n.x(), -1.0, 1.0));
    r = std::atan2(n.y(), n.z());
  }
  if (pitch) *pitch = p;
  if (roll) *roll = r;
  return (Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX())).toRotationMatrix();
}

KDL::Tree kdlTreeFromUrdfFile(const std::string& urdf_path) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(urdf_path);
  if (!model || !model->root_link_) throw ConfigError(urdf_path + ": cannot read or parse the URDF");
  model->root_link_->inertial.reset();  // KDL has no root inertia; kdl_parser would warn and drop it
  KDL::Tree tree;
  if (!kdl_parser::treeFromUrdfModel(*model, tree))
    throw ConfigError(urdf_path + ": kdl_parser could not build a KDL tree from this URDF");
  return tree;
}

Eigen::Isometry3d toEigen(const KDL::Frame& f) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = f.M(r, c);
    X.translation()[r] = f.p[r];
  }
  return X;
}

KinematicModel::KinematicModel(const RobotConfig& config) : config_(config) {
  tree_ = kdlTreeFromUrdfFile(config_.urdf_path);
  // Every configured joint must exist in the URDF as a moving joint.
  for (const auto& j : config_.joints) {
    bool found = false;
    for (const auto& [name, element] : tree_.getSegments()) {
      const KDL::Joint& joint = GetTreeElementSegment(element).getJoint();
      if (joint.getName() == j.name && joint.getType() != KDL::Joint::None) found = true;
    }
    if (!found)
      throw ConfigError(config_.source_file + ": joint '" + j.name + "' is not a moving joint of URDF " +
                        config_.urdf_path);
  }
}

LimbChain KinematicModel::chain(const std::string& root_link, const std::string& tip_link) const {
  LimbChain limb;
  limb.root_link = root_link;
  limb.tip_link = tip_link;
  if (!tree_.getChain(root_link, tip_link, limb.chain))
    throw ConfigError(config_.urdf_path + ": no KDL chain from link '" + root_link + "' to link '" + tip_link + "'");
  for (unsigned s = 0; s < limb.chain.getNrOfSegments(); ++s) {
    const KDL::Joint& joint = limb.chain.getSegment(s).getJoint();
    if (joint.getType() == KDL::Joint::None) continue;
    const int idx = config_.jointIndex(joint.getName());
    if (idx < 0)
      throw ConfigError(config_.source_file + ": URDF joint '" + joint.getName() + "' on chain " + root_link + " -> " +
                        tip_link + " is missing from the robot config's joints");
    limb.joint_index.push_back(idx);
  }
  return limb;
}

ChainFkWorkspace::ChainFkWorkspace(const LimbChain& limb)
    : limb_(&limb), solver_(limb.chain), q_chain_(limb.chain.getNrOfJoints()) {}

bool ChainFkWorkspace::tipPose(const Eigen::VectorXd& q, Eigen::Isometry3d& X_RT) noexcept {
  return segmentPose(q, -1, X_RT);
}

bool ChainFkWorkspace::segmentPose(const Eigen::VectorXd& q, int segment, Eigen::Isometry3d& X_RS) noexcept {
  for (std::size_t i = 0; i < limb_->joint_index.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(limb_->joint_index[i]);
    if (k >= q.size()) return false;
    q_chain_(static_cast<unsigned>(i)) = q[k];
  }
  if (solver_.JntToCart(q_chain_, frame_, segment) < 0) return false;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X_RS.linear()(r, c) = frame_.M(r, c);
    X_RS.translation()[r] = frame_.p[r];
  }
  X_RS.makeAffine();
  return true;
}

}  // namespace pmg
