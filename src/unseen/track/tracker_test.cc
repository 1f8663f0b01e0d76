// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Render-then-track tests: the "camera image" is the model rendered (supersampled) over a
// background at a known pose; the tracker starts from a perturbed pose.
#include "unseen/track/tracker.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

using testing::Background;
using testing::Camera512;
using testing::OneCameraRig;

// The model rendered over `background`, 2x2 supersampled; the pixels integrate light
// linearly and the stored image is gamma-encoded (2.2).
cv::Mat Synthesize(const Mesh& mesh, const RigCamera& camera, const Rigid3d& world_from_obj,
                   const cv::Mat& background) {
  return testing::RenderOverBackground(mesh, camera, world_from_obj, background, 2.2);
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

TEST_F(TrackerScene, CoarseLevelsStopOnTheirOwnUpdateWhileTheTextureLeads) {
  Vector6d d;
  d << 0.006, -0.005, 0.02, 3 * kDeg, -3 * kDeg, 2 * kDeg;
  TrackerOptions o;
  o.pyramid.photometric_coarse_min_update_px = 1e3;  // one round per coarse level
  Tracker textured(rig_, cube_, o);
  const TrackResult r = textured.Align({image_}, Perturb(truth_, d));
  ASSERT_GT(r.summary.num_levels, 1);
  for (int level = 1; level < r.summary.num_levels; ++level) {
    EXPECT_EQ(r.summary.iterations_per_level[level], 1) << "level " << level;
  }
  EXPECT_LT(Difference(r.world_from_obj, truth_).translation, 0.001) << r.BriefReport();
  // (Led by the other modalities the coarse levels keep coarse_min_update_px:
  // modalities_test's DepthLedCoarseLevelsKeepTheirStricterStop.)
}

TEST_F(TrackerScene, StartingAtTheTruthStaysThere) {
  Tracker tracker(rig_, cube_);
  for (int levels : {1, 2, 3}) {
    const TrackResult r = tracker.Align({image_}, truth_, levels);
    const PoseDifference e = Difference(r.world_from_obj, truth_);
    // 0.2 mm at 1 m is 0.03 px of scale on the ~140 px cube. The tracker shades each 2x2
    // block of its render once, from the block's mip-map level, where this image averages
    // four lookups: the texture is a little softer than here (0.07-0.08 deg).
    EXPECT_LT(e.translation, 2e-4) << levels << " levels: " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 0.1 * kDeg) << levels << " levels: " << r.BriefReport();
    EXPECT_GT(r.confidence, 0.9);
    EXPECT_EQ(r.summary.num_levels, levels);
  }
  EXPECT_EQ(tracker.NumLevelsFor(truth_), 3);  // ~140 px across, >= 32 px at the coarsest
}

// A camera image is blurrier than a render (optics, compression): at the true pose its
// pixels beside the silhouette carry the object's colour, and the object's own pixels
// along it the background's. A virtual image whose outside is the input matches the input
// outside exactly and not inside, and the photometric solve shrinks the model (moves it
// away from the camera) to hide the mismatch; with the background beside the silhouette
// estimated from the input farther out (PreprocessOptions::background_band_px) and the rim
// giving rows (PyramidOptions::rim_px), the mismatch lies on both sides and the pose stays.
TEST_F(TrackerScene, ABlurredCameraImageDoesNotPullTheObjectAway) {
  cv::Mat dark = image_.clone();  // a dim object: the silhouette's contrast dominates
  const cv::Mat mask = testing::DepthImage(cube_, rig_.cameras[0], truth_, 0.0f) > 0.0f;
  cv::Mat dimmed = 0.3 * image_;
  dimmed.copyTo(dark, mask);
  cv::Mat blurred;
  cv::GaussianBlur(dark, blurred, cv::Size(), 1.5);
  TrackerOptions options;
  options.region.enabled = false;  // the photometric modality's own pull
  auto away = [&](int band_px, int rim_px) {
    options.preprocess.background_band_px = band_px;
    options.pyramid.rim_px = rim_px;
    Tracker tracker(rig_, cube_, options);
    tracker.Initialize(truth_);
    TrackResult r;
    for (int k = 0; k < 3; ++k) r = tracker.Track({blurred});  // at rest
    // Along the line of sight, metres (positive: farther than the truth).
    return (r.world_from_obj.translation() - truth_.translation())
        .dot(truth_.translation().normalized());
  };
  const double input_outside = away(0, 0), estimated_outside = away(2, 2);
  EXPECT_GT(input_outside, 5e-3);                                // 9.8 mm
  EXPECT_LT(std::abs(estimated_outside), 0.25 * input_outside);  // 1.3 mm nearer
}

