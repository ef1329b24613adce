// YAML reader of pmg::gco::GcoOptions (setup time only; may allocate and throw), with pmg::yaml.
#include "pmg/common/yaml_archive.hpp"
#include "pmg/gco/gco.hpp"

namespace pmg::gco {

namespace {

// A document with a top-level `gco:` section (config/gco/g1.yaml, the block in docs/gco.md).
struct GcoFile {
  GcoOptions gco;
  template <class A>
  void Serialize(A* a) {
    a->Visit("gco", &gco, "GCO options", yaml::kRequired);
  }
};

GcoOptions read(const yaml::YamlDocument& doc) {
  // An empty file is a mistake (a truncated or wrong file), not "all defaults": name it.
  if (!doc.root || doc.root.IsNull())
    yaml::fail(doc.source, doc.root, "empty file: expected the GCO options (a map, or a document with 'gco:')");
  // Accept either the bare mapping or a document with a top-level `gco:` section.
  if (doc.root.IsMap() && doc.root["gco"]) {
    GcoFile f;
    yaml::readYaml(doc, &f);
    return f.gco;
  }
  GcoOptions o;
  yaml::readYaml(doc, &o);
  return o;
}

}  // namespace

GcoOptions parseGcoOptionsYaml(const std::string& yaml_text, const std::string& source_name) {
  return read(yaml::parseYamlDocument(yaml_text, source_name));
}

GcoOptions loadGcoOptionsFile(const std::string& path) { return read(yaml::loadYamlDocument(path)); }

}  // namespace pmg::gco
