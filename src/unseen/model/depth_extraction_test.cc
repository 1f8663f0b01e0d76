// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/depth_extraction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "unseen/mesh/primitives.h"
#include "unseen/model/stereo_depth.h"
#include "unseen/model/test_rig_scene.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

using testing::MakeRigScene;
using testing::RigScene;

struct DepthCase {
  DepthSourceKind kind;
  int reference;
  double disparity_step_px = 0.0;  // plane sweep: planes by disparity step (0: all 64)
  int levels = 3;                  // plane sweep: pyramid levels (1: every plane at full size)
};

std::string CaseName(const ::testing::TestParamInfo<DepthCase>& info) {
  std::string name = ToString(info.param.kind) + "_ref" + std::to_string(info.param.reference);
  if (info.param.disparity_step_px > 0.0) {
    name += "_step" + std::to_string(static_cast<int>(info.param.disparity_step_px)) + "px";
  }
  if (info.param.kind == DepthSourceKind::kPlaneSweep) {
    name += "_levels" + std::to_string(info.param.levels);
  }
  return name;
}

class DepthSources : public ::testing::TestWithParam<DepthCase> {
 protected:
  static void SetUpTestSuite() { scene_ = new RigScene(MakeRigScene()); }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  static RigScene* scene_;
};
RigScene* DepthSources::scene_ = nullptr;

// On the cube's textured pixels of the reference view, over 80 % are measured, and the
// measured depth is within 1.5 % of the truth at the median and 5 % at the 90th percentile.
TEST_P(DepthSources, MeasureTheCubeAgainstTheTruth) {
  const RigScene& s = *scene_;
  const int ref = GetParam().reference;
  DepthExtractionOptions options;
  options.source = GetParam().kind;
  options.min_depth_m = 0.3;
  options.max_depth_m = 1.5;
  options.plane_sweep.disparity_step_px = GetParam().disparity_step_px;
  options.plane_sweep.levels = GetParam().levels;
  const std::unique_ptr<DepthSource> source = MakeDepthSource(s.rig, ref, options);
  EXPECT_EQ(source->kind(), GetParam().kind);
  const cv::Mat& mask = s.object_masks[ref];
  cv::Mat eroded;  // away from the outline, where windows straddle the wall
  cv::erode(mask, eroded, cv::Mat::ones(7, 7, CV_8U));
  const cv::Rect box = cv::boundingRect(mask);
  const PixelRect roi{box.x - 10, box.y - 10, box.x + box.width + 10, box.y + box.height + 10};
  const DepthMap map = source->Extract(s.frame, roi);
  ASSERT_EQ(map.depth.type(), CV_32FC1);
  ASSERT_EQ(map.depth.size(), mask.size());
  ASSERT_EQ(map.texturedness.size(), mask.size());
  const cv::Mat& truth = s.frame.depths[ref];
  std::vector<double> errors;
  int textured = 0;
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      const float d = map.depth.at<float>(y, x);
      const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
      if (!inside) {
        EXPECT_EQ(d, 0.0f) << "measured outside the region at " << x << "," << y;
        continue;
      }
      if (!eroded.at<uint8_t>(y, x)) continue;
      if (map.texturedness.at<float>(y, x) < options.min_texturedness) continue;
      ++textured;
      if (d > 0.0f) errors.push_back(std::abs(d - truth.at<float>(y, x)) / truth.at<float>(y, x));
    }
  }
  ASSERT_GT(textured, 200);
  EXPECT_GT(double(errors.size()) / textured, 0.8) << errors.size() << " of " << textured;
  ASSERT_FALSE(errors.empty());
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.015);
  EXPECT_LT(errors[errors.size() * 9 / 10], 0.05);
}

