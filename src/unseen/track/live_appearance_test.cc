// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Appearance from the live image: a captured projector reproduces the frame on the model,
// and a model without colours of its own takes them from the tracked frames, so that the
// photometric modality runs for it.
#include "unseen/track/live_appearance.h"

#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/test_scene.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

Rigid3d CubePose(double turn = 0.0) {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.45, 0.7 + turn, 0.1)),
                 Eigen::Vector3d(0.02, -0.01, 1.0));
}

class LiveAppearance : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_ = testing::OneCameraRig();
    textured_ = MakeLetteredCube(0.096, 64);
    background_ = testing::Background(rig_.cameras[0].intrinsics, 7);
  }
  cv::Mat Image(const Rigid3d& world_from_obj) const {
    return testing::RenderOverBackground(textured_, rig_.cameras[0], world_from_obj, background_);
  }
  // The flat (colourless) cube itself, shaded, over the background: no print.
  cv::Mat PlainImage(const Rigid3d& world_from_obj) const {
    return testing::RenderOverBackground(testing::FlatCube(), rig_.cameras[0], world_from_obj,
                                         background_);
  }
  // A tracker of the flat (colourless) cube, started at CubePose() and given the first frame.
  std::unique_ptr<Tracker> FlatCubeAtFirstFrame(const TrackerOptions& options,
                                                TrackResult* first) const {
    auto tracker = std::make_unique<Tracker>(rig_, testing::FlatCube(), options);
    tracker->Initialize(CubePose());
    *first = tracker->Track({Image(CubePose())});
    return tracker;
  }
  // Papers `area` of the background with the cube's print, tiled at half its size: colours
  // alike inside and around the silhouette.
  void PaperWithPrint(const cv::Rect& area) {
    cv::Mat print;
    cv::resize(textured_.materials[0].texture, print, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
    for (int y = area.y; y < area.y + area.height; y += print.rows) {
      for (int x = area.x; x < area.x + area.width; x += print.cols) {
        const cv::Rect tile(x, y, std::min(print.cols, area.x + area.width - x),
                            std::min(print.rows, area.y + area.height - y));
        print(cv::Rect(0, 0, tile.width, tile.height)).copyTo(background_(tile));
      }
    }
  }
  Rig rig_;
  Mesh textured_;
  cv::Mat background_;
};

TEST_F(LiveAppearance, ACapturedProjectorReproducesTheFrameOnTheModel) {
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  const Rigid3d pose = CubePose();
  const cv::Mat image = Image(pose);
  const PixelRect rect{150, 40, 370, 220};
  const std::optional<Projector> p = CaptureProjector(testing::FlatCube(), cam, pose, image, rect, 0.003f);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->image.cols, rect.width());
  EXPECT_EQ(p->depth.size(), p->image.size());
  Mesh live = testing::FlatCube();
  live.projectors = {*p};
  EXPECT_TRUE(live.HasAppearance());
  RenderBuffers out;
  Render(live, cam, pose, cam.ImageRect(), RenderOptions(), &out);
  // Inside the silhouette (away from its anti-aliased edge), the render is the frame.
  cv::Mat inner;
  cv::erode(out.mask, inner, cv::Mat(), cv::Point(-1, -1), 2);
  int checked = 0;
  double sum_error = 0.0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!inner.at<uint8_t>(v, u)) continue;
      sum_error += cv::norm(out.color.at<cv::Vec3f>(v, u) - image.at<cv::Vec3f>(v, u));
      ++checked;
    }
  }
  ASSERT_GT(checked, 5000);
  EXPECT_LT(sum_error / checked, 0.01);
  // Outside the image or of the object: nothing to capture.
  EXPECT_FALSE(CaptureProjector(testing::FlatCube(), cam, pose, image, PixelRect{600, 0, 700, 50}, 0.003f)
                   .has_value());
  EXPECT_FALSE(CaptureProjector(testing::FlatCube(), cam, pose, image, PixelRect{0, 0, 60, 60}, 0.003f)
                   .has_value());
  EXPECT_THROW(CaptureProjector(testing::FlatCube(), cam, pose, cv::Mat(10, 10, CV_32FC3), rect, 0.003f),
               Error);
}

