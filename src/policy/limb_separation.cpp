#include "pmg/policy/limb_separation.hpp"

#include <algorithm>
#include <stdexcept>

namespace pmg::policy {

void JointCommand::resize(std::size_t nj) {
  q_des.assign(nj, 0.0);
  qd_des.assign(nj, 0.0);
  kp.assign(nj, 0.0);
  kd.assign(nj, 0.0);
}

LimbSeparation::LimbSeparation(const PolicyContract& c)
    : is_actor_(c.joint_names.size(), false), kp_(c.kp), kd_(c.kd) {
  for (const auto& name : c.actuated_joints) {
    const auto it = std::find(c.joint_names.begin(), c.joint_names.end(), name);
    if (it == c.joint_names.end()) throw std::invalid_argument("actuated joint '" + name + "' is not in joint_names");
    const auto j = static_cast<int>(it - c.joint_names.begin());
    actor_index_.push_back(j);
    is_actor_[static_cast<std::size_t>(j)] = true;
  }
}

void LimbSeparation::compose(const double* actor_q_des, const double* upper_q_des, const double* upper_qd_des,
                             JointCommand& out) const noexcept {
  const std::size_t nj = is_actor_.size();
  for (std::size_t j = 0; j < nj; ++j) {
    if (!is_actor_[j]) {
      out.q_des[j] = upper_q_des[j];
      out.qd_des[j] = upper_qd_des != nullptr ? upper_qd_des[j] : 0.0;
    }
    out.kp[j] = kp_[j];
    out.kd[j] = kd_[j];
  }
  for (std::size_t i = 0; i < actor_index_.size(); ++i) {
    const auto j = static_cast<std::size_t>(actor_index_[i]);
    out.q_des[j] = actor_q_des[i];
    out.qd_des[j] = 0.0;
  }
}

}  // namespace pmg::policy
