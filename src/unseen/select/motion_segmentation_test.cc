// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/motion_segmentation.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// A random texture (smoothed noise) of `size`, CV_32FC3 in [0, 1].
cv::Mat Texture(cv::Size size, int seed) {
  cv::RNG rng(seed);
  cv::Mat noise(size, CV_32FC3);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.0);
  return noise;
}

// `background` shifted by `background_shift` with textured squares pasted at `corners`.
cv::Mat Scene(const cv::Mat& background, cv::Point background_shift,
              const std::vector<cv::Mat>& squares, const std::vector<cv::Point>& corners) {
  cv::Mat image;
  const cv::Matx23d shift(1, 0, background_shift.x, 0, 1, background_shift.y);
  cv::warpAffine(background, image, shift, background.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  for (size_t i = 0; i < squares.size(); ++i) {
    squares[i].copyTo(image(cv::Rect(corners[i], squares[i].size())));
  }
  return image;
}

// Bounding box of one label.
cv::Rect LabelBox(const cv::Mat& labels, int label) { return cv::boundingRect(labels == label); }

// The region holds the square and overshoots it by at most about a block and a half on
// each side (the dense flow spreads a little over the background next to it).
void ExpectAround(const cv::Rect& region, const cv::Rect& square) {
  EXPECT_EQ(region & square, square) << region << " does not hold " << square;
  EXPECT_LE(region.width, square.width + 24) << region;
  EXPECT_LE(region.height, square.height + 24) << region;
}

TEST(MotionSegmenter, TwoObjectsMovingApartAreTwoRegions) {
  const cv::Mat background = Texture(cv::Size(320, 240), 1);
  const std::vector<cv::Mat> squares = {Texture(cv::Size(64, 64), 2), Texture(cv::Size(56, 56), 3)};
  MotionSegmenter segmenter;
  cv::Mat labels;
  for (int t = 0; t < 4; ++t) {
    // One square moves right by 2 px a frame, the other up by 3; the background stands.
    labels = segmenter.Segment(Scene(background, {0, 0}, squares,
                                     {cv::Point(40 + 2 * t, 60), cv::Point(200, 150 - 3 * t)}));
    if (t == 0) {
      EXPECT_EQ(segmenter.num_regions(), 0);  // no motion yet
      EXPECT_EQ(cv::countNonZero(labels), 0);
    }
  }
  ASSERT_EQ(segmenter.num_regions(), 2);
  ASSERT_EQ(labels.type(), CV_32SC1);
  ASSERT_EQ(labels.size(), background.size());
  const cv::Rect first(46, 60, 64, 64), second(200, 141, 56, 56);
  const int at_first = labels.at<int>(92, 78), at_second = labels.at<int>(169, 228);
  ASSERT_GT(at_first, 0);
  ASSERT_GT(at_second, 0);
  EXPECT_NE(at_first, at_second);
  ExpectAround(LabelBox(labels, at_first), first);
  ExpectAround(LabelBox(labels, at_second), second);
  EXPECT_EQ(labels.at<int>(10, 300), 0);  // the background
  EXPECT_EQ(segmenter.flow().type(), CV_32FC2);
}

TEST(MotionSegmenter, NothingMovesNoRegion) {
  const cv::Mat image = Texture(cv::Size(160, 120), 4);
  MotionSegmenter segmenter;
  segmenter.Segment(image);
  const cv::Mat labels = segmenter.Segment(image);
  EXPECT_EQ(segmenter.num_regions(), 0);
  EXPECT_EQ(cv::countNonZero(labels), 0);
}

// A panning camera: everything moves; with the dominant motion taken out only the object
// moving otherwise is a region.
TEST(MotionSegmenter, AMovingCamerasMotionCanBeTakenOut) {
  const cv::Mat background = Texture(cv::Size(320, 240), 5);
  const std::vector<cv::Mat> squares = {Texture(cv::Size(64, 64), 6)};
  MotionSegmentationOptions options;
  options.remove_dominant_motion = true;
  MotionSegmenter segmenter(options);
  cv::Mat labels;
  for (int t = 0; t < 3; ++t) {
    labels =
        segmenter.Segment(Scene(background, {3 * t, 0}, squares, {cv::Point(120, 80 + 3 * t)}));
  }
  // The square, and at most slivers where it uncovers the background (whose flow there is
  // unreliable): nothing of the panning background.
  const int square = labels.at<int>(118, 152);
  ASSERT_GT(square, 0);
  ExpectAround(LabelBox(labels, square), cv::Rect(120, 86, 64, 64));
  const int square_area = cv::countNonZero(labels == square);
  for (int k = 1; k <= segmenter.num_regions(); ++k) {
    if (k != square) {
      EXPECT_LT(cv::countNonZero(labels == k), square_area / 3) << "region " << k;
    }
  }
}

// An object before a blank wall seen with a little sensor noise: the wall's flow (noise,
// and the spread of the object's) is not trusted, so the wall does not move.
TEST(MotionSegmenter, ABlankWallDoesNotMove) {
  const cv::Mat wall(240, 320, CV_32FC3, cv::Scalar(0.8, 0.8, 0.8));
  const std::vector<cv::Mat> squares = {Texture(cv::Size(64, 64), 7)};
  MotionSegmenter segmenter;
  cv::Mat labels;
  cv::RNG rng(11);
  for (int t = 0; t < 3; ++t) {
    cv::Mat image = Scene(wall, {0, 0}, squares, {cv::Point(100 + 2 * t, 90)});
    cv::Mat noise(image.size(), CV_32FC3);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.01);
    labels = segmenter.Segment(image + noise);
  }
  ASSERT_EQ(segmenter.num_regions(), 1);
  ExpectAround(LabelBox(labels, 1), cv::Rect(104, 90, 64, 64));
}

TEST(MotionSegmenter, RejectsWrongInput) {
  MotionSegmentationOptions options;
  options.block_px = 1;
  EXPECT_THROW(MotionSegmenter{options}, Error);
  options = {};
  options.relative_difference = -1.0;
  EXPECT_THROW(MotionSegmenter{options}, Error);
  MotionSegmenter segmenter;
  EXPECT_THROW(segmenter.Segment(cv::Mat(10, 10, CV_32FC1)), Error);
  segmenter.Segment(cv::Mat(40, 40, CV_8UC3, cv::Scalar(0)));
  EXPECT_THROW(segmenter.Segment(cv::Mat(40, 50, CV_8UC3, cv::Scalar(0))), Error);  // size
  EXPECT_THROW(segmenter.Segment(cv::Mat(40, 40, CV_8UC3), cv::Mat(40, 40, CV_8UC1)), Error);
}

}  // namespace
}  // namespace unseen
