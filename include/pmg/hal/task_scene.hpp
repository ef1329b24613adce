#pragma once
/// @file task_scene.hpp
/// Task scenes for teleoperated tasks in the MuJoCo 2.2 SIL (issue 14, the paper's Table III:
/// wiping a table, carrying a box): tables and free objects composed with the robot's MJCF, their
/// per-trial randomisation, and the object poses an operator sees. Setup code: allocates and throws
/// pmg::ConfigError naming the file, line and key. Frames: W = the SIL's world (x forward from the
/// robot's start, y left, z up, origin on the floor under the pelvis at start); a table's frame T
/// = its top centre, yawed by the table's yaw. SI units (m, kg, rad).
///
/// Scene file (config/tasks/*.yaml):
/// ```yaml
/// tables:                          # static: a 4 cm top at `height` on four legs
///   - {name: table, top_size: [0.6, 1.6], height: 0.76, pos: [0.62, 0.0], yaw: 0.0, friction: 0.8}
/// objects:                         # free bodies resting on a table's top at the start
///   - name: towel
///     kind: towel                  # towel (a thin plate) | box
///     size: [0.30, 0.30, 0.006]    # full extents x, y, z [m]
///     mass: 0.12                   # [kg]
///     friction: 0.9                # sliding friction coefficient against the table and the hands
///     on: table                    # the table it rests on
///     pos: [-0.05, 0.45]           # its centre in the table frame T [m]
///     yaw: 0.0                     # about z, relative to the table [rad]
///     randomize: {x: [-0.12, 0.0], y: [0.30, 0.55], yaw: [-0.3, 0.3]}   # per trial, uniform (optional)
/// ```
/// Unknown keys are errors; sizes and masses > 0; friction in (0, 2]; an object's footprint (at its
/// nominal pose and at every corner of its randomisation ranges) must lie on its table's top.
/// The robot's own bodies are untouched; the scene's bodies are named "task_<name>".

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <mujoco/mujoco.h>

#include "pmg/common/robot_config.hpp"