TEST_F(LiveAppearance, AModelWithoutColoursTakesThemFromTheTrackedFrames) {
  TrackerOptions options;
  options.live_appearance.enabled = true;
  Tracker tracker(rig_, testing::FlatCube(), options);
  EXPECT_FALSE(tracker.photometric_in_use()) << "a flat model starts on its silhouette";
  tracker.Initialize(CubePose());
  TrackResult r = tracker.Track({Image(CubePose())});
  EXPECT_EQ(r.summary.counts.used, 0) << r.BriefReport();
  EXPECT_TRUE(tracker.photometric_in_use()) << "the first confident frame gave it colours";
  EXPECT_EQ(tracker.model().projectors.size(), 1u);
  // The cube turns a degree a frame: the photometric modality now runs on the frames'
  // colours and the pose follows.
  for (int k = 1; k <= 6; ++k) {
    const Rigid3d truth = CubePose(k * kDeg);
    r = tracker.Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    EXPECT_GT(r.summary.counts.used, 1000) << k << ": " << r.BriefReport();
    const PoseDifference e = Difference(r.world_from_obj, truth);
    EXPECT_LT(e.translation, 0.004) << k << ": " << r.BriefReport();  // 0.3 px of scale
    EXPECT_LT(e.rotation_rad, 0.5 * kDeg) << k << ": " << r.BriefReport();
  }
  // A new start forgets the colours: the given model again.
  tracker.Initialize(CubePose());
  EXPECT_FALSE(tracker.photometric_in_use());
  EXPECT_TRUE(tracker.model().projectors.empty());
  // Off (the default), the flat model of a plain cube (no print to take) stays on its
  // silhouette.
  Tracker plain(rig_, testing::FlatCube());
  plain.Initialize(CubePose());
  plain.Track({PlainImage(CubePose())});
  r = plain.Track({PlainImage(CubePose(kDeg))});
  EXPECT_FALSE(plain.photometric_in_use());
  EXPECT_EQ(r.summary.counts.used, 0);
}

TEST_F(LiveAppearance, AModelWithoutColoursOfAPrintedObjectTakesThemFromItsFirstFrame) {
  // The bare cube given for the lettered one: its first frame shows the print, and the model
  // takes its colours from the frames although live_appearance.enabled is off.
  auto run = [&](double print_share) {
    TrackerOptions options;
    options.live_appearance.print_share = print_share;
    TrackResult first;
    std::unique_ptr<Tracker> tracker = FlatCubeAtFirstFrame(options, &first);
    EXPECT_EQ(first.status, TrackStatus::kTracking) << first.BriefReport();
    return tracker;
  };
  ASSERT_FALSE(TrackerOptions().live_appearance.enabled);
  std::unique_ptr<Tracker> tracker = run(TrackerOptions().live_appearance.print_share);
  EXPECT_TRUE(tracker->photometric_in_use());
  EXPECT_EQ(tracker->model().projectors.size(), 1u);
  for (int k = 1; k <= 6; ++k) {
    const Rigid3d truth = CubePose(k * kDeg);
    const TrackResult r = tracker->Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    EXPECT_GT(r.summary.counts.used, 1000) << k << ": " << r.BriefReport();
    const PoseDifference e = Difference(r.world_from_obj, truth);
    EXPECT_LT(e.translation, 0.004) << k << ": " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 0.5 * kDeg) << k << ": " << r.BriefReport();
  }
  // The rule off (print_share above 1), the model stays on its silhouette.
  EXPECT_FALSE(run(2.0)->photometric_in_use());
  // The print's share: the lettered cube's faces against the plain cube's.
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  const PixelRect rect = cam.ImageRect();
  const LiveAppearanceOptions lo;
  auto share = [&](const cv::Mat& image) {
    const std::optional<Projector> p =
        CaptureProjector(testing::FlatCube(), cam, CubePose(), image, rect, 0.003f);
    EXPECT_TRUE(p.has_value());
    return p ? TexturedShare(*p, lo.print_min_gradient, lo.print_inset_px) : -1.0;
  };
  EXPECT_GE(share(Image(CubePose())), lo.print_share);
  EXPECT_LT(share(PlainImage(CubePose())), 0.25 * lo.print_share);
  // Bad values and the YAML fields.
  const TrackerOptions parsed = ParseTrackerOptions(
      "live_appearance: {print_share: 0.3, print_min_gradient: 0.1, print_inset_px: 2}");
  EXPECT_EQ(parsed.live_appearance.print_share, 0.3);
  EXPECT_EQ(parsed.live_appearance.print_min_gradient, 0.1);
  EXPECT_EQ(parsed.live_appearance.print_inset_px, 2);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {print_share: -0.1}"), Error);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {print_min_gradient: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {print_inset_px: -1}"), Error);
}

