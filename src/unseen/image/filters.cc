// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/image/filters.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

void CheckFloat(const cv::Mat& image, const char* what) {
  UNSEEN_CHECK(!image.empty(), "{}: empty image", what);
  UNSEEN_CHECK(image.depth() == CV_32F, "{}: image type {} is not float (CV_32F)", what,
               image.type());
}

int KernelSize(double sigma_px) {
  return 2 * static_cast<int>(std::ceil(3.0 * sigma_px)) + 1;
}

}  // namespace

int LowPassFactor(cv::Size size, double sigma_px) {
  UNSEEN_CHECK(sigma_px > 0.0 && std::isfinite(sigma_px), "WideLowPass: sigma_px {} must be > 0",
               sigma_px);
  int factor = 1;
  while (factor < 8 && sigma_px / (2 * factor) >= 2.0 &&
         std::min(size.width, size.height) >= 8 * factor) {
    factor *= 2;
  }
  return factor;
}

cv::Mat BlurDownsampled(const cv::Mat& small, double sigma_px, int factor) {
  CheckFloat(small, "BlurDownsampled");
  UNSEEN_CHECK(factor >= 1, "BlurDownsampled: factor {} must be >= 1", factor);
  // Area down-sampling is itself a box low-pass of width `factor` (variance factor^2/12);
  // the remaining blur makes up the rest of the requested variance. Factor 1: the image
  // itself, blurred by the whole sigma.
  const double sigma_small =
      factor == 1
          ? sigma_px
          : std::sqrt(std::max(sigma_px * sigma_px - factor * factor / 12.0, 0.25)) / factor;
  cv::Mat out;
  cv::GaussianBlur(small, out, cv::Size(KernelSize(sigma_small), KernelSize(sigma_small)),
                   sigma_small, sigma_small, cv::BORDER_REPLICATE);
  return out;
}

cv::Mat LowPassDown(const cv::Mat& image, double sigma_px, int* factor_out) {
  CheckFloat(image, "WideLowPass");
  const int factor = LowPassFactor(image.size(), sigma_px);
  *factor_out = factor;
  if (factor == 1) return BlurDownsampled(image, sigma_px, 1);
  // The image is padded (border replicated) to a multiple of `factor`, so that both
  // resizes have an integer scale (OpenCV's fast paths) and the up-sampled pixels sit
  // exactly on the blocks.
  const int small_cols = (image.cols + factor - 1) / factor;
  const int small_rows = (image.rows + factor - 1) / factor;
  const int pad_cols = small_cols * factor - image.cols, pad_rows = small_rows * factor - image.rows;
  cv::Mat padded = image;
  if (pad_cols > 0 || pad_rows > 0) {
    cv::copyMakeBorder(image, padded, 0, pad_rows, 0, pad_cols, cv::BORDER_REPLICATE);
  }
  cv::Mat small;
  cv::resize(padded, small, cv::Size(small_cols, small_rows), 0, 0, cv::INTER_AREA);
  return BlurDownsampled(small, sigma_px, factor);
}

cv::Mat LowPassUp(const cv::Mat& small, cv::Size size, int factor) {
  if (factor == 1) return small;
  UNSEEN_CHECK(small.cols * factor >= size.width && small.rows * factor >= size.height &&
                   (small.cols - 1) * factor < size.width && (small.rows - 1) * factor < size.height,
               "LowPassUp: {}x{} image at factor {} does not match {}x{}", small.cols, small.rows,
               factor, size.width, size.height);
  cv::Mat out;
  cv::resize(small, out, cv::Size(small.cols * factor, small.rows * factor), 0, 0,
             cv::INTER_LINEAR);
  if (out.cols != size.width || out.rows != size.height) {
    out = out(cv::Rect(0, 0, size.width, size.height)).clone();
  }
  return out;
}

cv::Mat WideLowPass(const cv::Mat& image, double sigma_px) {
  int factor = 1;
  const cv::Mat small = LowPassDown(image, sigma_px, &factor);
  return LowPassUp(small, image.size(), factor);
}

