// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/overlay.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "unseen/eval/test_sequence.h"
#include "unseen/mesh/primitives.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

PinholeCamera TestCamera() { return PinholeCamera::Centered(320, 240, 300.0); }

Rigid3d CubePose() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.4, 0.6, 0.2)), Eigen::Vector3d(0.02, 0.03, 0.6));
}

// Full-image coverage mask of the mesh (reference for the outline).
cv::Mat FullMask(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj) {
  RenderOptions options;
  options.write_color = false;
  options.cull_back_faces = false;
  RenderBuffers buffers;
  Render(mesh, camera, cam_from_obj, camera.ImageRect(), options, &buffers);
  return buffers.mask;
}

std::string TempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("unseen_overlay_test_" + name)).string();
}

TEST(Overlay, OutlineLiesOnSilhouetteBoundary) {
  const Mesh cube = MakeLetteredCube(0.1, 32);
  const PinholeCamera camera = TestCamera();
  const cv::Mat mask = FullMask(cube, camera, CubePose());
  ASSERT_GT(cv::countNonZero(mask), 1000);

  const auto outline = SilhouetteOutline(cube, camera, CubePose(), 4);
  ASSERT_EQ(outline.size(), 1u);  // one convex silhouette
  std::set<std::pair<int, int>> on_outline;
  for (const cv::Point& p : outline[0]) {
    ASSERT_TRUE(camera.InImage(Eigen::Vector2d(p.x, p.y)));
    EXPECT_TRUE(testing::IsMaskBoundary(mask, p.x, p.y)) << p;
    on_outline.insert({p.x, p.y});
  }
  int boundary = 0, covered = 0;
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      if (!testing::IsMaskBoundary(mask, x, y)) continue;
      ++boundary;
      covered += on_outline.count({x, y});
    }
  }
  EXPECT_EQ(covered, boundary);
}

TEST(Overlay, ObjectOutOfViewGivesNoOutline) {
  const Mesh cube = MakeLetteredCube(0.1, 32);
  const Rigid3d behind(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -1.0));
  EXPECT_TRUE(SilhouetteOutline(cube, TestCamera(), behind).empty());
  const Rigid3d aside(Eigen::Quaterniond::Identity(), Eigen::Vector3d(5.0, 0, 1.0));
  EXPECT_TRUE(SilhouetteOutline(cube, TestCamera(), aside).empty());
}

TEST(Overlay, DrawsEstimateAndGroundTruthInTheirColours) {
  const Mesh cube = MakeLetteredCube(0.1, 32);
  const PinholeCamera camera = TestCamera();
  // The world frame is the camera frame moved; the estimate is in the world frame.
  const Rigid3d world_from_cam(ExpSO3(Eigen::Vector3d(0, 0.1, 0)), Eigen::Vector3d(0.1, 0, 0));
  const Rigid3d cam_from_world = world_from_cam.Inverse();
  const Rigid3d world_from_obj = world_from_cam * CubePose();
  const cv::Mat mask = FullMask(cube, camera, CubePose());

  OverlayOptions options;
  options.line_thickness_px = 1;
  PoseRecord record;
  record.frame = 7;
  record.confidence = 0.8;
  record.world_from_obj = world_from_obj;

  // Tracking: green pixels exactly on the silhouette boundary.
  cv::Mat image(camera.height, camera.width, CV_8UC3, cv::Scalar(0, 0, 0));
  OverlayFrame frame{7, &record, std::nullopt};
  DrawOverlay(cube, camera, cam_from_world, frame, options, &image);
  int green = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (image.at<cv::Vec3b>(y, x) != cv::Vec3b(0, 255, 0)) continue;
      ++green;
      EXPECT_TRUE(testing::IsMaskBoundary(mask, x, y)) << x << "," << y;
    }
  }
  EXPECT_GT(green, 100);
  // The status line is drawn (white text on black in the top-left corner).
  EXPECT_GT(cv::countNonZero(image(cv::Rect(0, 0, 100, 25)).reshape(1)), 20);

  // Lost: red outline; ground truth 10 px to the right: blue outline.
  record.status = TrackStatus::kLost;
  Rigid3d world_from_obj_gt =
      world_from_cam *
      Rigid3d(CubePose().rotation(), CubePose().translation() + Eigen::Vector3d(0.02, 0, 0));
  frame.ground_truth = world_from_obj_gt;
  image.setTo(cv::Scalar(0, 0, 0));
  DrawOverlay(cube, camera, cam_from_world, frame, options, &image);
  const cv::Mat gt_mask = FullMask(cube, camera, cam_from_world * world_from_obj_gt);
  int red = 0, blue = 0;
  for (int y = 30; y < image.rows; ++y) {  // below the status line
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b px = image.at<cv::Vec3b>(y, x);
      if (px == cv::Vec3b(0, 0, 255)) {
        ++red;
        EXPECT_TRUE(testing::IsMaskBoundary(mask, x, y));
      } else if (px == cv::Vec3b(255, 128, 0)) {
        ++blue;
        EXPECT_TRUE(testing::IsMaskBoundary(gt_mask, x, y));
      }
      EXPECT_NE(px, cv::Vec3b(0, 255, 0));
    }
  }
  EXPECT_GT(red, 100);
  EXPECT_GT(blue, 100);

  // Lost poses hidden on request.
  options.draw_lost_pose = false;
  options.draw_ground_truth = false;
  image.setTo(cv::Scalar(0, 0, 0));
  DrawOverlay(cube, camera, cam_from_world, frame, options, &image);
  EXPECT_EQ(cv::countNonZero(image(cv::Rect(0, 30, camera.width, camera.height - 30)).reshape(1)),
            0);
}

