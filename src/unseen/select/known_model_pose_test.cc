// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/known_model_pose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

Frame OneImage(const cv::Mat& image) {
  Frame frame;
  frame.images = {image};
  return frame;
}

// The cube at orientations the bank does not hold exactly: the pose is found, refined by
// the tracker to well within the tracking criterion, and the tracker goes on from it.
TEST(KnownModelPoser, FindsTheCubeFromItsBox) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  Tracker tracker(rig, cube);
  KnownModelPoser poser(&tracker);
  const cv::Mat background = testing::Background(camera.intrinsics, 3);
  const Eigen::Vector3d rotations[] = {{0.45, 0.7, 0.1}, {-1.2, 0.3, 2.0}, {2.5, -0.4, 0.9}};
  const Eigen::Vector3d places[] = {{-0.05, 0.01, 0.9}, {0.08, -0.02, 1.1}, {0.0, 0.03, 0.8}};
  for (int k = 0; k < 3; ++k) {
    const Rigid3d truth(ExpSO3(rotations[k]), places[k]);
    const Frame frame = OneImage(testing::RenderOverBackground(cube, camera, truth, background));
    const PixelRect box = SilhouetteBox(cube, camera.intrinsics, truth);
    const KnownModelPoseResult r = poser.Find(frame, 0, box);
    ASSERT_TRUE(r.found) << "pose " << k << ": " << r.BriefReport();
    const PoseDifference d = Difference(truth, r.world_from_obj);
    EXPECT_LT(d.translation, 0.005) << "pose " << k;
    EXPECT_LT(d.rotation_rad, 1.0 * kDeg) << "pose " << k;
    EXPECT_GT(r.box_iou, 0.9);
    EXPECT_GE(r.candidates_aligned, 1);
    // The tracker was initialised at the found pose: the same frame again stays there.
    EXPECT_EQ(tracker.status(), TrackStatus::kTracking);
    const TrackResult again = tracker.Track(frame);
    EXPECT_LT(Difference(truth, again.world_from_obj).translation, 0.005)
        << "pose " << k << ": " << r.BriefReport() << "; again: " << again.BriefReport();
  }
}

// Where the object is not, there is no pose: a box over the empty background.
TEST(KnownModelPoser, NoPoseWhereTheObjectIsNot) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  Tracker tracker(rig, cube);
  KnownModelPoser poser(&tracker);
  const Frame frame = OneImage(testing::Background(rig.cameras[0].intrinsics, 5));
  const KnownModelPoseResult r = poser.Find(frame, 0, PixelRect{200, 80, 290, 170});
  EXPECT_FALSE(r.found) << r.BriefReport();
  EXPECT_EQ(r.candidates_aligned, poser.Candidates(frame, 0, PixelRect{200, 80, 290, 170}).size());
}

// A model without texture has only its silhouette; whatever it answers, it never calls a
// wrong pose found.
TEST(KnownModelPoser, AModelWithoutTextureIsNeverPlacedWrongly) {
  const Mesh cube = testing::FlatCube();
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  Tracker tracker(rig, cube);
  KnownModelPoser poser(&tracker);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)), Eigen::Vector3d(-0.05, 0.01, 0.9));
  const Frame frame = OneImage(testing::RenderOverBackground(
      cube, camera, truth, testing::Background(camera.intrinsics, 9)));
  const KnownModelPoseResult r =
      poser.Find(frame, 0, SilhouetteBox(cube, camera.intrinsics, truth));
  if (r.found) {
    // A cube's silhouette repeats every 90°: the position must be right, and the
    // orientation one of the cube's symmetries (not checked here).
    EXPECT_LT(Difference(truth, r.world_from_obj).translation, 0.01) << r.BriefReport();
  }
}

TEST(KnownModelPoser, RejectsWrongInput) {
  const Mesh cube = MakeLetteredCube(0.096, 16);
  const Rig rig = testing::OneCameraRig();
  Tracker tracker(rig, cube);
  KnownModelPoseOptions options;
  options.views.num_directions = 10;
  options.views.num_rolls = 2;
  options.max_candidates = 0;
  EXPECT_THROW(KnownModelPoser(&tracker, options), Error);
  options.max_candidates = 2;
  options.min_box_iou = 2.0;
  EXPECT_THROW(KnownModelPoser(&tracker, options), Error);
  options.min_box_iou = 0.5;
  KnownModelPoser poser(&tracker, options);
  const Frame frame = OneImage(testing::Background(rig.cameras[0].intrinsics, 1));
  EXPECT_THROW(poser.Find(frame, 1, PixelRect{0, 0, 20, 20}), Error);    // no camera 1
  EXPECT_THROW(poser.Find(frame, 0, PixelRect{}), Error);                // empty box
  EXPECT_THROW(poser.Find(Frame{}, 0, PixelRect{0, 0, 20, 20}), Error);  // no image
}