TEST_F(TrackerScene, AligningCoarseLevelsOnlyJudgesThereAndLearnsNothing) {
  Tracker tracker(rig_, cube_);
  Tracker untouched(rig_, cube_);
  tracker.Initialize(truth_);
  untouched.Initialize(truth_);
  for (int i = 0; i < 3; ++i) {
    ASSERT_GT(tracker.Track({image_}).confidence, 0.5);
    ASSERT_GT(untouched.Track({image_}).confidence, 0.5);
  }
  Vector6d d;
  d << 0.012, -0.008, 0.02, 0.0, 3 * kDeg, 0.0;
  Frame frame;
  frame.images = {image_};
  const TrackResult whole = tracker.AlignLevels(frame, Perturb(truth_, d), 0, 3, 4);
  EXPECT_LT(Difference(whole.world_from_obj, truth_).translation, 0.001) << whole.BriefReport();
  const TrackResult coarse = tracker.AlignLevels(frame, Perturb(truth_, d), 1, 2, 4);
  ASSERT_EQ(coarse.summary.num_levels, 3);
  EXPECT_EQ(coarse.summary.iterations_per_level[0], 0);  // full resolution untouched
  EXPECT_GT(coarse.summary.iterations_per_level[1], 0);
  // Within a pixel of level 1 (~7 mm at 1 m), and judged there.
  EXPECT_LT(Difference(coarse.world_from_obj, truth_).translation, 0.007) << coarse.BriefReport();
  EXPECT_GT(coarse.confidence, 0.5) << coarse.BriefReport();
  // Neither alignment changed the tracking state: the next frame is tracked exactly as
  // without them.
  const TrackResult next = tracker.Track({image_});
  const TrackResult expected = untouched.Track({image_});
  EXPECT_EQ(next.world_from_obj.translation(), expected.world_from_obj.translation());
  EXPECT_EQ(next.confidence, expected.confidence);
  EXPECT_THROW(tracker.AlignLevels(frame, truth_, -1, 2, 4), Error);
  EXPECT_THROW(tracker.AlignLevels(frame, truth_, 1, 0, 4), Error);
  EXPECT_THROW(tracker.AlignLevels(frame, truth_, 6, 3, 4), Error);
  EXPECT_THROW(tracker.AlignLevels(frame, truth_, 1, 2, 0), Error);
}

// Multiplies the image by a gain and a smooth horizontal shading ramp.
cv::Mat Shade(const cv::Mat& image) {
  cv::Mat out = image.clone();
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      out.at<cv::Vec3f>(y, x) *= float(0.55 * (0.6 + 0.8 * x / double(out.cols)));
    }
  }
  return out;
}

TEST_F(TrackerScene, LinfMakesTheSolveInvariantToGainAndShading) {
  const cv::Mat shaded = Shade(image_);
  Vector6d d;
  d << 0.004, -0.003, 0.01, 2 * kDeg, -2 * kDeg, 1 * kDeg;
  const Rigid3d start = Perturb(truth_, d);
  TrackerOptions with;
  with.preprocess.shading_transfer = false;  // LINF alone
  TrackerOptions without = with;
  without.preprocess.use_linf = false;
  Tracker linf(rig_, cube_, with);
  Tracker plain(rig_, cube_, without);
  const Rigid3d a = linf.Align({image_}, start).world_from_obj;
  const Rigid3d b = linf.Align({shaded}, start).world_from_obj;
  const Rigid3d c = plain.Align({shaded}, start).world_from_obj;
  const PoseDifference linf_change = Difference(a, b);
  EXPECT_LT(linf_change.translation, 0.001);
  EXPECT_LT(linf_change.rotation_rad, 0.3 * kDeg);
  EXPECT_LT(Difference(b, truth_).translation, 0.0015);
  // Without LINF the same shading moves the solution much further.
  EXPECT_GT(Difference(c, truth_).translation, 2.0 * Difference(b, truth_).translation);
}

