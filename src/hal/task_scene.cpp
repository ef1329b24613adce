#include "pmg/hal/task_scene.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "pmg/common/config_error.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/yaml_archive.hpp"

namespace pmg {
namespace fs = std::filesystem;

std::vector<std::pair<std::string, TaskObjectKind>> yamlEnumNames(TaskObjectKind) {
  return {{"towel", TaskObjectKind::kTowel}, {"box", TaskObjectKind::kBox}};
}

namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool frictionOk(double v) { return std::isfinite(v) && v > 0.0 && v <= 2.0; }

std::string interval(const char* key, const std::optional<std::array<double, 2>>& r) {
  if (r && !((*r)[0] <= (*r)[1])) return fmt::format("{} = [{}, {}]: expected [lo, hi] with lo <= hi", key, (*r)[0], (*r)[1]);
  return "";
}


/// Replaces each named mesh geom of @p xml by a pad: the box bounding its compiled mesh in the
/// mesh's principal frame (where MuJoCo puts the compiled vertices and the geom's pose). MuJoCo's
/// own fitting of a primitive to a mesh gives the equivalent-inertia box (too thin: 0.029 m where
/// the rubber hand's vertices span 0.045 m), and 2.2's `fitaabb` mislocates the box's centre, so the
/// bounds are taken from the compiled mesh of one probe model for all @p pads. Each pad keeps its
/// geom's other attributes, gets the pad's extra attributes, and sits in geom group 3, which MuJoCo
/// does not draw by default (renders show the meshes). @throws ConfigError naming the scene key if
/// the probe does not compile or a geom has no compiled mesh.
struct PadSpec {
  std::string geom;         ///< the mesh geom's name
  std::string extra_attrs;  ///< e.g. contype/conaffinity; "" for none
  std::string key;          ///< the scene key that asked for it (for errors)
};
std::string withBoundingBoxPads(std::string xml, const std::vector<PadSpec>& pads, const std::string& robot_mjcf,
                                const std::string& out_mjcf_path) {
  const std::string probe = out_mjcf_path + ".pads.xml";
  {
    std::ofstream out(probe);
    if (!out) throw ConfigError(probe + ": cannot write the pads' probe MJCF");
    out << xml;
  }
  MjModelPtr m;
  try {
    m = loadMujocoModel(probe);
  } catch (const std::runtime_error& e) {
    fs::remove(probe);
    throw ConfigError(robot_mjcf + ": " + pads.front().key + ": box: " + e.what());
  }
  fs::remove(probe);
  for (const PadSpec& spec : pads) {
    const std::string& name = spec.geom;
    const std::string& extra_attrs = spec.extra_attrs;
    const int g = mj_name2id(m.get(), mjOBJ_GEOM, name.c_str());
    const int mesh = g < 0 ? -1 : m->geom_dataid[g];
    if (mesh < 0) throw ConfigError(robot_mjcf + ": " + spec.key + ": no compiled mesh for " + name);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
    for (int v = 0; v < m->mesh_vertnum[mesh]; ++v) {
      const float* p = m->mesh_vert + 3 * (m->mesh_vertadr[mesh] + v);
      const Eigen::Vector3d q(p[0], p[1], p[2]);
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
    const Eigen::Quaterniond q_BG(m->geom_quat[4 * g], m->geom_quat[4 * g + 1], m->geom_quat[4 * g + 2], m->geom_quat[4 * g + 3]);
    const Eigen::Vector3d c_B =
        Eigen::Vector3d(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]) + q_BG * (0.5 * (lo + hi));
    const Eigen::Vector3d h = 0.5 * (hi - lo);
    const auto open = xml.rfind("<geom", xml.find("name=\"" + name + "\""));
    const auto close = xml.find("/>", open);
    std::string geom = xml.substr(open + 5, close - open - 5);
    for (const char* attr : {"type", "mesh", "rgba", "group", "pos", "quat"}) {  // replaced below
      const auto a = geom.find(std::string(" ") + attr + "=\"");
      if (a != std::string::npos) geom.erase(a, geom.find('"', geom.find('"', a) + 1) + 1 - a);
    }
    const std::string pad = fmt::format(
        "<geom{} {}{}type=\"box\" pos=\"{:.6f} {:.6f} {:.6f}\" quat=\"{:.6f} {:.6f} {:.6f} {:.6f}\" "
        "size=\"{:.6f} {:.6f} {:.6f}\" group=\"3\" rgba=\"0.7 0.7 0.7 1\"/>",
        geom, extra_attrs, extra_attrs.empty() ? "" : " ", c_B.x(), c_B.y(), c_B.z(), q_BG.w(), q_BG.x(), q_BG.y(),
        q_BG.z(), h.x(), h.y(), h.z());
    xml.replace(open, close + 2 - open, pad);
  }
  return xml;
}
}  // namespace

