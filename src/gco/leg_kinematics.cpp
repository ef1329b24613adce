#include "pmg/gco/leg_kinematics.hpp"

#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"

#include <cmath>
#include <stdexcept>

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <urdf_parser/urdf_parser.h>

namespace pmg::gco {

void LegModelOptions::validate() const {
  if (base_link.empty()) throw std::invalid_argument("LegModelOptions.base_link: must not be empty");
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (foot_links[f].empty()) {
      throw std::invalid_argument("LegModelOptions.foot_links[" + std::to_string(f) + "]: must not be empty");
    }
  }
  if (!p_FS_F.allFinite() || p_FS_F.norm() > 0.5) {
    throw std::invalid_argument("LegModelOptions.p_FS_F: expected finite, |p| <= 0.5 m");
  }
}

std::shared_ptr<const LegModel> LegModel::build(std::array<KDL::Chain, kNumFeet> chains, const LegModelOptions& options,
                                                const std::string& source) {
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDFFile(source);
  if (!urdf_model) throw std::runtime_error(source + ": cannot read or parse the URDF");
  std::shared_ptr<LegModel> model(new LegModel());
  model->options_ = options;
  model->urdf_path_ = source;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    KDL::Chain& chain = chains[f];
    if (static_cast<int>(chain.getNrOfJoints()) != kLegDofs) {
      throw std::runtime_error(source + ": chain " + options.base_link + " -> " + options.foot_links[f] + " has " +
                               std::to_string(chain.getNrOfJoints()) + " moving joints, expected " +
                               std::to_string(kLegDofs));
    }
    const Eigen::Vector3d& p = options.p_FS_F;
    chain.addSegment(KDL::Segment("sole", KDL::Joint(KDL::Joint::None), KDL::Frame(KDL::Vector(p.x(), p.y(), p.z()))));
    int j = 0;
    for (unsigned s = 0; s < chain.getNrOfSegments(); ++s) {
      const KDL::Joint& joint = chain.getSegment(s).getJoint();
      if (joint.getType() == KDL::Joint::None) continue;
      model->joint_names_[f][j] = joint.getName();
      const urdf::JointConstSharedPtr uj = urdf_model->getJoint(joint.getName());
      if (uj && uj->limits) {
        model->limits_[f][j] = {uj->limits->lower, uj->limits->upper};
      } else {
        model->limits_[f][j] = {-M_PI, M_PI};
      }
      ++j;
    }
    model->chains_[f] = chain;
  }
  return model;
}

std::shared_ptr<const LegModel> LegModel::fromUrdfFile(const std::string& urdf_path, const LegModelOptions& options) {
  options.validate();
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDFFile(urdf_path);
  if (!urdf_model) throw std::runtime_error(urdf_path + ": cannot read or parse the URDF");
  // KDL has no root-link inertia: kdl_parser drops it with a (colour-coded) warning on every load.
  if (urdf_model->root_link_) urdf_model->root_link_->inertial.reset();
  KDL::Tree tree;
  if (!kdl_parser::treeFromUrdfModel(*urdf_model, tree)) {
    throw std::runtime_error(urdf_path + ": kdl_parser could not build a KDL tree");
  }
  std::array<KDL::Chain, kNumFeet> chains;
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    if (!tree.getChain(options.base_link, options.foot_links[f], chains[f])) {
      throw std::runtime_error(urdf_path + ": no kinematic chain from link '" + options.base_link + "' to link '" +
                               options.foot_links[f] + "'");
    }
  }
  return build(std::move(chains), options, urdf_path);
}

std::shared_ptr<const LegModel> LegModel::fromRobotConfig(const RobotConfig& config, const LegModelOptions& options) {
  LegModelOptions o = options;
  o.base_link = config.base_link;
  o.foot_links = {config.left_foot_link, config.right_foot_link};
  o.validate();
  const KinematicModel kinematics(config);
  return build({kinematics.leftLeg().chain, kinematics.rightLeg().chain}, o, config.urdf_path);
}

LegJointIndex LegModel::jointIndices(const std::vector<std::string>& joint_names) const {
  LegJointIndex idx{};
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    for (int j = 0; j < kLegDofs; ++j) {
      idx[f][j] = -1;
      for (std::size_t k = 0; k < joint_names.size(); ++k) {
        if (joint_names[k] == joint_names_[f][j]) idx[f][j] = static_cast<int>(k);
      }
      if (idx[f][j] < 0) {
        throw std::runtime_error("LegModel::jointIndices: leg joint '" + joint_names_[f][j] +
                                 "' is missing from the joint-name list");
      }
    }
  }
  return idx;
}

struct LegKinematics::Impl {
  struct PerFoot {
    explicit PerFoot(const KDL::Chain& c)
        : fk(c), jac_solver(c), ik(c, Eigen::Matrix<double, 6, 1>::Ones(), 1e-13, 1000, 1e-15), q(kLegDofs), q_out(kLegDofs), jac(kLegDofs) {}
    KDL::ChainFkSolverPos_recursive fk;
    KDL::ChainJntToJacSolver jac_solver;
    KDL::ChainIkSolverPos_LMA ik;
    KDL::JntArray q, q_out;
    KDL::Jacobian jac;
    KDL::Frame frame;
  };
  std::array<std::unique_ptr<PerFoot>, kNumFeet> feet;
};

