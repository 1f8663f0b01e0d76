// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/simplify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>

#include "unseen/util/error.h"

namespace unseen {

void SimplifyOptions::Check() const {
  UNSEEN_CHECK(max_normal_angle_rad >= 0.0 && max_normal_angle_rad < 0.1,
               "simplify: max_normal_angle_rad {} must be in [0, 0.1)", max_normal_angle_rad);
  UNSEEN_CHECK(relative_tolerance >= 0.0 && relative_tolerance < 0.01,
               "simplify: relative_tolerance {} must be in [0, 0.01)", relative_tolerance);
  UNSEEN_CHECK(attribute_tolerance >= 0.0 && attribute_tolerance < 0.01,
               "simplify: attribute_tolerance {} must be in [0, 0.01)", attribute_tolerance);
  UNSEEN_CHECK(texture_shift_tolerance >= 0.0 && texture_shift_tolerance < 0.1,
               "simplify: texture_shift_tolerance {} must be in [0, 0.1)",
               texture_shift_tolerance);
}

namespace {

constexpr int kMaxAttributes = 8;  // uv 2 + colour 3 + normal 3
using Attributes = Eigen::Matrix<double, kMaxAttributes, 1>;

// Edge collapses on a mesh whose vertices are welded by position for topology, each
// triangle keeping its own vertex copies (UV seams) for attributes.
class FlatPatchSimplifier {
 public:
  FlatPatchSimplifier(const Mesh& mesh, const SimplifyOptions& options)
      : mesh_(mesh), options_(options) {
    Eigen::Vector3f centre;
    float radius = 0.0f;
    mesh.BoundingSphere(&centre, &radius);
    tolerance_m_ = options.relative_tolerance * std::max(double(radius), 1e-12);
    texture_shift_m_ = options.texture_shift_tolerance * std::max(double(radius), 1e-12);
    min_cos_ = std::cos(options.max_normal_angle_rad);
    WeldPositions();
    num_attributes_ = (mesh.uvs.empty() ? 0 : 2) + (mesh.colors_bgr.empty() ? 0 : 3) +
                      (mesh.normals.empty() ? 0 : 3);
    triangles_ = mesh.triangles;
    alive_.assign(triangles_.size(), 1);
    incident_.assign(num_positions_, {});
    // A degenerate triangle is never collapsed through and pins its vertices (it is drawn
    // as nothing, but collapses around it would have to keep it consistent).
    pinned_.assign(num_positions_, 0);
    for (int t = 0; t < static_cast<int>(triangles_.size()); ++t) {
      const bool degenerate = Normal(triangles_[t]).squaredNorm() == 0.0;
      for (int k = 0; k < 3; ++k) {
        const int p = position_of_[triangles_[t][k]];
        if (degenerate) {
          pinned_[p] = 1;
        } else {
          incident_[p].push_back(t);
        }
      }
    }
  }

  // Collapses vertices until none can go; returns the simplified mesh.
  Mesh Run() {
    for (bool changed = true; changed;) {
      changed = false;
      for (int p = 0; p < num_positions_; ++p) {
        if (!pinned_[p] && TryRemove(p)) changed = true;
      }
    }
    return Compact();
  }

 private:
  void WeldPositions() {
    std::unordered_map<std::string, int> ids;
    position_of_.resize(mesh_.vertices.size());
    for (size_t v = 0; v < mesh_.vertices.size(); ++v) {
      std::string key(sizeof(float) * 3, '\0');
      std::memcpy(key.data(), mesh_.vertices[v].data(), sizeof(float) * 3);
      auto [it, inserted] = ids.emplace(key, static_cast<int>(ids.size()));
      position_of_[v] = it->second;
      if (inserted) position_vertex_.push_back(static_cast<int>(v));
    }
    num_positions_ = static_cast<int>(ids.size());
  }

  Eigen::Vector3d Point(int vertex) const { return mesh_.vertices[vertex].cast<double>(); }
  Eigen::Vector3d PositionPoint(int position) const {
    return Point(position_vertex_[position]);
  }
  Eigen::Vector3d Normal(const Eigen::Vector3i& t) const {
    const Eigen::Vector3d n = (Point(t[1]) - Point(t[0])).cross(Point(t[2]) - Point(t[0]));
    const double len = n.norm();
    return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  }
  int Material(int t) const {
    return mesh_.triangle_materials.empty() ? 0 : mesh_.triangle_materials[t];
  }
  Attributes AttributesOf(int vertex) const {
    Attributes a = Attributes::Zero();
    int k = 0;
    if (!mesh_.uvs.empty()) a.segment<2>(k) = mesh_.uvs[vertex].cast<double>(), k += 2;
    if (!mesh_.colors_bgr.empty()) a.segment<3>(k) = mesh_.colors_bgr[vertex].cast<double>(), k += 3;
    if (!mesh_.normals.empty()) a.segment<3>(k) = mesh_.normals[vertex].cast<double>();
    return a;
  }
  int CornerOf(int t, int position) const {
    for (int k = 0; k < 3; ++k) {
      if (position_of_[triangles_[t][k]] == position) return k;
    }
    return -1;
  }
  bool HasPosition(int t, int position) const { return CornerOf(t, position) >= 0; }

