// Contract parsing and checking: every bad_*.onnx model breaks one field and must be refused
// with a ContractError that names that field.
#include <cmath>

#include <gtest/gtest.h>

#include "pmg/clips/clip_io.hpp"
#include "pmg/policy/contract.hpp"
#include "pmg/policy/policy_runner.hpp"
#include "test_policy_common.hpp"

namespace pmg::policy::test {
namespace {

std::string loadError(const std::string& file, std::string* field = nullptr) {
  try {
    PolicyRunner runner(kDataDir + file, g1Spec());
  } catch (const ContractError& e) {
    if (field != nullptr) *field = e.field();
    return e.what();
  }
  return "";
}

TEST(PolicyRobotSpec, LoadsG1Config) {
  const PolicyRobotSpec s = g1Spec();
  ASSERT_EQ(s.joint_names.size(), 29u);
  EXPECT_EQ(s.joint_names[3], "left_knee_joint");
  EXPECT_DOUBLE_EQ(s.default_pose[3], 0.3);
  EXPECT_DOUBLE_EQ(s.kp[3], 200.0);
  EXPECT_DOUBLE_EQ(s.kd[4], 2.0);
  EXPECT_EQ(s.leg_joints.size(), 12u);
  ASSERT_EQ(s.waist_joints.size(), 3u);
  EXPECT_EQ(s.waist_joints[0], "waist_yaw_joint");
}

TEST(PolicyRobotSpec, MissingFileNamesPath) {
  try {
    loadPolicyRobotSpec(pmg::test::sourcePath("config/robots/none/none.yaml"), 0.01);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("config/robots/none/none.yaml"), std::string::npos) << e.what();
  }
}

struct BadCase {
  const char* file;
  const char* field;  // substring expected in ContractError::field()
};

class BadContract : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadContract, RefusedNamingTheField) {
  std::string field;
  const std::string what = loadError(GetParam().file, &field);
  ASSERT_FALSE(what.empty()) << GetParam().file << " was accepted";
  EXPECT_NE(field.find(GetParam().field), std::string::npos) << "field '" << field << "', message: " << what;
  EXPECT_NE(what.find(GetParam().file), std::string::npos) << "message does not name the file: " << what;
}

INSTANTIATE_TEST_SUITE_P(
    Models, BadContract,
    ::testing::Values(BadCase{"bad_joint_order.onnx", "joint_names[3]"}, BadCase{"bad_kp.onnx", "kp[3] (left_knee_joint)"},
                      BadCase{"bad_kd.onnx", "kd[0] (left_hip_pitch_joint)"},
                      BadCase{"bad_default_pose.onnx", "default_pose[3]"},
                      BadCase{"bad_control_period.onnx", "control_period"},
                      BadCase{"bad_reference.onnx", "reference_pairs[2].action[5]"},
                      BadCase{"bad_obs_layout.onnx", "observation"},
                      BadCase{"bad_actuated_waist.onnx", "actuated_joints"},
                      BadCase{"bad_unknown_joint.onnx", "actuated_joints[0]"}, BadCase{"bad_pmg_gco.onnx", "pmg.gco"},
                      BadCase{"bad_action_scale_size.onnx", "action.scale"}, BadCase{"bad_version.onnx", "version"},
                      BadCase{"bad_no_contract.onnx", "pmg.contract"}, BadCase{"bad_yaml.onnx", "pmg.contract"}),
    [](const ::testing::TestParamInfo<BadCase>& param_info) {
      std::string n = param_info.param.file;
      n = n.substr(0, n.find('.'));
      return n;
    });

TEST(Contract, GoodModelsAccepted) {
  EXPECT_EQ(loadError("g1_legs_ok.onnx"), "");
  EXPECT_EQ(loadError("g1_legs_waist_hist3_ok.onnx"), "");
}

