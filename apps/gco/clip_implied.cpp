// pmg_clip_implied: computes the stance-implied motion table of every dynamic clip of a clip folder
// (pmg::gco::computeImpliedMotion, include/pmg/gco/implied_motion.hpp) and writes it into the clip
// files (`implied_motion:`, docs/clip_format.md), or with --check verifies the stored tables.
//
//   pmg_clip_implied --clips config/clips/g1            # (re)write the tables
//   pmg_clip_implied --clips config/clips/g1 --check    # exit 1 if a table is missing or stale
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "pmg/clips/clip_io.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/implied_motion.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  CLI::App app{"Stance-implied motion tables of the dynamic clips (command-consistent blending, docs/generator.md)"};
  std::string robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string clips_dir = pmg::resolveData("config/clips/g1").string();
  bool check = false, map = true;
  double tolerance = 1e-5;  // files hold 6 decimals: pmg_make_clips computes from unrounded clips
  app.add_option("--robot", robot_path, "robot config YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--clips", clips_dir, "clip folder")->check(CLI::ExistingDirectory)->capture_default_str();
  app.add_flag("--check", check, "verify the stored tables instead of writing them");
  app.add_option("--tolerance", tolerance, "--check: largest difference accepted [m/s, rad/s]")->check(CLI::Range(0.0, 1.0));
  app.add_flag("--map,!--no-map", map, "also compute consistency_map.yaml (the residual correction over the envelope)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const pmg::GeneratorJointSpace js = pmg::generatorJointSpace(robot);
    const auto legs = pmg::gco::LegModel::fromRobotConfig(robot);
    const std::vector<double> amplitudes = pmg::gco::defaultImpliedAmplitudes();
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(clips_dir))
      if (e.is_regular_file() && e.path().extension() == ".yaml" && e.path().filename() != pmg::kConsistencyMapFile)
        files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    int bad = 0;
    std::printf("%-22s %5s %8s | %28s | %28s\n", "clip", "K", "a_max", "v(a=1) vx vy w", "v(a_max) vx vy w");
    for (const std::string& f : files) {
      if (pmg::readClipKind(f) != pmg::ClipKind::kDynamic) continue;
      pmg::DynamicClip clip = pmg::readDynamicClip(f, robot);
      const pmg::ImpliedMotionTable t = pmg::gco::computeImpliedMotion(clip, js, legs, amplitudes);
      const Eigen::Index K = t.amplitude.size();
      const Eigen::Index one = std::min<Eigen::Index>(K - 1, 10);
      std::printf("%-22s %5ld %8.2f | %8.3f %8.3f %8.3f | %8.3f %8.3f %8.3f\n", clip.name.c_str(), static_cast<long>(K),
                  t.amplitude[K - 1], t.velocity(one, 0), t.velocity(one, 1), t.velocity(one, 2), t.velocity(K - 1, 0),
                  t.velocity(K - 1, 1), t.velocity(K - 1, 2));
      if (check) {
        const bool same = !clip.implied.empty() && clip.implied.amplitude.size() == K &&
                          (clip.implied.amplitude - t.amplitude).cwiseAbs().maxCoeff() <= 1e-9 &&
                          (clip.implied.velocity - t.velocity).cwiseAbs().maxCoeff() <= tolerance;
        if (!same) {
          std::fprintf(stderr, "%s: implied_motion is %s: run pmg_clip_implied --clips %s\n", f.c_str(),
                       clip.implied.empty() ? "missing" : "stale", clips_dir.c_str());
          ++bad;
        }
      } else {
        clip.implied = t;
        pmg::writeClip(clip, f);
      }
    }
    if (map && check && bad == 0) {
      const pmg::ClipLibrary lib = pmg::loadClipLibrary(clips_dir, robot);
      const pmg::ConsistencyMap m = pmg::gco::computeConsistencyMap(lib, robot);
      const bool same = !lib.consistency.empty() && lib.consistency.delta.rows() == m.delta.rows() &&
                        (lib.consistency.delta - m.delta).cwiseAbs().maxCoeff() <= 1e-4;
      for (std::size_t d = 0; same && d < pmg::kConsistencyMapDims; ++d)
        if (lib.consistency.grid[d].size() != m.grid[d].size() || (lib.consistency.grid[d] - m.grid[d]).cwiseAbs().maxCoeff() > 1e-6)
          ++bad;
      if (!same) ++bad;
      if (bad > 0)
        std::fprintf(stderr, "%s/%s is %s: run pmg_clip_implied --clips %s\n", clips_dir.c_str(), pmg::kConsistencyMapFile,
                     lib.consistency.empty() ? "missing" : "stale", clips_dir.c_str());
      else
        std::printf("%s: %ld grid points current\n", pmg::kConsistencyMapFile, static_cast<long>(m.delta.rows()));
    }
    if (map && !check) {
      const pmg::ClipLibrary lib = pmg::loadClipLibrary(files, robot);  // with the tables just written, no old map
      double worst = 0.0;
      const pmg::ConsistencyMap m = pmg::gco::computeConsistencyMap(lib, robot, {}, &worst);
      const std::string path = (fs::path(clips_dir) / pmg::kConsistencyMapFile).string();
      pmg::writeConsistencyMap(m, "written by pmg_clip_implied; worst residual after the fixed point and Gauss-Newton " + std::to_string(worst), path);
      std::printf("wrote %s: %ld grid points, largest |correction| %.3f, worst residual %.4f\n", path.c_str(),
                  static_cast<long>(m.delta.rows()), m.delta.cwiseAbs().maxCoeff(), worst);
    }
    if (bad > 0) return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_clip_implied: %s\n", e.what());
    return 2;
  }
  return 0;
}