TEST_F(TrackerScene, ConvergenceBasinGrowsWithPyramidLevels) {
  Tracker tracker(rig_, cube_);
  int converged[2] = {0, 0};
  const int level_counts[2] = {1, 3};
  for (int i = 0; i < 2; ++i) {
    for (double offset_mm : {6.0, 10.0, 14.0, 18.0, 24.0}) {
      for (int axis : {0, 1}) {
        Vector6d d = Vector6d::Zero();
        d(axis) = offset_mm * 1e-3;
        const TrackResult r = tracker.Align({image_}, Perturb(truth_, d), level_counts[i]);
        if (Difference(r.world_from_obj, truth_).translation < 0.002) ++converged[i];
      }
    }
  }
  EXPECT_GT(converged[1], converged[0]);
  EXPECT_GE(converged[1], 6);  // three levels bring back offsets of ~15-20 mm (~15 px)
}

TEST_F(TrackerScene, OcclusionRejectionKeepsTheTrackUnderAnOccluder) {
  cv::Mat occluded = image_.clone();
  // A white bar across the middle of the cube.
  const Eigen::Vector2d centre = rig_.cameras[0].intrinsics.Project(truth_.translation());
  occluded(cv::Rect(int(centre.x()) - 12, 0, 24, occluded.rows)).setTo(cv::Scalar::all(1.0));
  Vector6d d;
  d << 0.004, 0.003, 0.01, 2 * kDeg, 1 * kDeg, -2 * kDeg;
  TrackerOptions off;
  off.selection.use_occlusion_rejection = false;
  Tracker with(rig_, cube_);
  Tracker without(rig_, cube_, off);
  const TrackResult a = with.Align({occluded}, Perturb(truth_, d));
  const TrackResult b = without.Align({occluded}, Perturb(truth_, d));
  EXPECT_GT(a.summary.counts.rejected_input_gradient, 100);
  EXPECT_LT(Difference(a.world_from_obj, truth_).translation, 0.002) << a.BriefReport();
  EXPECT_LT(Difference(a.world_from_obj, truth_).translation,
            Difference(b.world_from_obj, truth_).translation)
      << b.BriefReport();
}

// `image` with the columns [x0, x1) of the cube's projection at `pose` replaced by `cover`
// (a textured occluder in front of it); `covered` gets the share of the cube's pixels hidden.
cv::Mat Occlude(const Mesh& cube, const RigCamera& camera, const Rigid3d& pose,
                const cv::Mat& image, const cv::Mat& cover, double width_share,
                double* covered) {
  RenderBuffers buffers;
  const PinholeCamera& cam = camera.intrinsics;
  Render(cube, cam, camera.cam_from_world() * pose, cam.ImageRect(), RenderOptions(), &buffers);
  const cv::Rect box = cv::boundingRect(buffers.mask);
  const cv::Rect hidden(box.x, 0, int(width_share * box.width), image.rows);
  cv::Mat out = image.clone();
  cover(hidden).copyTo(out(hidden));
  *covered = double(cv::countNonZero(buffers.mask(hidden))) / cv::countNonZero(buffers.mask);
  return out;
}

TEST_F(TrackerScene, PartlyOccludedObjectStaysTrackedAndConfident) {
  // The cube moves 2 mm a frame to the right; after four clear frames a static occluder
  // textured like it (a second lettered cube, close to the camera) hides the left part of
  // it, about 40 % of its pixels.
  const cv::Mat background = Background(rig_.cameras[0].intrinsics, 1);
  const Rigid3d occluder_pose(ExpSO3(Eigen::Vector3d(-0.3, 0.5, 0.4)),
                              Eigen::Vector3d(-0.01, 0.0, 0.45));
  const cv::Mat cover = Synthesize(cube_, rig_.cameras[0], occluder_pose, background);
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  for (int k = 1; k <= 16; ++k) {
    const Rigid3d pose(truth_.rotation(), truth_.translation() + Eigen::Vector3d(0.002 * k, 0, 0));
    cv::Mat image = Synthesize(cube_, rig_.cameras[0], pose, background);
    if (k > 4) {
      double covered = 0.0;
      image = Occlude(cube_, rig_.cameras[0], pose, image, cover, 0.45, &covered);
      ASSERT_GT(covered, 0.3);
      ASSERT_LT(covered, 0.5);
    }
    const TrackResult r = tracker.Track({image});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << "frame " << k << ": " << r.BriefReport();
    EXPECT_GT(r.confidence, 0.5) << "frame " << k << ": " << r.BriefReport();
    EXPECT_LT(Difference(r.world_from_obj, pose).translation, 0.003)
        << "frame " << k << ": " << r.BriefReport();
    EXPECT_LT(Difference(r.world_from_obj, pose).rotation_rad, 1.0 * kDeg)
        << "frame " << k << ": " << r.BriefReport();
  }
}

