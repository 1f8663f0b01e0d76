// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/clutter.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(Clutter, DeterministicFromSeed) {
  const cv::Mat a = MakeClutterImage(320, 160, 7);
  const cv::Mat b = MakeClutterImage(320, 160, 7);
  const cv::Mat c = MakeClutterImage(320, 160, 8);
  ASSERT_EQ(a.type(), CV_32FC3);
  ASSERT_EQ(a.size(), cv::Size(320, 160));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1) / a.total(), 0.05);
}

TEST(Clutter, IsClutteredAndInRange) {
  const cv::Mat img = MakeClutterImage(640, 320, 3);
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(img.reshape(1), &lo, &hi);
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  // Many strong edges (what distracts a tracker): a good share of pixels with a large
  // gradient, and colour variety.
  cv::Mat grey, gx, gy, mag;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, mag);
  EXPECT_GT(cv::countNonZero(mag > 0.5), static_cast<int>(0.03 * mag.total()));
  cv::Scalar mean, stddev;
  cv::meanStdDev(img, mean, stddev);
  for (int ch = 0; ch < 3; ++ch) EXPECT_GT(stddev[ch], 0.08);
}

TEST(Clutter, RejectsTinySize) { EXPECT_THROW(MakeClutterImage(8, 100, 1), Error); }

}  // namespace
}  // namespace unseen