INSTANTIATE_TEST_SUITE_P(AllSources, DepthSources,
                         ::testing::Values(DepthCase{DepthSourceKind::kPlaneSweep, 0},
                                           DepthCase{DepthSourceKind::kPlaneSweep, 0, 0.0, 1},
                                           DepthCase{DepthSourceKind::kPlaneSweep, 0, 0.0, 2},
                                           DepthCase{DepthSourceKind::kPlaneSweep, 0, 2.0},
                                           DepthCase{DepthSourceKind::kStereo, 0},
                                           DepthCase{DepthSourceKind::kStereo, 1},
                                           DepthCase{DepthSourceKind::kSensor, 0}),
                         CaseName);

// Two cameras 80 mm apart (f = 400 px) see the cube 0.6 m ahead before a wall 1 m away
// tiled every 40 mm (16 px in the images) with the same random pattern: over the cube's
// depth band alone (0.55-0.7 m, disparities 46-58) the wall matches one tile over, at
// disparity 48 (0.67 m), and joins the object; searched past the band, it matches at its
// own disparity 32 and is dropped. The plane sweep likewise, by its planes behind the band
// (at its coarsest level, where the tiles are 4 px: less than half the wall's pixels
// remain, 16 700 -> 7 000).
TEST(DepthExtraction, ImageSourcesDoNotMistakeATiledWallForTheObject) {
  const PinholeCamera cam = PinholeCamera::Centered(320, 240, 400.0);
  Rig rig;
  rig.cameras.push_back({"left", cam, Rigid3d()});
  rig.cameras.push_back(
      {"right", cam, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.08, 0.0, 0.0))});
  const Mesh cube = MakeLetteredCube(0.1, 128);
  const Rigid3d world_from_obj(
      Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()) *
          Eigen::Quaterniond(Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(0.0, 0.0, 0.6));
  cv::Mat tile(16, 16, CV_32FC1);
  cv::RNG rng(7);
  rng.fill(tile, cv::RNG::UNIFORM, 0.1, 0.9);
  Frame frame;
  cv::Mat object_mask;
  for (const RigCamera& c : rig.cameras) {
    const double offset_px = c.world_from_cam.translation().x() * cam.fx;  // at 1 m
    cv::Mat image(cam.height, cam.width, CV_32FC3);
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const int u = static_cast<int>(std::lround(x + offset_px)) + 1600;
        const float v = tile.at<float>(y % 16, u % 16);
        image.at<cv::Vec3f>(y, x) = cv::Vec3f(v, v, v);
      }
    }
    RenderBuffers seen;
    Render(cube, cam, c.cam_from_world() * world_from_obj, cam.ImageRect(), RenderOptions(), &seen);
    seen.color.copyTo(image, seen.mask);
    frame.images.push_back(image);
    if (object_mask.empty()) object_mask = seen.mask.clone();
  }
  const std::optional<PixelRect> region = cam.SphereRect(world_from_obj.translation(), 0.12);
  ASSERT_TRUE(region.has_value());
  auto count = [&](DepthSourceKind kind, bool search_behind, int* on_object, int* off_object) {
    DepthExtractionOptions options;
    options.source = kind;
    options.stereo.search_behind = search_behind;
    options.plane_sweep.search_behind = search_behind;
    const DepthMap map = MakeDepthSource(rig, 0, options)->Extract(frame, *region, 0.55, 0.7);
    *on_object = *off_object = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        if (map.depth.at<float>(y, x) <= 0.0f) continue;
        ++(object_mask.at<uint8_t>(y, x) ? *on_object : *off_object);
      }
    }
  };
  for (DepthSourceKind kind : {DepthSourceKind::kStereo, DepthSourceKind::kPlaneSweep}) {
    SCOPED_TRACE(ToString(kind));
    int band_on = 0, band_off = 0, behind_on = 0, behind_off = 0;
    count(kind, false, &band_on, &band_off);
    count(kind, true, &behind_on, &behind_off);
    EXPECT_GT(band_off, 5000) << "the band-only search no longer mistakes the wall";
    EXPECT_LT(behind_off, kind == DepthSourceKind::kStereo ? band_off / 10 : band_off / 2);
    EXPECT_GT(behind_on, band_on / 2) << "the cube is still measured";
  }
}

