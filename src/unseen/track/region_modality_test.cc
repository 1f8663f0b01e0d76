// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The region (silhouette) modality's parts on their own: the colour histograms, and which
// lines across the contour give rows (none across an occluder, none whose colours leave the
// image's edge).
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "unseen/track/region_modality.h"
#include "unseen/track/tracker_options.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(RegionModality, HistogramsLearnAndJudgeColours) {
  ColorHistograms h(16);
  EXPECT_FALSE(h.learnt());
  const float red[3] = {0.1f, 0.1f, 0.9f}, grey[3] = {0.6f, 0.6f, 0.6f};
  for (int i = 0; i < 100; ++i) {
    h.Count(red, true);
    h.Count(grey, false);
  }
  h.Commit(0.2);
  ASSERT_TRUE(h.learnt());
  EXPECT_GT(h.Foreground(red), 0.99f);
  EXPECT_LT(h.Foreground(grey), 0.01f);
  // Too few samples leave the histograms as they are.
  h.Count(grey, true);
  h.Commit(1.0);
  EXPECT_LT(h.Foreground(grey), 0.01f);
  h.Reset();
  EXPECT_FALSE(h.learnt());
}

// A 48x48 square of `object` colour on `background` in a 96x96 image, its mask and depth,
// and the region modality's input over them.
struct SquareScene {
  SquareScene(const cv::Vec3f& background, const cv::Vec3f& object)
      : image(kSize, kSize, CV_32FC3, background),
        mask(cv::Mat::zeros(kSize, kSize, CV_8UC1)),
        depth(kSize, kSize, CV_32FC1, cv::Scalar(0.0f)) {
    image(square).setTo(object);
    mask(square).setTo(255);
    depth.setTo(1.0f, mask);
  }
  RegionModalityInput Input() const {
    RegionModalityInput in;
    in.image = &image;
    in.mask = &mask;
    in.rendered_depth = &depth;
    in.roi = PixelRect{0, 0, kSize, kSize};
    in.camera = PinholeCamera::Centered(kSize, kSize, 100.0);
    in.origin_in_cam = Eigen::Vector3d(0.0, 0.0, 1.0);
    return in;
  }
  // `histograms` learnt from the image as it is now.
  void Learn(const RegionModalityOptions& options, ColorHistograms* histograms) const {
    FlowEquations ignored;
    RegionCounts learnt;
    AddRegionEquations(Input(), options, /*learn=*/true, histograms, &ignored, &learnt);
    histograms->Commit(1.0);
  }
  static constexpr int kSize = 96;
  const cv::Rect square{24, 24, 48, 48};
  cv::Mat image, mask, depth;
};

// The largest offset (a row's right-hand side, px) the region modality's rows of `in` ask
// for, with `histograms` as learnt.
float LargestRowOffset(const RegionModalityInput& in, const RegionModalityOptions& options,
                       ColorHistograms* histograms, RegionCounts* counts) {
  FlowEquations rows;
  AddRegionEquations(in, options, /*learn=*/false, histograms, &rows, counts);
  float largest = 0.0f;
  for (float b : rows.rhs) largest = std::max(largest, std::abs(b));
  return largest;
}

// A square red object on grey; an occluder coloured like the background covers the square's
// right edge. Its lines see background where the object should be and pull the contour in by
// several standard deviations; with the occluder's blocks marked (as the photometric
// selection marks them) they are left out and the rest sit on the contour.
TEST(RegionModality, LinesAcrossAnOccluderAreLeftOut) {
  const int block = 8;
  SquareScene scene(cv::Vec3f(0.6f, 0.6f, 0.6f), cv::Vec3f(0.1f, 0.1f, 0.9f));
  const int size = SquareScene::kSize;
  const cv::Rect occluder(56, 16, 32, 64);  // over the square's right edge (x = 71)
  scene.image(occluder).setTo(cv::Vec3f(0.62f, 0.58f, 0.6f));
  cv::Mat occluded = cv::Mat::zeros(size / block, size / block, CV_8UC1);
  occluded(cv::Rect(occluder.x / block, occluder.y / block, occluder.width / block,
                    occluder.height / block))
      .setTo(255);

  RegionModalityOptions options;
  ColorHistograms histograms(options.bins_per_channel);
  scene.Learn(options, &histograms);
  ASSERT_TRUE(histograms.learnt());
  RegionModalityInput in = scene.Input();

  auto largest_offset = [&](bool mark, RegionCounts* counts) {
    in.occluded_blocks = mark ? &occluded : nullptr;
    in.occluded_block_px = mark ? block : 0;
    return LargestRowOffset(in, options, &histograms, counts);
  };
  RegionCounts unmarked, marked;
  EXPECT_GT(largest_offset(false, &unmarked), 3.0f);
  EXPECT_EQ(unmarked.occluded, 0);
  EXPECT_LT(largest_offset(true, &marked), 1.5f);
  EXPECT_GT(marked.occluded, 0);
  EXPECT_EQ(marked.lines + marked.occluded, unmarked.lines);
  EXPECT_GT(marked.Agreement(), unmarked.Agreement());
  // Switched off, the marks are ignored.
  options.skip_occluded_lines = false;
  RegionCounts off;
  EXPECT_GT(largest_offset(true, &off), 3.0f);
  EXPECT_EQ(off.occluded, 0);
}

