// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/tsdf_volume.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "unseen/util/error.h"

namespace unseen {

TsdfVolume::TsdfVolume(const Eigen::Vector3f& centre, float half_extent_m,
                       const TsdfOptions& options)
    : options_(options) {
  options_.Check();
  UNSEEN_CHECK(half_extent_m > 0.0f && std::isfinite(half_extent_m) && centre.allFinite(),
               "TsdfVolume: half extent {} m must be > 0 about a finite centre", half_extent_m);
  voxel_ = std::max(static_cast<float>(options_.min_voxel_m),
                    2.0f * half_extent_m / options_.voxels_per_side);
  n_ = std::max(2, static_cast<int>(std::ceil(2.0f * half_extent_m / voxel_)) + 1);
  truncation_ = static_cast<float>(options_.truncation_voxels) * voxel_;
  origin_ = centre - Eigen::Vector3f::Constant(0.5f * voxel_ * (n_ - 1));
  const size_t count = size_t(n_) * n_ * n_;
  tsdf_.assign(count, 1.0f);
  weight_.assign(count, 0.0f);
}

namespace {

// Per pixel, the cosine between the viewing ray and the measured surface's normal (from
// the depth of the pixel's neighbours, on each axis the side whose depth is closer, so
// that depth steps at outlines do not tilt it), at least `min_cos`; 1 where the
// neighbours have no depth. The signed distance along a ray times this is the distance
// from the surface: at a grazing angle the ray's is several times larger, and the band
// behind the surface would hold no voxel.
// Pixels on an outline (a 4-neighbour without depth, or farther in depth than `step` and
// than a surface at 80 degrees would step) get a negative cosine: a voxel whose nearest pixel is
// one may lie beside the surface rather than behind it, and must not be marked inside.
cv::Mat ViewCosines(const cv::Mat& depth, const PinholeCamera& camera, float min_cos, float step) {
  cv::Mat cosines(depth.size(), CV_32FC1, cv::Scalar(1.0f));
  const float ifx = 1.0f / static_cast<float>(camera.fx),
              ify = 1.0f / static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  // Depth step between neighbours on a surface at 80 degrees, per metre of depth.
  const float grazing_cos = 0.17f;
  const float pixel_step = ifx * std::sqrt(1.0f - grazing_cos * grazing_cos) / grazing_cos;
  auto point = [&](int x, int y) {
    const float d = depth.at<float>(y, x);
    return Eigen::Vector3f((x - cx) * ifx * d, (y - cy) * ify * d, d);
  };
  // The neighbour on the side of the closer depth along one axis, scaled to one step.
  auto tangent = [&](int x, int y, int dx, int dy, float d, Eigen::Vector3f* t) {
    const bool has_after =
        x + dx < depth.cols && y + dy < depth.rows && depth.at<float>(y + dy, x + dx) > 0.0f;
    const bool has_before = x - dx >= 0 && y - dy >= 0 && depth.at<float>(y - dy, x - dx) > 0.0f;
    if (!has_after && !has_before) return false;
    const bool after =
        has_after && (!has_before || std::abs(depth.at<float>(y + dy, x + dx) - d) <=
                                         std::abs(depth.at<float>(y - dy, x - dx) - d));
    *t = after ? point(x + dx, y + dy) - point(x, y) : point(x, y) - point(x - dx, y - dy);
    return true;
  };
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const float d = depth.at<float>(y, x);
      if (!(d > 0.0f)) continue;
      auto apart = [&](int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= depth.cols || ny >= depth.rows) return true;
        const float n = depth.at<float>(ny, nx);
        return !(n > 0.0f) || std::abs(n - d) > std::max(step, d * pixel_step);
      };
      const bool outline = apart(x - 1, y) || apart(x + 1, y) || apart(x, y - 1) || apart(x, y + 1);
      Eigen::Vector3f tx, ty;
      if (outline) cosines.at<float>(y, x) = -1.0f;
      if (!tangent(x, y, 1, 0, d, &tx) || !tangent(x, y, 0, 1, d, &ty)) continue;
      const Eigen::Vector3f normal = tx.cross(ty);
      const Eigen::Vector3f ray = point(x, y);
      const float norms = normal.norm() * ray.norm();
      if (norms > 0.0f) {
        const float cosine = std::max(min_cos, std::abs(normal.dot(ray)) / norms);
        cosines.at<float>(y, x) = outline ? -cosine : cosine;
      }
    }
  }
  return cosines;
}

}  // namespace

