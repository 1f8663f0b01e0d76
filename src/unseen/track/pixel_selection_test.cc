// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/pixel_selection.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

PinholeCamera Camera(int w, int h) {
  PinholeCamera cam;
  cam.width = w;
  cam.height = h;
  cam.fx = cam.fy = 800.0;
  cam.cx = w / 2.0;
  cam.cy = h / 2.0;
  return cam;
}

struct Scene {
  cv::Mat virtual_image, input_image;
  cv::Mat region, depth;
};

SelectionCounts Select(const Scene& scene, const PixelSelectionOptions& options,
                       const PreprocessOptions& pre, const cv::Mat& region) {
  PreprocessedImage v, i;
  Preprocess(scene.virtual_image, pre, 0, true, &v);
  Preprocess(scene.input_image, pre, 0, true, &i);
  SelectionInput in;
  in.virtual_image = &v;
  in.input_image = &i;
  in.region = &region;
  in.depth = &scene.depth;
  in.roi = {0, 0, scene.virtual_image.cols, scene.virtual_image.rows};
  in.camera = Camera(scene.virtual_image.cols, scene.virtual_image.rows);
  in.origin_in_cam = Eigen::Vector3d(0, 0, 1.0);
  FlowEquations eq;
  SelectionCounts counts;
  SelectPixels(in, options, &eq, &counts);
  EXPECT_EQ(eq.size(), counts.equations);
  return counts;
}

// A vertical edge between two colours at column `edge_x` (sub-pixel, anti-aliased).
cv::Mat EdgeImage(int w, int h, double edge_x, const cv::Vec3f& left, const cv::Vec3f& right) {
  cv::Mat image(h, w, CV_32FC3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double t = std::clamp(x + 0.5 - edge_x, 0.0, 1.0);  // share of the pixel right of the edge
      image.at<cv::Vec3f>(y, x) = left * float(1 - t) + right * float(t);
    }
  }
  return image;
}

// A 64x48 scene at 1 m depth whose virtual and input images show the same vertical edge
// between `left` and `right` at columns `virtual_x` and `input_x`.
Scene EdgeScene(double virtual_x, double input_x, const cv::Vec3f& left, const cv::Vec3f& right) {
  Scene scene;
  scene.virtual_image = EdgeImage(64, 48, virtual_x, left, right);
  scene.input_image = EdgeImage(64, 48, input_x, left, right);
  scene.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.0f));
  return scene;
}

// The region used in EdgeScene: all but an 8-pixel border.
cv::Mat EdgeSceneRegion() {
  cv::Mat region(48, 64, CV_8UC1, cv::Scalar(0));
  region(cv::Rect(8, 8, 48, 32)).setTo(255);
  return region;
}

TEST(PixelSelection, ColourGradientRedundancyKeepsIsoluminantEdgesThatGreyLoses) {
  // Two colours of equal luminance (BT.601 weights in BGR order).
  const cv::Vec3f a(0.2f, 0.5f, 0.5f);
  const float lum_a = 0.114f * a[0] + 0.587f * a[1] + 0.299f * a[2];
  const float b_blue = 0.7f, b_green = 0.35f;
  const cv::Vec3f b(b_blue, b_green, (lum_a - 0.114f * b_blue - 0.587f * b_green) / 0.299f);
  const Scene scene = EdgeScene(32.0, 32.5, a, b);
  const cv::Mat region = EdgeSceneRegion();
  PreprocessOptions pre;
  pre.use_linf = false;
  PixelSelectionOptions options;
  options.color_mode = ColorMode::kColorGradientRedundancy;
  const SelectionCounts redundancy = Select(scene, options, pre, region);
  options.color_mode = ColorMode::kGrey;
  const SelectionCounts grey = Select(scene, options, pre, region);
  options.color_mode = ColorMode::kRawColor;
  const SelectionCounts raw = Select(scene, options, pre, region);
  EXPECT_GT(redundancy.used, 32 * 4);  // a band of several columns along the edge
  EXPECT_EQ(grey.used, 0);
  EXPECT_EQ(grey.rejected_gradient, grey.candidates);
  EXPECT_GT(raw.used, 32 * 2);
  EXPECT_GE(raw.equations, raw.used);  // up to three equations a pixel
  EXPECT_EQ(raw.candidates, redundancy.candidates);
}

