// Zero-point calibration in the MuJoCo SIL (no gantry): the full tool path (captureZeroPoses through a
// pmg::HalBackend, then the estimator). See docs/calibration.md, "Zero-point calibration", for the
// measured recovery errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/calib/zero_calibration.hpp"
#include "pmg/calib/zero_io.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg::calib {
namespace {

struct FootPose {
  Eigen::Vector3d p;
  double yaw;
};

std::array<FootPose, 2> feet(MujocoBackend& sim, const RobotConfig& robot) {
  std::array<FootPose, 2> out{};
  int k = 0;
  for (const std::string& b : {robot.left_foot_link, robot.right_foot_link}) {
    const int id = mj_name2id(sim.model(), mjOBJ_BODY, b.c_str());
    const double* x = sim.data()->xpos + 3 * id;
    const double* R = sim.data()->xmat + 9 * id;
    out[static_cast<std::size_t>(k++)] = {Eigen::Vector3d(x[0], x[1], x[2]), std::atan2(R[3], R[0])};
  }
  return out;
}

/// Pushes the pelvis once, at a given backend time, through the same HAL interface.
class PushingBackend final : public HalBackend {
 public:
  PushingBackend(MujocoBackend& sim, double at, Eigen::Vector3d f) : sim_(sim), at_(at), f_(std::move(f)) {}
  const char* name() const noexcept override { return "mujoco+push"; }
  double cyclePeriod() const noexcept override { return sim_.cyclePeriod(); }
  BackendStatus exchange(const LowCommand& c, LowState& s) noexcept override {
    if (!pushed_ && sim_.data()->time >= at_) {
      sim_.push(sim_.pelvisBody(), f_, 0.3);
      pushed_ = true;
    }
    return sim_.exchange(c, s);
  }

