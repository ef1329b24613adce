#include "pmg/render/scene_renderer.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "pmg/common/mujoco_model.hpp"
#include "pmg/render/gl_context.hpp"

namespace pmg::render {

namespace {

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// MuJoCo reports renderer failures through mju_error, whose default handler prints, waits for
// Enter and exits. While a guard (ScopedMujocoErrorHandler, pmg/common/mujoco_model.hpp) lives, such
// errors become RenderError exceptions instead.
void throwingMujocoError(const char* message) {
  throw RenderError(std::string("MuJoCo renderer: ") + (message ? message : "unknown error"));
}

}  // namespace

void TrackingCamera::validate() const {
  check(distance > 0.2 && distance <= 50.0, "camera.distance = " + std::to_string(distance) + ": expected in (0.2, 50] m");
  check(elevation_deg >= -89.0 && elevation_deg <= 89.0,
        "camera.elevation_deg = " + std::to_string(elevation_deg) + ": expected in [-89, 89] deg");
  check(azimuth_deg >= -360.0 && azimuth_deg <= 360.0,
        "camera.azimuth_deg = " + std::to_string(azimuth_deg) + ": expected in [-360, 360] deg");
  check(lookat_dz >= -2.0 && lookat_dz <= 2.0, "camera.lookat_dz = " + std::to_string(lookat_dz) + ": expected in [-2, 2] m");
}

void RenderOptions::validate() const {
  check(width >= 16 && width <= 4096, "width = " + std::to_string(width) + ": expected in [16, 4096] px");
  check(height >= 16 && height <= 4096, "height = " + std::to_string(height) + ": expected in [16, 4096] px");
  check(samples >= 0 && samples <= 16, "samples = " + std::to_string(samples) + ": expected in [0, 16]");
  check(font_scale == 50 || font_scale == 100 || font_scale == 150 || font_scale == 200 || font_scale == 250 ||
            font_scale == 300,
        "font_scale = " + std::to_string(font_scale) + ": expected one of 50, 100, 150, 200, 250, 300");
  check(shadow_size >= 256 && shadow_size <= 8192,
        "shadow_size = " + std::to_string(shadow_size) + ": expected in [256, 8192] px");
  check(p_WT.allFinite(), "p_WT (tether top): expected finite coordinates [m]");
  camera.validate();
}

SceneRenderer::SceneRenderer(MjModelPtr model, const RobotConfig& robot, const RenderOptions& options)
    : model_(std::move(model)), options_(options) {
  options_.validate();
  check(model_ != nullptr, "SceneRenderer: null model");
  mjModel* m = model_.get();
  const int base_body = mj_name2id(m, mjOBJ_BODY, robot.base_link.c_str());
  check(base_body > 0, robot.source_file + ": base_link '" + robot.base_link + "' is not a body of the MuJoCo model");
  const int base_joint = m->body_jntadr[base_body];
  check(base_joint >= 0 && m->jnt_type[base_joint] == mjJNT_FREE,
        robot.source_file + ": base_link '" + robot.base_link + "' has no free joint in the MuJoCo model");
  base_qpos_ = m->jnt_qposadr[base_joint];
  base_body_ = base_body;
  qpos_index_.reserve(robot.numJoints());
  for (const JointConfig& j : robot.joints) {
    const int id = mj_name2id(m, mjOBJ_JOINT, j.name.c_str());
    check(id >= 0, robot.source_file + ": joint '" + j.name + "' is not in the MuJoCo model " + robot.mjcf_path);
    check(m->jnt_type[id] == mjJNT_HINGE || m->jnt_type[id] == mjJNT_SLIDE,
          robot.source_file + ": joint '" + j.name + "' is not a hinge or slide joint in the MuJoCo model");
    qpos_index_.push_back(m->jnt_qposadr[id]);
  }

  m->vis.global.offwidth = options_.width;
  m->vis.global.offheight = options_.height;
  m->vis.quality.offsamples = options_.samples;
  m->vis.quality.shadowsize = options_.shadow_size;
  data_.reset(mj_makeData(m));
  if (!data_) throw RenderError("mj_makeData failed");

  mjv_defaultOption(&vis_options_);
  mjv_defaultCamera(&camera_);
  camera_.type = mjCAMERA_FREE;
  camera_.distance = options_.camera.distance;
  camera_.azimuth = options_.camera.azimuth_deg;
  camera_.elevation = options_.camera.elevation_deg;
  mjv_defaultScene(&scene_);
  mjr_defaultContext(&context_);

  if (!GlContext::isCurrent())
    throw RenderError("SceneRenderer: no OpenGL context is current on this thread (create a pmg::render::GlContext first)");
  const ScopedMujocoErrorHandler guard(throwingMujocoError);
  mjv_makeScene(m, &scene_, 4000);
  scene_.flags[mjRND_SHADOW] = options_.shadows ? 1 : 0;
  scene_.flags[mjRND_REFLECTION] = options_.reflections ? 1 : 0;
  try {
    mjr_makeContext(m, &context_, options_.font_scale);
  } catch (...) {
    mjr_freeContext(&context_);
    mjv_freeScene(&scene_);
    throw;
  }
  if (context_.offWidth < options_.width || context_.offHeight < options_.height) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "MuJoCo's offscreen buffer is %dx%d px, smaller than the requested %dx%d",
                  context_.offWidth, context_.offHeight, options_.width, options_.height);
    mjr_freeContext(&context_);
    mjv_freeScene(&scene_);
    throw RenderError(buf);
  }
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  buffer_.resize(3 * static_cast<std::size_t>(options_.width) * options_.height);
}

