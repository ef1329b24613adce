// pmg::yaml archive: fields declared once with defaults in the struct; unknown keys, wrong types,
// non-finite numbers, bad syntax and missing files are errors naming file:line, key and the nearest key.
#include "pmg/common/yaml_archive.hpp"

#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

namespace pmg {
namespace {

namespace fs = std::filesystem;

enum class Transport { kCan, kUdp, kSim };
std::vector<std::pair<std::string, Transport>> yamlEnumNames(Transport) {
  return {{"can", Transport::kCan}, {"udp", Transport::kUdp}, {"sim", Transport::kSim}};
}

struct Gains {
  double kp = 100.0;
  double kd = 2.0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("kp", &kp, "stiffness [N*m/rad]");
    a->Visit("kd", &kd, "damping [N*m*s/rad]");
  }
  std::string validate() const {
    return kp >= 0 && kp <= 5000 ? "" : "kp = " + std::to_string(kp) + ": expected 0..5000";
  }
};

struct Safety {
  bool hal_supervisor = false;
  double max_velocity = 3.0;
  double limit = std::numeric_limits<double>::infinity();
  template <class A>
  void Serialize(A* a) {
    a->Visit("hal_supervisor", &hal_supervisor, "run the HAL supervisor");
    a->Visit("max_velocity", &max_velocity, "[rad/s]");
    a->Visit("limit", &limit, "[N*m], .inf = none", yaml::kAllowNonFinite);
  }
};

struct Config {
  std::string name;
  int count = 3;
  std::uint8_t id = 1;
  std::optional<double> height;
  Transport transport = Transport::kSim;
  std::string model;
  std::filesystem::path data;
  std::vector<double> weights{1.0, 2.0};
  std::array<double, 3> offset{0.0, 0.0, 0.0};
  std::map<std::string, Gains> gains;
  std::vector<Gains> joints;
  Safety safety;
  YAML::Node extra;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, "robot name", yaml::kRequired);
    a->Visit("count", &count);
    a->Visit("id", &id, "1..254");
    a->Visit("height", &height, "[m]");
    a->Visit("transport", &transport, "can | udp | sim");
    a->Visit("model", &model, "model file", yaml::kPath);
    a->Visit("data", &data);
    a->Visit("weights", &weights);
    a->Visit("offset", &offset, "[m]");
    a->Visit("gains", &gains);
    a->Visit("joints", &joints);
    a->Visit("safety", &safety);
    a->Visit("extra", &extra, "raw node");
  }
};

Config parse(const std::string& text) { return yaml::parseYamlString<Config>(text, "cfg.yaml", "", "/base"); }