// A square object before a background of nearly its colour, its histograms learnt; then a
// look-alike band (a shade darker, in the object's colour bins) right behind its right
// edge. Those lines' colours run the contour out onto the band, while the image's largest
// step stays on the rendered contour: with RegionModalityOptions::edge_contradiction_px
// they give no row, and the rest sit on the contour.
TEST(RegionModality, LinesWhoseColoursLeaveTheImagesEdgeGiveNoRow) {
  const cv::Vec3f object(0.56f, 0.56f, 0.56f), look_alike(0.505f, 0.505f, 0.505f),
      background(0.49f, 0.49f, 0.49f);
  SquareScene scene(background, object);
  RegionModalityOptions options;
  ColorHistograms histograms(options.bins_per_channel);
  scene.Learn(options, &histograms);
  ASSERT_TRUE(histograms.learnt());
  ASSERT_GT(histograms.Posterior(histograms.Bin(&look_alike[0])), 0.5f);
  scene.image(cv::Rect(scene.square.x + scene.square.width, 16, 9, 64)).setTo(look_alike);
  const RegionModalityInput in = scene.Input();

  auto largest_offset = [&](double contradiction_px, RegionCounts* counts) {
    options.edge_contradiction_px = contradiction_px;
    return LargestRowOffset(in, options, &histograms, counts);
  };
  RegionCounts off, on;
  EXPECT_GT(largest_offset(0.0, &off), 6.0f);
  EXPECT_LT(largest_offset(6.0, &on), 1.5f);
  EXPECT_LT(on.used, off.used);
  EXPECT_GT(on.used, off.used / 2);
  EXPECT_THROW(ParseTrackerOptions("region: {edge_contradiction_px: -1}\n"), Error);
}

// A square object before a background of another colour; then a look-alike of the object's
// very colour (its twin behind it) touching its right edge and reaching past the lines'
// outer ends. Those lines find no contour on them: their colours run on past their end, and
// would pull the contour their whole length onto the twin. Marked to skip them (as the
// tracker does while the silhouette tracks without texture) they give no row, and the rest
// sit on the contour.
TEST(RegionModality, LinesWhoseColoursRunPastTheirEndCanBeLeftOut) {
  const cv::Vec3f object(0.1f, 0.1f, 0.9f);
  SquareScene scene(cv::Vec3f(0.6f, 0.6f, 0.6f), object);
  RegionModalityOptions options;
  ColorHistograms histograms(options.bins_per_channel);
  scene.Learn(options, &histograms);
  ASSERT_TRUE(histograms.learnt());
  RegionCounts alone;
  EXPECT_LT(LargestRowOffset(scene.Input(), options, &histograms, &alone), 1.5f);
  EXPECT_EQ(alone.overrun, 0);
  // The twin: 20 px wide, more than a line's outer half (line_px = 12), the image's height.
  ASSERT_LT(options.line_px, 20);
  scene.image(cv::Rect(scene.square.x + scene.square.width, 0, 20, SquareScene::kSize))
      .setTo(object);
  RegionModalityInput in = scene.Input();

  auto largest_offset = [&](bool skip, RegionCounts* counts) {
    in.skip_overrun = skip;
    return LargestRowOffset(in, options, &histograms, counts);
  };
  RegionCounts kept, skipped;
  EXPECT_GT(largest_offset(false, &kept), 5.0f);
  EXPECT_LT(largest_offset(true, &skipped), 1.5f);
  EXPECT_GT(kept.overrun, 0);
  EXPECT_EQ(skipped.overrun, kept.overrun);
  EXPECT_EQ(skipped.used, kept.used - kept.overrun);
  EXPECT_EQ(skipped.lines, kept.lines);
  EXPECT_THROW(ParseTrackerOptions("region: {skip_overrun_lines: maybe}\n"), Error);
}

// A square object whose outermost 2 px are of a colour of their own (a shaded underside, a
// dark edge), before a grey background with a few dots of that colour. Learnt at the true
// contour, the rim is the object's from its second pixel in
// (RegionModalityOptions::foreground_margin_px 1) and the lines sit within half a standard
// deviation of the contour; left out of the foreground (a margin of 2), its colour is the
// background's and the lines place the contour several standard deviations inside.
TEST(RegionModality, TheObjectsOwnRimTeachesTheForeground) {
  const cv::Vec3f grey(0.6f, 0.6f, 0.6f), blue(0.1f, 0.1f, 0.9f), rim(0.15f, 0.3f, 0.45f);
  SquareScene scene(grey, rim);
  for (int y = 4; y < SquareScene::kSize; y += 8) {
    for (int x = 4; x < SquareScene::kSize; x += 8) scene.image.at<cv::Vec3f>(y, x) = rim;
  }
  scene.image(scene.square).setTo(rim);
  const cv::Rect core(scene.square.x + 2, scene.square.y + 2, scene.square.width - 4,
                      scene.square.height - 4);
  scene.image(core).setTo(blue);
  // The mean offset of the rows (contour offsets in standard deviations; < 0: inside).
  auto mean_offset = [&](const RegionModalityOptions& options) {
    ColorHistograms histograms(options.bins_per_channel);
    scene.Learn(options, &histograms);
    EXPECT_TRUE(histograms.learnt());
    FlowEquations rows;
    RegionCounts counts;
    AddRegionEquations(scene.Input(), options, /*learn=*/false, &histograms, &rows, &counts);
    EXPECT_GT(counts.used, 100);
    double sum = 0.0;
    for (float b : rows.rhs) sum += b;
    return rows.rhs.empty() ? 0.0 : sum / double(rows.rhs.size());
  };
  RegionModalityOptions options;
  ASSERT_EQ(options.foreground_margin_px, 1);
  const double taught = mean_offset(options);
  EXPECT_GT(taught, -0.6);
  EXPECT_LT(taught, 0.3);
  options.foreground_margin_px = 2;
  EXPECT_LT(mean_offset(options), -2.5);
}

}  // namespace
}  // namespace unseen
