// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/silhouette_share.h"

#include <gtest/gtest.h>

#include <array>

#include "unseen/render/rasterizer.h"
#include "unseen/render/test_render_meshes.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

using render_testing::MakeCube;
using render_testing::TestCamera;

constexpr float kEdge = 0.1f;

std::array<Eigen::Vector3d, 8> CubeCorners() {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    corners[k] = Eigen::Vector3d(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1) * (kEdge / 2);
  }
  return corners;
}

// The share counted at full resolution: the cube rendered into a camera three times as wide
// and high with the same focal lengths, the original image in its middle.
double ReferenceShare(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj) {
  PinholeCamera wide = camera;
  wide.width = 3 * camera.width;
  wide.height = 3 * camera.height;
  wide.cx += camera.width;
  wide.cy += camera.height;
  RenderOptions options;
  options.write_color = false;
  RenderBuffers buffers;
  Render(mesh, wide, cam_from_obj, wide.ImageRect(), options, &buffers);
  const cv::Rect middle(camera.width, camera.height, camera.width, camera.height);
  const double total = cv::countNonZero(buffers.mask);
  return total > 0 ? cv::countNonZero(buffers.mask(middle)) / total : 0.0;
}

Rigid3d Turned(const Eigen::Vector3d& translation) {
  return Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 0.5).normalized())),
      translation);
}

TEST(SilhouetteShareInImage, IsOneForAnObjectWhollyInView) {
  const Mesh cube = MakeCube(kEdge);
  const PinholeCamera camera = TestCamera();
  EXPECT_EQ(SilhouetteShareInImage(cube, camera, Turned({0.0, 0.0, 0.5}), CubeCorners()), 1.0);
}

TEST(SilhouetteShareInImage, CountsThePartPastEachBorder) {
  const Mesh cube = MakeCube(kEdge);
  const PinholeCamera camera = TestCamera();
  // Centres past the right, left, bottom and top borders and a corner of the image, at
  // different distances: shares from nearly all to a sliver.
  const std::vector<Eigen::Vector3d> centres = {
      {0.40, 0.0, 0.5},   {0.36, 0.02, 0.4}, {-0.42, -0.03, 0.5}, {0.05, 0.27, 0.5},
      {0.0, -0.30, 0.55}, {0.40, 0.28, 0.5}, {0.35, 0.0, 0.5},    {0.46, 0.0, 0.5}};
  for (const Eigen::Vector3d& centre : centres) {
    const Rigid3d cam_from_obj = Turned(centre);
    const double expected = ReferenceShare(cube, camera, cam_from_obj);
    const double share = SilhouetteShareInImage(cube, camera, cam_from_obj, CubeCorners());
    EXPECT_NEAR(share, expected, 0.03) << "centre " << centre.transpose();
    EXPECT_GT(expected, 0.0) << "centre " << centre.transpose();
    EXPECT_LT(expected, 1.0) << "centre " << centre.transpose();
  }
}

TEST(SilhouetteShareInImage, IsZeroForAnObjectWhollyOutOfView) {
  const Mesh cube = MakeCube(kEdge);
  EXPECT_EQ(SilhouetteShareInImage(cube, TestCamera(), Turned({0.9, 0.0, 0.5}), CubeCorners()),
            0.0);
}

TEST(SilhouetteShareInImage, IsOneWhenTheBoxReachesBehindTheCamera) {
  // No whole silhouette to compare with: the part in view stands for the whole.
  const Mesh cube = MakeCube(kEdge);
  EXPECT_EQ(SilhouetteShareInImage(cube, TestCamera(), Turned({0.0, 0.0, 0.02}), CubeCorners()),
            1.0);
}

TEST(SilhouetteShareInImage, RejectsATinyRender) {
  const Mesh cube = MakeCube(kEdge);
  EXPECT_THROW(
      SilhouetteShareInImage(cube, TestCamera(), Turned({0.4, 0.0, 0.5}), CubeCorners(), 2), Error);
}

}  // namespace
}  // namespace unseen
