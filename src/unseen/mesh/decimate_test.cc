// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/decimate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "unseen/mesh/primitives.h"
#include "unseen/mesh/simplify.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

double Area(const Mesh& mesh) {
  double area = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[t[0]];
    area += 0.5 * (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
  }
  return area;
}

TEST(Decimate, ASphereWithinTheBudgetAndTheError) {
  Mesh sphere = MakeTexturedSphere(0.05, 60, 120);  // 14 160 triangles
  sphere.uvs.clear();
  sphere.materials.clear();
  sphere.triangle_materials.clear();
  sphere.projectors.resize(1);
  sphere.projectors[0].image = cv::Mat(4, 4, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  sphere.projectors[0].camera = PinholeCamera::Centered(4, 4, 10.0);
  DecimateOptions options;
  options.max_triangles = 1500;
  options.max_error_m = 0.002;
  DecimateStats stats;
  const Mesh small = Decimate(sphere, options, &stats);
  small.Check("decimated sphere");
  EXPECT_EQ(stats.input_triangles, sphere.num_triangles());
  EXPECT_EQ(stats.output_triangles, small.num_triangles());
  EXPECT_LE(small.num_triangles(), 1500);
  EXPECT_GT(small.num_triangles(), 500);
  EXPECT_LE(stats.error_m, 0.002 + 1e-6);
  EXPECT_EQ(small.projectors.size(), 1u);
  ASSERT_EQ(small.normals.size(), small.vertices.size());
  // A subset of the vertices, still on the sphere, and the surface nearly as large (the
  // chords of the coarser triangles cut in a little).
  for (const Eigen::Vector3f& v : small.vertices) ASSERT_NEAR(v.norm(), 0.05f, 1e-5f);
  EXPECT_NEAR(Area(small) / Area(sphere), 1.0, 0.03);
  // Still facing outwards (the texture seam's duplicated vertices leave a few slivers
  // across it, edge-on).
  int outwards = 0;
  for (const Eigen::Vector3i& t : small.triangles) {
    const Eigen::Vector3f& a = small.vertices[t[0]];
    const Eigen::Vector3f n = (small.vertices[t[1]] - a).cross(small.vertices[t[2]] - a);
    const Eigen::Vector3f centre = a + small.vertices[t[1]] + small.vertices[t[2]];
    const float cosine = n.normalized().dot(centre.normalized());
    ASSERT_GT(cosine, -0.1f);
    outwards += cosine > 0.9f;
  }
  EXPECT_GT(outwards, 0.98 * small.num_triangles());
}

TEST(Decimate, KeepsTheOutlineOfAnOpenSurface) {
  // A flat 0.1 m square cut into 2x16x16 triangles: as few as the budget allows, the
  // border where it was.
  Mesh grid;
  const int n = 16;
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) grid.vertices.emplace_back(0.1f * x / n, 0.1f * y / n, 0.0f);
  }
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const int i = y * (n + 1) + x;
      grid.triangles.emplace_back(i, i + 1, i + n + 2);
      grid.triangles.emplace_back(i, i + n + 2, i + n + 1);
    }
  }
  DecimateOptions options;
  options.max_triangles = 100;
  const Mesh small = Decimate(grid, options);
  EXPECT_LE(small.num_triangles(), 100);
  EXPECT_NEAR(Area(small), 0.01, 1e-6);  // the outline is kept, so is the area
  Eigen::Vector3f lo, hi;
  small.BoundingBox(&lo, &hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f(0, 0, 0)));
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(0.1f, 0.1f, 0.0f)));
}

TEST(Decimate, WithinTheBudgetOrBadOptions) {
  const Mesh cube = MakeLetteredCube(0.1, 16);
  DecimateStats stats;
  const Mesh same = Decimate(cube, DecimateOptions(), &stats);
  EXPECT_EQ(same.num_triangles(), cube.num_triangles());
  EXPECT_EQ(stats.output_triangles, cube.num_triangles());
  DecimateOptions bad;
  bad.max_triangles = 2;
  EXPECT_THROW(Decimate(cube, bad), Error);
  bad = DecimateOptions();
  bad.max_error_m = -1.0;
  EXPECT_THROW(Decimate(cube, bad), Error);
}

}  // namespace
}  // namespace unseen
