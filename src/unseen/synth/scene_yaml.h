// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Reading a scene file (scene.h): YAML nodes that know the dotted path that led to them,
// so that every error names the file, the field, its line and the value; and the readers
// of the values every section shares (lengths in mm, colours, directions, file paths).
#pragma once

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "unseen/util/error.h"

namespace unseen::scene_yaml {

// A YAML node with the dotted path that led to it, for messages naming the file, the
// field, its line and the value.
class Field {
 public:
  Field(YAML::Node node, std::string path, const std::string* file)
      : node_(std::move(node)), path_(std::move(path)), file_(file) {}

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  bool IsMap() const { return node_.IsMap(); }
  bool IsSequence() const { return node_.IsSequence(); }
  bool IsScalar() const { return node_.IsScalar(); }
  size_t size() const { return node_.size(); }

  // "<file>: field 'a.b[2]' (line 4, column 7): <message>".
  template <typename... Args>
  [[noreturn]] void Fail(fmt::format_string<Args...> format, Args&&... args) const {
    const YAML::Mark mark = node_.Mark();
    std::string where = fmt::format("{}: field '{}'", *file_, path_.empty() ? "<root>" : path_);
    if (mark.line >= 0)
      where += fmt::format(" (line {}, column {})", mark.line + 1, mark.column + 1);
    throw Error(where + ": " + fmt::format(format, std::forward<Args>(args)...));
  }

  // Text of the node for messages.
  std::string Text() const {
    if (node_.IsScalar()) return "'" + node_.Scalar() + "'";
    YAML::Emitter e;
    e << YAML::Flow << node_;
    return e.c_str();
  }

  bool Has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

  Field Child(const std::string& key) const {
    if (!node_.IsMap()) Fail("expected a mapping, got {}", Text());
    const YAML::Node child = node_[key];
    if (!child.IsDefined()) Fail("missing required field '{}'", key);
    return Field(child, path_.empty() ? key : path_ + "." + key, file_);
  }
  Field Index(size_t i) const { return Field(node_[i], fmt::format("{}[{}]", path_, i), file_); }

  // Rejects keys not in `known` (catches misspelt field names).
  void ExpectKeys(std::initializer_list<const char*> known) const {
    if (!node_.IsMap()) Fail("expected a mapping, got {}", Text());
    const std::set<std::string> allowed(known.begin(), known.end());
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        Field(kv.first, path_.empty() ? key : path_ + "." + key, file_)
            .Fail("unknown field '{}' (known: {})", key, list);
      }
    }
  }

  double Double() const {
    if (!node_.IsScalar()) Fail("expected a number, got {}", Text());
    double v = 0.0;
    try {
      v = node_.as<double>();
    } catch (const YAML::Exception&) {
      Fail("expected a number, got {}", Text());
    }
    if (!std::isfinite(v)) Fail("expected a finite number, got {}", Text());
    return v;
  }
  int Int() const {
    if (!node_.IsScalar()) Fail("expected an integer, got {}", Text());
    long long v = 0;
    try {
      v = node_.as<long long>();
    } catch (const YAML::Exception&) {
      Fail("expected an integer, got {}", Text());
    }
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
      Fail("integer {} out of range", Text());
    }
    return static_cast<int>(v);
  }
  uint64_t UInt64() const {
    if (!node_.IsScalar()) Fail("expected a non-negative integer, got {}", Text());
    const std::string s = node_.Scalar();
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos) {
      Fail("expected a non-negative integer, got {}", Text());
    }
    try {
      return std::stoull(s);
    } catch (const std::exception&) {
      Fail("integer {} out of range", Text());
    }
  }
  bool Bool() const {
    if (!node_.IsScalar()) Fail("expected true or false, got {}", Text());
    try {
      return node_.as<bool>();
    } catch (const YAML::Exception&) {
      Fail("expected true or false, got {}", Text());
    }
  }
  std::string String() const {
    if (!node_.IsScalar()) Fail("expected a string, got {}", Text());
    return node_.Scalar();
  }
  // A list of exactly `n` numbers (or between n_min and n when n_min > 0).
  std::vector<double> Numbers(size_t n, size_t n_min = 0) const {
    const size_t lo = n_min > 0 ? n_min : n;
    if (!node_.IsSequence() || node_.size() < lo || node_.size() > n) {
      if (lo == n) Fail("expected a list of {} numbers, got {}", n, Text());
      Fail("expected a list of {} to {} numbers, got {}", lo, n, Text());
    }
    std::vector<double> out;
    for (size_t i = 0; i < node_.size(); ++i) out.push_back(Index(i).Double());
    return out;
  }
  Eigen::Vector3d Vec3() const {
    const auto v = Numbers(3);
    return {v[0], v[1], v[2]};
  }

  // Value checks with messages naming this field.
  double Positive(double v) const {
    if (!(v > 0.0)) Fail("must be positive, got {}", Text());
    return v;
  }
  double NonNegative(double v) const {
    if (!(v >= 0.0)) Fail("must not be negative, got {}", Text());
    return v;
  }
  double InRange(double v, double lo, double hi) const {
    if (!(v >= lo && v <= hi)) Fail("must be in [{}, {}], got {}", lo, hi, Text());
    return v;
  }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string* file_;
};

// Parse context: the file name and the folder relative paths are resolved against.
struct Context {
  std::string file;
  std::string base_dir;
};

// A length in millimetres, in metres.
double Mm(const Field& f);
Eigen::Vector3d Vec3Mm(const Field& f);
// A colour given as [r, g, b] in [0, 1], returned as BGR.
Eigen::Vector3d ColorRgb(const Field& f);
// A unit direction from a non-zero vector.
Eigen::Vector3d Direction(const Field& f);
// Expands $NAME / ${NAME} from the environment and resolves relative paths against the
// scene file's folder; checks that the file exists.
std::string FilePath(const Field& f, const Context& ctx);

}  // namespace unseen::scene_yaml
