// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/scene_yaml.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "unseen/util/files.h"

namespace unseen::scene_yaml {

double Mm(const Field& f) { return f.Double() * 1e-3; }
Eigen::Vector3d Vec3Mm(const Field& f) { return f.Vec3() * 1e-3; }

Eigen::Vector3d ColorRgb(const Field& f) {
  const Eigen::Vector3d rgb = f.Vec3();
  for (int i = 0; i < 3; ++i) {
    if (rgb[i] < 0.0 || rgb[i] > 1.0)
      f.Fail("colour components must be in [0, 1], got {}", f.Text());
  }
  return {rgb[2], rgb[1], rgb[0]};
}

Eigen::Vector3d Direction(const Field& f) {
  const Eigen::Vector3d d = f.Vec3();
  const double norm = d.stableNorm();  // norm() overflows for components near 1e308
  if (!(norm >= 1e-12 && std::isfinite(norm))) {
    f.Fail("direction must be neither zero nor huge, got {}", f.Text());
  }
  return d / norm;
}

std::string FilePath(const Field& f, const Context& ctx) {
  const std::string raw = f.String();
  if (raw.empty()) f.Fail("file path is empty");
  std::string out;
  for (size_t i = 0; i < raw.size();) {
    if (raw[i] != '$') {
      out += raw[i++];
      continue;
    }
    size_t start = i + 1, end = start;
    bool braced = start < raw.size() && raw[start] == '{';
    if (braced) {
      end = raw.find('}', start);
      if (end == std::string::npos) f.Fail("unterminated '${{' in path {}", f.Text());
      ++start;
    } else {
      while (end < raw.size() &&
             (std::isalnum(static_cast<unsigned char>(raw[end])) || raw[end] == '_')) {
        ++end;
      }
    }
    const std::string name = raw.substr(start, end - start);
    const char* value = name.empty() ? nullptr : std::getenv(name.c_str());
    if (value == nullptr) f.Fail("environment variable '{}' in path {} is not set", name, f.Text());
    out += value;
    i = braced ? end + 1 : end;
  }
  std::filesystem::path p(out);
  if (p.is_relative()) p = std::filesystem::path(ctx.base_dir) / p;
  if (!Exists(p)) f.Fail("file '{}' does not exist", p.string());
  return p.lexically_normal().string();
}

}  // namespace unseen::scene_yaml