TEST(Overlay, DrawRejectsBadInput) {
  const Mesh cube = MakeLetteredCube(0.1, 32);
  const PinholeCamera camera = TestCamera();
  cv::Mat wrong_size(100, 100, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_THROW(DrawOverlay(cube, camera, Rigid3d(), {}, {}, &wrong_size), Error);
  cv::Mat wrong_type(camera.height, camera.width, CV_32FC3);
  EXPECT_THROW(DrawOverlay(cube, camera, Rigid3d(), {}, {}, &wrong_type), Error);
  OverlayOptions bad;
  bad.line_thickness_px = 0;
  EXPECT_THROW(bad.Check(), Error);
  bad = OverlayOptions();
  bad.tracking_color = cv::Scalar(0, 300, 0);
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Overlay, SinkWritesPngFolderAndVideos) {
  const cv::Size size(64, 48);
  cv::Mat image(size, CV_8UC3, cv::Scalar(10, 200, 30));

  const std::string folder = TempPath("frames");
  fs::remove_all(folder);
  {
    OverlaySink sink(folder, 30.0, size);
    EXPECT_FALSE(sink.is_video());
    sink.Write(image, 0);
    sink.Write(image, 5);
    EXPECT_THROW(sink.Write(cv::Mat(10, 10, CV_8UC3), 6), Error);
  }
  EXPECT_TRUE(fs::exists(folder + "/frame_000005.png"));
  const cv::Mat back = cv::imread(folder + "/frame_000000.png");
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(back.at<cv::Vec3b>(3, 3), cv::Vec3b(10, 200, 30));
  fs::remove_all(folder);

  for (const char* ext : {".avi", ".mp4"}) {
    const std::string video = TempPath(std::string("video") + ext);
    fs::remove(video);
    {
      OverlaySink sink(video, 30.0, size);
      EXPECT_TRUE(sink.is_video());
      for (int i = 0; i < 5; ++i) sink.Write(image, i);
    }
    EXPECT_GT(fs::file_size(video), 0u) << video;
    fs::remove(video);
  }

  EXPECT_THROW(OverlaySink(TempPath("bad.xyz"), 30.0, size), Error);
  EXPECT_THROW(OverlaySink("/nonexistent_dir/out.mp4", 30.0, size), Error);
  EXPECT_THROW(OverlaySink(TempPath("zero_fps.avi"), 0.0, size), Error);
}

}  // namespace
}  // namespace unseen