TEST(Contract, MismatchMessageGivesBothValues) {
  const std::string what = loadError("bad_kp.onnx");
  EXPECT_NE(what.find("100"), std::string::npos) << what;
  EXPECT_NE(what.find("200"), std::string::npos) << what;
}

TEST(Contract, ControllerPmgSettingMissingFromContract) {
  PolicyRobotSpec s = g1Spec();
  s.pmg["gco_iterations"] = "3";
  try {
    PolicyRunner runner(kDataDir + "g1_legs_ok.onnx", s);
    FAIL() << "accepted a contract without pmg.gco_iterations";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.gco_iterations");
  }
}

// The reference settings beyond the paper (GeneratorParams::upright_walking, GcoOptions::
// sole_levelling) are contract keys: older contracts read as false, and a policy trained on them
// (the uplev fine-tune, trained with both) runs only where the controller runs both.
TEST(Contract, ReferenceSettingsMustMatchTheController) {
  PolicyRobotSpec s = g1Spec();
  s.pmg = {{"enabled", "true"}, {"gco", "true"}, {"mode", "pmg"}, {"sole_levelling", "false"}, {"upright_walking", "false"}};
  EXPECT_NO_THROW(PolicyRunner(pmg::test::sourcePath("config/policies/g1_pmg_policy_bk_vy6.onnx"), s));  // no keys: false
  const std::string uplev = pmg::test::sourcePath("training/results/fidelity/upright_level/uplev/g1_pmg_policy_uplev.onnx");
  try {
    PolicyRunner runner(uplev, s);
    FAIL() << "accepted a policy trained with levelled soles on a controller without";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.sole_levelling");
    EXPECT_NE(std::string(e.what()).find("'true'"), std::string::npos) << e.what();
  }
  s.pmg["sole_levelling"] = "true";
  try {
    PolicyRunner runner(uplev, s);
    FAIL() << "accepted a policy trained upright on a controller without";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.upright_walking");
  }
  s.pmg["upright_walking"] = "true";
  EXPECT_NO_THROW(PolicyRunner(uplev, s));
  EXPECT_THROW(PolicyRunner(pmg::test::sourcePath("config/policies/g1_pmg_policy_bk_vy6.onnx"), s), ContractError);
  // GcoOptions::stride_adaptation: no shipped actor was trained on it (2026-12-04), so a controller
  // that adapts the strides refuses every one of them, naming the key.
  s.pmg["stride_adaptation"] = "true";
  try {
    PolicyRunner runner(uplev, s);
    FAIL() << "accepted a policy trained without the stride adaptation on a controller with it";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.stride_adaptation");
  }
  // pmg.stride_standing_hold: S24b (173.7 M steps) was trained with the stride adaptation before
  // StrideAdaptationOptions::standing_hold (no key: false, every offset decaying while standing). A
  // controller that holds the standing feet refuses it, naming the key; one that decays runs it.
  const std::string s24b = pmg::test::sourcePath("training/results/fidelity/stride_adaptation/S24b_173M/g1_pmg_policy.onnx");
  s.pmg["upright_walking"] = "false";
  s.pmg["sole_levelling"] = "false";
  s.pmg["stride_standing_hold"] = "true";
  try {
    PolicyRunner runner(s24b, s);
    FAIL() << "accepted a policy trained on decaying standing offsets on a controller that holds them";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.stride_standing_hold");
  }
  s.pmg["stride_standing_hold"] = "false";
  EXPECT_NO_THROW(PolicyRunner(s24b, s));
}

