// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "unseen/util/error.h"

namespace unseen {

bool Mesh::HasUvTexture() const {
  if (uvs.empty()) return false;
  return std::any_of(materials.begin(), materials.end(),
                     [](const Material& m) { return !m.texture.empty(); });
}

bool Mesh::HasAppearance() const {
  if (HasUvTexture() || !projectors.empty()) return true;
  constexpr float kSameColour = 2.0f / 255.0f;
  auto varies = [&](const std::vector<Eigen::Vector3f>& colours) {
    for (const Eigen::Vector3f& c : colours) {
      if ((c - colours.front()).cwiseAbs().maxCoeff() > kSameColour) return true;
    }
    return false;
  };
  if (!colors_bgr.empty() && varies(colors_bgr)) return true;
  if (materials.size() > 1 && !triangle_materials.empty()) {
    std::vector<Eigen::Vector3f> used;
    for (int m : triangle_materials) used.push_back(materials[m].diffuse_bgr);
    return varies(used);
  }
  return false;
}

void Mesh::Check(const std::string& what) const {
  UNSEEN_CHECK(!triangles.empty(), "{}: mesh has no triangles", what);
  UNSEEN_CHECK(!vertices.empty(), "{}: mesh has no vertices", what);
  for (size_t i = 0; i < vertices.size(); ++i) {
    UNSEEN_CHECK(vertices[i].allFinite(), "{}: vertex {} is not finite ({} {} {})", what, i,
                 vertices[i].x(), vertices[i].y(), vertices[i].z());
  }
  const int n = num_vertices();
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int idx = triangles[t][k];
      UNSEEN_CHECK(idx >= 0 && idx < n, "{}: triangle {} has vertex index {} out of range [0, {})",
                   what, t, idx, n);
    }
  }
  UNSEEN_CHECK(normals.empty() || normals.size() == vertices.size(),
               "{}: {} normals for {} vertices", what, normals.size(), vertices.size());
  UNSEEN_CHECK(uvs.empty() || uvs.size() == vertices.size(), "{}: {} uvs for {} vertices",
               what, uvs.size(), vertices.size());
  for (size_t i = 0; i < uvs.size(); ++i) {
    UNSEEN_CHECK(uvs[i].allFinite(), "{}: texture coordinate {} is not finite ({} {})", what, i,
                 uvs[i].x(), uvs[i].y());
  }
  UNSEEN_CHECK(colors_bgr.empty() || colors_bgr.size() == vertices.size(),
               "{}: {} colours for {} vertices", what, colors_bgr.size(), vertices.size());
  UNSEEN_CHECK(triangle_materials.empty() || triangle_materials.size() == triangles.size(),
               "{}: {} triangle materials for {} triangles", what, triangle_materials.size(),
               triangles.size());
  for (size_t t = 0; t < triangle_materials.size(); ++t) {
    const int m = triangle_materials[t];
    UNSEEN_CHECK(m >= 0 && m < static_cast<int>(materials.size()),
                 "{}: triangle {} has material {} out of range [0, {})", what, t, m,
                 materials.size());
  }
  for (const Material& m : materials) {
    UNSEEN_CHECK(m.texture.empty() || m.texture.type() == CV_32FC3,
                 "{}: material '{}' texture must be CV_32FC3", what, m.name);
  }
  for (size_t p = 0; p < projectors.size(); ++p) {
    UNSEEN_CHECK(!projectors[p].image.empty() && projectors[p].image.type() == CV_32FC3,
                 "{}: projector {} has no CV_32FC3 image", what, p);
    projectors[p].camera.Check(what + " projector " + std::to_string(p));
    const cv::Mat& depth = projectors[p].depth;
    UNSEEN_CHECK(depth.empty() || (depth.type() == CV_32FC1 &&
                                   depth.size() == projectors[p].image.size()),
                 "{}: projector {} depth must be empty or CV_32FC1 of its image's size", what, p);
    UNSEEN_CHECK(projectors[p].depth_tolerance_m >= 0.0f &&
                     std::isfinite(projectors[p].depth_tolerance_m),
                 "{}: projector {} depth_tolerance_m {} must be >= 0", what, p,
                 projectors[p].depth_tolerance_m);
  }
}

void Mesh::BoundingBox(Eigen::Vector3f* min, Eigen::Vector3f* max) const {
  *min = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  *max = Eigen::Vector3f::Constant(std::numeric_limits<float>::lowest());
  for (const Eigen::Vector3f& v : vertices) {
    *min = min->cwiseMin(v);
    *max = max->cwiseMax(v);
  }
}

void Mesh::BoundingSphere(Eigen::Vector3f* centre, float* radius) const {
  Eigen::Vector3f lo, hi;
  BoundingBox(&lo, &hi);
  *centre = 0.5f * (lo + hi);
  float r2 = 0.0f;
  for (const Eigen::Vector3f& v : vertices) r2 = std::max(r2, (v - *centre).squaredNorm());
  *radius = std::sqrt(r2);
}

void Mesh::Scale(float s) {
  for (Eigen::Vector3f& v : vertices) v *= s;
  for (Projector& p : projectors) {
    p.cam_from_obj.set_translation(p.cam_from_obj.translation() * static_cast<double>(s));
    if (!p.depth.empty()) p.depth *= s;
    p.depth_tolerance_m *= s;
  }
}

void Mesh::RemoveUnusedVertices() {
  std::vector<int> new_index(vertices.size(), -1);
  int used = 0;
  for (const Eigen::Vector3i& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      if (new_index[t[k]] < 0) new_index[t[k]] = used++;
    }
  }
  auto keep = [&](auto& attribute) {
    if (attribute.empty()) return;
    std::remove_reference_t<decltype(attribute)> kept(used);
    for (size_t i = 0; i < new_index.size(); ++i) {
      if (new_index[i] >= 0) kept[new_index[i]] = attribute[i];
    }
    attribute = std::move(kept);
  };
  keep(vertices);
  keep(normals);
  keep(uvs);
  keep(colors_bgr);
  for (Eigen::Vector3i& t : triangles) {
    for (int k = 0; k < 3; ++k) t[k] = new_index[t[k]];
  }
}

void Mesh::ComputeNormals() {
  normals.assign(vertices.size(), Eigen::Vector3f::Zero());
  for (const Eigen::Vector3i& t : triangles) {
    const Eigen::Vector3f n =
        (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;  // |n| = 2 * area: area-weighted
  }
  for (Eigen::Vector3f& n : normals) {
    const float len = n.norm();
    n = len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f(0, 0, 1);
  }
}

}  // namespace unseen
