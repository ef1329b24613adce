#pragma once
/// @file scene_renderer.hpp
/// Renders recorded robot poses (StateSample) with MuJoCo 2.2's renderer into RGB images:
/// the pose is written into qpos, forward kinematics (mj_kinematics, mj_comPos, mj_camlight) places
/// the bodies, mjv_updateScene/mjr_render draw the scene into the offscreen framebuffer
/// (mjFB_OFFSCREEN) and mjr_readPixels reads it back. The camera follows the pelvis.
/// Offline tool code, not a real-time path: the constructor and render() may allocate and throw.

#include <array>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/render/image.hpp"
#include "pmg/render/state_track.hpp"

namespace pmg::render {

/// A camera that tracks the pelvis: it looks at p_WB + (0, 0, lookat_dz) from @p distance away,
/// in the world-frame direction given by azimuth/elevation (MuJoCo's free-camera convention:
/// the camera sits at lookat − distance · (cos az cos el, sin az cos el, sin el)). It follows the
/// pelvis position only, not its yaw, so a turning robot is seen turning.
struct TrackingCamera {
  double distance = 3.0;        ///< camera to look-at point [m], in (0.2, 50]
  double azimuth_deg = 130.0;   ///< [deg]; 90 = robot's right side (camera at −y), 180 = front (camera at +x); 130: right front quarter
  double elevation_deg = -10.0; ///< [deg], in [−89, 89]; negative = camera above the look-at point
  double lookat_dz = -0.25;     ///< look-at point height relative to the pelvis [m] (−0.25: mid-body)
  /// @throws std::invalid_argument naming the field and its range.
  void validate() const;
};

/// Options of SceneRenderer.
struct RenderOptions {
  int width = 480;             ///< frame width [px], in [16, 4096]
  int height = 640;            ///< frame height [px], in [16, 4096]
  int samples = 4;             ///< multisampling of the offscreen buffer, in [0, 16]
  int font_scale = 150;        ///< overlay font scale: one of 50, 100, 150, 200, 250, 300 [%]
  bool show_labels = true;     ///< draw the time/command label in the top-left corner
  bool shadows = true;         ///< shadow mapping (one extra scene pass per light that casts shadows)
  bool reflections = true;     ///< floor reflection (one extra scene pass)
  int shadow_size = 2048;      ///< shadow map size [px], in [256, 8192] (MuJoCo's default 4096)
  /// Draw a rope (dark capsule, 12 mm) from p_WT down to the pelvis origin, to picture the SIL's
  /// virtual gantry (which is a spring-damper on the pelvis, not a modelled rope).
  bool tether = false;
  Eigen::Vector3d p_WT{0.0, 0.0, 2.5};  ///< upper end of the rope in the world frame W [m], finite
  TrackingCamera camera;
  /// @throws std::invalid_argument naming the field and its range.
  void validate() const;
};

/// Renders poses of one robot. Needs a current GlContext on the calling thread for its whole life.
class SceneRenderer {
 public:
  /// @param model the robot's MuJoCo model (pmg::loadMujocoModel(robot.mjcf_path)); its offscreen
  ///   buffer size is set to the frame size. @param robot joint order of the samples and the base
  ///   body (robot.base_link). @throws std::invalid_argument on bad options or a model that does not
  ///   match the config (no free base joint, a config joint missing from the model);
  ///   RenderError if no GL context is current or MuJoCo cannot make its renderer context.
  SceneRenderer(MjModelPtr model, const RobotConfig& robot, const RenderOptions& options);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  /// Renders @p sample into @p out (resized to width × height on first use). With labels on, the
  /// top-left corner shows t [s], the gait phase and the command (vx, vy [m/s], wz [rad/s]).
  void render(const StateSample& sample, Image& out);

  /// Renders with the label text given explicitly (left and right column, lines separated by
  /// '\n'; empty = no label).
  void render(const StateSample& sample, const std::string& label_left, const std::string& label_right,
              Image& out);

  /// Places a free body of the model other than the robot (a task scene's towel or box) for the
  /// following render() calls: @p p_W its position [m] and @p quat_W its orientation (w x y z, unit)
  /// in the world frame W. Until first set, a body stays at the model's qpos0.
  /// @throws std::invalid_argument if @p body is not a body of the model with a free joint, is the
  ///   robot's base, or the pose is not finite.
  void setFreeBodyPose(const std::string& body, const Eigen::Vector3d& p_W, const Eigen::Vector4d& quat_W);

  const RenderOptions& options() const { return options_; }
  const mjModel& model() const { return *model_; }

 private:
  void setPose(const StateSample& sample);
  void addTether();

  MjModelPtr model_;
  MjDataPtr data_;
  RenderOptions options_;
  std::vector<int> qpos_index_;  // qpos address of each config joint
  int base_qpos_ = 0;            // qpos address of the free joint (position, then w x y z)
  int base_body_ = 0;            // body id of the base link
  mjvScene scene_{};
  mjvCamera camera_{};
  mjvOption vis_options_{};
  mjrContext context_{};
  std::vector<unsigned char> buffer_;  // bottom-up rows from mjr_readPixels
  std::vector<std::pair<int, std::array<double, 7>>> free_bodies_;  // (qpos address, x y z w x y z) set by setFreeBodyPose
};

}  // namespace pmg::render
