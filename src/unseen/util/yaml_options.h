// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Reading options structs from YAML: each section of a file is a map of settings, each
// setting writes one field. Unknown sections and keys, and values of the wrong type, are
// errors naming the file, the section, the key and the value.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <string>

#include "unseen/util/error.h"

namespace unseen {

// Writes one field from a YAML value; `where` names it in errors ("file: section.key").
using YamlSetter = std::function<void(const YAML::Node&, const std::string&)>;

template <typename T>
YamlSetter YamlField(T* field) {
  return [field](const YAML::Node& node, const std::string& where) {
    try {
      *field = node.as<T>();
    } catch (const YAML::Exception&) {
      ThrowError("{}: value '{}' has the wrong type", where, YAML::Dump(node));
    }
  };
}

// An enumeration read from its name by `parse(text, where)`.
// A number written into `field` times `scale` (a file in mm or degrees, a struct in metres
// or radians).
inline YamlSetter YamlScaledField(double* field, double scale) {
  return [field, scale](const YAML::Node& node, const std::string& where) {
    double value = 0.0;
    YamlField (&value)(node, where);
    *field = value * scale;
  };
}

template <typename E>
YamlSetter YamlEnumField(E* field, E (*parse)(const std::string&, const std::string&)) {
  return [field, parse](const YAML::Node& node, const std::string& where) {
    std::string text;
    try {
      text = node.as<std::string>();
    } catch (const YAML::Exception&) {
      ThrowError("{}: value '{}' is not a string", where, YAML::Dump(node));
    }
    *field = parse(text, where);
  };
}

using YamlSection = std::map<std::string, YamlSetter>;

// A map key as text. Throws naming `where` for a key that is not a plain name (YAML allows
// lists and maps as keys: "? [a, b]: 1").
std::string YamlKeyName(const YAML::Node& key, const std::string& where);

// Applies the settings of `node` (a map) with `fields`.
void ApplyYamlSection(const YAML::Node& node, const std::string& where, const YamlSection& fields);

// Applies a whole document: each top-level key names a section of `sections`. `what`
// names the file or text in errors.
void ApplyYamlSections(const YAML::Node& root, const std::string& what,
                       const std::map<std::string, YamlSection>& sections);

// The YAML document of a file; throws naming `path` ("cannot read the `kind` file",
// malformed YAML).
YAML::Node LoadYamlFile(const std::string& path, const std::string& kind);

// The YAML document `text`; throws unseen::Error "<what>: malformed YAML: ..." otherwise.
YAML::Node ParseYamlText(const std::string& text, const std::string& what);

// options.Check(), its error prefixed with `what` (the file the options came from).
template <typename Options>
void CheckOptionsFrom(const Options& options, const std::string& what) {
  try {
    options.Check();
  } catch (const Error& e) {
    ThrowError("{}: {}", what, e.what());
  }
}

}  // namespace unseen