TEST(DepthExtraction, TheNaturalSourceFollowsTheRig) {
  const RigScene s = MakeRigScene();  // left, right 80 mm to its right, top 50 mm up
  EXPECT_EQ(NaturalDepthSource(s.rig, 0, /*has_depth=*/true), DepthSourceKind::kSensor);
  EXPECT_EQ(NaturalDepthSource(s.rig, 0, false), DepthSourceKind::kPlaneSweep);
  Rig pair = s.rig;
  pair.cameras.pop_back();
  EXPECT_EQ(NaturalDepthSource(pair, 0, false), DepthSourceKind::kStereo);
  EXPECT_EQ(NaturalDepthSource(pair, 1, false), DepthSourceKind::kStereo);
  Rig stacked = pair;
  stacked.cameras[1].world_from_cam =
      Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.01, 0.08, 0.0));
  EXPECT_EQ(NaturalDepthSource(stacked, 0, false), DepthSourceKind::kPlaneSweep);
  // Toed in towards the object: 10 degrees still for stereo, 35 for the plane sweep.
  Rig toed = pair;
  for (const double deg : {10.0, 35.0}) {
    toed.cameras[1].world_from_cam = Rigid3d(
        Eigen::Quaterniond(Eigen::AngleAxisd(-deg * M_PI / 180.0, Eigen::Vector3d::UnitY())),
        pair.cameras[1].world_from_cam.translation());
    EXPECT_EQ(NaturalDepthSource(toed, 0, false),
              deg < kMaxStereoConvergenceDeg ? DepthSourceKind::kStereo : DepthSourceKind::kPlaneSweep)
        << deg;
  }
  pair.cameras.pop_back();
  EXPECT_EQ(NaturalDepthSource(pair, 0, false), DepthSourceKind::kSensor);
}

// The sweep's tiles are independent: spread over threads, the map is the same to the bit.
TEST(DepthExtraction, PlaneSweepGivesTheSameMapOnAnyNumberOfThreads) {
  const RigScene s = MakeRigScene();
  DepthExtractionOptions options;
  options.min_depth_m = 0.3;
  options.max_depth_m = 1.5;
  cv::Mat first;
  for (const int threads : {1, 2, 3}) {
    options.plane_sweep.threads = threads;
    const DepthMap map = MakeDepthSource(s.rig, 0, options)->Extract(s.frame, PixelRect());
    ASSERT_GT(map.ValidPixels(), 200) << threads << " threads";
    if (first.empty()) {
      first = map.depth;
    } else {
      EXPECT_EQ(cv::norm(map.depth, first, cv::NORM_INF), 0.0) << threads << " threads";
    }
  }
}

TEST(DepthExtraction, TexturednessIsTheSumOfSquaredChannelGradients) {
  cv::Mat image(5, 5, CV_32FC3, cv::Scalar(0.2, 0.2, 0.2));
  for (int y = 0; y < 5; ++y) image.at<cv::Vec3f>(y, 3) = cv::Vec3f(0.6f, 0.2f, 0.2f);
  const cv::Mat t = Texturedness(image);
  // Around column 3 the blue channel steps by 0.4: central difference 0.2 at columns 2, 4.
  EXPECT_NEAR(t.at<float>(2, 2), 0.04f, 1e-6);
  EXPECT_NEAR(t.at<float>(2, 4), 0.04f, 1e-6);
  EXPECT_NEAR(t.at<float>(2, 3), 0.0f, 1e-6);
  EXPECT_NEAR(t.at<float>(2, 0), 0.0f, 1e-6);
}

