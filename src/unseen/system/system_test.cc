// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/system.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "unseen/mesh/primitives.h"
#include "unseen/model/test_rig_scene.h"
#include "unseen/render/rasterizer.h"
#include "unseen/system/system_overlay.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// The lettered cube drifting and turning before a still camera.
Rigid3d CubeAt(int t) {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.4 + 0.02 * t, 0.6, 0.1 + 0.01 * t)),
                 Eigen::Vector3d(-0.08 + 0.004 * t, 0.01, 0.9));
}

InterestFilterBank MotionBank() {
  InterestFilterBank bank;
  bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  return bank;
}

Frame FrameOf(const cv::Mat& image, int t) {
  Frame frame;
  frame.frame_id = t;
  frame.time_s = t / 30.0;
  frame.images = {image};
  return frame;
}

// A known model: learning, then the moving cube is selected, posed and tracked; when it
// leaves the view the system reports it lost, then no object; when it comes back it is
// found again.
TEST(System, FindsTracksLosesAndFindsAgainAKnownObject) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  const cv::Mat background = testing::Background(camera.intrinsics, 21);
  SystemOptions options;
  options.reselect_after_lost_frames = 3;
  System system(rig, 0, cube, MotionBank(), options);
  int first_tracked = -1;
  for (int t = 0; t < 30; ++t) {
    const SystemStep step =
        system.Step(FrameOf(testing::RenderOverBackground(cube, camera, CubeAt(t), background), t));
    if (t < 7) {
      EXPECT_EQ(step.status, SystemStatus::kLearning) << "frame " << t;
    }
    if (step.status == SystemStatus::kTracking) {
      if (first_tracked < 0) {
        first_tracked = t;
        // The frame it was found in: the selected region is one of the candidates.
        EXPECT_FALSE(step.region.empty());
        EXPECT_NE(std::find(step.candidates.begin(), step.candidates.end(), step.region),
                  step.candidates.end());
      }
      ASSERT_TRUE(step.track.has_value());
      EXPECT_LT(Difference(step.track->world_from_obj, CubeAt(t)).translation, 0.005)
          << "frame " << t;
    } else if (first_tracked >= 0) {
      ADD_FAILURE() << "frame " << t << ": " << ToString(step.status) << " after tracking";
    }
  }
  ASSERT_GE(first_tracked, 7);
  EXPECT_LE(first_tracked, 15);
  EXPECT_TRUE(system.tracking());

  // The cube is gone: lost, then searched for (no object).
  std::vector<SystemStatus> gone;
  for (int t = 30; t < 40; ++t) gone.push_back(system.Step(FrameOf(background.clone(), t)).status);
  // The tracker calls a track lost after FailureOptions::lost_after_frames bad frames.
  EXPECT_NE(std::find(gone.begin(), gone.begin() + 3, SystemStatus::kLost), gone.begin() + 3);
  EXPECT_EQ(gone.back(), SystemStatus::kNoObject);
  EXPECT_FALSE(system.tracking());

  // It comes back elsewhere and is found again.
  bool found_again = false;
  for (int t = 40; t < 60 && !found_again; ++t) {
    const Rigid3d pose = CubeAt(t - 35);
    const SystemStep step =
        system.Step(FrameOf(testing::RenderOverBackground(cube, camera, pose, background), t));
    if (step.status == SystemStatus::kTracking) {
      found_again = true;
      EXPECT_LT(Difference(step.track->world_from_obj, pose).translation, 0.005);
    }
  }
  EXPECT_TRUE(found_again);
}

// Nothing moves: never an object, never a pose.
TEST(System, NoMovingObjectIsNoObject) {
  const Rig rig = testing::OneCameraRig();
  System system(rig, 0, MakeLetteredCube(0.096, 16), MotionBank());
  const cv::Mat still = testing::Background(rig.cameras[0].intrinsics, 4);
  for (int t = 0; t < 15; ++t) {
    const SystemStep step = system.Step(FrameOf(still, t));
    EXPECT_EQ(step.status, t < 7 ? SystemStatus::kLearning : SystemStatus::kNoObject);
    EXPECT_FALSE(step.track.has_value());
  }
}

TEST(System, RejectsWrongInput) {
  const Rig rig = testing::OneCameraRig();
  EXPECT_THROW(System(rig, 1, MakeLetteredCube(0.096, 16), MotionBank()), Error);
  EXPECT_THROW(System(rig, 0, MakeLetteredCube(0.096, 16), InterestFilterBank()), Error);
  SystemOptions options;
  options.reselect_after_lost_frames = 0;
  EXPECT_THROW(System(rig, 0, MakeLetteredCube(0.096, 16), MotionBank(), options), Error);
  // One camera without depth cannot model an unknown object.
  EXPECT_THROW(System(rig, 0, std::nullopt, MotionBank()), Error);
  System system(rig, 0, MakeLetteredCube(0.096, 16), MotionBank());
  Frame two;
  two.images = {cv::Mat(), cv::Mat()};
  EXPECT_THROW(system.Step(two), Error);
  Frame none;
  none.images = {cv::Mat()};
  EXPECT_EQ(system.Step(none).status, SystemStatus::kNoObject);  // a dropped frame
}