template <class A>
void TaskTable::Serialize(A* a) {
  a->Visit("name", &name, "table name", yaml::kRequired);
  a->Visit("top_size", &top_size, "top extents x, y [m]", yaml::kRequired);
  a->Visit("height", &height, "top surface above the floor [m]", yaml::kRequired);
  a->Visit("pos", &pos, "centre in the world frame [m]", yaml::kRequired);
  a->Visit("yaw", &yaw, "about z [rad]");
  a->Visit("friction", &friction, "sliding friction of the top");
}

std::string TaskTable::validate() const {
  if (!positive(top_size[0]) || !positive(top_size[1]))
    return fmt::format("top_size = [{}, {}]: expected extents > 0 m", top_size[0], top_size[1]);
  if (!(height > 0.1 && height <= 1.5)) return fmt::format("height = {}: expected (0.1, 1.5] m", height);
  if (!frictionOk(friction)) return fmt::format("friction = {}: expected (0, 2]", friction);
  return "";
}

template <class A>
void TaskRandomization::Serialize(A* a) {
  a->Visit("x", &x, "centre x in the table frame [m]: [lo, hi]");
  a->Visit("y", &y, "centre y in the table frame [m]: [lo, hi]");
  a->Visit("yaw", &yaw, "yaw relative to the table [rad]: [lo, hi]");
}

std::string TaskRandomization::validate() const {
  for (const auto& [k, r] : {std::pair{"x", x}, std::pair{"y", y}, std::pair{"yaw", yaw}})
    if (std::string e = interval(k, r); !e.empty()) return e;
  return "";
}

template <class A>
void TaskObject::Serialize(A* a) {
  a->Visit("name", &name, "object name", yaml::kRequired);
  a->Visit("kind", &kind, "towel | box", yaml::kRequired);
  a->Visit("size", &size, "full extents x, y, z [m]", yaml::kRequired);
  a->Visit("mass", &mass, "[kg]", yaml::kRequired);
  a->Visit("friction", &friction, "sliding friction coefficient");
  a->Visit("on", &on, "the table it rests on", yaml::kRequired);
  a->Visit("pos", &pos, "centre in the table frame [m]");
  a->Visit("yaw", &yaw, "relative to the table [rad]");
  a->Visit("randomize", &randomize, "per-trial pose ranges");
}

std::string TaskObject::validate() const {
  if (!positive(size[0]) || !positive(size[1]) || !positive(size[2]))
    return fmt::format("size = [{}, {}, {}]: expected extents > 0 m", size[0], size[1], size[2]);
  if (!positive(mass)) return fmt::format("mass = {}: expected > 0 kg", mass);
  if (!frictionOk(friction)) return fmt::format("friction = {}: expected (0, 2]", friction);
  return "";
}

template <class A>
void TaskScene::Serialize(A* a) {
  a->Visit("tables", &tables, "static tables", yaml::kRequired);
  a->Visit("objects", &objects, "free objects on the tables", yaml::kRequired);
  a->Visit("hand_collision", &hand_collision, "the robot's rubber hands get collision geoms (true | false)");
  a->Visit("hand_collision_shape", &hand_collision_shape, "the rubber hands' collision geoms: mesh | box");
  a->Visit("hand_torsional_friction", &hand_torsional_friction, "the rubber hands' torsional friction [m], [0, 0.1]");
  a->Visit("wrist_torsional_friction", &wrist_torsional_friction, "the wrist links' torsional friction [m], [0, 0.1]");
  a->Visit("wrist_collision_shape", &wrist_collision_shape, "the wrist links' collision geoms: mesh | box");
  a->Visit("impratio", &impratio, "MuJoCo option/impratio, [1, 100]");
  a->Visit("cone", &cone, "MuJoCo option/cone: pyramidal | elliptic");
  a->Visit("noslip_iterations", &noslip_iterations, "MuJoCo option/noslip_iterations, [0, 1000]");
}