TEST_F(LiveAppearance, AModelWhoseSilhouetteCannotConfirmTheGivenPoseTakesTheFramesColours) {
  // The flat model's object is the lettered cube, before a wall papered with the cube's own
  // print: the colours inside and around the silhouette are alike, and the silhouette alone
  // cannot confirm the given pose.
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  PaperWithPrint(cv::Rect(0, 0, cam.width, cam.height));
  auto run = [&](bool when_silhouette_fails, TrackResult* first) {
    TrackerOptions options;
    options.live_appearance.when_silhouette_fails = when_silhouette_fails;
    options.live_appearance.print_share = 2.0;  // the print rule aside (below)
    return FlatCubeAtFirstFrame(options, first);
  };
  TrackResult r;
  std::unique_ptr<Tracker> by_silhouette = run(false, &r);
  EXPECT_FALSE(by_silhouette->photometric_in_use());
  const double silhouette_confidence = r.confidence;
  ASSERT_LT(silhouette_confidence, 0.8) << "the scene must defeat the silhouette: "
                                        << r.BriefReport();
  std::unique_ptr<Tracker> tracker = run(true, &r);
  EXPECT_TRUE(tracker->photometric_in_use()) << r.BriefReport();
  EXPECT_EQ(tracker->model().projectors.size(), 1u);
  EXPECT_GT(r.confidence, silhouette_confidence) << r.BriefReport();
  EXPECT_LT(Difference(r.world_from_obj, CubePose()).translation, 0.002) << r.BriefReport();
  // It follows the cube turning a degree a frame, which the silhouette alone could not
  // vouch for at the first frame.
  for (int k = 1; k <= 6; ++k) {
    const Rigid3d truth = CubePose(k * kDeg);
    r = tracker->Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    const PoseDifference e = Difference(r.world_from_obj, truth);
    EXPECT_LT(e.translation, 0.006) << k << ": " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 1.0 * kDeg) << k << ": " << r.BriefReport();
  }
  // A model whose silhouette confirms the given pose keeps to it (the smooth background).
  background_ = testing::Background(cam, 7);
  tracker = run(true, &r);
  EXPECT_FALSE(tracker->photometric_in_use()) << r.BriefReport();
  // Bad values and the YAML field.
  TrackerOptions parsed = ParseTrackerOptions("live_appearance: {when_silhouette_fails: false}");
  EXPECT_FALSE(parsed.live_appearance.when_silhouette_fails);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {when_silhouette_fails: 3}"), Error);
}