TEST_F(TrackerScene, TheFirstFramesCorrectionOfTheGivenPoseIsNoMotion) {
  // The cube stands still; the pose given for the first frame is 8 mm and 3 degrees off.
  // The first frame brings it back; the motion model starts at rest there, so that the
  // next frames are predicted where the cube is, not 8 mm further on.
  Vector6d d;
  d << 0.006, -0.004, 0.004, 2 * kDeg, -2 * kDeg, 0.0;
  Tracker tracker(rig_, cube_);
  tracker.Initialize(Perturb(truth_, d));
  for (int k = 0; k < 3; ++k) {
    const TrackResult r = tracker.Track({image_});
    ASSERT_EQ(r.status, TrackStatus::kTracking) << "frame " << k << ": " << r.BriefReport();
    EXPECT_LT(Difference(r.world_from_obj, truth_).translation, 0.001)
        << "frame " << k << ": " << r.BriefReport();
    EXPECT_LT(tracker.predictor().Velocity().head<3>().norm(), 0.01)
        << "frame " << k << ": the first frame's correction was taken for motion";
    EXPECT_LT(tracker.predictor().Velocity().tail<3>().norm(), 0.05)
        << "frame " << k << ": the first frame's correction was taken for motion";
  }
}

TEST_F(TrackerScene, AFirstFrameTheGivenPoseCannotAlignStartsFromTheSilhouettesPose) {
  // One round per pyramid level: from a given pose 30 mm and 8 degrees off, the joint
  // alignment of the first frame does not arrive. Aligned first by the silhouette (whose
  // colour statistics pull the contour in from further away), then jointly from there, it
  // does.
  Vector6d d;
  d << 0.006, 0.015, 0.045, 9 * kDeg, 6 * kDeg, -6 * kDeg;
  TrackerOptions options;
  options.pyramid.max_iterations_per_level = 1;
  options.pyramid.coarse_max_iterations = 1;
  auto first_frame = [&](bool start_by_silhouette) {
    options.photometric.start_by_silhouette = start_by_silhouette;
    Tracker tracker(rig_, cube_, options);
    tracker.Initialize(Perturb(truth_, d));
    return tracker.Track({image_});
  };
  const TrackResult from_given = first_frame(false);
  EXPECT_LT(from_given.confidence, 0.5) << from_given.BriefReport();
  const TrackResult r = first_frame(true);
  EXPECT_GE(r.confidence, 0.5) << r.BriefReport();
  EXPECT_EQ(r.status, TrackStatus::kTracking) << r.BriefReport();
  EXPECT_LT(Difference(r.world_from_obj, truth_).translation, 0.002) << r.BriefReport();
  EXPECT_LT(Difference(r.world_from_obj, truth_).rotation_rad, 0.5 * kDeg) << r.BriefReport();
}

TEST_F(TrackerScene, ASilhouetteFarOffItsContourVetoesTheTexturesConfidence) {
  // The textured cube tracked confidently; the same frame's summary with the silhouette's
  // residual 20 times what the confident frames had: the texture alone no longer vouches.
  auto confidences = [&](const TrackerOptions& options) {
    Tracker tracker(rig_, cube_, options);
    tracker.Initialize(truth_);
    TrackResult r;
    for (int k = 0; k < 4; ++k) r = tracker.Track({image_});
    EXPECT_GT(r.summary.region_residual, 0.0) << r.BriefReport();
    SolveSummary off_contour = r.summary;
    off_contour.region_residual *= 20.0;
    return std::make_pair(tracker.Confidence(r.summary), tracker.Confidence(off_contour));
  };
  TrackerOptions options;
  const auto [tracked, vetoed] = confidences(options);
  EXPECT_GT(tracked, 0.8);
  EXPECT_LT(vetoed, 0.05);
  options.failure.silhouette_veto_ratio = 0.0;
  const auto [tracked_without, judged_by_texture] = confidences(options);
  EXPECT_GT(judged_by_texture, 0.8);
  EXPECT_DOUBLE_EQ(tracked_without, tracked);
  EXPECT_THROW(ParseTrackerOptions("failure: {silhouette_veto_ratio: 2}\n"), Error);
  EXPECT_EQ(ParseTrackerOptions("failure: {silhouette_veto_ratio: 0}\n").failure.silhouette_veto_ratio,
            0.0);
}

