// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A mesh simplified by SimplifyFlatPatches (mesh/simplify.h) draws as the original did:
// colour, silhouette and depth.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/mesh/primitives.h"
#include "unseen/mesh/simplify.h"
#include "unseen/render/rasterizer.h"

namespace unseen {
namespace {

// Colour, mask and depth of `mesh` seen at a turned pose from the thesis camera.
RenderBuffers Draw(const Mesh& mesh) {
  const PinholeCamera camera = PinholeCamera::Centered(512, 256, 837.3);
  const Rigid3d cam_from_obj(ExpSO3(Eigen::Vector3d(0.5, 0.6, 0.2)),
                             Eigen::Vector3d(0.01, -0.005, 0.6));
  RenderBuffers buffers;
  Render(mesh, camera, cam_from_obj, camera.ImageRect(), RenderOptions(), &buffers);
  return buffers;
}

void ExpectDrawnAlike(const Mesh& a, const Mesh& b) {
  const RenderBuffers ra = Draw(a), rb = Draw(b);
  const int covered = cv::countNonZero(ra.mask);
  ASSERT_GT(covered, 5000);
  cv::Mat mask_diff;
  cv::compare(ra.mask, rb.mask, mask_diff, cv::CMP_NE);
  // Pixels whose centre lies on an edge may fall either way under rounding.
  EXPECT_LE(cv::countNonZero(mask_diff), covered / 500);
  cv::Mat both;
  cv::bitwise_and(ra.mask, rb.mask, both);
  cv::Mat colour_diff;
  cv::absdiff(ra.color, rb.color, colour_diff);
  cv::Mat big = colour_diff.reshape(1) > 0.02f;
  cv::Mat big_any;
  cv::reduce(big.reshape(3).reshape(1, big.rows * big.cols / 3), big_any, 1, cv::REDUCE_MAX);
  EXPECT_LE(cv::countNonZero(big_any.reshape(1, ra.mask.rows) & both), covered / 500);
  double max_depth_diff = 0.0;
  cv::Mat depth_diff;
  cv::absdiff(ra.depth, rb.depth, depth_diff);
  cv::minMaxLoc(depth_diff, nullptr, &max_depth_diff, nullptr, nullptr, both);
  EXPECT_LT(max_depth_diff, 1e-5);
}

TEST(SimplifiedMesh, DrawsLikeTheFinelyCutOne) {
  const Mesh fine = SubdivideMidpoints(MakeLetteredCube(0.096, 64), 4);
  const Mesh simple = SimplifyFlatPatches(fine);
  ASSERT_LT(simple.num_triangles(), fine.num_triangles() / 100);
  ExpectDrawnAlike(fine, simple);
  // And the finely cut one like the original.
  ExpectDrawnAlike(MakeLetteredCube(0.096, 64), fine);
}

TEST(SimplifiedMesh, KeptVerticesKeepTheirTextureBend) {
  Mesh fine = SubdivideMidpoints(MakeLetteredCube(0.096, 64), 2);
  for (int v = 0; v < fine.num_vertices(); ++v) {
    if ((fine.vertices[v] - Eigen::Vector3f(0.0f, 0.0f, 0.048f)).norm() < 1e-6f) {
      fine.uvs[v] += Eigen::Vector2f(0.01f, 0.0f);
    }
  }
  ExpectDrawnAlike(fine, SimplifyFlatPatches(fine));
}

TEST(SimplifiedMesh, VertexColoursDrawAlike) {
  Mesh coloured = SubdivideMidpoints(MakeLetteredCube(0.096, 64), 2);
  coloured.uvs.clear();
  for (Material& m : coloured.materials) m.texture.release();
  coloured.colors_bgr.resize(coloured.vertices.size());
  for (int v = 0; v < coloured.num_vertices(); ++v) {
    const Eigen::Vector3f& p = coloured.vertices[v];
    const float s = 0.5f + 200.0f * p.x() * p.y() * p.z() / 0.048f;
    coloured.colors_bgr[v] = Eigen::Vector3f(s, 0.5f, 1.0f - s);
  }
  ExpectDrawnAlike(coloured, SimplifyFlatPatches(coloured));
}

}  // namespace
}  // namespace unseen
