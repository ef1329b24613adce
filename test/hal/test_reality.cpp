// A "reality" (the hidden truth of pmg_sil --reality, include/pmg/hal/reality.hpp): drawn realities
// are plausible, deterministic and round-trip through their file; bad files are refused naming the
// file, key and range; applied to the MuJoCo SIL, the effects are really there (actuator model on
// the joint, offset in the encoder reading, heavier torso).
#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/reality.hpp"
#include "temp_dir.hpp"

namespace pmg::hal {
namespace {

const int kKnee = 3;  // left_knee_joint

bool isLeg(const RobotConfig& robot, const std::string& name) {
  for (int i = 0; i < 12; ++i)
    if (robot.joints[static_cast<std::size_t>(i)].name == name) return true;
  return false;
}

TEST(Reality, DrawnRealitiesArePlausibleAndOneEffectPerJoint) {
  const RobotConfig& robot = test::g1Robot();
  std::set<std::string> seen_effects;
  int with_links = 0;
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    const Reality r = drawReality(robot, seed);
    EXPECT_GE(r.joints.size(), 4u);
    EXPECT_LE(r.joints.size(), 6u);
    EXPECT_GE(r.zero_offsets.size(), 2u);
    EXPECT_LE(r.zero_offsets.size(), 4u);
    for (const auto& [name, b] : r.joints) {
      EXPECT_TRUE(isLeg(robot, name)) << name;
      const std::string e = drawnEffectName(b);
      ASSERT_FALSE(e.empty()) << "seed " << seed << " " << name;
      seen_effects.insert(e);
      // Exactly one effect: every other field at its default.
      const int set = (b.params.fc_Nm > 0) + (b.params.fv_Nms_per_rad > 0) + (b.params.delay_s > 0) +
                      (b.armature_kgm2.has_value()) + (b.kp_scale != 1.0) + (b.kd_scale != 1.0) +
                      (b.params.kt_scale != 1.0) + (b.params.offset_rad != 0.0);
      EXPECT_EQ(set, 1) << "seed " << seed << " " << name;
      if (e == "coulomb_friction") {
        EXPECT_TRUE(b.params.fc_Nm >= 1.0 && b.params.fc_Nm <= 3.0);
      }
      if (e == "viscous_friction") {
        EXPECT_TRUE(b.params.fv_Nms_per_rad >= 0.5 && b.params.fv_Nms_per_rad <= 2.0);
      }
      if (e == "transport_delay") {
        EXPECT_TRUE(b.params.delay_s >= 0.004 && b.params.delay_s <= 0.012);
      }
      if (e == "armature") {
        EXPECT_TRUE(*b.armature_kgm2 >= 0.02 && *b.armature_kgm2 <= 0.05);
      }
      if (e == "pd_gain") {
        EXPECT_TRUE(std::fabs(b.kp_scale - 1.0) >= 0.12 && std::fabs(b.kp_scale - 1.0) <= 0.25);
      }
    }
    for (const auto& [name, z] : r.zero_offsets) {
      EXPECT_TRUE(isLeg(robot, name)) << name;
      EXPECT_TRUE(std::fabs(z) >= 0.01 && std::fabs(z) <= 0.05) << name << " " << z;
    }
    if (!r.links.empty()) {
      ++with_links;
      EXPECT_TRUE(r.links.at("torso_link").mass_scale >= 0.95 && r.links.at("torso_link").mass_scale <= 1.10);
    }
  }
  EXPECT_EQ(seen_effects.size(), drawableEffects().size()) << "40 draws cover every drawable effect";
  EXPECT_GT(with_links, 5);
  EXPECT_LT(with_links, 35);
}

TEST(Reality, DrawIsDeterministicAndRoundTripsThroughItsFile) {
  const RobotConfig& robot = test::g1Robot();
  const test::TempDir dir;
  const Reality a = drawReality(robot, 7);
  writeReality(dir.file("a.yaml"), a, "seed 7");
  writeReality(dir.file("b.yaml"), drawReality(robot, 7), "seed 7");
  writeReality(dir.file("c.yaml"), drawReality(robot, 8), "seed 8");
  EXPECT_EQ(test::readTextFile(dir.file("a.yaml")), test::readTextFile(dir.file("b.yaml")));
  EXPECT_NE(test::readTextFile(dir.file("a.yaml")), test::readTextFile(dir.file("c.yaml")));
  const Reality back = loadReality(dir.file("a.yaml"), robot);
  ASSERT_EQ(back.joints.size(), a.joints.size());
  for (const auto& [name, b] : a.joints) {
    const calib::ActuatorBlock& c = back.joints.at(name);
    EXPECT_EQ(drawnEffectName(c), drawnEffectName(b)) << name;
    EXPECT_NEAR(c.params.fc_Nm, b.params.fc_Nm, 1e-5);
    EXPECT_NEAR(c.params.fv_Nms_per_rad, b.params.fv_Nms_per_rad, 1e-5);
    EXPECT_NEAR(c.params.delay_s, b.params.delay_s, 1e-7);
    EXPECT_NEAR(c.kp_scale, b.kp_scale, 1e-5);
    EXPECT_EQ(c.armature_kgm2.has_value(), b.armature_kgm2.has_value());
  }
  ASSERT_EQ(back.zero_offsets.size(), a.zero_offsets.size());
  for (const auto& [name, z] : a.zero_offsets) EXPECT_NEAR(back.zero_offsets.at(name), z, 1e-6);
  EXPECT_EQ(back.links.size(), a.links.size());
  EXPECT_EQ(back.affectedJoints(robot).size(), a.affectedJoints(robot).size());
}

// Bad files: the error names the file, the key path and what was expected.
void expectRefused(const std::string& text, const std::vector<std::string>& must_contain) {
  const test::TempDir dir;
  const std::string path = dir.write("reality.yaml", text);
  try {
    loadReality(path, test::g1Robot());
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("reality.yaml"), std::string::npos) << what;
    for (const auto& s : must_contain) EXPECT_NE(what.find(s), std::string::npos) << "'" << s << "' not in: " << what;
  }
}