TEST_F(TrackerScene, PoseFarOutsideTheCaptureRangeGetsLowConfidence) {
  Tracker tracker(rig_, cube_);
  // Offsets far beyond what the pyramid brings back: the solve ends somewhere wrong.
  Vector6d offsets[3];
  offsets[0] << 0.06, 0.0, 0.0, 0.0, 0.0, 0.0;
  offsets[1] << 0.0, 0.03, 0.0, 0.0, 0.0, 35 * kDeg;
  offsets[2] << 0.0, 0.0, 0.0, 40 * kDeg, -30 * kDeg, 0.0;
  for (const Vector6d& d : offsets) {
    const TrackResult r = tracker.Align({image_}, Perturb(truth_, d));
    const PoseDifference e = Difference(r.world_from_obj, truth_);
    if (e.translation < 0.005 && e.rotation_rad < 2 * kDeg) continue;  // brought back after all
    EXPECT_LT(r.confidence, tracker.options().failure.lost_confidence)
        << "error " << e.translation * 1e3 << " mm " << e.rotation_rad / kDeg
        << " deg: " << r.BriefReport();
  }
}

TEST_F(TrackerScene, AnObjectFarSmallerThanJustTrackedIsDoubted) {
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  for (int i = 0; i < 3; ++i) ASSERT_GT(tracker.Track({image_}).confidence, 0.5);
  // The same cube 2.5 times as far along its line of sight: aligned at its true pose it
  // fits, but it covers a sixth of the area it has just covered.
  const Rigid3d far(truth_.rotation(), 2.5 * truth_.translation());
  const cv::Mat far_image =
      Synthesize(cube_, rig_.cameras[0], far, Background(rig_.cameras[0].intrinsics, 1));
  const TrackResult doubted = tracker.Align({far_image}, far);
  EXPECT_LT(doubted.confidence, tracker.options().failure.lost_confidence) << doubted.BriefReport();
  EXPECT_GT(doubted.summary.object_px, 0.0);
  // A tracker that has not seen the cube nearer trusts the same alignment, and so does one
  // that has but does not judge the area.
  Tracker fresh(rig_, cube_);
  fresh.Initialize(far);
  const TrackResult trusted = fresh.Align({far_image}, far);
  EXPECT_GT(trusted.confidence, 0.5) << trusted.BriefReport();
  TrackerOptions no_area;
  no_area.failure.min_area_ratio = 0.0;
  no_area.failure.good_area_ratio = 1e-9;
  Tracker unguarded(rig_, cube_, no_area);
  unguarded.Initialize(truth_);
  for (int i = 0; i < 3; ++i) ASSERT_GT(unguarded.Track({image_}).confidence, 0.5);
  EXPECT_GT(unguarded.Align({far_image}, far).confidence, 0.5);
}

TEST(TrackerMultiCamera, TwoCamerasBeatOneOnDepth) {
  // Two cameras 0.6 m apart verging on the object; noisy images.
  Rig rig;
  rig.cameras.push_back({"left", Camera512(), Rigid3d()});
  const Eigen::Vector3d target(0.0, 0.0, 1.0);
  const Eigen::Vector3d right_centre(0.6, 0.0, 0.0);
  const Rigid3d right_pose(ExpSO3(Eigen::Vector3d(0, -std::atan2(0.6, 1.0), 0)), right_centre);
  rig.cameras.push_back({"right", Camera512(), right_pose});
  const Mesh cube = MakeLetteredCube(0.096, 128);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.3, 0.9, 0.2)), target);
  std::vector<cv::Mat> images;
  cv::RNG rng(4);
  for (int c = 0; c < 2; ++c) {
    cv::Mat im = Synthesize(cube, rig.cameras[c], truth, Background(Camera512(), 10 + c));
    cv::Mat noise(im.size(), im.type());
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.03);
    images.push_back(im + noise);
  }
  Vector6d d;
  d << 0.003, -0.002, 0.03, 1 * kDeg, 2 * kDeg, -1 * kDeg;
  const Rigid3d start = Perturb(truth, d);
  Tracker both(rig, cube);
  Rig left_only;
  left_only.cameras.push_back(rig.cameras[0]);
  Tracker one(left_only, cube);
  double depth_error_both = 0, depth_error_one = 0;
  const TrackResult rb = both.Align(images, start);
  const TrackResult ro = one.Align({images[0]}, start);
  depth_error_both = std::abs(rb.world_from_obj.translation().z() - truth.translation().z());
  depth_error_one = std::abs(ro.world_from_obj.translation().z() - truth.translation().z());
  EXPECT_LT(Difference(rb.world_from_obj, truth).translation, 0.002) << rb.BriefReport();
  EXPECT_LT(depth_error_both, depth_error_one) << rb.BriefReport() << "\n" << ro.BriefReport();
  // Each camera's rows built on a thread of its own: the same result, every time.
  TrackerOptions two_threads;
  two_threads.threads = 2;
  Tracker parallel(rig, cube, two_threads);
  for (int k = 0; k < 5; ++k) {
    const TrackResult rp = parallel.Align(images, start);
    EXPECT_LT(Difference(rp.world_from_obj, rb.world_from_obj).translation, 2e-5) << k;
    EXPECT_EQ(rp.summary.counts.used, rb.summary.counts.used) << k;
  }
}

