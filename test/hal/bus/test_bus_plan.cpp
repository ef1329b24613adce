// Bus plan: bit-level frame times, the 80 % start-up check and the per-bus send schedule.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "g1_fixture.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/bus/bus_plan.hpp"
#include "temp_dir.hpp"

using namespace pmg::hal::bus;

TEST(BusTiming, ClassicFrameBits) {
  // 8-byte frame: 111 bits + 24 worst-case stuff bits; 6-byte: 95 + 20.
  EXPECT_EQ(classicFrameBitsNoStuffing(8), 111u);
  EXPECT_EQ(classicFrameBitsWorstCase(8), 135u);
  EXPECT_EQ(classicFrameBitsNoStuffing(6), 95u);
  EXPECT_EQ(classicFrameBitsWorstCase(6), 115u);
  EXPECT_EQ(classicFrameBitsWorstCase(0), 55u);
  EXPECT_EQ(classicFrameBitsWorstCase(8, true), 160u);
  // MIT command + reply at 1 Mbit/s: 0.206 ms unstuffed, 0.250 ms worst case (issue: 0.21-0.25 ms).
  EXPECT_NEAR(classicFrameTime(8, 1e6) + classicFrameTime(6, 1e6), 250e-6, 1e-12);
  EXPECT_NEAR((classicFrameBitsNoStuffing(8) + classicFrameBitsNoStuffing(6)) / 1e6, 206e-6, 1e-12);
  EXPECT_NEAR(classicFrameTime(8, 500e3), 270e-6, 1e-12);
}

TEST(BusTiming, FdFrameTime) {
  // Without bit-rate switch an FD frame is longer than the classic one (bigger CRC, stuff count).
  EXPECT_GT(fdFrameTime(8, 1e6, 1e6, false), classicFrameTime(8, 1e6));
  // 8 bytes at 1/5 Mbit/s: nominal 17 + 13 + floor(85/4)=21 -> 51 bits; data 1+4+64+4+17+6 = 96 bits.
  EXPECT_NEAR(fdFrameTime(8, 1e6, 5e6, true), 51e-6 + 96 / 5e6, 1e-12);
  // Payload is padded to a legal FD length: 9 bytes cost the same as 12.
  EXPECT_DOUBLE_EQ(fdFrameTime(9, 1e6, 5e6, true), fdFrameTime(12, 1e6, 5e6, true));
  EXPECT_GT(fdFrameTime(20, 1e6, 5e6, true), fdFrameTime(16, 1e6, 5e6, true));
  EXPECT_LT(fdFrameTime(8, 1e6, 5e6, true), 0.6 * classicFrameTime(8, 1e6));
}

namespace {
BusConfig busWith(const std::string& name, int first_joint, int n) {
  BusConfig b;
  b.name = name;
  for (int k = 0; k < n; ++k) {
    MotorSpec m;
    m.name = "j" + std::to_string(first_joint + k);
    m.joint_index = first_joint + k;
    m.motor_id = static_cast<std::uint8_t>(k + 1);
    m.command_can_id = static_cast<std::uint32_t>(k + 1);
    m.reply_can_id = 0;
    b.motors.push_back(m);
  }
  return b;
}
}  // namespace

TEST(BusPlan, RefusesBusOverEightyPercent) {
  BusPlanOptions o;
  o.num_joints = 13;
  // 6 motors x 250 us = 1.5 ms = 75 %: accepted. 7 motors = 87.5 %: refused.
  BusPlanCheck ok = checkBusPlan({busWith("can0", 0, 6), busWith("can1", 6, 7)}, o);
  EXPECT_FALSE(ok.ok);
  ASSERT_EQ(ok.loads.size(), 2u);
  EXPECT_NEAR(ok.loads[0].load, 0.75, 1e-9);
  EXPECT_NEAR(ok.loads[1].load, 0.875, 1e-9);
  EXPECT_NE(ok.message.find("can1"), std::string::npos);
  EXPECT_NE(ok.message.find("87.5 %"), std::string::npos);
  EXPECT_EQ(ok.message.find("'can0'"), std::string::npos) << ok.message;
  EXPECT_THROW(BusPlan({busWith("can0", 0, 6), busWith("can1", 6, 7)}, o), std::invalid_argument);

  // Same 7 motors on CAN FD (1/5 Mbit/s): accepted.
  BusConfig fd = busWith("can1", 6, 7);
  fd.timing.fd = true;
  fd.timing.data_bitrate = 5e6;
  BusPlan plan({busWith("can0", 0, 6), fd}, o);
  EXPECT_LT(plan.loads()[1].load, 0.5);
}