TEST(SilhouetteBox, BoundsTheProjectedModel) {
  const Mesh cube = MakeLetteredCube(0.1, 16);
  const PinholeCamera camera = testing::Camera512();
  // Face-on at 1 m: the front face (10 cm) spans fx * 0.1 / 0.95 px, centred.
  const Rigid3d cam_from_obj(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.0));
  const PixelRect box = SilhouetteBox(cube, camera, cam_from_obj);
  const double side = camera.fx * 0.1 / 0.95;
  EXPECT_NEAR(box.width(), side, 2.0);
  EXPECT_NEAR(box.height(), side, 2.0);
  EXPECT_NEAR(0.5 * (box.x0 + box.x1), camera.cx + 0.5, 1.0);
  // Behind the camera: no pixel.
  EXPECT_TRUE(SilhouetteBox(cube, camera,
                            Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -1.0)))
                  .empty());
}

// The view bank's proposals for a cube turned 60 degrees from any pose the tracker saw:
// one of the first four is within 15 degrees of it (the tracker's alignment does the rest).
TEST(ViewBankProposer, ProposesTheOrientationOfATurnedCube) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  const cv::Mat background = testing::Background(camera.intrinsics, 3);
  Tracker tracker(rig, cube);
  const PoseProposer propose = ViewBankProposer(&tracker);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.0, 60.0 * kDeg, 0.0)) *
                          ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)),
                      Eigen::Vector3d(0.04, 0.03, 1.0));
  const Frame frame =
      OneImage(testing::RenderOverBackground(cube, camera, truth, background));
  // The cube's box: its silhouette's bounding box at the true pose.
  RenderBuffers buffers;
  Render(cube, camera.intrinsics, camera.cam_from_world() * truth, camera.intrinsics.ImageRect(),
         RenderOptions{}, &buffers);
  const cv::Rect bounds = cv::boundingRect(buffers.mask);
  const PixelRect box{bounds.x, bounds.y, bounds.x + bounds.width, bounds.y + bounds.height};
  const std::vector<Rigid3d> proposals = propose(frame, 0, box);
  ASSERT_GE(proposals.size(), 4u);
  double closest = 1e9;
  for (int k = 0; k < 4; ++k) {
    closest = std::min(closest, Difference(proposals[k], truth).rotation_rad);
  }
  EXPECT_LT(closest, 15.0 * kDeg);
  // A box with nothing of the model in it is no crash: proposals (wrong ones) or none.
  EXPECT_NO_THROW(propose(OneImage(background), 0, PixelRect{10, 10, 60, 60}));
}

// Views rendered beside tracking propose what views rendered at the first call do.
TEST(ViewBankProposer, ViewsRenderedInTheBackgroundProposeTheSame) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  Tracker tracker(rig, cube);
  const PoseProposer at_first_use = ViewBankProposer(&tracker);
  auto background =
      std::make_shared<BackgroundViewBank>(tracker.shared_given_model(), ViewBankOptions{});
  background->Wait();
  const PoseProposer in_background = ViewBankProposer(&tracker, {}, background);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.3, -0.8, 0.2)), Eigen::Vector3d(-0.02, 0.01, 0.9));
  const Frame frame = OneImage(testing::RenderOverBackground(
      cube, camera, truth, testing::Background(camera.intrinsics, 5)));
  const PixelRect box = SilhouetteBox(cube, camera.intrinsics, camera.cam_from_world() * truth);
  const std::vector<Rigid3d> expected = at_first_use(frame, 0, box);
  const std::vector<Rigid3d> proposed = in_background(frame, 0, box);
  EXPECT_EQ(background->TakeIfDone(), nullptr);  // the proposer took the views
  ASSERT_FALSE(expected.empty());
  ASSERT_EQ(proposed.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) {
    EXPECT_LT(Difference(proposed[k], expected[k]).rotation_rad, 1e-9) << k;
    EXPECT_LT(Difference(proposed[k], expected[k]).translation, 1e-9) << k;
  }
  // A tracker dropped while its views are rendered beside it cancels them.
  Tracker dropped(rig, cube);
  dropped.SetPoseProposer(ViewBankProposer(&dropped, {}, ViewBankBuild::kInBackground));
}

}  // namespace
}  // namespace unseen