TEST_F(LiveAppearance, AModelWhoseLinesRunOnAtTheFirstFrameTakesTheFramesColours) {
  // The wall is papered with the cube's print along the cube's left and upper-left sides:
  // there the silhouette's lines run on past their end and are left out of its alignment,
  // and the lines on the smooth side confirm the given pose by themselves (confidence 1),
  // on too little of the object: the silhouette alone slides off towards the paper.
  const PinholeCamera& cam = rig_.cameras[0].intrinsics;
  const Eigen::Vector2d centre = cam.Project(CubePose().translation());
  PaperWithPrint(cv::Rect(0, 0, static_cast<int>(centre.x()) - 40, cam.height));
  PaperWithPrint(cv::Rect(0, 0, static_cast<int>(centre.x()), static_cast<int>(centre.y()) - 20));
  auto run = [&](double first_overrun_share, TrackResult* first) {
    TrackerOptions options;
    options.live_appearance.first_overrun_share = first_overrun_share;
    options.live_appearance.print_share = 2.0;  // the print rule aside (below)
    return FlatCubeAtFirstFrame(options, first);
  };
  TrackResult r;
  std::unique_ptr<Tracker> by_silhouette = run(1.0, &r);  // the share never counts
  EXPECT_FALSE(by_silhouette->photometric_in_use()) << r.BriefReport();
  ASSERT_GE(r.confidence, TrackerOptions().live_appearance.min_confidence) << r.BriefReport();
  const LiveAppearanceOptions defaults;
  ASSERT_GT(r.summary.region_counts.OverrunShare(), defaults.first_overrun_share)
      << r.BriefReport();
  const double silhouette_error = Difference(r.world_from_obj, CubePose()).translation;
  std::unique_ptr<Tracker> tracker = run(defaults.first_overrun_share, &r);
  EXPECT_TRUE(tracker->photometric_in_use()) << r.BriefReport();
  EXPECT_EQ(tracker->model().projectors.size(), 1u);
  const double colours_error = Difference(r.world_from_obj, CubePose()).translation;
  EXPECT_LT(colours_error, 0.003) << r.BriefReport();  // the silhouette alone: 18 mm
  EXPECT_LT(colours_error, 0.5 * silhouette_error) << r.BriefReport();
  // It follows the cube turning a degree a frame.
  for (int k = 1; k <= 6; ++k) {
    const Rigid3d truth = CubePose(k * kDeg);
    r = tracker->Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    const PoseDifference e = Difference(r.world_from_obj, truth);
    EXPECT_LT(e.translation, 0.003) << k << ": " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 0.5 * kDeg) << k << ": " << r.BriefReport();
  }
  // Bad values and the YAML field.
  EXPECT_EQ(ParseTrackerOptions("live_appearance: {first_overrun_share: 0.5}")
                .live_appearance.first_overrun_share,
            0.5);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {first_overrun_share: 1.5}"), Error);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {first_overrun_share: -0.1}"), Error);
}

