// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The modalities behind their common interface (modality.h): each fills the equations of
// the camera a round names, counts what it saw, and starts every round empty.
#include "unseen/track/photometric_modality.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "unseen/image/filters.h"
#include "unseen/mesh/primitives.h"
#include "unseen/track/depth_modality.h"
#include "unseen/track/region_modality.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// The lettered cube rendered 2x2 supersampled at a pose slightly off the one of the
// frame, as one round of the tracker at level 0 would see it.
class ModalityRoundTest : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_ = testing::OneCameraRig();
    const PinholeCamera& cam = rig_.cameras[0].intrinsics;
    cube_ = MakeLetteredCube(0.096, 64);
    const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)), Eigen::Vector3d(0.02, -0.01, 1.0));
    image_ = testing::RenderOverBackground(cube_, rig_.cameras[0], truth,
                                           testing::Background(cam, 3));
    RenderBuffers depth_render;
    RenderOptions depth_only;
    depth_only.write_color = false;
    Render(cube_, cam, truth, cam.ImageRect(), depth_only, &depth_render);
    measured_depth_ = cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(1.6f));
    depth_render.depth.copyTo(measured_depth_, depth_render.mask);

    start_ = Rigid3d(truth.rotation(), truth.translation() + Eigen::Vector3d(0.002, 0, 0));
    const Rigid3d& start = start_;
    roi_ = PixelRect{150, 30, 370, 230};
    input_roi_ = DownsampledRegion(image_, 0, roi_);
    double ms = 0.0;
    ASSERT_TRUE(ComposeVirtualImage(cube_, cam, start, roi_, PixelRect(), input_roi_, true,
                                    PreprocessOptions(), 0, nullptr, &virtual_image_, &ms, &ms));
    Preprocess(virtual_image_.composite, PreprocessOptions(), 0, true, &virtual_pre_);
    Preprocess(input_roi_, PreprocessOptions(), 0, true, &input_pre_);

    round_.camera = 1;  // the second camera of a two-camera rig
    round_.level = 0;
    round_.roi = roi_;
    round_.level_camera = cam;
    round_.camera_intrinsics = cam;
    round_.origin_in_cam = start.translation();
    round_.virtual_image = &virtual_image_;
    round_.input = &input_roi_;
    round_.virtual_pre = &virtual_pre_;
    round_.input_pre = &input_pre_;
    round_.photometric_region = &virtual_image_.mask;
    round_.photometric_depth = &virtual_image_.depth;
  }
  Rig rig_;
  Mesh cube_;
  Rigid3d start_;  // the round's pose: 2 mm to the right of the frame's
  cv::Mat image_, measured_depth_, input_roi_;
  PixelRect roi_;
  VirtualImage virtual_image_;
  PreprocessedImage virtual_pre_, input_pre_;
  ModalityRound round_;
};

TEST_F(ModalityRoundTest, EachModalityFillsTheCameraOfTheRound) {
  PhotometricModality photometric;
  DepthModality depth;
  RegionModality region(RegionModalityOptions(), 2);
  std::vector<Modality*> all = {&photometric, &depth, &region};
  for (Modality* m : all) m->BeginRound(2);
  round_.first_frame = true;  // the region modality learns its statistics at once
  for (Modality* m : all) m->AddEquations(round_);
  EXPECT_GT(photometric.counts().used, 1000);
  EXPECT_EQ(photometric.equations().cameras[0].size(), 0);
  EXPECT_GT(photometric.equations().cameras[1].size(), 1000);
  EXPECT_EQ(depth.equations().size(), 0) << "no measured depth, no depth rows";
  EXPECT_GT(region.counts().used, 50);
  EXPECT_GT(region.equations().cameras[1].size(), 50);
  EXPECT_EQ(region.name(), "region");

  round_.measured_depth = &measured_depth_;
  depth.AddEquations(round_);
  EXPECT_GT(depth.equations().cameras[1].size(), 100);
  EXPECT_GT(depth.counts().agreeing, 100);

  // A new round starts empty.
  for (Modality* m : all) m->BeginRound(2);
  for (Modality* m : all) EXPECT_EQ(m->equations().size(), 0) << m->name();
  EXPECT_EQ(photometric.counts().used, 0);

  // Forgotten statistics give no region rows until the next first frame.
  region.Reset();
  round_.first_frame = false;
  region.AddEquations(round_);
  EXPECT_EQ(region.equations().size(), 0);
}

// RMS normal flow (pixels) of a modality's equations of camera `c`.
double RmsNormalFlow(const Modality& m, int c) {
  const FlowEquations& eq = m.equations().cameras[c];
  double sum = 0.0;
  for (int i = 0; i < eq.size(); ++i) {
    const double px = double(eq.rhs[i]) * eq.inv_grad_norm[i];
    sum += px * px;
  }
  return eq.size() > 0 ? std::sqrt(sum / eq.size()) : 0.0;
}