  // The live triangles around position p (pruning dead ones from its list).
  const std::vector<int>& Incident(int p) {
    std::vector<int>& list = incident_[p];
    list.erase(std::remove_if(list.begin(), list.end(), [&](int t) { return !alive_[t]; }),
               list.end());
    return list;
  }

  // Whether two triangles are one flat patch: coplanar, one material, and each one's
  // vertices on the other's affine attribute map.
  bool SamePatch(int a, int b) const {
    if (Material(a) != Material(b)) return false;
    const Eigen::Vector3d na = Normal(triangles_[a]), nb = Normal(triangles_[b]);
    if (na.dot(nb) < min_cos_) return false;
    return OnAffineMap(a, triangles_[b]) && OnAffineMap(b, triangles_[a]);
  }

  // Whether the vertices of `tri` lie in triangle t's plane and carry the attributes that
  // t's affine map (plane coordinates -> attributes) gives them there.
  bool OnAffineMap(int t, const Eigen::Vector3i& tri) const {
    const Eigen::Vector3i& ref = triangles_[t];
    const Eigen::Vector3d o = Point(ref[0]);
    const Eigen::Vector3d n = Normal(ref);
    const Eigen::Vector3d e1 = (Point(ref[1]) - o).normalized();
    const Eigen::Vector3d e2 = n.cross(e1);
    Eigen::Matrix3d plane;  // rows: (s, t, 1) of the reference corners
    Eigen::Matrix<double, 3, kMaxAttributes> values;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = Point(ref[k]) - o;
      plane.row(k) << d.dot(e1), d.dot(e2), 1.0;
      values.row(k) = AttributesOf(ref[k]).transpose();
    }
    const Eigen::Matrix<double, 3, kMaxAttributes> map = plane.fullPivLu().solve(values);
    // UV per plane coordinate (s, t): a UV error maps back to a slide over the surface.
    const int uv_dims = mesh_.uvs.empty() ? 0 : 2;
    Eigen::Matrix2d surface_from_uv = Eigen::Matrix2d::Zero();
    if (uv_dims > 0) {
      const Eigen::Matrix2d uv_from_surface = map.topLeftCorner<2, 2>().transpose();
      if (std::abs(uv_from_surface.determinant()) < 1e-12) return false;  // UVs collapsed
      surface_from_uv = uv_from_surface.inverse();
    }
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = Point(tri[k]) - o;
      if (std::abs(d.dot(n)) > tolerance_m_) return false;
      if (num_attributes_ == 0) continue;
      const Eigen::RowVector3d st(d.dot(e1), d.dot(e2), 1.0);
      const Attributes error = (st * map).transpose() - AttributesOf(tri[k]);
      if (uv_dims > 0 && (surface_from_uv * error.head<2>()).norm() > texture_shift_m_) {
        return false;
      }
      if (num_attributes_ > uv_dims &&
          error.segment(uv_dims, num_attributes_ - uv_dims).cwiseAbs().maxCoeff() >
              options_.attribute_tolerance) {
        return false;
      }
    }
    return true;
  }