cv::Mat LocalIlluminationNormalize(const cv::Mat& image, double sigma_px, double epsilon) {
  CheckFloat(image, "LocalIlluminationNormalize");
  UNSEEN_CHECK(epsilon > 0.0 && std::isfinite(epsilon),
               "LocalIlluminationNormalize: epsilon {} must be > 0", epsilon);
  const cv::Mat low = WideLowPass(image, sigma_px);
  cv::Mat out(image.size(), image.type());
  const int n = image.cols * image.channels();
  const float eps = static_cast<float>(epsilon);
  for (int y = 0; y < image.rows; ++y) {
    const float* src = image.ptr<float>(y);
    const float* lp = low.ptr<float>(y);
    float* dst = out.ptr<float>(y);
    for (int i = 0; i < n; ++i) {
      dst[i] = 0.5f * (src[i] + eps) / (std::max(lp[i], 0.0f) + eps);
    }
  }
  return out;
}

cv::Mat GaussianBlurred(const cv::Mat& image, double sigma_px) {
  CheckFloat(image, "GaussianBlurred");
  UNSEEN_CHECK(sigma_px > 0.0 && std::isfinite(sigma_px),
               "GaussianBlurred: sigma_px {} must be > 0", sigma_px);
  cv::Mat out;
  cv::GaussianBlur(image, out, cv::Size(KernelSize(sigma_px), KernelSize(sigma_px)), sigma_px,
                   sigma_px, cv::BORDER_REPLICATE);
  return out;
}

void CentralGradients(const cv::Mat& image, cv::Mat* gx, cv::Mat* gy) {
  CheckFloat(image, "CentralGradients");
  const int w = image.cols, h = image.rows, c = image.channels();
  gx->create(image.size(), image.type());
  gy->create(image.size(), image.type());
  const int n = w * c;
  for (int y = 0; y < h; ++y) {
    const float* row = image.ptr<float>(y);
    const float* up = image.ptr<float>(std::max(y - 1, 0));
    const float* down = image.ptr<float>(std::min(y + 1, h - 1));
    const float sy = (y == 0 || y == h - 1) ? (h > 1 ? 1.0f : 0.0f) : 0.5f;
    float* ox = gx->ptr<float>(y);
    float* oy = gy->ptr<float>(y);
    for (int i = 0; i < n; ++i) oy[i] = sy * (down[i] - up[i]);
    if (w == 1) {
      for (int i = 0; i < n; ++i) ox[i] = 0.0f;
      continue;
    }
    for (int k = 0; k < c; ++k) {
      ox[k] = row[c + k] - row[k];
      ox[n - c + k] = row[n - c + k] - row[n - 2 * c + k];
    }
    for (int i = c; i < n - c; ++i) ox[i] = 0.5f * (row[i + c] - row[i - c]);
  }
}

PixelRect LevelRect(int width0, int height0, int level) {
  return {0, 0, width0 >> level, height0 >> level};
}

cv::Mat DownsampledRegion(const cv::Mat& image0, int level, const PixelRect& roi) {
  CheckFloat(image0, "DownsampledRegion");
  UNSEEN_CHECK(level >= 0 && level < 16, "DownsampledRegion: level {} out of range", level);
  const PixelRect bounds = LevelRect(image0.cols, image0.rows, level);
  UNSEEN_CHECK(!roi.empty() && roi.Intersect(bounds) == roi,
               "DownsampledRegion: region [{}, {}) x [{}, {}) is empty or outside the level-{} "
               "image {}x{}",
               roi.x0, roi.x1, roi.y0, roi.y1, level, bounds.x1, bounds.y1);
  const int s = 1 << level;
  const cv::Mat block = image0(cv::Rect(roi.x0 * s, roi.y0 * s, roi.width() * s, roi.height() * s));
  if (s == 1) return block.clone();
  cv::Mat out;
  cv::resize(block, out, cv::Size(roi.width(), roi.height()), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace unseen