LegKinematics::LegKinematics(std::shared_ptr<const LegModel> model) : model_(std::move(model)) {
  if (!model_) throw std::invalid_argument("LegKinematics: model must not be null");
  impl_ = std::make_unique<Impl>();
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    impl_->feet[f] = std::make_unique<Impl::PerFoot>(model_->chain(static_cast<Foot>(f)));
  }
}

LegKinematics::~LegKinematics() = default;

namespace {
void toEigen(const KDL::Frame& fr, Eigen::Vector3d* p, Eigen::Matrix3d* R) {
  for (int r = 0; r < 3; ++r) {
    (*p)(r) = fr.p(r);
    for (int c = 0; c < 3; ++c) (*R)(r, c) = fr.M(r, c);
  }
}
void toIsometry(const KDL::Frame& fr, Eigen::Isometry3d* X) {
  Eigen::Vector3d p;
  Eigen::Matrix3d R;
  toEigen(fr, &p, &R);
  X->linear() = R;
  X->translation() = p;
}
}  // namespace

bool LegKinematics::forward(Foot foot, const LegVector& q, Eigen::Isometry3d* X_BS) noexcept {
  if (!q.allFinite() || X_BS == nullptr) return false;
  Impl::PerFoot& pf = *impl_->feet[LegModel::index(foot)];
  pf.q.data = q;
  if (pf.fk.JntToCart(pf.q, pf.frame) < 0) return false;
  toIsometry(pf.frame, X_BS);
  return true;
}

bool LegKinematics::compute(Foot foot, const LegVector& q, const LegVector& qd, FootKinematics* out) noexcept {
  if (!q.allFinite() || !qd.allFinite() || out == nullptr) return false;
  Impl::PerFoot& pf = *impl_->feet[LegModel::index(foot)];
  pf.q.data = q;
  if (pf.fk.JntToCart(pf.q, pf.frame) < 0) return false;
  // Jacobian of the tip (S) expressed in the root frame B, reference point S.
  if (pf.jac_solver.JntToJac(pf.q, pf.jac) < 0) return false;
  toEigen(pf.frame, &out->p_BS_B, &out->R_BF);
  const Eigen::Matrix<double, 6, 1> twist = pf.jac.data * qd;
  out->v_BS_B = twist.head<3>();
  out->w_BF_B = twist.tail<3>();
  return true;
}

bool LegKinematics::jacobian(Foot foot, const LegVector& q, Eigen::Isometry3d* X_BS,
                             Eigen::Matrix<double, 6, kLegDofs>* J_B) noexcept {
  if (!q.allFinite() || X_BS == nullptr || J_B == nullptr) return false;
  Impl::PerFoot& pf = *impl_->feet[LegModel::index(foot)];
  pf.q.data = q;
  if (pf.fk.JntToCart(pf.q, pf.frame) < 0) return false;
  if (pf.jac_solver.JntToJac(pf.q, pf.jac) < 0) return false;
  toIsometry(pf.frame, X_BS);
  *J_B = pf.jac.data;
  return true;
}

bool LegKinematics::orientation(Foot foot, const LegVector& q, Eigen::Matrix3d* R_BF,
                                Eigen::Matrix<double, 3, kLegDofs>* J_w_B) noexcept {
  if (R_BF == nullptr || J_w_B == nullptr) return false;
  Eigen::Isometry3d X;
  Eigen::Matrix<double, 6, kLegDofs> J;
  if (!jacobian(foot, q, &X, &J)) return false;
  *R_BF = X.linear();
  *J_w_B = J.bottomRows<3>();
  return true;
}

double LegKinematics::inverse(Foot foot, const Eigen::Isometry3d& X_BS_target, const LegVector& q_init, LegVector* q) {
  Impl::PerFoot& pf = *impl_->feet[LegModel::index(foot)];
  KDL::Frame target;
  for (int r = 0; r < 3; ++r) {
    target.p(r) = X_BS_target.translation()(r);
    for (int c = 0; c < 3; ++c) target.M(r, c) = X_BS_target.linear()(r, c);
  }
  pf.q.data = q_init;
  pf.ik.CartToJnt(pf.q, target, pf.q_out);
  const auto& lim = model_->jointLimits(foot);
  for (int j = 0; j < kLegDofs; ++j) {
    (*q)(j) = std::min(std::max(pf.q_out(j), lim[j].first), lim[j].second);
  }
  Eigen::Isometry3d X;
  if (!forward(foot, *q, &X)) return std::numeric_limits<double>::infinity();
  const Eigen::AngleAxisd err(X.linear().transpose() * X_BS_target.linear());
  return (X.translation() - X_BS_target.translation()).norm() + std::abs(err.angle());
}

}  // namespace pmg::gco
