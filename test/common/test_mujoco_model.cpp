// loadMujocoModel's opt-in compiled-model cache (mujoco_model.hpp): off without PMG_MJCF_CACHE_DIR; a
// second load is served from the entry and is the same model, byte for byte, as a compile; a corrupted
// or unchecked entry is rejected, counted and rewritten; the key follows the options and the content of
// the mesh files; a model MuJoCo cannot compile still throws and leaves no entry.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sodium.h>

#include "g1_fixture.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "temp_dir.hpp"

namespace pmg {
namespace {
namespace fs = std::filesystem;

/// Sets (or unsets) PMG_MJCF_CACHE_DIR for one test and restores what the suite had (scripts/run_tests.sh sets it).
class CacheDirGuard {
 public:
  explicit CacheDirGuard(const std::optional<std::string>& dir) {
    if (const char* old = std::getenv("PMG_MJCF_CACHE_DIR")) old_ = old;
    if (dir) {
      setenv("PMG_MJCF_CACHE_DIR", dir->c_str(), 1);
    } else {
      unsetenv("PMG_MJCF_CACHE_DIR");
    }
  }
  ~CacheDirGuard() {
    if (old_) {
      setenv("PMG_MJCF_CACHE_DIR", old_->c_str(), 1);
    } else {
      unsetenv("PMG_MJCF_CACHE_DIR");
    }
  }
  CacheDirGuard(const CacheDirGuard&) = delete;
  CacheDirGuard& operator=(const CacheDirGuard&) = delete;

