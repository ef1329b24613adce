// The bridge's self-signed certificate and access token (vr_certificate.cpp): generated once with
// a private key (0600) and a SAN naming 127.0.0.1, reused afterwards, unsafe or broken files refused.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "g1_fixture.hpp"
#include "pmg/teleop/vr_certificate.hpp"
#include "temp_dir.hpp"

namespace pmg::teleop {
namespace {

namespace fs = std::filesystem;

unsigned modeOf(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 0777;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

TEST(VrCertificate, FirstRunGeneratesPrivateKeyAndSanThenReuses) {
  test::TempDir tmp;
  const fs::path dir = tmp.path() / "cfg" / "pmg" / "vr";  // created, with its parents
  const VrCertificateInfo first = ensureVrCertificate(dir, {"192.0.2.7", "robot-base.local"});
  EXPECT_TRUE(first.created);
  ASSERT_TRUE(fs::is_regular_file(first.cert_file));
  ASSERT_TRUE(fs::is_regular_file(first.key_file));
  EXPECT_EQ(modeOf(first.key_file), 0600u) << "private key readable by its owner only";
  EXPECT_EQ(modeOf(dir), 0700u);
  EXPECT_EQ(first.sha256_fingerprint.size(), 32u * 3 - 1) << first.sha256_fingerprint;
  EXPECT_TRUE(contains(first.subject_alt_names, "IP Address:127.0.0.1"));
  EXPECT_TRUE(contains(first.subject_alt_names, "DNS:localhost"));
  EXPECT_TRUE(contains(first.subject_alt_names, "IP Address:192.0.2.7")) << "extra names are added";
  EXPECT_TRUE(contains(first.subject_alt_names, "DNS:robot-base.local"));
  EXPECT_FALSE(first.not_after.empty());
  const std::string pem = test::readTextFile(first.cert_file.string());
  EXPECT_NE(pem.find("BEGIN CERTIFICATE"), std::string::npos);

  const VrCertificateInfo second = ensureVrCertificate(dir);
  EXPECT_FALSE(second.created) << "reused on the next run";
  EXPECT_EQ(second.sha256_fingerprint, first.sha256_fingerprint);
  EXPECT_EQ(test::readTextFile(second.cert_file.string()), pem);
}

TEST(VrCertificate, UnsafeOrBrokenFilesAreRefusedWithTheFileNamed) {
  test::TempDir tmp;
  const fs::path dir = tmp.path() / "vr";
  const VrCertificateInfo info = ensureVrCertificate(dir);
  const auto message = [&]() -> std::string {
    try {
      ensureVrCertificate(dir);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  fs::permissions(info.key_file, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  std::string m = message();
  EXPECT_NE(m.find(info.key_file.string()), std::string::npos) << m;
  EXPECT_NE(m.find("chmod 600"), std::string::npos) << m;
  fs::permissions(info.key_file, fs::perms::owner_read | fs::perms::owner_write);

  { std::ofstream(info.cert_file) << "not a certificate\n"; }
  m = message();
  EXPECT_NE(m.find(info.cert_file.string()), std::string::npos) << m;
  EXPECT_NE(m.find("PEM"), std::string::npos) << m;

  // A key of another pair does not match the certificate.
  const VrCertificateInfo other = ensureVrCertificate(tmp.path() / "other");
  { std::ofstream(info.cert_file) << test::readTextFile(other.cert_file.string()); }
  m = message();
  EXPECT_NE(m.find("does not match"), std::string::npos) << m;

  fs::remove(info.cert_file);
  m = message();
  EXPECT_NE(m.find("missing"), std::string::npos) << m;
}

TEST(VrCertificate, AccessTokenIsCreatedPrivateAndReused) {
  test::TempDir tmp;
  const std::string t1 = ensureVrAccessToken(tmp.path() / "vr");
  EXPECT_EQ(t1.size(), 16u);
  EXPECT_EQ(modeOf(tmp.path() / "vr" / "token"), 0600u);
  EXPECT_EQ(ensureVrAccessToken(tmp.path() / "vr"), t1);
  EXPECT_NE(ensureVrAccessToken(tmp.path() / "vr2"), t1) << "random per folder";
  { std::ofstream(tmp.path() / "vr" / "token") << "bad token!\n"; }
  EXPECT_THROW(ensureVrAccessToken(tmp.path() / "vr"), std::runtime_error);
}

}  // namespace
}  // namespace pmg::teleop
