// pmg_render_log: renders a pmg_controller run from its LCM event log (PMG_STATE telemetry) with
// MuJoCo 2.2's renderer and writes PNG files:
//   <out-dir>/strip.png             N frames side by side, each labelled with t and the command;
//   <out-dir>/frames/frame_NNNNN.png with --video-fps F: numbered frames at F frames per second
//                                    (ffmpeg -framerate F -i frame_%05d.png run.mp4).
//
//   pmg_render_log --log out/sil_demo/run.lcmlog --out-dir out/sil_demo/render --frames 8
// Needs an X display with OpenGL (Xvfb + Mesa on machines without a screen; scripts/render_sil.sh
// starts one). Exit status: 0 done, 1 bad input, 3 no OpenGL context / renderer failure.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/render/gl_context.hpp"
#include "pmg/render/image.hpp"
#include "pmg/render/object_track.hpp"
#include "pmg/render/scene_renderer.hpp"
#include "pmg/render/state_track.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmg_render_log: render a pmg_controller LCM event log (PMG_STATE) to PNG frames"};
  std::string log_path, out_dir, robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  std::string channel = "PMG_STATE";
  std::string strip_name = "strip.png";
  int frames = 6;
  double t0 = 0.0, t1 = 0.0, video_fps = 0.0;
  pmg::render::RenderOptions options;
  options.width = 360;
  options.height = 560;
  options.font_scale = 100;
  bool one_cycle = false;
  bool no_labels = false, no_shadows = false, no_reflections = false;
  app.add_option("--log", log_path, "LCM event log written by pmg_controller --log")->required()->check(CLI::ExistingFile);
  app.add_option("--out-dir", out_dir, "output folder (created)")->required();
  app.add_option("--robot", robot_path, "robot config (joint order, base link, MJCF)")->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--channel", channel, "telemetry channel")->capture_default_str();
  app.add_option("--frames", frames, "frames in the strip, evenly spaced over [t0, t1]")
      ->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--strip", strip_name, "strip file name inside --out-dir")->capture_default_str();
  CLI::Option* t0_option = app.add_option("--t0", t0, "first time shown [s] (default: start of the log)");
  CLI::Option* t1_option = app.add_option("--t1", t1, "last time shown [s] (default: end of the log)");
  app.add_flag("--one-cycle", one_cycle,
               "spread the strip's frames over one gait period from --t0 (the log's period there), last frame "
               "one step before the cycle closes");
  app.add_option("--video-fps", video_fps, "also write numbered frames at this rate to <out-dir>/frames (0: off)")
      ->check(CLI::Range(0.0, 240.0))->capture_default_str();
  app.add_option("--width", options.width, "frame width [px]")->capture_default_str();
  app.add_option("--height", options.height, "frame height [px]")->capture_default_str();
  app.add_option("--azimuth", options.camera.azimuth_deg, "camera azimuth [deg] (90 right side, 180 front)")
      ->capture_default_str();
  app.add_option("--elevation", options.camera.elevation_deg, "camera elevation [deg] (negative: from above)")
      ->capture_default_str();
  app.add_option("--distance", options.camera.distance, "camera distance to the look-at point [m]")
      ->capture_default_str();
  app.add_option("--lookat-dz", options.camera.lookat_dz, "look-at point height relative to the pelvis [m]")
      ->capture_default_str();
  app.add_option("--samples", options.samples, "multisampling (anti-aliasing) samples")->capture_default_str();
  std::vector<double> tether;
  app.add_option("--tether", tether, "draw a rope from this world point X Y Z [m] to the pelvis (the SIL gantry)")
      ->expected(3);
  app.add_option("--font-scale", options.font_scale, "label font scale [%]: 50, 100, 150, 200, 250 or 300")
      ->capture_default_str();
  app.add_option("--shadow-size", options.shadow_size, "shadow map size [px]")->capture_default_str();
  std::string mjcf_path, objects_path;
  app.add_option("--mjcf", mjcf_path, "draw this MuJoCo model instead of the robot config's (a task scene that "
                                      "composes the robot: pmg_teleop_bench's trial_<k>_scene.xml)")
      ->check(CLI::ExistingFile);
  app.add_option("--objects", objects_path, "object track CSV (t,body,x,y,z,qw,qx,qy,qz; W frame): poses of the "
                                            "model's free objects, zero-order hold (include/pmg/render/object_track.hpp)")
      ->check(CLI::ExistingFile);
  app.add_flag("--no-labels", no_labels, "no time/command label on the frames");
  app.add_flag("--no-shadows", no_shadows, "no shadows (faster on software OpenGL)");
  app.add_flag("--no-reflections", no_reflections, "no floor reflection (faster on software OpenGL)");
  CLI11_PARSE(app, argc, argv);
  options.show_labels = !no_labels;
  options.shadows = !no_shadows;
  options.reflections = !no_reflections;
  if (tether.size() == 3) {
    options.tether = true;
    options.p_WT = Eigen::Vector3d(tether[0], tether[1], tether[2]);
  }

  try {
    options.validate();
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    const pmg::render::StateTrack track =
        pmg::render::readStateTrack(log_path, static_cast<int>(robot.numJoints()), channel);
    const double start = t0_option->count() > 0 ? t0 : track.startTime();
    double end = t1_option->count() > 0 ? t1 : track.endTime();
    if (one_cycle) {
      const double period = track.at(start).period;
      if (!(period > 0.0))
        throw std::invalid_argument("--one-cycle: the log's gait period at t = " + std::to_string(start) +
                                    " s is " + std::to_string(period) + " s, expected > 0 (is the PMG generator running?)");
      end = std::min(start + period * (frames - 1) / frames, track.endTime());
    }
    if (start > track.endTime() || end < track.startTime() || !(end >= start)) {
      char buf[200];
      std::snprintf(buf, sizeof(buf), "[--t0, --t1] = [%.3f, %.3f] s: expected t0 <= t1 inside the log's span [%.3f, %.3f] s",
                    start, end, track.startTime(), track.endTime());
      throw std::invalid_argument(buf);
    }
    pmg::render::ObjectTrack objects;
    if (!objects_path.empty()) objects = pmg::render::readObjectTrack(objects_path);
    fs::create_directories(out_dir);

    const auto gl = pmg::render::GlContext::create();
    pmg::render::SceneRenderer renderer(pmg::loadMujocoModel(mjcf_path.empty() ? robot.mjcf_path : mjcf_path), robot, options);
    // Places the objects at time t (before each render; an unknown body fails here, naming it).
    auto placeObjects = [&](double t) {
      for (const auto& [body, poses] : objects.bodies) {
        const pmg::render::ObjectPose& p = objects.at(body, t);
        try {
          renderer.setFreeBodyPose(body, p.p_W, p.quat_W);
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument(objects_path + ": " + e.what());
        }
      }
    };
    std::printf("pmg_render_log: %s: %zu %s samples, t = %.2f..%.2f s; OpenGL %s (%s)\n", log_path.c_str(),
                track.samples.size(), channel.c_str(), track.startTime(), track.endTime(), gl->version().c_str(),
                gl->renderer().c_str());

    // The first frame also uploads meshes and textures; its time is reported on its own.
    auto t_render = Clock::now();
    std::vector<pmg::render::Image> images(static_cast<std::size_t>(frames));
    const std::vector<double> times = pmg::render::evenlySpacedTimes(start, end, frames);
    double first_s = 0.0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      placeObjects(times[i]);
      renderer.render(track.at(times[i]), images[i]);
      if (i == 0) {
        first_s = secondsSince(t_render);
        t_render = Clock::now();
      }
    }
    const double rest_s = secondsSince(t_render);
    const auto t_png = Clock::now();
    const std::uint8_t white[3] = {255, 255, 255};
    const std::string strip_path = (fs::path(out_dir) / strip_name).string();
    pmg::render::writePng(strip_path, pmg::render::hstack(images, 4, white));
    std::printf("strip: %d frames %dx%d px, t = %.2f..%.2f s -> %s\n", frames, options.width, options.height, start,
                end, strip_path.c_str());
    std::printf("  render: first frame %.0f ms, then %.0f ms/frame; PNG %.0f ms\n", 1e3 * first_s,
                frames > 1 ? 1e3 * rest_s / (frames - 1) : 0.0, 1e3 * secondsSince(t_png));

    if (video_fps > 0.0) {
      const fs::path frames_dir = fs::path(out_dir) / "frames";
      fs::create_directories(frames_dir);
      const int count = 1 + static_cast<int>((end - start) * video_fps + 1e-9);
      pmg::render::Image image;
      char name[32];
      double render_s = 0.0, png_s = 0.0;
      for (int k = 0; k < count; ++k) {
        const auto t_frame = Clock::now();
        placeObjects(start + k / video_fps);
        renderer.render(track.at(start + k / video_fps), image);
        const auto t_write = Clock::now();
        render_s += std::chrono::duration<double>(t_write - t_frame).count();
        std::snprintf(name, sizeof(name), "frame_%05d.png", k);
        pmg::render::writePng((frames_dir / name).string(), image);
        png_s += secondsSince(t_write);
      }
      std::printf("frames: %d at %g fps -> %s/frame_%%05d.png\n", count, video_fps, frames_dir.c_str());
      std::printf("  render %.0f ms/frame, PNG %.0f ms/frame\n", 1e3 * render_s / count, 1e3 * png_s / count);
    }
    return 0;
  } catch (const pmg::render::RenderError& e) {
    std::fprintf(stderr, "pmg_render_log: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_render_log: %s\n", e.what());
    return 1;
  }
}
