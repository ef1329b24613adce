#include "pmg/common/mujoco_model.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

namespace pmg {
namespace fs = std::filesystem;

std::string withAbsoluteMeshdir(const std::string& mjcf_text, const std::string& mjcf_dir) {
  const std::regex compiler_re(R"(<compiler([^>]*?)(/?)>)");
  std::smatch m;
  if (!std::regex_search(mjcf_text, m, compiler_re)) throw std::runtime_error("MJCF has no <compiler> element");
  std::string attrs = m[1].str();
  std::smatch md;
  std::string meshdir = mjcf_dir;
  if (std::regex_search(attrs, md, std::regex(R"(meshdir=\"([^\"]*)\")"))) {
    const fs::path p(md[1].str());
    meshdir = (p.is_absolute() ? p : fs::path(mjcf_dir) / p).lexically_normal().string();
    attrs = std::regex_replace(attrs, std::regex(R"(\s*meshdir=\"[^\"]*\")"), "");
  }
  return mjcf_text.substr(0, static_cast<std::size_t>(m.position(0))) + "<compiler" + attrs + " meshdir=\"" + meshdir +
         "\"" + m[2].str() + ">" + mjcf_text.substr(static_cast<std::size_t>(m.position(0) + m.length(0)));
}

std::string adaptMjcfForMujoco22(const std::string& mjcf_text, const std::string& mjcf_dir,
                                 const Mujoco22Options& o) {
  if (!(o.timestep > 0 && o.timestep <= 0.01))
    throw std::runtime_error("Mujoco22Options.timestep = " + std::to_string(o.timestep) + ": expected (0, 0.01] s");
  // 1. attributes unknown to 2.2.
  std::string xml = std::regex_replace(mjcf_text, std::regex(R"(\s+actuatorfrc(range|limited)=\"[^\"]*\")"), "");
  // 2. compiler: absolute meshdir + autolimits.
  xml = withAbsoluteMeshdir(xml, mjcf_dir);
  const std::regex compiler_re(R"(<compiler([^>]*?)/?>)");
  std::smatch m;
  std::regex_search(xml, m, compiler_re);  // present: withAbsoluteMeshdir checked it
  std::string attrs = std::regex_replace(m[1].str(), std::regex(R"(\s*autolimits=\"[^\"]*\")"), "");
  std::ostringstream head;
  head << "<compiler" << attrs << " autolimits=\"true\"/>\n"
       << "  <option timestep=\"" << o.timestep << "\"/>\n"
       << "  <size nconmax=\"500\" njmax=\"2000\"/>\n"
       << "  <default><joint armature=\"" << o.armature << "\" damping=\"" << o.damping << "\" frictionloss=\""
       << o.frictionloss << "\"/></default>";
  xml = xml.substr(0, static_cast<std::size_t>(m.position(0))) + head.str() +
        xml.substr(static_cast<std::size_t>(m.position(0) + m.length(0)));
  // 5. IMU orientation sensor.
  const std::string quat = "<framequat name=\"" + o.imu_site + "-orientation\" objtype=\"site\" objname=\"" +
                           o.imu_site + "\"/>";
  const auto sensor_pos = xml.find("<sensor>");
  if (sensor_pos != std::string::npos) {
    xml.insert(sensor_pos + 8, "\n    " + quat);
  } else {
    const auto end = xml.rfind("</mujoco>");
    if (end == std::string::npos) throw std::runtime_error("MJCF has no </mujoco> end tag");
    xml.insert(end, "  <sensor>" + quat + "</sensor>\n");
  }
  return xml;
}

MjModelPtr loadMujocoModel(const std::string& mjcf_path, const Mujoco22Options& options) {
  std::ifstream in(mjcf_path);
  if (!in) throw std::runtime_error(mjcf_path + ": cannot open MJCF file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string dir = fs::absolute(fs::path(mjcf_path)).parent_path().string();
  const std::string xml = adaptMjcfForMujoco22(ss.str(), dir, options);
  // MuJoCo 2.2 compiles from a file: write the adapted text to a private temporary file.
  std::string tmpl = (fs::temp_directory_path() / "pmg_mjcf_XXXXXX").string();
  const int fd = mkstemp(tmpl.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary file for the adapted MJCF");
  close(fd);
  const std::string tmp = tmpl + ".xml";
  fs::rename(tmpl, tmp);
  {
    std::ofstream out(tmp);
    out << xml;
  }
  char error[1024] = {0};
  mjModel* model = mj_loadXML(tmp.c_str(), nullptr, error, sizeof(error));
  std::remove(tmp.c_str());
  if (!model) throw std::runtime_error(mjcf_path + ": MuJoCo 2.2 could not load the adapted MJCF: " + error);
  return MjModelPtr(model);
}

}  // namespace pmg
