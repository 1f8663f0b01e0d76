// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/decimate.h"

#include <meshoptimizer.h>

#include <cmath>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {

void DecimateOptions::Check() const {
  UNSEEN_CHECK(max_triangles >= 4, "decimate.max_triangles {} must be >= 4", max_triangles);
  UNSEEN_CHECK(max_error_m >= 0.0 && std::isfinite(max_error_m),
               "decimate.max_error_m {} must be >= 0", max_error_m);
}

Mesh Decimate(const Mesh& mesh, const DecimateOptions& options, DecimateStats* stats) {
  options.Check();
  mesh.Check("Decimate: mesh");
  DecimateStats local;
  DecimateStats& s = stats ? *stats : local;
  s = DecimateStats();
  s.input_triangles = s.output_triangles = mesh.num_triangles();
  if (mesh.num_triangles() <= options.max_triangles || !mesh.triangle_materials.empty()) {
    return mesh;
  }
  static_assert(sizeof(Eigen::Vector3i) == 3 * sizeof(unsigned int));
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  const auto* indices = reinterpret_cast<const unsigned int*>(mesh.triangles.data());
  const auto* positions = reinterpret_cast<const float*>(mesh.vertices.data());
  const size_t index_count = 3 * mesh.triangles.size();
  // meshoptimizer's error is relative to the mesh's extent.
  const float scale = meshopt_simplifyScale(positions, mesh.vertices.size(), sizeof(float) * 3);
  const float relative_error =
      scale > 0.0f ? static_cast<float>(options.max_error_m) / scale : 0.0f;
  std::vector<unsigned int> kept(index_count);
  float result_error = 0.0f;
  kept.resize(meshopt_simplify(kept.data(), indices, index_count, positions, mesh.vertices.size(),
                               sizeof(float) * 3, 3 * size_t(options.max_triangles), relative_error,
                               meshopt_SimplifyLockBorder, &result_error));
  Mesh out = mesh;
  out.triangles.resize(kept.size() / 3);
  for (size_t t = 0; t < out.triangles.size(); ++t) {
    out.triangles[t] = Eigen::Vector3i(kept[3 * t], kept[3 * t + 1], kept[3 * t + 2]);
  }
  if (out.triangles.empty()) return mesh;  // never happens with an error bound; stay safe
  out.RemoveUnusedVertices();
  if (!out.normals.empty()) out.ComputeNormals();
  s.output_triangles = out.num_triangles();
  s.error_m = result_error * scale;
  return out;
}

}  // namespace unseen
