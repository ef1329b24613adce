// Static files of the VR page (vr_static_files.cpp): MIME types, and no request target reaches a
// file outside the web root (dot segments, encoded dots, symlinks, backslashes, NUL).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "g1_fixture.hpp"
#include "pmg/teleop/vr_static_files.hpp"
#include "temp_dir.hpp"

namespace pmg::teleop {
namespace {

namespace fs = std::filesystem;

struct Root {
  test::TempDir tmp;
  fs::path web = tmp.path() / "web";
  Root() {
    fs::create_directories(web / "sub");
    std::ofstream(web / "index.html") << "<html></html>";
    std::ofstream(web / "vr.js") << "'use strict';";
    std::ofstream(web / "sub" / "index.html") << "sub";
    std::ofstream(web / "data.bin") << "x";
    std::ofstream(web / ".hidden.txt") << "secret";
    std::ofstream(tmp.path() / "secret.txt") << "outside";
    fs::create_symlink(tmp.path() / "secret.txt", web / "escape.txt");
  }
};

TEST(VrStaticFiles, ServesFilesWithTheirMimeTypes) {
  Root r;
  auto l = vrLookupStatic(r.web, "/");
  ASSERT_EQ(l.status, 200) << l.reason;
  EXPECT_EQ(l.file.filename(), "index.html");
  EXPECT_EQ(l.mime, "text/html; charset=utf-8");
  l = vrLookupStatic(r.web, "/vr.js?v=1#x");
  ASSERT_EQ(l.status, 200) << l.reason;
  EXPECT_EQ(l.mime, "text/javascript; charset=utf-8");
  l = vrLookupStatic(r.web, "/sub/");
  ASSERT_EQ(l.status, 200) << l.reason;
  EXPECT_EQ(l.file.parent_path().filename(), "sub");
  l = vrLookupStatic(r.web, "//sub//index%2Ehtml");
  EXPECT_EQ(l.status, 200) << "empty segments skipped, an encoded dot inside a name is fine: " << l.reason;
  EXPECT_EQ(vrMimeType(".css"), "text/css; charset=utf-8");
  EXPECT_EQ(vrMimeType(".png"), "image/png");
  EXPECT_EQ(vrMimeType(".svg"), "image/svg+xml");
  EXPECT_EQ(vrMimeType(".exe"), "");
}

TEST(VrStaticFiles, ShippedPageIsServable) {
  for (const char* f : {"/", "/vr.js", "/style.css"}) {
    const auto l = vrLookupStatic(test::sourcePath("data/vr/web"), f);
    EXPECT_EQ(l.status, 200) << f << ": " << l.reason;
  }
}

TEST(VrStaticFiles, PathTraversalIsImpossible) {
  Root r;
  for (const char* target :
       {"/../secret.txt", "/sub/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E/secret.txt",
        "/sub/%2e%2e/%2e%2e/secret.txt", "/..%2fsecret.txt", "/%2e%2e%2fsecret.txt", "/.%2e/secret.txt",
        "/./index.html", "/.hidden.txt", "/sub/%2e/index.html", "/escape.txt", "/data.bin", "/missing.html", "/sub"}) {
    const auto l = vrLookupStatic(r.web, target);
    EXPECT_NE(l.status, 200) << target << " served " << l.file;
    EXPECT_FALSE(l.reason.empty()) << target;
  }
  for (const char* target :
       {"", "index.html", "/..\\secret.txt", "/%5c..%5csecret.txt", "/a%00.html", "/%zz", "/%2", "/\x01"}) {
    const auto l = vrLookupStatic(r.web, target);
    EXPECT_EQ(l.status, 400) << "'" << target << "': " << l.reason;
  }
  EXPECT_EQ(vrLookupStatic(r.web, "/" + std::string(2000, 'a')).status, 400);
  EXPECT_EQ(vrLookupStatic(r.tmp.path() / "no_such_root", "/").status, 404);
}

}  // namespace
}  // namespace pmg::teleop