// Inside a region the texturedness is that of the whole image (its differences reach past
// the region's edge), outside it 0; an 8-bit image is scaled to [0, 1] first.
TEST(DepthExtraction, TexturednessOfARegionIsThatOfTheWholeImageThere) {
  cv::Mat image(40, 60, CV_8UC3);
  cv::randu(image, 0, 255);
  const cv::Mat whole = Texturedness(image);
  const PixelRect roi{10, 5, 35, 30};
  const cv::Mat part = Texturedness(image, roi);
  ASSERT_EQ(part.size(), image.size());
  ASSERT_EQ(part.type(), CV_32FC1);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
      ASSERT_FLOAT_EQ(part.at<float>(y, x), inside ? whole.at<float>(y, x) : 0.0f) << x << "," << y;
    }
  }
  EXPECT_GT(cv::norm(whole(cv::Rect(10, 5, 25, 25)), cv::NORM_INF), 0.1);
  // A region over the image's edge: clipped, replicated there as over the whole image.
  const cv::Mat edge = Texturedness(image, PixelRect{-5, -5, 12, 8});
  EXPECT_FLOAT_EQ(edge.at<float>(0, 0), whole.at<float>(0, 0));
  EXPECT_FLOAT_EQ(edge.at<float>(7, 11), whole.at<float>(7, 11));
  EXPECT_EQ(edge.at<float>(8, 11), 0.0f);
}

TEST(DepthExtraction, BadConfigurationsAndInputsAreClearErrors) {
  const RigScene s = MakeRigScene();
  DepthExtractionOptions options;
  EXPECT_THROW(ParseDepthSourceKind("lidar"), Error);
  EXPECT_EQ(ParseDepthSourceKind("stereo"), DepthSourceKind::kStereo);
  options.max_depth_m = options.min_depth_m;
  EXPECT_THROW(MakeDepthSource(s.rig, 0, options), Error);
  options = DepthExtractionOptions();
  options.plane_sweep.window_px = 4;
  EXPECT_THROW(options.Check(), Error);
  options.plane_sweep.window_px = 7;
  options.plane_sweep.levels = 0;
  EXPECT_THROW(options.Check(), Error);
  options.plane_sweep.levels = 3;
  options.plane_sweep.threads = -1;
  EXPECT_THROW(options.Check(), Error);
  options.plane_sweep.threads = 0;
  options = DepthExtractionOptions();
  options.stereo.num_disparities = 100;
  EXPECT_THROW(options.Check(), Error);

  // One camera: no plane sweep, no stereo.
  Rig one;
  one.cameras.push_back(s.rig.cameras[0]);
  options = DepthExtractionOptions();
  for (DepthSourceKind k : {DepthSourceKind::kPlaneSweep, DepthSourceKind::kStereo}) {
    options.source = k;
    EXPECT_THROW(MakeDepthSource(one, 0, options), Error) << ToString(k);
  }
  // Stereo with a camera that is not in the rig, or a pair stacked vertically.
  options.source = DepthSourceKind::kStereo;
  options.stereo.other_camera = "middle";
  EXPECT_THROW(MakeDepthSource(s.rig, 0, options), Error);
  Rig stacked = one;
  stacked.cameras.push_back({"below", s.rig.cameras[0].intrinsics,
                             Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0.1, 0))});
  options.stereo.other_camera = "below";
  Frame two;
  two.images = {s.frame.images[0], s.frame.images[0]};
  EXPECT_THROW(MakeDepthSource(stacked, 0, options)->Extract(two, PixelRect()), Error);

  // The sensor without depth images; an image of the wrong size.
  options = DepthExtractionOptions();
  options.source = DepthSourceKind::kSensor;
  Frame colour_only = s.frame;
  colour_only.depths.clear();
  EXPECT_THROW(MakeDepthSource(s.rig, 0, options)->Extract(colour_only, PixelRect()), Error);
  options.source = DepthSourceKind::kPlaneSweep;
  Frame small = s.frame;
  cv::resize(s.frame.images[1], small.images[1], cv::Size(160, 120));
  EXPECT_THROW(MakeDepthSource(s.rig, 0, options)->Extract(small, PixelRect()), Error);
}

}  // namespace
}  // namespace unseen