// pmg.upper_body_ff: an actor trained with the controller's waist feed-forward in its environment
// (pmg-train --upper-body-ff: the teleoperation actor since 2026-11-29) runs only where the controller
// feeds the waist's gravity torque forward (`upper_body: enabled`), and an actor without the key
// (trained without it) only where the controller does not.
TEST(Contract, UpperBodyFeedForwardMustMatchTheController) {
  PolicyRobotSpec s = g1Spec();
  s.pmg = {{"enabled", "true"}, {"gco", "true"}, {"mode", "pmg"}, {"sole_levelling", "false"},
           {"upright_walking", "false"}, {"upper_body_ff", "false"}};
  const std::string trained_with = pmg::test::sourcePath("config/policies/g1_teleop_upper_body.onnx");
  const std::string trained_without = pmg::test::sourcePath("config/policies/g1_table2_baseline.onnx");
  EXPECT_NO_THROW(PolicyRunner(trained_without, s));  // no key: false
  try {
    PolicyRunner runner(trained_with, s);
    FAIL() << "accepted an actor trained with the waist feed-forward on a controller without it";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.upper_body_ff");
    EXPECT_NE(std::string(e.what()).find("'true'"), std::string::npos) << e.what();
  }
  s.pmg["upper_body_ff"] = "true";
  EXPECT_NO_THROW(PolicyRunner(trained_with, s));
  EXPECT_THROW(PolicyRunner(trained_without, s), ContractError);
}

// pmg.clips_digest (pmg::clipsDigest): a policy whose contract names the clips it was trained on
// runs only on those clips (wh6hs, trained on the raised walking templates, is refused on the
// captured ones); a contract without the key (bk_vy6, exported before it existed) is not checked.
// wh6hs's digest was written by the training side (training/pmg_train/contract.py), so its
// acceptance also shows that the two implementations agree. The digest ignores changes below the
// 1e-4 rounding and sees a joint moved by 2e-4 rad.
TEST(Contract, ClipsDigestMustMatchWhereTheContractHasOne) {
  const RobotConfig& robot = pmg::test::g1Robot();
  const ClipLibrary raised_clips = loadClipLibrary(pmg::test::sourcePath("config/clips/g1_walking_height"), robot);
  const std::string raised = clipsDigest(raised_clips);
  const std::string captured = clipsDigest(loadClipLibrary(pmg::test::g1ClipDir(), robot));
  EXPECT_NE(raised, captured);
  EXPECT_EQ(raised.rfind("fnv1a64:", 0), 0u);
  EXPECT_EQ(raised.size(), 24u);
  ClipLibrary moved = raised_clips;
  moved.dynamic_clips[0].q(10, 3) += 2e-4;
  EXPECT_NE(clipsDigest(moved), raised);
  moved = raised_clips;
  const double v = moved.dynamic_clips[0].q(10, 3);
  const double rounded = std::floor(v * 1e4 + 0.5) / 1e4;  // stay inside the same rounding cell
  moved.dynamic_clips[0].q(10, 3) = rounded + 0.3 * (v - rounded);
  ASSERT_NE(moved.dynamic_clips[0].q(10, 3), v);
  EXPECT_EQ(clipsDigest(moved), raised);

  PolicyRobotSpec s = g1Spec();
  s.pmg = {{"enabled", "true"}, {"gco", "true"}, {"mode", "pmg"}, {"sole_levelling", "false"}, {"upright_walking", "false"},
           {"clips_digest", raised}};
  const std::string wh6hs = pmg::test::sourcePath("config/policies/g1_pmg_policy_wh6hs.onnx");
  EXPECT_NO_THROW(PolicyRunner(wh6hs, s));
  s.pmg["clips_digest"] = captured;
  try {
    PolicyRunner runner(wh6hs, s);
    FAIL() << "accepted a policy trained on the raised walking templates on the captured ones";
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "pmg.clips_digest");
    EXPECT_NE(std::string(e.what()).find(raised), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(PolicyRunner(pmg::test::sourcePath("config/policies/g1_pmg_policy_bk_vy6.onnx"), s));  // no key
}

TEST(Contract, NumericPmgSettingComparedAsNumber) {
  PolicyRobotSpec s = g1Spec();
  s.pmg["gait_period"] = "0.80";  // same number, different text
  EXPECT_NO_THROW(PolicyRunner(kDataDir + "g1_legs_ok.onnx", s));
  s.pmg["gait_period"] = "0.7";
  EXPECT_THROW(PolicyRunner(kDataDir + "g1_legs_ok.onnx", s), ContractError);
}

TEST(Contract, ParseRejectsNonFiniteAndWrongSizes) {
  const std::string base =
      "version: 1\njoint_names: [a, b]\nactuated_joints: [a]\ncontrols_waist: false\ncontrol_period: 0.01\n"
      "default_pose: [0, 0]\nkp: [1, 1]\nkd: [0.1, 0.1]\naction: {scale: [0.5], offset: [0], clip: 5}\n"
      "observation: {history_length: 2, clip: 10, terms: [{name: x, size: 2, scale: [1, 2]}]}\npmg: {enabled: true}\n";
  const PolicyContract c = parseContract(base + "reference_pairs: [{obs: [1, 2, 3, 4], action: [0.5]}]\n", "mem");
  EXPECT_EQ(c.observation.size(), 4);
  EXPECT_FLOAT_EQ(c.observation.terms[0].scale[1], 2.0f);
  EXPECT_EQ(c.pmg.at("enabled"), "true");
  try {
    parseContract(base + "reference_pairs: [{obs: [1, 2, 3], action: [0.5]}]\n", "mem");
    FAIL();
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "reference_pairs[0].obs");
  }
  try {
    parseContract(base + "reference_pairs: [{obs: [1, 2, 3, .nan], action: [0.5]}]\n", "mem");
    FAIL();
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "reference_pairs[0].obs[3]");
  }
}

