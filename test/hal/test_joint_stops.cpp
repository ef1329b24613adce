// The MuJoCo SIL's joint stops (mujoco.joint_stops, docs/controller.md "Joint stops"): the public G1
// MJCF leaves MuJoCo's default joint-limit constraint, solref (0.02 s, 1), soft enough that a joint
// driven into its stop overtravels by a tenth of a radian, which is what tripped the supervisor's
// joint position check (0.1 rad beyond a limit) in stumbles of the crouched probe. The hidden effect:
// a free ankle in the gantry, driven into its lower stop, overtravels beyond that margin with the
// MJCF's stops and a fifth as far with the configured stiff ones; elsewhere nothing changes.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg {
namespace {

const int kRightAnklePitch = 10;  // right_ankle_pitch_joint: range [-0.87267, 0.5236] rad, 50 N*m
const double kSlamTorque = 5.0;  // [N*m]

MujocoBackendOptions gantry(double timeconst) {
  MujocoBackendOptions o;
  o.gantry.enabled = true;
  o.joint_stops.timeconst = timeconst;
  return o;
}

struct StopRun {
  double overtravel_peak = 0;   // [rad] largest reading beyond the lower limit
  double overtravel_held = 0;   // [rad] beyond the limit at the end, held there by the drive torque
  double impact_speed = 0;      // [rad/s] |qd| at the last reading before the limit
};

// Holds every joint at its default pose (its PD gains) for 0.6 s, then drives the free right ankle
// pitch (the robot hangs in the gantry) at -5 N*m into its lower stop for 0.6 s: it arrives at about
// 20 rad/s (the SIL stumble that tripped the supervisor: 7 rad/s, with the robot's weight behind it).
StopRun slamAnkle(double timeconst, std::vector<double>* other_q = nullptr) {
  const RobotConfig& robot = test::g1Robot();
  MujocoBackend sim(robot, gantry(timeconst));
  LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  for (std::size_t i = 0; i < robot.numJoints(); ++i)
    cmd.motors[i] = MotorCommand{robot.joints[i].default_position, 0.0, robot.joints[i].kp, robot.joints[i].kd, 0.0};
  const double lower = robot.joints[kRightAnklePitch].lower;
  LowState state;
  StopRun r;
  bool crossed = false;
  for (int c = 0; c < 600; ++c) {
    if (c == 300) cmd.motors[kRightAnklePitch] = MotorCommand{0.0, 0.0, 0.0, 0.0, -kSlamTorque};
    sim.exchange(cmd, state);
    const double q = state.motors[kRightAnklePitch].q;
    r.overtravel_peak = std::max(r.overtravel_peak, lower - q);
    r.overtravel_held = lower - q;
    if (q >= lower && !crossed) r.impact_speed = -state.motors[kRightAnklePitch].qd;
    crossed = crossed || q < lower;
    if (c == 299 && other_q) {  // the pose before the slam: the stops must not change it
      other_q->clear();
      for (std::size_t i = 0; i < robot.numJoints(); ++i) other_q->push_back(state.motors[i].q);
    }
  }
  return r;
}

TEST(JointStops, StiffStopsKeepASlammedAnkleWithinCentiradiansTheMjcfsLetItThrough) {
  std::vector<double> pose_soft, pose_stiff;
  const StopRun soft = slamAnkle(0.0, &pose_soft);     // the MJCF's (MuJoCo's default 0.02 s)
  const StopRun stiff = slamAnkle(0.004, &pose_stiff);  // g1_sil_policy.yaml's
  EXPECT_GT(soft.impact_speed, 15.0);
  EXPECT_LT(soft.impact_speed, 25.0);
  EXPECT_NEAR(stiff.impact_speed, soft.impact_speed, 1e-6);  // the same run up to the stop
  // The effect is there: the soft stop lets the ankle through by more than the supervisor's
  // 0.1 rad joint position margin (measured 0.141 rad).
  EXPECT_GT(soft.overtravel_peak, 0.1);
  // The stiff stop holds it to a fifth of that or less (measured 0.020 rad), and, held against it,
  // to millirad.
  EXPECT_LT(stiff.overtravel_peak, 0.03);
  EXPECT_LT(stiff.overtravel_peak, 0.2 * soft.overtravel_peak);
  EXPECT_LT(stiff.overtravel_held, 0.005);
  // Away from the stops nothing changes: the held pose before the slam is the same to 1e-9 rad.
  ASSERT_EQ(pose_soft.size(), pose_stiff.size());
  for (std::size_t i = 0; i < pose_soft.size(); ++i) EXPECT_NEAR(pose_soft[i], pose_stiff[i], 1e-9) << "joint " << i;
}

TEST(JointStops, OptionsOutsideTheirRangesAreRefusedNamingTheField) {
  MujocoBackendOptions o;  // timestep 0.001
  EXPECT_EQ(o.validate(), "");
  o.joint_stops.timeconst = 0.001;  // below 2 timesteps: MuJoCo's stability rule
  EXPECT_NE(o.validate().find("mujoco.joint_stops.timeconst"), std::string::npos) << o.validate();
  o.joint_stops.timeconst = -0.004;
  EXPECT_NE(o.validate().find("mujoco.joint_stops.timeconst"), std::string::npos) << o.validate();
  o.joint_stops.timeconst = std::nan("");
  EXPECT_NE(o.validate().find("mujoco.joint_stops.timeconst"), std::string::npos) << o.validate();
  o.joint_stops.timeconst = 0.004;
  EXPECT_EQ(o.validate(), "");
  o.joint_stops.dampratio = 0.0;
  EXPECT_NE(o.validate().find("mujoco.joint_stops.dampratio"), std::string::npos) << o.validate();
  o.joint_stops.dampratio = std::nan("");
  EXPECT_NE(o.validate().find("mujoco.joint_stops.dampratio"), std::string::npos) << o.validate();
  EXPECT_THROW(MujocoBackend(test::g1Robot(), o), ConfigError);
}

}  // namespace
}  // namespace pmg