  // Removes position p by collapsing it onto a neighbour when that changes nothing drawn.
  bool TryRemove(int p) {
    const std::vector<int> fan = Incident(p);
    if (fan.empty()) return false;
    // Triangles per neighbouring position (the edges at p).
    std::map<int, std::vector<int>> edges;
    for (int t : fan) {
      const int k = CornerOf(t, p);
      for (int j = 1; j <= 2; ++j) edges[position_of_[triangles_[t][(k + j) % 3]]].push_back(t);
    }
    // Patches: triangles of the fan joined across shared edges where they are one patch.
    std::vector<int> patch(fan.size());
    for (size_t i = 0; i < fan.size(); ++i) patch[i] = static_cast<int>(i);
    auto find = [&](int i) {
      while (patch[i] != i) i = patch[i] = patch[patch[i]];
      return i;
    };
    auto index_in_fan = [&](int t) {
      return static_cast<int>(std::find(fan.begin(), fan.end(), t) - fan.begin());
    };
    std::vector<int> feature;  // neighbours across a crease or an open border
    for (const auto& [q, tris] : edges) {
      if (tris.size() > 2) return false;  // non-manifold
      if (tris.size() == 1) {
        feature.push_back(q);
      } else if (SamePatch(tris[0], tris[1])) {
        patch[find(index_in_fan(tris[0]))] = find(index_in_fan(tris[1]));
      } else {
        feature.push_back(q);
      }
    }
    std::vector<int> targets;
    if (feature.empty()) {
      // Inside one patch: the fan must be one patch (it is closed: every edge has two sides).
      for (size_t i = 1; i < fan.size(); ++i) {
        if (find(static_cast<int>(i)) != find(0)) return false;
      }
      for (const auto& kv : edges) targets.push_back(kv.first);
    } else if (feature.size() == 2) {
      // On a crease or border: only along it, and only where it runs straight through p.
      const Eigen::Vector3d a = PositionPoint(feature[0]), b = PositionPoint(feature[1]);
      const Eigen::Vector3d x = PositionPoint(p);
      const Eigen::Vector3d ab = b - a;
      const double len2 = ab.squaredNorm();
      if (len2 <= 0.0) return false;
      const double s = (x - a).dot(ab) / len2;
      if (s <= 0.0 || s >= 1.0 || (a + s * ab - x).norm() > tolerance_m_) return false;
      targets = feature;
    } else {
      return false;  // a corner
    }
    for (int q : targets) {
      if (TryCollapse(p, q, fan, edges.at(q), find)) return true;
    }
    return false;
  }

  template <typename Find>
  bool TryCollapse(int p, int q, const std::vector<int>& fan, const std::vector<int>& removed,
                   Find& find) {
    // Link condition: p and q share no neighbour but the apexes of their common triangles
    // (else the collapse would fold the surface onto itself).
    std::vector<int> apexes;
    for (int t : removed) {
      for (int k = 0; k < 3; ++k) {
        const int r = position_of_[triangles_[t][k]];
        if (r != p && r != q) apexes.push_back(r);
      }
    }
    std::vector<int> p_neighbours, q_neighbours;
    auto neighbours = [&](int c, std::vector<int>* out) {
      for (int t : Incident(c)) {
        for (int k = 0; k < 3; ++k) {
          const int r = position_of_[triangles_[t][k]];
          if (r != c) out->push_back(r);
        }
      }
      std::sort(out->begin(), out->end());
      out->erase(std::unique(out->begin(), out->end()), out->end());
    };
    neighbours(p, &p_neighbours);
    neighbours(q, &q_neighbours);
    std::vector<int> common;
    std::set_intersection(p_neighbours.begin(), p_neighbours.end(), q_neighbours.begin(),
                          q_neighbours.end(), std::back_inserter(common));
    std::sort(apexes.begin(), apexes.end());
    apexes.erase(std::unique(apexes.begin(), apexes.end()), apexes.end());
    if (common != apexes) return false;

    // Per patch of the fan: its copy of q (from a removed triangle of that patch), and every
    // triangle of it on one plane and one affine attribute map.
    std::vector<int> target_copy(fan.size(), -1);
    for (int t : removed) {
      const int i = static_cast<int>(std::find(fan.begin(), fan.end(), t) - fan.begin());
      target_copy[find(i)] = triangles_[t][CornerOf(t, q)];
    }
    for (size_t i = 0; i < fan.size(); ++i) {
      const int root = find(static_cast<int>(i));
      if (target_copy[root] < 0) return false;  // a patch without the edge p-q
      size_t first = 0;
      while (find(static_cast<int>(first)) != root) ++first;
      if (first != i && !OnAffineMap(fan[first], triangles_[fan[i]])) return false;
    }
    // The moved triangles keep their orientation and some area.
    std::vector<std::pair<int, Eigen::Vector3i>> moved;
    for (size_t i = 0; i < fan.size(); ++i) {
      const int t = fan[i];
      if (std::find(removed.begin(), removed.end(), t) != removed.end()) continue;
      Eigen::Vector3i tri = triangles_[t];
      tri[CornerOf(t, p)] = target_copy[find(static_cast<int>(i))];
      const Eigen::Vector3d before = Normal(triangles_[t]);
      const Eigen::Vector3d cross =
          (Point(tri[1]) - Point(tri[0])).cross(Point(tri[2]) - Point(tri[0]));
      const double len = cross.norm();
      const double longest = std::max({(Point(tri[1]) - Point(tri[0])).norm(),
                                       (Point(tri[2]) - Point(tri[1])).norm(),
                                       (Point(tri[0]) - Point(tri[2])).norm()});
      // Height over the longest edge above the tolerance: no sliver that rounds away.
      if (len <= 0.0 || len / longest < 10.0 * tolerance_m_) return false;
      if ((cross / len).dot(before) < min_cos_) return false;
      moved.emplace_back(t, tri);
    }
    for (int t : removed) alive_[t] = 0;
    for (const auto& [t, tri] : moved) {
      triangles_[t] = tri;
      incident_[q].push_back(t);
    }
    incident_[p].clear();
    return true;
  }

