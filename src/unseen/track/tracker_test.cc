// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Render-then-track tests: the "camera image" is the model rendered (supersampled) over a
// background at a known pose; the tracker starts from a perturbed pose.
#include "unseen/track/tracker.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

PinholeCamera Camera512() {
  PinholeCamera cam;
  cam.width = 512;
  cam.height = 256;
  cam.fx = cam.fy = 837.3;
  cam.cx = 255.5;
  cam.cy = 127.5;
  return cam;
}

Rig OneCameraRig() {
  Rig rig;
  rig.cameras.push_back({"cam0", Camera512(), Rigid3d()});
  return rig;
}

// A smooth, mildly textured background.
cv::Mat Background(const PinholeCamera& cam, int seed) {
  cv::RNG rng(seed);
  cv::Mat small(cam.height / 32 + 1, cam.width / 32 + 1, CV_32FC3);
  rng.fill(small, cv::RNG::UNIFORM, 0.3, 0.8);
  cv::Mat out;
  cv::resize(small, out, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_CUBIC);
  return out;
}

// The model rendered at `world_from_obj` over `background`, 2x2 supersampled.
cv::Mat Synthesize(const Mesh& mesh, const RigCamera& camera, const Rigid3d& world_from_obj,
                   const cv::Mat& background) {
  const PinholeCamera fine = camera.intrinsics.Scaled(0.5);
  RenderBuffers buffers;
  Render(mesh, fine, camera.cam_from_world() * world_from_obj, fine.ImageRect(), RenderOptions(),
         &buffers);
  cv::Mat big;
  cv::resize(background, big, cv::Size(fine.width, fine.height), 0, 0, cv::INTER_LINEAR);
  buffers.color.copyTo(big, buffers.mask);
  cv::Mat out;
  cv::resize(big, out, cv::Size(camera.intrinsics.width, camera.intrinsics.height), 0, 0,
             cv::INTER_AREA);
  return out;
}

Rigid3d CubePose() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)), Eigen::Vector3d(0.02, -0.01, 1.0));
}

Rigid3d Perturb(const Rigid3d& pose, const Vector6d& d) {
  return Rigid3d(ExpSO3(d.tail<3>()) * pose.rotation(), pose.translation() + d.head<3>());
}

class TrackerScene : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_ = OneCameraRig();
    cube_ = MakeLetteredCube(0.096, 128);
    truth_ = CubePose();
    image_ = Synthesize(cube_, rig_.cameras[0], truth_, Background(rig_.cameras[0].intrinsics, 1));
  }
  Rig rig_;
  Mesh cube_;
  Rigid3d truth_;
  cv::Mat image_;
};

TEST_F(TrackerScene, RecoversOffsetsInEachDegreeOfFreedom) {
  Tracker tracker(rig_, cube_);
  const double offsets[6] = {0.008, 0.008, 0.03, 4 * kDeg, 4 * kDeg, 4 * kDeg};
  for (int k = 0; k < 6; ++k) {
    for (double sign : {-1.0, 1.0}) {
      Vector6d d = Vector6d::Zero();
      d(k) = sign * offsets[k];
      const TrackResult r = tracker.Align({image_}, Perturb(truth_, d));
      const PoseDifference e = Difference(r.world_from_obj, truth_);
      EXPECT_LT(e.translation, 0.001) << "dof " << k << " sign " << sign << ": "
                                      << r.BriefReport();
      EXPECT_LT(e.rotation_rad, 0.2 * kDeg) << "dof " << k << " sign " << sign << ": "
                                            << r.BriefReport();
      EXPECT_GT(r.confidence, 0.5) << r.BriefReport();
    }
  }
}

TEST_F(TrackerScene, RecoversACombinedOffset) {
  Tracker tracker(rig_, cube_);
  Vector6d d;
  d << 0.006, -0.005, 0.02, 3 * kDeg, -3 * kDeg, 2 * kDeg;
  const TrackResult r = tracker.Align({image_}, Perturb(truth_, d));
  const PoseDifference e = Difference(r.world_from_obj, truth_);
  EXPECT_LT(e.translation, 0.001) << r.BriefReport();
  EXPECT_LT(e.rotation_rad, 0.2 * kDeg) << r.BriefReport();
}

TEST_F(TrackerScene, StartingAtTheTruthStaysThere) {
  Tracker tracker(rig_, cube_);
  for (int levels : {1, 2, 3}) {
    const TrackResult r = tracker.Align({image_}, truth_, levels);
    const PoseDifference e = Difference(r.world_from_obj, truth_);
    EXPECT_LT(e.translation, 1e-4) << levels << " levels: " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 0.02 * kDeg) << levels << " levels: " << r.BriefReport();
    EXPECT_GT(r.confidence, 0.9);
    EXPECT_EQ(r.summary.num_levels, levels);
  }
  EXPECT_EQ(tracker.NumLevelsFor(truth_), 3);  // ~140 px across, >= 32 px at the coarsest
}

}  // namespace
}  // namespace unseen