// An unknown object on a three-camera rig (plane sweep): the lettered cube, whose letters
// are its only texture, drifts slowly (under a pixel a frame) before a textured wall, so that
// few of its blocks move. Its first model covers the cube's silhouette when it is built
// from the whole selected region, a fragment of it when only from the moving blocks.
TEST(System, AnUnknownObjectsFirstModelCoversItWithImageDepth) {
  const Rig rig = testing::MakeRigScene().rig;  // left, right 80 mm to its right, top
  const PinholeCamera& cam = rig.cameras[0].intrinsics;
  const Mesh cube = MakeLetteredCube(0.1, 128);
  const Mesh wall = MakeTexturedBox(Eigen::Vector3d(1.6, 1.2, 0.02));
  const Rigid3d world_from_wall(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.0));
  auto cube_at = [](int t) {
    return Rigid3d(ExpSO3(Eigen::Vector3d(-0.4, 0.5 + 0.003 * t, 0.0)),
                   Eigen::Vector3d(0.01 + 0.0012 * t, 0.0, 0.6));
  };
  auto frame_at = [&](int t) {
    Frame frame;
    frame.frame_id = t;
    frame.time_s = t / 30.0;
    for (const RigCamera& c : rig.cameras) {
      RenderBuffers behind, seen;
      Render(wall, cam, c.cam_from_world() * world_from_wall, cam.ImageRect(), RenderOptions(),
             &behind);
      Render(cube, cam, c.cam_from_world() * cube_at(t), cam.ImageRect(), RenderOptions(), &seen);
      cv::Mat image = behind.color.clone();
      seen.color.copyTo(image, seen.mask);
      frame.images.push_back(image);
    }
    return frame;
  };
  // The share of the cube's silhouette in the reference camera that its first model covers.
  auto first_model_coverage = [&](bool from_motion) {
    SystemOptions options;
    options.first_model_from_motion_with_image_depth = from_motion;
    ModellerOptions modeller;
    modeller.depth.source = DepthSourceKind::kPlaneSweep;
    System system(rig, 0, std::nullopt, MotionBank(), options, TrackerOptions(), modeller);
    for (int t = 0; t < 30; ++t) {
      const SystemStep step = system.Step(frame_at(t));
      if (step.status != SystemStatus::kTracking) continue;
      RenderBuffers truth, model;
      Render(cube, cam, cube_at(t), cam.ImageRect(), RenderOptions(), &truth);
      Render(system.tracker()->model(), cam, step.track->world_from_obj, cam.ImageRect(),
             RenderOptions(), &model);
      return double(cv::countNonZero(truth.mask & model.mask)) / cv::countNonZero(truth.mask);
    }
    return 0.0;
  };
  const double whole = first_model_coverage(false), moving = first_model_coverage(true);
  // Measured: 0.63 of the silhouette from the whole region, 0.34 from the moving blocks.
  EXPECT_GT(whole, 0.5);
  EXPECT_LT(moving, 0.8 * whole);
}

// The overlay shows the interest (red tint), the selected region (cyan), the model's outline
// at the tracked pose (green) and leaves the rest of the image alone.
TEST(SystemOverlay, DrawsInterestRegionsModelAndStatus) {
  const Mesh cube = MakeLetteredCube(0.096, 16);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  const cv::Mat grey(camera.intrinsics.height, camera.intrinsics.width, CV_32FC3,
                     cv::Scalar::all(0.5));
  SystemStep step;
  step.frame_id = 3;
  step.status = SystemStatus::kTracking;
  step.interest = cv::Mat::zeros(grey.size(), CV_32FC1);
  step.interest(cv::Rect(20, 200, 40, 40)).setTo(1.0f);
  step.region = PixelRect{300, 50, 400, 150};
  step.candidates = {step.region, PixelRect{20, 150, 60, 190}};
  TrackResult track;
  track.world_from_obj = CubeAt(0);
  track.confidence = 0.9;
  step.track = track;
  cv::Mat image = grey.clone();
  DrawSystemOverlay(step, &cube, camera.intrinsics, camera.cam_from_world(), SystemOverlayOptions(),
                    &image);
  ASSERT_EQ(image.type(), CV_8UC3);
  const cv::Vec3b tinted = image.at<cv::Vec3b>(220, 40);
  const cv::Vec3b plain = image.at<cv::Vec3b>(image.rows - 10, image.cols - 10);
  EXPECT_GT(tinted[2], plain[2] + 50);
  EXPECT_LT(tinted[1], plain[1] - 50);
  EXPECT_EQ(image.at<cv::Vec3b>(100, 300), cv::Vec3b(255, 255, 0));  // the selected box
  // The outline: green pixels around the cube's projected centre, none far from it.
  const Eigen::Vector2d centre =
      camera.intrinsics.Project(camera.cam_from_world() * CubeAt(0).translation());
  cv::Mat green;
  cv::inRange(image, cv::Scalar(0, 200, 0), cv::Scalar(60, 255, 60), green);
  const cv::Rect near(static_cast<int>(centre.x()) - 120, static_cast<int>(centre.y()) - 120, 240,
                      240);
  const int all_green = cv::countNonZero(green);
  EXPECT_GT(all_green, 100);
  EXPECT_EQ(cv::countNonZero(green(near & cv::Rect(0, 0, image.cols, image.rows))), all_green);

  SystemOverlayOptions bad;
  bad.interest_alpha = 2.0;
  EXPECT_THROW(
      DrawSystemOverlay(step, &cube, camera.intrinsics, camera.cam_from_world(), bad, &image),
      Error);
}

}  // namespace
}  // namespace unseen