std::string errorOf(const std::string& text) {
  try {
    parse(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(YamlArchive, ReadsEveryFieldTypeAndKeepsDefaults) {
  const Config c = parse(
      "name: g1\n"
      "count: 0x10\n"
      "height: 0.7\n"
      "transport: udp\n"
      "model: models/g1.xml\n"
      "data: /abs/data\n"
      "offset: [1, 2, 3]\n"
      "gains: {knee: {kp: 200}, hip: {kd: 5}}\n"
      "joints: [{kp: 1}, {}]\n"
      "safety: {limit: .inf}\n"
      "extra: {anything: [1, 2]}\n");
  EXPECT_EQ(c.name, "g1");
  EXPECT_EQ(c.count, 16);
  EXPECT_EQ(c.id, 1);  // default kept
  ASSERT_TRUE(c.height.has_value());
  EXPECT_DOUBLE_EQ(*c.height, 0.7);
  EXPECT_EQ(c.transport, Transport::kUdp);
  EXPECT_EQ(c.model, "/base/models/g1.xml");
  EXPECT_EQ(c.data, fs::path("/abs/data"));
  EXPECT_EQ(c.weights, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(c.offset, (std::array<double, 3>{1, 2, 3}));
  ASSERT_EQ(c.gains.size(), 2u);
  EXPECT_DOUBLE_EQ(c.gains.at("knee").kp, 200);
  EXPECT_DOUBLE_EQ(c.gains.at("knee").kd, 2.0);
  EXPECT_DOUBLE_EQ(c.gains.at("hip").kp, 100.0);
  ASSERT_EQ(c.joints.size(), 2u);
  EXPECT_DOUBLE_EQ(c.joints[0].kp, 1.0);
  EXPECT_DOUBLE_EQ(c.joints[1].kp, 100.0);
  EXPECT_TRUE(std::isinf(c.safety.limit));
  EXPECT_DOUBLE_EQ(c.safety.max_velocity, 3.0);
  EXPECT_EQ(c.extra["anything"].size(), 2u);
}

TEST(YamlArchive, NullOptionalIsEmpty) {
  EXPECT_FALSE(parse("name: a\nheight: ~\n").height.has_value());
  EXPECT_FALSE(parse("name: a\n").height.has_value());
}

TEST(YamlArchive, UnknownKeyNamesFileLineKeyAndNearestKey) {
  EXPECT_EQ(errorOf("name: g1\nsafety:\n  max_velocity: 2\n  hal_supervisr: true\n"),
            "cfg.yaml:4: unknown key 'hal_supervisr' in 'safety' (did you mean 'hal_supervisor'?)");
  EXPECT_EQ(errorOf("name: g1\nwieghts: [1]\n"),
            "cfg.yaml:2: unknown key 'wieghts' at the top level (did you mean 'weights'?)");
  EXPECT_EQ(errorOf("name: g1\njoints: [{kp: 1}, {kpp: 2}]\n"),
            "cfg.yaml:2: unknown key 'kpp' in 'joints[1]' (did you mean 'kp'?)");
  EXPECT_EQ(errorOf("name: g1\ngains:\n  knee: {kp: 1, kdd: 2}\n"),
            "cfg.yaml:3: unknown key 'kdd' in 'gains.knee' (did you mean 'kd'?)");
}

TEST(YamlArchive, DuplicateKeyIsAnError) {
  EXPECT_EQ(errorOf("name: g1\ncount: 1\ncount: 2\n"), "cfg.yaml:3: duplicate key 'count'");
}

TEST(YamlArchive, MissingRequiredKey) { EXPECT_EQ(errorOf("count: 1\n"), "cfg.yaml:1: missing required key 'name'"); }

TEST(YamlArchive, MisspeltRequiredKeyIsNamedAsUnknownWithTheNearestKey) {
  EXPECT_EQ(errorOf("count: 1\nnmae: g1\n"), "cfg.yaml:2: unknown key 'nmae' at the top level (did you mean 'name'?)");
}

TEST(YamlArchive, TypeErrorsNameLineKeyPathAndExpectedType) {
  EXPECT_EQ(errorOf("name: g1\ncount: 1.5\n"), "cfg.yaml:2: count: expected an integer, got '1.5'");
  EXPECT_EQ(errorOf("name: g1\nid: 300\n"), "cfg.yaml:2: id: expected an integer in 0..255, got 300");
  EXPECT_EQ(errorOf("name: g1\nid: -1\n"), "cfg.yaml:2: id: expected an integer in 0..255, got -1");
  EXPECT_EQ(errorOf("name: g1\njoints:\n  - {kp: fast}\n"),
            "cfg.yaml:3: joints[0].kp: expected a finite number, got 'fast'");
  EXPECT_EQ(errorOf("name: [a]\n"), "cfg.yaml:1: name: expected a string, got a list");
  EXPECT_EQ(errorOf("name: g1\nsafety: {hal_supervisor: maybe}\n"),
            "cfg.yaml:2: safety.hal_supervisor: expected true or false, got 'maybe'");
  EXPECT_EQ(errorOf("name: g1\nweights: 3\n"), "cfg.yaml:2: weights: expected a list, got '3'");
  EXPECT_EQ(errorOf("name: g1\noffset: [1, 2]\n"), "cfg.yaml:2: offset: expected a list of exactly 3 items, got 2");
  EXPECT_EQ(errorOf("name: g1\nsafety: 7\n"), "cfg.yaml:2: safety: expected a map, got '7'");
  EXPECT_EQ(errorOf("name: g1\ntransport: cann\n"),
            "cfg.yaml:2: transport: expected one of 'can', 'udp', 'sim', got 'cann' (did you mean 'can'?)");
  EXPECT_EQ(errorOf("- a\n- b\n"), "cfg.yaml:1: expected a map, got a list");
}

TEST(YamlArchive, NonFiniteNumbersRefusedUnlessAllowed) {
  for (const char* v : {".inf", "-.inf", ".nan", ".NaN", "+.Inf"}) {
    EXPECT_EQ(errorOf(std::string("name: g1\nsafety: {max_velocity: ") + v + "}\n"),
              std::string("cfg.yaml:2: safety.max_velocity: expected a finite number, got '") + v + "'");
  }
  EXPECT_EQ(errorOf("name: g1\nweights: [1, .nan]\n"), "cfg.yaml:2: weights[1]: expected a finite number, got '.nan'");
  EXPECT_TRUE(std::isinf(parse("name: g1\nsafety: {limit: -.inf}\n").safety.limit));
}

TEST(YamlArchive, ValidateIsCalledAndNamesFileLineAndKeyPath) {
  EXPECT_EQ(errorOf("name: g1\njoints:\n  - {kp: 1}\n  - {kp: -1}\n"),
            "cfg.yaml:4: joints[1]: kp = -1.000000: expected 0..5000");
}

struct ThrowingCheck {
  double dt = 0.01;
  template <class A>
  void Serialize(A* a) {
    a->Visit("dt", &dt, "[s]");
  }
  void validate() const {
    if (!(dt > 0 && dt < 0.1)) throw std::invalid_argument("dt = " + std::to_string(dt) + ": expected in (0, 0.1) s");
  }
};

TEST(YamlArchive, ThrowingValidateIsConvertedToConfigErrorWithLocation) {
  EXPECT_DOUBLE_EQ(yaml::parseYamlString<ThrowingCheck>("dt: 0.002\n", "t.yaml").dt, 0.002);
  try {
    yaml::parseYamlString<ThrowingCheck>("\ndt: 5\n", "t.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "t.yaml:2: dt = 5.000000: expected in (0, 0.1) s");
  }
}

TEST(YamlArchive, SyntaxErrorAndMissingFileNameThePath) {
  const std::string msg = errorOf("name: [g1\n");
  EXPECT_EQ(msg.rfind("cfg.yaml:", 0), 0u) << msg;
  EXPECT_NE(msg.find("YAML syntax error"), std::string::npos) << msg;
  try {
    yaml::loadYamlFile<Config>("/nonexistent/dir/cfg.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/dir/cfg.yaml: cannot open file");
  }
}

TEST(YamlArchive, FileLoadResolvesPathsAgainstTheFileFolderAndReadsOneKey) {
  const fs::path dir = fs::temp_directory_path() / ("pmg_yaml_archive_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir / "sub");
  const fs::path file = dir / "sub" / "cfg.yaml";
  std::ofstream(file) << "robot:\n  name: g1\n  model: ../models/g1.xml\ngains: {kp: 7}\nother: [whatever]\n";
  const Config c = yaml::loadYamlFile<Config>(file.string(), "robot");
  EXPECT_EQ(c.model, (dir / "models" / "g1.xml").string());
  EXPECT_DOUBLE_EQ(yaml::loadYamlFile<Gains>(file.string(), "gains").kp, 7.0);
  try {
    yaml::loadYamlFile<Gains>(file.string(), "gainz");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ":1: missing required key 'gainz'");
  }
  fs::remove_all(dir);
}

TEST(YamlArchive, SourceWithoutLinesNamesOnlyTheFile) {
  Gains g;
  try {
    yaml::readYaml(YAML::Load("\n\nkq: 1\n"), yaml::YamlSource{"robot.yaml: joints[2].gains", "", "", false}, &g);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "robot.yaml: joints[2].gains: unknown key 'kq' at the top level (did you mean 'kp'?)");
  }
}

TEST(YamlArchive, PublicHelpersForCustomReaders) {
  const yaml::YamlSource root{"f.yaml", "/d", ""};
  EXPECT_EQ(yaml::childSource(root, "safety").key_path, "safety");
  EXPECT_EQ(yaml::itemSource(yaml::childSource(root, "joints"), 3).key_path, "joints[3]");
  EXPECT_EQ(yaml::childSource(yaml::itemSource(yaml::childSource(root, "joints"), 3), "kp").key_path, "joints[3].kp");
  const yaml::YamlDocument doc = yaml::parseYamlDocument("a: 1\nbb: 2\n", "f.yaml");
  EXPECT_NO_THROW(yaml::rejectUnknownKeys(doc.root, doc.source, {"a", "bb"}));
  try {
    yaml::rejectUnknownKeys(doc.root, doc.source, {"a", "b"});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "f.yaml:2: unknown key 'bb' at the top level (did you mean 'b'?)");
  }
}

TEST(YamlArchive, EditDistanceAndNearestKey) {
  EXPECT_EQ(yaml::editDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(yaml::editDistance("", "abc"), 3u);
  EXPECT_EQ(yaml::editDistance("policyy", "policy"), 1u);
  EXPECT_EQ(yaml::nearestKey("vxx", {"vy", "vx", "wz"}), "vx");
  EXPECT_EQ(yaml::nearestKey("x", {}), "");
  EXPECT_EQ(yaml::nearestKey("rp", {"name", "dp", "rpy"}), "rpy");  // tie at distance 1: longer common prefix
}

TEST(YamlArchive, DescribeFieldsListsDeclarationsInOrder) {
  const auto fields = yaml::describeFields<Safety>();
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[0].name, "hal_supervisor");
  EXPECT_EQ(fields[1].doc, "[rad/s]");
  EXPECT_EQ(fields[2].flags, yaml::kAllowNonFinite);
}

}  // namespace
}  // namespace pmg
