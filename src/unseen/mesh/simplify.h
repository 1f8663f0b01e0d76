// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Lossless simplification of flat patches. CAD exports and scans of boxy objects often cut a
// flat face into thousands of triangles (a 6 cm cube of 12 288 triangles) that the tracker
// pays for in every render. A vertex whose surroundings are flat and whose attributes (UV,
// colour, normal) are one affine function of position across them can be removed by
// collapsing it onto a neighbour: the surface, its silhouette and its appearance stay
// exactly as they were (up to float rounding), only the triangles that draw them change.
// Vertices on creases (where flat patches meet) and on open borders go only along a
// straight crease, so the outline is kept too. Nothing is approximated: a mesh with no flat
// patch comes back as it was.
#pragma once

#include "unseen/mesh/mesh.h"

namespace unseen {

struct SimplifyOptions {
  // For the users of a mesh (the tracker): whether to simplify it at all.
  bool enabled = true;
  // Triangles are coplanar when their unit normals differ by less than this (radians).
  double max_normal_angle_rad = 1e-4;
  // Points lie on a line or in a plane when within this share of the mesh's bounding
  // radius of it.
  double relative_tolerance = 1e-5;
  // Attributes are one affine function when every vertex of a patch is within this of it:
  // colour and normal components, and for UVs the distance the texture would slide over
  // the surface, as a share of the bounding radius (exported UVs are rarely exactly
  // affine: a real 6 cm cube's slide 0.01-0.07 mm, 0.8 mm at worst; 2e-3 of its radius
  // is 0.08 mm, a tenth of a pixel at 40 cm).
  double attribute_tolerance = 1e-5;
  double texture_shift_tolerance = 2e-3;
  void Check() const;
};

struct SimplifyStats {
  int input_triangles = 0, output_triangles = 0;
  int input_vertices = 0, output_vertices = 0;
};

// `mesh` with the vertices of its flat patches removed where that changes nothing rendered
// (see above); projectors and materials are kept. Throws unseen::Error for an invalid mesh
// (Mesh::Check) or options.
Mesh SimplifyFlatPatches(const Mesh& mesh, const SimplifyOptions& options = {},
                         SimplifyStats* stats = nullptr);

// The converse, exact as well: each triangle cut into four at its edges' midpoints
// (attributes interpolated, normals of the edge's first vertex), `levels` times; midpoints
// are shared by the triangles of an edge. Finer meshes that draw like the original (the
// way CAD exports cut flat faces), e.g. to test the above. Throws for an invalid mesh or
// levels outside [0, 6].
Mesh SubdivideMidpoints(const Mesh& mesh, int levels);

}  // namespace unseen