 private:
  MujocoBackend& sim_;
  double at_;
  Eigen::Vector3d f_;
  bool pushed_ = false;
};

class ZeroSilTest : public ::testing::Test {
 protected:
  void SetUp() override {
    robot = pmg::test::g1Robot();
    model = gco::LegModel::fromRobotConfig(robot);
    protocol = loadZeroProtocol(pmg::test::g1ZeroProtocolPath());
  }
  RobotConfig robot;
  std::shared_ptr<const gco::LegModel> model;
  ZeroProtocol protocol;
};

// Without hidden offsets: the capture holds every pose still, the feet stay planted (SIL truth), the
// estimator converges and the estimated offsets stay small.
TEST_F(ZeroSilTest, ToolPathWithoutOffsetsKeepsFeetPlanted) {
  MujocoBackendOptions bo;
  bo.gantry.enabled = false;
  MujocoBackend sim(robot, bo);
  std::array<FootPose, 2> start{};
  bool have_start = false;
  const ZeroCapture cap = captureZeroPoses(sim, robot, model, protocol, [&](const std::string& s) {
    if (!have_start && s.rfind("home: centre", 0) == 0) {
      start = feet(sim, robot);
      have_start = true;
    }
  });
  ASSERT_TRUE(have_start);
  const auto end = feet(sim, robot);
  for (int f = 0; f < 2; ++f) {
    EXPECT_LT((end[f].p - start[f].p).head<2>().norm(), 0.003) << "foot " << f << " slipped";
    EXPECT_LT(std::abs(end[f].yaw - start[f].yaw), 0.01) << "foot " << f << " turned";
  }
  EXPECT_FALSE(cap.feet_moved) << cap.home_drift;
  ASSERT_EQ(cap.samples.size(), protocol.poses.size());
  for (const auto& s : cap.samples) EXPECT_TRUE(s.valid) << s.name << ": " << s.reason;
  ZeroEstimator est(model, {});
  const ZeroEstimate r = est.estimate(cap.samples);
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_LT(r.z.cwiseAbs().maxCoeff(), 0.05) << r.z.transpose();
}

// A shove during a hold: the capture refuses the pose (moving) or aborts (tipped); it never returns a
// sample taken while the robot moved.
TEST_F(ZeroSilTest, PushDuringHoldIsRefusedOrAborts) {
  MujocoBackendOptions bo;
  bo.gantry.enabled = false;
  MujocoBackend sim(robot, bo);
  ZeroProtocol p = protocol;
  p.poses.resize(3);
  // Time of the second pose's averaging window: ramp + settle + home move + settle + 2 moves + 1 hold.
  const double t_push = p.move_s + p.settle_s + p.move_s + p.settle_s + 2 * p.move_s + p.hold_s +
                        (p.hold_s - p.average_s) + 0.05;
  PushingBackend pushing(sim, t_push, Eigen::Vector3d(0.0, 120.0, 0.0));
  try {
    const ZeroCapture cap = captureZeroPoses(pushing, robot, model, p);
    ASSERT_EQ(cap.samples.size(), 3u);
    EXPECT_TRUE(cap.samples[0].valid) << cap.samples[0].reason;
    EXPECT_FALSE(cap.samples[1].valid);
    EXPECT_NE(cap.samples[1].reason.find("moving"), std::string::npos) << cap.samples[1].reason;
    std::printf("pushed pose refused: %s\n", cap.samples[1].reason.c_str());
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tipped"), std::string::npos) << e.what();
    std::printf("capture aborted: %s\n", e.what());
  }
}

// Issue #6 acceptance: random hidden offsets |o| <= 0.05 rad on the 12 leg joints, recovered within
// 0.005 rad. SIL on the calibration bench floor (MujocoBackendOptions::sole_contacts: the estimator assumes
// flat, planted soles; MuJoCo's default soft contacts let them tilt by millirad, docs/calibration.md), three
// capture passes as `pmg_calib_zero --passes 3 --bench-contacts`, each planned on the previous estimate.
// Seeds 1 and 17: the worst of seeds 1-10 and of 11-20 after pass 2 (measured with the tool before the
// safety stack: pass 3 0.0011 / 0.0017 rad; through the stack, whose supervisor clamps the commanded
// slew and torque: 0.0028 / 0.0015 rad). Also: passes 2 and 3 each improve on the previous
// one (pass 1 alone can be worse than uncalibrated: seed 17, planned on the nominal model, 0.068 rad).
TEST_F(ZeroSilTest, RecoversRandomLegOffsets) {
  for (unsigned seed : {1u, 17u}) {
    MujocoBackendOptions bo;
    bo.gantry.enabled = false;
    bo.sole_contacts.enabled = true;
    bo.encoder_offsets = randomLegOffsets(robot, *model, seed, 0.05);
    // Through the same safety stack as pmg_controller and pmg_calib_zero (makeHalStack, engaged).
    HalStackConfig hs;
    declareProtocolGains(protocol, robot, *model, hs);
    HalStack stack = makeHalStack(robot, hs, std::make_unique<MujocoBackend>(robot, bo));
    engageActive(stack, robot);
    HalBackend& sim = *stack.backend;
    const auto idx = zeroJointIndices(*model, robot);
    const auto error = [&](const ZeroVector& z) {
      double e = 0.0;
      for (int j = 0; j < kZeroJoints; ++j)
        e = std::max(e, std::abs(-z(j) - bo.encoder_offsets[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])]));
      return e;
    };
    ZeroEstimator est(model, {});
    ZeroVector z = ZeroVector::Zero();
    ZeroEstimate r;
    ZeroCapture cap;
    double e_prev = error(z);
    std::printf("seed %u: max |offset error| uncalibrated %.5f", seed, e_prev);
    for (int pass = 0; pass < 3; ++pass) {
      cap = captureZeroPoses(sim, robot, model, protocol, {}, z, cap.final_targets);
      EXPECT_FALSE(cap.feet_moved) << "seed " << seed << " pass " << pass + 1 << ": " << cap.home_drift;
      for (const auto& s : cap.samples) EXPECT_TRUE(s.valid) << "seed " << seed << " " << s.name << ": " << s.reason;
      r = est.estimate(cap.samples, z);
      ASSERT_TRUE(r.converged) << "seed " << seed << " pass " << pass + 1 << ": " << r.message;
      z = r.z;
      const double e = error(z);
      std::printf(", pass %d %.5f", pass + 1, e);
      if (pass > 0) {
        EXPECT_LT(e, e_prev) << "seed " << seed << " pass " << pass + 1 << " did not improve";
      }
      e_prev = e;
    }
    std::printf(" rad\n");
    for (int j = 0; j < kZeroJoints; ++j)
      EXPECT_LT(std::abs(-r.z(j) - bo.encoder_offsets[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])]), 0.005)
          << "seed " << seed << " joint " << robot.joints[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].name;
  }
}

