// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/simplify.h"

#include <gtest/gtest.h>

#include "unseen/mesh/primitives.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(SimplifyFlatPatches, AFinelyCutCubeComesBackToItsFaces) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Mesh fine = SubdivideMidpoints(cube, 4);  // 12 -> 3072 triangles
  ASSERT_EQ(fine.num_triangles(), 256 * cube.num_triangles());
  SimplifyStats stats;
  const Mesh simple = SimplifyFlatPatches(fine, {}, &stats);
  EXPECT_NO_THROW(simple.Check());
  EXPECT_EQ(stats.input_triangles, fine.num_triangles());
  EXPECT_EQ(stats.output_triangles, simple.num_triangles());
  // Every vertex but the corners can go: two triangles a face.
  EXPECT_EQ(simple.num_triangles(), cube.num_triangles());
  EXPECT_EQ(simple.materials.size(), cube.materials.size());
  Eigen::Vector3f c0, c1;
  float r0 = 0, r1 = 0;
  fine.BoundingSphere(&c0, &r0);
  simple.BoundingSphere(&c1, &r1);
  EXPECT_NEAR(r0, r1, 1e-6);
}

TEST(SimplifyFlatPatches, KeepsWhatTheAttributesNeed) {
  // One interior vertex of a face carries a UV off its face's affine map: the texture bends
  // there, so that vertex (and the triangles around it) must stay.
  Mesh fine = SubdivideMidpoints(MakeLetteredCube(0.096, 64), 2);
  int bent = -1;
  const Eigen::Vector3f centre_of_face(0.0f, 0.0f, 0.048f);
  for (int v = 0; v < fine.num_vertices(); ++v) {
    if ((fine.vertices[v] - centre_of_face).norm() < 1e-6f) bent = v;
  }
  ASSERT_GE(bent, 0);
  fine.uvs[bent] += Eigen::Vector2f(0.01f, 0.0f);
  const Mesh simple = SimplifyFlatPatches(fine);
  EXPECT_GT(simple.num_triangles(), 12);
  EXPECT_LT(simple.num_triangles(), fine.num_triangles());
  bool kept = false;
  for (int v = 0; v < simple.num_vertices(); ++v) {
    if ((simple.vertices[v] - centre_of_face).norm() < 1e-6f) kept = true;
  }
  EXPECT_TRUE(kept);
}

TEST(SimplifyFlatPatches, LeavesCurvedSurfacesAlone) {
  const Mesh sphere = MakeTexturedSphere(0.05, 12, 24, cv::Mat());
  const Mesh simple = SimplifyFlatPatches(sphere);
  // The poles' rings are fans of degenerate-free triangles on a curved surface: nothing
  // is flat, so nothing goes.
  EXPECT_EQ(simple.num_triangles(), sphere.num_triangles());
}

TEST(SimplifyFlatPatches, VertexColoursAreAttributesToo) {
  Mesh coloured = SubdivideMidpoints(MakeLetteredCube(0.096, 64), 2);
  coloured.colors_bgr.resize(coloured.vertices.size());
  for (int v = 0; v < coloured.num_vertices(); ++v) {
    // A colour that varies non-linearly over each face: most vertices must stay.
    const Eigen::Vector3f& p = coloured.vertices[v];
    const float s = 0.5f + 200.0f * p.x() * p.y() * p.z() / 0.048f;
    coloured.colors_bgr[v] = Eigen::Vector3f(s, 0.5f, 1.0f - s);
  }
  const Mesh simple = SimplifyFlatPatches(coloured);
  EXPECT_GT(simple.num_triangles(), coloured.num_triangles() / 2);
}

TEST(SimplifyFlatPatches, RejectsBadInput) {
  Mesh empty;
  EXPECT_THROW(SimplifyFlatPatches(empty), Error);
  SimplifyOptions options;
  options.relative_tolerance = -1.0;
  EXPECT_THROW(SimplifyFlatPatches(MakeLetteredCube(0.1, 16), options), Error);
}

}  // namespace
}  // namespace unseen
