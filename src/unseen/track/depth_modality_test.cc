// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The depth modality's rows on their own: none at the true pose, none from a surface in
// front of the object (an occluder) unless most of the object is behind it, and rows kept on
// steep faces whose measurement sits pixels off.
#include <cmath>

#include <gtest/gtest.h>

#include "unseen/render/rasterizer.h"
#include "unseen/track/depth_modality.h"
#include "unseen/track/test_scene.h"
#include "unseen/track/tracker_options.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

Rigid3d CubePose() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)), Eigen::Vector3d(0.02, -0.01, 1.0));
}

// The flat cube rendered at CubePose() in one camera, and the depth modality's input for a
// measured depth image of it.
struct DepthScene {
  explicit DepthScene(const Rigid3d& pose = CubePose()) : cam_from_obj(pose) {
    RenderOptions options;
    options.write_color = false;
    Render(cube, rig.cameras[0].intrinsics, cam_from_obj, roi, options, &rendered);
  }
  cv::Mat TrueDepth() const { return testing::DepthImage(cube, rig.cameras[0], cam_from_obj, 1.6f); }
  DepthModalityInput Input(const cv::Mat* measured) const {
    DepthModalityInput in;
    in.rendered_depth = &rendered.depth;
    in.roi = roi;
    in.level_camera = rig.cameras[0].intrinsics;
    in.measured_depth = measured;
    in.camera = rig.cameras[0].intrinsics;
    in.origin_in_cam = cam_from_obj.translation();
    return in;
  }
  Rig rig = testing::OneCameraRig();
  Mesh cube = testing::FlatCube();
  Rigid3d cam_from_obj;
  PixelRect roi{150, 50, 370, 210};
  RenderBuffers rendered;
};

TEST(DepthModality, RowsVanishAtTheTruePose) {
  const DepthScene scene;
  const cv::Mat measured = scene.TrueDepth();
  FlowEquations eq;
  DepthCounts counts;
  AddDepthEquations(scene.Input(&measured), DepthModalityOptions(), &eq, &counts);
  ASSERT_GT(eq.size(), 200);
  for (int i = 0; i < eq.size(); ++i) EXPECT_LT(std::abs(eq.rhs[i]), 1e-4) << i;
  EXPECT_EQ(counts.agreeing, counts.measured);
  EXPECT_EQ(counts.hidden, 0);
  EXPECT_NEAR(counts.Agreement(DepthModalityOptions()), 1.0, 1e-12);
}

TEST(DepthModality, ASurfaceInFrontGivesNoRowsUnlessMostOfTheObjectIsBehindOne) {
  // The measured depth of the cube at its true pose, with a band of the image 19 mm nearer
  // (a finger across it). Within the gate, those pairs would give rows that pull the face
  // towards the finger; nearer by more than occluder_margin_m, they are an occluder and give
  // none. When most of the object is behind the measured surface, the pose is behind it:
  // then every pair gives its row.
  const DepthScene scene;
  const cv::Mat truth = scene.TrueDepth();
  const PixelRect& roi = scene.roi;
  auto rows = [&](int band_rows, double margin_m, DepthCounts* counts) {
    cv::Mat measured = truth.clone();
    cv::Mat band = measured(cv::Rect(0, roi.y0, measured.cols, band_rows));
    band -= 0.019f;
    DepthModalityOptions options;
    options.occluder_margin_m = margin_m;
    FlowEquations eq;
    AddDepthEquations(scene.Input(&measured), options, &eq, counts);
    int in_front = 0;
    for (int i = 0; i < eq.size(); ++i) in_front += eq.rhs[i] > 0.005f;  // towards the camera
    return std::make_pair(eq.size(), in_front);
  };
  const double margin = DepthModalityOptions().occluder_margin_m;
  DepthCounts partly, kept_counts, mostly;
  const auto [rows_partly, front_partly] = rows(60, margin, &partly);
  const auto [rows_kept, front_kept] = rows(60, 0.0, &kept_counts);
  EXPECT_GT(partly.hidden, 30);
  EXPECT_LT(2 * partly.hidden, partly.measured);
  EXPECT_EQ(front_partly, 0) << "no row from the surface in front";
  EXPECT_GT(rows_partly, 100);
  EXPECT_GT(front_kept, 30) << "without the margin, the surface in front gives rows";
  EXPECT_GT(rows_kept, rows_partly);
  const auto [rows_mostly, front_mostly] = rows(roi.height(), margin, &mostly);
  EXPECT_GT(2 * mostly.hidden, mostly.measured);
  EXPECT_GT(front_mostly, 100) << "the pose is behind the measured surface: every row";
  EXPECT_THROW(ParseTrackerOptions("depth: {occluder_margin_m: -0.01}\n"), Error);
  EXPECT_THROW(ParseTrackerOptions("depth: {occluder_margin_sigmas: -1}\n"), Error);
  EXPECT_THROW(ParseTrackerOptions("depth: {occluder_margin_sigmas: .nan}\n"), Error);
}