const TaskTable& TaskScene::table(const std::string& name) const {
  for (const auto& t : tables)
    if (t.name == name) return t;
  throw std::invalid_argument("no table '" + name + "' in the task scene");
}

const TaskObject& TaskScene::object(const std::string& name) const {
  for (const auto& o : objects)
    if (o.name == name) return o;
  throw std::invalid_argument("no object '" + name + "' in the task scene");
}

Eigen::Vector2d tablePointInWorld(const TaskTable& t, const std::array<double, 2>& p_T) {
  const double c = std::cos(t.yaw), s = std::sin(t.yaw);
  return {t.pos[0] + c * p_T[0] - s * p_T[1], t.pos[1] + s * p_T[0] + c * p_T[1]};
}

void TaskScene::check() const {
  const std::string where = source.empty() ? std::string("task scene") : source;
  if (!(hand_torsional_friction >= 0.0 && hand_torsional_friction <= 0.1))
    throw ConfigError(fmt::format("{}: hand_torsional_friction = {}: expected [0, 0.1] m", where, hand_torsional_friction));
  if (hand_torsional_friction > 0.0 && !hand_collision)
    throw ConfigError(fmt::format("{}: hand_torsional_friction needs hand_collision: true", where));
  if (!(wrist_torsional_friction >= 0.0 && wrist_torsional_friction <= 0.1))
    throw ConfigError(fmt::format("{}: wrist_torsional_friction = {}: expected [0, 0.1] m", where, wrist_torsional_friction));
  if (hand_collision_shape != "mesh" && hand_collision_shape != "box")
    throw ConfigError(fmt::format("{}: hand_collision_shape = '{}': expected mesh | box", where, hand_collision_shape));
  if (wrist_collision_shape != "mesh" && wrist_collision_shape != "box")
    throw ConfigError(fmt::format("{}: wrist_collision_shape = '{}': expected mesh | box", where, wrist_collision_shape));
  if (hand_collision_shape != "mesh" && !hand_collision)
    throw ConfigError(fmt::format("{}: hand_collision_shape needs hand_collision: true", where));
  if (!(impratio >= 1.0 && impratio <= 100.0)) throw ConfigError(fmt::format("{}: impratio = {}: expected [1, 100]", where, impratio));
  if (!(noslip_iterations >= 0 && noslip_iterations <= 1000))
    throw ConfigError(fmt::format("{}: noslip_iterations = {}: expected [0, 1000]", where, noslip_iterations));
  if (cone != "pyramidal" && cone != "elliptic")
    throw ConfigError(fmt::format("{}: cone = '{}': expected pyramidal | elliptic", where, cone));
  std::set<std::string> names;
  for (const auto& t : tables)
    if (!names.insert(t.name).second) throw ConfigError(fmt::format("{}: tables.{}: the name is used twice", where, t.name));
  for (const auto& o : objects) {
    if (!names.insert(o.name).second) throw ConfigError(fmt::format("{}: objects.{}: the name is used twice", where, o.name));
    const TaskTable* t = nullptr;
    for (const auto& c : tables)
      if (c.name == o.on) t = &c;
    if (!t) throw ConfigError(fmt::format("{}: objects.{}.on = '{}': no table of that name", where, o.name, o.on));
    // The footprint's corners must lie on the top, at the nominal pose and at every corner of the
    // randomisation's ranges.
    std::vector<std::array<double, 3>> poses{{o.pos[0], o.pos[1], o.yaw}};
    if (o.randomize) {
      const auto& r = *o.randomize;
      const std::array<double, 2> xs = r.x.value_or(std::array<double, 2>{o.pos[0], o.pos[0]});
      const std::array<double, 2> ys = r.y.value_or(std::array<double, 2>{o.pos[1], o.pos[1]});
      const std::array<double, 2> yaws = r.yaw.value_or(std::array<double, 2>{o.yaw, o.yaw});
      for (double x : xs)
        for (double y : ys)
          for (double yaw : yaws) poses.push_back({x, y, yaw});
    }
    for (const auto& [x, y, yaw] : poses)
      for (double sx : {-0.5, 0.5})
        for (double sy : {-0.5, 0.5}) {
          const double cx = x + std::cos(yaw) * sx * o.size[0] - std::sin(yaw) * sy * o.size[1];
          const double cy = y + std::sin(yaw) * sx * o.size[0] + std::cos(yaw) * sy * o.size[1];
          if (std::abs(cx) > 0.5 * t->top_size[0] + 1e-9 || std::abs(cy) > 0.5 * t->top_size[1] + 1e-9)
            throw ConfigError(fmt::format(
                "{}: objects.{}: at pos [{:.3f}, {:.3f}], yaw {:.3f} (nominal or a corner of `randomize`) a corner "
                "({:.3f}, {:.3f}) is off the top of table '{}' (expected |x| <= {:.3f}, |y| <= {:.3f} m in its frame)",
                where, o.name, x, y, yaw, cx, cy, t->name, 0.5 * t->top_size[0], 0.5 * t->top_size[1]));
        }
  }
}

