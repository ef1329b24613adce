// The MuJoCo SIL's foot-floor friction (mujoco.sliding_friction, docs/controller.md "Slippery floors"): the
// training draws the sliding friction of every geom in [0.4, 1.25], and the SIL ran the MJCF's 1.0 only.
// The hidden effect: the G1 standing in the gantry on its PD gains (the band holds the pelvis, the feet bear
// weight), its left foot pushed outward with a tenth of the robot's weight for 0.3 s, keeps that foot where it
// stood on the MJCF's floor (2 mm, measured) and slides it on a floor of 0.1 (10 cm).
// Elsewhere nothing changes: the option sets only the sliding coefficient, of every geom.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg {
namespace {

struct PushRun {
  double foot_slide = 0;     // [m] largest horizontal travel of the pushed foot from where it stood
  double pelvis_travel = 0;  // [m] horizontal travel of the pelvis at the end
};

// Stands the robot in the gantry, feet on the floor, on its PD gains for 1 s, pushes its left foot body along
// +y (world, outward) with 0.1 m g for 0.3 s, then holds 0.5 s more.
PushRun pushSideways(double sliding_friction) {
  const RobotConfig& robot = test::g1Robot();
  MujocoBackendOptions o;
  o.gantry.enabled = true;
  o.gantry.anchor_height = 0.76;  // the band holds the pelvis 3 cm below its standing height: the feet bear weight
  o.sliding_friction = sliding_friction;
  MujocoBackend sim(robot, o);
  LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  for (std::size_t i = 0; i < robot.numJoints(); ++i)
    cmd.motors[i] = MotorCommand{robot.joints[i].default_position, 0.0, robot.joints[i].kp, robot.joints[i].kd, 0.0};
  const mjModel* m = sim.model();
  const int foot = mj_name2id(m, mjOBJ_BODY, robot.left_foot_link.c_str());
  double mass = 0;
  for (int b = 1; b < m->nbody; ++b) mass += m->body_mass[b];
  LowState state;
  double foot0[2] = {}, pelvis0[2] = {};
  PushRun r;
  const mjData* d = sim.data();
  for (int c = 0; c < 900; ++c) {  // 500 Hz HAL cycles: 1.8 s
    if (c == 500) {
      for (int k = 0; k < 2; ++k) foot0[k] = d->xpos[3 * foot + k], pelvis0[k] = d->xpos[3 * sim.pelvisBody() + k];
      sim.push(foot, Eigen::Vector3d(0.0, 0.1 * mass * 9.81, 0.0), 0.3);
    }
    sim.exchange(cmd, state);
    if (c < 500) continue;
    r.foot_slide = std::max(r.foot_slide, std::hypot(d->xpos[3 * foot] - foot0[0], d->xpos[3 * foot + 1] - foot0[1]));
    r.pelvis_travel = std::hypot(d->xpos[3 * sim.pelvisBody()] - pelvis0[0], d->xpos[3 * sim.pelvisBody() + 1] - pelvis0[1]);
  }
  return r;
}

TEST(SlidingFriction, APushSlidesTheFootOnASlipperyFloorAndNotOnTheMjcfs) {
  const PushRun grippy = pushSideways(0.0);  // the MJCF's: 1.0
  const PushRun slippery = pushSideways(0.1);
  std::printf("[ SIL ] left foot pushed 0.1 m g for 0.3 s: it slides %.4f m (MJCF's floor), %.4f m (0.1); pelvis %.3f, %.3f m\n",
              grippy.foot_slide, slippery.foot_slide, grippy.pelvis_travel, slippery.pelvis_travel);
  EXPECT_LT(grippy.foot_slide, 0.01) << "the feet hold on the MJCF's floor";
  EXPECT_GT(slippery.foot_slide, 0.03) << "and slide on a floor of 0.1";
  EXPECT_GT(slippery.foot_slide, 5.0 * grippy.foot_slide);
}

TEST(SlidingFriction, SetsTheSlidingCoefficientOfEveryGeomOnly) {
  const RobotConfig& robot = test::g1Robot();
  MujocoBackendOptions o;
  o.gantry.enabled = false;
  const MujocoBackend nominal(robot, o);
  o.sliding_friction = 0.5;
  const MujocoBackend slippery(robot, o);
  const mjModel* a = nominal.model();
  const mjModel* b = slippery.model();
  ASSERT_EQ(a->ngeom, b->ngeom);
  const int floor = mj_name2id(a, mjOBJ_GEOM, "floor");
  ASSERT_GE(floor, 0);
  EXPECT_DOUBLE_EQ(a->geom_friction[3 * floor], 1.0) << "the MJCF's floor (MuJoCo's default)";
  for (int g = 0; g < b->ngeom; ++g) {
    EXPECT_DOUBLE_EQ(b->geom_friction[3 * g], 0.5) << "geom " << g;
    EXPECT_DOUBLE_EQ(b->geom_friction[3 * g + 1], a->geom_friction[3 * g + 1]) << "torsional, geom " << g;
    EXPECT_DOUBLE_EQ(b->geom_friction[3 * g + 2], a->geom_friction[3 * g + 2]) << "rolling, geom " << g;
  }
}

TEST(SlidingFriction, OutOfRangeIsAConfigErrorNamingTheKey) {
  for (double bad : {0.05, 2.5, -1.0, std::nan("")}) {
    MujocoBackendOptions o;
    o.sliding_friction = bad;
    const std::string e = o.validate();
    EXPECT_NE(e.find("mujoco.sliding_friction"), std::string::npos) << bad << ": " << e;
    EXPECT_NE(e.find("[0.1, 2]"), std::string::npos) << e;
    EXPECT_THROW(MujocoBackend(test::g1Robot(), o), ConfigError) << bad;
  }
  MujocoBackendOptions ok;
  ok.sliding_friction = 0.1;
  EXPECT_EQ(ok.validate(), "");
}

}  // namespace
}  // namespace pmg