TEST(DepthModality, AHandOverNearlyHalfTheObjectIsStillAnOccluder) {
  // A hand over 48 % of the object, 11 mm in front of it (fingers lying across its faces),
  // and the sensor's noise (1 mm, independent from pixel to pixel). The hand spreads the
  // pairs' depth differences far beyond the noise; taken for noise, that spread raises the
  // occluder margin past the hand and keeps its rows, which pull the object towards it.
  // The measured surface's roughness between neighbouring pixels sees the noise alone.
  const DepthScene scene;
  cv::Mat measured = scene.TrueDepth();
  cv::Mat noise(measured.size(), CV_32F);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.001);
  cv::add(measured, noise, measured, measured > 0.0f);
  const cv::Mat on_object = scene.rendered.depth > 0.0f;
  const int object_px = cv::countNonZero(on_object);
  int hand_rows = 0;
  for (int covered = 0; covered < 0.48 * object_px; ++hand_rows) {
    covered += cv::countNonZero(on_object.row(hand_rows));
  }
  measured(cv::Rect(0, scene.roi.y0, measured.cols, hand_rows)) -= 0.011f;
  auto rows = [&](const DepthModalityOptions& options, DepthCounts* counts) {
    FlowEquations eq;
    AddDepthEquations(scene.Input(&measured), options, &eq, counts);
    double pull = 0.0;  // mean right-hand side: > 0 pulls the object towards the camera
    for (int i = 0; i < eq.size(); ++i) pull += eq.rhs[i];
    return std::make_pair(eq.size(), pull / std::max(1, eq.size()));
  };
  DepthCounts counts, spread_counts;
  const auto [kept, pull] = rows(DepthModalityOptions(), &counts);
  EXPECT_GT(counts.hidden, 0.35 * counts.measured);
  EXPECT_LT(2 * counts.hidden, counts.measured);
  DepthModalityOptions spread_only;
  spread_only.roughness_noise_factor = 1e6;
  const auto [spread_kept, spread_pull] = rows(spread_only, &spread_counts);
  EXPECT_GT(spread_kept, kept + 150) << "the spread alone keeps the hand's rows";
  EXPECT_GT(spread_pull, 0.002);
  EXPECT_LT(pull, 0.001) << "without them, little pull towards the hand";
  EXPECT_GT(kept, 300);
  EXPECT_THROW(ParseTrackerOptions("depth: {roughness_noise_factor: 0}\n"), Error);
}

TEST(DepthModality, ASteepSurfaceMeasuredPixelsOffKeepsItsRows) {
  // The cube turned so that one face is seen at 69 deg, its depth image registered 3 px off
  // the colour camera, nothing in front: on the steep face the measured surface lies more
  // than the occluder margin nearer than the rendered one at the same pixel. Those pairs
  // are no occluder: the margin grows with the rendered slope.
  const DepthScene scene(Rigid3d(ExpSO3(Eigen::Vector3d(0.2, 1.2, 0.0)), CubePose().translation()));
  const cv::Mat truth = scene.TrueDepth();
  cv::Mat measured(truth.size(), CV_32F, cv::Scalar(0.0f));
  const int shift = 3;
  truth(cv::Rect(shift, 0, truth.cols - shift, truth.rows))
      .copyTo(measured(cv::Rect(0, 0, truth.cols - shift, truth.rows)));
  auto rows = [&](double slope_px, DepthCounts* counts) {
    DepthModalityOptions options;
    options.occluder_slope_px = slope_px;
    FlowEquations eq;
    AddDepthEquations(scene.Input(&measured), options, &eq, counts);
    return eq.size();
  };
  DepthCounts counts, flat_counts;
  const int kept = rows(DepthModalityOptions().occluder_slope_px, &counts);
  const int kept_flat = rows(0.0, &flat_counts);
  EXPECT_GT(counts.hidden, 30);
  EXPECT_GT(kept, kept_flat + 50) << "the steep face's rows are kept";
  EXPECT_GT(kept, 0.85 * counts.measured);
  EXPECT_THROW(ParseTrackerOptions("depth: {occluder_slope_px: -1}\n"), Error);
}

}  // namespace
}  // namespace unseen