TEST_F(LiveAppearance, AHeldTextureIsTakenAgainOnceItNoLongerFits) {
  TrackerOptions options;
  options.live_appearance.enabled = true;
  ASSERT_GT(options.live_appearance.refresh_frames, 10);
  Tracker tracker(rig_, testing::FlatCube(), options);
  tracker.Initialize(CubePose());
  tracker.Track({Image(CubePose())});
  ASSERT_EQ(tracker.model().projectors.size(), 1u);
  const Rigid3d first_projector = tracker.model().projectors[0].cam_from_obj;
  auto projector_moved = [&] {
    return Difference(tracker.model().projectors[0].cam_from_obj, first_projector).rotation_rad >
           0.1 * kDeg;
  };
  // The cube turns a degree a frame: the first frame's colours still fit and are held (taken
  // every frame, the pose would walk with them).
  int k = 1;
  for (; k <= 4; ++k) {
    const Rigid3d truth = CubePose(k * kDeg);
    const TrackResult r = tracker.Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    EXPECT_LT(Difference(r.world_from_obj, truth).rotation_rad, 0.5 * kDeg) << k << ": " << r.BriefReport();
    EXPECT_FALSE(projector_moved()) << k;
  }
  // The print fades into another (the light or the view moved on): the held colours are
  // taken again long before refresh_frames, and the pose stays with the cube.
  const cv::Mat print = textured_.materials[0].texture.clone();
  cv::Mat blotches(8, 8, CV_32FC3), other;
  cv::RNG(5).fill(blotches, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::resize(blotches, other, print.size(), 0.0, 0.0, cv::INTER_CUBIC);
  bool taken_again = false;
  for (int step = 1; step <= 8; ++step, ++k) {
    const double a = std::min(1.0, 0.2 * step);
    cv::addWeighted(print, 1.0 - a, other, a, 0.0, textured_.materials[0].texture);
    const Rigid3d truth = CubePose(k * kDeg);
    const TrackResult r = tracker.Track({Image(truth)});
    EXPECT_EQ(r.status, TrackStatus::kTracking) << k << ": " << r.BriefReport();
    const PoseDifference e = Difference(r.world_from_obj, truth);
    EXPECT_LT(e.translation, 0.004) << k << ": " << r.BriefReport();
    EXPECT_LT(e.rotation_rad, 0.5 * kDeg) << k << ": " << r.BriefReport();
    taken_again = taken_again || projector_moved();
  }
  EXPECT_TRUE(taken_again);
  EXPECT_LT(k, options.live_appearance.refresh_frames);
}

TEST_F(LiveAppearance, ProjectedColoursGiveWayToMeasuredDepth) {
  // A model whose colours were projected onto it from a frame whose pose was 3 mm off (as
  // an on-line model's key view sits on an approximate surface): its texture pulls the pose
  // aside. With the frame's measured depth, the photometric modality keeps
  // photometric.projected_with_depth_ratio of its weight and the depth holds the pose.
  const RigCamera& camera = rig_.cameras[0];
  const PinholeCamera& cam = camera.intrinsics;
  const Rigid3d truth = CubePose();
  const Rigid3d aside(truth.rotation(), truth.translation() + Eigen::Vector3d(0.003, 0.0, 0.0));
  const std::optional<Projector> p =
      CaptureProjector(testing::FlatCube(), cam, camera.cam_from_world() * truth, Image(aside),
                       PixelRect{150, 40, 370, 220}, 0.003f);
  ASSERT_TRUE(p.has_value());
  Mesh projected = testing::FlatCube();
  projected.projectors = {*p};
  RenderBuffers buffers;
  RenderOptions depth_only;
  depth_only.write_color = false;
  Render(testing::FlatCube(), cam, camera.cam_from_world() * truth, cam.ImageRect(), depth_only,
         &buffers);
  Frame frame;
  frame.images = {Image(truth)};
  frame.depths = {cv::Mat(buffers.depth.size(), CV_32FC1, cv::Scalar(1.6f))};
  buffers.depth.copyTo(frame.depths[0], buffers.mask);
  auto error_mm = [&](double ratio, bool with_depth) {
    TrackerOptions options;
    options.photometric.projected_with_depth_ratio = ratio;
    options.photometric.start_drag_px = 0.0;  // the colours stay in use whatever they pull
    options.photometric.min_start_fit = 0.0;
    Tracker tracker(rig_, projected, options);
    tracker.Initialize(truth);
    Frame input = frame;
    if (!with_depth) input.depths.clear();
    TrackResult r;
    for (int k = 0; k < 4; ++k) r = tracker.Track(input);
    EXPECT_TRUE(tracker.photometric_in_use());
    return 1e3 * Difference(r.world_from_obj, truth).translation;
  };
  const double full = error_mm(1.0, true);
  const double reduced = error_mm(0.3, true);
  EXPECT_GT(full, 0.5) << "the displaced colours should pull the pose aside";
  EXPECT_LT(reduced, 0.6 * full);
  // Without depth, the colours keep their whole weight: the ratio changes nothing.
  EXPECT_DOUBLE_EQ(error_mm(0.3, false), error_mm(1.0, false));
}

TEST(LiveAppearanceOptions, CheckRejectsBadValues) {
  LiveAppearanceOptions o;
  EXPECT_NO_THROW(o.Check());
  o.refresh_frames = 0;
  EXPECT_THROW(o.Check(), Error);
  o = LiveAppearanceOptions();
  o.min_confidence = 1.5;
  EXPECT_THROW(o.Check(), Error);
  o = LiveAppearanceOptions();
  o.photometric_weight = 0.0;
  EXPECT_THROW(o.Check(), Error);
  o = LiveAppearanceOptions();
  o.occlusion_tolerance = -1.0;
  EXPECT_THROW(o.Check(), Error);
  o = LiveAppearanceOptions();
  o.refresh_share_ratio = 1.5;
  EXPECT_THROW(o.Check(), Error);
  EXPECT_DOUBLE_EQ(
      ParseTrackerOptions("live_appearance: {refresh_share_ratio: 0.5}").live_appearance.refresh_share_ratio,
      0.5);
  EXPECT_DOUBLE_EQ(ParseTrackerOptions("photometric: {projected_with_depth_ratio: 0.5}")
                       .photometric.projected_with_depth_ratio,
                   0.5);
  EXPECT_THROW(ParseTrackerOptions("photometric: {projected_with_depth_ratio: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("photometric: {projected_with_depth_ratio: 1.5}"), Error);
}

}  // namespace
}  // namespace unseen