  Mesh Compact() const {
    Mesh out;
    out.materials = mesh_.materials;
    out.projectors = mesh_.projectors;
    std::vector<int> new_index(mesh_.vertices.size(), -1);
    for (size_t t = 0; t < triangles_.size(); ++t) {
      if (!alive_[t]) continue;
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        int& v = new_index[triangles_[t][k]];
        if (v < 0) {
          v = out.num_vertices();
          const int old = triangles_[t][k];
          out.vertices.push_back(mesh_.vertices[old]);
          if (!mesh_.normals.empty()) out.normals.push_back(mesh_.normals[old]);
          if (!mesh_.uvs.empty()) out.uvs.push_back(mesh_.uvs[old]);
          if (!mesh_.colors_bgr.empty()) out.colors_bgr.push_back(mesh_.colors_bgr[old]);
        }
        tri[k] = v;
      }
      out.triangles.push_back(tri);
      if (!mesh_.triangle_materials.empty()) {
        out.triangle_materials.push_back(mesh_.triangle_materials[t]);
      }
    }
    return out;
  }

  const Mesh& mesh_;
  SimplifyOptions options_;
  double tolerance_m_ = 0.0;
  double texture_shift_m_ = 0.0;  // UV error allowed, as a slide over the surface (m)
  double min_cos_ = 1.0;
  int num_attributes_ = 0;
  std::vector<int> position_of_;      // per vertex
  std::vector<int> position_vertex_;  // per position: one vertex there
  int num_positions_ = 0;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<int>> incident_;  // per position
  std::vector<uint8_t> pinned_;  // per position
};

}  // namespace

Mesh SimplifyFlatPatches(const Mesh& mesh, const SimplifyOptions& options,
                         SimplifyStats* stats) {
  mesh.Check("SimplifyFlatPatches");
  options.Check();
  Mesh out = FlatPatchSimplifier(mesh, options).Run();
  if (stats) {
    stats->input_triangles = mesh.num_triangles();
    stats->input_vertices = mesh.num_vertices();
    stats->output_triangles = out.num_triangles();
    stats->output_vertices = out.num_vertices();
  }
  return out;
}

Mesh SubdivideMidpoints(const Mesh& input, int levels) {
  input.Check("SubdivideMidpoints");
  UNSEEN_CHECK(levels >= 0 && levels <= 6, "SubdivideMidpoints: levels {} not in [0, 6]", levels);
  Mesh mesh = input;
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      if (auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      const int m = mesh.num_vertices();
      mesh.vertices.push_back(0.5f * (mesh.vertices[a] + mesh.vertices[b]));
      if (!mesh.uvs.empty()) mesh.uvs.push_back(0.5f * (mesh.uvs[a] + mesh.uvs[b]));
      if (!mesh.normals.empty()) mesh.normals.push_back(mesh.normals[key.first]);
      if (!mesh.colors_bgr.empty()) {
        mesh.colors_bgr.push_back(0.5f * (mesh.colors_bgr[a] + mesh.colors_bgr[b]));
      }
      midpoint.emplace(key, m);
      return m;
    };
    std::vector<Eigen::Vector3i> triangles;
    std::vector<int> materials;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Eigen::Vector3i v = mesh.triangles[t];
      const int ab = mid(v[0], v[1]), bc = mid(v[1], v[2]), ca = mid(v[2], v[0]);
      for (const Eigen::Vector3i& tri :
           {Eigen::Vector3i(v[0], ab, ca), Eigen::Vector3i(ab, v[1], bc),
            Eigen::Vector3i(ca, bc, v[2]), Eigen::Vector3i(ab, bc, ca)}) {
        triangles.push_back(tri);
        if (!mesh.triangle_materials.empty()) materials.push_back(mesh.triangle_materials[t]);
      }
    }
    mesh.triangles = std::move(triangles);
    mesh.triangle_materials = std::move(materials);
  }
  return mesh;
}

}  // namespace unseen