TEST_F(TrackerScene, AdaptivePyramidUsesFewerLevelsForSmallMotionsAndAllForAJump) {
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  const cv::Mat background = Background(rig_.cameras[0].intrinsics, 1);
  const int full = tracker.NumLevelsFor(truth_);
  ASSERT_EQ(full, 3);
  // Steady motion of 1 mm a frame (~0.8 px): the predictor follows it, the corrections are
  // small, so fewer levels suffice.
  Rigid3d pose = truth_;
  int fewer = 0;
  for (int k = 1; k <= 10; ++k) {
    pose = Rigid3d(truth_.rotation(), truth_.translation() + Eigen::Vector3d(0.001 * k, 0, 0));
    const TrackResult r = tracker.Track({Synthesize(cube_, rig_.cameras[0], pose, background)});
    EXPECT_LT(Difference(r.world_from_obj, pose).translation, 0.001) << r.BriefReport();
    if (k > 3 && r.summary.num_levels < full) ++fewer;
  }
  EXPECT_GE(fewer, 5);
  // A sudden jump of 12 mm (~10 px, beyond two levels' reach) is still aligned: the doubtful
  // reduced alignment is redone with the whole pyramid.
  const Rigid3d jumped(pose.rotation(), pose.translation() + Eigen::Vector3d(0.001, 0.012, 0));
  const TrackResult r = tracker.Track({Synthesize(cube_, rig_.cameras[0], jumped, background)});
  EXPECT_EQ(r.status, TrackStatus::kTracking) << r.BriefReport();
  EXPECT_LT(Difference(r.world_from_obj, jumped).translation, 0.001) << r.BriefReport();
  EXPECT_EQ(r.summary.num_levels, full) << r.BriefReport();
}

// The level-0 area of the rectangle of the cube's corners in the image (a cube's bounding
// box is the cube).
double ObjectAreaPx(const Mesh& mesh, const PinholeCamera& cam, const Rigid3d& cam_from_obj) {
  std::vector<Eigen::Vector3d> corners;
  for (const Eigen::Vector3f& v : mesh.vertices) corners.push_back(cam_from_obj * v.cast<double>());
  const std::optional<PixelRect> rect = cam.PointsRect(corners);
  if (!rect) return 0.0;
  const PixelRect in_image = rect->Intersect(cam.ImageRect());
  return double(in_image.width()) * double(in_image.height());
}