namespace pmg {

/// A static table: a 4 cm top at `height` on four legs (room for a robot's knees and feet under it).
struct TaskTable {
  std::string name;
  std::array<double, 2> top_size{0.6, 1.2};  ///< top extents along its x and y [m], > 0
  double height = 0.76;                      ///< top surface above the floor [m], in (0.1, 1.5]
  std::array<double, 2> pos{0.6, 0.0};       ///< centre in W [m]
  double yaw = 0.0;                          ///< about z in W [rad]
  double friction = 0.8;                     ///< sliding friction of the top, (0, 2]
  template <class A>
  void Serialize(A* a);
  std::string validate() const;  ///< "" if valid, else "field = v: expected ..."
};

/// Per-trial randomisation of an object's pose on its table (uniform in each interval).
struct TaskRandomization {
  std::optional<std::array<double, 2>> x, y;  ///< centre in T [m]: [lo, hi]
  std::optional<std::array<double, 2>> yaw;   ///< relative to the table [rad]: [lo, hi]
  template <class A>
  void Serialize(A* a);
  std::string validate() const;
};

enum class TaskObjectKind { kTowel, kBox };

/// A free object resting on a table's top at the start.
struct TaskObject {
  std::string name;
  TaskObjectKind kind = TaskObjectKind::kBox;
  std::array<double, 3> size{0.3, 0.3, 0.2};  ///< full extents [m], > 0
  double mass = 1.0;                          ///< [kg], > 0
  double friction = 0.8;                      ///< (0, 2]
  std::string on;                             ///< the table's name
  std::array<double, 2> pos{0.0, 0.0};        ///< centre in the table frame T [m]
  double yaw = 0.0;                           ///< relative to the table [rad]
  std::optional<TaskRandomization> randomize;
  template <class A>
  void Serialize(A* a);
  std::string validate() const;
};

/// A task scene (see the file comment).
struct TaskScene {
  std::string source;  ///< the file it was read from ("" if built in code)
  std::vector<TaskTable> tables;
  std::vector<TaskObject> objects;
  /// Give the robot's rubber hands contact: a collision copy of each `*_rubber_hand` visual mesh
  /// (MuJoCo collides its convex hull; mass 0, friction 1.0). The public G1 MJCF renders the hands
  /// without contact, so the wrist links (0.13 m behind the finger tips) were all that touched an
  /// object. Off by default; both shipped task scenes turn it on.
  bool hand_collision = false;
  /// With hand_collision: the shape of each hand's collision geom. "mesh" (default): the visual
  /// mesh itself (MuJoCo collides its convex hull). MuJoCo 2.2's general convex collider (libccd,
  /// used for mesh-box pairs) returns ONE contact point per geom pair, so a box squeezed between two
  /// mesh hands touches at two points and pivots about the line through them, resisted only by
  /// torsional friction. "box": a pad, the box bounding the same mesh in its principal frame
  /// (about 0.05 x 0.12 x 0.15 m for the G1 rubber hand, its thin axis across the palm; taken from
  /// the compiled mesh, since MuJoCo's own primitive fitting gives the thinner equivalent-inertia
  /// box). Box-box pairs use MuJoCo's dedicated collider, which returns up to 8 points: a pad pressed
  /// flat on the box's side touches over a patch, as a rubber palm does, and resists the box turning
  /// in the grip. @throws ConfigError from robotWithTaskScene if the mesh cannot be compiled.
  std::string hand_collision_shape = "mesh";
  /// With hand_collision: the rubber hands' torsional friction coefficient [m], [0, 0.1] (MuJoCo's
  /// second friction coefficient, with condim 4). A rubber pad touches over a patch of a few
  /// centimetres and resists turning about the contact normal; MuJoCo's point contact (condim 3)
  /// does not, so a box squeezed between two hands pivots freely about the line through the two
  /// contacts. 0 (default): condim 3, MuJoCo's default torsional coefficient 0.005 unused.
  double hand_torsional_friction = 0.0;
  /// The wrist links' collision meshes (`*_wrist_roll_link`, `*_wrist_pitch_link`,
  /// `*_wrist_yaw_link`): torsional friction coefficient [m], [0, 0.1], with condim 4. 0 (default):
  /// the robot's own contact model (condim 3). The G1's wrist housings stand out beyond its rubber
  /// hands, so they are what squeezes a box; MuJoCo's point contact lets the box pivot freely about
  /// the line through the two housings' contacts, while a real housing pressed into cardboard
  /// touches over a patch. For a patch of radius a and friction mu the torque it resists is about
  /// (2/3) mu a N: 0.005 m (MuJoCo's default coefficient) is a = 1 cm at mu = 0.7.
  double wrist_torsional_friction = 0.0;
  /// The wrist links' collision geoms: "mesh" (default: the robot's own, MuJoCo colliding each
  /// link's convex hull, one contact point per geom pair through libccd) or "box": each of the six
  /// links (`*_wrist_{roll,pitch,yaw}_link`) collides as the box bounding its mesh in the mesh's
  /// principal frame (G1: about 0.056-0.103 x 0.054-0.060 x 0.057-0.060 m). A housing pressed
  /// into a cardboard side touches it along a strip, which resists the box turning about the
  /// contact normal; the box-box collider's several points model that strip, the single libccd
  /// point does not. The boxes overstate the round housings' width (their corners), and are made
  /// to collide with the scene's tables and objects only (contype/conaffinity 2; the scene's bodies
  /// get 3): the six boxes would otherwise touch each other. Works with wrist_torsional_friction.
  std::string wrist_collision_shape = "mesh";
  /// MuJoCo's `option/impratio` for the composed model, [1, 100]: the ratio of the frictional to the
  /// normal constraints' impedance. MuJoCo's default 1 lets an object held by friction creep out of a
  /// squeeze (soft friction constraints slide under a steady load); MuJoCo's documentation
  /// recommends a larger value with elliptic cones for grasping. It applies to every contact of the
  /// composed model, the feet's too. Default 1 (the robot's own model, no `<option>` written).
  double impratio = 1.0;
  /// MuJoCo's `option/cone`: "pyramidal" (MuJoCo's default, the model the policies were trained
  /// with) or "elliptic".
  std::string cone = "pyramidal";
  /// MuJoCo's `option/noslip_iterations` for the composed model, [0, 1000]: iterations of MuJoCo's
  /// no-slip solver, run after the main solver on the friction dimensions only. MuJoCo's soft
  /// friction constraints let a contact creep under a steady tangential load (and turn under a
  /// steady torque about the normal), which real static friction does not; the no-slip pass
  /// removes that creep. MuJoCo's documentation recommends it for grasping. It applies to every
  /// contact of the composed model. Default 0 (off, MuJoCo's default).
  int noslip_iterations = 0;
  template <class A>
  void Serialize(A* a);
  /// Cross-checks: unique names, `on` names a table, footprints on the top (nominal and at the
  /// randomisation's corners). @throws pmg::ConfigError naming the source, the object and the field.
  void check() const;
  const TaskTable& table(const std::string& name) const;    ///< @throws std::invalid_argument naming it
  const TaskObject& object(const std::string& name) const;  ///< @throws std::invalid_argument naming it
};

/// A point of table @p t's top frame T (x, y relative to the top's centre) in the world frame W [m].
Eigen::Vector2d tablePointInWorld(const TaskTable& t, const std::array<double, 2>& p_T);

/// Reads and checks a scene file. @throws pmg::ConfigError "<file>:<line>: <key>: <what>".
TaskScene loadTaskScene(const std::string& path);

/// The scene of trial @p seed: every object's randomised pose drawn (uniform, std::mt19937_64
/// seeded with @p seed; the same seed gives the same scene) and written into its pos / yaw; the
/// randomisation is then cleared. Objects without `randomize` keep their pose.
TaskScene drawTaskTrial(const TaskScene& scene, std::uint64_t seed);

/// The MJCF `<body>` elements of the scene (tables as static bodies: top and legs; objects with a free joint
/// that has no armature, damping or friction of its own), object centres at their start pose
/// resting on the top (1 mm above, to settle). Object poses use the nominal pos / yaw: draw a
/// trial first for randomised scenes. Every scene geom has contype = conaffinity = 3: it collides
/// with the robot's geoms (1), as MuJoCo's default would, and with wrist pads (2, see
/// TaskScene::wrist_collision_shape).
std::string taskSceneBodies(const TaskScene& scene);

/// The robot's MJCF with the scene's bodies added to its world, written to @p out_mjcf_path (a
/// model file of its own, so the shipped MJCF stays pristine; its meshdir is made absolute), and a
/// copy of @p robot that loads it (mjcf_path = @p out_mjcf_path). @throws pmg::ConfigError if the
/// file cannot be written or the robot MJCF has no world body.
RobotConfig robotWithTaskScene(const RobotConfig& robot, const TaskScene& scene, const std::string& out_mjcf_path);

/// An object's state as the simulator holds it (the truth: an operator's view adds noise and
/// latency on top).
struct TaskObjectState {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();           ///< centre [m]
  Eigen::Quaterniond q_W = Eigen::Quaterniond::Identity();  ///< orientation
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();           ///< linear velocity of the centre [m/s]
};

/// The state of object @p name ("task_<name>" in the model). @throws std::out_of_range if the
/// model has no such body.
TaskObjectState taskObjectState(const mjModel* model, const mjData* data, const std::string& name);

}  // namespace pmg