TEST(Reality, BadFilesAreRefusedNamingFileKeyAndRange) {
  expectRefused("joint: {left_knee_joint: {fc_Nm: 1}}\n", {"joint", "joints"});
  expectRefused("joints: {left_knee: {fc_Nm: 1}}\n", {"joints.left_knee", "left_knee_joint"});
  expectRefused("joints: {left_knee_joint: {fc_nm: 1}}\n", {"fc_nm", "fc_Nm"});
  expectRefused("joints: {left_knee_joint: {fc_Nm: -1}}\n", {"left_knee_joint", "fc_Nm"});
  expectRefused("joints: {left_knee_joint: {backlash_gap_rad: 0.01}}\n", {"backlash_gap_rad"});
  expectRefused("zero_offsets: {left_knee_joint: 0.7}\n", {"zero_offsets.left_knee_joint", "0.5"});
  expectRefused("zero_offsets: {left_kne_joint: 0.01}\n", {"left_knee_joint"});
  expectRefused("links: {torso_link: {mass_scale: 3}}\n", {"links.torso_link", "mass_scale", "0.5..2"});
  expectRefused("links: {torso_link: {mass: 3}}\n", {"mass", "mass_scale"});
}

TEST(Reality, AppliedToTheSilTheEffectsAreThere) {
  const RobotConfig& nominal = test::g1Robot();
  const test::TempDir dir;
  const std::string path = dir.write("reality.yaml",
                                     "joints: {left_knee_joint: {fc_Nm: 4.0, fs_Nm: 5.0}}\n"
                                     "zero_offsets: {left_knee_joint: 0.03, right_ankle_pitch_joint: -0.02}\n"
                                     "links: {torso_link: {mass_scale: 1.5}}\n");
  const Reality r = loadReality(path, nominal);
  EXPECT_EQ(r.affectedJoints(nominal), (std::vector<std::string>{"left_knee_joint", "right_ankle_pitch_joint"}));
  RobotConfig robot = nominal;
  MujocoBackendOptions o;
  o.gantry.enabled = true;
  applyReality(r, &robot, &o);
  MujocoBackend real(robot, o);
  MujocoBackendOptions o_nominal;
  o_nominal.gantry.enabled = true;
  MujocoBackend sim(nominal, o_nominal);
  EXPECT_TRUE(real.hasActuatorModel(kKnee));
  EXPECT_FALSE(sim.hasActuatorModel(kKnee));
  const int torso = mj_name2id(real.model(), mjOBJ_BODY, "torso_link");
  ASSERT_GE(torso, 0);
  EXPECT_NEAR(real.model()->body_mass[torso], 1.5 * sim.model()->body_mass[torso], 1e-9);
  EXPECT_NEAR(real.model()->body_inertia[3 * torso], 1.5 * sim.model()->body_inertia[3 * torso], 1e-12);
  // The encoders read true angle + offset: at the default pose the difference is the offset.
  LowCommand cmd;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  // zero gains and torque: every motor limp for the one 2 ms cycle read here
  LowState a, b;
  real.exchange(cmd, a);
  sim.exchange(cmd, b);
  const int r_ankle = 10;  // right_ankle_pitch_joint
  ASSERT_EQ(robot.joints[r_ankle].name, "right_ankle_pitch_joint");
  EXPECT_NEAR(a.motors[kKnee].q - b.motors[kKnee].q, 0.03, 1e-3);
  EXPECT_NEAR(a.motors[r_ankle].q - b.motors[r_ankle].q, -0.02, 1e-3);
  EXPECT_NEAR(a.motors[0].q, b.motors[0].q, 1e-3);  // an unaffected joint reads the same
  // An unknown link is named when the SIL loads it.
  MujocoBackendOptions bad = o_nominal;
  bad.body_mass_scale["torso"] = 1.1;
  try {
    MujocoBackend x(nominal, bad);
    ADD_FAILURE() << "unknown body accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("links.torso"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg::hal