TEST_F(TrackerScene, ALargeObjectIsAlignedAtTheBudgetsLevelAsWellAsAtLevelZero) {
  // The cube 0.4 m away: ~250 px across, its rectangle clipped by the 256 rows.
  const Rigid3d near(truth_.rotation(), Eigen::Vector3d(0.01, -0.005, 0.4));
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  const double area_px = ObjectAreaPx(cube_, cam, near);
  ASSERT_GT(area_px, 60000.0);
  const cv::Mat background = Background(cam, 3);
  TrackerOptions budget;
  budget.pyramid.max_finest_px = 0.5 * area_px;  // level 1 holds a quarter of it
  TrackerOptions full = budget;
  full.pyramid.max_finest_px = 0.0;
  Tracker budgeted(rig_, cube_, budget), unbudgeted(rig_, cube_, full);
  budgeted.Initialize(near);
  unbudgeted.Initialize(near);
  Rigid3d last = near;
  for (int k = 1; k <= 6; ++k) {
    const Rigid3d pose(ExpSO3(Eigen::Vector3d(0, 0.004 * k, 0)) * near.rotation(),
                       near.translation() + Eigen::Vector3d(0.001 * k, 0.0005 * k, 0));
    const cv::Mat image = Synthesize(cube_, rig_.cameras[0], pose, background);
    const TrackResult b = budgeted.Track({image});
    const TrackResult u = unbudgeted.Track({image});
    EXPECT_EQ(b.summary.finest_level, 1) << b.BriefReport();
    EXPECT_EQ(u.summary.finest_level, 0) << u.BriefReport();
    EXPECT_EQ(b.status, TrackStatus::kTracking) << b.BriefReport();
    // Judged in level-0 units: as confident as the level-0 alignment.
    EXPECT_GT(b.confidence, 0.9) << b.BriefReport();
    EXPECT_GT(b.summary.object_px, 0.5 * u.summary.object_px);
    EXPECT_LT(b.summary.object_px, 2.0 * u.summary.object_px);
    EXPECT_LT(Difference(b.world_from_obj, pose).translation, 5e-4) << b.BriefReport();
    EXPECT_LT(Difference(b.world_from_obj, pose).rotation_rad, 0.2 * kDeg) << b.BriefReport();
    EXPECT_LT(Difference(u.world_from_obj, pose).translation, 5e-4) << u.BriefReport();
    last = b.world_from_obj;
  }
  // Back at level 0 only once the object fits the budget with room to spare.
  const auto at_depth = [&](double z) {
    return Rigid3d(last.rotation(), Eigen::Vector3d(last.translation().x(),
                                                    last.translation().y(), z));
  };
  double z_tight = last.translation().z(), z_roomy = z_tight;
  while (ObjectAreaPx(cube_, cam, at_depth(z_tight)) > 0.85 * budget.pyramid.max_finest_px) {
    z_tight += 0.005;
  }
  while (ObjectAreaPx(cube_, cam, at_depth(z_roomy)) > 0.6 * budget.pyramid.max_finest_px) {
    z_roomy += 0.005;
  }
  EXPECT_EQ(budgeted.FinestLevelFor(at_depth(z_tight)), 1);  // within the hysteresis
  EXPECT_EQ(budgeted.FinestLevelFor(at_depth(z_roomy)), 0);
  EXPECT_EQ(unbudgeted.FinestLevelFor(near), 0);
}

TEST_F(TrackerScene, SameResultOnOneAndTwoThreads) {
  Vector6d d;
  d << 0.004, -0.003, 0.01, 2 * kDeg, -2 * kDeg, 1 * kDeg;
  const Rigid3d start = Perturb(truth_, d);
  TrackerOptions options;
  options.threads = 1;
  const TrackResult one = Tracker(rig_, cube_, options).Align({image_}, start);
  options.threads = 2;
  const TrackResult two = Tracker(rig_, cube_, options).Align({image_}, start);
  // The same work, split over threads.
  EXPECT_LT(Difference(one.world_from_obj, two.world_from_obj).translation, 2e-5);
  EXPECT_LT(Difference(one.world_from_obj, two.world_from_obj).rotation_rad, 0.005 * kDeg);
  EXPECT_EQ(one.summary.counts.used, two.summary.counts.used);
  EXPECT_NEAR(one.confidence, two.confidence, 0.01);
}

TEST_F(TrackerScene, ObjectLeavingTheViewIsReportedLost) {
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  const cv::Mat background = Background(rig_.cameras[0].intrinsics, 1);
  bool lost = false;
  int tracked_frames = 0;
  for (int k = 0; k < 40 && !lost; ++k) {
    // Moves right by 15 mm a frame: out of the image (x > ~0.35 m) after ~20 frames.
    const Rigid3d pose(truth_.rotation(),
                       truth_.translation() + Eigen::Vector3d(0.015 * k, 0.0, 0.0));
    const bool visible = pose.translation().x() < 0.2;
    const cv::Mat image = Synthesize(cube_, rig_.cameras[0], pose, background);
    const TrackResult r = tracker.Track({image});
    ASSERT_TRUE(r.world_from_obj.IsValid());
    ASSERT_GE(r.confidence, 0.0);
    ASSERT_LE(r.confidence, 1.0);
    if (visible) {
      EXPECT_EQ(r.status, TrackStatus::kTracking) << "frame " << k << ": " << r.BriefReport();
      EXPECT_LT(Difference(r.world_from_obj, pose).translation, 0.003) << r.BriefReport();
      ++tracked_frames;
    }
    if (r.status == TrackStatus::kLost) {
      lost = true;
      EXPECT_FALSE(visible) << "lost while fully visible at frame " << k;
    } else if (pose.translation().x() > 0.45) {
      // Entirely out of view: a tracking status must not come with a confident pose.
      EXPECT_LT(r.confidence, 0.3) << r.BriefReport();
    }
  }
  EXPECT_TRUE(lost);
  EXPECT_GT(tracked_frames, 10);
  // A pose hint brings it back.
  tracker.Reset(truth_);
  const TrackResult r = tracker.Track({image_});
  EXPECT_EQ(r.status, TrackStatus::kTracking);
  EXPECT_LT(Difference(r.world_from_obj, truth_).translation, 0.001);
}

