// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Lossy simplification to a triangle budget, for meshes that come out of measurements (the
// on-line model's fused surface has a vertex per voxel the surface crosses: thousands of
// triangles the tracker would render on every iteration). Quadric-error edge collapses
// (Garland & Heckbert 1997) by meshoptimizer: the surface moves by at most the given
// error, open borders (the silhouette of a surface seen from one side) stay where they
// are. Unlike SimplifyFlatPatches (simplify.h) this approximates.
#pragma once

#include "unseen/mesh/mesh.h"

namespace unseen {

struct DecimateOptions {
  int max_triangles = 2000;  // budget; a mesh within it is returned as it is
  // Largest distance the surface may move, metres; collapsing stops there even above the
  // budget.
  double max_error_m = 0.002;
  void Check() const;
};

struct DecimateStats {
  int input_triangles = 0, output_triangles = 0;
  double error_m = 0.0;  // the largest deviation meshoptimizer reports
};

// `mesh` within the budget: a subset of its vertices (attributes kept) joined by fewer
// triangles, normals recomputed when it had them; projectors and materials kept (per
// triangle materials are not: a mesh with several materials is returned as it is). Throws
// unseen::Error for an invalid mesh (Mesh::Check) or options.
Mesh Decimate(const Mesh& mesh, const DecimateOptions& options, DecimateStats* stats = nullptr);

}  // namespace unseen