TEST(BusPlan, ScheduleIsSequentialInsideTheSlot) {
  BusPlanOptions o;
  o.num_joints = 6;
  o.turnaround_s = 20e-6;
  BusPlan plan({busWith("can0", 0, 6)}, o);
  const auto& s = plan.schedule().at(0);
  ASSERT_EQ(s.size(), 6u);
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_EQ(s[k].motor, static_cast<int>(k));
    EXPECT_NEAR(s[k].send_offset_s, k * 270e-6, 1e-12);
    EXPECT_NEAR(s[k].reply_due_s - s[k].send_offset_s, 270e-6, 1e-12);
    if (k > 0) {
      EXPECT_GE(s[k].send_offset_s, s[k - 1].reply_due_s - 1e-15);
    }
  }
  EXPECT_LE(s.back().reply_due_s, o.period_s);
  EXPECT_NE(plan.report().find("75.0%"), std::string::npos);
}

TEST(BusPlan, ValidationNamesTheField) {
  BusPlanOptions o;
  o.num_joints = 3;
  BusConfig b = busWith("can0", 0, 3);
  b.motors[1].motor_id = 1;  // duplicate id
  b.motors[2].joint_index = 7;
  BusPlanCheck c = checkBusPlan({b}, o);
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.message.find("motors[1] 'j1'.motor_id: duplicate"), std::string::npos) << c.message;
  EXPECT_NE(c.message.find("motors[2] 'j2'.joint_index: expected 0..2, got 7"), std::string::npos) << c.message;
  EXPECT_NE(c.message.find("joint_index 2: appears 0 times"), std::string::npos) << c.message;

  BusConfig clash = busWith("can0", 0, 3);
  clash.motors[0].reply_can_id = 2;  // equals motor 2's command id
  EXPECT_NE(checkBusPlan({clash}, o).message.find("also a reply id"), std::string::npos);
  BusConfig proto = busWith("can0", 0, 3);
  proto.protocol = "nope";
  EXPECT_NE(checkBusPlan({proto}, o).message.find("protocol"), std::string::npos);
}