TEST_F(TrackerScene, ReacquiresAfterALossBySearchingAroundTheLastPose) {
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  const cv::Mat empty = Background(rig_.cameras[0].intrinsics, 1);
  TrackResult r;
  for (int k = 0; k < 4; ++k) r = tracker.Track({empty});  // the object vanishes
  EXPECT_EQ(r.status, TrackStatus::kLost);
  // It reappears 25 mm from where it was lost.
  const Rigid3d moved(truth_.rotation(), truth_.translation() + Eigen::Vector3d(0.025, 0.0, 0.0));
  const cv::Mat image = Synthesize(cube_, rig_.cameras[0], moved, empty);
  for (int k = 0; k < 3 && r.status == TrackStatus::kLost; ++k) r = tracker.Track({image});
  EXPECT_EQ(r.status, TrackStatus::kTracking) << r.BriefReport();
  EXPECT_LT(Difference(r.world_from_obj, moved).translation, 0.002) << r.BriefReport();
}

TEST_F(TrackerScene, BadInputThrows) {
  Tracker tracker(rig_, cube_);
  EXPECT_THROW(tracker.Track({image_}), Error);  // not initialised
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(tracker.Initialize(Rigid3d(Eigen::Quaterniond::Identity(),
                                          Eigen::Vector3d(nan, 0, 1))),
               Error);
  tracker.Initialize(truth_);
  EXPECT_THROW(tracker.Track(std::vector<cv::Mat>{}), Error);                    // wrong camera count
  EXPECT_THROW(tracker.Track({image_, image_}), Error);      // wrong camera count
  cv::Mat small;
  cv::resize(image_, small, cv::Size(256, 128));
  EXPECT_THROW(tracker.Track({small}), Error);               // wrong size
  EXPECT_THROW(tracker.Track({cv::Mat(256, 512, CV_32FC1)}), Error);  // wrong type
  cv::Mat bytes;
  image_.convertTo(bytes, CV_8UC3, 255.0);
  EXPECT_NO_THROW(tracker.Track({bytes}));                   // 8-bit is converted
  EXPECT_THROW(Tracker(rig_, Mesh()), Error);                 // empty model
  TrackerOptions bad;
  bad.pyramid.max_levels = 0;
  EXPECT_THROW(Tracker(rig_, cube_, bad), Error);
}

TEST_F(TrackerScene, UntexturedModelTracksFromMaterialColour) {
  Mesh plain = cube_;
  for (Material& m : plain.materials) {
    m.texture = cv::Mat();
    m.texture_path.clear();
    m.diffuse_bgr = Eigen::Vector3f(0.2f, 0.3f, 0.8f);
  }
  plain.uvs.clear();
  const cv::Mat image =
      Synthesize(plain, rig_.cameras[0], truth_, Background(rig_.cameras[0].intrinsics, 1));
  // No appearance: the silhouette against the colour statistics learnt on the first frame.
  Tracker tracker(rig_, plain);
  tracker.Initialize(truth_);
  tracker.Track({image});
  Vector6d d;
  d << 0.004, -0.003, 0.0, 0.0, 0.0, 0.0;
  const TrackResult r = tracker.Align({image}, Perturb(truth_, d));
  EXPECT_LT(Difference(r.world_from_obj, truth_).translation, 0.003) << r.BriefReport();
}

TEST_F(TrackerScene, ModelCanBeSwappedBetweenFrames) {
  Tracker tracker(rig_, cube_);
  tracker.Initialize(truth_);
  tracker.Track({image_});
  Mesh bigger = cube_;
  bigger.Scale(1.5f);
  tracker.SetModel(bigger);
  EXPECT_NEAR(tracker.model().vertices[0].norm(), 1.5f * cube_.vertices[0].norm(), 1e-6);
  const TrackResult r = tracker.Track({image_});
  EXPECT_TRUE(r.world_from_obj.IsValid());
}

}  // namespace
}  // namespace unseen
