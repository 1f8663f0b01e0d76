// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/tsdf_volume.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/core.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// Share of the vertices within `tolerance` of the 100 mm cube's surface, and the farthest.
double ShareOnCube(const Mesh& mesh, float tolerance, float* farthest) {
  int on = 0;
  *farthest = 0.0f;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    const float off = std::abs(v.cwiseAbs().maxCoeff() - 0.05f);
    on += off <= tolerance;
    *farthest = std::max(*farthest, off);
  }
  return double(on) / std::max(1, mesh.num_vertices());
}

// A camera `distance` from the object's origin in direction `from`, looking at the origin.
Rigid3d CamLookingAtOrigin(const Eigen::Vector3d& from, double distance) {
  const Eigen::Vector3d z = -from.normalized();
  const Eigen::Vector3d helper =
      std::abs(z.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d x = helper.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d obj_from_cam_rotation;
  obj_from_cam_rotation << x, y, z;
  const Rigid3d obj_from_cam(Eigen::Quaterniond(obj_from_cam_rotation), distance * -z);
  return obj_from_cam.Inverse();
}

class Tsdf : public ::testing::Test {
 protected:
  RenderBuffers See(const Mesh& mesh, const Rigid3d& cam_from_obj) const {
    RenderOptions options;
    options.write_color = false;
    RenderBuffers buffers;
    Render(mesh, camera_, cam_from_obj, camera_.ImageRect(), options, &buffers);
    return buffers;
  }
  void Fuse(TsdfVolume* volume, const Eigen::Vector3d& from) const {
    const Rigid3d cam_from_obj = CamLookingAtOrigin(from, 0.5);
    const RenderBuffers seen = See(cube_, cam_from_obj);
    volume->Integrate(seen.depth, seen.mask, camera_, cam_from_obj);
  }
  // Intersection over union of the true cube's and the mesh's silhouettes seen from `from`,
  // and the median depth difference where both are seen.
  void Compare(const Mesh& mesh, const Eigen::Vector3d& from, double* iou,
               double* median_mm) const {
    const Rigid3d cam_from_obj = CamLookingAtOrigin(from, 0.5);
    const RenderBuffers truth = See(cube_, cam_from_obj), got = See(mesh, cam_from_obj);
    const cv::Mat both = truth.mask & got.mask;
    *iou = double(cv::countNonZero(both)) / cv::countNonZero(truth.mask | got.mask);
    std::vector<float> errors;
    for (int y = 0; y < both.rows; ++y) {
      for (int x = 0; x < both.cols; ++x) {
        if (both.at<uint8_t>(y, x)) {
          errors.push_back(std::abs(truth.depth.at<float>(y, x) - got.depth.at<float>(y, x)));
        }
      }
    }
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    *median_mm = errors.empty() ? 1e9 : 1e3 * errors[errors.size() / 2];
  }

  const PinholeCamera camera_ = PinholeCamera::Centered(320, 240, 400.0);  // 1.25 mm px at 0.5 m
  const Mesh cube_ = MakeLetteredCube(0.1, 16);  // 100 mm about the origin
};

TEST_F(Tsdf, OneViewGivesTheSeenSideOnly) {
  TsdfVolume volume(Eigen::Vector3f::Zero(), 0.09f, TsdfOptions());
  EXPECT_FLOAT_EQ(volume.voxel_m(), 0.002f);  // 0.18 / 96 is below min_voxel_m
  const Eigen::Vector3d front(0.3, -0.4, -1.0);
  Fuse(&volume, front);
  const Mesh mesh = volume.ExtractMesh();
  ASSERT_GT(mesh.num_triangles(), 100);
  // On the surface but near the cube's edges, which the field rounds off.
  float farthest = 0.0f;
  EXPECT_GT(ShareOnCube(mesh, volume.voxel_m(), &farthest), 0.97);
  EXPECT_LT(farthest, 2.5f * volume.voxel_m());
  // The outline's pixels only say what is in front of them: the silhouette is a pixel
  // short all round (1.25 mm pixels, a 60x60 px silhouette).
  double iou, median_mm;
  Compare(mesh, front, &iou, &median_mm);
  EXPECT_GT(iou, 0.9);
  EXPECT_LT(median_mm, 0.5);
  Compare(mesh, -front, &iou, &median_mm);  // the far side was never seen
  EXPECT_LT(iou, 0.3);
}

TEST_F(Tsdf, ViewsAllAroundGiveTheWholeObject) {
  TsdfVolume volume(Eigen::Vector3f::Zero(), 0.09f, TsdfOptions());
  const Eigen::Vector3d views[] = {{0.3, -0.4, -1.0}, {-0.3, 0.4, 1.0}, {1.0, 0.3, 0.2},
                                   {-1.0, -0.2, 0.3}, {0.2, 1.0, -0.3}, {-0.2, -1.0, 0.3}};
  for (const Eigen::Vector3d& from : views) Fuse(&volume, from);
  EXPECT_EQ(volume.integrations(), 6);
  const Mesh mesh = volume.ExtractMesh();
  float farthest = 0.0f;
  EXPECT_GT(ShareOnCube(mesh, volume.voxel_m(), &farthest), 0.95);
  EXPECT_GT(ShareOnCube(mesh, 2.5f * volume.voxel_m(), &farthest), 0.999);
  EXPECT_LT(farthest, 5.0f * volume.voxel_m());
  // From directions none of the views had, the silhouette and the depth are the cube's:
  // the surface is closed and its triangles face outwards (back faces are culled).
  for (const Eigen::Vector3d& from :
       {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-1, 0.5, -0.7), Eigen::Vector3d(0.1, -1, -1)}) {
    double iou, median_mm;
    Compare(mesh, from, &iou, &median_mm);
    EXPECT_GT(iou, 0.95) << from.transpose();
    EXPECT_LT(median_mm, 0.5) << from.transpose();
  }
}

