// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/image/template_matching.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

cv::Mat SmoothNoise(int rows, int cols, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(rows, cols, CV_32FC1);
  rng.fill(image, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  return image;
}

cv::Mat DiscMask(int side, int radius) {
  cv::Mat mask = cv::Mat::zeros(side, side, CV_8UC1);
  cv::circle(mask, cv::Point(side / 2, side / 2), radius, cv::Scalar(255), cv::FILLED);
  return mask;
}

// Expects `matcher`'s scores of the image's own square at `at` to be OpenCV's masked
// TM_CCOEFF_NORMED and to peak there at 1; returns the scores.
cv::Mat ExpectOpenCvScores(const MaskedTemplateMatcher& matcher, const cv::Mat& image,
                           const cv::Mat& templ, const cv::Mat& mask, cv::Point at) {
  const cv::Mat scores = matcher.Match(templ, mask);
  cv::Mat expected;
  cv::matchTemplate(image, templ, expected, cv::TM_CCOEFF_NORMED, mask);
  EXPECT_EQ(scores.size(), expected.size());
  EXPECT_EQ(scores.type(), CV_32FC1);
  if (scores.size() != expected.size()) return scores;
  cv::patchNaNs(expected, -1.0);
  EXPECT_LT(cv::norm(scores, expected, cv::NORM_INF), 1e-4);
  cv::Point peak;
  double best = 0.0;
  cv::minMaxLoc(scores, nullptr, &best, nullptr, &peak);
  EXPECT_EQ(peak, at);
  EXPECT_NEAR(best, 1.0, 1e-6);
  return scores;
}

// The scores are OpenCV's masked TM_CCOEFF_NORMED, and several templates share the image's
// transforms.
TEST(MaskedTemplateMatcher, ScoresAreOpenCvsMaskedNormalisedCorrelation) {
  const cv::Mat image = SmoothNoise(150, 170, 7);
  const cv::Mat mask = DiscMask(41, 17);
  const MaskedTemplateMatcher matcher(image, mask.size());
  for (const cv::Point at : {cv::Point(30, 20), cv::Point(100, 90), cv::Point(0, 0)}) {
    const cv::Mat templ = image(cv::Rect(at, mask.size())).clone();
    ExpectOpenCvScores(matcher, image, templ, mask, at);
  }
  // A gain and an offset of the template do not change the scores; a darker copy of the
  // image region still peaks there.
  const cv::Mat templ = image(cv::Rect(cv::Point(60, 40), mask.size())).clone();
  const cv::Mat scaled = templ * 0.3 + 0.2;
  EXPECT_LT(cv::norm(matcher.Match(templ, mask), matcher.Match(scaled, mask), cv::NORM_INF), 1e-5);
}

// Colour: the channels scored together as one vector, as OpenCV scores a three-channel
// image; a template whose colours are permuted is no match.
TEST(MaskedTemplateMatcher, ColourScoresAreOpenCvsOverAllChannels) {
  std::vector<cv::Mat> planes{SmoothNoise(110, 125, 21), SmoothNoise(110, 125, 22),
                              SmoothNoise(110, 125, 23)};
  cv::Mat image;
  cv::merge(planes, image);
  const cv::Mat mask = DiscMask(35, 15);
  const MaskedTemplateMatcher matcher(image, mask.size());
  const cv::Point at(52, 31);
  const cv::Mat templ = image(cv::Rect(at, mask.size())).clone();
  ExpectOpenCvScores(matcher, image, templ, mask, at);
  // The same pattern in the wrong channels scores low where the right one scores 1.
  std::vector<cv::Mat> templ_planes;
  cv::split(templ, templ_planes);
  std::swap(templ_planes[0], templ_planes[2]);
  cv::Mat swapped;
  cv::merge(templ_planes, swapped);
  EXPECT_LT(matcher.Match(swapped, mask).at<float>(at), 0.7);
  // A template of another channel count is refused.
  EXPECT_THROW(matcher.Match(planes[0](cv::Rect(at, mask.size())).clone(), mask), Error);
}

// A template prepared once is matched in a series of images (frames) of one size: the
// scores are those of matching it afresh in each.
TEST(MaskedTemplateMatcher, APreparedTemplateMatchesLaterImagesAsAFreshOne) {
  const cv::Mat mask = DiscMask(31, 12);
  const cv::Mat first = SmoothNoise(120, 130, 6);
  const cv::Mat templ = first(cv::Rect(40, 50, 31, 31)).clone();
  const MaskedTemplateMatcher::Prepared prepared =
      MaskedTemplateMatcher(first, mask.size()).Prepare(templ, mask);
  for (int seed : {7, 8}) {
    const MaskedTemplateMatcher later(SmoothNoise(120, 130, seed), mask.size());
    ASSERT_TRUE(later.Fits(prepared));
    EXPECT_EQ(cv::norm(later.Match(prepared), later.Match(templ, mask), cv::NORM_INF), 0.0);
  }
  // Prepared for another image size or template size: refused, not misread.
  const MaskedTemplateMatcher wider(SmoothNoise(120, 260, 6), mask.size());
  EXPECT_FALSE(wider.Fits(prepared));
  EXPECT_THROW(wider.Match(prepared), Error);
  const MaskedTemplateMatcher smaller_template(first, cv::Size(21, 21));
  EXPECT_FALSE(smaller_template.Fits(prepared));
  EXPECT_THROW(smaller_template.Match(prepared), Error);
}

TEST(MaskedTemplateMatcher, FeaturelessImageTemplateOrMaskScoreMinusOne) {
  const cv::Mat mask = DiscMask(21, 8);
  const cv::Mat flat(60, 70, CV_32FC1, cv::Scalar(0.4));
  const cv::Mat templ = SmoothNoise(21, 21, 3);
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(MaskedTemplateMatcher(flat, mask.size()).Match(templ, mask), &lo, &hi);
  EXPECT_EQ(lo, -1.0);
  EXPECT_EQ(hi, -1.0);
  const MaskedTemplateMatcher matcher(SmoothNoise(60, 70, 4), mask.size());
  cv::minMaxLoc(matcher.Match(cv::Mat(21, 21, CV_32FC1, cv::Scalar(0.5)), mask), &lo, &hi);
  EXPECT_EQ(hi, -1.0);
  cv::minMaxLoc(matcher.Match(templ, cv::Mat::zeros(21, 21, CV_8UC1)), &lo, &hi);
  EXPECT_EQ(hi, -1.0);
}

TEST(MaskedTemplateMatcher, BadInputThrows) {
  const cv::Mat image = SmoothNoise(40, 40, 5);
  EXPECT_THROW(MaskedTemplateMatcher(cv::Mat(), cv::Size(5, 5)), Error);
  EXPECT_THROW(MaskedTemplateMatcher(cv::Mat(40, 40, CV_8UC1), cv::Size(5, 5)), Error);
  EXPECT_THROW(MaskedTemplateMatcher(image, cv::Size(41, 5)), Error);
  EXPECT_THROW(MaskedTemplateMatcher(image, cv::Size(0, 5)), Error);
  const MaskedTemplateMatcher matcher(image, cv::Size(9, 9));
  const cv::Mat mask = DiscMask(9, 3);
  EXPECT_THROW(matcher.Match(cv::Mat(8, 9, CV_32FC1), mask), Error);
  EXPECT_THROW(matcher.Match(cv::Mat(9, 9, CV_32FC3), mask), Error);
  EXPECT_THROW(matcher.Match(cv::Mat(9, 9, CV_32FC1), cv::Mat(9, 9, CV_32FC1)), Error);
}

}  // namespace
}  // namespace unseen