TaskScene loadTaskScene(const std::string& path) {
  TaskScene s = yaml::loadYamlFile<TaskScene>(path);
  s.source = path;
  s.check();
  return s;
}

TaskScene drawTaskTrial(const TaskScene& scene, std::uint64_t seed) {
  TaskScene s = scene;
  std::mt19937_64 rng(seed);
  auto draw = [&](const std::optional<std::array<double, 2>>& r, double nominal) {
    if (!r) return nominal;
    return std::uniform_real_distribution<double>((*r)[0], (*r)[1])(rng);
  };
  for (auto& o : s.objects) {
    if (!o.randomize) continue;
    o.pos[0] = draw(o.randomize->x, o.pos[0]);
    o.pos[1] = draw(o.randomize->y, o.pos[1]);
    o.yaw = draw(o.randomize->yaw, o.yaw);
    o.randomize.reset();
  }
  return s;
}

std::string taskSceneBodies(const TaskScene& scene) {
  std::ostringstream x;
  x.precision(9);
  for (const auto& t : scene.tables) {
    // A 4 cm top on four 4 cm legs inset 3 cm from the corners (a robot can stand with its knees
    // and feet under the top, as at a real table). Body origin: the top's surface centre.
    const double top = 0.02, leg_h = 0.5 * (t.height - 2.0 * top);
    const double lx = 0.5 * t.top_size[0] - 0.05, ly = 0.5 * t.top_size[1] - 0.05;
    x << "    <body name=\"task_" << t.name << "\" pos=\"" << t.pos[0] << " " << t.pos[1] << " " << t.height
      << "\" euler=\"0 0 " << t.yaw << "\">\n"
      << "      <geom name=\"task_" << t.name << "_geom\" contype=\"3\" conaffinity=\"3\" type=\"box\" pos=\"0 0 " << -top << "\" size=\""
      << 0.5 * t.top_size[0] << " " << 0.5 * t.top_size[1] << " " << top << "\" friction=\"" << t.friction
      << " 0.005 0.0001\" rgba=\"0.55 0.42 0.3 1\"/>\n";
    int leg = 0;
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        x << "      <geom name=\"task_" << t.name << "_leg" << leg++ << "\" contype=\"3\" conaffinity=\"3\" type=\"box\" pos=\"" << sx * lx << " "
          << sy * ly << " " << -(2.0 * top + leg_h) << "\" size=\"0.02 0.02 " << leg_h
          << "\" rgba=\"0.45 0.34 0.24 1\"/>\n";
    x << "    </body>\n";
  }
  for (const auto& o : scene.objects) {
    const TaskTable& t = scene.table(o.on);
    const Eigen::Vector2d p_W = tablePointInWorld(t, o.pos);
    const double xw = p_W.x(), yw = p_W.y();
    const double zw = t.height + 0.5 * o.size[2] + 0.001;
    const char* rgba = o.kind == TaskObjectKind::kTowel ? "0.2 0.45 0.8 1" : "0.8 0.6 0.3 1";
    x << "    <body name=\"task_" << o.name << "\" pos=\"" << xw << " " << yw << " " << zw << "\" euler=\"0 0 "
      << t.yaw + o.yaw << "\">\n"
      << "      <joint name=\"task_" << o.name << "_free\" type=\"free\" armature=\"0\" damping=\"0\" frictionloss=\"0\"/>\n"
      << "      <geom name=\"task_" << o.name << "_geom\" contype=\"3\" conaffinity=\"3\" type=\"box\" size=\"" << 0.5 * o.size[0] << " " << 0.5 * o.size[1]
      << " " << 0.5 * o.size[2] << "\" mass=\"" << o.mass << "\" friction=\"" << o.friction
      << " 0.005 0.0001\" rgba=\"" << rgba << "\"/>\n"
      << "    </body>\n";
  }
  return x.str();
}

