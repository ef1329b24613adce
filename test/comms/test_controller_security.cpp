// The controller config's `security:` block (src/controller/controller_config.cpp): an unsafe,
// missing or malformed key file is a setup error naming the file and the reason; a good one is
// loaded; the verifier options are range-checked and unknown keys are errors.
#include <sys/stat.h>

#include <string>

#include <gtest/gtest.h>

#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/comms/auth.hpp"
#include "pmg/controller/controller_config.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {

const std::string kHexKey = "8f1e2d3c4b5a69788796a5b4c3d2e1f00f1e2d3c4b5a69788796a5b4c3d2e1f0";

/// g1_sil.yaml with its relative paths made absolute and @p security appended, written into @p dir.
std::string configWith(const test::TempDir& dir, const std::string& security) {
  std::string text;
  {
    std::FILE* f = std::fopen(test::g1SilControllerConfigPath().c_str(), "rb");
    EXPECT_NE(f, nullptr);
    char buf[4096];
    for (std::size_t n; f != nullptr && (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
    if (f != nullptr) std::fclose(f);
  }
  const std::string config_dir = test::sourceDir() + "/config/";
  for (std::size_t at; (at = text.find(": ../")) != std::string::npos;) text.replace(at, 5, ": " + config_dir);
  return dir.write("controller.yaml", text + "\n" + security + "\n");
}

std::string keyFile(const test::TempDir& dir, const std::string& name, mode_t mode) {
  const std::string path = dir.write(name, kHexKey + "\n");
  EXPECT_EQ(::chmod(path.c_str(), mode), 0);
  return path;
}

std::string loadError(const std::string& config) {
  try {
    (void)loadControllerConfig(config);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ControllerSecurityConfig, NoBlockMeansPlainCommandsAndTheDefaults) {
  test::TempDir dir;
  const ControllerConfig c = loadControllerConfig(configWith(dir, ""));
  EXPECT_FALSE(c.security.enabled());
  EXPECT_DOUBLE_EQ(c.security.verifier.max_age_s, 0.5);
  EXPECT_EQ(c.security.verifier.max_senders, 8);
  EXPECT_NE(c.lcm_url.find("ttl=0"), std::string::npos) << "the default URL keeps traffic on the host";
}

TEST(ControllerSecurityConfig, OwnerOnlyKeyIsLoadedRelativeToTheConfig) {
  test::TempDir dir;
  keyFile(dir, "keys/robot.key", 0600);
  const ControllerConfig c = loadControllerConfig(
      configWith(dir, "security:\n  key_file: keys/robot.key\n  max_message_age_s: 0.25\n  max_senders: 3"));
  ASSERT_TRUE(c.security.enabled());
  EXPECT_EQ(c.security.key_file, dir.file("keys/robot.key"));
  EXPECT_EQ(comms::toHex(c.security.key), kHexKey);
  EXPECT_DOUBLE_EQ(c.security.verifier.max_age_s, 0.25);
  EXPECT_EQ(c.security.verifier.max_senders, 3);
}

TEST(ControllerSecurityConfig, WorldReadableKeyIsAnErrorNamingTheFile) {
  test::TempDir dir;
  const std::string key = keyFile(dir, "robot.key", 0644);
  const std::string config = configWith(dir, "security:\n  key_file: robot.key");
  const std::string e = loadError(config);
  EXPECT_NE(e.find(key), std::string::npos) << e;
  EXPECT_NE(e.find("controller.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("security"), std::string::npos) << e;
  EXPECT_NE(e.find("mode 0644"), std::string::npos) << e;
  EXPECT_NE(e.find("chmod 600"), std::string::npos) << e;
}

TEST(ControllerSecurityConfig, MissingOrMalformedKeyAndBadOptionsAreErrors) {
  test::TempDir dir;
  std::string e = loadError(configWith(dir, "security:\n  key_file: nowhere.key"));
  EXPECT_NE(e.find(dir.file("nowhere.key")), std::string::npos) << e;
  EXPECT_NE(e.find("cannot open"), std::string::npos) << e;
  const std::string bad = dir.write("short.key", "abcd\n");
  ASSERT_EQ(::chmod(bad.c_str(), 0600), 0);
  e = loadError(configWith(dir, "security:\n  key_file: short.key"));
  EXPECT_NE(e.find(bad), std::string::npos) << e;
  EXPECT_NE(e.find("64 hex"), std::string::npos) << e;
  e = loadError(configWith(dir, "security:\n  max_senders: 0"));
  EXPECT_NE(e.find("max_senders"), std::string::npos) << e;
  EXPECT_NE(e.find("1..64"), std::string::npos) << e;
  e = loadError(configWith(dir, "security:\n  max_message_age_s: .inf"));
  EXPECT_NE(e.find("max_message_age_s"), std::string::npos) << e;
  e = loadError(configWith(dir, "security:\n  key_fil: robot.key"));
  EXPECT_NE(e.find("key_fil"), std::string::npos) << e;
}

}  // namespace
}  // namespace pmg