// A typo in the contract is an error naming the model, the key, its line and the nearest valid key.
TEST(Contract, UnknownKeysNameTheNearestKey) {
  const std::string base =
      "version: 1\njoint_names: [a, b]\nactuated_joints: [a]\ncontrols_waist: false\ncontrol_period: 0.01\n"
      "default_pose: [0, 0]\nkp: [1, 1]\nkd: [0.1, 0.1]\naction: {scale: [0.5], offset: [0], clip: 5}\n"
      "observation: {history_length: 2, clip: 10, terms: [{name: x, size: 2, scale: [1, 2]}]}\npmg: {enabled: true}\n"
      "reference_pairs: [{obs: [1, 2, 3, 4], action: [0.5]}]\n";
  EXPECT_NO_THROW(parseContract(base, "m.onnx"));
  struct Case {
    std::string text, field, what;
  };
  const Case cases[] = {
      {base + "policyy: {}\n", "policyy",
       "m.onnx: policyy: unknown key at line 13 of the pmg.contract metadata (did you mean 'pmg'?)"},
      {"kpp: [1, 1]\n" + base, "kpp",
       "m.onnx: kpp: unknown key at line 1 of the pmg.contract metadata (did you mean 'kp'?)"},
      {base + "version: 2\n", "version", "m.onnx: version: duplicate key at line 13 of the pmg.contract metadata"},
  };
  for (const Case& c : cases) {
    try {
      parseContract(c.text, "m.onnx");
      FAIL() << c.text;
    } catch (const ContractError& e) {
      EXPECT_EQ(e.field(), c.field);
      EXPECT_EQ(std::string(e.what()), c.what);
    }
  }
  std::string nested = base;
  nested.replace(nested.find("clip: 5"), 7, "clipp: 5");
  try {
    parseContract(nested, "m.onnx");
    FAIL();
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "action.clipp");
    EXPECT_NE(std::string(e.what()).find("(did you mean 'clip'?)"), std::string::npos) << e.what();
  }
  std::string term = base;
  term.replace(term.find("size: 2"), 7, "sise: 2");
  try {
    parseContract(term, "m.onnx");
    FAIL();
  } catch (const ContractError& e) {
    EXPECT_EQ(e.field(), "observation.terms[0].sise");
    EXPECT_NE(std::string(e.what()).find("(did you mean 'size'?)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pmg::policy::test