TEST_F(Tsdf, FreeSpaceAroundTheSilhouetteCarvesAWrongSurface) {
  TsdfVolume volume(Eigen::Vector3f::Zero(), 0.09f, TsdfOptions());
  // A first, wrong measurement: a cube half as large again.
  const Mesh big = MakeLetteredCube(0.15, 16);
  const Eigen::Vector3d front(0.3, -0.4, -1.0);
  const Rigid3d cam_from_obj = CamLookingAtOrigin(front, 0.5);
  const RenderBuffers wrong = See(big, cam_from_obj);
  volume.Integrate(wrong.depth, wrong.mask, camera_, cam_from_obj);
  // Then the right one from three sides, with the background behind (a wall 1 m away).
  const Mesh wall = MakeTexturedBox(Eigen::Vector3d(3.0, 3.0, 0.01));
  for (const Eigen::Vector3d& from :
       {front, Eigen::Vector3d(1.0, 0.3, -0.2), Eigen::Vector3d(-1.0, -0.2, -0.3)}) {
    const Rigid3d c = CamLookingAtOrigin(from, 0.5);
    const RenderBuffers object = See(cube_, c);
    const RenderBuffers behind =
        See(wall, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, 1.0)));
    cv::Mat depth = behind.depth.clone();
    object.depth.copyTo(depth, object.mask);
    for (int i = 0; i < 3; ++i) volume.Integrate(depth, object.mask, camera_, c);
  }
  const Mesh mesh = volume.ExtractMesh();
  double iou, median_mm;
  Compare(mesh, front, &iou, &median_mm);
  EXPECT_GT(iou, 0.9);
  EXPECT_LT(median_mm, 1.0);
}

TEST_F(Tsdf, BadInputIsAnError) {
  TsdfOptions options;
  options.truncation_voxels = 1.0;
  EXPECT_THROW(options.Check(), Error);
  EXPECT_THROW(TsdfVolume(Eigen::Vector3f::Zero(), 0.0f, TsdfOptions()), Error);
  TsdfVolume volume(Eigen::Vector3f::Zero(), 0.09f, TsdfOptions());
  const cv::Mat depth(camera_.height, camera_.width, CV_32FC1, cv::Scalar(0.5));
  const cv::Mat mask(camera_.height, camera_.width, CV_8UC1, cv::Scalar(255));
  const Rigid3d pose = CamLookingAtOrigin(Eigen::Vector3d(0, 0, -1), 0.5);
  EXPECT_THROW(volume.Integrate(depth(cv::Rect(0, 0, 10, 10)), mask, camera_, pose), Error);
  EXPECT_THROW(volume.Integrate(depth, cv::Mat(), camera_, pose), Error);
  EXPECT_TRUE(volume.ExtractMesh().triangles.empty());  // nothing fused yet
}

}  // namespace
}  // namespace unseen