// The bench floor is opt-in: by default the soles keep the MJCF's contact parameters (other SIL tests and
// the policy depend on them); enabled, the sole geoms get the configured solref/solimp and dominate the
// mix, and a standing robot's soles sink less. Bad values are refused naming the field.
TEST_F(ZeroSilTest, BenchSoleContactsAreOptInAndStiffer) {
  const auto soleGeoms = [&](const mjModel* m) {
    std::vector<int> g;
    for (const std::string& b : {robot.left_foot_link, robot.right_foot_link}) {
      const int id = mj_name2id(m, mjOBJ_BODY, b.c_str());
      for (int k = 0; k < m->ngeom; ++k)
        if (m->geom_bodyid[k] == id && (m->geom_contype[k] != 0 || m->geom_conaffinity[k] != 0)) g.push_back(k);
    }
    return g;
  };
  // Deepest sole penetration [m] while standing still on the default targets for 1.5 s (last 0.5 s).
  const auto standingPenetration = [&](MujocoBackend& sim) {
    LowCommand c;
    LowState st;
    c.num_motors = static_cast<int>(robot.numJoints());
    const Eigen::VectorXd q0 = robot.defaultPose(), kp = robot.kp(), kd = robot.kd();
    const auto legs = zeroJointIndices(*model, robot);
    double worst = 0.0;
    for (int cyc = 0; cyc < 750; ++cyc) {
      for (int i = 0; i < c.num_motors; ++i) {
        auto& m = c.motors[static_cast<std::size_t>(i)];
        m.q = q0(i);
        m.kp = kp(i);
        m.kd = kd(i);
      }
      for (int j = 0; j < kZeroJoints; ++j) {  // the capture's leg gains (the default ankle kp cannot stand)
        auto& m = c.motors[static_cast<std::size_t>(legs[static_cast<std::size_t>(j)])];
        m.kp = protocol.leg_kp[static_cast<std::size_t>(j % 6)];
        m.kd = protocol.leg_kd[static_cast<std::size_t>(j % 6)];
      }
      EXPECT_EQ(sim.exchange(c, st), BackendStatus::kOk);
      if (cyc < 500) continue;
      for (int k = 0; k < sim.data()->ncon; ++k) worst = std::max(worst, -sim.data()->contact[k].dist);
    }
    return worst;
  };
  MujocoBackendOptions bo;
  bo.gantry.enabled = false;
  MujocoBackend soft(robot, bo);
  const auto g = soleGeoms(soft.model());
  ASSERT_EQ(g.size(), 8u);
  for (int k : g) {
    EXPECT_EQ(soft.model()->geom_solmix[k], 1.0);
    EXPECT_NEAR(soft.model()->geom_solref[mjNREF * k], 0.02, 1e-12);  // MuJoCo's default, as the MJCF leaves it
  }
  bo.sole_contacts.enabled = true;
  MujocoBackend bench(robot, bo);
  for (int k : g) {
    EXPECT_EQ(bench.model()->geom_solref[mjNREF * k], bo.sole_contacts.timeconst);
    EXPECT_EQ(bench.model()->geom_solimp[mjNIMP * k], bo.sole_contacts.dmin);
    EXPECT_EQ(bench.model()->geom_solimp[mjNIMP * k + 1], bo.sole_contacts.dmax);
    EXPECT_GT(bench.model()->geom_solmix[k], 100.0);
  }
  const double p_soft = standingPenetration(soft), p_bench = standingPenetration(bench);
  std::printf("standing sole penetration: default contacts %.3g m, bench contacts %.3g m\n", p_soft, p_bench);
  EXPECT_GT(p_soft, 0.0);
  EXPECT_LT(p_bench, 0.2 * p_soft);
  bo.sole_contacts.timeconst = 0.001;  // < 2 timesteps
  try {
    MujocoBackend bad(robot, bo);
    ADD_FAILURE() << "timeconst below 2 timesteps accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sole_contacts.timeconst"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg::calib
