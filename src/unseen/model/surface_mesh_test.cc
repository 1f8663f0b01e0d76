// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/surface_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/model/test_rig_scene.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

using testing::MakeRigScene;
using testing::RigScene;

class SurfaceMesh : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = MakeRigScene();
    camera_ = scene_.rig.cameras[0].intrinsics;
    cam_from_obj_ = scene_.rig.cameras[0].cam_from_world() * scene_.world_from_obj;
    map_.depth = scene_.frame.depths[0];
    map_.texturedness = Texturedness(scene_.frame.images[0]);
    options_.untextured_vertices = true;  // exact depth everywhere, like a sensor's
  }
  // Distance of an object-frame point from the 100 mm cube's surface.
  static double OffCube(const Eigen::Vector3f& p) {
    return std::abs(p.cwiseAbs().maxCoeff() - 0.05f);
  }
  RenderBuffers RenderAtTruth(const Mesh& mesh) const {
    RenderBuffers buffers;
    Render(mesh, camera_, cam_from_obj_, camera_.ImageRect(), RenderOptions(), &buffers);
    return buffers;
  }
  RigScene scene_;
  PinholeCamera camera_;
  Rigid3d cam_from_obj_;
  DepthMap map_;
  SurfaceMeshOptions options_;
};

TEST_F(SurfaceMesh, CoversTheObjectOnItsSurfaceWithItsColours) {
  const cv::Mat& mask = scene_.object_masks[0];
  SurfaceMeshReport report;
  std::string why;
  const std::optional<Mesh> mesh = BuildSurfaceMesh(map_, scene_.frame.images[0], camera_,
                                                    cam_from_obj_, mask, options_, &report, &why);
  ASSERT_TRUE(mesh.has_value()) << why;
  EXPECT_EQ(report.vertices, mesh->num_vertices());
  EXPECT_GT(mesh->num_triangles(), 40);
  for (const Eigen::Vector3f& v : mesh->vertices) EXPECT_LT(OffCube(v), 0.004) << v.transpose();
  ASSERT_EQ(mesh->projectors.size(), 1u);
  // Rendered at the truth, it covers most of the object and nothing beside it, with the
  // image's colours.
  const RenderBuffers r = RenderAtTruth(*mesh);
  cv::Mat both, outside, grown;
  cv::bitwise_and(r.mask, mask, both);
  cv::dilate(mask, grown, cv::Mat::ones(3, 3, CV_8U));
  cv::bitwise_and(r.mask, ~grown, outside);
  EXPECT_GT(cv::countNonZero(both), 0.8 * cv::countNonZero(mask));
  EXPECT_EQ(cv::countNonZero(outside), 0);
  cv::Mat diff;
  cv::absdiff(r.color, scene_.frame.images[0], diff);
  const cv::Scalar mean_diff = cv::mean(diff, both);
  EXPECT_LT(mean_diff[0] + mean_diff[1] + mean_diff[2], 0.1);
  // Triangles face the camera that saw them.
  EXPECT_GT(cv::countNonZero(r.mask), 0);
}

TEST_F(SurfaceMesh, DropsTrianglesAcrossDepthStepsAndBeyondTheRadius) {
  // A mask grown well onto the wall: no triangle may bridge the cube and the wall.
  cv::Mat grown;
  cv::dilate(scene_.object_masks[0], grown, cv::Mat::ones(31, 31, CV_8U));
  SurfaceMeshReport report;
  const std::optional<Mesh> mesh = BuildSurfaceMesh(map_, scene_.frame.images[0], camera_,
                                                    cam_from_obj_, grown, options_, &report);
  ASSERT_TRUE(mesh.has_value());
  EXPECT_GT(report.dropped_discontinuity, 0);
  for (const Eigen::Vector3i& t : mesh->triangles) {
    int on_cube = 0;
    for (int k = 0; k < 3; ++k) on_cube += OffCube(mesh->vertices[t[k]]) < 0.004 ? 1 : 0;
    EXPECT_TRUE(on_cube == 0 || on_cube == 3) << t.transpose();
  }
  // With the object's extent, the wall is left out.
  options_.max_radius_m = 0.1;
  const std::optional<Mesh> cube_only = BuildSurfaceMesh(map_, scene_.frame.images[0], camera_,
                                                         cam_from_obj_, grown, options_, &report);
  ASSERT_TRUE(cube_only.has_value());
  EXPECT_GT(report.dropped_far, 0);
  for (const Eigen::Vector3f& v : cube_only->vertices) EXPECT_LT(OffCube(v), 0.004);
}

TEST_F(SurfaceMesh, ConcaveOutlinesAreNotFilled) {
  // The object's mask with a notch cut out: Delaunay's hull would span it.
  cv::Mat notched = scene_.object_masks[0].clone();
  const cv::Rect box = cv::boundingRect(notched);
  const cv::Rect notch(box.x + box.width / 2 - 8, box.y, 16, box.height * 2 / 3);
  notched(notch).setTo(0);
  const std::optional<Mesh> mesh =
      BuildSurfaceMesh(map_, scene_.frame.images[0], camera_, cam_from_obj_, notched, options_);
  ASSERT_TRUE(mesh.has_value());
  const RenderBuffers r = RenderAtTruth(*mesh);
  cv::Mat inner = cv::Mat::zeros(notched.size(), CV_8U);
  inner(cv::Rect(notch.x + 4, notch.y + 4, notch.width - 8, notch.height - 8)).setTo(255);
  cv::Mat covered;
  cv::bitwise_and(r.mask, inner, covered);
  EXPECT_EQ(cv::countNonZero(covered), 0);
}

TEST_F(SurfaceMesh, TexturelessDepthNeedsASensorsDepth) {
  // Image-based depth: vertices only where there is texture, fewer than with a sensor.
  SurfaceMeshReport with_sensor, textured_only;
  ASSERT_TRUE(BuildSurfaceMesh(map_, scene_.frame.images[0], camera_, cam_from_obj_,
                               scene_.object_masks[0], options_, &with_sensor));
  options_.untextured_vertices = false;
  ASSERT_TRUE(BuildSurfaceMesh(map_, scene_.frame.images[0], camera_, cam_from_obj_,
                               scene_.object_masks[0], options_, &textured_only));
  EXPECT_LT(textured_only.candidate_vertices, with_sensor.candidate_vertices);
}

TEST_F(SurfaceMesh, NothingToModelIsAStatusAndBadInputAnError) {
  std::string why;
  const cv::Mat empty = cv::Mat::zeros(camera_.height, camera_.width, CV_8U);
  EXPECT_FALSE(BuildSurfaceMesh(map_, scene_.frame.images[0], camera_, cam_from_obj_, empty,
                                options_, nullptr, &why));
  EXPECT_NE(why.find("empty"), std::string::npos) << why;
  DepthMap no_depth = map_;
  no_depth.depth = cv::Mat(map_.depth.size(), CV_32FC1, cv::Scalar(0));  // not in place
  EXPECT_FALSE(BuildSurfaceMesh(no_depth, scene_.frame.images[0], camera_, cam_from_obj_,
                                scene_.object_masks[0], options_, nullptr, &why));
  EXPECT_NE(why.find("vertices"), std::string::npos) << why;
  cv::Mat small;
  cv::resize(scene_.object_masks[0], small, cv::Size(100, 80));
  EXPECT_THROW(
      BuildSurfaceMesh(map_, scene_.frame.images[0], camera_, cam_from_obj_, small, options_),
      Error);
  options_.cell_px = 1;
  EXPECT_THROW(options_.Check(), Error);
}

}  // namespace
}  // namespace unseen