RobotConfig robotWithTaskScene(const RobotConfig& robot, const TaskScene& scene, const std::string& out_mjcf_path) {
  std::ifstream in(robot.mjcf_path);
  if (!in) throw ConfigError(robot.mjcf_path + ": cannot read the robot MJCF");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string xml = ss.str();
  // The robot's meshdir, made absolute, so the composed model loads from any folder.
  try {
    xml = withAbsoluteMeshdir(xml, fs::absolute(fs::path(robot.mjcf_path)).parent_path().string());
  } catch (const std::runtime_error& e) {
    throw ConfigError(robot.mjcf_path + ": " + e.what());
  }
  std::vector<PadSpec> pads;  // mesh geoms to replace by their bounding boxes (one probe compile for all)
  if (scene.hand_collision) {
    // A collision copy of each rubber hand's visual geom: the same mesh and pose, default contact
    // classes, no mass (the visual geom has density 0 too, so the model's inertias are unchanged).
    const std::string visual_attrs = "contype=\"0\" conaffinity=\"0\" group=\"1\" density=\"0\" ";
    const double torsional = scene.hand_torsional_friction;
    const std::string contact_attrs = fmt::format("mass=\"0\" friction=\"1.0 {} 0.0001\" condim=\"{}\"",
                                                  torsional > 0 ? torsional : 0.005, torsional > 0 ? 4 : 3);
    for (const std::string side : {"left", "right"}) {
      const std::string key = "mesh=\"" + side + "_rubber_hand\"/>";
      const auto at = xml.find(key);
      const auto open = at == std::string::npos ? std::string::npos : xml.rfind("<geom", at);
      std::string geom = open == std::string::npos ? std::string() : xml.substr(open, at + key.size() - open);
      const auto attrs = geom.find(visual_attrs);
      if (attrs == std::string::npos)
        throw ConfigError(robot.mjcf_path + ": hand_collision: no visual <geom " + visual_attrs + "mesh=\"" + side +
                          "_rubber_hand\"/> to copy (scene " + scene.source + ")");
      geom.erase(attrs, visual_attrs.size());
      geom.insert(5, fmt::format(" name=\"task_{}_hand_collision\" {}", side, contact_attrs));
      xml.insert(at + key.size(), "\n" + geom);
    }
    if (scene.hand_collision_shape == "box")
      for (const char* name : {"task_left_hand_collision", "task_right_hand_collision"})
        pads.push_back({name, "", "hand_collision_shape"});
  }
  if (scene.wrist_torsional_friction > 0.0) {
    // The wrist links' collision geoms (the robot MJCF's unnamed mesh geoms with the default contact
    // classes) get condim 4 and the torsional coefficient; sliding and rolling stay MuJoCo's defaults.
    for (const std::string side : {"left", "right"})
      for (const std::string link : {"roll", "pitch", "yaw"}) {
        const std::string geom = "<geom type=\"mesh\" rgba=\"0.7 0.7 0.7 1\" mesh=\"" + side + "_wrist_" + link + "_link\"/>";
        const auto at = xml.find(geom);
        if (at == std::string::npos)
          throw ConfigError(robot.mjcf_path + ": wrist_torsional_friction: no collision " + geom + " (scene " + scene.source + ")");
        xml.insert(at + 5, fmt::format(" condim=\"4\" friction=\"1 {} 0.0001\"", scene.wrist_torsional_friction));
      }
  }
  if (scene.wrist_collision_shape == "box") {
    // Name the wrist links' collision meshes, then replace each by its bounding box. The boxes
    // collide with the scene's bodies only (contype/conaffinity 2 against the robot's 1; the
    // scene's tables and objects are written with 3), so that the six boxes, wider than the round
    // housings, do not touch each other or the arm.
    for (const std::string side : {"left", "right"})
      for (const std::string link : {"roll", "pitch", "yaw"}) {
        const std::string mesh = "mesh=\"" + side + "_wrist_" + link + "_link\"/>";
        std::size_t at = 0;
        for (;;) {  // the collision geom: the one without contype="0"
          at = xml.find(mesh, at);
          if (at == std::string::npos)
            throw ConfigError(robot.mjcf_path + ": wrist_collision_shape: no collision geom with " + mesh + " (scene " +
                              scene.source + ")");
          const auto open = xml.rfind("<geom", at);
          if (xml.substr(open, at - open).find("contype=\"0\"") == std::string::npos) {
            pads.push_back({"task_" + side + "_wrist_" + link + "_collision", "contype=\"2\" conaffinity=\"2\"",
                            "wrist_collision_shape"});
            xml.insert(open + 5, " name=\"" + pads.back().geom + "\"");
            break;
          }
          at += mesh.size();
        }
      }
  }
  if (!pads.empty()) xml = withBoundingBoxPads(xml, pads, robot.mjcf_path, out_mjcf_path);
  if (scene.impratio != 1.0 || scene.cone != "pyramidal" || scene.noslip_iterations != 0) {
    // The scene's contact options, written after <compiler> (the robot's MJCF has no <option> of its own).
    if (xml.find("<option") != std::string::npos)
      throw ConfigError(robot.mjcf_path + ": impratio/cone/noslip_iterations: the robot MJCF has an <option> already (scene " + scene.source + ")");
    const auto comp = xml.find("<compiler");
    const auto comp_end = comp == std::string::npos ? std::string::npos : xml.find('>', comp);
    if (comp_end == std::string::npos) throw ConfigError(robot.mjcf_path + ": the MJCF has no <compiler> to put <option> after");
    xml.insert(comp_end + 1, fmt::format("\n  <option impratio=\"{}\" cone=\"{}\" noslip_iterations=\"{}\"/>", scene.impratio,
                                         scene.cone, scene.noslip_iterations));
  }
  const auto end = xml.rfind("</worldbody>");
  if (end == std::string::npos) throw ConfigError(robot.mjcf_path + ": the MJCF has no </worldbody>");
  xml.insert(end, "    <!-- task scene" + (scene.source.empty() ? std::string() : " " + scene.source) + " (pmg) -->\n" +
                      taskSceneBodies(scene) + "  ");
  {
    std::ofstream out(out_mjcf_path);
    if (!out) throw ConfigError(out_mjcf_path + ": cannot write the composed scene MJCF");
    out << xml;
  }
  RobotConfig r = robot;
  r.mjcf_path = fs::absolute(out_mjcf_path).string();
  return r;
}

TaskObjectState taskObjectState(const mjModel* model, const mjData* data, const std::string& name) {
  const int b = mj_name2id(model, mjOBJ_BODY, ("task_" + name).c_str());
  if (b < 0) throw std::out_of_range("no task object '" + name + "' (body task_" + name + ") in the model");
  TaskObjectState s;
  s.p_W = Eigen::Vector3d(data->xpos[3 * b], data->xpos[3 * b + 1], data->xpos[3 * b + 2]);
  s.q_W = Eigen::Quaterniond(data->xquat[4 * b], data->xquat[4 * b + 1], data->xquat[4 * b + 2], data->xquat[4 * b + 3]);
  // The free joint's linear velocity (qvel[0..2] of a free joint: the body origin's, in W).
  const int j = model->body_jntadr[b];
  if (j >= 0 && model->jnt_type[j] == mjJNT_FREE) {
    const int v = model->jnt_dofadr[j];
    s.v_W = Eigen::Vector3d(data->qvel[v], data->qvel[v + 1], data->qvel[v + 2]);
  }
  return s;
}

}  // namespace pmg