TsdfIntegration TsdfVolume::Integrate(const cv::Mat& depth, const cv::Mat& object_mask,
                                      const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                                      const Eigen::Vector4f* support_plane) {
  UNSEEN_CHECK(
      depth.type() == CV_32FC1 && depth.cols == camera.width && depth.rows == camera.height,
      "TsdfVolume: depth must be CV_32FC1 of the camera's {}x{} pixels (got {}x{} type {})",
      camera.width, camera.height, depth.cols, depth.rows, depth.type());
  UNSEEN_CHECK(
      object_mask.type() == CV_8UC1 && object_mask.size() == depth.size(),
      "TsdfVolume: object mask must be CV_8UC1 of the depth map's size (got {}x{} type {})",
      object_mask.cols, object_mask.rows, object_mask.type());
  UNSEEN_CHECK(cam_from_obj.IsValid(), "TsdfVolume: {} is not a valid pose",
               cam_from_obj.ToString());
  const Eigen::Matrix3f rotation = cam_from_obj.rotation().toRotationMatrix().cast<float>();
  const Eigen::Vector3f translation = cam_from_obj.translation().cast<float>();
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const Eigen::Vector3f step_x = rotation.col(0) * voxel_;
  const float inv_truncation = 1.0f / truncation_;
  const float free_weight = options_.free_space_weight;
  const cv::Mat cosines = ViewCosines(depth, camera, 0.25f, truncation_);
  TsdfIntegration report;
  for (int z = 0; z < n_; ++z) {
    for (int y = 0; y < n_; ++y) {
      const Eigen::Vector3f start =
          rotation * (origin_ + voxel_ * Eigen::Vector3f(0.0f, float(y), float(z))) + translation;
      float* tsdf = &tsdf_[Index(0, y, z)];
      float* weight = &weight_[Index(0, y, z)];
      // Height above the support plane along the row: h(x) = h0 + x dh.
      const Eigen::Vector3f row_origin =
          origin_ + voxel_ * Eigen::Vector3f(0.0f, float(y), float(z));
      const float h0 = support_plane
                           ? support_plane->head<3>().dot(row_origin) + (*support_plane)[3]
                           : std::numeric_limits<float>::infinity();
      const float dh = support_plane ? (*support_plane)[0] * voxel_ : 0.0f;
      const float margin = static_cast<float>(options_.support_margin_m);
      for (int x = 0; x < n_; ++x) {
        const Eigen::Vector3f p = start + float(x) * step_x;
        if (p.z() <= 1e-3f) continue;
        const float inv_z = 1.0f / p.z();
        const int u = static_cast<int>(std::floor(fx * p.x() * inv_z + cx + 0.5f));
        const int v = static_cast<int>(std::floor(fy * p.y() * inv_z + cy + 0.5f));
        if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
        if (h0 + float(x) * dh < margin) {  // on or below the support: not the object
          const float total = weight[x] + 1.0f;
          tsdf[x] = (tsdf[x] * weight[x] + 1.0f) / total;
          weight[x] = std::min(total, options_.max_weight);
          ++report.updated_voxels;
          continue;
        }
        const float d = depth.at<float>(v, u);
        if (!(d > 0.0f)) continue;
        // Signed distance from the measured surface: + in front of it (free).
        const float cosine = cosines.at<float>(v, u);
        const float sdf = (d - p.z()) * std::abs(cosine);
        if (sdf < -truncation_) continue;           // hidden behind the surface: no information
        if (sdf < 0.0f && cosine < 0.0f) continue;  // maybe beside an outline, not behind
        float value, w;
        if (object_mask.at<uint8_t>(v, u)) {
          value = std::min(1.0f, sdf * inv_truncation);
          w = 1.0f;
          ++report.surface_voxels;
        } else if (free_weight > 0.0f && sdf > truncation_) {
          value = 1.0f;  // in front of what the pixel sees, and the pixel is not the object
          w = free_weight;
        } else {
          continue;
        }
        const float total = weight[x] + w;
        tsdf[x] = (tsdf[x] * weight[x] + value * w) / total;
        weight[x] = std::min(total, options_.max_weight);
        ++report.updated_voxels;
      }
    }
  }
  ++integrations_;
  return report;
}

namespace {

// Union-find over vertex ids, for the connected parts of the mesh.
int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Drops the triangles of parts smaller than `share` of the largest and the vertices no
// triangle uses.
void KeepLargeParts(double share, Mesh* mesh) {
  std::vector<int> parent(mesh->vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const Eigen::Vector3i& t : mesh->triangles) {
    parent[Root(parent, t[1])] = Root(parent, t[0]);
    parent[Root(parent, t[2])] = Root(parent, t[0]);
  }
  std::vector<int> part_triangles(parent.size(), 0);
  for (const Eigen::Vector3i& t : mesh->triangles) ++part_triangles[Root(parent, t[0])];
  const int largest = *std::max_element(part_triangles.begin(), part_triangles.end());
  std::erase_if(mesh->triangles, [&](const Eigen::Vector3i& t) {
    return part_triangles[Root(parent, t[0])] < share * largest;
  });
  mesh->RemoveUnusedVertices();
}

}  // namespace