TEST(BusPlan, G1PlansFromYaml) {
  BusPlan can = BusPlan::fromYaml(pmg::test::g1CanPlanPath());
  EXPECT_EQ(can.motorCount(), 29u);
  EXPECT_EQ(can.buses().size(), 6u);
  for (const BusLoad& l : can.loads()) EXPECT_LE(l.load, 0.8);
  // Reply window: joint range + 0.2 rad margin (left knee: [-0.087, 2.88]).
  const MotorSpec& knee = can.buses()[0].motors[3];
  EXPECT_EQ(knee.name, "left_knee_joint");
  EXPECT_NEAR(knee.reply_limits.q_min, -0.287267, 1e-9);
  EXPECT_NEAR(knee.ranges.tau_max, 150.0, 1e-12);

  BusPlan fd = BusPlan::fromYaml(pmg::test::sourcePath("config/hal/g1_canfd.yaml"));
  EXPECT_EQ(fd.buses().size(), 5u);
  EXPECT_EQ(fd.motorCount(), 29u);

  try {
    BusPlan::fromYaml(pmg::test::sourcePath("config/hal/g1_can_per_limb.yaml"));
    FAIL() << "per-limb classic plan must be refused";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("g1_can_per_limb.yaml"), std::string::npos);
    EXPECT_NE(msg.find("'can3': load 87.5 %"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'can4': load 87.5 %"), std::string::npos) << msg;
  }
}

TEST(BusPlan, YamlErrorsNameFileAndField) {
  const pmg::test::TempDir path_dir;
  const std::string path = path_dir.file("pmg_bad_plan.yaml");
  {
    std::ofstream f(path);
    f << "motor_types:\n  a: {kp_min: 0, kp_max: 10}\nbuses:\n  - name: can0\n    motors:\n"
         "      - {joint: j0, joint_index: 0, motor_id: 300, type: a}\n";
  }
  try {
    BusPlan::fromYaml(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ":6: buses[0].motors[0]: motor_id: expected 1..254, got 300");
  }
  {
    std::ofstream f(path);
    f << "buses:\n  - name: can0\n    motors:\n      - {joint: j0, joint_index: 0, motor_id: 1, type: zz}\n";
  }
  EXPECT_THROW(
      {
        try {
          BusPlan::fromYaml(path);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("unknown motor type 'zz'"), std::string::npos);
          throw;
        }
      },
      std::runtime_error);
  {
    std::ofstream f(path);
    f << "motor_types:\n  a: {kp_min: 0, kp_max: 10}\nbuses:\n  - name: can0\n    motors:\n"
         "      - {joint: j0, joint_index: 0, motor_id: 1, type: a, joint_rnage: [0, 1]}\n";
  }
  try {
    BusPlan::fromYaml(path);
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              path + ":6: unknown key 'joint_rnage' in 'buses[0].motors[0]' (did you mean 'joint_range'?)");
  }
  {
    std::ofstream f(path);
    f << "max_laod: 0.5\nbuses: []\n";
  }
  try {
    BusPlan::fromYaml(path);
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":1: unknown key 'max_laod' at the top level (did you mean 'max_load'?)");
  }
  {
    std::ofstream f(path);
    f << "max_load: .inf\nbuses: []\n";
  }
  try {
    BusPlan::fromYaml(path);
    FAIL();
  } catch (const pmg::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":1: max_load: expected a finite number, got '.inf'");
  }
  std::remove(path.c_str());
}

// The robot config is the source of truth for the wiring: the plan the CAN backend runs must agree.
TEST(BusPlan, ShippedCanPlanAgreesWithTheRobotConfig) {
  const pmg::RobotConfig robot = pmg::loadRobotConfig(pmg::test::g1RobotConfigPath());
  const BusPlan can = BusPlan::fromYaml(pmg::test::g1CanPlanPath());
  EXPECT_NO_THROW(checkPlanAgainstRobot(can.buses(), pmg::test::g1CanPlanPath(), robot));
}

TEST(BusPlan, PlanRobotMismatchNamesBothFilesTheJointAndBothIds) {
  pmg::RobotConfig robot = pmg::loadRobotConfig(pmg::test::g1RobotConfigPath());
  const std::string plan_file = pmg::test::g1CanPlanPath();
  const BusPlan can = BusPlan::fromYaml(plan_file);
  robot.joints[3].motor_id = 17;  // left knee: can0 id 4 in the plan
  try {
    checkPlanAgainstRobot(can.buses(), plan_file, robot);
    FAIL() << "mismatch accepted";
  } catch (const pmg::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), plan_file + ": buses[0].motors[3]: joint 'left_knee_joint' is on bus can0 with "
                                                 "motor_id 4, but " + robot.source_file +
                                                 " says bus can0 with motor_id 17");
  }
  robot = pmg::loadRobotConfig(pmg::test::g1RobotConfigPath());
  std::swap(robot.joints[0].name, robot.joints[1].name);  // joint order differs from the plan's joint_index
  EXPECT_THROW(checkPlanAgainstRobot(can.buses(), plan_file, robot), pmg::ConfigError);

  // The CAN FD study plan wires the arms differently (one bus per arm): refused for this robot.
  const std::string fd_file = pmg::test::sourcePath("config/hal/g1_canfd.yaml");
  const BusPlan fd = BusPlan::fromYaml(fd_file);
  robot = pmg::loadRobotConfig(pmg::test::g1RobotConfigPath());
  try {
    checkPlanAgainstRobot(fd.buses(), fd_file, robot);
    FAIL() << "mismatch accepted";
  } catch (const pmg::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(fd_file), std::string::npos) << msg;
    EXPECT_NE(msg.find(robot.source_file), std::string::npos) << msg;
    EXPECT_NE(msg.find("joint 'left_wrist_roll_joint' is on bus can3 with motor_id 5"), std::string::npos) << msg;
  }
}
