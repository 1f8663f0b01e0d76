// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/image/filters.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

cv::Mat RandomTexture(int w, int h, int seed) {
  cv::RNG rng(seed);
  cv::Mat small(h / 8, w / 8, CV_32FC3);
  rng.fill(small, cv::RNG::UNIFORM, 0.1, 0.9);
  cv::Mat out;
  cv::resize(small, out, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  return out;
}

TEST(Filters, LinfMakesConstantMidGrey) {
  cv::Mat image(40, 60, CV_32FC3, cv::Scalar(0.2, 0.7, 0.9));
  const cv::Mat out = LocalIlluminationNormalize(image, 10.0, 0.02);
  double lo, hi;
  cv::minMaxLoc(out.reshape(1), &lo, &hi);
  EXPECT_NEAR(lo, 0.5, 1e-4);
  EXPECT_NEAR(hi, 0.5, 1e-4);
}

TEST(Filters, LinfRemovesGainAndRamp) {
  const cv::Mat base = RandomTexture(128, 96, 1);
  cv::Mat shaded = base.clone();
  for (int y = 0; y < shaded.rows; ++y) {
    for (int x = 0; x < shaded.cols; ++x) {
      const float gain = 0.5f * (0.6f + 0.4f * x / shaded.cols);  // gain and a slow ramp
      shaded.at<cv::Vec3f>(y, x) *= gain;
    }
  }
  const double eps = 1e-3;
  const cv::Mat a = LocalIlluminationNormalize(base, 12.0, eps);
  const cv::Mat b = LocalIlluminationNormalize(shaded, 12.0, eps);
  // Before: mean absolute difference is large; after LINF it is small.
  const double before = cv::norm(base, shaded, cv::NORM_L1) / base.total() / 3;
  const double after = cv::norm(a, b, cv::NORM_L1) / a.total() / 3;
  EXPECT_GT(before, 0.1);
  EXPECT_LT(after, 0.02);
}

TEST(Filters, WideLowPassKeepsMeanAndSmooths) {
  const cv::Mat image = RandomTexture(160, 120, 2);
  const cv::Mat low = WideLowPass(image, 16.0);
  ASSERT_EQ(low.size(), image.size());
  ASSERT_EQ(low.type(), image.type());
  const cv::Scalar m0 = cv::mean(image), m1 = cv::mean(low);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(m0[c], m1[c], 0.02);
  cv::Mat d0, d1;
  cv::meanStdDev(image, cv::noArray(), d0);
  cv::meanStdDev(low, cv::noArray(), d1);
  EXPECT_LT(d1.at<double>(0), 0.7 * d0.at<double>(0));
}

TEST(Filters, CentralGradientsOfARamp) {
  cv::Mat image(20, 30, CV_32FC1);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 30; ++x) image.at<float>(y, x) = 0.01f * x - 0.02f * y;
  cv::Mat gx, gy;
  CentralGradients(image, &gx, &gy);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 30; ++x) {
      EXPECT_NEAR(gx.at<float>(y, x), 0.01f, 1e-5);
      EXPECT_NEAR(gy.at<float>(y, x), -0.02f, 1e-5);
    }
  }
}

TEST(Filters, DownsampledRegionAveragesBlocks) {
  const cv::Mat image = RandomTexture(64, 48, 3);
  const PixelRect roi{3, 2, 10, 9};
  const cv::Mat out = DownsampledRegion(image, 2, roi);
  ASSERT_EQ(out.cols, 7);
  ASSERT_EQ(out.rows, 7);
  for (int y = 0; y < 7; ++y) {
    for (int x = 0; x < 7; ++x) {
      const cv::Scalar m = cv::mean(image(cv::Rect((roi.x0 + x) * 4, (roi.y0 + y) * 4, 4, 4)));
      const cv::Vec3f v = out.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], m[c], 1e-5);
    }
  }
  EXPECT_THROW(DownsampledRegion(image, 2, PixelRect{10, 0, 17, 5}), Error);
  EXPECT_THROW(DownsampledRegion(cv::Mat(8, 8, CV_8UC3), 0, PixelRect{0, 0, 2, 2}), Error);
}

TEST(Filters, RejectsBadArguments) {
  const cv::Mat image(8, 8, CV_32FC3, cv::Scalar::all(0.5));
  EXPECT_THROW(LocalIlluminationNormalize(image, 4.0, 0.0), Error);
  EXPECT_THROW(GaussianBlurred(image, -1.0), Error);
  EXPECT_THROW(WideLowPass(cv::Mat(), 4.0), Error);
}

TEST(Filters, LowPassHalvesComposeToWideLowPass) {
  cv::Mat image(37, 53, CV_32FC4);  // odd size: the halves pad and crop
  cv::RNG(5).fill(image, cv::RNG::UNIFORM, 0.0, 1.0);
  for (double sigma : {1.5, 4.0, 9.0}) {
    int factor = 0;
    const cv::Mat small = LowPassDown(image, sigma, &factor);
    EXPECT_EQ(factor, sigma < 4.0 ? 1 : (sigma < 8.0 ? 2 : 4)) << sigma;
    EXPECT_EQ(small.cols, (image.cols + factor - 1) / factor);
    const cv::Mat both = LowPassUp(small, image.size(), factor);
    ASSERT_EQ(both.size(), image.size());
    EXPECT_LT(cv::norm(both, WideLowPass(image, sigma), cv::NORM_INF), 1e-6) << sigma;
  }
  int factor = 0;
  const cv::Mat small = LowPassDown(image, 9.0, &factor);
  EXPECT_THROW(LowPassUp(small, cv::Size(200, 37), factor), Error);
}

}  // namespace
}  // namespace unseen