 private:
  std::optional<std::string> old_;
};

/// MuJoCo's binary image of @p m (mj_saveModel): equal images are the same model.
std::string imageOf(const mjModel* m) {
  std::string bytes(static_cast<std::size_t>(mj_sizeModel(m)), '\0');
  mj_saveModel(m, nullptr, bytes.data(), static_cast<int>(bytes.size()));
  return bytes;
}

MujocoModelCacheStats delta(const MujocoModelCacheStats& before) {
  const MujocoModelCacheStats now = mujocoModelCacheStats();
  return {now.hits - before.hits, now.misses - before.misses, now.rejected - before.rejected,
          now.stored - before.stored};
}

std::vector<fs::path> entries(const fs::path& dir, const std::string& extension) {
  std::vector<fs::path> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == extension) out.push_back(e.path());
  return out;
}

/// A binary STL tetrahedron with edge @p s [m] at the origin, faces outward.
std::string tetrahedronStl(float s) {
  const std::array<std::array<float, 3>, 4> v = {{{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}}};
  const std::array<std::array<int, 3>, 4> faces = {{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  std::string stl(80, '\0');
  const std::uint32_t n = faces.size();
  stl.append(reinterpret_cast<const char*>(&n), sizeof n);
  for (const auto& f : faces) {
    const float normal[3] = {0, 0, 0};
    stl.append(reinterpret_cast<const char*>(normal), sizeof normal);
    for (int i : f) stl.append(reinterpret_cast<const char*>(v[static_cast<std::size_t>(i)].data()), 3 * sizeof(float));
    const std::uint16_t attribute = 0;
    stl.append(reinterpret_cast<const char*>(&attribute), sizeof attribute);
  }
  return stl;
}

const char* kTinyMjcf = R"(<mujoco model="tiny">
  <compiler angle="radian" meshdir="meshes"/>
  <asset><mesh name="tet" file="tet.stl"/></asset>
  <worldbody>
    <body name="pelvis" pos="0 0 1">
      <joint type="free"/>
      <geom type="mesh" mesh="tet"/>
      <site name="imu_in_pelvis"/>
    </body>
  </worldbody>
</mujoco>
)";

TEST(MujocoModelCache, OffWithoutTheVariableReadsAndWritesNothing) {
  const CacheDirGuard guard(std::nullopt);
  const MujocoModelCacheStats before = mujocoModelCacheStats();
  const MjModelPtr a = loadMujocoModel(pmg::test::g1Robot().mjcf_path);
  const MjModelPtr b = loadMujocoModel(pmg::test::g1Robot().mjcf_path);
  const MujocoModelCacheStats d = delta(before);
  EXPECT_EQ(d.hits + d.misses + d.rejected + d.stored, 0);
  EXPECT_EQ(imageOf(a.get()), imageOf(b.get()));  // MuJoCo's compile is deterministic: what the cache relies on
}

TEST(MujocoModelCache, SecondLoadIsServedFromTheEntryAndIsTheSameModelAsACompile) {
  const test::TempDir tmp;
  const fs::path dir = tmp.path() / "cache" / "nested";  // created on the first store
  std::string compiled;
  {
    const CacheDirGuard off(std::nullopt);
    compiled = imageOf(loadMujocoModel(pmg::test::g1Robot().mjcf_path).get());
  }
  const CacheDirGuard guard(dir.string());
  MujocoModelCacheStats before = mujocoModelCacheStats();
  const MjModelPtr first = loadMujocoModel(pmg::test::g1Robot().mjcf_path);
  MujocoModelCacheStats d = delta(before);
  EXPECT_EQ(d.misses, 1);
  EXPECT_EQ(d.hits, 0);
  EXPECT_EQ(d.stored, 1);
  ASSERT_EQ(entries(dir, ".mjb").size(), 1u);
  ASSERT_EQ(entries(dir, ".b2").size(), 1u);

  before = mujocoModelCacheStats();
  const MjModelPtr second = loadMujocoModel(pmg::test::g1Robot().mjcf_path);
  d = delta(before);
  EXPECT_EQ(d.hits, 1);
  EXPECT_EQ(d.misses, 0);
  EXPECT_EQ(d.stored, 0);
  EXPECT_EQ(imageOf(first.get()), compiled);
  EXPECT_EQ(imageOf(second.get()), compiled);
  EXPECT_EQ(second->nmesh, 35);
  EXPECT_GT(second->nmeshgraph, 0);  // the convex hulls came with the entry (no qhull on this load)

  // Other options: another key, another entry.
  Mujoco22Options o;
  o.timestep = 0.002;
  before = mujocoModelCacheStats();
  const MjModelPtr other = loadMujocoModel(pmg::test::g1Robot().mjcf_path, o);
  d = delta(before);
  EXPECT_EQ(d.misses, 1);
  EXPECT_EQ(entries(dir, ".mjb").size(), 2u);
  EXPECT_DOUBLE_EQ(other->opt.timestep, 0.002);
}

TEST(MujocoModelCache, ACorruptedOrUncheckedEntryIsRejectedCountedAndRewritten) {
  const test::TempDir tmp;
  tmp.write("robot/meshes/tet.stl", tetrahedronStl(0.1F));
  const std::string mjcf = tmp.write("robot/tiny.xml", kTinyMjcf);
  const fs::path dir = tmp.path() / "cache";
  std::string compiled;
  {
    const CacheDirGuard off(std::nullopt);
    compiled = imageOf(loadMujocoModel(mjcf).get());
  }
  const CacheDirGuard guard(dir.string());
  loadMujocoModel(mjcf);
  const std::vector<fs::path> mjb = entries(dir, ".mjb");
  ASSERT_EQ(mjb.size(), 1u);

  // One byte flipped in the middle of the entry (a double of the model, say).
  {
    std::fstream f(mjb[0], std::ios::in | std::ios::out | std::ios::binary);
    const auto middle = static_cast<std::streamoff>(fs::file_size(mjb[0]) / 2);
    f.seekg(middle);
    char c = 0;
    f.get(c);
    f.seekp(middle);
    f.put(static_cast<char>(c ^ 0x5a));
  }
  MujocoModelCacheStats before = mujocoModelCacheStats();
  const MjModelPtr after_flip = loadMujocoModel(mjcf);
  MujocoModelCacheStats d = delta(before);
  EXPECT_EQ(d.rejected, 1);
  EXPECT_EQ(d.misses, 1);
  EXPECT_EQ(d.hits, 0);
  EXPECT_EQ(d.stored, 1);
  EXPECT_EQ(imageOf(after_flip.get()), compiled);

  before = mujocoModelCacheStats();
  EXPECT_EQ(imageOf(loadMujocoModel(mjcf).get()), compiled);
  EXPECT_EQ(delta(before).hits, 1);  // rewritten: served again

  // An entry without its checksum file is not trusted either.
  fs::remove(fs::path(mjb[0].string() + ".b2"));
  before = mujocoModelCacheStats();
  EXPECT_EQ(imageOf(loadMujocoModel(mjcf).get()), compiled);
  d = delta(before);
  EXPECT_EQ(d.rejected, 1);
  EXPECT_EQ(d.stored, 1);

  // A truncated entry with a checksum that matches the truncated bytes: the checksum passes, MuJoCo refuses it.
  {
    std::ifstream in(mjb[0], std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes.resize(bytes.size() / 3);
    std::ofstream(mjb[0], std::ios::binary | std::ios::trunc) << bytes;
    std::array<unsigned char, crypto_generichash_BYTES> h{};
    crypto_generichash(h.data(), h.size(), reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                       nullptr, 0);
    std::array<char, 2 * crypto_generichash_BYTES + 1> hex{};
    sodium_bin2hex(hex.data(), hex.size(), h.data(), h.size());
    std::ofstream(mjb[0].string() + ".b2", std::ios::binary | std::ios::trunc) << hex.data();
  }
  before = mujocoModelCacheStats();
  EXPECT_EQ(imageOf(loadMujocoModel(mjcf).get()), compiled);
  d = delta(before);
  EXPECT_EQ(d.rejected, 1);
  EXPECT_EQ(d.stored, 1);
}

TEST(MujocoModelCache, TheKeyFollowsTheMeshFilesContent) {
  const test::TempDir tmp;
  tmp.write("robot/meshes/tet.stl", tetrahedronStl(0.1F));
  const std::string mjcf = tmp.write("robot/tiny.xml", kTinyMjcf);
  const CacheDirGuard guard((tmp.path() / "cache").string());
  const MjModelPtr small = loadMujocoModel(mjcf);

  tmp.write("robot/meshes/tet.stl", tetrahedronStl(0.2F));  // same name, same MJCF, other mesh
  const MujocoModelCacheStats before = mujocoModelCacheStats();
  const MjModelPtr large = loadMujocoModel(mjcf);
  const MujocoModelCacheStats d = delta(before);
  EXPECT_EQ(d.hits, 0);
  EXPECT_EQ(d.misses, 1);
  // The bounding radius of the geom follows the mesh: a stale entry would have kept 0.1 m's.
  EXPECT_GT(large->geom_rbound[0], 1.5 * small->geom_rbound[0]);
}

TEST(MujocoModelCache, KeepsTheMostRecentlyUsedEntriesUpToItsLimit) {
  const test::TempDir tmp;
  tmp.write("robot/meshes/tet.stl", tetrahedronStl(0.1F));
  const std::string mjcf = tmp.write("robot/tiny.xml", kTinyMjcf);
  const fs::path dir = tmp.path() / "cache";
  const CacheDirGuard guard(dir.string());
  const std::size_t n = kMujocoModelCacheMaxEntries + 2;
  auto options = [](std::size_t i) {
    Mujoco22Options o;
    o.timestep = 0.001 + 1e-5 * static_cast<double>(i);  // another key each
    return o;
  };
  // Entry i is given the time (an hour ago) + i s, so "least recently used" is exact whatever the clock's
  // resolution; a new entry (now) is the newest.
  const auto base = fs::file_time_type::clock::now() - std::chrono::hours(1);
  std::vector<fs::path> known;
  for (std::size_t i = 0; i < n; ++i) {
    loadMujocoModel(mjcf, options(i));
    for (const fs::path& p : entries(dir, ".mjb")) {
      if (std::find(known.begin(), known.end(), p) != known.end()) continue;
      fs::last_write_time(p, base + std::chrono::seconds(i));
      known.push_back(p);
    }
    ASSERT_EQ(known.size(), i + 1);
  }
  EXPECT_EQ(entries(dir, ".mjb").size(), kMujocoModelCacheMaxEntries);
  EXPECT_EQ(entries(dir, ".b2").size(), kMujocoModelCacheMaxEntries);
  EXPECT_FALSE(fs::exists(known[0]));
  EXPECT_FALSE(fs::exists(known[1]));

  MujocoModelCacheStats before = mujocoModelCacheStats();
  loadMujocoModel(mjcf, options(2));  // the oldest kept; served, and its time renewed
  EXPECT_EQ(delta(before).hits, 1);
  before = mujocoModelCacheStats();
  loadMujocoModel(mjcf, options(0));  // evicted: compiled and stored again, evicting entry 3, not entry 2
  EXPECT_EQ(delta(before).misses, 1);
  EXPECT_TRUE(fs::exists(known[2]));
  EXPECT_FALSE(fs::exists(known[3]));
}

TEST(MujocoModelCache, AModelMuJoCoCannotCompileStillThrowsAndLeavesNoEntry) {
  const test::TempDir tmp;
  const std::string mjcf = tmp.write("robot/tiny.xml", kTinyMjcf);  // its mesh file is missing
  const fs::path dir = tmp.path() / "cache";
  const CacheDirGuard guard(dir.string());
  EXPECT_THROW(loadMujocoModel(mjcf), std::runtime_error);
  EXPECT_TRUE(entries(dir, ".mjb").empty());
}

}  // namespace
}  // namespace pmg