SceneRenderer::~SceneRenderer() {
  mjr_freeContext(&context_);
  mjv_freeScene(&scene_);
}

void SceneRenderer::setPose(const StateSample& sample) {
  if (sample.q.size() != static_cast<Eigen::Index>(qpos_index_.size()))
    throw std::invalid_argument("SceneRenderer::render: sample has " + std::to_string(sample.q.size()) +
                                " joint positions, the robot config has " + std::to_string(qpos_index_.size()));
  mjtNum* qpos = data_->qpos;
  for (int a = 0; a < 3; ++a) qpos[base_qpos_ + a] = sample.p_WB[a];
  for (int a = 0; a < 4; ++a) qpos[base_qpos_ + 3 + a] = sample.quat_WB[a];
  for (std::size_t i = 0; i < qpos_index_.size(); ++i) qpos[qpos_index_[i]] = sample.q[static_cast<Eigen::Index>(i)];
  for (const auto& [adr, pose] : free_bodies_)
    for (int a = 0; a < 7; ++a) qpos[adr + a] = pose[static_cast<std::size_t>(a)];
  mj_kinematics(model_.get(), data_.get());
  mj_comPos(model_.get(), data_.get());
  mj_camlight(model_.get(), data_.get());
}

void SceneRenderer::setFreeBodyPose(const std::string& body, const Eigen::Vector3d& p_W, const Eigen::Vector4d& quat_W) {
  const mjModel* m = model_.get();
  const int id = mj_name2id(m, mjOBJ_BODY, body.c_str());
  check(id > 0, "SceneRenderer::setFreeBodyPose: '" + body + "' is not a body of the MuJoCo model");
  check(id != base_body_, "SceneRenderer::setFreeBodyPose: '" + body + "' is the robot's base (its pose comes from the samples)");
  const int jnt = m->body_jntadr[id];
  check(jnt >= 0 && m->jnt_type[jnt] == mjJNT_FREE, "SceneRenderer::setFreeBodyPose: body '" + body + "' has no free joint");
  check(p_W.allFinite() && quat_W.allFinite() && std::abs(quat_W.norm() - 1.0) < 1e-3,
        "SceneRenderer::setFreeBodyPose: body '" + body + "': position must be finite and the quaternion unit (w x y z)");
  std::array<double, 7> pose{p_W.x(), p_W.y(), p_W.z(), quat_W[0], quat_W[1], quat_W[2], quat_W[3]};
  const int adr = m->jnt_qposadr[jnt];
  for (auto& fb : free_bodies_)
    if (fb.first == adr) {
      fb.second = pose;
      return;
    }
  free_bodies_.emplace_back(adr, pose);
}

void SceneRenderer::addTether() {
  mjvGeom* g = scene_.geoms + scene_.ngeom;
  const float rgba[4] = {0.15f, 0.15f, 0.15f, 1.0f};
  mjv_initGeom(g, mjGEOM_CAPSULE, nullptr, nullptr, nullptr, rgba);
  g->category = mjCAT_DECOR;
  const mjtNum* p_WP = data_->xpos + 3 * base_body_;
  mjv_makeConnector(g, mjGEOM_CAPSULE, 0.006, options_.p_WT[0], options_.p_WT[1], options_.p_WT[2], p_WP[0], p_WP[1],
                    p_WP[2]);
  ++scene_.ngeom;
}

void SceneRenderer::render(const StateSample& sample, Image& out) {
  if (!options_.show_labels) {
    render(sample, "", "", out);
    return;
  }
  char right[160];
  std::snprintf(right, sizeof(right), "%.2f s\n%.2f\n%+.2f m/s\n%+.2f m/s\n%+.2f rad/s", sample.t, sample.phase,
                sample.command[0], sample.command[1], sample.command[2]);
  render(sample, "t\nphase\nvx\nvy\nwz", right, out);
}

void SceneRenderer::render(const StateSample& sample, const std::string& label_left, const std::string& label_right,
                           Image& out) {
  setPose(sample);
  for (int a = 0; a < 3; ++a) camera_.lookat[a] = sample.p_WB[a];
  camera_.lookat[2] += options_.camera.lookat_dz;
  const mjrRect viewport{0, 0, options_.width, options_.height};
  const ScopedMujocoErrorHandler guard(throwingMujocoError);
  mjv_updateScene(model_.get(), data_.get(), &vis_options_, nullptr, &camera_, mjCAT_ALL, &scene_);
  if (options_.tether && scene_.ngeom < scene_.maxgeom) addTether();
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  mjr_render(viewport, &scene_, &context_);
  if (!label_left.empty() || !label_right.empty())
    mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, viewport, label_left.c_str(), label_right.c_str(), &context_);
  mjr_readPixels(buffer_.data(), nullptr, viewport, &context_);
  if (out.width != options_.width || out.height != options_.height) out = Image(options_.width, options_.height);
  // mjr_readPixels returns rows bottom to top (OpenGL); Image rows run top to bottom.
  const std::size_t row = 3 * static_cast<std::size_t>(options_.width);
  for (int y = 0; y < options_.height; ++y)
    std::memcpy(out.rgb.data() + row * static_cast<std::size_t>(y),
                buffer_.data() + row * static_cast<std::size_t>(options_.height - 1 - y), row);
}

}  // namespace pmg::render