TEST(PixelSelection, ARimGivesRowsButLeavesTheObjectsCountsAlone) {
  // The edge at column 32 lies on the rim: the object's pixels end at column 31.
  const Scene scene =
      EdgeScene(32.0, 32.5, cv::Vec3f(0.2f, 0.3f, 0.4f), cv::Vec3f(0.7f, 0.6f, 0.5f));
  cv::Mat object(48, 64, CV_8UC1, cv::Scalar(0));
  object(cv::Rect(8, 8, 24, 32)).setTo(kObjectPixel);
  cv::Mat with_rim = object.clone();
  with_rim(cv::Rect(32, 8, 4, 32)).setTo(kRimPixel);
  cv::Mat as_object = object.clone();
  as_object(cv::Rect(32, 8, 4, 32)).setTo(kObjectPixel);
  PreprocessOptions pre;
  pre.use_linf = false;
  const PixelSelectionOptions options;
  const SelectionCounts alone = Select(scene, options, pre, object);
  const SelectionCounts rim = Select(scene, options, pre, with_rim);
  const SelectionCounts widened = Select(scene, options, pre, as_object);
  ASSERT_GT(alone.used, 32);
  EXPECT_GT(rim.equations, alone.equations + 32);  // the rim's columns gave rows
  EXPECT_EQ(rim.equations, widened.equations);
  EXPECT_EQ(rim.candidates, alone.candidates);
  EXPECT_EQ(rim.used, alone.used);
  EXPECT_EQ(rim.gradient_pixels(), alone.gradient_pixels());
  EXPECT_EQ(rim.rejected_input_gradient + rim.rejected_direction + rim.rejected_magnitude +
                rim.rejected_undirected + rim.rejected_normal_flow + rim.rejected_block,
            alone.rejected_input_gradient + alone.rejected_direction + alone.rejected_magnitude +
                alone.rejected_undirected + alone.rejected_normal_flow + alone.rejected_block);
  EXPECT_EQ(rim.block_used, alone.block_used);
  EXPECT_DOUBLE_EQ(rim.block_share_sum, alone.block_share_sum);
  EXPECT_GT(widened.used, alone.used);  // the same pixels counted as the object's
}

TEST(PixelSelection, OcclusionRejectionRemovesAnOccludersPixels) {
  cv::RNG rng(11);
  cv::Mat small(12, 16, CV_32FC3);
  rng.fill(small, cv::RNG::UNIFORM, 0.1, 0.9);
  Scene scene;
  cv::resize(small, scene.virtual_image, cv::Size(128, 96), 0, 0, cv::INTER_CUBIC);
  // The input: the same texture moved by half a pixel, with a white bar in front.
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 0.5, 0, 1, 0);
  cv::warpAffine(scene.virtual_image, scene.input_image, shift, scene.virtual_image.size(),
                 cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const cv::Rect bar(50, 0, 20, 96);
  scene.input_image(bar).setTo(cv::Scalar::all(1.0));
  scene.depth = cv::Mat(96, 128, CV_32FC1, cv::Scalar(1.0f));
  cv::Mat occluded(96, 128, CV_8UC1, cv::Scalar(0));
  occluded(cv::Rect(bar.x + 3, 4, bar.width - 6, 88)).setTo(255);  // bar without its edges
  cv::Mat free(96, 128, CV_8UC1, cv::Scalar(0));
  free(cv::Rect(6, 4, 36, 88)).setTo(255);
  free(cv::Rect(80, 4, 42, 88)).setTo(255);

  PreprocessOptions pre;
  PixelSelectionOptions on;
  PixelSelectionOptions off;
  off.use_occlusion_rejection = false;
  const SelectionCounts occ_on = Select(scene, on, pre, occluded);
  const SelectionCounts occ_off = Select(scene, off, pre, occluded);
  const SelectionCounts free_on = Select(scene, on, pre, free);
  const SelectionCounts free_off = Select(scene, off, pre, free);
  ASSERT_GT(occ_off.used, 100);
  EXPECT_LT(occ_on.used, occ_off.used / 20);
  EXPECT_GT(occ_on.rejected_input_gradient, occ_off.used / 2);
  EXPECT_GT(free_on.used, 0.85 * free_off.used);
}