Mesh TsdfVolume::ExtractMesh() const {
  Mesh mesh;
  const int cells = n_ - 1;
  auto cell_index = [cells](int x, int y, int z) { return (size_t(z) * cells + y) * cells + x; };
  std::vector<int> cell_vertex(size_t(cells) * cells * cells, -1);
  // The cube's 12 edges as pairs of corner numbers (corner bit 0: +x, bit 1: +y, bit 2: +z).
  static constexpr std::array<std::array<int, 2>, 12> kEdges = {{{0, 1},
                                                                 {2, 3},
                                                                 {4, 5},
                                                                 {6, 7},
                                                                 {0, 2},
                                                                 {1, 3},
                                                                 {4, 6},
                                                                 {5, 7},
                                                                 {0, 4},
                                                                 {1, 5},
                                                                 {2, 6},
                                                                 {3, 7}}};
  for (int z = 0; z < cells; ++z) {
    for (int y = 0; y < cells; ++y) {
      for (int x = 0; x < cells; ++x) {
        // The cell's corners; an unobserved one is neither inside nor outside. Seen at a
        // grazing angle, the inside corners of a cell are often farther behind the surface
        // along the ray than the truncation band: the edges between observed corners still
        // place the vertex.
        std::array<float, 8> value;
        std::array<bool, 8> observed;
        int inside = 0, outside = 0;
        for (int c = 0; c < 8; ++c) {
          const size_t i = Index(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
          observed[c] = weight_[i] > 0.0f;
          value[c] = tsdf_[i];
          inside += observed[c] && value[c] < 0.0f;
          outside += observed[c] && value[c] >= 0.0f;
        }
        if (inside == 0 || outside == 0) continue;
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        int crossings = 0;
        for (const auto& e : kEdges) {
          const float a = value[e[0]], b = value[e[1]];
          if (!observed[e[0]] || !observed[e[1]] || (a < 0.0f) == (b < 0.0f)) continue;
          const float t = a / (a - b);
          const Eigen::Vector3f ca(e[0] & 1, (e[0] >> 1) & 1, (e[0] >> 2) & 1);
          const Eigen::Vector3f cb(e[1] & 1, (e[1] >> 1) & 1, (e[1] >> 2) & 1);
          sum += ca + t * (cb - ca);
          ++crossings;
        }
        if (crossings == 0) continue;
        cell_vertex[cell_index(x, y, z)] = mesh.num_vertices();
        mesh.vertices.push_back(origin_ +
                                voxel_ * (Eigen::Vector3f(x, y, z) + sum / float(crossings)));
      }
    }
  }
  // One quad per grid edge the surface crosses, joining the four cells around the edge.
  for (int z = 0; z < n_; ++z) {
    for (int y = 0; y < n_; ++y) {
      for (int x = 0; x < n_; ++x) {
        const size_t i = Index(x, y, z);
        if (!(weight_[i] > 0.0f)) continue;
        const Eigen::Vector3i p(x, y, z);
        for (int axis = 0; axis < 3; ++axis) {
          Eigen::Vector3i q = p;
          ++q[axis];
          if (q[axis] >= n_) continue;
          const size_t j = Index(q.x(), q.y(), q.z());
          if (!(weight_[j] > 0.0f) || (tsdf_[i] < 0.0f) == (tsdf_[j] < 0.0f)) continue;
          const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
          if (p[a1] < 1 || p[a2] < 1 || p[a1] >= cells || p[a2] >= cells) continue;
          std::array<int, 4> quad;
          bool complete = true;
          for (int k = 0; k < 4 && complete; ++k) {
            Eigen::Vector3i c = p;
            // Around the edge: (0, 0), (-1, 0), (-1, -1), (0, -1) in (a1, a2).
            c[a1] -= (k == 1 || k == 2);
            c[a2] -= (k >= 2);
            quad[k] = cell_vertex[cell_index(c.x(), c.y(), c.z())];
            complete = quad[k] >= 0;
          }
          if (!complete) continue;
          // Outward (towards the free side): +axis when the edge leaves the inside.
          const Eigen::Vector3f& v0 = mesh.vertices[quad[0]];
          const Eigen::Vector3f normal =
              (mesh.vertices[quad[1]] - v0).cross(mesh.vertices[quad[2]] - v0);
          const float outward = tsdf_[i] < 0.0f ? 1.0f : -1.0f;
          if (normal[axis] * outward < 0.0f) std::swap(quad[1], quad[3]);
          mesh.triangles.emplace_back(quad[0], quad[1], quad[2]);
          mesh.triangles.emplace_back(quad[0], quad[2], quad[3]);
        }
      }
    }
  }
  if (mesh.triangles.empty()) return Mesh();
  KeepLargeParts(options_.min_component_share, &mesh);
  mesh.ComputeNormals();
  return mesh;
}

}  // namespace unseen