TEST_F(ModalityRoundTest, PhotometricRowsMeasureAgainAtAMovedPose) {
  // Blur alone: LINF and the shading transfer, normalised around the rendered pose, hold
  // part of the offset in the virtual image itself.
  PreprocessOptions plain;
  plain.use_linf = false;
  plain.shading_transfer = false;
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  double ms = 0.0;
  ASSERT_TRUE(ComposeVirtualImage(cube_, cam, start_, roi_, PixelRect(), input_roi_, true, plain, 0,
                                  nullptr, &virtual_image_, &ms, &ms));
  Preprocess(virtual_image_.composite, plain, 0, true, &virtual_pre_);
  Preprocess(input_roi_, plain, 0, true, &input_pre_);
  PhotometricModality photometric;
  photometric.BeginRound(2);
  photometric.AddEquations(round_);
  const FlowEquations& eq = photometric.equations().cameras[1];
  ASSERT_GT(eq.size(), 1000);
  const std::vector<float> rendered_rhs = eq.rhs;
  const double at_start = RmsNormalFlow(photometric, 1);
  std::vector<Vector6d> twist(2, Vector6d::Zero());
  twist[1](0) = -0.002;
  photometric.MoveBy(twist);
  const double at_truth = RmsNormalFlow(photometric, 1);
  EXPECT_LT(at_truth, 0.6 * at_start);
  twist[1](0) = +0.002;  // twice as far off instead
  photometric.MoveBy(twist);
  EXPECT_GT(RmsNormalFlow(photometric, 1), at_start);
  // Moves are from the rendered pose, not from the last move; no move, the rendered rows.
  photometric.MoveBy(std::vector<Vector6d>(2, Vector6d::Zero()));
  for (int i = 0; i < eq.size(); ++i) EXPECT_NEAR(eq.rhs[i], rendered_rhs[i], 1e-5f) << i;
  EXPECT_THROW(photometric.MoveBy(std::vector<Vector6d>(1, Vector6d::Zero())), Error);

  // With a margin wider than the object no equation is measured again: all follow their
  // rows' linear model.
  PhotometricModality linear(PixelSelectionOptions(), 1000);
  linear.BeginRound(2);
  linear.AddEquations(round_);
  const FlowEquations& leq = linear.equations().cameras[1];
  ASSERT_EQ(leq.size(), eq.size());
  twist[1](0) = -0.002;
  linear.MoveBy(twist);
  const Eigen::Matrix<float, 6, 1> t = twist[1].cast<float>();
  for (int i = 0; i < leq.size(); ++i) {
    EXPECT_NEAR(leq.rhs[i], rendered_rhs[i] - leq.rows[i].dot(t), 1e-5f) << i;
  }
}

TEST_F(ModalityRoundTest, OtherRowsFollowTheirLinearModelWhenMoved) {
  RegionModality region(RegionModalityOptions(), 2);
  region.BeginRound(2);
  round_.first_frame = true;
  region.AddEquations(round_);
  const FlowEquations& eq = region.equations().cameras[1];
  ASSERT_GT(eq.size(), 50);
  const std::vector<float> rendered_rhs = eq.rhs;
  std::vector<Vector6d> twist(2, Vector6d::Zero());
  twist[1] << -0.002, 0.001, 0.003, 0.01, -0.02, 0.005;
  region.MoveBy(twist);
  region.MoveBy(twist);  // not cumulative
  const Eigen::Matrix<float, 6, 1> t = twist[1].cast<float>();
  for (int i = 0; i < eq.size(); ++i) {
    EXPECT_NEAR(eq.rhs[i], rendered_rhs[i] - eq.rows[i].dot(t), 1e-4f) << i;
  }
  // A new round forgets the rendered right-hand sides of the last one.
  region.BeginRound(2);
  region.AddEquations(round_);
  region.MoveBy(std::vector<Vector6d>(2, Vector6d::Zero()));
  for (int i = 0; i < eq.size(); ++i) EXPECT_NEAR(eq.rhs[i], rendered_rhs[i], 1e-5f) << i;
}

TEST_F(ModalityRoundTest, ARoundWithoutItsImagesIsAnError) {
  PhotometricModality photometric;
  photometric.BeginRound(2);
  round_.virtual_pre = nullptr;
  EXPECT_THROW(photometric.AddEquations(round_), Error);
  RegionModality region(RegionModalityOptions(), 1);
  region.BeginRound(1);
  round_.camera = 0;
  round_.input = nullptr;
  EXPECT_THROW(region.AddEquations(round_), Error);
}

}  // namespace
}  // namespace unseen
