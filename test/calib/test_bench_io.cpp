// Bench log readers (pmg CSV, Rhoban BAM JSON, DFKI CSV pairs), rig YAML and actuator YAML.
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/calib/actuator_yaml.hpp"
#include "pmg/calib/bench_log.hpp"
#include "pmg/calib/bench_sim.hpp"
#include "pmg/calib/dynamics_calibration.hpp"
#include "temp_dir.hpp"

namespace pmg::calib {
namespace {

template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(BenchLog, ReadsPmgCsvWithOptionalColumnsAndWindow) {
  const BenchLog l = load_bench_log(pmg::test::sourcePath("test/data/calib/small_log.csv"));
  ASSERT_EQ(l.size(), 4u);
  EXPECT_TRUE(l.has_dq());
  EXPECT_TRUE(l.has_kp());
  EXPECT_FALSE(l.has_tau());
  EXPECT_DOUBLE_EQ(l.q[2], 0.010);
  EXPECT_EQ(l.enabled[3], 0);
  const BenchLog w = load_bench_log(pmg::test::sourcePath("test/data/calib/small_log.csv@0.005:0.025"));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_DOUBLE_EQ(w.t[0], 0.01);
}

TEST(BenchLog, ErrorsNameFileAndField) {
  EXPECT_NE(error_of([] { load_bench_log(pmg::test::sourcePath("test/data/calib/bad_time.csv")); }).find("strictly increasing"), std::string::npos);
  EXPECT_NE(error_of([] { load_bench_log(pmg::test::sourcePath("test/data/calib/no_such.csv")); }).find("no_such.csv"), std::string::npos);
  EXPECT_NE(error_of([] { load_bench_log(pmg::test::sourcePath("test/data/calib/small_log.csv@x:1")); }).find("window"), std::string::npos);
}

TEST(BenchLog, ReadsRhobanBamJson) {
  const BenchLog l = load_bench_log(pmg::test::sourcePath("config/bench/data/bam_xl330/2026-01-15_10h28m17.json"));  // lift_and_drop, kp 100
  EXPECT_EQ(l.size(), 1510u);
  ASSERT_TRUE(l.has_kp());
  EXPECT_DOUBLE_EQ(l.kp[0], 100.0);
  std::size_t off = 0;
  for (auto e : l.enabled) off += e == 0;
  EXPECT_EQ(off, 1138u);  // torque switched off for the free swing
}

TEST(BenchLog, ReadsDfkiPairAndDetectsTorqueMode) {
  const BenchLog es = load_bench_log(pmg::test::sourcePath("config/bench/data/dfki_ak80_6/energy_shaping/data_measured.csv"));
  EXPECT_EQ(es.size(), 4000u);
  ASSERT_TRUE(es.has_kp() && es.has_tau_ff());
  EXPECT_EQ(es.kp[100], 0.0);  // torque-controlled run
  const BenchLog pd = load_bench_log(pmg::test::sourcePath("config/bench/data/dfki_ak80_6/pd_system_identification/data_measured.csv"));
  EXPECT_EQ(pd.size(), 1170u);
  EXPECT_FALSE(pd.has_kp());  // PD run: rig gains
  EXPECT_TRUE(pd.has_dq_cmd());
}

TEST(RigConfig, LoadsShippedRigsAndRejectsBadValues) {
  for (const char* f : {"config/bench/bam_xl330.yaml", "config/bench/bam_sts3250.yaml", "config/bench/dfki_ak80_6.yaml"}) {
    const RigConfig r = load_rig_config(pmg::test::sourcePath(f));
    EXPECT_GT(r.mass_kg, 0.0) << f;
    BenchSimulator sim(r, false);  // the MJCF built from it compiles
  }
  const std::string e = error_of([] { load_rig_config(pmg::test::sourcePath("test/data/calib/bad_rig.yaml")); });
  EXPECT_NE(e.find("bad_rig.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("rig.mass_kg"), std::string::npos) << e;
  // Typos and non-finite numbers name the file, line, key (and the nearest key).
  const pmg::test::TempDir bad_dir;
  const std::string bad = bad_dir.file("rig_typo.yaml");
  const std::string motor = "motor: {control: pd, kp_Nm_per_rad: 4, kd_Nms_per_rad: 0.1, armature_kgm2: 0.001}\n";
  std::ofstream(bad) << "rig:\n  type: pendulum\n  mass_kg: 1\n  com_m: 0.1\n  gravity: 9.81\n" << motor;
  EXPECT_EQ(error_of([&] { load_rig_config(bad); }),
            bad + ":5: unknown key 'gravity' in 'rig' (did you mean 'gravity_mps2'?)");
  std::ofstream(bad) << "rig: {type: pendulum, mass_kg: 1, com_m: 0.1}\n" << motor << "sim: {dt: 0.001}\n";
  EXPECT_EQ(error_of([&] { load_rig_config(bad); }), bad + ":3: unknown key 'dt' in 'sim' (did you mean 'dt_s'?)");
  std::ofstream(bad) << "rig: {type: pendulm, mass_kg: 1, com_m: 0.1}\n" << motor;
  EXPECT_EQ(error_of([&] { load_rig_config(bad); }),
            bad + ":1: rig.type: expected one of 'pendulum', got 'pendulm' (did you mean 'pendulum'?)");
  std::ofstream(bad) << "rig: {type: pendulum, mass_kg: 1, com_m: 0.1}\n"
                     << "motor: {control: pd, kp_Nm_per_rad: 4, kd_Nms_per_rad: 0.1, armature_kgm2: 0.001, "
                        "torque_limit_Nm: .inf}\n";
  EXPECT_EQ(error_of([&] { load_rig_config(bad); }),
            bad + ":2: motor.torque_limit_Nm: expected a finite number, got '.inf'");
}

TEST(BenchLog, CsvNonFiniteValueIsRefused) {
  const pmg::test::TempDir bad_dir;
  const std::string bad = bad_dir.file("nan_log.csv");
  std::ofstream(bad) << "t,q_cmd,q\n0,0,0\n0.001,nan,0\n0.002,0,0\n";
  EXPECT_EQ(error_of([&] { load_bench_log(bad); }), bad + ": line 3, column 'q_cmd': 'nan' is not a finite number");
}

TEST(BenchLog, BamJsonTypoNamesFileLineAndNearestKey) {
  const pmg::test::TempDir bad_dir;
  const std::string bad = bad_dir.file("bam_typo.json");
  std::ofstream(bad) << "{\"kp\": 32, \"entries\": [\n"
                        "{\"timestamp\": 0, \"goal_position\": 0, \"position\": 0, \"speed\": 0,"
                        " \"torque_enable\": true},\n"
                        "{\"timestamp\": 0.01, \"goal_position\": 0, \"positon\": 0, \"speed\": 0,"
                        " \"torque_enable\": true}]}\n";
  EXPECT_EQ(error_of([&] { load_bench_log(bad); }),
            bad + ":3: unknown key 'positon' in 'entries[1]' (did you mean 'position'?)");
}

TEST(BenchSimulator, PendulumFreeSwingMatchesSmallAnglePeriod) {
  RigConfig r;
  r.source_file = "inline";
  r.mass_kg = 1.0;
  r.com_m = 0.25;
  r.kp_Nm_per_rad = 1.0;
  r.kd_Nms_per_rad = 0.1;
  r.armature_kgm2 = 0.0;
  r.sim_dt_s = 0.0005;
  BenchSimulator sim(r, false);
  BenchLog l;
  for (int i = 0; i <= 2000; ++i) {
    l.t.push_back(i * 0.001);
    l.q_cmd.push_back(0.0);
    l.q.push_back(i == 0 ? 0.05 : 0.0);
    l.enabled.push_back(0);
  }
  RolloutTrace tr;
  sim.rollout(l, RigParams{1.0, 1.0, 0.0, {}}, &tr);
  // First downward zero crossing after a quarter period: T = 2 pi sqrt(I / (m g l)), I = m l^2.
  const double T = 2 * M_PI * std::sqrt(0.25 / 9.81);
  std::size_t k = 1;
  while (k < tr.q.size() && tr.q[k] > 0) ++k;
  EXPECT_NEAR(k * 0.001, T / 4, 0.003);
}

TEST(ActuatorYaml, RoundTripAndUnknownKeyRejected) {
  ActuatorBlock b;
  b.params.fc_Nm = 0.12;
  b.params.delay_s = 0.004;
  b.params.rate_hz = 500;
  b.params.torque_limit_Nm = 25.0;
  b.armature_kgm2 = 0.01;
  b.kp_scale = 1.2;
  const pmg::test::TempDir path_dir;
  const std::string path = path_dir.file("act.yaml");
  write_actuator_file(path, b, "test");
  const ActuatorBlock r = load_actuator_file(path);
  EXPECT_DOUBLE_EQ(r.params.fc_Nm, 0.12);
  EXPECT_DOUBLE_EQ(r.params.delay_s, 0.004);
  EXPECT_DOUBLE_EQ(r.params.torque_limit_Nm, 25.0);
  EXPECT_DOUBLE_EQ(*r.armature_kgm2, 0.01);
  EXPECT_DOUBLE_EQ(r.kp_scale, 1.2);
  const std::string e = error_of([] { parse_actuator_block(YAML::Load("{fc_nm: 0.1}"), "robot.yaml"); });
  EXPECT_EQ(e, "robot.yaml: unknown key 'fc_nm' in 'actuator' (did you mean 'fc_Nm'?)");
  // In a file: the line of the misspelt key.
  const pmg::test::TempDir bad_dir;
  const std::string bad = bad_dir.file("act_typo.yaml");
  std::ofstream(bad) << "actuator:\n  fc_Nm: 0.1\n  delay: 0.002\n";
  EXPECT_EQ(error_of([&] { load_actuator_file(bad); }),
            bad + ":3: unknown key 'delay' in 'actuator' (did you mean 'delay_s'?)");
  std::ofstream(bad) << "actuator: {fc_Nm: .nan}\n";
  EXPECT_EQ(error_of([&] { load_actuator_file(bad); }),
            bad + ":1: actuator.fc_Nm: expected a finite number, got '.nan'");
  std::ofstream(bad) << "actuator: {torque_limit_Nm: .inf}\n";
  EXPECT_TRUE(std::isinf(load_actuator_file(bad).params.torque_limit_Nm));  // .inf = no saturation
  std::ofstream(bad) << "actuator: {fc_Nm: 0.1}\nactuater: {}\n";
  EXPECT_EQ(error_of([&] { load_actuator_file(bad); }),
            bad + ":2: unknown key 'actuater' at the top level (did you mean 'actuator'?)");
  const std::string e2 = error_of([] { parse_actuator_block(YAML::Load("{delay_s: -1}"), "robot.yaml"); });
  EXPECT_NE(e2.find("actuator.delay_s"), std::string::npos) << e2;
}

}  // namespace
}  // namespace pmg::calib
