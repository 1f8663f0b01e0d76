// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/mipmap.h"

#include <cmath>

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

cv::Mat RandomTexture(int w, int h, unsigned seed) {
  cv::Mat t(h, w, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::UNIFORM, 0.0, 1.0);
  return t;
}

TEST(Mipmap, LevelsHalveDownToOnePixelAndAverageTwoByTwoBlocks) {
  const cv::Mat texture = RandomTexture(64, 16, 1);
  const std::vector<cv::Mat> levels = MipmapLevels(texture);
  ASSERT_EQ(levels.size(), 7u);  // 64x16, 32x8, 16x4, 8x2, 4x1, 2x1, 1x1
  EXPECT_EQ(levels[0].data, texture.data);
  EXPECT_EQ(levels[1].size(), cv::Size(32, 8));
  EXPECT_EQ(levels[4].size(), cv::Size(4, 1));
  EXPECT_EQ(levels[6].size(), cv::Size(1, 1));
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 32; ++x) {
      const cv::Vec3f mean = 0.25f * (texture.at<cv::Vec3f>(2 * y, 2 * x) +
                                      texture.at<cv::Vec3f>(2 * y, 2 * x + 1) +
                                      texture.at<cv::Vec3f>(2 * y + 1, 2 * x) +
                                      texture.at<cv::Vec3f>(2 * y + 1, 2 * x + 1));
      ASSERT_LT(cv::norm(levels[1].at<cv::Vec3f>(y, x) - mean), 1e-5);
    }
  }
  const cv::Scalar overall = cv::mean(texture);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(levels[6].at<cv::Vec3f>(0, 0)[k], overall[k], 1e-5);
  // Odd sizes round up.
  const std::vector<cv::Mat> odd = MipmapLevels(RandomTexture(5, 3, 2));
  ASSERT_EQ(odd.size(), 4u);
  EXPECT_EQ(odd[1].size(), cv::Size(3, 2));
  EXPECT_EQ(odd[2].size(), cv::Size(2, 1));
}

TEST(Mipmap, CachedLevelsAreReusedAndRebuiltWhenTheContentChanges) {
  cv::Mat texture = RandomTexture(32, 32, 3);
  const std::vector<cv::Mat> a = MipmapLevels(texture);
  const std::vector<cv::Mat> b = MipmapLevels(texture);
  EXPECT_EQ(a[1].data, b[1].data);  // from the cache
  texture.setTo(cv::Scalar::all(0.25));  // edited in place
  const std::vector<cv::Mat> c = MipmapLevels(texture);
  EXPECT_NEAR(c[1].at<cv::Vec3f>(3, 4)[1], 0.25f, 1e-6);
  ClearMipmapCache();
  const std::vector<cv::Mat> d = MipmapLevels(texture);
  EXPECT_NE(d[1].data, c[1].data);
  EXPECT_NEAR(d[2].at<cv::Vec3f>(1, 1)[2], 0.25f, 1e-6);
}

TEST(Mipmap, LevelForTexelsPerPixel) {
  EXPECT_EQ(MipmapLevelFor(0.5, 10), 0);
  EXPECT_EQ(MipmapLevelFor(3.9, 10), 0);
  EXPECT_EQ(MipmapLevelFor(4.0, 10), 1);
  EXPECT_EQ(MipmapLevelFor(15.0, 10), 1);
  EXPECT_EQ(MipmapLevelFor(16.0, 10), 2);
  EXPECT_EQ(MipmapLevelFor(1e12, 10), 9);
  EXPECT_EQ(MipmapLevelFor(std::nan(""), 10), 0);
  EXPECT_EQ(MipmapLevelFor(100.0, 1), 0);
}

TEST(Mipmap, BadTextureThrows) {
  EXPECT_THROW(MipmapLevels(cv::Mat()), Error);
  EXPECT_THROW(MipmapLevels(cv::Mat(4, 4, CV_8UC3)), Error);
}

}  // namespace
}  // namespace unseen
