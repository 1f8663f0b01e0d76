// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/yaml_options.h"

namespace unseen {

std::string YamlKeyName(const YAML::Node& key, const std::string& where) {
  UNSEEN_CHECK(key.IsScalar(), "{}: key '{}' is not a plain name", where, YAML::Dump(key));
  return key.Scalar();
}

void ApplyYamlSection(const YAML::Node& node, const std::string& where, const YamlSection& fields) {
  UNSEEN_CHECK(node.IsMap(), "{}: expected a map of settings", where);
  for (const auto& kv : node) {
    const std::string key = YamlKeyName(kv.first, where);
    const auto it = fields.find(key);
    if (it == fields.end()) {
      std::string known;
      for (const auto& f : fields) known += (known.empty() ? "" : ", ") + f.first;
      ThrowError("{}: unknown key '{}' (known: {})", where, key, known);
    }
    it->second(kv.second, where + "." + key);
  }
}

void ApplyYamlSections(const YAML::Node& root, const std::string& what,
                       const std::map<std::string, YamlSection>& sections) {
  if (root.IsNull()) return;
  UNSEEN_CHECK(root.IsMap(), "{}: expected a map of sections", what);
  for (const auto& kv : root) {
    const std::string key = YamlKeyName(kv.first, what);
    const auto it = sections.find(key);
    if (it == sections.end()) {
      std::string known;
      for (const auto& s : sections) known += (known.empty() ? "" : ", ") + s.first;
      ThrowError("{}: unknown section '{}' (known: {})", what, key, known);
    }
    ApplyYamlSection(kv.second, what + ": " + key, it->second);
  }
}

YAML::Node LoadYamlFile(const std::string& path, const std::string& kind) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    ThrowError("{}: cannot read the {} file", path, kind);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", path, e.what());
  }
}

YAML::Node ParseYamlText(const std::string& text, const std::string& what) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", what, e.what());
  }
}

}  // namespace unseen