// A smooth random colour texture of w x h pixels.
cv::Mat Texture(int w, int h, int seed) {
  cv::RNG rng(seed);
  cv::Mat small(h / 8, w / 8, CV_32FC3);
  rng.fill(small, cv::RNG::UNIFORM, 0.1, 0.9);
  cv::Mat out;
  cv::resize(small, out, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
  return out;
}

cv::Mat Shifted(const cv::Mat& image, double dx) {
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, 0);
  cv::Mat out;
  cv::warpAffine(image, out, shift, image.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

TEST(PixelSelection, BlocksTellACoherentOccluderFromAMisalignment) {
  Scene clear;
  clear.virtual_image = Texture(160, 96, 21);
  clear.input_image = Shifted(clear.virtual_image, 0.3);
  clear.depth = cv::Mat(96, 160, CV_32FC1, cv::Scalar(1.0f));
  // The same with another texture in front of the left 40 % of the object.
  Scene occluded = clear;
  occluded.input_image = clear.input_image.clone();
  const cv::Rect cover(0, 0, 64, 96);
  Texture(160, 96, 22)(cover).copyTo(occluded.input_image(cover));
  // And with the whole object misaligned by 2.5 px instead.
  Scene misaligned = clear;
  misaligned.input_image = Shifted(clear.virtual_image, 2.5);
  cv::Mat region(96, 160, CV_8UC1, cv::Scalar(0));
  region(cv::Rect(4, 4, 152, 88)).setTo(255);

  PreprocessOptions pre;
  PixelSelectionOptions plain;
  plain.block_min_share_ratio = 0.0;
  PixelSelectionOptions blocks;
  blocks.block_min_share_ratio = 0.5;
  const SelectionCounts c = Select(clear, plain, pre, region);
  const SelectionCounts o = Select(occluded, plain, pre, region);
  const SelectionCounts m = Select(misaligned, plain, pre, region);
  auto share = [](const SelectionCounts& k) { return double(k.used) / k.gradient_pixels(); };
  ASSERT_GT(c.used, 2000);
  // Occluded: the share falls with the hidden part, the block share stays near a clear view's.
  EXPECT_LT(share(o), 0.8 * share(c));
  EXPECT_GT(o.BlockShare(), 0.9 * c.BlockShare());
  // Misaligned: the rejections are spread, so the block share falls with the share.
  EXPECT_LT(share(m), 0.8 * share(c));
  EXPECT_LT(m.BlockShare(), 0.85 * c.BlockShare());
  // So the occluder's rejections gather in blocks, the misaligned pose's do not.
  // (This texture keeps only a third of its pixels in a clear view, so even the
  // occluder's gathering is far from 1.)
  EXPECT_GT(o.RejectionGathering(), 0.25);
  EXPECT_LT(m.RejectionGathering(), 0.2);
  EXPECT_GT(o.RejectionGathering(), 2.0 * m.RejectionGathering());

  // Block rejection drops the occluder's chance survivors, little of a clear view (weak blocks).
  cv::Mat covered_region = region.clone();
  covered_region(cv::Rect(64, 0, 96, 96)).setTo(0);
  const SelectionCounts survivors = Select(occluded, plain, pre, covered_region);
  const SelectionCounts ob = Select(occluded, blocks, pre, region);
  const SelectionCounts cb = Select(clear, blocks, pre, region);
  EXPECT_GT(ob.rejected_block, survivors.used / 2);
  EXPECT_EQ(ob.used + ob.rejected_block, o.used);
  EXPECT_LT(cb.rejected_block, c.used / 12);
}

TEST(PixelSelection, NormalFlowBoundRejectsLargeMotion) {
  const cv::Vec3f dark(0.2f, 0.2f, 0.2f), bright(0.8f, 0.8f, 0.8f);
  const Scene scene = EdgeScene(30.0, 36.0, dark, bright);  // 6 px apart
  const cv::Mat region = EdgeSceneRegion();
  PreprocessOptions pre;
  pre.use_linf = false;
  PixelSelectionOptions options;
  options.use_occlusion_rejection = false;
  const SelectionCounts bounded = Select(scene, options, pre, region);
  options.use_normal_flow_bound = false;
  const SelectionCounts unbounded = Select(scene, options, pre, region);
  EXPECT_GT(bounded.rejected_normal_flow, 0);
  EXPECT_LT(bounded.used, unbounded.used);
}

TEST(PixelSelection, OptionsAndNames) {
  PixelSelectionOptions o;
  EXPECT_NO_THROW(o.Check());
  o.max_normal_flow_px = 0;
  EXPECT_THROW(o.Check(), Error);
  o = PixelSelectionOptions();
  o.block_min_share_ratio = 1.5;
  EXPECT_THROW(o.Check(), Error);
  o = PixelSelectionOptions();
  o.block_px = 1;
  EXPECT_THROW(o.Check(), Error);
  EXPECT_EQ(ParseColorMode("grey"), ColorMode::kGrey);
  EXPECT_EQ(ParseColorMode(ToString(ColorMode::kRawColor)), ColorMode::kRawColor);
  EXPECT_THROW(ParseColorMode("hsv"), Error);
}

}  // namespace
}  // namespace unseen
