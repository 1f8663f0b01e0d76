// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// An object that moves past the image border is only partly out of view: its pose stays
// tracked while enough of it shows, and the part in view is not mistaken for a shrunken
// object (FailureOptions::min_in_image_share).
#include <gtest/gtest.h>

#include <cmath>

#include "unseen/mesh/primitives.h"
#include "unseen/render/silhouette_share.h"
#include "unseen/track/test_scene.h"
#include "unseen/track/tracker.h"

namespace unseen {
namespace {

// The lettered cube at frame k, 1 m away, moving 20 mm a frame (17 px) to the right from
// 110 px inside the right border of a 512 x 256 image: an eighth of it shows at frame 9,
// (about) none at frame 10. It turns 0.5 degrees a frame.
Rigid3d CubeAt(int k) {
  const Eigen::Vector3d rotation(0.45, 0.7 + 0.5 * M_PI / 180.0 * k, 0.1);
  return Rigid3d(ExpSO3(rotation), Eigen::Vector3d(0.173 + 0.020 * k, -0.01, 1.0));
}

constexpr int kLastInView = 9;

std::array<Eigen::Vector3d, 8> BoxCorners(const Mesh& mesh) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    lo = lo.cwiseMin(v.cast<double>());
    hi = hi.cwiseMax(v.cast<double>());
  }
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    corners[k] =
        Eigen::Vector3d(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  }
  return corners;
}

// Frames 1 to kLastInView + 1 tracked from the true first pose.
std::vector<TrackResult> TrackOutOfView(const TrackerOptions& options) {
  const Rig rig = testing::OneCameraRig();
  const Mesh cube = MakeLetteredCube(0.096, 128);
  const cv::Mat background = testing::Background(rig.cameras[0].intrinsics, 5);
  Tracker tracker(rig, cube, options);
  tracker.Initialize(CubeAt(0));
  std::vector<TrackResult> results(1);
  for (int k = 1; k <= kLastInView + 1; ++k) {
    results.push_back(tracker.Track(
        {testing::RenderOverBackground(cube, rig.cameras[0], CubeAt(k), background, 2.2)}));
  }
  return results;
}

TEST(TrackerViewBorder, TheSceneTakesTheCubeOutOfView) {
  const Rig rig = testing::OneCameraRig();
  const Mesh cube = MakeLetteredCube(0.096, 128);
  auto share = [&](int k) {
    return SilhouetteShareInImage(cube, rig.cameras[0].intrinsics, CubeAt(k), BoxCorners(cube));
  };
  EXPECT_EQ(share(0), 1.0);
  EXPECT_GT(share(kLastInView), 0.08);
  EXPECT_LT(share(kLastInView), 0.2);
  EXPECT_LT(share(kLastInView + 1), 0.01);
}

TEST(TrackerViewBorder, ACubeLeavingTheImageStaysConfidentWhileAnEighthOfItShows) {
  const TrackerOptions options;
  const std::vector<TrackResult> results = TrackOutOfView(options);
  for (int k = 1; k <= kLastInView; ++k) {
    const TrackResult& r = results[k];
    EXPECT_EQ(r.status, TrackStatus::kTracking) << "frame " << k << ": " << r.BriefReport();
    EXPECT_GE(r.confidence, 0.9) << "frame " << k << ": " << r.BriefReport();
    EXPECT_LT(1e3 * Difference(r.world_from_obj, CubeAt(k)).translation, 5.0)
        << "frame " << k << ": " << r.BriefReport();
  }
  // Wholly out of view: nothing vouches for a pose.
  EXPECT_LT(results[kLastInView + 1].confidence, options.failure.lost_confidence);
}

TEST(TrackerViewBorder, CountingOnlyThePartInViewDoubtsIt) {
  TrackerOptions options;
  options.failure.min_in_image_share = 1.0;  // the area of the part in the image alone
  const std::vector<TrackResult> results = TrackOutOfView(options);
  EXPECT_LT(results[kLastInView].confidence, options.failure.lost_confidence);
}

}  // namespace
}  // namespace unseen
